//! The outcome vocabulary, one for every answer from the kernel to the JSON report, the ROS
//! message and the Python object: how a run ended (`Status`, with the `Limit` that stopped it),
//! what one box is (`BoxStatus`), whether an answer is complete (`Completeness`, by one rule),
//! and what a verdict concerns (`Scope`).
//!
//! This is ibex's split between a solver's status and the status of each box of its cover
//! (Chabert and Jaulin 2009): the run says whether it was stopped, each box says what is proven
//! in it, and "complete" is derived from both, in one place.

use super::search::Wire;

/// Why a run stopped early.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Limit {
    /// `max_cells` cells were processed.
    Boxes,
    /// `timeout` elapsed.
    Time,
    /// Pending cells would have held more than `max_memory` bytes.
    Memory,
    /// The caller raised the cancel flag.
    Cancelled,
    /// The sink asked to stop.
    Sink,
}

impl Limit {
    /// The name used in reports and messages.
    pub fn name(self) -> &'static str {
        match self {
            Limit::Boxes => "boxes",
            Limit::Time => "time",
            Limit::Memory => "memory",
            Limit::Cancelled => "cancelled",
            Limit::Sink => "sink",
        }
    }
}

/// How one run of the kernel ended: it decided every cell, or a limit stopped it. A run says
/// nothing about its answer's completeness by itself: cells decided as undecided at the
/// precision leave an answer incomplete too (`Completeness::of`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// Every cell was processed to a decision (which may be "undecided at the precision").
    Finished,
    /// Stopped by a limit; results and undecided cells together enclose everything sought.
    Stopped(Limit),
}

impl Status {
    /// True when no limit stopped the run.
    pub fn finished(self) -> bool {
        self == Status::Finished
    }

    /// The limit that stopped the run, if one did.
    pub fn limit(self) -> Option<Limit> {
        match self {
            Status::Finished => None,
            Status::Stopped(l) => Some(l),
        }
    }

    /// The first limit of two runs that make up one answer: finished only if both are.
    pub fn and(self, other: Status) -> Status {
        match self {
            Status::Finished => other,
            s => s,
        }
    }
}

/// What one reported box is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BoxStatus {
    /// No wider than the precision and not proven empty: it may hold solutions.
    Solution,
    /// Proven (interval Newton, Krawczyk's operator) to hold exactly one solution.
    Unique,
    /// Left unprocessed when a limit stopped the run.
    Undecided,
}

impl BoxStatus {
    /// A solution box, certified or not.
    pub fn is_solution(self) -> bool {
        matches!(self, BoxStatus::Solution | BoxStatus::Unique)
    }

    /// The name used in reports, messages and Python tags.
    pub fn name(self) -> &'static str {
        match self {
            BoxStatus::Solution => "solution",
            BoxStatus::Unique => "unique",
            BoxStatus::Undecided => "undecided",
        }
    }
}

impl Wire for BoxStatus {
    fn put(&self, out: &mut Vec<u8>) {
        (*self as u8).put(out)
    }
    fn take(input: &mut &[u8]) -> Self {
        match u8::take(input) {
            0 => BoxStatus::Solution,
            1 => BoxStatus::Unique,
            _ => BoxStatus::Undecided,
        }
    }
}

/// Why an answer is incomplete: a limit stopped one of its runs, or it ended with something it
/// could not decide.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Incompleteness {
    /// A limit stopped a run.
    Limit(Limit),
    /// Strips were set aside as near-degenerate (undecided as a whole).
    NearDegenerate,
    /// Cells were left undecided at the precision.
    Undecided,
}

impl Incompleteness {
    /// The reason `name` spells, if any (records read back).
    pub fn from_name(name: &str) -> Option<Self> {
        let limits = [Limit::Boxes, Limit::Time, Limit::Memory, Limit::Cancelled, Limit::Sink].map(Incompleteness::Limit);
        limits.into_iter().chain([Incompleteness::NearDegenerate, Incompleteness::Undecided]).find(|r| r.name() == name)
    }

    /// The name used in reports and messages (a limit's own name, `near_degenerate`,
    /// `undecided`).
    pub fn name(self) -> &'static str {
        match self {
            Incompleteness::Limit(l) => l.name(),
            Incompleteness::NearDegenerate => "near_degenerate",
            Incompleteness::Undecided => "undecided",
        }
    }
}

/// Whether an answer is complete: nothing stopped it and nothing is left undecided. The one
/// completeness type of the library; every report, message and record spells it through
/// `word` and `reason`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Completeness {
    /// Every cell decided, nothing left open: the answer's boxes hold everything sought and
    /// every count is exact.
    Complete,
    /// Something is open, and why.
    Incomplete(Incompleteness),
}

impl Completeness {
    /// The one rule: the limit that stopped the run, else near-degenerate strips, else
    /// undecided cells; complete when none of these.
    ///
    /// # Examples
    ///
    /// ```
    /// use linkspace::app::{Completeness, Incompleteness, Limit, Status};
    /// assert_eq!(Completeness::of(Status::Finished, 0, false), Completeness::Complete);
    /// assert_eq!(Completeness::of(Status::Finished, 3, false), Completeness::Incomplete(Incompleteness::Undecided));
    /// assert_eq!(Completeness::of(Status::Stopped(Limit::Boxes), 3, true), Completeness::Incomplete(Incompleteness::Limit(Limit::Boxes)));
    /// ```
    pub fn of(status: Status, undecided: usize, near_degenerate: bool) -> Self {
        match status {
            Status::Stopped(l) => Completeness::Incomplete(Incompleteness::Limit(l)),
            Status::Finished if near_degenerate => Completeness::Incomplete(Incompleteness::NearDegenerate),
            Status::Finished if undecided > 0 => Completeness::Incomplete(Incompleteness::Undecided),
            Status::Finished => Completeness::Complete,
        }
    }

    /// Of a run that left nothing else open: complete exactly when no limit stopped it.
    pub fn of_run(status: Status) -> Self {
        Self::of(status, 0, false)
    }

    /// True when nothing is open.
    pub fn is_complete(self) -> bool {
        self == Completeness::Complete
    }

    /// Why it is incomplete (`None` when complete).
    pub fn reason(self) -> Option<Incompleteness> {
        match self {
            Completeness::Complete => None,
            Completeness::Incomplete(why) => Some(why),
        }
    }

    /// `complete` or `incomplete`: the only place either word is spelled.
    pub fn word(self) -> &'static str {
        match self {
            Completeness::Complete => "complete",
            Completeness::Incomplete(_) => "incomplete",
        }
    }

    /// `complete`, or `incomplete (REASON)`: the text front ends print. A limit is named as
    /// a limit (`incomplete (time limit)`), so a reader knows what to raise.
    pub fn text(self) -> String {
        match self {
            Completeness::Complete => self.word().to_string(),
            Completeness::Incomplete(Incompleteness::Limit(l)) => format!("{} ({} limit)", self.word(), l.name()),
            Completeness::Incomplete(why) => format!("{} ({})", self.word(), why.name()),
        }
    }

    /// The first incomplete of two answers that make up one.
    pub fn and(self, other: Completeness) -> Completeness {
        match self {
            Completeness::Complete => other,
            c => c,
        }
    }
}

/// What a verdict concerns: the mechanism as a whole, or a named part of it (the 3R
/// positioning sub-chain of an arm, with its joints and point), so that a verdict about a part
/// is never read as the arm's.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Scope {
    /// The whole mechanism (the arm).
    Mechanism,
    /// A sub-chain: its joints, base first, and the point it positions (a link and its
    /// coordinates, as text).
    SubChain {
        /// The sub-chain's joints.
        joints: Vec<String>,
        /// The point it positions.
        point: String,
    },
}

impl Scope {
    /// `mechanism`, or `sub_chain`.
    pub fn name(&self) -> &'static str {
        match self {
            Scope::Mechanism => "mechanism",
            Scope::SubChain { .. } => "sub_chain",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_limit_outranks_what_is_undecided() {
        let c = Completeness::of(Status::Stopped(Limit::Time), 2, true);
        assert_eq!(c.reason(), Some(Incompleteness::Limit(Limit::Time)));
        assert_eq!(c.text(), "incomplete (time limit)");
        assert_eq!(Completeness::of(Status::Finished, 0, true).text(), "incomplete (near_degenerate)");
        assert!(Completeness::of_run(Status::Finished).is_complete());
        assert_eq!(Completeness::Complete.and(c), c);
    }

    #[test]
    fn box_tags_cross_the_wire_unchanged() {
        for tag in [BoxStatus::Solution, BoxStatus::Unique, BoxStatus::Undecided] {
            let mut bytes = Vec::new();
            tag.put(&mut bytes);
            assert_eq!(BoxStatus::take(&mut bytes.as_slice()), tag);
        }
    }
}

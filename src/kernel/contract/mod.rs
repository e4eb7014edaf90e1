//! Contractors: box-shrinking steps that remove only what they prove holds no solution.
//!
//! Owns the `Contractor` trait, its outcome `Contraction`, the combinator `Sequence`, and the
//! implementations: equation-wise interval propagation (`propagate`), the LP shrink of Porta et al.
//! (2006) (`lp_shrink`), the one Krawczyk operator with ε-inflation (`krawczyk`, used by every
//! search) and its adapter for square systems (`newton`), and trapezoid clipping of
//! polynomial equations (`trapezoid`, Porta et al. 2003); `filter` applies non-equation conditions
//! (joint limits) to every box, certified or not.
//! A contractor does no IO; numerical trouble gives `Unchanged`, never `Empty`.

mod filter;
pub mod krawczyk;
mod lp_shrink;
mod newton;
mod propagate;
mod trapezoid;

pub use filter::{Filter, Filtered, Inclusion};
pub use lp_shrink::LpShrink;
pub use newton::Newton;
pub use propagate::Propagation;
pub use trapezoid::{clip_segment, ClipError, FaceBounds, TrapezoidClip, MAX_CONTROL_POINTS};

use crate::kernel::interval::IntervalBox;
use crate::kernel::lp::LpCounters;

/// What a contractor did to a box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Contraction {
    /// Proven to hold no solution; the box is left in an unspecified state.
    Empty,
    /// Some component narrowed.
    Reduced,
    /// Nothing proven; the box is as it was.
    Unchanged,
    /// The box (possibly narrowed) holds exactly one solution: an existence and uniqueness
    /// certificate.
    Proven,
}

impl Contraction {
    /// Combines the outcomes of two steps applied one after the other.
    pub fn then(self, next: Contraction) -> Contraction {
        match (self, next) {
            (Contraction::Empty, _) | (_, Contraction::Empty) => Contraction::Empty,
            (Contraction::Proven, _) | (_, Contraction::Proven) => Contraction::Proven,
            (Contraction::Reduced, _) | (_, Contraction::Reduced) => Contraction::Reduced,
            _ => Contraction::Unchanged,
        }
    }
}

/// A sound box-shrinking step.
///
/// Contract: for every solution `x` of the problem with `x ∈ b` before the call, either the call
/// returns `Empty` (and then no such `x` existed), or `x ∈ b` still holds after it.
pub trait Contractor {
    /// Narrows `b` to what may still hold solutions.
    fn contract(&mut self, b: &mut IntervalBox) -> Contraction;
    /// As `contract`, giving up early once `stop` says so (the run's deadline or cancel), with
    /// what it proved so far; the default asks only before it starts.
    fn contract_until(&mut self, b: &mut IntervalBox, stop: &dyn Fn() -> bool) -> Contraction {
        if stop() {
            return Contraction::Unchanged;
        }
        self.contract(b)
    }
    /// A short name for statistics and charts.
    fn name(&self) -> &'static str;
    /// LPs this contractor solved so far (zero for those that solve none).
    fn lp_counters(&self) -> LpCounters {
        LpCounters::default()
    }
    /// A box holding exactly one solution, and every solution of `b`, if this contractor can
    /// prove one exists (e.g. interval Newton on a slightly inflated `b`); `None` otherwise.
    fn certify(&mut self, _b: &IntervalBox) -> Option<IntervalBox> {
        None
    }
}

/// Applies contractors in order; stops at the first `Empty`, and after a `Proven` (the rest
/// could only narrow a box already known to hold its one solution). So no step that must see
/// every box belongs here: conditions like joint limits are `Filter`s, run by `Filtered`.
pub struct Sequence<'a>(pub Vec<Box<dyn Contractor + Send + 'a>>);

impl Contractor for Sequence<'_> {
    fn contract(&mut self, b: &mut IntervalBox) -> Contraction {
        self.contract_until(b, &|| false)
    }

    fn contract_until(&mut self, b: &mut IntervalBox, stop: &dyn Fn() -> bool) -> Contraction {
        let mut outcome = Contraction::Unchanged;
        for c in &mut self.0 {
            outcome = outcome.then(c.contract_until(b, stop));
            if matches!(outcome, Contraction::Empty | Contraction::Proven) {
                break;
            }
        }
        outcome
    }

    fn name(&self) -> &'static str {
        "sequence"
    }

    fn certify(&mut self, b: &IntervalBox) -> Option<IntervalBox> {
        self.0.iter_mut().find_map(|c| c.certify(b))
    }

    fn lp_counters(&self) -> LpCounters {
        self.0.iter().map(|c| c.lp_counters()).fold(LpCounters::default(), |a, b| LpCounters { solved: a.solved + b.solved, unverified: a.unverified + b.unverified })
    }
}

//! Filters: conditions of the problem that are not equations (joint limits), applied to every
//! box a contractor pipeline passes on, including boxes it has certified.
//!
//! A filter only judges a box. `Filtered` runs the pipeline, then every filter: a box wholly
//! outside a filter's set is `Empty`; a box it cannot place wholly inside loses a `Proven`
//! outcome, because the unique root the certificate speaks of may be the one outside.

use super::{Contraction, Contractor};
use crate::interval::IntervalBox;
use crate::lp::LpCounters;

/// Where a box lies with respect to a filter's admissible set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Every point of the box is admissible.
    Inside,
    /// No point of the box is admissible (proven).
    Outside,
    /// Neither could be proven.
    Straddles,
}

impl Verdict {
    /// The verdict on the intersection of two admissible sets: `Outside` when either is,
    /// `Inside` only when both are.
    pub fn and(self, other: Verdict) -> Verdict {
        match (self, other) {
            (Verdict::Outside, _) | (_, Verdict::Outside) => Verdict::Outside,
            (Verdict::Inside, Verdict::Inside) => Verdict::Inside,
            _ => Verdict::Straddles,
        }
    }
}

/// A sound test of a box against a condition that is not an equation.
pub trait Filter {
    /// `Outside` only when no point of `b` is admissible; `Inside` only when every point is.
    fn judge(&self, b: &IntervalBox) -> Verdict;
}

/// A judging function is a filter (a problem's own limit test, borrowed).
impl<F: Fn(&IntervalBox) -> Verdict> Filter for F {
    fn judge(&self, b: &IntervalBox) -> Verdict {
        self(b)
    }
}

/// A contractor pipeline followed by filters that see every box it passes on.
pub struct Filtered<'a> {
    /// The pipeline.
    pub inner: Box<dyn Contractor + Send + 'a>,
    /// Applied after the pipeline to every box it does not empty.
    pub filters: Vec<Box<dyn Filter + Send + Sync + 'a>>,
}

impl Filtered<'_> {
    fn verdict(&self, b: &IntervalBox) -> Verdict {
        let mut verdict = Verdict::Inside;
        for f in &self.filters {
            verdict = verdict.and(f.judge(b));
            if verdict == Verdict::Outside {
                break;
            }
        }
        verdict
    }
}

impl Contractor for Filtered<'_> {
    fn contract(&mut self, b: &mut IntervalBox) -> Contraction {
        let outcome = self.inner.contract(b);
        if outcome == Contraction::Empty {
            return outcome;
        }
        match (self.verdict(b), outcome) {
            (Verdict::Outside, _) => Contraction::Empty,
            // The one root may lie outside the admissible set: keep the box, without the
            // certificate, so the search goes on narrowing or splitting it.
            (Verdict::Straddles, Contraction::Proven) => Contraction::Reduced,
            (_, o) => o,
        }
    }

    fn name(&self) -> &'static str {
        "filtered"
    }

    fn lp_counters(&self) -> LpCounters {
        self.inner.lp_counters()
    }

    /// A certified box is returned only when it lies wholly inside every filter's set: the
    /// certificate then speaks of an admissible root.
    fn certify(&mut self, b: &IntervalBox) -> Option<IntervalBox> {
        let proven = self.inner.certify(b)?;
        (self.verdict(&proven) == Verdict::Inside).then_some(proven)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interval::interval;

    /// Proves every box with a root at 0.5 and narrows nothing.
    struct Certifier;
    impl Contractor for Certifier {
        fn contract(&mut self, _b: &mut IntervalBox) -> Contraction {
            Contraction::Proven
        }
        fn name(&self) -> &'static str {
            "certifier"
        }
        fn certify(&mut self, b: &IntervalBox) -> Option<IntervalBox> {
            Some(b.clone())
        }
    }

    /// Admits x ≤ 1.
    struct AtMostOne;
    impl Filter for AtMostOne {
        fn judge(&self, b: &IntervalBox) -> Verdict {
            let x = b.dims[0];
            if x.sup() <= 1.0 {
                Verdict::Inside
            } else if x.inf() > 1.0 {
                Verdict::Outside
            } else {
                Verdict::Straddles
            }
        }
    }

    #[test]
    fn a_certified_box_still_meets_every_filter() {
        let mut f = Filtered { inner: Box::new(Certifier), filters: vec![Box::new(AtMostOne)] };
        let mut inside = IntervalBox::new(vec![interval(0.0, 0.9)]);
        assert_eq!(f.contract(&mut inside), Contraction::Proven);
        assert!(f.certify(&inside).is_some());
        let mut outside = IntervalBox::new(vec![interval(1.5, 2.0)]);
        assert_eq!(f.contract(&mut outside), Contraction::Empty);
        let mut across = IntervalBox::new(vec![interval(0.5, 1.5)]);
        assert_eq!(f.contract(&mut across), Contraction::Reduced);
        assert!(f.certify(&across).is_none());
    }
}

//! Filters: conditions of the problem that are not equations (joint limits), applied to every
//! box a contractor pipeline passes on, including boxes it has certified.
//!
//! A filter only judges a box. `Filtered` runs the pipeline, then every filter: a box wholly
//! outside a filter's set is `Empty`; a box it cannot place wholly inside loses a `Proven`
//! outcome, because the unique root the certificate speaks of may be the one outside.

use super::{Contraction, Contractor};
use crate::kernel::interval::IntervalBox;
use crate::kernel::lp::LpCounters;

/// Where a box lies with respect to a filter's admissible set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Inclusion {
    /// Every point of the box is admissible.
    Inside,
    /// No point of the box is admissible (proven).
    Outside,
    /// Neither could be proven.
    Straddles,
}

impl Inclusion {
    /// The verdict on the intersection of two admissible sets: `Outside` when either is,
    /// `Inside` only when both are.
    pub fn and(self, other: Inclusion) -> Inclusion {
        match (self, other) {
            (Inclusion::Outside, _) | (_, Inclusion::Outside) => Inclusion::Outside,
            (Inclusion::Inside, Inclusion::Inside) => Inclusion::Inside,
            _ => Inclusion::Straddles,
        }
    }
}

/// A sound test of a box against a condition that is not an equation.
pub trait Filter {
    /// `Outside` only when no point of `b` is admissible; `Inside` only when every point is.
    fn judge(&self, b: &IntervalBox) -> Inclusion;
}

/// A judging function is a filter (a problem's own limit test, borrowed).
impl<F: Fn(&IntervalBox) -> Inclusion> Filter for F {
    fn judge(&self, b: &IntervalBox) -> Inclusion {
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
    fn verdict(&self, b: &IntervalBox) -> Inclusion {
        let mut verdict = Inclusion::Inside;
        for f in &self.filters {
            verdict = verdict.and(f.judge(b));
            if verdict == Inclusion::Outside {
                break;
            }
        }
        verdict
    }
}

impl Contractor for Filtered<'_> {
    fn contract(&mut self, b: &mut IntervalBox) -> Contraction {
        self.contract_until(b, &|| false)
    }

    fn contract_until(&mut self, b: &mut IntervalBox, stop: &dyn Fn() -> bool) -> Contraction {
        let outcome = self.inner.contract_until(b, stop);
        if outcome == Contraction::Empty {
            return outcome;
        }
        match (self.verdict(b), outcome) {
            (Inclusion::Outside, _) => Contraction::Empty,
            // The one root may lie outside the admissible set: keep the box, without the
            // certificate, so the search goes on narrowing or splitting it.
            (Inclusion::Straddles, Contraction::Proven) => Contraction::Reduced,
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
        (self.verdict(&proven) == Inclusion::Inside).then_some(proven)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::interval::interval;

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
        fn judge(&self, b: &IntervalBox) -> Inclusion {
            let x = b.dims[0];
            if x.sup() <= 1.0 {
                Inclusion::Inside
            } else if x.inf() > 1.0 {
                Inclusion::Outside
            } else {
                Inclusion::Straddles
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

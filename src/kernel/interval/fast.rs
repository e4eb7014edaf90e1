//! `Iv`: a minimal interval type whose operations inline, for the hot loops of the 3R searches
//! (Taylor jets, Krawczyk).
//!
//! Each result is the round-to-nearest floating-point result moved one ulp outward
//! (`next_down`/`next_up`), which contains the exact result because rounding to nearest errs by
//! at most half an ulp. inari's operations are not inlined across crates and dominated the run
//! time of the 3R searches; `Iv` is slightly wider (one ulp per operation) and converts to and
//! from `inari::Interval` at the API.

use inari::Interval;

/// A closed interval `[lo, hi]` with outward-rounded arithmetic (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Iv {
    /// Lower bound.
    pub lo: f64,
    /// Upper bound.
    pub hi: f64,
}

impl Iv {
    /// [0, 0]
    pub(crate) const ZERO: Iv = Iv { lo: 0.0, hi: 0.0 };

    /// From an inari interval (empty becomes NaN bounds, which every operation keeps).
    #[inline(always)]
    pub(crate) fn from(x: Interval) -> Iv {
        if x.is_empty() {
            Iv { lo: f64::NAN, hi: f64::NAN }
        } else {
            Iv { lo: x.inf(), hi: x.sup() }
        }
    }

    /// Back to an inari interval.
    #[inline(always)]
    pub(crate) fn to(self) -> Interval {
        crate::kernel::interval::interval(self.lo, self.hi)
    }

    /// Sum.
    #[inline(always)]
    pub(crate) fn add(self, o: Iv) -> Iv {
        Iv { lo: (self.lo + o.lo).next_down(), hi: (self.hi + o.hi).next_up() }
    }

    /// Difference.
    #[inline(always)]
    pub(crate) fn sub(self, o: Iv) -> Iv {
        Iv { lo: (self.lo - o.hi).next_down(), hi: (self.hi - o.lo).next_up() }
    }

    /// Negation (exact).
    #[inline(always)]
    pub(crate) fn neg(self) -> Iv {
        Iv { lo: -self.hi, hi: -self.lo }
    }

    /// `y · self` for a finite double `y`.
    #[inline(always)]
    pub(crate) fn scale(self, y: f64) -> Iv {
        if y == 0.0 {
            // Exactly zero, even for unbounded `self` (where y·∞ would be NaN).
            return Iv::ZERO;
        }
        let (a, b) = (y * self.lo, y * self.hi);
        if y > 0.0 {
            Iv { lo: a.next_down(), hi: b.next_up() }
        } else {
            Iv { lo: b.next_down(), hi: a.next_up() }
        }
    }

    /// Product.
    #[inline(always)]
    pub(crate) fn mul(self, o: Iv) -> Iv {
        let (a, b, c, d) = (self.lo * o.lo, self.lo * o.hi, self.hi * o.lo, self.hi * o.hi);
        // A product 0·∞ (NaN) stands for 0, which min and max then ignore rightly, as the other
        // products bound the set; a NaN operand (empty) makes every product NaN.
        let out = Iv { lo: a.min(b).min(c.min(d)).next_down(), hi: a.max(b).max(c.max(d)).next_up() };
        if out.lo.is_nan() && !(self.lo.is_nan() || o.lo.is_nan()) {
            // Every product was 0·∞: [0, 0]·[−∞, ∞] and the like. Whole line, to be safe.
            return Iv { lo: f64::NEG_INFINITY, hi: f64::INFINITY };
        }
        out
    }
}


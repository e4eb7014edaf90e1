//! What the cusp search needs of a mechanism: a map `f` of the torus `[−π, π]²` to the plane,
//! evaluated soundly with its derivatives over boxes (`Jets`). The 3R chain's `(ρ, z)` in
//! `(θ₂, θ₃)` is one (`Chain3R`); a planar platform on three R-P-R legs with one leg locked,
//! its actuated legs' squared lengths in the locked leg's angle and the platform's, is another
//! (`formulate::singular::pose`). The cusp search (`cusps`) is written once, over this trait.

use super::chain::{Chain3R, Derived, Jets};
use super::motion::{self, Band};
use inari::Interval;

/// A smooth map of the torus `[−π, π]²` (periodic in both angles) to the plane.
pub trait TorusMap: Sync {
    /// `f` over `theta`, as jets to `order` (at most `taylor::MAX_ORDER`).
    fn jets(&self, theta: [Interval; 2], order: usize) -> Jets;

    /// `Df`, `det Df` and the tangency rows over `theta`, from jets to `order`.
    fn derived(&self, theta: [Interval; 2], order: usize) -> Derived {
        self.jets(theta, order).derived()
    }

    /// Half-width of the uncertainty in the map's lengths (0 when they are exact): boxes of an
    /// uncertain map are proven by ε-inflation, since its cusps move with the geometry.
    fn uncertainty(&self) -> f64 {
        0.0
    }

    /// Strips `θ₂ ∈ [−π, π]`, `θ₃ ∈ band` on which `det Df` vanishes identically (internal
    /// motions), which the searches set aside; none unless the map has them.
    fn bands(&self, _precision: f64) -> Vec<Band> {
        Vec::new()
    }
}

impl TorusMap for Chain3R {
    fn jets(&self, theta: [Interval; 2], order: usize) -> Jets {
        Chain3R::jets(self, theta, order)
    }

    fn derived(&self, theta: [Interval; 2], order: usize) -> Derived {
        Chain3R::derived(self, theta, order)
    }

    fn uncertainty(&self) -> f64 {
        self.uncertainty
    }

    fn bands(&self, precision: f64) -> Vec<Band> {
        motion::bands(self, precision)
    }
}

//! What the cusp search needs of a mechanism: a map `f` of the torus `[−π, π]²` to the plane,
//! evaluated soundly with its derivatives over boxes (`Jets`). The 3R chain's `(ρ, z)` in
//! `(θ₂, θ₃)` is one (`Chain3R`); a planar platform on three R-P-R legs with one leg locked,
//! its actuated legs' squared lengths in the locked leg's angle and the platform's, is another
//! (`formulate::singular::pose`). The cusp search (`cusps`) is written once, over this trait.

pub use crate::formulate::torus::TorusMap;
use super::chain::{Chain3R, Derived, Jets};
use super::motion::{self, Band};
use crate::kernel::search::{Control, Status};
use inari::Interval;

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

    fn bands(&self, precision: f64, control: &Control) -> (Vec<Band>, Status) {
        motion::bands_within(self, precision, control)
    }
}

//! A smooth map of the torus `[−π, π]²` to the plane, the object the cusp, node and
//! inverse-kinematics searches are written over (`TorusMap`): its values and derivatives over a
//! box as Taylor jets (`Jets`, `Derived`), and the strips where it degenerates (`Band`). The 3R
//! chain's `(ρ, z)` in `(θ₂, θ₃)` is one such map (`analyses::arm3r`), a planar platform's
//! actuator map with one leg locked another (`formulate::singular::pose`).

use crate::kernel::search::{Control, Status};
use crate::kernel::taylor::Taylor;
use inari::Interval;

/// The map and its derivatives over a box, as jets.
#[derive(Clone, Copy, Debug)]
pub struct Jets {
    /// ρ, the squared distance from the first axis.
    pub rho: Taylor,
    /// z, the coordinate along the first axis.
    pub z: Taylor,
}

impl Jets {
    /// f₁ = ρ (`k` = 0) or f₂ = z (`k` = 1).
    pub fn f(&self, k: usize) -> Taylor {
        if k == 0 {
            self.rho
        } else {
            self.z
        }
    }

    /// det Df = ∂ρ/∂θ₂ ∂z/∂θ₃ − ∂ρ/∂θ₃ ∂z/∂θ₂, one order lower than the jets.
    pub fn det(&self) -> Taylor {
        self.rho.d(0) * self.z.d(1) - self.rho.d(1) * self.z.d(0)
    }

    /// System (2) of Benoit, Delanoue, Lagrange and Wenger (2019), row `k`:
    /// `∂f_k/∂θ₂·(−∂det/∂θ₃) + ∂f_k/∂θ₃·∂det/∂θ₂`, that is `∇f_k · T` with
    /// `T = (−∂det/∂θ₃, ∂det/∂θ₂)` the tangent of the singular curve.
    /// Two orders lower than the jets.
    pub fn tangency(&self, k: usize) -> Taylor {
        self.derived().g[k]
    }

    /// Df, det Df and system (2) at once, each computed once.
    pub fn derived(&self) -> Derived {
        let df = [[self.rho.d(0), self.rho.d(1)], [self.z.d(0), self.z.d(1)]];
        let det = df[0][0] * df[1][1] - df[0][1] * df[1][0];
        let g = if det.order() >= 1 {
            let (d0, d1) = (det.d(0), det.d(1));
            [0, 1].map(|k| df[k][1] * d0 - df[k][0] * d1)
        } else {
            [Taylor::constant(Interval::ENTIRE, 0); 2]
        };
        Derived { f: [self.rho, self.z], df, det, g }
    }
}

/// Quantities derived from `Jets` (orders: f as the jets, Df and det one lower, g two lower).
#[derive(Clone, Copy, Debug)]
pub struct Derived {
    /// (ρ, z)
    pub f: [Taylor; 2],
    /// `df[k][i] = ∂fₖ/∂θᵢ`
    pub df: [[Taylor; 2]; 2],
    /// det Df
    pub det: Taylor,
    /// System (2): `g[k] = ∇fₖ · T`
    pub g: [Taylor; 2],
}

/// One internal-motion strip: θ₂ over the whole turn, θ₃ in a band where the map degenerates
/// (`arm3r::motion` finds them for a 3R chain).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Band {
    /// Encloses every θ₃ in the strip where the end point may lie on the second axis.
    pub theta3: [f64; 2],
    /// The strip set aside: `theta3` plus one cell on each side (radians).
    pub strip: [f64; 2],
    /// `Some(d)` for a near-degenerate strip: the end point may come within `d` metres of the
    /// second axis there but is nowhere proven on it (a tiny twist, e.g. an angle written
    /// 1.5707963267948966 and taken as written), so along θ₂ the map may vary by as little as
    /// 2π·d, under what a search box of the precision resolves. Such a strip is set aside
    /// *undecided*: no internal motion is claimed, and reports are incomplete. `None`: a true
    /// band (the point may lie on the axis).
    pub near: Option<f64>,
}

impl Band {
    /// True when the interval `t3` lies inside the strip.
    pub fn holds(&self, t3: Interval) -> bool {
        self.strip[0] <= t3.inf() && t3.sup() <= self.strip[1]
    }
}

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
    /// motions), which the searches set aside; none unless the map has them. Found within
    /// `control` (its time and cancel flag), with how that walk ended: a limit leaves the
    /// stretches it did not reach inside strips, so the strips stay sound and the searches'
    /// answer is incomplete.
    fn bands(&self, _precision: f64, _control: &Control) -> (Vec<Band>, Status) {
        (Vec::new(), Status::Finished)
    }
}

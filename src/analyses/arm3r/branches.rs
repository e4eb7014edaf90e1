//! The singular set of an arm with axes 2 and 3 exactly parallel and axis 1 not (PUMA, KUKA KR,
//! UR), as certified branches, from the same structural data as `verdict::parallel_structure`.
//!
//! Notation (all in the first link's frame, axis 1 through its origin, on the rounded geometry,
//! every quantity an interval): d̂₂ the unit direction of axis 2, ê = a₁ × d₂ / |a₁ × d₂|,
//! t̂ = d̂₂ × ê, so (ê, t̂) is an oriented basis of the plane P ⟂ d₂ in which the point moves
//! (rotation about d₂ by θ turns ê towards t̂). O is the point of axis 2 in P. In these
//! coordinates u = o₃ − o₂ and v = p − o₃ (projected; |u| = l₂, |v| = l₃), axis 3 is s·d₂
//! (s = ±1), and the point is X = O + w with
//!
//! ```text
//! w = h(θ₂, θ₃) = Rot(θ₂) (u + Rot(s θ₃) v),   f = g∘h,   g(w) = (ρ, z)(O + w).
//! ```
//!
//! det Dh = s·l₂·l₃·sin(arg(Rot(sθ₃)v) − arg u), and with w = wₑ ê + w_t t̂, z = a₁·O + (a₁·t̂) w_t
//! is affine (a₁·ê = 0) and ρ = (e₀ + wₑ)² + F(w_t), e₀ = O·ê, so det Dg = 2(a₁·t̂)(e₀ + wₑ),
//! with a₁·t̂ ≠ 0 because a₁ ∦ d₂. Hence det Df = det Dg(h)·det Dh vanishes exactly on
//!
//! - the **outstretched** line θ₃ = θ₃⁺ = s(arg u − arg v) and the **folded** line θ₃⁺ + π
//!   (θ₂ free), mapped by h onto the circles |w| = l₂ + l₃ and |l₂ − l₃|;
//! - the **fold of g**, h⁻¹(L), L = {wₑ = −e₀} the line of P closest to axis 1 (distance
//!   d = |e₀| from axis 2): θ₂ = arg(−e₀, ±√(|m|² − e₀²)) − arg m, m = u + Rot(sθ₃)v, for
//!   every θ₃ with |m(θ₃)| ≥ d. Its image is g(L ∩ annulus), a segment of the line of the
//!   plane through axis 1 and L (for a₁ ⟂ d₂ the vertical segment radius = |X·d̂₂|).
//!
//! g is two-to-one: g(w) = g(w') iff w' is w's mirror image about L. So
//!
//! - every point of h⁻¹(L) inside the open annulus has two h-preimages (elbow up and down),
//!   both on h⁻¹(L), with one image: the fold of g is a **curve of nodes**;
//! - the mirror of the circle |w| = R is the circle of radius R about O's mirror image, which
//!   is the circle itself iff d = 0: then each θ₃ line is a curve of nodes (w and its mirror
//!   are two points of the line with one image); for d > 0 it meets the circle only on L (the
//!   crossings), and it meets the other circle at isolated nodes when
//!   w_e = (R₋² − R₊² − 4e₀²)/(4e₀) lies strictly inside (−R₊, R₊) (listed in `isolated_nodes`).
//!
//! The **crossings** are the points of a θ₃ line on h⁻¹(L): w = (−e₀, ±√(R² − e₀²)), R the
//! line's radius, two per line when d < R and none when d > R; θ₂ = arg w − arg m with
//! m = u·R/l₂ (outstretched) or u·(l₂ − l₃)/l₂ (folded). Angles are enclosed soundly by
//! `arg` (a floating-point guess proven by the signs of two cross products).
//!
//! **No cusp anywhere** (the argument `explain` uses for the cusp search's undecided boxes):
//! off the crossings the singular set is a smooth curve on which f folds. On a θ₃ line off
//! L, Dg is invertible so ker Df = ker Dh, and Dh's columns are J·m and s·J·Rot(sθ₃)v,
//! parallel nonzero vectors (R > 0), so its kernel has a nonzero θ₃ component: transverse to
//! the line. On h⁻¹(L) off the θ₃ lines, Dh is invertible and maps the curve's tangent onto
//! L's direction t̂ while ker Dg = ê: ker Df = Dh⁻¹ ê is transverse to the curve. Both
//! factors have nonzero gradients on their zero sets there, so ∇det ≠ 0 and the system (2)
//! of Benoit et al. (2019) (kernel tangent to the curve) has no solution. At a crossing ∇det = 0:
//! it is a crossing of two fold curves, not a cusp point. This needs l₂ ≠ l₃ proven (else the
//! folded line is an internal motion and the argument is not made).

use super::chain::{add, cross, dot, scale, sub, Chain3R, V3};
use super::records::{bounds, joints, radius, workspace, Bounds, Joints, Workspace};
use crate::kernel::interval::trig::{cos, sin};
use super::verdict::Geometry;
use crate::kernel::interval::{interval, point};
use crate::model::Mechanism;
use inari::Interval;

pub use crate::kernel::interval::angle::{arg, wrap};

mod attribution;

pub use self::attribution::Attribution;

fn unit(v: &V3) -> V3 {
    let n = dot(v, v).sqrt();
    [v[0] / n, v[1] / n, v[2] / n]
}

/// `interval::strict_sign` as a factor ±1.
fn sign(x: Interval) -> Option<f64> {
    crate::kernel::interval::strict_sign(x).map(|positive| if positive { 1.0 } else { -1.0 })
}

/// The planar structure of the arm (module doc's notation).
#[derive(Clone, Debug)]
pub struct Planar {
    a1: V3,
    e: V3,
    t: V3,
    centre: V3,
    /// O·ê: L is wₑ = −e₀, d = |e₀|.
    pub e0: Interval,
    /// o₃ − o₂ in (ê, t̂).
    pub u: [Interval; 2],
    /// p − o₃ in (ê, t̂) at θ₃ = 0.
    pub v: [Interval; 2],
    /// Axis 3 is s·axis 2.
    pub s: f64,
    /// |u|
    pub l2: Interval,
    /// |v|
    pub l3: Interval,
}

fn rot(c: Interval, s: Interval, w: [Interval; 2]) -> [Interval; 2] {
    [c * w[0] - s * w[1], s * w[0] + c * w[1]]
}

impl Planar {
    /// From the mechanism, when axes 2 and 3 are proven parallel and axis 1 not, and both
    /// lengths are proven positive (exactly `verdict::parallel_structure`'s condition).
    pub fn of(m: &Mechanism) -> Option<Self> {
        super::verdict::parallel_structure(m)?;
        Self::from_geometry(&super::verdict::geometry(m)?)
    }

    fn from_geometry(g: &Geometry) -> Option<Self> {
        let d2 = unit(&g.d2);
        let e = unit(&cross(&g.a1, &d2));
        let t = cross(&d2, &e);
        let s = sign(dot(&g.d3, &g.d2))?;
        let centre = add(&g.o2, &scale(&d2, dot(&sub(&g.p, &g.o2), &d2)));
        let uv = |x: &V3| [dot(x, &e), dot(x, &t)];
        let (u, v) = (uv(&sub(&g.o3, &g.o2)), uv(&sub(&g.p, &g.o3)));
        let norm = |w: &[Interval; 2]| (w[0].sqr() + w[1].sqr()).sqrt();
        Some(Planar { a1: g.a1, e, t, centre, e0: dot(&centre, &e), l2: norm(&u), l3: norm(&v), u, v, s })
    }

    /// m(θ₃) = u + Rot(sθ₃) v.
    pub fn m(&self, t3: Interval) -> [Interval; 2] {
        let st = point(self.s) * t3;
        let r = rot(cos(st), sin(st), self.v);
        [self.u[0] + r[0], self.u[1] + r[1]]
    }

    /// w = h(θ₂, θ₃).
    pub fn h(&self, t2: Interval, t3: Interval) -> [Interval; 2] {
        rot(cos(t2), sin(t2), self.m(t3))
    }

    /// g(w) = (ρ, z), as `Chain3R` computes them (ρ = |X − (a₁·X)a₁|², z = a₁·X).
    pub fn g(&self, w: [Interval; 2]) -> (Interval, Interval) {
        let x = add(&self.centre, &add(&scale(&self.e, w[0]), &scale(&self.t, w[1])));
        let z = dot(&self.a1, &x);
        let perp = sub(&x, &scale(&self.a1, z));
        (dot(&perp, &perp), z)
    }

    /// h in plain floating point (midpoints), for tests and sampling only.
    pub fn h_f64(&self, t2: f64, t3: f64) -> [f64; 2] {
        let w = self.h(point(t2), point(t3));
        [w[0].mid(), w[1].mid()]
    }

    /// The θ₂ values of the fold of g at θ₃, in plain floating point (for tests and sampling).
    pub fn fold_theta2_f64(&self, t3: f64) -> Vec<f64> {
        let m = self.m(point(t3)).map(|x| x.mid());
        let e0 = self.e0.mid();
        let r2 = m[0] * m[0] + m[1] * m[1];
        if r2 < e0 * e0 {
            return Vec::new();
        }
        let tau = (r2 - e0 * e0).sqrt();
        let am = m[1].atan2(m[0]);
        [tau, -tau].iter().map(|&y| y.atan2(-e0) - am).collect()
    }

    /// The enclosures of the fold's θ₂ values at θ₃ (`None` where |m| ≥ d is not proven or
    /// an angle is not enclosed).
    fn fold_theta2(&self, t3: Interval) -> Option<[Interval; 2]> {
        let m = self.m(t3);
        let r2 = m[0].sqr() + m[1].sqr();
        let e2 = self.e0.sqr();
        if !((r2 - e2).inf() > 0.0) {
            return None;
        }
        let tau = (r2 - e2).sqrt();
        let am = arg(m[0], m[1])?;
        Some([wrap(arg(-self.e0, tau)? - am), wrap(arg(-self.e0, -tau)? - am)])
    }

    /// Can the box meet the fold of g (interval test: wₑ + e₀ may vanish)?
    pub fn may_meet_fold(&self, b: [Interval; 2]) -> bool {
        let w = self.h(b[0], b[1]);
        (w[0] + self.e0).contains(0.0)
    }
}

/// One crossing of two branches.
#[derive(Clone, Debug, PartialEq)]
pub struct CrossingRecord {
    /// e.g. `outstretched x fold, t > 0`.
    pub name: String,
    /// Joint enclosure.
    pub joints: Joints,
    /// Image enclosure.
    pub workspace: Workspace,
    /// (θ₂, θ₃) enclosed.
    pub theta: [Interval; 2],
}

/// A point of a fold branch at a given θ₃.
#[derive(Clone, Debug, PartialEq)]
pub struct FoldSample {
    /// The third joint (exact).
    pub theta3: f64,
    /// The two θ₂ values, enclosed.
    pub theta2: [Bounds; 2],
}

/// The image of a branch.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageRecord {
    /// In words, with numbers.
    pub description: String,
    /// Enclosure of the radius over the branch.
    pub radius: Bounds,
    /// Enclosure of z over the branch.
    pub z: Bounds,
}

/// One branch of the singular set.
#[derive(Clone, Debug, PartialEq)]
pub struct SingularBranch {
    /// `outstretched`, `folded` or `fold_of_g`.
    pub name: String,
    /// `theta3_line` (θ₂ free, θ₃ enclosed) or `curve` (θ₂ given by a formula in θ₃).
    pub kind: &'static str,
    /// Joint-space description in words.
    pub description: String,
    /// For a θ₃ line: the box (θ₂ over the full range, θ₃ enclosed).
    pub joints: Option<Joints>,
    /// For the fold of g: θ₂ enclosures at sample values of θ₃.
    pub samples: Vec<FoldSample>,
    /// Its image.
    pub image: ImageRecord,
    /// True: every image point is reached from two points of the branch (a curve of nodes);
    /// false: only at isolated points; null: not decided.
    pub curve_of_nodes: Option<bool>,
    /// Crossings with other branches (null count: existence not decided).
    pub crossings: Vec<CrossingRecord>,
    /// Why.
    pub proof: String,
    /// θ₃ enclosure of a line, for attribution.
    pub theta3: Option<Interval>,
}

/// An isolated node between the two θ₃ lines (d > 0 only).
#[derive(Clone, Debug, PartialEq)]
pub struct IsolatedNode {
    /// Its two points (outstretched, folded).
    pub points: [Joints; 2],
    /// Their image.
    pub workspace: Workspace,
}

/// `"singular_branches"` in the JSON.
#[derive(Clone, Debug, PartialEq)]
pub struct SingularBranches {
    /// The branches.
    pub branches: Vec<SingularBranch>,
    /// Crossings of the θ₃ lines with the fold of g, all of them (`null`: not decided).
    pub crossings: Option<usize>,
    /// Isolated nodes (between the outstretched and folded lines, d > 0 only).
    pub isolated_nodes: Vec<IsolatedNode>,
    /// l₂, l₃, d (the fold line's distance from axis 2), enclosed.
    pub l2: Bounds,
    /// see `l2`
    pub l3: Bounds,
    /// see `l2`
    pub d: Bounds,
    /// True when the no-cusp argument of the module doc is made (l₂ ≠ l₃ proven and every
    /// angle enclosed): the cusp search's undecided boxes are then explained.
    pub no_cusp_proven: bool,
    /// The argument.
    pub argument: String,
}

fn image(p: &Planar, pieces: impl Iterator<Item = [Interval; 2]>) -> (Interval, Interval) {
    let mut r = Interval::EMPTY;
    let mut z = Interval::EMPTY;
    for w in pieces {
        let (rho, zz) = p.g(w);
        r = r.convex_hull(radius(rho));
        z = z.convex_hull(zz);
    }
    (r, z)
}

fn pm(x: Interval) -> String {
    format!("{:.6}", x.mid())
}

/// The branches of `chain`'s singular set, `None` unless the structure of
/// `verdict::parallel_structure` holds on `m` (the mechanism `chain` was built from, nominal
/// lengths).
pub fn of(m: &Mechanism, chain: &Chain3R) -> Option<SingularBranches> {
    if chain.uncertainty > 0.0 {
        return None;
    }
    let p = Planar::of(m)?;
    let mut s = Sketch::new(&p, chain);
    let (l2, l3) = (p.l2, p.l3);
    let au = arg(p.u[0], p.u[1]);
    let av = arg(p.v[0], p.v[1]);
    let out = match (au, av) {
        (Some(a), Some(b)) => Some(wrap(point(p.s) * (a - b))),
        _ => None,
    };
    let folded = out.map(|t| wrap(t + Interval::PI));
    let l2_gt_l3 = sign(l2 - l3);
    if l2_gt_l3.is_none() || out.is_none() {
        s.complete = false;
    }
    let mut branches = Vec::new();
    let mut total = Some(0usize);
    let mut all_crossings = Vec::new();
    for (name, radius, theta3, arg_m) in [
        ("outstretched", s.rp, out, au),
        ("folded", s.rm, folded, au.zip(l2_gt_l3).map(|(a, sg)| if sg > 0.0 { a } else { a + Interval::PI })),
    ] {
        let branch = s.theta3_line(name, radius, theta3, arg_m, &mut total);
        all_crossings.extend(branch.crossings.iter().cloned());
        branches.push(branch);
    }
    if let Some(fold) = s.fold_of_g(&all_crossings) {
        branches.push(fold);
    }
    let isolated_nodes = s.isolated_nodes(out, folded, au, l2_gt_l3);
    let no_cusp_proven = s.complete && s.rm.inf() > 0.0;
    Some(SingularBranches {
        argument: format!(
            "f = g o h with h the planar 2R of joints 2-3 and g two-to-one (mirror about the line L of the plane of motion closest to axis 1), so det Df = det Dg(h) det Dh vanishes exactly on the two theta3 lines (det Dh = 0) and on h^-1(L) (det Dg = 0); off their crossings each is a smooth curve on which f folds (ker Df transverse to it, closed form), so no point of the singular set is a cusp point; at a crossing grad det = 0 (two folds cross, no cusp){}",
            if no_cusp_proven { "" } else { "; NOT all of this is proven here (an angle, an existence or l2 != l3 undecided)" }
        ),
        branches,
        crossings: total,
        isolated_nodes,
        l2: bounds(l2),
        l3: bounds(l3),
        d: bounds(s.d),
        no_cusp_proven,
    })
}

/// What `of` derives the branches from: the planar reduction, the chain for joint names and
/// boxes, the radii of the two θ₃ lines' circles and the fold line's distance, and whether
/// every step so far was decided (`complete`).
struct Sketch<'a> {
    p: &'a Planar,
    chain: &'a Chain3R,
    e0: Interval,
    /// `|e₀|`: the fold line's distance from axis 2.
    d: Interval,
    /// `l₂ + l₃` and `|l₂ − l₃|`: the radii of the outstretched and folded circles.
    rp: Interval,
    rm: Interval,
    /// `d = 0` exactly, and `d > 0` proven.
    d_zero: bool,
    d_pos: bool,
    complete: bool,
}

impl<'a> Sketch<'a> {
    fn new(p: &'a Planar, chain: &'a Chain3R) -> Self {
        let (l2, l3, e0) = (p.l2, p.l3, p.e0);
        let d = e0.abs();
        let (rp, rm) = (l2 + l3, (l2 - l3).abs());
        let d_zero = e0.inf() == 0.0 && e0.sup() == 0.0;
        let d_pos = d.inf() > 0.0;
        Sketch { p, chain, e0, d, rp, rm, d_zero, d_pos, complete: true }
    }

    /// The θ₃ line `name` (`theta3`, the circle of `radius` about axis 2 in the plane of
    /// motion; `arg_m` the angle of its `m`), with its crossings with the fold of g, whose
    /// count is added to `total` (`None` once a count is not decided).
    fn theta3_line(&mut self, name: &str, radius: Interval, theta3: Option<Interval>, arg_m: Option<Interval>, total: &mut Option<usize>) -> SingularBranch {
        let (p, chain, e0, d) = (self.p, self.chain, self.e0, self.d);
        let full = super::motion::full_range();
        let steps = 256;
        let arc = |k: usize| interval(-std::f64::consts::PI + std::f64::consts::TAU * k as f64 / steps as f64, -std::f64::consts::PI + std::f64::consts::TAU * (k + 1) as f64 / steps as f64);
        let circle = arc_pieces(radius, steps, &arc);
        let (ir, iz) = image(p, circle);
        let exists = if d.sup() < radius.inf() {
            Some(true)
        } else if d.inf() > radius.sup() {
            Some(false)
        } else {
            None
        };
        let mut crossings = Vec::new();
        match (exists, theta3, arg_m) {
            (Some(true), Some(t3), Some(am)) => {
                let tau = (radius.sqr() - e0.sqr()).sqrt();
                for (sgn, label) in [(1.0, "w_t > 0"), (-1.0, "w_t < 0")] {
                    let w = [-e0, point(sgn) * tau];
                    match arg(w[0], w[1]) {
                        Some(aw) => {
                            let t2 = wrap(aw - am);
                            let (rho, z) = p.g(w);
                            let theta = [t2, t3];
                            crossings.push(CrossingRecord { name: format!("{name} x fold_of_g, {label}"), joints: joints(chain, &theta), workspace: workspace(rho, z), theta });
                        }
                        None => self.complete = false,
                    }
                }
                *total = total.map(|n| n + 2);
            }
            (Some(false), _, _) => {}
            _ => {
                *total = None;
                self.complete = false;
            }
        }
        let curve_of_nodes = if self.d_zero {
            Some(true)
        } else if self.d_pos {
            Some(false)
        } else {
            None
        };
        let description = match theta3 {
            Some(t) => format!("{} = {} (enclosure [{:.15}, {:.15}]), {} free: the 2R of joints 2-3 {}", chain.joints[2], pm(t), t.inf(), t.sup(), chain.joints[1], if name == "outstretched" { "outstretched" } else { "folded back" }),
            None => format!("{} = constant (not enclosed)", chain.joints[2]),
        };
        SingularBranch {
            name: name.into(),
            kind: "theta3_line",
            description,
            joints: theta3.map(|t| joints(chain, &[full, t])),
            samples: Vec::new(),
            image: ImageRecord {
                description: format!("g of the circle of radius {} about axis 2 in the plane of motion (an oval of the (radius, z) half-plane)", pm(radius)),
                radius: bounds(ir),
                z: bounds(iz),
            },
            curve_of_nodes,
            crossings,
            proof: format!(
                "det Dh = s*l2*l3*sin(elbow angle) vanishes exactly here; {}",
                match curve_of_nodes {
                    Some(true) => "the fold line L of g passes through axis 2 (d = 0 exactly), so the mirror image about L of each point of the circle is another point of the circle: two points of this line per image point",
                    Some(false) => "d > 0: the circle's mirror image about L meets it only on L (the crossings), so its points have no partner on this line",
                    None => "d = 0 not decided",
                }
            ),
            theta3,
        }
    }

    /// The fold of g (where the wrist is in the plane through axis 1 parallel to axis 2), with
    /// every crossing of the θ₃ lines; `None` when it is proven not to exist or not decided.
    fn fold_of_g(&mut self, all_crossings: &[CrossingRecord]) -> Option<SingularBranch> {
        let (p, chain, e0, d, rp, rm) = (self.p, self.chain, self.e0, self.d, self.rp, self.rm);
        let fold_exists = sign(rp - d);
        let mut samples = Vec::new();
        let n = 24;
        for k in 0..n {
            let t3 = -std::f64::consts::PI + std::f64::consts::TAU * k as f64 / n as f64;
            if let Some(t2) = p.fold_theta2(point(t3)) {
                samples.push(FoldSample { theta3: t3, theta2: t2.map(bounds) });
            }
        }
        if fold_exists != Some(1.0) {
            if fold_exists.is_none() {
                self.complete = false;
            }
            return None;
        }
        let tau_hi = (rp.sqr() - e0.sqr()).sqrt();
        let tau_lo = if d.sup() < rm.inf() { (rm.sqr() - e0.sqr()).sqrt() } else { point(0.0) };
        let seg = |k: usize, sg: f64| {
            let lo = tau_lo.inf() + (tau_hi.sup() - tau_lo.inf()) * k as f64 / 128.0;
            let hi = tau_lo.inf() + (tau_hi.sup() - tau_lo.inf()) * (k + 1) as f64 / 128.0;
            [-e0, point(sg) * interval(lo, hi.max(lo))]
        };
        let (ir, iz) = image(p, (0..128).flat_map(|k| [seg(k, 1.0), seg(k, -1.0)]));
        let a1t = dot(&p.a1, &p.t);
        let vertical = a1t.abs().inf() == 1.0 && a1t.abs().sup() == 1.0;
        // For a₁ ⟂ d₂ the radius on L is constant: its value at one point of L, tightly.
        let ir = if vertical { radius(p.g([-e0, point(0.0)]).0) } else { ir };
        let description = if vertical {
            format!("axis 1 is perpendicular to axis 2, so the image is the vertical segment radius = {:.6} (the point's constant offset along axis 2 from axis 1) for z in [{:.6}, {:.6}], covered twice (the annulus meets L in two segments){}", ir.mid(), iz.inf(), iz.sup(), if ir.sup() < 1e-12 { ": axis 1 itself" } else { "" })
        } else {
            format!("a segment of the line where the plane of axis 1 and L cuts P, mapped to (radius, z): radius in [{:.6}, {:.6}], z in [{:.6}, {:.6}]", ir.inf(), ir.sup(), iz.inf(), iz.sup())
        };
        Some(SingularBranch {
            name: "fold_of_g".into(),
            kind: "curve",
            description: format!(
                "{t2} = arg(-e0, +-sqrt(|m|^2 - e0^2)) - arg m, m = u + Rot({s}*{t3}) v, for every {t3} with |m| >= d (e0 = {e0:.6}, u = ({:.6}, {:.6}), v = ({:.6}, {:.6}) in the plane of motion): the points where the wrist is in the plane through axis 1 parallel to axis 2{}",
                p.u[0].mid(),
                p.u[1].mid(),
                p.v[0].mid(),
                p.v[1].mid(),
                if d.sup() < rm.inf() { format!("; d < |l2 - l3|, so two closed curves, graphs over {}", chain.joints[2]) } else { String::new() },
                t2 = chain.joints[1],
                t3 = chain.joints[2],
                s = p.s,
                e0 = e0.mid()
            ),
            joints: None,
            samples,
            image: ImageRecord { description, radius: bounds(ir), z: bounds(iz) },
            curve_of_nodes: Some(true),
            crossings: all_crossings.to_vec(),
            proof: "det Dg = 2 (a1.t) (e0 + w_e) vanishes exactly on the line L (w_e = -e0) of the plane of motion; each point of L inside the open annulus has two h-preimages (elbow up and down), both on this curve, with one image: a curve of nodes".into(),
            theta3: None,
        })
    }

    /// Isolated nodes between the two lines (d > 0): w on the outstretched circle whose mirror
    /// about L is on the folded one. `out`, `folded`: the lines' θ₃; `a_out`: the angle of the
    /// outstretched `m`; `l2_gt_l3`: the sign of `l₂ − l₃`.
    fn isolated_nodes(&mut self, out: Option<Interval>, folded: Option<Interval>, a_out: Option<Interval>, l2_gt_l3: Option<f64>) -> Vec<IsolatedNode> {
        let (p, chain, e0, rp, rm) = (self.p, self.chain, self.e0, self.rp, self.rm);
        let mut isolated_nodes = Vec::new();
        if self.d_pos {
            if let (Some(t_out), Some(t_fold), Some(a_out), Some(sg)) = (out, folded, a_out, l2_gt_l3) {
                let we = (rm.sqr() - rp.sqr() - point(4.0) * e0.sqr()) / (point(4.0) * e0);
                let a_fold = if sg > 0.0 { a_out } else { a_out + Interval::PI };
                let inside = (rp - we.abs()).inf() > 0.0;
                let outside = (we.abs() - rp).inf() > 0.0;
                if inside {
                    let wt = (rp.sqr() - we.sqr()).sqrt();
                    for sgn in [1.0, -1.0] {
                        let w = [we, point(sgn) * wt];
                        let w2 = [point(-2.0) * e0 - we, point(sgn) * wt];
                        match (arg(w[0], w[1]), arg(w2[0], w2[1])) {
                            (Some(x), Some(y)) => {
                                let (rho, z) = p.g(w);
                                let (rho2, z2) = p.g(w2);
                                isolated_nodes.push(IsolatedNode {
                                    points: [joints(chain, &[wrap(x - a_out), t_out]), joints(chain, &[wrap(y - a_fold), t_fold])],
                                    workspace: workspace(rho.intersection(rho2), z.intersection(z2)),
                                });
                            }
                            _ => self.complete = false,
                        }
                    }
                } else if !outside {
                    self.complete = false;
                }
            } else {
                self.complete = false;
            }
        } else if !self.d_zero {
            self.complete = false;
        }
        isolated_nodes
    }
}

fn arc_pieces<'a>(radius: Interval, steps: usize, arc: &'a dyn Fn(usize) -> Interval) -> impl Iterator<Item = [Interval; 2]> + 'a {
    (0..steps).map(move |k| {
        let phi = arc(k);
        [radius * cos(phi), radius * sin(phi)]
    })
}

#[cfg(test)]
mod tests;

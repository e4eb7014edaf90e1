//! The cusp system of a planar platform on R-P-R legs in pose coordinates, not in the joint
//! coordinates of every leg. Each leg `i` is a revolute joint to the ground at `A_i`, a slider
//! along the leg whose axis passes through `A_i`, and a revolute joint on the platform at
//! `B_i = P + R(φ) b_i` on the slider's axis, so its travel is `|B_i − A_i|` (limits above 0).
//! Three legs, one locked (`--fix`) at length `L`, two actuated. The locked leg's end is
//! `B_l = A_l + L u`, `u = (cos α, sin α)`, so a configuration is a point `(α, φ)` of a torus
//! (held as two `(c, s)` pairs) and the legs' angles and travels follow from it: `C` is the
//! torus itself, no constraint row is left, and the search is two-dimensional.
//!
//! The actuator map is `h_i = |E_i|²`, `E_i = B_i − A_i = A_l + L u + R(φ) d_i − A_i`,
//! `d_i = b_i − b_l` (a diffeomorphism of the travels, so the same cusps). With `U = L u`,
//! `D_i = R(φ) d_i`, the gradient of `h_i / 2` in `(α, φ)` is `(U × E_i, D_i × E_i)` and its
//! second derivative along `v` is `v_α² (L² − E_i·U) + 2 v_α v_φ U·D_i + v_φ² (|d_i|² − E_i·D_i)`.
//! The system is the one of `image`'s module doc with no `F` rows and these for `A`: `A v = 0`,
//! `μ H[v, v] + A w = 0`, `v_k = 1`, `w_k = 0`, one chart of `(μ, w)`: 4 chart pairs (36 in the
//! joint coordinates of the bundled 3-RPR). `v`, `w` and `μ` are derived variables: once the
//! pose is known they solve a linear system, so the search bisects the pose alone and Krawczyk,
//! on the whole square system, narrows them and certifies the roots. A regular root with `μ ≠ 0`
//! is a Whitney cusp as in `image`.
//!
//! The same map, `(α, φ) ↦ (h_a, h_b)` over the actuated legs, is also a `arm3r::TorusMap`
//! (`LockedLegMap`): the cusp search of the 3R arms runs on it directly, two angles and no
//! auxiliary unknown (`CuspFormulation::Torus`, the default for this platform).

use super::image::{pin, Builder};
use super::CHART_REACH;
use crate::kernel::interval::angle::{arg, wrap};
use crate::kernel::interval::{interval, point, Interval, IntervalBox};
use crate::formulate::torus::{Jets, TorusMap};
use crate::kernel::taylor::Taylor;
use crate::model::{JointKind, Mechanism};
use crate::formulate::angles::stated;
use crate::kernel::system::{Equation, EquationSystem, Monomial, Term, VarId, VarRole};
use nalgebra::Vector3;
use std::collections::BTreeMap;

/// Which angle a link turns by.
#[derive(Clone, Copy, Debug, PartialEq)]
enum LinkAngle {
    Ground,
    Leg(usize),
    Platform,
}

/// How a free joint's value is read from a pose box.
#[derive(Clone, Copy, Debug)]
enum Reading {
    /// A slider: the square root of its `h` variable.
    Travel(VarId),
    /// A revolute joint or loop: the child's (successor's) angle minus the parent's.
    Revolute { parent: LinkAngle, child: LinkAngle },
}

/// One R-P-R leg as read from the mechanism.
#[derive(Clone, Debug)]
struct Leg {
    /// The ground point `A`.
    ground: [Interval; 2],
    /// The platform point `b` in the platform's frame.
    platform: [Interval; 2],
    /// The slider's name.
    slider: String,
    /// The slider's limits.
    limits: (f64, f64),
}

/// What `recognise` reads: the legs, which one is locked and at what length, and the readings
/// of the joints that are not computed from an `h` variable.
struct Platform {
    legs: Vec<Leg>,
    locked: usize,
    length: f64,
    readings: Vec<(String, Reading)>,
}

/// The cusp systems in pose coordinates and how to read joint values off their boxes.
#[derive(Clone, Debug)]
pub(crate) struct PoseCusps {
    /// One system per chart pair, as `CuspProblem::charts`.
    pub charts: Vec<((usize, usize), EquationSystem)>,
    /// `[v_x, v_y, v_φ]`.
    pub v: Vec<VarId>,
    /// `[μ, w_x, w_y, w_φ]`.
    pub tangent: Vec<VarId>,
    /// The pose variables `x, y, c, s` come first: the configuration part of a box.
    pub base_vars: usize,
    pub readout: PoseReadout,
    /// The actuator map on the torus of the two angles.
    pub map: LockedLegMap,
}

/// One actuated leg of `LockedLegMap`.
#[derive(Clone, Debug)]
struct ActuatedLeg {
    /// The slider's name.
    slider: String,
    /// `A_l − A_i`: the locked leg's ground point from this leg's.
    ground: [Interval; 2],
    /// `d_i = b_i − b_l` in the platform's frame.
    platform: [Interval; 2],
    /// The slider's travel limits.
    travel: Interval,
    /// The pose system's `X_i, Y_i` and `h_i` (`= X_i² + Y_i²`).
    vars: (VarId, VarId, VarId),
}

/// The actuator map of the platform with its locked leg, `(α, φ) ↦ (h_a, h_b)`: the actuated
/// legs' squared lengths `|E_i|²`, `E_i = A_l − A_i + L u(α) + R(φ) d_i`, over the torus of
/// the locked leg's angle `α` and the platform's angle `φ`. Every point of the torus is a
/// configuration while the travels stay within their limits (`within_travel`).
#[derive(Clone, Debug)]
pub(crate) struct LockedLegMap {
    length: Interval,
    legs: [ActuatedLeg; 2],
    /// The pose system's `cos α, sin α, cos φ, sin φ`.
    trig: [VarId; 4],
}

impl LockedLegMap {
    /// `E_i` of both actuated legs over `theta = (α, φ)`, as jets to `order`.
    fn ends(&self, theta: [Interval; 2], order: usize) -> [[Taylor; 2]; 2] {
        let (sa, ca) = Taylor::sin_cos(0, theta[0], order);
        let (sp, cp) = Taylor::sin_cos(1, theta[1], order);
        let (ua, va) = (ca.scale(self.length), sa.scale(self.length));
        [0, 1].map(|i| {
            let l = &self.legs[i];
            let d = l.platform;
            [(ua + cp.scale(d[0]) - sp.scale(d[1])).shift(l.ground[0]), (va + sp.scale(d[0]) + cp.scale(d[1])).shift(l.ground[1])]
        })
    }

    /// `Some(true)` when both actuated travels over `theta` lie within their limits,
    /// `Some(false)` when one lies wholly outside (no configuration there), `None` otherwise.
    pub(crate) fn within_travel(&self, theta: [Interval; 2]) -> Option<bool> {
        let e = self.ends(theta, 0);
        let mut inside = true;
        for (l, e) in self.legs.iter().zip(e) {
            let travel = (e[0] * e[0] + e[1] * e[1]).value().sqrt();
            if travel.disjoint(l.travel) {
                return Some(false);
            }
            inside &= travel.subset(l.travel);
        }
        inside.then_some(true)
    }
}

/// The platform's actuator map on its torus, with what reads joint values off a torus box: the
/// cusp and node searches of the `Torus` formulation run on `map`.
#[derive(Clone, Debug)]
pub(crate) struct PlatformTorus {
    pub map: LockedLegMap,
    /// Per component of the map, its slider's index in the actuated joints.
    actuated: [usize; 2],
    readout: PoseReadout,
    /// A box of the pose systems (a chart's initial box), which `pose_box` fills.
    template: IntervalBox,
}

impl PlatformTorus {
    /// The torus of `m` with `fixed` and `actuated`, or `None` when `m` is not a planar platform
    /// on three R-P-R legs with one locked (see `recognise`).
    pub(crate) fn new(m: &Mechanism, fixed: &[(String, f64)], actuated: &[String]) -> Option<Self> {
        let p = PoseCusps::new(m, fixed, actuated)?;
        let index = |slider: &str| actuated.iter().position(|a| a == slider);
        let order = [index(&p.map.legs[0].slider)?, index(&p.map.legs[1].slider)?];
        let template = p.charts[0].1.initial_box();
        Some(Self { map: p.map, actuated: order, readout: p.readout, template })
    }

    /// A box of the pose systems over `theta`: the angles' cosines and sines, the legs'
    /// `X_i, Y_i` and `h_i` set to their enclosures (the rest as a chart's initial box), which
    /// is all `PoseReadout::joint_values` and the clustering by pose read.
    pub(crate) fn pose_box(&self, theta: [Interval; 2]) -> IntervalBox {
        let map = &self.map;
        let mut b = self.template.clone();
        let [cl, sl, c, s] = map.trig;
        b.dims[cl] = crate::kernel::interval::trig::cos(theta[0]);
        b.dims[sl] = crate::kernel::interval::trig::sin(theta[0]);
        b.dims[c] = crate::kernel::interval::trig::cos(theta[1]);
        b.dims[s] = crate::kernel::interval::trig::sin(theta[1]);
        for (l, e) in map.legs.iter().zip(map.ends(theta, 0)) {
            let (x, y, h) = l.vars;
            b.dims[x] = e[0].value();
            b.dims[y] = e[1].value();
            b.dims[h] = (e[0] * e[0] + e[1] * e[1]).value();
        }
        b
    }

    /// For each component of the map (`h_a`, `h_b`, in leg order), its slider's index in
    /// `actuated`.
    pub(crate) fn actuated_order(&self) -> [usize; 2] {
        self.actuated
    }

    /// Free joint values over the torus box `theta` (radians or metres), outward rounded.
    pub(crate) fn joint_values(&self, theta: [Interval; 2]) -> BTreeMap<String, (f64, f64)> {
        self.readout.joint_values(&self.pose_box(theta))
    }
}

impl TorusMap for LockedLegMap {
    fn jets(&self, theta: [Interval; 2], order: usize) -> Jets {
        let [a, b] = self.ends(theta, order);
        Jets { rho: a[0] * a[0] + a[1] * a[1], z: b[0] * b[0] + b[1] * b[1] }
    }
}

/// Joint values over a pose box.
#[derive(Clone, Debug)]
pub(crate) struct PoseReadout {
    /// Per leg, the variables `X_i, Y_i` (`B_i − A_i`).
    legs: Vec<(VarId, VarId)>,
    /// The platform's `c, s`.
    platform: (VarId, VarId),
    readings: Vec<(String, Reading)>,
}

impl PoseReadout {
    fn angle(&self, b: &[Interval], a: LinkAngle) -> Option<Interval> {
        match a {
            LinkAngle::Ground => Some(point(0.0)),
            LinkAngle::Leg(i) => arg(b[self.legs[i].0], b[self.legs[i].1]),
            LinkAngle::Platform => arg(b[self.platform.0], b[self.platform.1]),
        }
    }

    /// Free joint values over a box (radians or metres), outward rounded; an angle whose
    /// vectors may vanish reads `[−4, 4]` (every angle the readings use).
    pub(crate) fn joint_values(&self, b: &IntervalBox) -> BTreeMap<String, (f64, f64)> {
        let d = &b.dims;
        self.readings
            .iter()
            .map(|(name, r)| {
                let x = match *r {
                    Reading::Travel(h) => d[h].sqrt(),
                    Reading::Revolute { parent, child } => match (self.angle(d, parent), self.angle(d, child)) {
                        (Some(p), Some(c)) => wrap(c - p),
                        _ => interval(-4.0, 4.0),
                    },
                };
                (name.clone(), (x.inf(), x.sup()))
            })
            .collect()
    }
}

fn planar_zero(v: &Vector3<f64>) -> bool {
    v.x == 0.0 && v.y == 0.0
}

fn in_plane(v: &Vector3<f64>) -> [Interval; 2] {
    [stated(v.x), stated(v.y)]
}

const Z: Vector3<f64> = Vector3::new(0.0, 0.0, 1.0);
const X: Vector3<f64> = Vector3::new(1.0, 0.0, 0.0);

/// The legs, the readings and the locked leg's length when `m` is a planar platform on three
/// R-P-R legs (every frame unrotated, revolute axes `+z`, slider axes `+x`, continuous revolute
/// joints, slider limits above 0) with one slider fixed at `locked` and the two others
/// actuated; `None` for any other mechanism.
fn recognise(m: &Mechanism, fixed: &[(String, f64)], actuated: &[String]) -> Option<Platform> {
    let unrotated = |rpy: [f64; 3]| rpy == [0.0; 3];
    if m.joints.iter().any(|j| j.mimic.is_some() || !unrotated(j.rpy)) || m.loops.iter().any(|l| l.compound.is_some() || !unrotated(l.predecessor_rpy) || !unrotated(l.successor_rpy)) {
        return None;
    }
    let legs_n = m.joints.iter().filter(|j| matches!(j.kind, JointKind::Prismatic { .. })).count();
    if legs_n != 3 || m.links.len() != 2 * legs_n + 2 || m.joints.len() != 2 * legs_n + 1 || m.loops.len() != legs_n - 1 {
        return None;
    }
    let mut angle_of: BTreeMap<usize, LinkAngle> = BTreeMap::from([(m.root, LinkAngle::Ground)]);
    let mut legs = Vec::new();
    let mut platform: Option<usize> = None;
    let mut readings = Vec::new();
    let mut same_platform = |p: usize| *platform.get_or_insert(p) == p;
    for p in m.joints.iter().filter(|j| matches!(j.kind, JointKind::Prismatic { .. })) {
        let JointKind::Prismatic { limits } = p.kind else { return None };
        let i = legs.len();
        let base = m.joints.get(m.links[p.parent].parent_joint?)?;
        let continuous = base.kind == JointKind::Revolute { limits: None };
        if !continuous || base.parent != m.root || base.axis != Z || p.axis != X || !planar_zero(&p.origin.translation.vector) || limits.0 <= 0.0 {
            return None;
        }
        angle_of.insert(p.parent, LinkAngle::Leg(i));
        angle_of.insert(p.child, LinkAngle::Leg(i));
        readings.push((base.name.clone(), Reading::Revolute { parent: LinkAngle::Ground, child: LinkAngle::Leg(i) }));
        // The slider's end on the platform: a tree joint from the slide or a loop.
        let tree = m.joints.iter().find(|j| j.parent == p.child);
        let b = if let Some(j) = tree {
            if j.kind != (JointKind::Revolute { limits: None }) || j.axis != Z || !planar_zero(&j.origin.translation.vector) || !same_platform(j.child) {
                return None;
            }
            readings.push((j.name.clone(), Reading::Revolute { parent: LinkAngle::Leg(i), child: LinkAngle::Platform }));
            [point(0.0), point(0.0)]
        } else {
            let l = m.loops.iter().find(|l| l.predecessor == p.child || l.successor == p.child)?;
            if l.kind != (JointKind::Revolute { limits: None }) || l.axis != Z {
                return None;
            }
            let (slide_origin, plat, plat_origin, slide_is_successor) =
                if l.successor == p.child { (&l.successor_origin, l.predecessor, &l.predecessor_origin, true) } else { (&l.predecessor_origin, l.successor, &l.successor_origin, false) };
            if !planar_zero(&slide_origin.translation.vector) || !same_platform(plat) {
                return None;
            }
            let (parent, child) = if slide_is_successor { (LinkAngle::Platform, LinkAngle::Leg(i)) } else { (LinkAngle::Leg(i), LinkAngle::Platform) };
            readings.push((l.name.clone(), Reading::Revolute { parent, child }));
            in_plane(&plat_origin.translation.vector)
        };
        legs.push(Leg { ground: in_plane(&base.origin.translation.vector), platform: b, slider: p.name.clone(), limits });
    }
    let platform = platform?;
    angle_of.insert(platform, LinkAngle::Platform);
    // Every link read, one platform joined by a tree joint; sliders fixed or actuated, nothing else.
    if angle_of.len() != m.links.len() || m.links[platform].parent_joint.is_none() {
        return None;
    }
    if fixed.len() != 1 || actuated.len() != 2 {
        return None;
    }
    let locked = legs.iter().position(|l| l.slider == fixed[0].0)?;
    let length = fixed[0].1;
    if !(length > 0.0) || actuated.iter().any(|a| a == &fixed[0].0 || !legs.iter().any(|l| &l.slider == a)) || actuated[0] == actuated[1] {
        return None;
    }
    Some(Platform { legs, locked, length, readings })
}

fn lin(coef: Interval, v: VarId) -> Term {
    Term { coef, mono: Monomial::Linear(v) }
}

/// `coef · p · q` (a square for `p = q`).
fn prod(coef: Interval, p: VarId, q: VarId) -> Term {
    Term { coef, mono: if p == q { Monomial::Square(p) } else { Monomial::Product(p, q) } }
}

/// `Σ coef · p · q + constant` as a derived variable (its domain from the terms' domains, within
/// `bound`).
fn quadratic(b: &mut Builder, name: String, terms: &[(Interval, VarId, VarId)], constant: Interval, bound: Interval) -> VarId {
    let dom = |v: VarId| b.aug.vars[v].domain;
    let value = terms.iter().fold(constant, |acc, &(k, p, q)| acc + k * if p == q { dom(p).sqr() } else { dom(p) * dom(q) }).intersection(bound);
    let z = b.aug.add_var(name, VarRole::Derived, value);
    let mut t = vec![lin(point(1.0), z)];
    t.extend(terms.iter().map(|&(k, p, q)| prod(-k, p, q)));
    b.aug.add(Equation::new(t, -constant));
    z
}

/// `Σ coef · var + constant` as a derived variable (its domain from the terms' domains, within
/// `bound`).
fn linear(b: &mut Builder, name: String, terms: &[(Interval, VarId)], constant: Interval, bound: Interval) -> VarId {
    let dom = terms.iter().fold(constant, |acc, &(c, v)| acc + c * b.aug.vars[v].domain).intersection(bound);
    let z = b.aug.add_var(name, VarRole::Derived, dom);
    let mut t = vec![lin(point(1.0), z)];
    t.extend(terms.iter().map(|&(c, v)| lin(-c, v)));
    b.aug.add(Equation::new(t, -constant));
    z
}

impl PoseCusps {
    /// The pose cusp systems of `m` with `fixed` and `actuated`, or `None` when `m` is not a
    /// planar platform on three R-P-R legs (see `recognise`).
    pub(crate) fn new(m: &Mechanism, fixed: &[(String, f64)], actuated: &[String]) -> Option<Self> {
        let Platform { legs, locked, length, mut readings } = recognise(m, fixed, actuated)?;
        let mut b = Builder::new(EquationSystem::default());
        let unit = interval(-1.0, 1.0);
        // The locked leg's direction u and the platform's angle: the torus C lies in.
        let cl = b.aug.add_var(format!("cos_{}", legs[locked].slider), VarRole::Primary, unit);
        let sl = b.aug.add_var(format!("sin_{}", legs[locked].slider), VarRole::Primary, unit);
        let c = b.aug.add_var("cos_platform", VarRole::Primary, unit);
        let s = b.aug.add_var("sin_platform", VarRole::Primary, unit);
        b.aug.add(Equation::circle(cl, sl));
        b.aug.add(Equation::circle(c, s));
        let base_vars = b.aug.vars.len();
        // v, w and μ follow from the pose (a linear system once it is known): bisecting the pose
        // alone, the search is two-dimensional, and Krawczyk narrows them.
        let reach = interval(-CHART_REACH, CHART_REACH);
        let v: Vec<VarId> = ["alpha", "phi"].iter().map(|n| b.aug.add_var(format!("v_{n}"), VarRole::Derived, reach)).collect();
        let w: Vec<VarId> = ["alpha", "phi"].iter().map(|n| b.aug.add_var(format!("w_{n}"), VarRole::Derived, reach)).collect();
        let mu = b.aug.add_var("mu", VarRole::Derived, reach);
        // μ v_a v_b: the second-order terms as products of two unknowns.
        let t: Vec<VarId> = (0..2).map(|a| quadratic(&mut b, format!("mu*v_{a}"), &[(point(1.0), mu, v[a])], point(0.0), Interval::ENTIRE)).collect();
        let r = [(0, 0), (0, 1), (1, 1)].map(|(i, j)| quadratic(&mut b, format!("mu*v_{i}*v_{j}"), &[(point(1.0), t[i], v[j])], point(0.0), Interval::ENTIRE));
        let len = stated(length);
        let (al, bl) = (legs[locked].ground, legs[locked].platform);
        let mut leg_xy = vec![(cl, sl); legs.len()];
        let mut actuated_legs = Vec::new();
        for (i, l) in legs.iter().enumerate() {
            if i == locked {
                continue;
            }
            let hi = stated(l.limits.1);
            let bound = interval(-hi.sup(), hi.sup());
            // E = B − A = A_l + L u + R(φ) d − A, d = b − b_l.
            let d = [l.platform[0] - bl[0], l.platform[1] - bl[1]];
            let xv = linear(&mut b, format!("X_{i}"), &[(len, cl), (d[0], c), (-d[1], s)], al[0] - l.ground[0], bound);
            let yv = linear(&mut b, format!("Y_{i}"), &[(len, sl), (d[1], c), (d[0], s)], al[1] - l.ground[1], bound);
            leg_xy[i] = (xv, yv);
            let lo = stated(l.limits.0);
            let h = quadratic(&mut b, format!("{}^2", l.slider), &[(point(1.0), xv, xv), (point(1.0), yv, yv)], point(0.0), interval(lo.sqr().inf(), hi.sqr().sup()));
            readings.push((l.slider.clone(), Reading::Travel(h)));
            actuated_legs.push(ActuatedLeg { slider: l.slider.clone(), ground: [al[0] - l.ground[0], al[1] - l.ground[1]], platform: d, travel: lo.convex_hull(hi), vars: (xv, yv, h) });
            // The gradient of |E|²/2 in (α, φ): (U × E, D × E), U = L u, D = R(φ) d.
            let ga = quadratic(&mut b, format!("grad_alpha_{i}"), &[(len, cl, yv), (-len, sl, xv)], point(0.0), Interval::ENTIRE);
            let gp = quadratic(&mut b, format!("grad_phi_{i}"), &[(d[0], c, yv), (-d[1], s, yv), (-d[1], c, xv), (-d[0], s, xv)], point(0.0), Interval::ENTIRE);
            // Its second derivative along v: v_α² (L² − E·U) + 2 v_α v_φ U·D + v_φ² (|d|² − E·D).
            let paa = quadratic(&mut b, format!("h_aa_{i}"), &[(-len, cl, xv), (-len, sl, yv)], len.sqr(), Interval::ENTIRE);
            let pap = quadratic(&mut b, format!("h_ap_{i}"), &[(len * d[0], cl, c), (-len * d[1], cl, s), (len * d[1], sl, c), (len * d[0], sl, s)], point(0.0), Interval::ENTIRE);
            let ppp = quadratic(&mut b, format!("h_pp_{i}"), &[(-d[0], c, xv), (d[1], s, xv), (-d[1], c, yv), (-d[0], s, yv)], d[0].sqr() + d[1].sqr(), Interval::ENTIRE);
            // A v = 0; μ H[v, v] + A w = 0.
            b.aug.add(Equation::new(vec![prod(point(1.0), ga, v[0]), prod(point(1.0), gp, v[1])], point(0.0)));
            b.aug.add(Equation::new(
                vec![prod(point(1.0), ga, w[0]), prod(point(1.0), gp, w[1]), prod(point(1.0), paa, r[0]), prod(point(2.0), pap, r[1]), prod(point(1.0), ppp, r[2])],
                point(0.0),
            ));
        }
        let mut tangent = vec![mu];
        tangent.extend(&w);
        let mut charts = Vec::new();
        for k in 0..v.len() {
            for (tau, &pinned) in tangent.iter().enumerate() {
                if tau == k + 1 {
                    continue;
                }
                let mut sys = b.aug.clone();
                pin(&mut sys, v[k], 1.0);
                pin(&mut sys, w[k], 0.0);
                pin(&mut sys, pinned, 1.0);
                charts.push(((k, tau), sys));
            }
        }
        let legs: [ActuatedLeg; 2] = actuated_legs.try_into().ok()?;
        let map = LockedLegMap { length: len, legs, trig: [cl, sl, c, s] };
        Some(Self { charts, v, tangent, base_vars, readout: PoseReadout { legs: leg_xy, platform: (c, s), readings }, map })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::urdf;

    const THREE_RPR: &str = include_str!("../../../urdf/three_rpr.urdf");

    fn names(xs: &[&str]) -> Vec<String> {
        xs.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn the_three_rpr_with_one_locked_leg_takes_the_pose_formulation() {
        let m = urdf::parse(THREE_RPR).expect("bundled");
        let p = PoseCusps::new(&m, &[("rho3".into(), 17.0)], &names(&["rho1", "rho2"])).expect("a platform on R-P-R legs");
        assert_eq!(p.charts.len(), 4);
        assert_eq!(p.base_vars, 4);
        for (_, s) in &p.charts {
            assert_eq!(s.vars.len(), s.equations.len(), "square");
        }
    }

    #[test]
    fn other_mechanisms_and_actuations_do_not() {
        let m = urdf::parse(THREE_RPR).expect("bundled");
        // No leg locked, a revolute joint fixed, a locked leg actuated.
        assert!(PoseCusps::new(&m, &[], &names(&["rho1", "rho2"])).is_none());
        assert!(PoseCusps::new(&m, &[("a3_joint".into(), 0.5)], &names(&["rho1", "rho2"])).is_none());
        assert!(PoseCusps::new(&m, &[("rho3".into(), 17.0)], &names(&["rho1", "rho3"])).is_none());
        // A rotated frame.
        let rotated = urdf::parse(&THREE_RPR.replacen("<origin xyz=\"15.91 0 0\" rpy=\"0 0 0\"/>", "<origin xyz=\"15.91 0 0\" rpy=\"0 0 0.1\"/>", 1)).expect("parses");
        assert!(PoseCusps::new(&rotated, &[("rho3".into(), 17.0)], &names(&["rho1", "rho2"])).is_none());
        let five_bar = urdf::parse(include_str!("../../../urdf/five_bar.urdf")).expect("bundled");
        assert!(PoseCusps::new(&five_bar, &[], &names(&["crank1_joint", "crank2_joint"])).is_none());
    }
}

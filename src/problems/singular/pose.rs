//! The cusp system of a planar platform on R-P-R legs in pose coordinates: the unknowns are the
//! platform's pose (the position `P` of its frame and its angle `φ`, held as `c, s`), not the
//! joint coordinates of every leg. Each leg `i` is a revolute joint to the ground at `A_i`, a
//! slider along the leg whose axis passes through `A_i`, and a revolute joint on the platform at
//! `B_i = P + R(φ) b_i` on the slider's axis, so its travel is `|B_i − A_i|` (limits above 0):
//! a pose determines the legs' angles and travels, and the pose curve `C` is the linkage's.
//! Three legs, one locked (`--fix`), two actuated: `C` is `g = |B_l − A_l|² − L² = 0`, the
//! actuator map `h_i = |B_i − A_i|²` (a diffeomorphism of the travels, so the same cusps).
//!
//! With `X_i, Y_i = B_i − A_i`, `R_i = R(φ) b_i`, the rows `h_i / 2` have gradient
//! `(X_i, Y_i, K_i)` in `(x, y, φ)`, `K_i = R_i × (B_i − A_i)`, and second derivative along
//! `v = (v_x, v_y, v_φ)`: `v_x² + v_y² − 2 R_iy v_x v_φ + 2 R_ix v_y v_φ − L_i v_φ²`,
//! `L_i = R_i · (P − A_i)`. The system is the one of `image`'s module doc with these rows for
//! `F` (the locked leg) and `A` (the actuated legs): `J v = 0`, `μ H[v, v] + J w = 0` over the
//! three rows, `v_k = 1`, `w_k = 0`, one chart of `(μ, w)`: 11 unknowns, 11 equations, 9 chart
//! pairs (against one `(c, s)` per leg and one travel per slider in the joint coordinates).

use super::image::{pin, Builder};
use super::CHART_REACH;
use crate::interval::angle::{arg, wrap};
use crate::interval::{interval, point, Interval, IntervalBox};
use crate::model::{JointKind, Mechanism};
use crate::problems::angles::stated;
use crate::system::{Equation, EquationSystem, Monomial, Term, VarId, VarRole};
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
    pub fn joint_values(&self, b: &IntervalBox) -> BTreeMap<String, (f64, f64)> {
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
fn recognise(m: &Mechanism, fixed: &[(String, f64)], actuated: &[String]) -> Option<(Vec<Leg>, usize, f64, Vec<(String, Reading)>)> {
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
    Some((legs, locked, length, readings))
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
    pub fn new(m: &Mechanism, fixed: &[(String, f64)], actuated: &[String]) -> Option<Self> {
        let (legs, locked, length, mut readings) = recognise(m, fixed, actuated)?;
        let mut b = Builder::new(EquationSystem::default());
        let reach_of = |l: &Leg| {
            let hi = if l.slider == legs[locked].slider { stated(length) } else { stated(l.limits.1) };
            hi + (l.platform[0].sqr() + l.platform[1].sqr()).sqrt()
        };
        // P lies within reach of every ground point.
        let mut px = Interval::ENTIRE;
        let mut py = Interval::ENTIRE;
        for l in &legs {
            let r = reach_of(l);
            px = px.intersection(l.ground[0] + interval(-r.sup(), r.sup()));
            py = py.intersection(l.ground[1] + interval(-r.sup(), r.sup()));
        }
        if px.is_empty() || py.is_empty() {
            return None;
        }
        let x = b.aug.add_var("x_platform", VarRole::Primary, px);
        let y = b.aug.add_var("y_platform", VarRole::Primary, py);
        let c = b.aug.add_var("cos_platform", VarRole::Primary, interval(-1.0, 1.0));
        let s = b.aug.add_var("sin_platform", VarRole::Primary, interval(-1.0, 1.0));
        b.aug.add(Equation::circle(c, s));
        let base_vars = b.aug.vars.len();
        let reach = interval(-CHART_REACH, CHART_REACH);
        // v, w and μ follow from the pose (a linear system once it is known): bisecting the pose
        // alone, the search is three-dimensional, and Krawczyk narrows them.
        let role = VarRole::Derived;
        let v: Vec<VarId> = ["x", "y", "phi"].iter().map(|n| b.aug.add_var(format!("v_{n}"), role, reach)).collect();
        let w: Vec<VarId> = ["x", "y", "phi"].iter().map(|n| b.aug.add_var(format!("w_{n}"), role, reach)).collect();
        let mu = b.aug.add_var("mu", role, reach);
        // μ v_a and μ v_a v_φ: the second-order terms as products of two unknowns.
        let t: Vec<VarId> = (0..3).map(|a| quadratic(&mut b, format!("mu*v_{a}"), &[(point(1.0), mu, v[a])], point(0.0), Interval::ENTIRE)).collect();
        let r: Vec<VarId> = (0..3).map(|a| quadratic(&mut b, format!("mu*v_{a}*v_phi"), &[(point(1.0), t[a], v[2])], point(0.0), Interval::ENTIRE)).collect();
        let mut leg_vars = Vec::new();
        for (i, l) in legs.iter().enumerate() {
            let hi = if i == locked { stated(length) } else { stated(l.limits.1) };
            let bound = interval(-hi.sup(), hi.sup());
            let [bx, by] = l.platform;
            // X, Y = B − A = P + R(φ) b − A.
            let xv = linear(&mut b, format!("X_{i}"), &[(point(1.0), x), (bx, c), (-by, s)], -l.ground[0], bound);
            let yv = linear(&mut b, format!("Y_{i}"), &[(point(1.0), y), (by, c), (bx, s)], -l.ground[1], bound);
            let sq = [(point(1.0), xv, xv), (point(1.0), yv, yv)];
            if i == locked {
                b.aug.add(Equation::new(sq.iter().map(|&(k, p, q)| prod(k, p, q)).collect(), -stated(length).sqr()));
            } else {
                let lo = stated(l.limits.0);
                let h = quadratic(&mut b, format!("{}^2", l.slider), &sq, point(0.0), interval(lo.sqr().inf(), hi.sqr().sup()));
                readings.push((l.slider.clone(), Reading::Travel(h)));
            }
            // K = R × (B − A) and L = R · (P − A) = R · (B − A) − |b|², R = (bx c − by s, by c + bx s).
            let offset = bx != point(0.0) || by != point(0.0);
            let kl = offset.then(|| {
                let k = quadratic(&mut b, format!("K_{i}"), &[(bx, c, yv), (-by, s, yv), (-by, c, xv), (-bx, s, xv)], point(0.0), Interval::ENTIRE);
                let ll = quadratic(&mut b, format!("L_{i}"), &[(bx, c, xv), (-by, s, xv), (by, c, yv), (bx, s, yv)], -(bx.sqr() + by.sqr()), Interval::ENTIRE);
                (k, ll)
            });
            leg_vars.push((xv, yv, bx, by, kl));
        }
        for &(xv, yv, bx, by, kl) in &leg_vars {
            // J v = 0.
            let mut row = vec![prod(point(1.0), xv, v[0]), prod(point(1.0), yv, v[1])];
            if let Some((k, _)) = kl {
                row.push(prod(point(1.0), k, v[2]));
            }
            b.aug.add(Equation::new(row, point(0.0)));
            // μ H[v, v] + J w = 0: H = v_x² + v_y² − 2 R_y v_x v_φ + 2 R_x v_y v_φ − L v_φ².
            let mut row = vec![prod(point(1.0), xv, w[0]), prod(point(1.0), yv, w[1]), prod(point(1.0), t[0], v[0]), prod(point(1.0), t[1], v[1])];
            if let Some((k, ll)) = kl {
                let two = point(2.0);
                row.extend([prod(point(1.0), k, w[2]), prod(-two * by, c, r[0]), prod(-two * bx, s, r[0]), prod(two * bx, c, r[1]), prod(-two * by, s, r[1]), prod(point(-1.0), ll, r[2])]);
            }
            b.aug.add(Equation::new(row, point(0.0)));
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
        let legs_xy = leg_vars.iter().map(|&(xv, yv, ..)| (xv, yv)).collect();
        Some(Self { charts, v, tangent, base_vars, readout: PoseReadout { legs: legs_xy, platform: (c, s), readings } })
    }
}

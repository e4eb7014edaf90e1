//! Collision sets of a 3R chain (Benoit et al. 2019, section 6.2): which joint configurations make
//! two bodies of the robot touch.
//!
//! # Model
//! Every body is a capsule: a segment and a radius, the set of points at most the radius from
//! the segment. A URDF `<capsule radius length>` (SDF convention: the segment along z, centred,
//! `length` long) is one exactly; a `<cylinder radius length>` becomes the capsule around its
//! axis segment, which contains it (so "free" holds for the cylinder too, and "colliding" is
//! about the capsule); a `<sphere>` is a capsule of zero length. Boxes and meshes are refused.
//! Two capsules collide when the distance between their segments is at most the sum of radii.
//!
//! Pairs checked: bodies on rigid bodies (links joined by fixed joints) that are not joined by
//! one revolute joint, as an SRDF would disable adjacent links, which always touch at the joint.
//!
//! # Why (θ₂, θ₃) and not θ₁
//! Bodies on the first link and after it move rigidly with joint 1, so their mutual distances
//! do not depend on θ₁. A body on the base is accepted only if its segment lies on the first
//! axis: joint 1 then turns the arm about the body's own axis of symmetry, and its distance to
//! the arm does not depend on θ₁ either. The set is thus exactly a subset of (θ₂, θ₃) space; a
//! base body off the axis is an error rather than a silently wrong set. Joint limits are not
//! applied (the search covers [-π, π]², as the singularity searches do).
//!
//! # Search (SIVIA)
//! Boxes of (θ₂, θ₃), from [-π, π]², each with the pairs still open. For a pair with segments
//! `P(s) = P₀ + s(P₁ − P₀)`, `Q(t)` whose end points are enclosed over the box:
//!
//! | test | proves | how |
//! |---|---|---|
//! | separation | distance > r₁ + r₂ for every θ in the box | `min(n·P₀, n·P₁) − max(n·Q₀, n·Q₁) > (r₁ + r₂)·|n|` |
//! | witness | distance ≤ r₁ + r₂ for every θ in the box | `|P(s*) − Q(t*)|² ≤ (r₁ + r₂)²` |
//!
//! Both hold for any direction `n` and any fixed `s*, t* ∈ [0, 1]` (n·x is linear, so its
//! extremes over a segment are at end points; and the distance is a minimum over s, t); we take
//! the closest points of the segments at the box's midpoint, computed in floating point, for
//! which both tests become exact as the box shrinks. A box is **colliding** when one pair is
//! proven colliding on all of it, **free** when every pair is proven free, and **undecided**
//! when it reaches the precision with neither.
//! Every test is outward-rounded interval arithmetic over sound sin/cos (`trig`).
//!
//! # References
//! L. Jaulin, E. Walter, *Set inversion via interval analysis for nonlinear bounded-error
//! estimation*, Automatica 29 (1993); C. Ericson, *Real-Time Collision Detection* (2005), 5.1.9.

use super::chain::{self, Pose, V3, ZERO};
use super::cusps::bisect;
use super::drive::{drive, no_progress, Order};
use super::{motion, Chain3R, Manip3rError};
use crate::kernel::interval::trig;
use crate::kernel::search::Control;
use crate::kernel::interval::point;
use crate::model::{JointKind, Mechanism, Shape};
use crate::kernel::search::{Limits, Progress, Prune, Stats, Status, Step};
use inari::Interval;
use smallvec::smallvec;
use std::time::Instant;

/// A body as a capsule, in its link's frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Capsule {
    /// The collision element's name, or `link/index` when it has none.
    pub name: String,
    /// The link it belongs to.
    pub link: String,
    /// Radius (metres).
    pub radius: f64,
    /// End points of the segment in the link frame (metres).
    pub segment: [[f64; 3]; 2],
}

/// A point of a body in the first link's frame: `Σ c[a][b] e₂[a] e₃[b]` with
/// `eₖ = (cos θₖ, sin θₖ, 1)`, exact for any axes and offsets (Rodrigues, as in `chain`).
#[derive(Clone, Copy, Debug)]
struct Placed {
    c: [[V3; 3]; 3],
}

impl Placed {
    /// Enclosure over a box, from `e2`, `e3` enclosing (cos, sin, 1) of the two angles.
    fn over(&self, e2: &[Interval; 3], e3: &[Interval; 3]) -> V3 {
        let mut p = [ZERO; 3];
        for (a, ca) in self.c.iter().enumerate() {
            let h = [0, 1, 2].map(|i| ca[0][i] * e3[0] + ca[1][i] * e3[1] + ca[2][i]);
            for i in 0..3 {
                p[i] += e2[a] * h[i];
            }
        }
        p
    }

    /// The point at (θ₂, θ₃) in floating point (midpoints of the coefficients): for choosing
    /// test directions only, never for decisions.
    #[allow(clippy::needless_range_loop)] // tensor coefficients c[a][b] paired with e2[a], e3[b]
    fn at(&self, e2: &[f64; 3], e3: &[f64; 3]) -> [f64; 3] {
        let mut p = [0.0; 3];
        for a in 0..3 {
            for b in 0..3 {
                for (i, pi) in p.iter_mut().enumerate() {
                    *pi += self.c[a][b][i].mid() * e2[a] * e3[b];
                }
            }
        }
        p
    }
}

#[derive(Clone, Debug)]
struct Body {
    capsule: Capsule,
    /// Rigid body: 0 the base, k after the k-th revolute joint.
    stage: usize,
    ends: [Placed; 2],
    /// How far the placed segment may lie from the real one (base bodies projected onto the
    /// first axis); added to the radius for "free", taken off for "colliding".
    slack: f64,
}

/// The robot's bodies as capsules, ready for `classify`.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Robot name.
    pub name: String,
    /// The three revolute joints, base first.
    pub joints: [String; 3],
    bodies: Vec<Body>,
    pairs: Vec<(usize, usize)>,
}

/// Capsule of a `<collision>` element, in its link frame.
fn capsule(link: &str, index: usize, c: &crate::model::Collision) -> Result<Capsule, Manip3rError> {
    let (radius, half) = match c.shape {
        Shape::Cylinder { radius, length } | Shape::Capsule { radius, length } => (radius, length / 2.0),
        Shape::Sphere { radius } => (radius, 0.0),
        Shape::Box { .. } => return Err(Manip3rError::UnsupportedShape { link: link.into(), shape: "box".into() }),
        Shape::Mesh { .. } => return Err(Manip3rError::UnsupportedShape { link: link.into(), shape: "mesh".into() }),
    };
    let end = |z: f64| {
        let p = c.origin * nalgebra::Point3::new(0.0, 0.0, z);
        [p.x, p.y, p.z]
    };
    let name = c.name.clone().unwrap_or_else(|| format!("{link}/{index}"));
    Ok(Capsule { name, link: link.into(), radius, segment: [end(-half), end(half)] })
}

impl Scene {
    /// Reads the chain (as `Chain3R::from_mechanism` does) and the capsules of its links.
    ///
    /// Errors: everything `Chain3R::from_mechanism` refuses; a box or mesh collision shape; a
    /// base body off the first axis (see the module doc); no pair of bodies to check.
    pub fn from_mechanism(m: &Mechanism) -> Result<Self, Manip3rError> {
        let chain = Chain3R::from_mechanism(m, 0.0)?;
        let tip = m.link(&chain.tip_link).expect("invariant: the chain names its tip link");
        let path = m.path_to(tip);
        // Stage and pose in the stage frame of every link on the chain; `segments[k]` is the
        // frame of revolute joint k+1 in stage k (as in `chain`).
        let mut stage_of = vec![None; m.links.len()];
        stage_of[m.root] = Some((0, Pose::identity()));
        let mut segments = [Pose::identity(); 3];
        let mut axes = [[ZERO; 3]; 3];
        let (mut stage, mut acc) = (0, Pose::identity());
        for &j in &path {
            let joint = &m.joints[j];
            acc = acc.then(&Pose::from_origin(joint, 0.0));
            if matches!(joint.kind, JointKind::Revolute { .. }) {
                segments[stage] = acc;
                axes[stage] = [0, 1, 2].map(|i| point(joint.axis[i]));
                stage += 1;
                acc = Pose::identity();
            }
            stage_of[joint.child] = Some((stage, acc));
        }
        let place = |stage: usize, y: V3| -> Placed {
            let mut c = [[[ZERO; 3]; 3]; 3];
            // In link 2's frame, as coefficients of (cos θ₃, sin θ₃, 1).
            let q: [V3; 3] = match stage {
                3 => {
                    let r = chain::rodrigues(&axes[2], &y);
                    let mut q = [0, 1, 2].map(|b| chain::apply(&segments[2].r, &r[b]));
                    q[2] = chain::add(&q[2], &segments[2].t);
                    q
                }
                _ => [[ZERO; 3], [ZERO; 3], y],
            };
            if stage == 1 {
                c[2][2] = y;
                return Placed { c };
            }
            for b in 0..3 {
                let r = chain::rodrigues(&axes[1], &q[b]);
                for a in 0..3 {
                    c[a][b] = chain::apply(&segments[1].r, &r[a]);
                }
            }
            c[2][2] = chain::add(&c[2][2], &segments[1].t);
            Placed { c }
        };
        let mut bodies = Vec::new();
        for (l, link) in m.links.iter().enumerate() {
            for (index, c) in link.collisions.iter().enumerate() {
                let capsule = capsule(&link.name, index, c)?;
                let Some((stage, pose)) = stage_of[l] else { continue };
                let ends = capsule.segment.map(|x| {
                    let x = x.map(point);
                    chain::add(&chain::apply(&pose.r, &x), &pose.t)
                });
                let (ends, slack) = if stage == 0 {
                    // Into joint 1's frame: z = Rᵀ(y − t); on the axis, z = (a₁·z) a₁.
                    let to_joint1 = |y: &V3| {
                        let d = chain::sub(y, &segments[0].t);
                        [0, 1, 2].map(|i| segments[0].r[0][i] * d[0] + segments[0].r[1][i] * d[1] + segments[0].r[2][i] * d[2])
                    };
                    let mut slack: f64 = 0.0;
                    let on_axis = ends.map(|y| {
                        let z = to_joint1(&y);
                        let on = chain::scale(&axes[0], chain::dot(&axes[0], &z));
                        let off = chain::sub(&z, &on);
                        slack = slack.max(chain::dot(&off, &off).sqrt().sup());
                        on
                    });
                    let scale = 1.0 + capsule.segment.iter().flatten().fold(0.0f64, |s, v| s.max(v.abs()));
                    if !(slack <= 1e-9 * scale) {
                        return Err(Manip3rError::BaseBodyOffAxis(capsule.name));
                    }
                    (on_axis.map(|z| place(1, z)), slack)
                } else {
                    (ends.map(|y| place(stage, y)), 0.0)
                };
                bodies.push(Body { capsule, stage, ends, slack });
            }
        }
        if bodies.is_empty() {
            return Err(Manip3rError::NoCollisionGeometry(format!("no link of '{}' has a <collision> cylinder, capsule or sphere", m.name)));
        }
        let mut pairs = Vec::new();
        for i in 0..bodies.len() {
            for j in i + 1..bodies.len() {
                if bodies[i].stage.abs_diff(bodies[j].stage) >= 2 {
                    pairs.push((i, j));
                }
            }
        }
        if pairs.is_empty() {
            return Err(Manip3rError::NoCollisionGeometry(format!(
                "the {} collision bodies of '{}' are all on adjacent links: no pair to check",
                bodies.len(),
                m.name
            )));
        }
        Ok(Scene { name: m.name.clone(), joints: chain.joints.clone(), bodies, pairs })
    }

    /// The capsules, in the order pairs refer to them.
    pub fn capsules(&self) -> Vec<&Capsule> {
        self.bodies.iter().map(|b| &b.capsule).collect()
    }

    /// The pairs checked, as indices into `capsules()`.
    pub fn pairs(&self) -> &[(usize, usize)] {
        &self.pairs
    }

    /// The segment of body `i` in the first link's frame at (θ₂, θ₃), in floating point: for
    /// sampling and tests, never for decisions.
    pub fn segment_f64(&self, i: usize, t2: f64, t3: f64) -> [[f64; 3]; 2] {
        let (e2, e3) = ([t2.cos(), t2.sin(), 1.0], [t3.cos(), t3.sin(), 1.0]);
        self.bodies[i].ends.map(|p| p.at(&e2, &e3))
    }
}

/// Parameters `(s, t)` of the closest points of segments `p0p1` and `q0q1` (Ericson 5.1.9),
/// in floating point: they only choose the tests' direction and witness.
pub fn closest_parameters(p: [[f64; 3]; 2], q: [[f64; 3]; 2]) -> (f64, f64) {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let (d1, d2, r) = (sub(p[1], p[0]), sub(q[1], q[0]), sub(p[0], q[0]));
    let (a, e, f) = (dot(d1, d1), dot(d2, d2), dot(d2, r));
    let tiny = 1e-300;
    if a <= tiny && e <= tiny {
        return (0.0, 0.0);
    }
    if a <= tiny {
        return (0.0, (f / e).clamp(0.0, 1.0));
    }
    let c = dot(d1, r);
    if e <= tiny {
        return ((-c / a).clamp(0.0, 1.0), 0.0);
    }
    let b = dot(d1, d2);
    let denom = a * e - b * b;
    let mut s = if denom > 0.0 { ((b * f - c * e) / denom).clamp(0.0, 1.0) } else { 0.0 };
    let mut t = (b * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = (-c / a).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - c) / a).clamp(0.0, 1.0);
    }
    (s, t)
}

/// Distance between segments in floating point (tests and sampling only).
pub fn segment_distance(p: [[f64; 3]; 2], q: [[f64; 3]; 2]) -> f64 {
    let (s, t) = closest_parameters(p, q);
    let at = |x: [[f64; 3]; 2], u: f64| [0, 1, 2].map(|i| x[0][i] + u * (x[1][i] - x[0][i]));
    let (a, b) = (at(p, s), at(q, t));
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Settings of a collision classification (its bounds are a `Control`).
#[derive(Clone, Copy, Debug)]
pub struct CollisionSettings {
    /// Largest width of an undecided box (radians).
    pub precision: f64,
}

impl Default for CollisionSettings {
    fn default() -> Self {
        CollisionSettings { precision: 1e-2 }
    }
}

/// Boxes a classification processes at most unless told otherwise (`classify`).
pub const DEFAULT_MAX_BOXES: u64 = 5_000_000;

/// A box proven colliding, with the pair that collides on all of it.
#[derive(Clone, Copy, Debug)]
pub struct CollidingBox {
    /// (θ₂, θ₃)
    pub theta: [Interval; 2],
    /// Index into `Scene::pairs`.
    pub pair: usize,
}

/// The outcome: colliding, free and undecided boxes covering [-π, π]².
#[derive(Clone, Debug)]
pub struct CollisionSet {
    /// Boxes where some pair collides for every configuration.
    pub colliding: Vec<CollidingBox>,
    /// Boxes where no pair collides, for every configuration.
    pub free: Vec<[Interval; 2]>,
    /// Boxes at the precision with neither proven (or left by a limit).
    pub undecided: Vec<[Interval; 2]>,
    /// `Complete` when every box was decided; otherwise the limit that stopped the run.
    pub status: Status,
    /// The kernel's counters (nothing is discarded: every box is colliding, free, undecided
    /// or split).
    pub stats: Stats,
    /// Total area of the colliding boxes (rad²).
    pub colliding_area: f64,
    /// Total area of the free boxes (rad²).
    pub free_area: f64,
    /// Total area of the undecided boxes (rad²).
    pub undecided_area: f64,
    /// Wall-clock seconds.
    pub seconds: f64,
}

impl CollisionSet {
    /// Complete when no limit stopped the run and no box is undecided: boxes at the precision
    /// neither proven colliding nor free leave the classification open.
    pub fn completeness(&self) -> crate::kernel::outcome::Completeness {
        crate::kernel::outcome::Completeness::of(self.status, self.undecided.len(), false)
    }
}

/// What the two tests prove for one pair over a box.
enum Verdict {
    Colliding,
    Free,
    Open,
}

fn dot(a: &V3, b: &V3) -> Interval {
    chain::dot(a, b)
}

/// The separation and witness tests of the module doc for bodies `x`, `y` with end points
/// enclosed by `ex`, `ey` over the box and `mx`, `my` at its midpoint.
fn test_pair(x: &Body, ex: &[V3; 2], mx: [[f64; 3]; 2], y: &Body, ey: &[V3; 2], my: [[f64; 3]; 2]) -> Verdict {
    let (s, t) = closest_parameters(mx, my);
    let radii = point(x.capsule.radius) + point(y.capsule.radius);
    let slack = point(x.slack) + point(y.slack);
    let at = |e: &[V3; 2], u: f64| -> V3 {
        let (a, b) = (point(1.0) - point(u), point(u));
        [0, 1, 2].map(|i| a * e[0][i] + b * e[1][i])
    };
    let d = chain::sub(&at(ex, s), &at(ey, t));
    let d2 = dot(&d, &d);
    let inner = radii - slack;
    if inner.inf() >= 0.0 && d2.sup() <= inner.sqr().inf() {
        return Verdict::Colliding;
    }
    let ps = [0, 1, 2].map(|i| mx[0][i] + s * (mx[1][i] - mx[0][i]));
    let qt = [0, 1, 2].map(|i| my[0][i] + t * (my[1][i] - my[0][i]));
    let n = [0, 1, 2].map(|i| point(ps[i] - qt[i]));
    let norm = dot(&n, &n).sqrt();
    if norm.inf() > 0.0 {
        let (a, b) = (dot(&n, &ex[0]), dot(&n, &ex[1]));
        let (c, e) = (dot(&n, &ey[0]), dot(&n, &ey[1]));
        // min over P's end points minus max over Q's, rounded down.
        let gap = (point(a.inf().min(b.inf())) - point(c.sup().max(e.sup()))).inf();
        if gap > ((radii + slack) * norm).sup() {
            return Verdict::Free;
        }
    }
    Verdict::Open
}

fn area(b: &[Interval; 2]) -> f64 {
    b[0].wid() * b[1].wid()
}

/// A box with the pairs still open on it.
#[derive(Clone, Debug)]
pub struct CollisionCell {
    b: [Interval; 2],
    open: Vec<usize>,
    order: Order,
    level: u32,
}

/// What a box was proven to be.
enum Class {
    Colliding(CollidingBox),
    Free([Interval; 2]),
}

/// The tests of the module doc, one box at a time.
struct CollisionPrune<'a> {
    scene: &'a Scene,
    precision: f64,
    /// Scratch: enclosed and midpoint end points per body, filled on first use in a box.
    ends: Vec<Option<Ends>>,
}

/// A body's end points over a box (enclosed) and at its midpoint (floating point).
type Ends = ([V3; 2], [[f64; 3]; 2]);

impl Prune for CollisionPrune<'_> {
    type Cell = CollisionCell;
    type Found = (Order, Class);
    type Reason = crate::kernel::search::NoDiscard;

    fn process(&mut self, cell: CollisionCell) -> Step<CollisionCell, (Order, Class), crate::kernel::search::NoDiscard> {
        let scene = self.scene;
        let b = cell.b;
        let e2 = [trig::cos(b[0]), trig::sin(b[0]), point(1.0)];
        let e3 = [trig::cos(b[1]), trig::sin(b[1]), point(1.0)];
        let m = [b[0].mid(), b[1].mid()];
        let (m2, m3) = ([m[0].cos(), m[0].sin(), 1.0], [m[1].cos(), m[1].sin(), 1.0]);
        self.ends.clear();
        self.ends.resize(scene.bodies.len(), None);
        let ends = &mut self.ends;
        let mut get = |i: usize| -> ([V3; 2], [[f64; 3]; 2]) {
            *ends[i].get_or_insert_with(|| {
                let body = &scene.bodies[i];
                (body.ends.map(|p| p.over(&e2, &e3)), body.ends.map(|p| p.at(&m2, &m3)))
            })
        };
        let mut still = Vec::new();
        for &k in &cell.open {
            let (i, j) = scene.pairs[k];
            let ((ei, mi), (ej, mj)) = (get(i), get(j));
            match test_pair(&scene.bodies[i], &ei, mi, &scene.bodies[j], &ej, mj) {
                Verdict::Colliding => return Step::Found((cell.order, Class::Colliding(CollidingBox { theta: b, pair: k }))),
                Verdict::Free => {}
                Verdict::Open => still.push(k),
            }
        }
        if still.is_empty() {
            Step::Found((cell.order, Class::Free(b)))
        } else if b[0].wid().max(b[1].wid()) <= self.precision {
            Step::Undecided(cell, "precision")
        } else {
            let (lo, hi) = bisect(b, false);
            let (order, level) = (cell.order, cell.level + 1);
            Step::Split(smallvec![
                CollisionCell { b: lo, open: still.clone(), order: order.child(0, 2), level },
                CollisionCell { b: hi, open: still, order: order.child(1, 2), level }
            ])
        }
    }

    fn level(&self, cell: &CollisionCell) -> u32 {
        cell.level
    }

    fn bytes(&self, cell: &CollisionCell) -> usize {
        std::mem::size_of::<CollisionCell>() + cell.open.capacity() * std::mem::size_of::<usize>()
    }
}

/// Classifies [-π, π]² into colliding, free and undecided boxes (see the module doc), depth
/// first on one thread with at most `DEFAULT_MAX_BOXES` boxes.
pub fn classify(scene: &Scene, settings: &CollisionSettings) -> Result<CollisionSet, Manip3rError> {
    let control = Control::with_limits(Limits { max_cells: DEFAULT_MAX_BOXES, ..Limits::default() });
    classify_with(scene, settings, &control, &mut no_progress)
}

/// As `classify`, within `control`, reporting progress.
pub fn classify_with(scene: &Scene, settings: &CollisionSettings, control: &Control, progress: &mut dyn FnMut(&Progress)) -> Result<CollisionSet, Manip3rError> {
    super::check_precision(settings.precision)?;
    let start = Instant::now();
    let all: Vec<usize> = (0..scene.pairs.len()).collect();
    let root = CollisionCell { b: [motion::full_range(), motion::full_range()], open: all, order: Order::ROOT, level: 0 };
    let mut run = drive(|| CollisionPrune { scene, precision: settings.precision, ends: Vec::new() }, root, control, progress);
    // Depth-first order, that of the loop this replaced: the areas are sums in that order.
    run.found.sort_by_key(|(order, _)| *order);
    run.undecided.sort_by_key(|(c, _)| c.order);
    let (mut colliding, mut free) = (Vec::new(), Vec::new());
    for (_, class) in run.found {
        match class {
            Class::Colliding(c) => colliding.push(c),
            Class::Free(b) => free.push(b),
        }
    }
    let undecided: Vec<[Interval; 2]> = run.undecided.into_iter().map(|(c, _)| c.b).collect();
    Ok(CollisionSet {
        colliding_area: colliding.iter().map(|c| area(&c.theta)).sum(),
        free_area: free.iter().map(area).sum(),
        undecided_area: undecided.iter().map(area).sum(),
        colliding,
        free,
        undecided,
        status: run.status,
        stats: run.stats,
        seconds: start.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distances with closed forms: skew lines, parallel segments, end point to end point,
    /// and a degenerate segment (a point).
    #[test]
    fn segment_distances_match_closed_forms() {
        let x = [[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
        assert!((segment_distance(x, [[0.0, -1.0, 2.0], [0.0, 1.0, 2.0]]) - 2.0).abs() < 1e-15);
        assert!((segment_distance(x, [[-5.0, 3.0, 0.0], [5.0, 3.0, 0.0]]) - 3.0).abs() < 1e-15);
        assert!((segment_distance(x, [[4.0, 4.0, 0.0], [7.0, 9.0, 0.0]]) - 5.0).abs() < 1e-15);
        assert!((segment_distance(x, [[0.5, 0.0, 1.0], [0.5, 0.0, 1.0]]) - 1.0).abs() < 1e-15);
        assert_eq!(segment_distance(x, [[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]]), 0.0);
    }
}

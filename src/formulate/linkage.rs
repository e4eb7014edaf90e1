//! Planar linkages: a `Mechanism` whose joint axes are all parallel becomes the system of Porta,
//! Ros and Thomas (2006).
//!
//! One angle per rigid group of links (links joined by fixed, prismatic or fixed-by-the-user
//! joints turn together), as `c = cos φ`, `s = sin φ` with `c² + s² = 1`; the ground's angle is 0.
//! One loop-closure vector equation per `<loop>` (the fundamental cycles of the spanning tree):
//! the closure point reached through the predecessor equals the one reached through the
//! successor, which is linear in the `c, s` variables.
//! Slider travel `d` enters as `d·c`, `d·s`: new variables defined by the bilinear equations
//! `z = d·c` (the hyperbolic equations of Porta et al. 2006).
//! Traced points (their equation 5) are derived variables defined by linear equations.
//! Builds only; solving is `search`'s job.

mod build;

use super::angles::{self, against_limits, cos_sin, wrap};
use crate::kernel::contract::{Filtered, Inclusion};
use crate::kernel::search::{default_contractor, SolveError, Solver, SolverSettings};
use crate::kernel::interval::{point, Interval, IntervalBox};
use crate::model::{JointKind, Mechanism, ModelError};
use crate::kernel::system::{EquationSystem, Monomial, VarId};
use std::collections::BTreeMap;
use thiserror::Error;

/// What stops a mechanism from becoming a planar linkage problem.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum LinkageError {
    /// The description itself is bad.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// Joint axes are not all parallel (or a slider axis is not in the plane).
    #[error("not planar: {0} (the planar builder takes planar linkages only; `solve --model spatial` takes the rest)")]
    NonPlanar(String),
    /// `--fix` names no joint or loop.
    #[error("--fix: no joint or loop named '{0}'")]
    UnknownJoint(String),
    /// `--fix` on a joint that does not move.
    #[error("--fix: joint '{0}' is fixed and takes no value")]
    NotMovable(String),
    /// `--fix` on a joint of more than one degree of freedom.
    #[error("--fix: joint '{0}' is a {1} joint: --fix sets one value, of a revolute, continuous or prismatic joint")]
    NotOneValue(String, &'static str),
    /// A fixed value outside the joint's limits, or not finite.
    #[error("--fix {joint}={value}: outside its limits [{lower}, {upper}]")]
    OutsideLimits {
        /// joint
        joint: String,
        /// value given
        value: f64,
        /// lower limit
        lower: f64,
        /// upper limit
        upper: f64,
    },
    /// A revolute value too large to reduce modulo 2π accurately.
    #[error("--fix {joint}={value}: more than {max:e} rad, too many turns to reduce modulo 2π accurately; give the angle modulo 2π", max = angles::MAX_REDUCIBLE)]
    TooManyTurns {
        /// joint
        joint: String,
        /// value given
        value: f64,
    },
    /// A value that is not a finite number.
    #[error("--fix {0}: the value is not a finite number")]
    NotFinite(String),
    /// The loop provably cannot close for any joint values.
    #[error("loop '{0}' cannot close: its links are too short or too long to meet (proven by interval propagation)")]
    CannotClose(String),
    /// A closure row has no unknown left and its constant excludes 0: as written, the loop's
    /// two chains miss each other whatever the joint values.
    #[error("loop '{name}' cannot close as written: whatever the joint values, one of its closure rows (a coordinate difference of its two chains) is the constant [{lower:e}, {upper:e}], not 0")]
    Gap {
        /// The loop.
        name: String,
        /// The constant's enclosure.
        lower: f64,
        /// The constant's enclosure.
        upper: f64,
    },
    /// Fixed angles around a cycle contradict each other.
    #[error("loop '{0}': the fixed joint angles around it contradict each other")]
    Contradiction(String),
    /// A joint follows another through `<mimic>`.
    #[error("joint '{joint}' follows '{leader}' through <mimic>, which planar linkages do not model yet")]
    Mimic {
        /// the follower
        joint: String,
        /// the joint it follows
        leader: String,
    },
    /// A traced point names an unknown link.
    #[error("--trace: no link named '{0}'")]
    UnknownTraceLink(String),
    /// A spatial description leaves some motion free that no loop constrains (a link spinning
    /// between two ball joints outside the recognised patterns, a ball or floating joint on no
    /// loop).
    #[error("under-constrained: {0}")]
    UnderConstrained(String),
    /// A joint or closure the spatial builder does not model.
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// A traced point off the plane z = 0 of its link's frame, with the planar model forced.
    #[error("--trace '{0}': the planar model traces points of the plane z = 0 of a link's frame")]
    TraceOffPlane(String),
    /// A tree has no loop to close: every joint value is a configuration.
    #[error("the mechanism has no <loop> closure: every joint value is a configuration, there is nothing to enclose (serial chains: see `singularities`)")]
    NoLoops,
    /// `--model pose` or `distances` on a mechanism that is not a platform on six fixed legs.
    #[error("--model pose or distances: {0}")]
    Platform(#[from] super::PlatformError),
    /// A traced point with `--model pose` or `distances`, which place only the platform.
    #[error("--trace {0}: the pose and distance models place the platform only; trace with --model spatial")]
    TraceOnPose(String),
    /// The pose or distance model where joint coordinates are needed (singular sets).
    #[error("the pose and distance models have no joint coordinates to differentiate; singular sets take --model planar, spatial or auto")]
    NotJointModel,
}

/// The pair of variables of a rotating group, or the ground.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Angle {
    Ground,
    Free { c: VarId, s: VarId },
}

/// A rotation of the plane known as an angle (for read-outs) and as its cosine and sine (for
/// coefficients), both enclosures of the same exact rotation.
#[derive(Clone, Copy, Debug)]
struct Turn {
    angle: Interval,
    c: Interval,
    s: Interval,
}

impl Turn {
    fn zero() -> Self {
        Self { angle: point(0.0), c: point(1.0), s: point(0.0) }
    }

    /// The turn by `angle` (already reduced to about a turn, so the read-out stays tight).
    fn by(angle: Interval) -> Self {
        let (c, s) = cos_sin(angle);
        Self { angle, c, s }
    }

    /// The direction of the in-plane vector `(x, y)`, which must miss the origin.
    fn towards(x: Interval, y: Interval) -> Self {
        let len = (x.sqr() + y.sqr()).sqrt();
        Self { angle: angles::angle_interval(x, y), c: x / len, s: y / len }
    }

    fn plus(self, o: Turn) -> Turn {
        Turn { angle: self.angle + o.angle, c: self.c * o.c - self.s * o.s, s: self.s * o.c + self.c * o.s }
    }

    fn neg(self) -> Turn {
        Turn { angle: -self.angle, c: self.c, s: -self.s }
    }

    fn minus(self, o: Turn) -> Turn {
        self.plus(o.neg())
    }

    /// `R(self)·v`
    fn rotate(&self, v: [Interval; 2]) -> [Interval; 2] {
        [self.c * v[0] - self.s * v[1], self.s * v[0] + self.c * v[1]]
    }
}

/// How a joint's value is read off a solution box.
#[derive(Clone, Debug)]
enum Reading {
    /// `sign·(φ_b − φ_a) + offset`.
    Revolute { a: usize, b: usize, sign: f64, offset: Interval },
    /// A travel variable.
    Travel(VarId),
}

/// A point whose world coordinates are traced (Porta et al. 2006, eq. 5).
#[derive(Clone, Debug)]
pub struct Trace {
    /// `LINK@X,Y` as given.
    pub name: String,
    /// World x variable.
    pub x: VarId,
    /// World y variable.
    pub y: VarId,
}

/// A planar linkage as a polynomial system, with what is needed to read joint values back.
///
/// Every coefficient is an interval enclosing its value in the stated mechanism (the decimals of
/// the file and of `--fix`, see `stated`), so the boxes enclose that mechanism's configurations.
#[derive(Clone, Debug)]
pub struct LinkageProblem {
    /// The system to solve.
    pub system: EquationSystem,
    /// Robot name.
    pub name: String,
    /// Joints (tree and loop) with unknown values, in file order.
    pub free_joints: Vec<String>,
    /// Joints fixed by the user, with their values.
    pub fixed_joints: Vec<(String, f64)>,
    /// Traced points.
    pub traces: Vec<Trace>,
    /// Per link: (name, group angle, offset to the group angle, rest yaw in the plane).
    links: Vec<(String, Angle, Interval, Interval)>,
    readings: Vec<(String, Reading)>,
    /// How many of `readings` (the first) are the tree's joints; the rest are the loops'.
    tree_readings: usize,
    /// Revolute readings with limits: (index into `readings`, lower, upper), enclosing the stated limits.
    limits: Vec<(usize, Interval, Interval)>,
}

impl LinkageProblem {
    /// Builds the planar system of `m`, with `fixed` joint values and traced points
    /// `(link name, x, y)` in the link's frame.
    pub fn new(m: &Mechanism, fixed: &[(String, f64)], traces: &[(String, f64, f64)]) -> Result<Self, LinkageError> {
        // A mimic couples two joint values: an equation the builder does not write yet, so it is
        // refused by name rather than silently ignored.
        if let Some(j) = m.joints.iter().find(|j| j.mimic.is_some() && j.kind != JointKind::Fixed) {
            let leader = j.mimic.as_ref().map_or("", |x| x.joint.as_str());
            return Err(LinkageError::Mimic { joint: j.name.clone(), leader: leader.to_string() });
        }
        // Whether a loop can close at all is a property of the geometry: judge it with every
        // joint free and no revolute limits. A fixed value or a limit that leaves no
        // configuration is an answer (complete, no box), not bad input.
        let limited = m.joints.iter().any(|j| matches!(j.kind, JointKind::Revolute { limits: Some(_) }));
        if fixed.is_empty() && !limited {
            return Self::build(m, fixed, traces, true, true);
        }
        Self::build(m, &[], &[], false, true)?;
        Self::build(m, fixed, traces, true, false)
    }

    /// World orientation of every link over the box, radians, keyed by link name; outward
    /// rounded.
    pub fn link_angles(&self, b: &IntervalBox) -> BTreeMap<String, (f64, f64)> {
        self.link_angles_of(b, |_| true)
    }

    /// `link_angles` of the links `keep` names only (the others are not computed).
    pub fn link_angles_of(&self, b: &IntervalBox, keep: impl Fn(&str) -> bool) -> BTreeMap<String, (f64, f64)> {
        self.links.iter().filter(|(name, ..)| keep(name)).map(|(name, angle, off, yaw)| (name.clone(), bounds(wrap(self.angle(b, *angle, *off + *yaw))))).collect()
    }

    fn angle(&self, b: &IntervalBox, angle: Angle, off: Interval) -> Interval {
        match angle {
            Angle::Ground => off,
            Angle::Free { c, s } => angles::angle_interval(b.dims[c], b.dims[s]) + off,
        }
    }

    /// Values of the free joints over the box (radians or metres), keyed by joint name; outward
    /// rounded.
    pub fn joint_values(&self, b: &IntervalBox) -> BTreeMap<String, (f64, f64)> {
        self.readings.iter().map(|(name, r)| (name.clone(), bounds(self.reading(r, b)))).collect()
    }

    fn reading(&self, r: &Reading, b: &IntervalBox) -> Interval {
        match *r {
            Reading::Travel(v) => b.dims[v],
            Reading::Revolute { a, b: c, sign, offset } => {
                let pa = self.angle(b, self.links[a].1, self.links[a].2);
                let pc = self.angle(b, self.links[c].1, self.links[c].2);
                let d = pc - pa;
                wrap(if sign > 0.0 { d } else { -d } + offset)
            }
        }
    }

    /// Where the box lies against the limits of the limited revolute joints (angles compared
    /// modulo 2π, any number of turns). The joint intervals are outward-rounded enclosures
    /// (`angles`), so `Outside` means no point of the box respects the limits.
    pub fn limit_verdict(&self, b: &IntervalBox) -> Inclusion {
        let mut verdict = Inclusion::Inside;
        for &(k, lower, upper) in &self.limits {
            verdict = verdict.and(against_limits(self.reading(&self.readings[k].1, b), lower, upper));
            if verdict == Inclusion::Outside {
                return verdict;
            }
        }
        verdict
    }

    /// True when some limited revolute joint's value over `b` lies wholly outside its limits.
    pub fn violates_limits(&self, b: &IntervalBox) -> bool {
        self.limit_verdict(b) == Inclusion::Outside
    }

    /// A solver for this problem: the default pipeline, plus a joint-limit filter when joints
    /// away from the ground carry limits (those next to it already bound the initial box). The
    /// filter sees every box, certified ones included.
    pub fn solver(&self, settings: SolverSettings) -> Result<Solver<'_>, SolveError> {
        let solver = Solver::new(&self.system, settings)?;
        if self.limits.is_empty() {
            return Ok(solver);
        }
        Ok(solver.with_contractor(Box::new(move |system, settings| {
            Box::new(Filtered { inner: default_contractor(system, settings), filters: vec![Box::new(move |b: &IntervalBox| self.limit_verdict(b))] })
        })))
    }

    /// A box's point in the system's variables from link angles (radians, by link name) and
    /// slider travels (by joint name): for tests and references. Traced and product variables
    /// are filled in from the equations.
    pub fn point_from(&self, angles: &BTreeMap<String, f64>, travels: &BTreeMap<String, f64>) -> Option<Vec<f64>> {
        let mut x = vec![f64::NAN; self.system.vars.len()];
        for (name, angle, off, yaw) in &self.links {
            if let Angle::Free { c, s } = angle {
                let phi = angles.get(name)? - off.mid() - yaw.mid();
                x[*c] = phi.cos();
                x[*s] = phi.sin();
            }
        }
        for (name, r) in &self.readings {
            if let Reading::Travel(v) = r {
                x[*v] = *travels.get(name)?;
            }
        }
        self.fill_derived(&mut x)?;
        Some(x)
    }

    /// A point of the system's variables at the free joints' values `values` (`free_joints`
    /// order, radians or metres), read the way the readings define them: each group's angle
    /// follows from the tree joints on its path from the ground (any number of turns: each
    /// value is reduced modulo 2π, the sum wrapped once), travels are taken as given, products
    /// and traced points come from their equations. The loops' joint values are not used:
    /// closing the loops is left to a polish, and the caller checks them against the readings of
    /// the point it ends at, modulo 2π. `None` when the count is wrong or a revolute value is
    /// beyond `angles::MAX_REDUCIBLE`.
    pub fn point_from_joints(&self, values: &[f64]) -> Option<Vec<f64>> {
        if values.len() != self.readings.len() {
            return None;
        }
        let mut x = vec![f64::NAN; self.system.vars.len()];
        let mut known: BTreeMap<VarId, f64> = BTreeMap::new();
        // The group angle of `link` when known (the ground's is 0), plus the link's offset.
        let link_angle = |known: &BTreeMap<VarId, f64>, link: usize| match self.links[link].1 {
            Angle::Ground => Some(self.links[link].2.mid()),
            Angle::Free { c, .. } => known.get(&c).map(|psi| psi + self.links[link].2.mid()),
        };
        // Repeated passes: the tree joints need not be listed parents first.
        loop {
            let mut progress = false;
            for ((_, r), &q) in self.readings[..self.tree_readings].iter().zip(values) {
                let Reading::Revolute { a, b, sign, offset } = *r else { continue };
                // q = sign·(φ_b − φ_a) + offset, so φ_b − φ_a = sign·(q − offset).
                let turn = sign * (angles::reduce(point(q))?.mid() - offset.mid());
                let (to, angle) = match (link_angle(&known, a), link_angle(&known, b)) {
                    (Some(pa), None) => (self.links[b].1, pa + turn - self.links[b].2.mid()),
                    (None, Some(pb)) => (self.links[a].1, pb - turn - self.links[a].2.mid()),
                    _ => continue,
                };
                if let Angle::Free { c, .. } = to {
                    known.insert(c, angle);
                    progress = true;
                }
            }
            if !progress {
                break;
            }
        }
        for (_, angle, ..) in &self.links {
            if let Angle::Free { c, s } = *angle {
                let psi = known.get(&c).map_or(0.0, |&p| wrap_f64(p));
                x[c] = psi.cos();
                x[s] = psi.sin();
            }
        }
        for ((_, r), &q) in self.readings.iter().zip(values) {
            if let Reading::Travel(v) = *r {
                x[v] = q;
            }
        }
        self.fill_derived(&mut x)?;
        Some(x)
    }

    /// The derived variables of `x` from its primaries: products, then traces (each defined by
    /// one equation).
    fn fill_derived(&self, x: &mut [f64]) -> Option<()> {
        for e in &self.system.equations {
            if let crate::kernel::system::EquationKind::Bilinear { z, x: a, y: c } = e.kind {
                x[z] = x[a] * x[c];
            }
        }
        for t in &self.traces {
            for v in [t.x, t.y] {
                let e = self.system.equations.iter().find(|e| e.terms.iter().any(|k| k.mono == Monomial::Linear(v)))?;
                let coef = e.terms.iter().find(|k| k.mono == Monomial::Linear(v))?.coef.mid();
                x[v] = 0.0;
                x[v] = -e.residual(x) / coef;
            }
        }
        Some(())
    }
}

/// How a free joint's value moves with the system's variables: what velocity-level analyses
/// (singularities, `formulate::singular`) need. `Angles` is `φ_plus − φ_minus` (plus a constant),
/// each group angle given by its `(cos, sin)` variables, `None` for the ground.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JointCoordinate {
    /// A revolute joint: the difference of two group angles.
    Angles {
        /// the group angle that enters with a plus sign
        plus: Option<(VarId, VarId)>,
        /// the group angle that enters with a minus sign
        minus: Option<(VarId, VarId)>,
    },
    /// A slider: its travel variable.
    Travel(VarId),
}

impl LinkageProblem {
    /// How the free joint `name` depends on the system's variables; `None` for a joint that is
    /// not free (unknown, fixed by `--fix`, or welded).
    pub fn joint_coordinate(&self, name: &str) -> Option<JointCoordinate> {
        let (_, r) = self.readings.iter().find(|(n, _)| n == name)?;
        let pair = |link: usize| match self.links[link].1 {
            Angle::Ground => None,
            Angle::Free { c, s } => Some((c, s)),
        };
        Some(match *r {
            Reading::Travel(v) => JointCoordinate::Travel(v),
            Reading::Revolute { a, b, sign, .. } if sign > 0.0 => JointCoordinate::Angles { plus: pair(b), minus: pair(a) },
            Reading::Revolute { a, b, .. } => JointCoordinate::Angles { plus: pair(a), minus: pair(b) },
        })
    }

    /// The constant `K` of the revolute joint `name`'s reading `θ = φ_plus − φ_minus + K`
    /// (`joint_coordinate`), enclosed and not wrapped (so tight even where `K` lies at ±π);
    /// `None` for a slider or a joint that is not free.
    pub fn joint_offset(&self, name: &str) -> Option<Interval> {
        let (_, r) = self.readings.iter().find(|(n, _)| n == name)?;
        let Reading::Revolute { a, b, sign, offset } = *r else { return None };
        let d = self.links[b].2 - self.links[a].2;
        Some(if sign > 0.0 { d } else { -d } + offset)
    }

    /// A solver for `system`, which must extend this problem's system (the same variables
    /// first, in order, then its own): the default pipeline plus this problem's joint-limit
    /// filter, which reads only the shared variables. Used by augmented systems (singular sets).
    pub fn extended_solver<'s>(&'s self, system: &'s EquationSystem, settings: SolverSettings) -> Result<Solver<'s>, SolveError> {
        debug_assert!(system.vars.len() >= self.system.vars.len());
        let solver = Solver::new(system, settings)?;
        if self.limits.is_empty() {
            return Ok(solver);
        }
        Ok(solver.with_contractor(Box::new(move |system, settings| {
            Box::new(Filtered { inner: default_contractor(system, settings), filters: vec![Box::new(move |b: &IntervalBox| self.limit_verdict(b))] })
        })))
    }
}

/// `x` shifted by whole turns into [−π, π].
fn wrap_f64(x: f64) -> f64 {
    x - std::f64::consts::TAU * (x / std::f64::consts::TAU).round()
}

fn bounds(x: Interval) -> (f64, f64) {
    (x.inf(), x.sup())
}

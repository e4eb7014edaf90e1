//! An input motion of a 1-dof planar closed loop checked against its input (type II, turning
//! point) singularities by tube following: from an assembly, the actuated joint moves from `a`
//! to `b`, and each step `[aₖ, aₖ₊₁]` of the input gets a box of the loop's other coordinates
//! proven, by one parametric Krawczyk step (`contract::krawczyk`, the input an interval), to
//! hold exactly one configuration for every input value of the step.
//!
//! The loop's system (`LinkageProblem`: `c, s` per rigid group, travels, their products) has one
//! row fewer than variables; the input row makes it square: for a revolute input `θ = φ₊ − φ₋ + K`
//! it is `sin(a − K)·cos Δ − cos(a − K)·sin Δ = 0` with `Δ = φ₊ − φ₋` written in the groups'
//! `c, s`, for a slider `d − a = 0`. The revolute row also vanishes at `Δ = a − K + π`: a step
//! counts only when `cos(a − K − Δ) > 0` is proven on its enclosure, so its configuration has
//! the input value `a` itself.
//!
//! The start: the assembly is read as the builder reads joint values
//! (`LinkageProblem::point_from_joints`: each group angle along the tree joints from the
//! ground, values any number of turns out), Newton polishes it at its own input value, and
//! every given joint value, the loops' included, is checked against the polished point's
//! reading modulo 2π: a start more than `ASSEMBLY_SLACK` off in some joint is off the mechanism
//! and refused, naming that joint and the distance. One Krawczyk proof boxes that configuration,
//! and when the assembly's input value is not `from` (modulo 2π for a revolute input, taken the
//! representative nearest `from`) the same steps carry its branch to `from` first (refused
//! unless all proven), so the motion starts on the assembly's branch, not on a neighbour's.
//!
//! Continuity: step `k + 1`'s trial box holds the enclosure of step `k`'s configuration at the
//! shared input value, and uniqueness there makes the configuration of step `k + 1` at that
//! value the same: the boxes follow one branch. A regular point of the input map is exactly where
//! the square system's Jacobian is regular, so a proven step crosses no input singularity;
//! where steps keep failing down to the minimum step the motion is left undecided from there on
//! (a turning point or the end of the branch may be ahead), never claimed to cross.
//! Output (type I) singularities are not examined. No IO.

use crate::kernel::contract::krawczyk::{self, Inflation, Step};
use crate::kernel::interval::{interval, point, trig, Interval, IntervalBox};
use crate::model::Mechanism;
use crate::formulate::linkage::JointCoordinate;
use crate::formulate::{Coordinates, LinkageError, LinkageProblem, Output, SingularError, SingularKind};
use crate::kernel::outcome::BoxStatus;
use crate::kernel::search::{Budget, Control, Limit, SolverSettings};

use crate::kernel::system::{Monomial, VarId};
use nalgebra::{DMatrix, DVector};
use std::collections::BTreeMap;
use thiserror::Error;

/// What cannot be checked.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum MotionError {
    /// The mechanism is not a planar linkage (or `--fix` is bad).
    #[error(transparent)]
    Linkage(#[from] LinkageError),
    /// The request itself is bad (names, numbers, counts).
    #[error("{0}")]
    BadRequest(String),
    /// The loop does not have one degree of freedom once the input is given.
    #[error("the loop has {vars} coordinates and {rows} rows: the input motion check needs one degree of freedom")]
    NotOneDof {
        /// coordinates (system variables)
        vars: usize,
        /// rows (equations)
        rows: usize,
    },
    /// No configuration of the loop is proven near the given assembly, or its branch does not
    /// reach the start value.
    #[error("the assembly (at {joint} = {value}): {why}")]
    NoAssembly {
        /// the actuated joint
        joint: String,
        /// its value in the assembly
        value: f64,
        /// what failed
        why: String,
    },
}

/// An input motion to check.
#[derive(Clone, Debug)]
pub struct MotionRequest {
    /// The actuated joint.
    pub actuated: String,
    /// Its start value (radians or metres).
    pub from: f64,
    /// Its end value.
    pub to: f64,
    /// An approximate configuration of the loop: the value of every free joint, in
    /// `motion_joints` order (angles modulo 2π). When its actuated value is not `from`, its
    /// branch is followed to `from` by the same proven steps first.
    pub assembly: Vec<f64>,
    /// The largest step of the input.
    pub max_step: f64,
    /// Steps are halved on failure down to this; then the motion is undecided.
    pub min_step: f64,
    /// Whether an undecided motion searches the certified turning points of the input
    /// (`singular::points`) to name the one next to where the proof stopped.
    pub name_turning_point: bool,
}

/// One proven step.
#[derive(Clone, Debug)]
pub struct MotionStep {
    /// The input's range `[lo, hi]`.
    pub input: [f64; 2],
    /// Every free joint over the step's box (holding exactly one configuration per input
    /// value), outward rounded.
    pub joints: BTreeMap<String, [f64; 2]>,
}

/// What the motion holds.
#[derive(Clone, Debug, PartialEq)]
pub enum MotionVerdict {
    /// Every step proven: no input singularity between `from` and `to` on the branch of the
    /// assembly.
    Clear,
    /// Proven up to `from`; beyond it no step could be proven.
    Undecided {
        /// The last input value proven.
        from: f64,
        /// Why.
        reason: String,
        /// A certified turning point of the input next to where the proof stopped: its joints.
        near: Option<BTreeMap<String, [f64; 2]>>,
    },
    /// A limit stopped the check after `from`.
    Stopped {
        /// The last input value proven.
        from: f64,
        /// The limit.
        limit: Limit,
    },
}

/// What `check_input_motion` found.
#[derive(Clone, Debug)]
pub struct InputMotionCheck {
    /// The mechanism's name.
    pub mechanism: String,
    /// The request.
    pub request: MotionRequest,
    /// The joints of the assembly, in order.
    pub joints: Vec<String>,
    /// The configuration at `from` on the assembly's branch, enclosed (at the assembly's own
    /// input value when a limit stopped the run before it reached `from`).
    pub start: BTreeMap<String, [f64; 2]>,
    /// The proven steps, in order of the motion.
    pub steps: Vec<MotionStep>,
    /// The verdict.
    pub verdict: MotionVerdict,
    /// Wall time.
    pub seconds: f64,
}

impl InputMotionCheck {
    /// Complete when every step is proven; a limit or a step that could not be proven leaves
    /// the rest undecided.
    pub fn completeness(&self) -> crate::kernel::outcome::Completeness {
        use crate::kernel::outcome::{Completeness, Incompleteness};
        match self.verdict {
            MotionVerdict::Clear => Completeness::Complete,
            MotionVerdict::Undecided { .. } => Completeness::Incomplete(Incompleteness::Undecided),
            MotionVerdict::Stopped { limit, .. } => Completeness::Incomplete(Incompleteness::Limit(limit)),
        }
    }

    /// The set checked against, as reports name it.
    pub fn set_name(&self) -> String {
        format!("input singularities of {}, actuated {}", self.mechanism, self.request.actuated)
    }
}

/// The free joints of the planar loop `m` (with `fixed`), the order an assembly is given in.
pub fn motion_joints(m: &Mechanism, fixed: &[(String, f64)]) -> Result<Vec<String>, MotionError> {
    Ok(LinkageProblem::new(m, fixed, &[])?.free_joints)
}

/// The input row of the square system.
enum Input {
    /// `θ = φ₊ − φ₋ + K`: the groups' `(c, s)` (None: the ground) and `K`.
    Angle { plus: Option<(VarId, VarId)>, minus: Option<(VarId, VarId)>, offset: Interval },
    /// A slider's travel.
    Travel(VarId),
}

/// The loop's system plus the input row, evaluated over boxes of the coordinates and the input.
struct Square<'p> {
    problem: &'p LinkageProblem,
    input: Input,
}

fn cs(b: &[Interval], g: Option<(VarId, VarId)>) -> (Interval, Interval) {
    g.map_or((point(1.0), point(0.0)), |(c, s)| (b[c], b[s]))
}

impl Square<'_> {
    fn n(&self) -> usize {
        self.problem.system.vars.len()
    }

    /// The rows over `x` and input `a`.
    fn values(&self, x: &[Interval], a: Interval) -> DVector<Interval> {
        let eqs = &self.problem.system.equations;
        let mut f = DVector::from_element(self.n(), point(0.0));
        for (k, e) in eqs.iter().enumerate() {
            f[k] = e.eval(x);
        }
        f[eqs.len()] = match self.input {
            Input::Travel(d) => x[d] - a,
            Input::Angle { plus, minus, offset } => {
                let (sa, ca) = (trig::sin(a - offset), trig::cos(a - offset));
                let ((cp, sp), (cm, sm)) = (cs(x, plus), cs(x, minus));
                sa * (cp * cm + sp * sm) - ca * (sp * cm - cp * sm)
            }
        };
        f
    }

    /// The Jacobian in the coordinates over `x` and input `a`.
    fn jacobian(&self, x: &[Interval], a: Interval) -> DMatrix<Interval> {
        let eqs = &self.problem.system.equations;
        let mut j = DMatrix::from_element(self.n(), self.n(), point(0.0));
        for (k, e) in eqs.iter().enumerate() {
            for t in &e.terms {
                match t.mono {
                    Monomial::Linear(v) => j[(k, v)] += t.coef,
                    Monomial::Square(v) => j[(k, v)] += t.coef * point(2.0) * x[v],
                    Monomial::Product(p, q) => {
                        j[(k, p)] += t.coef * x[q];
                        j[(k, q)] += t.coef * x[p];
                    }
                }
            }
        }
        let r = eqs.len();
        match self.input {
            Input::Travel(d) => j[(r, d)] += point(1.0),
            Input::Angle { plus, minus, offset } => {
                let (sa, ca) = (trig::sin(a - offset), trig::cos(a - offset));
                let ((cp, sp), (cm, sm)) = (cs(x, plus), cs(x, minus));
                if let Some((c, s)) = plus {
                    j[(r, c)] += sa * cm + ca * sm;
                    j[(r, s)] += sa * sm - ca * cm;
                }
                if let Some((c, s)) = minus {
                    j[(r, c)] += sa * cp - ca * sp;
                    j[(r, s)] += sa * sp + ca * cp;
                }
            }
        }
        j
    }

    /// Whether the configurations in `x` have the input value `a` itself, not `a + π` (the
    /// revolute row's other zero): `cos(a − K − Δ) > 0` over the box.
    fn on_input(&self, x: &[Interval], a: Interval) -> bool {
        match self.input {
            Input::Travel(_) => true,
            Input::Angle { plus, minus, offset } => {
                let (sa, ca) = (trig::sin(a - offset), trig::cos(a - offset));
                let ((cp, sp), (cm, sm)) = (cs(x, plus), cs(x, minus));
                (ca * (cp * cm + sp * sm) + sa * (sp * cm - cp * sm)).inf() > 0.0
            }
        }
    }

    /// Krawczyk's image of `x` for every input in `a`.
    fn image(&self, x: &[Interval], a: Interval) -> Option<Vec<Interval>> {
        let m: Vec<f64> = x.iter().map(|d| d.mid()).collect();
        let mp: Vec<Interval> = m.iter().map(|&v| point(v)).collect();
        let b = DVector::from_column_slice(x);
        krawczyk::image(&b, &DVector::from_vec(m), &self.values(&mp, a), &self.jacobian(x, a)).map(|k| k.data.into())
    }

    fn step(&self, x: &[Interval], a: Interval) -> Step<Vec<Interval>> {
        let m: Vec<f64> = x.iter().map(|d| d.mid()).collect();
        let mp: Vec<Interval> = m.iter().map(|&v| point(v)).collect();
        let b = DVector::from_column_slice(x);
        krawczyk::step(&b, &DVector::from_vec(m), &self.values(&mp, a), &self.jacobian(x, a)).map(|k| k.data.into())
    }

    /// Newton in floating point at input `a` from `x` (a predictor, and the assembly's polish):
    /// the point and its last residual.
    fn newton(&self, mut x: Vec<f64>, a: f64) -> (Vec<f64>, f64) {
        let mut residual = f64::INFINITY;
        for _ in 0..30 {
            let xp: Vec<Interval> = x.iter().map(|&v| point(v)).collect();
            let f = self.values(&xp, point(a)).map(|v| v.mid());
            residual = f.amax();
            if !residual.is_finite() || residual < 1e-14 {
                break;
            }
            let j = self.jacobian(&xp, point(a)).map(|v| v.mid());
            let Some(dx) = j.lu().solve(&f) else { break };
            for (x, d) in x.iter_mut().zip(dx.iter()) {
                *x -= d;
            }
        }
        (x, residual)
    }
}

fn bounds(m: BTreeMap<String, (f64, f64)>) -> BTreeMap<String, [f64; 2]> {
    m.into_iter().map(|(k, (lo, hi))| (k, [lo, hi])).collect()
}

fn wrap_f64(x: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let w = x.rem_euclid(t);
    if w > std::f64::consts::PI {
        w - t
    } else {
        w
    }
}

/// Checks the motion of `request.actuated` from `from` to `to`, starting at the assembly, on the
/// planar loop `m` with joints `fixed` (module doc). A limit of `control` (timeout, cancel)
/// stops it with what is proven so far.
pub fn check_input_motion(m: &Mechanism, fixed: &[(String, f64)], request: &MotionRequest, control: &Control) -> Result<InputMotionCheck, MotionError> {
    let budget = Budget::start(control.limits, control.cancel);
    let r = request;
    if !(r.from.is_finite() && r.to.is_finite()) {
        return Err(MotionError::BadRequest(format!("the input's start and end must be finite numbers, got {} and {}", r.from, r.to)));
    }
    if !(r.min_step > 0.0 && r.max_step >= r.min_step && r.max_step.is_finite()) {
        return Err(MotionError::BadRequest(format!("steps must satisfy 0 < min ≤ max, got min {} and max {}", r.min_step, r.max_step)));
    }
    let problem = LinkageProblem::new(m, fixed, &[])?;
    let joints = problem.free_joints.clone();
    if r.assembly.len() != joints.len() || !r.assembly.iter().all(|v| v.is_finite()) {
        return Err(MotionError::BadRequest(format!("the assembly is {} finite values, one per free joint in this order: {}", joints.len(), joints.join(", "))));
    }
    let (vars, rows) = (problem.system.vars.len(), problem.system.equations.len());
    if rows + 1 != vars {
        return Err(MotionError::NotOneDof { vars, rows });
    }
    let coordinate = |name: &str| problem.joint_coordinate(name);
    let Some(actuated) = coordinate(&r.actuated) else {
        return Err(MotionError::BadRequest(format!("'{}' is not a free joint of the loop ({})", r.actuated, joints.join(", "))));
    };
    let input = match actuated {
        JointCoordinate::Travel(d) => Input::Travel(d),
        JointCoordinate::Angles { plus, minus } => {
            let offset = problem.joint_offset(&r.actuated).expect("invariant: a free revolute joint has an offset");
            Input::Angle { plus, minus, offset }
        }
    };
    let square = Square { problem: &problem, input };

    // The assembly read as the builder reads joint values: group angles along the tree joints,
    // loop joints left to the polish and checked against it below.
    let Some(read) = problem.point_from_joints(&r.assembly) else {
        return Err(MotionError::BadRequest(format!("the assembly's angles must lie within ±{:e} rad to be reduced modulo 2π", crate::formulate::angles::MAX_REDUCIBLE)));
    };
    let place_of_input = joints.iter().position(|j| *j == r.actuated).expect("invariant: the actuated joint is free");
    let given = r.assembly[place_of_input];
    let no_assembly = |why: String| MotionError::NoAssembly { joint: r.actuated.clone(), value: given, why };
    // The input row reads a revolute input through its sine and cosine: the assembly's value
    // taken the whole turns nearest `from`, so a value given turns away needs no lead.
    let a_asm = match square.input {
        Input::Angle { .. } => r.from + wrap_f64(given - r.from),
        Input::Travel(_) => given,
    };
    let a_asm = if (a_asm - r.from).abs() <= SAME_INPUT * r.from.abs().max(1.0) { r.from } else { a_asm };
    let off = |x: &[f64]| worst_gap(&problem, x, &joints, &r.assembly);
    // Newton at the assembly's own input value projects it onto the loop's configurations
    // without moving along the curve; it only polishes: a start it moves by more than
    // `ASSEMBLY_SLACK` in some joint is not on the mechanism.
    let (x0, residual) = square.newton(read.clone(), a_asm);
    if !(residual < 1e-9) {
        // Where a loop joint disagrees with its tree joints, that names the joint that is off.
        let before = off(&read);
        let why = if before.distance > ASSEMBLY_SLACK {
            format!("off the mechanism: {} (Newton from it does not converge: residual {residual:.1e})", before.describe("the value the tree joints give it"))
        } else {
            format!("off the mechanism: its loops do not close near it (Newton from it does not converge: residual {residual:.1e})")
        };
        return Err(no_assembly(why));
    }
    let moved = off(&x0);
    if !(moved.distance <= ASSEMBLY_SLACK) {
        return Err(no_assembly(format!("off the mechanism: {}; a start within {ASSEMBLY_SLACK} of a configuration in every joint is needed", moved.describe("its value in the configuration Newton finds from it at this input"))));
    }
    // The configuration at the assembly's value, proven unique in a small box about the
    // polished point.
    let point_box: Vec<Interval> = x0.iter().map(|&v| point(v)).collect();
    let Some(at_assembly) = krawczyk::inflate(&point_box, &INFLATION, |x| square.image(x, point(a_asm))).filter(|k| square.on_input(k, point(a_asm))) else {
        return Err(no_assembly("no box about it is proven to hold exactly one configuration (a singular configuration?)".into()));
    };
    let stopped = || budget.interrupted();
    // The branch of the assembly carried to `from` by the same tube, so the motion starts on it.
    let start = if a_asm == r.from {
        at_assembly
    } else {
        let lead = follow(&square, r, at_assembly.clone(), a_asm, r.from, &stopped, &mut |_, _| {});
        if let MotionVerdict::Stopped { limit, .. } = lead.verdict {
            // A limit is an answer: nothing of the motion proven, its start not reached.
            let start = bounds(problem.joint_values(&IntervalBox::new(at_assembly)));
            let verdict = MotionVerdict::Stopped { from: r.from, limit };
            return Ok(InputMotionCheck { mechanism: problem.name.clone(), request: r.clone(), joints, start, steps: Vec::new(), verdict, seconds: budget.elapsed().as_secs_f64() });
        }
        if lead.verdict != MotionVerdict::Clear {
            let reached = match lead.verdict {
                MotionVerdict::Undecided { from, .. } | MotionVerdict::Stopped { from, .. } => from,
                MotionVerdict::Clear => r.from,
            };
            return Err(no_assembly(format!("its branch is proven only up to {} = {reached}, short of the start {}", r.actuated, r.from)));
        }
        lead.enclosure
    };
    let start_joints = bounds(problem.joint_values(&IntervalBox::new(start.clone())));
    // Each proven step is read out as it is taken, so the deadline the walk asks before each
    // step bounds its read-outs too.
    let mut steps = Vec::new();
    let Followed { verdict, enclosure } = follow(&square, r, start, r.from, r.to, &stopped, &mut |a, k| steps.push(MotionStep { input: a, joints: bounds(problem.joint_values(&IntervalBox::new(k.to_vec()))) }));
    let verdict = match verdict {
        MotionVerdict::Undecided { from, reason, .. } if r.name_turning_point => {
            let here = problem.joint_values(&IntervalBox::new(enclosure.clone()));
            let near = nearest_turning_point(m, fixed, &r.actuated, &here, control, &budget);
            MotionVerdict::Undecided { from, reason, near }
        }
        v => v,
    };
    Ok(InputMotionCheck { mechanism: problem.name.clone(), request: r.clone(), joints, start: start_joints, steps, verdict, seconds: budget.elapsed().as_secs_f64() })
}

/// How `krawczyk::inflate` grows a trial box: a tenth of each component's width a round.
const INFLATION: Inflation<'static> = Inflation { rounds: 5, own: 0.1, widest: 0.0, widest_of: &[], absolute: 1e-12, ulps: 8.0 };

/// How far (radians or metres, in every joint) Newton may move the given assembly.
const ASSEMBLY_SLACK: f64 = 0.1;

/// An assembly's input value this close to `from` (relative, at least absolute) is taken as
/// `from`: the difference of a value given whole turns away, reduced.
const SAME_INPUT: f64 = 1e-12;

/// The joint of an assembly farthest from a point's readings (angles modulo 2π).
struct Gap {
    joint: String,
    distance: f64,
    given: f64,
    there: f64,
}

impl Gap {
    fn describe(&self, whose: &str) -> String {
        format!("{} = {} is {:.3} from {:.6}, {whose}", self.joint, self.given, self.distance, self.there)
    }
}

/// The joint whose given value lies farthest from its reading at `x` (angles modulo 2π).
fn worst_gap(problem: &LinkageProblem, x: &[f64], joints: &[String], given: &[f64]) -> Gap {
    let read = problem.joint_values(&IntervalBox::new(x.iter().map(|&v| point(v)).collect()));
    let mut worst = Gap { joint: String::new(), distance: -1.0, given: f64::NAN, there: f64::NAN };
    for (j, &q) in joints.iter().zip(given) {
        let there = read.get(j).map_or(f64::NAN, |&(lo, hi)| 0.5 * (lo + hi));
        // An angle's reading, the whole turns nearest the value given (as the message shows it).
        let there = match problem.joint_coordinate(j) {
            Some(JointCoordinate::Angles { .. }) => q + wrap_f64(there - q),
            _ => there,
        };
        let d = (there - q).abs();
        let d = if d.is_nan() { f64::INFINITY } else { d };
        if d > worst.distance {
            worst = Gap { joint: j.clone(), distance: d, given: q, there };
        }
    }
    worst
}

/// What a tube following gives (its steps went to its `step` callback).
struct Followed {
    verdict: MotionVerdict,
    /// The configuration at the last proven input value, enclosed.
    enclosure: Vec<Interval>,
}

/// Follows the one configuration in `enclosure` at input `from` to input `to` (module doc),
/// handing each proven step (the input's range and the box) to `step`.
fn follow(square: &Square, r: &MotionRequest, mut enclosure: Vec<Interval>, from: f64, to: f64, stopped: &dyn Fn() -> Option<Limit>, step: &mut dyn FnMut([f64; 2], &[Interval])) -> Followed {
    let direction = if to >= from { 1.0 } else { -1.0 };
    let mut a = from;
    let mut h = r.max_step;
    let verdict = loop {
        if a == to {
            break MotionVerdict::Clear;
        }
        if let Some(limit) = stopped() {
            break MotionVerdict::Stopped { from: a, limit };
        }
        let a1 = if (to - a).abs() <= h { to } else { a + direction * h };
        let range = interval(a.min(a1), a.max(a1));
        let centre: Vec<f64> = enclosure.iter().map(|d| d.mid()).collect();
        let (predicted, res) = square.newton(centre.clone(), a1);
        let predicted = if res < 1e-9 { predicted } else { centre };
        // The trial holds the enclosure at `a` (continuity) and the predicted point at `a1`.
        let trial: Vec<Interval> = enclosure.iter().zip(&predicted).map(|(e, &p)| e.convex_hull(point(p))).collect();
        let proven = krawczyk::inflate(&trial, &INFLATION, |x| square.image(x, range)).filter(|k| square.on_input(k, range));
        match proven {
            Some(k) => {
                // The one configuration at `a1` in `k`, enclosed tightly for the next trial.
                enclosure = krawczyk::tighten(k.clone(), 1e-13, |x| square.step(x, point(a1)));
                step([range.inf(), range.sup()], &k);
                a = a1;
                h = (2.0 * h).min(r.max_step);
            }
            None if h * 0.5 >= r.min_step => h *= 0.5,
            None => {
                let reason = format!(
                    "no Krawczyk step from {} = {a} could be proven down to a step of {}: the configuration is near an input singularity (a turning point of {}) or the branch ends",
                    r.actuated, r.min_step, r.actuated
                );
                break MotionVerdict::Undecided { from: a, reason, near: None };
            }
        }
    };
    Followed { verdict, enclosure }
}

/// How far (largest joint gap, wrapped for angles) a certified turning point may lie from the
/// last proven configuration to be named.
const NEAR: f64 = 0.05;

/// The certified turning point of `actuated` (`singular::points`) nearest to `here`, when one
/// lies within `NEAR` in every joint.
fn nearest_turning_point(m: &Mechanism, fixed: &[(String, f64)], actuated: &str, here: &BTreeMap<String, (f64, f64)>, control: &Control, budget: &Budget) -> Option<BTreeMap<String, [f64; 2]>> {
    let sets = crate::analyses::loop_singular::SingularSets::new(m, fixed, &[SingularKind::Input], &[actuated.to_string()], None::<Output>).map_err(|_: SingularError| ()).ok()?;
    let settings = SolverSettings { timeout: control.limits.timeout.map(|t| t.saturating_sub(budget.elapsed())), ..SolverSettings::default() };
    let solved = sets.solve(&settings, control.cancel).ok()?;
    let (p, set) = (sets.problems.first()?, solved.first()?);
    let mut best: Option<(f64, BTreeMap<String, [f64; 2]>)> = None;
    for sb in set.boxes.iter().filter(|b| b.status == BoxStatus::Unique) {
        let values = p.linkage.joint_values(&sb.b);
        let gap = here
            .iter()
            .map(|(k, &(lo, hi))| values.get(k).map_or(f64::INFINITY, |&(l, h)| wrap_f64(0.5 * (l + h) - 0.5 * (lo + hi)).abs()))
            .fold(0.0, f64::max);
        if gap <= NEAR && best.as_ref().is_none_or(|(g, _)| gap < *g) {
            best = Some((gap, bounds(values)));
        }
    }
    best.map(|(_, v)| v)
}

//! Singular sets of planar closed-loop linkages: the loop constraints of `LinkageProblem` plus a
//! null vector of the relevant Jacobian block (Bohigas, Porta, Ros, *Singularities of Robot
//! Mechanisms*, 2017), as one more `EquationSystem` for the unchanged `Solver`.
//!
//! Coordinates `q`: one angle φ per free rigid group (held as `c = cos φ`, `s = sin φ`) and one
//! travel `d` per free slider. The loop rows `F(q) = 0` are linear in `c, s` and in the
//! products `z = d·c`, `d·s`, so their derivatives are linear in the same variables:
//! `d/dt c = −s·φ̇`, `d/dt s = c·φ̇`, `d/dt (d·c) = c·ḋ − (d·s)·φ̇`, `d/dt (d·s) = s·ḋ + (d·c)·φ̇`.
//! A null vector `m` of a Jacobian block therefore enters through products (variable × `m_i`),
//! each a new derived variable defined by a bilinear equation: the augmented system keeps the
//! three shapes (linear, circle, bilinear) the LP relaxation knows, and degree two.
//!
//! - C-space singularities (bifurcations): `λᵀ F_q = 0`, `λ ≠ 0` (the loop rows lose rank).
//! - Input (type II): `F_q v = 0`, `A v = 0`, `v ≠ 0`, `A` the rates of the actuated joints:
//!   with the actuators locked the mechanism still moves.
//! - Output (type I): `F_q v = 0`, `O v = 0`, `v ≠ 0`, `O` the rates of the output (a point's
//!   velocity or output joints; by default every passive joint): the mechanism moves while the
//!   output stands still.
//!
//! `v ≠ 0` up to scale and sign: the direction lies on the projective sphere, covered by charts
//! `m_k = 1, |m_j| ≤ 1.05` (k over the components: the max-norm sphere, whose face `m_k = −1`
//! is the antipode of `m_k = 1`). Each chart is a linear normalisation, so no solution is lost
//! and each chart's system is square when the singular set is made of points (Krawczyk can
//! certify them). A direction whose largest component is at `k` lies strictly inside chart
//! `k`'s domain; a box of chart `k` proven to hold only directions owned by another chart (the
//! first index of largest |m|) is dropped, because that chart finds them; the rest are merged
//! by their configuration parts.
//! Builds only; `SingularProblem::solve` (in `crate::analyses::loop_singular`) runs the kernel's `Solver` on
//! each chart.

use super::linkage::{LinkageError, LinkageProblem};
use super::{Linkage, Model};
use crate::kernel::interval::fast::Iv;
use crate::kernel::interval::{interval, point, Interval, IntervalBox};
use crate::model::Mechanism;
use crate::kernel::search::{SolveError, Solver, SolverSettings};
use crate::kernel::system::{Equation, EquationSystem, Monomial, Term, VarId, VarRole};
use std::collections::BTreeMap;
use thiserror::Error;

pub(crate) mod image;
mod parts;
pub(crate) mod pose;
pub(crate) mod velocity;

pub(crate) use self::parts::Parts;
use self::parts::{merge, Coord, Rate};

/// Half-width of a chart's free components: above 1, so a direction whose largest components
/// tie (|m_j| = |m_k| = 1) lies inside both charts' domains, not on their boundary.
const CHART_REACH: f64 = 1.05;

/// Which singular set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SingularKind {
    /// C-space singularities: the loop constraints lose rank (branches cross).
    Cspace,
    /// Input (type II): the passive coordinates' Jacobian loses rank; an uncontrolled motion.
    Input,
    /// Output (type I): the output stands still while the mechanism moves.
    Output,
}

impl SingularKind {
    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            SingularKind::Cspace => "cspace",
            SingularKind::Input => "input",
            SingularKind::Output => "output",
        }
    }
}

/// The output whose rate vanishes at output (type I) singularities.
#[derive(Clone, Debug, PartialEq)]
pub enum Output {
    /// A point `(x, y)` of a link's frame (its world velocity vanishes).
    Point {
        /// link name
        link: String,
        /// x in the link's frame
        x: f64,
        /// y in the link's frame
        y: f64,
    },
    /// Joints (their rates vanish).
    Joints(Vec<String>),
}

/// What stops a singular-set problem from being built.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum SingularError {
    /// The linkage itself does not build.
    #[error(transparent)]
    Linkage(#[from] LinkageError),
    /// `--actuated` names a joint that is not a free joint of the linkage.
    #[error("--actuated: '{0}' is not a free joint of the mechanism (free joints: {1})")]
    UnknownActuated(String, String),
    /// `--output` names a joint that is not free.
    #[error("--output: '{0}' is not a free joint of the mechanism (free joints: {1})")]
    UnknownOutput(String, String),
    /// Input singularities need as many actuators as degrees of freedom.
    #[error("input singularities need as many actuated joints as degrees of freedom: {actuated} actuated ({names}), {dof} degrees of freedom (set them with --actuated J1,J2,... or <transmission> elements)")]
    ActuatorCount {
        /// number given
        actuated: usize,
        /// their names
        names: String,
        /// degrees of freedom
        dof: isize,
    },
    /// A joint named twice.
    #[error("joint '{0}' is named twice")]
    Repeated(String),
    /// A spatial linkage's loop joint as an actuated or output joint.
    #[error("'{0}' is a loop joint of a spatial linkage: its rate is read from the closure frames, not a coordinate; name tree joints")]
    LoopJoint(String),
    /// The system has an equation shape the differentiation does not know.
    #[error("internal: equation {0} has a shape the differentiation does not know (a variable that is neither a coordinate nor defined by an earlier equation)")]
    Unexpected(usize),
}

/// The augmented systems of one singular set: the linkage's system, the multiplier variables
/// and their equations, one system per chart.
#[derive(Clone, Debug)]
pub struct SingularProblem<L = LinkageProblem> {
    /// The linkage (with the output point traced, if any).
    pub linkage: L,
    /// Which set.
    pub kind: SingularKind,
    /// Actuated joints.
    pub actuated: Vec<String>,
    /// The output, for output singularities.
    pub output: Option<Output>,
    /// Degrees of freedom, counted as coordinates minus loop rows (full rank assumed: a
    /// mechanism whose rows are dependent everywhere has more).
    pub dof: isize,
    /// Expected dimension of the set for generic geometry (negative: generically empty).
    pub expected_dimension: isize,
    /// The linkage's system with the multipliers and the null-vector rows; chart `k` adds
    /// `m[k] = 1` (`chart`). Built one at a time when solved: a chart is as large as this
    /// system, and a mechanism of n joints has about n charts.
    pub augmented: EquationSystem,
    /// Ids of the multiplier variables `m` (velocity or row multipliers), chart `k` fixing `m[k] = 1`.
    pub multipliers: Vec<VarId>,
    /// Number of the linkage's variables (the configuration part of every box).
    pub base_vars: usize,
}

/// What a singular-set builder adds to a linkage's system: the multipliers (one chart each) and
/// the rows that make them a null vector of the relevant Jacobian block.
#[derive(Clone, Debug)]
pub struct Augmented {
    /// The linkage's system extended by the multipliers, the rows and their product variables.
    pub system: EquationSystem,
    /// The multipliers, chart `k` fixing `multipliers[k] = 1`.
    pub multipliers: Vec<VarId>,
    /// Degrees of freedom of the linkage (coordinates minus constraint rows).
    pub dof: isize,
    /// Rows added beyond the derived variables they define: the set's expected dimension is
    /// `dof + (multipliers − 1) − rows`.
    pub rows: isize,
}

/// A linkage's system seen through its coordinates: what the chart, search, cluster and report
/// machinery of singular sets needs of a model, planar (`LinkageProblem`) or spatial
/// (`SpatialProblem`, through `velocity`), so that machinery exists once.
pub trait Coordinates {
    /// The configuration system; its variables are the first of every chart's.
    fn system(&self) -> &EquationSystem;
    /// Robot name.
    fn name(&self) -> &str;
    /// The builder of the configuration system.
    fn model(&self) -> Model;
    /// Joints fixed by the user, with their values.
    fn fixed_joints(&self) -> &[(String, f64)];
    /// Free joint values over a box of the configuration variables (radians or metres).
    fn joint_values(&self, b: &IntervalBox) -> BTreeMap<String, (f64, f64)>;
    /// A solver for `system`, an extension of `self.system()`, with the model's filters.
    fn extended_solver<'s>(&'s self, system: &'s EquationSystem, settings: SolverSettings) -> Result<Solver<'s>, SolveError>;
    /// The multipliers and rows of `kind` (actuated joints checked here: which joints have a
    /// rate is the model's business).
    fn augment(&self, kind: SingularKind, actuated: &[String], output: Option<&Output>) -> Result<Augmented, SingularError>;
    /// Whether a root of the augmented system in `b` (configuration variables first) is a
    /// singular configuration of the mechanism, not an artefact of how its rows are written:
    /// a Krawczyk certificate counts only where this holds.
    fn rows_faithful(&self, _b: &IntervalBox) -> bool {
        true
    }
    /// The velocity rows of an input or output set as a square matrix of the configuration
    /// (`RateMatrix`), when they are as many as the coordinates and the model writes them as
    /// such a matrix; `None` otherwise (C-space sets, non-square rows, the spatial model).
    fn rate_matrix(&self, _kind: SingularKind, _actuated: &[String], _output: Option<&Output>) -> Option<RateMatrix> {
        None
    }
}

impl Coordinates for LinkageProblem {
    fn system(&self) -> &EquationSystem {
        &self.system
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn model(&self) -> Model {
        Model::Planar
    }

    fn fixed_joints(&self) -> &[(String, f64)] {
        &self.fixed_joints
    }

    fn joint_values(&self, b: &IntervalBox) -> BTreeMap<String, (f64, f64)> {
        LinkageProblem::joint_values(self, b)
    }

    fn extended_solver<'s>(&'s self, system: &'s EquationSystem, settings: SolverSettings) -> Result<Solver<'s>, SolveError> {
        LinkageProblem::extended_solver(self, system, settings)
    }

    fn augment(&self, kind: SingularKind, actuated: &[String], output: Option<&Output>) -> Result<Augmented, SingularError> {
        let linkage = self;
        let free = || linkage.free_joints.join(", ");
        let rate_of = |name: &str| linkage.joint_coordinate(name);
        for a in actuated {
            if rate_of(a).is_none() {
                return Err(SingularError::UnknownActuated(a.clone(), free()));
            }
        }
        if let Some(Output::Joints(js)) = output {
            for j in js {
                if rate_of(j).is_none() {
                    return Err(SingularError::UnknownOutput(j.clone(), free()));
                }
            }
        }
        let system = &linkage.system;
        let mut aug = system.clone();
        let parts = Parts::new(linkage, &mut aug)?;
        let Parts { coords, loop_rates, .. } = &parts;
        let loop_rows = &parts.loop_rows;
        let dof = parts.dof();
        let coord_name = |c: &Coord| parts.coord_name(system, c);

        // Multipliers: velocities (input, output) or row multipliers (C-space).
        let n_mult = if kind == SingularKind::Cspace { loop_rows.len() } else { coords.len() };
        let multipliers: Vec<VarId> = (0..n_mult)
            .map(|i| {
                let name = if kind == SingularKind::Cspace { format!("lambda_{i}") } else { format!("v_{}", coord_name(&coords[i])) };
                aug.add_var(name, VarRole::Primary, interval(-CHART_REACH, CHART_REACH))
            })
            .collect();
        // factor·m as a linear term, through a cached bilinear product variable.
        let mut prod_cache: BTreeMap<(VarId, VarId), VarId> = BTreeMap::new();
        let mut term = |aug: &mut EquationSystem, coef: Interval, factor: Option<VarId>, m: VarId| -> Term {
            let Some(f) = factor else { return Term { coef, mono: Monomial::Linear(m) } };
            let p = *prod_cache.entry((f, m)).or_insert_with(|| {
                let dom = aug.vars[f].domain * aug.vars[m].domain;
                let p = aug.add_var(format!("{}*{}", aug.vars[f].name, aug.vars[m].name), VarRole::Derived, dom);
                aug.add(Equation::bilinear(p, f, m));
                p
            });
            Term { coef, mono: Monomial::Linear(p) }
        };
        let mut rows: Vec<Vec<Term>> = Vec::new();
        match kind {
            SingularKind::Cspace => {
                // Column i of λᵀ F_q: Σ_r λ_r ∂F_r/∂q_i.
                for i in 0..coords.len() {
                    let mut row = Vec::new();
                    for (r, rates) in loop_rates.iter().enumerate() {
                        for rate in rates.iter().filter(|x| x.coord == i) {
                            row.push(term(&mut aug, rate.coef, rate.factor, multipliers[r]));
                        }
                    }
                    rows.push(row);
                }
            }
            SingularKind::Input | SingularKind::Output => {
                if kind == SingularKind::Input && actuated.len() as isize != dof {
                    return Err(SingularError::ActuatorCount { actuated: actuated.len(), names: actuated.join(","), dof });
                }
                for rates in parts.velocity_rows(linkage, kind, actuated, output) {
                    let row = rates.iter().map(|r| term(&mut aug, r.coef, r.factor, multipliers[r.coord])).collect();
                    rows.push(row);
                }
            }
        }
        let n_rows = rows.len() as isize;
        for row in rows {
            // A row without terms reads 0 = 0: it constrains nothing (e.g. a joint to the ground
            // of a welded group), so it is left out rather than written.
            if !row.is_empty() {
                aug.add(Equation::new(merge(row), point(0.0)));
            }
        }
        Ok(Augmented { system: aug, multipliers, dof, rows: n_rows })
    }

    fn rate_matrix(&self, kind: SingularKind, actuated: &[String], output: Option<&Output>) -> Option<RateMatrix> {
        if kind == SingularKind::Cspace {
            return None;
        }
        let mut scratch = self.system.clone();
        let parts = Parts::new(self, &mut scratch).ok()?;
        let rows = parts.velocity_rows(self, kind, actuated, output);
        (rows.len() == parts.coords.len() && rows.iter().all(|r| !r.is_empty())).then(|| RateMatrix::new(parts, rows))
    }
}

/// The square matrix of a singular set's velocity rows, `[F_q; A]` (input) or `[F_q; O]`
/// (output), as a function of the configuration: the set is where it is singular. Columns are
/// the coordinates in the order of the set's multipliers (column `k` is chart `k`'s).
#[derive(Clone, Debug)]
pub struct RateMatrix {
    parts: Parts,
    rows: Vec<Vec<Rate>>,
    /// The entries grouped by their factor (`None`: constant): `M = Σ_f C_f · f`, each `C_f` a
    /// constant matrix given as `(row, column, coefficient)`.
    by_factor: Vec<(Option<VarId>, Entries)>,
}

/// `(row, column, coefficient)` entries of a constant matrix.
type Entries = Vec<(usize, usize, Interval)>;

impl RateMatrix {
    fn new(parts: Parts, rows: Vec<Vec<Rate>>) -> Self {
        let mut groups: BTreeMap<Option<VarId>, Entries> = BTreeMap::new();
        for (i, rates) in rows.iter().enumerate() {
            for r in rates {
                groups.entry(r.factor).or_default().push((i, r.coord, r.coef));
            }
        }
        RateMatrix { parts, rows, by_factor: groups.into_iter().collect() }
    }

    /// `Y·M` over a box of the linkage's variables, for a real matrix `Y`: each `Y·C_f` formed
    /// first and then multiplied by the range of its factor `f`, which is the exact range of
    /// each entry as a function of the factors, where the interval product `Y·M(b)` would add
    /// up the widths of every entry it combines. Outward rounded (`fast::Iv`).
    pub(crate) fn preconditioned(&self, y: &nalgebra::DMatrix<f64>, b: &[Interval]) -> nalgebra::DMatrix<Iv> {
        let n = self.order();
        let mut w = nalgebra::DMatrix::from_element(n, n, Iv::ZERO);
        let mut acc = nalgebra::DMatrix::from_element(n, n, Iv::ZERO);
        let mut touched = vec![false; n];
        for (factor, entries) in &self.by_factor {
            let x = Iv::from(factor.map_or(point(1.0), |f| self.parts.eval_var(b, f)));
            acc.fill(Iv::ZERO);
            touched.fill(false);
            for &(l, j, coef) in entries {
                let c = Iv::from(coef);
                touched[j] = true;
                for i in 0..n {
                    acc[(i, j)] = acc[(i, j)].add(c.scale(y[(i, l)]));
                }
            }
            for j in (0..n).filter(|&j| touched[j]) {
                for i in 0..n {
                    w[(i, j)] = w[(i, j)].add(acc[(i, j)].mul(x));
                }
            }
        }
        w
    }

    /// Its order (rows = columns = coordinates).
    pub fn order(&self) -> usize {
        self.rows.len()
    }

    /// The matrix over a box of the linkage's variables (the configuration part of a chart's
    /// box), outward rounded.
    pub fn over(&self, b: &[Interval]) -> nalgebra::DMatrix<Interval> {
        let n = self.order();
        let mut m = nalgebra::DMatrix::from_element(n, n, point(0.0));
        for (i, rates) in self.rows.iter().enumerate() {
            for r in rates {
                m[(i, r.coord)] += r.factor.map_or(r.coef, |f| r.coef * self.parts.eval_var(b, f));
            }
        }
        m
    }
}

/// The model-chosen linkage as a coordinate source: either builder's rows, one orchestration.
impl Coordinates for Linkage {
    fn system(&self) -> &EquationSystem {
        match self {
            Linkage::Planar(p) => Coordinates::system(p),
            Linkage::Spatial(p, _) => Coordinates::system(p),
            Linkage::Pose(p, _) => &p.system,
            Linkage::Distances(p, _) => &p.system,
        }
    }

    fn name(&self) -> &str {
        match self {
            Linkage::Planar(p) => Coordinates::name(p),
            Linkage::Spatial(p, _) => Coordinates::name(p),
            Linkage::Pose(p, _) => &p.name,
            Linkage::Distances(p, _) => &p.name,
        }
    }

    fn model(&self) -> Model {
        match self {
            Linkage::Planar(p) => p.model(),
            Linkage::Spatial(p, _) => p.model(),
            Linkage::Pose(..) => Model::Pose,
            Linkage::Distances(..) => Model::Distances,
        }
    }

    fn fixed_joints(&self) -> &[(String, f64)] {
        match self {
            Linkage::Planar(p) => Coordinates::fixed_joints(p),
            Linkage::Spatial(p, _) => Coordinates::fixed_joints(p),
            Linkage::Pose(p, _) => &p.fixed,
            Linkage::Distances(p, _) => &p.fixed,
        }
    }

    fn joint_values(&self, b: &IntervalBox) -> BTreeMap<String, (f64, f64)> {
        match self {
            Linkage::Planar(p) => p.joint_values(b),
            Linkage::Spatial(p, _) => p.joint_values(b),
            Linkage::Pose(p, _) => p.joint_values(b),
            Linkage::Distances(p, _) => p.joint_values(b),
        }
    }

    fn extended_solver<'s>(&'s self, system: &'s EquationSystem, settings: SolverSettings) -> Result<Solver<'s>, SolveError> {
        match self {
            Linkage::Planar(p) => p.extended_solver(system, settings),
            Linkage::Spatial(p, _) => p.extended_solver(system, settings),
            // The pose model's own pipeline on its own system; no other system extends it.
            Linkage::Pose(p, _) if std::ptr::eq(system, &p.system) => p.solver(settings),
            Linkage::Pose(..) | Linkage::Distances(..) => Solver::new(system, settings),
        }
    }

    fn augment(&self, kind: SingularKind, actuated: &[String], output: Option<&Output>) -> Result<Augmented, SingularError> {
        match self {
            Linkage::Planar(p) => p.augment(kind, actuated, output),
            Linkage::Spatial(p, _) => p.augment(kind, actuated, output),
            Linkage::Pose(..) | Linkage::Distances(..) => Err(SingularError::Linkage(LinkageError::NotJointModel)),
        }
    }

    fn rows_faithful(&self, b: &IntervalBox) -> bool {
        match self {
            Linkage::Planar(p) => p.rows_faithful(b),
            Linkage::Spatial(p, _) => p.rows_faithful(b),
            Linkage::Pose(..) | Linkage::Distances(..) => true,
        }
    }

    fn rate_matrix(&self, kind: SingularKind, actuated: &[String], output: Option<&Output>) -> Option<RateMatrix> {
        match self {
            Linkage::Planar(p) => p.rate_matrix(kind, actuated, output),
            Linkage::Spatial(p, _) => p.rate_matrix(kind, actuated, output),
            // Singular sets are built in joint coordinates (`Linkage::build_in_joints`).
            Linkage::Pose(..) | Linkage::Distances(..) => None,
        }
    }
}

impl SingularProblem {
    /// Builds the augmented systems of `kind` for the planar linkage `m` with joints `fixed`
    /// (`SingularSets` builds either model, as `solve --model auto` chooses).
    pub fn new(m: &Mechanism, fixed: &[(String, f64)], kind: SingularKind, actuated: &[String], output: Option<Output>) -> Result<Self, SingularError> {
        let traces: Vec<(String, f64, f64)> = match (&output, kind) {
            (Some(Output::Point { link, x, y }), SingularKind::Output) => vec![(link.clone(), *x, *y)],
            _ => Vec::new(),
        };
        Self::with_linkage(LinkageProblem::new(m, fixed, &traces)?, kind, actuated, output)
    }
}

impl<L: Coordinates> SingularProblem<L> {
    /// Builds the augmented systems of `kind` for a built linkage (with the output point traced
    /// when `output` is a point).
    pub fn with_linkage(linkage: L, kind: SingularKind, actuated: &[String], output: Option<Output>) -> Result<Self, SingularError> {
        for (k, a) in actuated.iter().enumerate() {
            if actuated[..k].contains(a) {
                return Err(SingularError::Repeated(a.clone()));
            }
        }
        let base_vars = linkage.system().vars.len();
        let Augmented { system: aug, multipliers, dof, rows } = linkage.augment(kind, actuated, output.as_ref())?;
        let n_mult = multipliers.len();
        // Unknowns added: the multipliers (one fixed by the chart); equations added: the rows.
        let expected_dimension = dof + (n_mult as isize - 1) - rows;
        let output = if kind == SingularKind::Output { output } else { None };
        Ok(Self { linkage, kind, actuated: actuated.to_vec(), output, dof, expected_dimension, augmented: aug, multipliers, base_vars })
    }

    /// Number of charts: one per multiplier.
    pub fn chart_count(&self) -> usize {
        self.multipliers.len()
    }

    /// The system of chart `k` (`m[k] = 1`); every chart shares every variable id.
    pub fn chart(&self, k: usize) -> EquationSystem {
        let mut s = self.augmented.clone();
        s.vars[self.multipliers[k]].domain = point(1.0);
        s.add(Equation::new(vec![Term { coef: point(1.0), mono: Monomial::Linear(self.multipliers[k]) }], point(-1.0)));
        s
    }

    /// Values of the actuated joints over a box (radians or metres), outward rounded.
    pub fn actuator_values(&self, b: &IntervalBox) -> Vec<(f64, f64)> {
        let base = IntervalBox::new(b.dims[..self.base_vars].to_vec());
        let all = self.linkage.joint_values(&base);
        self.actuated.iter().map(|a| all.get(a).copied().unwrap_or((f64::NAN, f64::NAN))).collect()
    }

    /// Free joint values over a box.
    pub fn joint_values(&self, b: &IntervalBox) -> BTreeMap<String, (f64, f64)> {
        self.linkage.joint_values(&IntervalBox::new(b.dims[..self.base_vars].to_vec()))
    }

    /// The model the linkage was built with.
    pub fn model(&self) -> Model {
        self.linkage.model()
    }
}

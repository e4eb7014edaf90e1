//! Velocity rows of a degree-2 system whose derived variables are defined one after the other,
//! and with them the singular-set systems of spatial linkages (`SpatialProblem`), built as the
//! planar ones are: a null vector on charts of the max-norm sphere, entering through products.
//!
//! Coordinates `q`: one angle per circle `c² + s² = 1` (rate `ω`: `ċ = −s·ω`, `ṡ = c·ω`) and
//! every other primary (its rate its own). Each derived variable `z` is defined by the first
//! equation that mentions it, linearly and after the variables it depends on (the spatial
//! builder writes them so: products, named forms, `n = |x|²`, traced points); its velocity is
//! a new derived variable `ż` defined by that equation's time derivative. Every other equation
//! with unknowns is a constraint row, and its time derivative is one row of `F_q v = 0`.
//! A degree-2 equation's derivative is linear in the velocities with coefficients linear in the
//! variables, so each `variable × velocity` is a derived product variable with a bilinear
//! definition: the augmented system keeps degree two and the solver's shapes.
//!
//! Why the rank condition is the mechanism's: the circles and definitions describe a manifold
//! M parametrised by `q` (each derived variable a function of earlier ones, its coefficient
//! non-zero), and their derivatives make `ż = ∂z/∂q · q̇` exactly; so the velocity rows hold iff
//! `F_q q̇ = 0` with F the constraint rows on M, and the velocity vector is non-zero iff `q̇` is:
//! the charts need only the coordinates' rates, as many as the planar builder's.
//! Only the variables the equations touch get velocities; derivatives of circles are not
//! written (the parametrisation satisfies them).
//!
//! C-space sets are the transposed construction (`adjoint_rows`): a multiplier per constraint
//! row, an adjoint per derived variable solved back through the definitions, one row per
//! coordinate. Axis closures written with two rows are widened to three at this level
//! (`Faithful`), so neither construction inherits the two rows' rank loss.

use crate::formulate::Model;
use super::{merge, Augmented, Coordinates, Output, SingularError, SingularKind, CHART_REACH};
use crate::kernel::interval::{interval, point, Interval, IntervalBox};
use crate::formulate::spatial::{AxisVelocity, JointMotion, LinearForm, SpatialProblem};
use crate::kernel::search::{SolveError, Solver, SolverSettings};
use crate::kernel::system::{Equation, EquationKind, EquationSystem, Monomial, Term, VarId, VarRole};
use std::collections::BTreeMap;

/// A coordinate of the configuration system.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Coordinate {
    /// An angle held as `(c, s)` on a circle.
    Angle { c: VarId, s: VarId },
    /// A primary variable of its own (travel, position).
    Var(VarId),
}

/// How a system's equations split: coordinates, definitions of the derived variables (in the
/// order they are defined), constraint rows.
#[derive(Clone, Debug)]
struct Structure {
    coords: Vec<Coordinate>,
    /// `(z, equation, a)`: the equation defines `z`, in which it appears once, as `a·z`.
    definitions: Vec<(VarId, usize, Interval)>,
    /// Equations with unknowns that define nothing (circles left out).
    constraints: Vec<usize>,
}

impl Structure {
    /// Each derived variable is defined by the first equation that mentions it, where it must
    /// appear linearly with a coefficient that is not zero, after the variables it depends on;
    /// anything else is an equation shape this construction does not know.
    fn new(system: &EquationSystem, skip: &[usize]) -> Result<Self, SingularError> {
        let n = system.vars.len();
        let mut coords: Vec<Coordinate> = Vec::new();
        let mut in_circle = vec![false; n];
        for (k, e) in system.equations.iter().enumerate() {
            if let EquationKind::Circle { x, y } = e.kind {
                if in_circle[x] || in_circle[y] {
                    return Err(SingularError::Unexpected(k));
                }
                in_circle[x] = true;
                in_circle[y] = true;
                coords.push(Coordinate::Angle { c: x, s: y });
            }
        }
        coords.extend(system.primaries().into_iter().filter(|&v| !in_circle[v]).map(Coordinate::Var));
        let mut known: Vec<bool> = system.vars.iter().map(|v| v.role == VarRole::Primary).collect();
        let mut definitions = Vec::new();
        let mut constraints = Vec::new();
        for (k, e) in system.equations.iter().enumerate() {
            if matches!(e.kind, EquationKind::Circle { .. }) || e.terms.is_empty() || skip.contains(&k) {
                continue;
            }
            let mut unknown: Vec<VarId> = e.vars().filter(|&v| !known[v]).collect();
            unknown.sort_unstable();
            unknown.dedup();
            match unknown.as_slice() {
                [] => constraints.push(k),
                &[z] => {
                    let linear: Vec<&Term> = e.terms.iter().filter(|t| t.mono == Monomial::Linear(z)).collect();
                    let only_linear = e.terms.iter().all(|t| t.mono == Monomial::Linear(z) || !mentions(t.mono, z));
                    let [t] = linear.as_slice() else { return Err(SingularError::Unexpected(k)) };
                    if !only_linear || t.coef.contains(0.0) {
                        return Err(SingularError::Unexpected(k));
                    }
                    definitions.push((z, k, t.coef));
                    known[z] = true;
                }
                _ => return Err(SingularError::Unexpected(k)),
            }
        }
        Ok(Self { coords, definitions, constraints })
    }
}

/// The equations as the first-order rows see them: each axis closure written with two rows
/// (`spatial::AxisVelocity`) replaced by its three component rows, appended, whose rows get one
/// more unknown `ν` times the axis (`δ = ν·u`), so that they keep the mechanism's rank where the
/// component left out vanishes and the system stays square.
#[derive(Clone, Debug)]
struct Faithful {
    system: EquationSystem,
    /// Per axis closure: its component rows (indices into `system.equations`) with the axis
    /// `u`'s component each, and how many rows the configuration system has for it.
    axes: Vec<(Vec<(usize, LinearForm)>, usize)>,
}

impl Faithful {
    /// A component whose `u − v` is identically zero (both axes confined to a plane) has no row
    /// in either form and is left out: the closure then has one row written, and its two other
    /// components become two rows with `ν`. A closure whose left-out component is identically
    /// equal on both sides keeps its rows as written (no mirror branch to meet).
    fn new(system: &EquationSystem, axes: &[AxisVelocity]) -> Self {
        let identity = |(terms, constant): &LinearForm| terms.is_empty() && constant.inf() == 0.0 && constant.sup() == 0.0;
        let widened: Vec<(&AxisVelocity, Vec<usize>)> = axes
            .iter()
            .map(|a| (a, (0..3).filter(|&c| !identity(&a.diff[c])).collect::<Vec<usize>>()))
            .filter(|(a, comps)| comps.len() == a.rows.len() + 1)
            .collect();
        let written: Vec<usize> = widened.iter().flat_map(|(a, _)| a.rows.iter().copied()).collect();
        let mut equations: Vec<Equation> = system.equations.iter().enumerate().filter(|(k, _)| !written.contains(k)).map(|(_, e)| e.clone()).collect();
        let mut out = Vec::new();
        for (a, comps) in widened {
            let rows = comps
                .iter()
                .map(|&c| {
                    let (terms, constant) = &a.diff[c];
                    equations.push(Equation::new(terms.iter().map(|&(x, k)| Term { coef: k, mono: Monomial::Linear(x) }).collect(), *constant));
                    (equations.len() - 1, a.u[c].clone())
                })
                .collect();
            out.push((rows, a.rows.len()));
        }
        Faithful { system: EquationSystem { vars: system.vars.clone(), equations }, axes: out }
    }

    /// The appended rows, which `Structure` leaves to the axis handling.
    fn axis_rows(&self) -> Vec<usize> {
        self.axes.iter().flat_map(|(r, _)| r.iter().map(|&(k, _)| k)).collect()
    }

    /// Constraint rows of the configuration system: the structure's plus the axis rows written.
    fn constraint_count(&self, st: &Structure) -> usize {
        st.constraints.len() + self.axes.iter().map(|(_, w)| w).sum::<usize>()
    }
}

/// `x·w` product variables with their bilinear definitions, added to an extended system on
/// first use.
#[derive(Clone, Debug, Default)]
struct Products(BTreeMap<(VarId, VarId), VarId>);

impl Products {
    fn get(&mut self, aug: &mut EquationSystem, x: VarId, w: VarId) -> VarId {
        *self.0.entry((x, w)).or_insert_with(|| {
            let dom = aug.vars[x].domain * aug.vars[w].domain;
            let p = aug.add_var(format!("{}*{}", aug.vars[x].name, aug.vars[w].name), VarRole::Derived, dom);
            aug.add(Equation::bilinear(p, x, w));
            p
        })
    }

    /// `factor·Σ a·w` as terms (`factor` 1 when `None`).
    fn times(&mut self, aug: &mut EquationSystem, factor: Option<VarId>, form: &[(VarId, Interval)], k: Interval, out: &mut Vec<Term>) {
        for &(w, a) in form {
            let mono = match factor {
                None => Monomial::Linear(w),
                Some(f) => Monomial::Linear(self.get(aug, f, w)),
            };
            out.push(Term { coef: k * a, mono });
        }
    }
}

/// `∂E/∂v` of one equation as `(factor, k)` pairs: `Σ k·factor`, factor a variable or 1.
fn partial(e: &Equation, v: VarId) -> Vec<(Option<VarId>, Interval)> {
    let mut out = Vec::new();
    for t in &e.terms {
        match t.mono {
            Monomial::Linear(x) if x == v => out.push((None, t.coef)),
            Monomial::Square(x) if x == v => out.push((Some(x), t.coef * point(2.0))),
            Monomial::Product(x, y) if x == v && y == v => out.push((Some(x), t.coef * point(2.0))),
            Monomial::Product(x, y) if x == v => out.push((Some(y), t.coef)),
            Monomial::Product(x, y) if y == v => out.push((Some(x), t.coef)),
            _ => {}
        }
    }
    out
}

/// The enclosure of `Σ terms` over the variables' domains.
fn enclosure(aug: &EquationSystem, terms: &[Term]) -> Interval {
    terms.iter().fold(point(0.0), |acc, t| {
        let m = match t.mono {
            Monomial::Linear(v) => aug.vars[v].domain,
            Monomial::Square(v) => aug.vars[v].domain.sqr(),
            Monomial::Product(x, y) => aug.vars[x].domain * aug.vars[y].domain,
        };
        acc + t.coef * m
    })
}

/// The velocity rows of a system, written into an extension of it.
#[derive(Clone, Debug)]
struct Velocities {
    /// Per coordinate: the variable of its rate (a multiplier of the null vector) and what it
    /// moves.
    coords: Vec<(VarId, Coordinate)>,
    /// Per variable of the base system: its velocity `Σ a·w` over velocity-level variables
    /// (rates, `ż` variables, products); empty when no equation needs it.
    vel: Vec<Vec<(VarId, Interval)>>,
    /// The constraint rows' derivatives: the rows of `F_q v = 0`.
    rows: Vec<Vec<Term>>,
}

impl Velocities {
    /// Writes into `aug` (which extends `system`) the rate variables, the velocities of the
    /// derived variables with their defining rows, and the products they need; the constraint
    /// rows' derivatives are kept in `rows`, for the caller to write with its own rows. `name`
    /// names a coordinate's rate.
    fn new(f: &Faithful, st: &Structure, aug: &mut EquationSystem, name: impl Fn(Coordinate) -> String) -> Result<Self, SingularError> {
        let system = &f.system;
        let mut products = Products::default();
        let coords: Vec<(VarId, Coordinate)> = st.coords.iter().map(|&c| (aug.add_var(format!("v_{}", name(c)), VarRole::Primary, interval(-CHART_REACH, CHART_REACH)), c)).collect();
        let mut vel = vec![Vec::new(); system.vars.len()];
        for &(w, c) in &coords {
            match c {
                Coordinate::Angle { c, s } => {
                    vel[c] = vec![(products.get(aug, s, w), point(-1.0))];
                    vel[s] = vec![(products.get(aug, c, w), point(1.0))];
                }
                Coordinate::Var(v) => vel[v] = vec![(w, point(1.0))],
            }
        }
        // d/dt Σ terms, the velocities of the variables known.
        let derivative = |terms: &[&Term], vel: &[Vec<(VarId, Interval)>], products: &mut Products, aug: &mut EquationSystem, k: usize| -> Result<Vec<Term>, SingularError> {
            let mut out = Vec::new();
            for t in terms {
                let parts: Vec<(Option<VarId>, VarId, Interval)> = match t.mono {
                    Monomial::Linear(x) => vec![(None, x, point(1.0))],
                    Monomial::Square(x) => vec![(Some(x), x, point(2.0))],
                    Monomial::Product(x, y) => vec![(Some(y), x, point(1.0)), (Some(x), y, point(1.0))],
                };
                for (factor, x, m) in parts {
                    if vel[x].is_empty() {
                        return Err(SingularError::Unexpected(k));
                    }
                    products.times(aug, factor, &vel[x], t.coef * m, &mut out);
                }
            }
            Ok(merge(out))
        };
        for &(z, k, a) in &st.definitions {
            // `a·z + rest = 0`, so `a·ż + d(rest)/dt = 0`.
            let rest: Vec<&Term> = system.equations[k].terms.iter().filter(|t| t.mono != Monomial::Linear(z)).collect();
            let mut row = derivative(&rest, &vel, &mut products, aug, k)?;
            let dz = aug.add_var(format!("d({})", system.vars[z].name), VarRole::Derived, -enclosure(aug, &row) / a);
            row.push(Term { coef: a, mono: Monomial::Linear(dz) });
            aug.add(Equation::new(row, point(0.0)));
            vel[z] = vec![(dz, point(1.0))];
        }
        let mut rows: Vec<Vec<Term>> = st.constraints.iter().map(|&k| derivative(&system.equations[k].terms.iter().collect::<Vec<_>>(), &vel, &mut products, aug, k)).collect::<Result<_, _>>()?;
        for (a, (comps, _)) in f.axes.iter().enumerate() {
            // δ_c − ν·u_c = 0 for the components.
            let nu = aug.add_var(format!("nu_{a}"), VarRole::Primary, interval(-CHART_REACH, CHART_REACH));
            for (k, (terms, constant)) in comps.iter().map(|(k, u)| (*k, u)) {
                let mut row = derivative(&system.equations[k].terms.iter().collect::<Vec<_>>(), &vel, &mut products, aug, k)?;
                for &(x, c) in terms {
                    products.times(aug, Some(x), &[(nu, point(1.0))], -c, &mut row);
                }
                row.push(Term { coef: -*constant, mono: Monomial::Linear(nu) });
                rows.push(merge(row));
            }
        }
        Ok(Velocities { coords, vel, rows })
    }

    /// The rate of a joint that moves one coordinate or variable, as linear terms.
    fn rate(&self, motion: JointMotion) -> Option<Vec<Term>> {
        match motion {
            JointMotion::Angle { c, .. } => {
                let &(w, _) = self.coords.iter().find(|(_, k)| matches!(k, Coordinate::Angle { c: x, .. } if *x == c))?;
                Some(vec![Term { coef: point(1.0), mono: Monomial::Linear(w) }])
            }
            JointMotion::Var(v) => self.var_rate(v),
            JointMotion::Loop => None,
        }
    }

    /// The velocity of a variable of the base system as linear terms.
    fn var_rate(&self, v: VarId) -> Option<Vec<Term>> {
        let vel = self.vel.get(v).filter(|x| !x.is_empty())?;
        Some(vel.iter().map(|&(w, a)| Term { coef: a, mono: Monomial::Linear(w) }).collect())
    }
}

/// The C-space rows `λᵀ dF/dq = 0` of a system, written into an extension of it: one
/// multiplier `λ_r` per constraint row and, through the definitions, an adjoint `μ_z` per
/// derived variable (`a·μ_z + Σ_e κ_e ∂E_e/∂z = 0` over the later equations `e` that mention `z`,
/// `κ` being `λ` or `μ`; solved from the last definition back, so `μ` is a function of `λ` and
/// vanishes with it); then one row per coordinate, `Σ_e κ_e ∂E_e/∂q = 0`, with `∂/∂φ =
/// −s ∂/∂c + c ∂/∂s` for an angle. That is `λᵀ` times the total derivative of the constraint
/// rows on the manifold of the definitions: the rows lose rank exactly where it has a root.
/// Returns the multipliers and the rows.
fn adjoint_rows(f: &Faithful, st: &Structure, aug: &mut EquationSystem) -> (Vec<VarId>, Vec<Vec<Term>>) {
    let system = &f.system;
    let mut products = Products::default();
    let rows_with_lambda: Vec<usize> = st.constraints.iter().copied().chain(f.axis_rows()).collect();
    let lambdas: Vec<VarId> = (0..rows_with_lambda.len()).map(|i| aug.add_var(format!("lambda_{i}"), VarRole::Primary, interval(-CHART_REACH, CHART_REACH))).collect();
    // κ per equation: λ for constraint rows, μ for definitions (once made).
    let mut kappa: Vec<Option<VarId>> = vec![None; system.equations.len()];
    for (&k, &l) in rows_with_lambda.iter().zip(&lambdas) {
        kappa[k] = Some(l);
    }
    let mut mentions_of: Vec<Vec<usize>> = vec![Vec::new(); system.vars.len()];
    for (k, e) in system.equations.iter().enumerate() {
        if matches!(e.kind, EquationKind::Circle { .. }) || e.terms.is_empty() {
            continue;
        }
        let mut vs: Vec<VarId> = e.vars().collect();
        vs.sort_unstable();
        vs.dedup();
        for v in vs {
            mentions_of[v].push(k);
        }
    }
    // Σ_e κ_e ∂E_e/∂v as terms, over the equations with a κ, but `skip`.
    let column = |v: VarId, skip: Option<usize>, kappa: &[Option<VarId>], products: &mut Products, aug: &mut EquationSystem| -> Vec<Term> {
        let mut out = Vec::new();
        for &k in &mentions_of[v] {
            let Some(kv) = kappa[k].filter(|_| Some(k) != skip) else { continue };
            for (factor, c) in partial(&system.equations[k], v) {
                products.times(aug, factor, &[(kv, point(1.0))], c, &mut out);
            }
        }
        merge(out)
    };
    for &(z, k, a) in st.definitions.iter().rev() {
        let mut row = column(z, Some(k), &kappa, &mut products, aug);
        let mu = aug.add_var(format!("mu({})", system.vars[z].name), VarRole::Derived, -enclosure(aug, &row) / a);
        row.push(Term { coef: a, mono: Monomial::Linear(mu) });
        aug.add(Equation::new(merge(row), point(0.0)));
        kappa[k] = Some(mu);
    }
    let mut rows = Vec::new();
    for &c in &st.coords {
        match c {
            Coordinate::Var(v) => rows.push(column(v, None, &kappa, &mut products, aug)),
            Coordinate::Angle { c, s } => {
                // −s·(λᵀ∂F/∂c) + c·(λᵀ∂F/∂s), each a form in κ-level variables times a variable.
                let dc = column(c, None, &kappa, &mut products, aug);
                let ds = column(s, None, &kappa, &mut products, aug);
                let mut row = Vec::new();
                for (factor, form, sign) in [(s, dc, -1.0), (c, ds, 1.0)] {
                    let pairs: Vec<(VarId, Interval)> = form.iter().map(|t| match t.mono {
                        Monomial::Linear(w) => (w, t.coef),
                        _ => unreachable!("columns are linear"),
                    }).collect();
                    products.times(aug, Some(factor), &pairs, point(sign), &mut row);
                }
                rows.push(merge(row));
            }
        }
    }
    // ν's column: −Σ_c λ_c u_c = 0 (λ orthogonal to the axis).
    for (comps, _) in &f.axes {
        let mut row = Vec::new();
        for (k, (terms, constant)) in comps.iter().map(|(k, u)| (*k, u)) {
            let l = kappa[k].expect("axis rows carry a multiplier");
            for &(x, c) in terms {
                products.times(aug, Some(x), &[(l, point(1.0))], -c, &mut row);
            }
            row.push(Term { coef: -*constant, mono: Monomial::Linear(l) });
        }
        rows.push(merge(row));
    }
    (lambdas, rows)
}

fn mentions(m: Monomial, v: VarId) -> bool {
    match m {
        Monomial::Linear(x) | Monomial::Square(x) => x == v,
        Monomial::Product(x, y) => x == v || y == v,
    }
}


impl Coordinates for SpatialProblem {
    fn system(&self) -> &EquationSystem {
        &self.system
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn model(&self) -> Model {
        Model::Spatial
    }

    fn fixed_joints(&self) -> &[(String, f64)] {
        &self.fixed_joints
    }

    fn joint_values(&self, b: &IntervalBox) -> BTreeMap<String, (f64, f64)> {
        SpatialProblem::joint_values(self, b)
    }

    fn extended_solver<'s>(&'s self, system: &'s EquationSystem, settings: SolverSettings) -> Result<Solver<'s>, SolveError> {
        SpatialProblem::extended_solver(self, system, settings)
    }

    /// An axis closure is written with two of its three rows (`axes_agree` in `spatial`): the
    /// mirror branch they also admit (the component left out of opposite signs) is removed by
    /// the sign filter only where the signs are told apart, and it meets the true branch where
    /// that component vanishes; a root in a box that straddles zero there may be the mirror's,
    /// so it is never certified.
    fn rows_faithful(&self, b: &IntervalBox) -> bool {
        !self.axis_rows_may_degenerate(b)
    }

    fn augment(&self, kind: SingularKind, actuated: &[String], output: Option<&Output>) -> Result<Augmented, SingularError> {
        let free = || self.free_joints.join(", ");
        let motion = |name: &str, unknown: fn(String, String) -> SingularError| -> Result<JointMotion, SingularError> {
            match self.joint_motion(name) {
                None => Err(unknown(name.to_string(), free())),
                Some(JointMotion::Loop) => Err(SingularError::LoopJoint(name.to_string())),
                Some(m) => Ok(m),
            }
        };
        let actuated_motions = actuated.iter().map(|a| motion(a, SingularError::UnknownActuated)).collect::<Result<Vec<_>, _>>()?;
        let output_motions = match output {
            Some(Output::Joints(js)) => js.iter().map(|j| motion(j, SingularError::UnknownOutput)).collect::<Result<Vec<_>, _>>()?,
            // Default: every passive tree joint stands still (a loop joint's rate is no
            // coordinate's, so it is left out).
            None => self.free_joints.iter().filter(|j| !actuated.contains(j)).filter_map(|j| self.joint_motion(j)).filter(|m| *m != JointMotion::Loop).collect(),
            Some(Output::Point { .. }) => Vec::new(),
        };
        let coordinate_name = |c: Coordinate| -> String {
            let joint = self.free_joints.iter().find(|j| match (self.joint_motion(j), c) {
                (Some(JointMotion::Angle { c: x, .. }), Coordinate::Angle { c, .. }) => x == c,
                (Some(JointMotion::Var(x)), Coordinate::Var(v)) => x == v,
                _ => false,
            });
            match (joint, c) {
                (Some(j), _) => j.clone(),
                (None, Coordinate::Angle { c, .. }) => self.system.vars[c].name.clone(),
                (None, Coordinate::Var(v)) => self.system.vars[v].name.clone(),
            }
        };
        let faithful = Faithful::new(&self.system, &self.axis_velocities());
        let st = Structure::new(&faithful.system, &faithful.axis_rows())?;
        let dof = st.coords.len() as isize - faithful.constraint_count(&st) as isize;
        let mut aug = self.system.clone();
        if kind == SingularKind::Cspace {
            let (multipliers, rows) = adjoint_rows(&faithful, &st, &mut aug);
            let n_rows = rows.len() as isize;
            for row in rows.into_iter().filter(|r| !r.is_empty()) {
                aug.add(Equation::new(row, point(0.0)));
            }
            return Ok(Augmented { system: aug, multipliers, dof, rows: n_rows });
        }
        let vel = Velocities::new(&faithful, &st, &mut aug, coordinate_name)?;
        let mut rows = vel.rows.clone();
        // Each ν is one more unknown beside its three rows.
        let nus = faithful.axes.len() as isize;
        match kind {
            SingularKind::Input => {
                if actuated.len() as isize != dof {
                    return Err(SingularError::ActuatorCount { actuated: actuated.len(), names: actuated.join(","), dof });
                }
                rows.extend(actuated_motions.iter().map(|&m| vel.rate(m).expect("checked: a tree joint's motion")));
            }
            SingularKind::Output => match output {
                Some(Output::Point { link, x, y }) => {
                    let label = point_label(link, *x, *y);
                    let t = self.traces.iter().find(|t| t.name == label).ok_or(SingularError::Unexpected(0))?;
                    for v in t.xyz {
                        // A coordinate that no equation touches has velocity zero.
                        rows.push(vel.var_rate(v).unwrap_or_default());
                    }
                }
                _ => rows.extend(output_motions.iter().map(|&m| vel.rate(m).expect("checked: a tree joint's motion"))),
            },
            SingularKind::Cspace => unreachable!("handled above"),
        }
        let n_rows = rows.len() as isize - nus;
        for row in rows {
            if !row.is_empty() {
                aug.add(Equation::new(merge(row), point(0.0)));
            }
        }
        Ok(Augmented { system: aug, multipliers: vel.coords.iter().map(|&(w, _)| w).collect(), dof, rows: n_rows })
    }
}

/// The name of an output point `LINK@X,Y` as traced (`SingularSets` builds it so).
pub(crate) fn point_label(link: &str, x: f64, y: f64) -> String {
    format!("{link}@{x},{y}")
}

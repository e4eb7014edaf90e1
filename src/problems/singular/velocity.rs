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

use super::{merge, Augmented, Coordinates, Output, SingularError, SingularKind, CHART_REACH};
use crate::interval::{interval, point, Interval, IntervalBox};
use crate::problems::spatial::{JointMotion, SpatialProblem};
use crate::search::{SolveError, Solver, SolverSettings};
use crate::system::{Equation, EquationKind, EquationSystem, Monomial, Term, VarId, VarRole};
use std::collections::BTreeMap;

/// A coordinate of the configuration system.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Coordinate {
    /// An angle held as `(c, s)` on a circle.
    Angle { c: VarId, s: VarId },
    /// A primary variable of its own (travel, position).
    Var(VarId),
}

/// The velocity rows of a system, written into an extension of it.
#[derive(Clone, Debug)]
pub(crate) struct Velocities {
    /// Per coordinate: the variable of its rate (a multiplier of the null vector) and what it
    /// moves.
    coords: Vec<(VarId, Coordinate)>,
    /// Per variable of the base system: its velocity `Σ a·w` over velocity-level variables
    /// (rates, `ż` variables, products); empty when no equation needs it.
    vel: Vec<Vec<(VarId, Interval)>>,
    /// The constraint rows' derivatives: the rows of `F_q v = 0`.
    rows: Vec<Vec<Term>>,
    /// `x·w` products, keyed by (base variable, velocity-level variable).
    products: BTreeMap<(VarId, VarId), VarId>,
}

impl Velocities {
    /// Reads the coordinates and definitions of `system` and writes into `aug` (which extends
    /// it) the rate variables, the velocities of the derived variables with their defining
    /// rows, and the products they need; the constraint rows' derivatives are kept in `rows`,
    /// for the caller to write with its own rows. `name` names a coordinate's rate.
    fn new(system: &EquationSystem, aug: &mut EquationSystem, name: impl Fn(Coordinate) -> String) -> Result<Self, SingularError> {
        let n = system.vars.len();
        let mut coords: Vec<Coordinate> = Vec::new();
        let mut in_circle = vec![false; n];
        for e in &system.equations {
            if let EquationKind::Circle { x, y } = e.kind {
                if in_circle[x] || in_circle[y] {
                    return Err(SingularError::Unexpected(0));
                }
                in_circle[x] = true;
                in_circle[y] = true;
                coords.push(Coordinate::Angle { c: x, s: y });
            }
        }
        coords.extend(system.primaries().into_iter().filter(|&v| !in_circle[v]).map(Coordinate::Var));
        let rates: Vec<(VarId, Coordinate)> = coords.iter().map(|&c| (aug.add_var(format!("v_{}", name(c)), VarRole::Primary, interval(-CHART_REACH, CHART_REACH)), c)).collect();
        let mut me = Velocities { coords: rates.clone(), vel: vec![Vec::new(); n], rows: Vec::new(), products: BTreeMap::new() };
        for &(w, c) in &rates {
            match c {
                Coordinate::Angle { c, s } => {
                    let sw = me.product(aug, s, w);
                    let cw = me.product(aug, c, w);
                    me.vel[c] = vec![(sw, point(-1.0))];
                    me.vel[s] = vec![(cw, point(1.0))];
                }
                Coordinate::Var(v) => me.vel[v] = vec![(w, point(1.0))],
            }
        }
        for (k, e) in system.equations.iter().enumerate() {
            if matches!(e.kind, EquationKind::Circle { .. }) || e.terms.is_empty() {
                continue;
            }
            let mut unknown: Vec<VarId> = e.vars().filter(|&v| me.vel[v].is_empty()).collect();
            unknown.sort_unstable();
            unknown.dedup();
            match unknown.as_slice() {
                [] => {
                    let row = me.derivative(aug, &e.terms, k)?;
                    me.rows.push(row);
                }
                &[z] => {
                    // z's definition: `a·z + rest = 0`, so `ż = −(d rest/dt)/a`.
                    let linear: Vec<&Term> = e.terms.iter().filter(|t| t.mono == Monomial::Linear(z)).collect();
                    let only_linear = e.terms.iter().all(|t| t.mono == Monomial::Linear(z) || !mentions(t.mono, z));
                    let [t] = linear.as_slice() else { return Err(SingularError::Unexpected(k)) };
                    let a = t.coef;
                    if system.vars[z].role != VarRole::Derived || !only_linear || a.contains(0.0) {
                        return Err(SingularError::Unexpected(k));
                    }
                    let rest: Vec<Term> = e.terms.iter().filter(|t| t.mono != Monomial::Linear(z)).copied().collect();
                    let mut row = me.derivative(aug, &rest, k)?;
                    let sum = row.iter().fold(point(0.0), |acc, t| acc + t.coef * enclosure(aug, t.mono));
                    let dz = aug.add_var(format!("d({})", system.vars[z].name), VarRole::Derived, -sum / a);
                    row.push(Term { coef: a, mono: Monomial::Linear(dz) });
                    aug.add(Equation::new(row, point(0.0)));
                    me.vel[z] = vec![(dz, point(1.0))];
                }
                _ => return Err(SingularError::Unexpected(k)),
            }
        }
        Ok(me)
    }

    /// The product variable `x·w`, added to `aug` on first use.
    fn product(&mut self, aug: &mut EquationSystem, x: VarId, w: VarId) -> VarId {
        *self.products.entry((x, w)).or_insert_with(|| {
            let dom = aug.vars[x].domain * aug.vars[w].domain;
            let p = aug.add_var(format!("{}*{}", aug.vars[x].name, aug.vars[w].name), VarRole::Derived, dom);
            aug.add(Equation::bilinear(p, x, w));
            p
        })
    }

    /// `d/dt Σ terms` as linear terms in velocity-level variables (products added to `aug`).
    fn derivative(&mut self, aug: &mut EquationSystem, terms: &[Term], row: usize) -> Result<Vec<Term>, SingularError> {
        let mut out: Vec<Term> = Vec::new();
        for t in terms {
            // (factor, variable whose velocity, multiplier): d(mono) = Σ factor·vel(variable)·k.
            let parts: Vec<(Option<VarId>, VarId, Interval)> = match t.mono {
                Monomial::Linear(x) => vec![(None, x, point(1.0))],
                Monomial::Square(x) => vec![(Some(x), x, point(2.0))],
                Monomial::Product(x, y) => vec![(Some(y), x, point(1.0)), (Some(x), y, point(1.0))],
            };
            for (factor, x, k) in parts {
                if self.vel[x].is_empty() {
                    return Err(SingularError::Unexpected(row));
                }
                for (w, a) in self.vel[x].clone() {
                    let mono = match factor {
                        None => Monomial::Linear(w),
                        Some(f) => Monomial::Linear(self.product(aug, f, w)),
                    };
                    out.push(Term { coef: t.coef * a * k, mono });
                }
            }
        }
        Ok(merge(out))
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

fn mentions(m: Monomial, v: VarId) -> bool {
    match m {
        Monomial::Linear(x) | Monomial::Square(x) => x == v,
        Monomial::Product(x, y) => x == v || y == v,
    }
}

/// The enclosure of a linear monomial over the variables' domains.
fn enclosure(aug: &EquationSystem, m: Monomial) -> Interval {
    match m {
        Monomial::Linear(v) => aug.vars[v].domain,
        Monomial::Square(v) => aug.vars[v].domain.sqr(),
        Monomial::Product(x, y) => aug.vars[x].domain * aug.vars[y].domain,
    }
}

impl Coordinates for SpatialProblem {
    fn system(&self) -> &EquationSystem {
        &self.system
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn model(&self) -> &'static str {
        "spatial"
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

    fn augment(&self, kind: SingularKind, actuated: &[String], output: Option<&Output>) -> Result<Augmented, SingularError> {
        if kind == SingularKind::Cspace {
            return Err(SingularError::SpatialCspace);
        }
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
        let mut aug = self.system.clone();
        let vel = Velocities::new(&self.system, &mut aug, coordinate_name)?;
        let dof = vel.coords.len() as isize - vel.rows.len() as isize;
        let mut rows = vel.rows.clone();
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
                    let t = self.traces.iter().find(|t| t.name == label).ok_or_else(|| SingularError::Unexpected(0))?;
                    for v in t.xyz {
                        // A coordinate that no equation touches has velocity zero.
                        rows.push(vel.var_rate(v).unwrap_or_default());
                    }
                }
                _ => rows.extend(output_motions.iter().map(|&m| vel.rate(m).expect("checked: a tree joint's motion"))),
            },
            SingularKind::Cspace => unreachable!("refused above"),
        }
        let n_rows = rows.len() as isize;
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

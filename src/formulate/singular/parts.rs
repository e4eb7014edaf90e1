//! The coordinates of a linkage's system and the time derivatives of its rows (`Parts`): which
//! variable is a cosine, a sine, a travel or a product `z = d·f`, and each loop or trace row's
//! first and second derivatives as `Rate` and `Rate2` terms. Shared by the singular-set, cusp and
//! node builders; it adds only the product partners the derivatives need.

use super::{Output, SingularError, SingularKind};
use crate::formulate::linkage::{JointCoordinate, LinkageProblem};
use crate::kernel::interval::{interval, point, Interval};
use crate::kernel::system::{Equation, EquationKind, EquationSystem, Monomial, Term, VarId, VarRole};
use std::collections::BTreeMap;

/// The velocity coordinates: a free group angle or a slider travel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Coord {
    Angle { c: VarId, s: VarId },
    Travel(VarId),
}

/// What a base variable is, for differentiation.
#[derive(Clone, Copy, Debug)]
enum Role {
    Cos { coord: usize, s: VarId },
    Sin { coord: usize, c: VarId },
    Travel { coord: usize },
    /// `z = d·f`, `f` the cosine or sine of an angle coordinate.
    Product { d: VarId, f: VarId },
    Other,
}

/// `coef · factor · ṁ_coord`, `factor` a variable or 1: one term of a row's time derivative.
#[derive(Clone, Copy, Debug)]
pub(super) struct Rate {
    pub(super) coef: Interval,
    pub(super) factor: Option<VarId>,
    pub(super) coord: usize,
}

/// The coordinates of a linkage's system and the time derivatives of its rows, shared by the
/// singular-set, cusp and node builders.
#[derive(Clone, Debug)]
pub(crate) struct Parts {
    pub(super) coords: Vec<Coord>,
    roles: Vec<Role>,
    /// `z = d·f` products, keyed by (travel, cosine or sine); grows with the partners the
    /// derivatives need.
    products: BTreeMap<(VarId, VarId), VarId>,
    pub(super) loop_rows: Vec<usize>,
    pub(super) loop_rates: Vec<Vec<Rate>>,
    trace_rates: Vec<Vec<Rate>>,
    traced: Vec<VarId>,
}

impl Parts {
    /// Reads the coordinates of `linkage`'s system and differentiates its rows; product
    /// partners the derivatives need are added to `aug` (which extends the linkage's system).
    pub(crate) fn new(linkage: &LinkageProblem, aug: &mut EquationSystem) -> Result<Self, SingularError> {
        let system = &linkage.system;
        let base_vars = system.vars.len();
        let mut coords: Vec<Coord> = Vec::new();
        let mut roles = vec![Role::Other; base_vars];
        for e in &system.equations {
            if let EquationKind::Circle { x, y } = e.kind {
                roles[x] = Role::Cos { coord: coords.len(), s: y };
                roles[y] = Role::Sin { coord: coords.len(), c: x };
                coords.push(Coord::Angle { c: x, s: y });
            }
        }
        for v in system.primaries() {
            if matches!(roles[v], Role::Other) {
                roles[v] = Role::Travel { coord: coords.len() };
                coords.push(Coord::Travel(v));
            }
        }
        let mut products: BTreeMap<(VarId, VarId), VarId> = BTreeMap::new();
        for e in &system.equations {
            if let EquationKind::Bilinear { z, x, y } = e.kind {
                // linkage writes z = d·f with the travel first.
                let (d, f) = if matches!(roles[x], Role::Travel { .. }) { (x, y) } else { (y, x) };
                roles[z] = Role::Product { d, f };
                products.insert((d, f), z);
            }
        }
        let traced: Vec<VarId> = linkage.traces.iter().flat_map(|t| [t.x, t.y]).collect();
        let mut loop_rows = Vec::new();
        let mut trace_rows = Vec::new();
        for (k, e) in system.equations.iter().enumerate() {
            if e.kind != EquationKind::Linear {
                continue;
            }
            if e.vars().any(|v| traced.contains(&v)) {
                trace_rows.push(k);
            } else {
                loop_rows.push(k);
            }
        }
        let mut p = Parts { coords, roles, products, loop_rows: loop_rows.clone(), loop_rates: Vec::new(), trace_rates: Vec::new(), traced };
        p.loop_rates = loop_rows.iter().map(|&r| p.derivative(system, r, aug)).collect::<Result<_, _>>()?;
        p.trace_rates = trace_rows.iter().map(|&r| p.derivative(system, r, aug)).collect::<Result<_, _>>()?;
        Ok(p)
    }

    /// The rows of `F_q v = 0` and of the input's or output's rates (`A v = 0`, `O v = 0`).
    pub(super) fn velocity_rows(&self, linkage: &LinkageProblem, kind: SingularKind, actuated: &[String], output: Option<&Output>) -> Vec<Vec<Rate>> {
        let mut rows: Vec<Vec<Rate>> = self.loop_rates.clone();
        let joint_rates = |name: &str| self.joint_rates(linkage, name);
        if kind == SingularKind::Input {
            rows.extend(actuated.iter().map(|a| joint_rates(a)));
        } else {
            match output {
                Some(Output::Point { .. }) => rows.extend(self.trace_rates.iter().cloned()),
                Some(Output::Joints(js)) => rows.extend(js.iter().map(|j| joint_rates(j))),
                // Default: every passive joint stands still (the Jacobian with respect to the
                // actuated coordinates loses rank).
                None => rows.extend(linkage.free_joints.iter().filter(|j| !actuated.contains(j)).map(|j| joint_rates(j))),
            }
        }
        rows
    }

    /// Coordinates minus loop rows.
    pub(super) fn dof(&self) -> isize {
        self.coords.len() as isize - self.loop_rows.len() as isize
    }

    pub(super) fn coord_name(&self, system: &EquationSystem, c: &Coord) -> String {
        match *c {
            Coord::Angle { c, .. } => system.vars[c].name.trim_start_matches("cos_").to_string(),
            Coord::Travel(d) => system.vars[d].name.trim_start_matches("d_").to_string(),
        }
    }

    /// The product variable `d·partner`, added to `aug` on first use.
    fn product(&mut self, aug: &mut EquationSystem, d: VarId, partner: VarId) -> VarId {
        *self.products.entry((d, partner)).or_insert_with(|| {
            let reach = aug.vars[d].domain.mag();
            let z = aug.add_var(format!("{}*{}", aug.vars[d].name, aug.vars[partner].name), VarRole::Derived, interval(-reach, reach));
            aug.add(Equation::bilinear(z, d, partner));
            z
        })
    }

    /// Time derivative of a linear row, as rates; every variable but the traced ones.
    fn derivative(&mut self, system: &EquationSystem, row: usize, aug: &mut EquationSystem) -> Result<Vec<Rate>, SingularError> {
        let mut out = Vec::new();
        for t in &system.equations[row].terms {
            let Monomial::Linear(v) = t.mono else { return Err(SingularError::Unexpected(row)) };
            let coef = t.coef;
            match self.roles[v] {
                Role::Cos { coord, s } => out.push(Rate { coef: -coef, factor: Some(s), coord }),
                Role::Sin { coord, c } => out.push(Rate { coef, factor: Some(c), coord }),
                Role::Travel { coord } => out.push(Rate { coef, factor: None, coord }),
                Role::Product { d, f } => {
                    let Role::Travel { coord: dc } = self.roles[d] else { return Err(SingularError::Unexpected(row)) };
                    out.push(Rate { coef, factor: Some(f), coord: dc });
                    let (coord, partner, sign) = match self.roles[f] {
                        Role::Cos { coord, s } => (coord, s, -1.0),
                        Role::Sin { coord, c } => (coord, c, 1.0),
                        _ => return Err(SingularError::Unexpected(row)),
                    };
                    let zp = self.product(aug, d, partner);
                    out.push(Rate { coef: coef * point(sign), factor: Some(zp), coord });
                }
                Role::Other if self.traced.contains(&v) => {}
                Role::Other => return Err(SingularError::Unexpected(row)),
            }
        }
        Ok(out)
    }

    /// Second time derivative of a loop row along a straight line in the coordinates
    /// (`q̈ = 0`, `q̇ = m`): `F_qq[m, m]` as terms `coef · factor · m_a · m_b`.
    /// `c̈ = −c·φ̇²`, `s̈ = −s·φ̇²`, `d̈ = 0`, `(d·c)̈ = −2·s·ḋ·φ̇ − (d·c)·φ̇²`,
    /// `(d·s)̈ = 2·c·ḋ·φ̇ − (d·s)·φ̇²`.
    pub(super) fn second_derivative(&self, system: &EquationSystem, row: usize) -> Result<Vec<Rate2>, SingularError> {
        let mut out = Vec::new();
        for t in &system.equations[row].terms {
            let Monomial::Linear(v) = t.mono else { return Err(SingularError::Unexpected(row)) };
            let coef = t.coef;
            match self.roles[v] {
                Role::Cos { coord, .. } | Role::Sin { coord, .. } => out.push(Rate2 { coef: -coef, factor: Some(v), a: coord, b: coord }),
                Role::Travel { .. } => {}
                Role::Product { d, f } => {
                    let Role::Travel { coord: dc } = self.roles[d] else { return Err(SingularError::Unexpected(row)) };
                    let (coord, partner, sign) = match self.roles[f] {
                        Role::Cos { coord, s } => (coord, s, -1.0),
                        Role::Sin { coord, c } => (coord, c, 1.0),
                        _ => return Err(SingularError::Unexpected(row)),
                    };
                    out.push(Rate2 { coef: coef * point(2.0 * sign), factor: Some(partner), a: dc.min(coord), b: dc.max(coord) });
                    out.push(Rate2 { coef: -coef, factor: Some(v), a: coord, b: coord });
                }
                Role::Other if self.traced.contains(&v) => {}
                Role::Other => return Err(SingularError::Unexpected(row)),
            }
        }
        Ok(out)
    }

    /// The coordinate of a variable (the cosine of an angle, or a travel).
    fn coord_of(&self, var: VarId) -> Option<usize> {
        match self.roles[var] {
            Role::Cos { coord, .. } | Role::Travel { coord } => Some(coord),
            _ => None,
        }
    }

    /// The rate of a joint as rates with factor 1.
    pub(super) fn joint_rates(&self, linkage: &LinkageProblem, name: &str) -> Vec<Rate> {
        match linkage.joint_coordinate(name) {
            Some(JointCoordinate::Travel(v)) => self.coord_of(v).map(|coord| Rate { coef: point(1.0), factor: None, coord }).into_iter().collect(),
            Some(JointCoordinate::Angles { plus, minus }) => {
                let mut r = Vec::new();
                if let Some(coord) = plus.and_then(|(c, _)| self.coord_of(c)) {
                    r.push(Rate { coef: point(1.0), factor: None, coord });
                }
                if let Some(coord) = minus.and_then(|(c, _)| self.coord_of(c)) {
                    r.push(Rate { coef: point(-1.0), factor: None, coord });
                }
                r
            }
            None => Vec::new(),
        }
    }

    /// The variables of a joint that is a coordinate of its own (a revolute joint to the
    /// ground: its cosine and sine; a slider: its travel), else `None`.
    pub(crate) fn own_coordinate(&self, linkage: &LinkageProblem, name: &str) -> Option<(usize, Vec<VarId>)> {
        match linkage.joint_coordinate(name)? {
            JointCoordinate::Travel(v) => Some((self.coord_of(v)?, vec![v])),
            JointCoordinate::Angles { plus: Some((c, s)), minus: None } | JointCoordinate::Angles { plus: None, minus: Some((c, s)) } => Some((self.coord_of(c)?, vec![c, s])),
            _ => None,
        }
    }

    /// Value of a variable of `aug` over a box of the linkage's variables: the variable itself,
    /// or a product partner added by the derivatives (`d·partner`).
    pub(super) fn eval_var(&self, b: &[Interval], v: VarId) -> Interval {
        if v < b.len() {
            return b[v];
        }
        self.products.iter().find(|(_, &z)| z == v).map_or(Interval::ENTIRE, |(&(d, f), _)| b[d] * b[f])
    }

    /// The loop rows' Jacobian `F_q` over a box of the linkage's variables (rows: loop rows,
    /// columns: coordinates), outward rounded.
    pub(crate) fn jacobian(&self, b: &[Interval]) -> Vec<Vec<Interval>> {
        self.loop_rates
            .iter()
            .map(|rates| {
                let mut row = vec![point(0.0); self.coords.len()];
                for r in rates {
                    row[r.coord] += r.factor.map_or(r.coef, |f| r.coef * self.eval_var(b, f));
                }
                row
            })
            .collect()
    }
}

/// `coef · factor · m_a · m_b` (`a ≤ b`), `factor` a variable or 1: one term of a row's second
/// derivative.
#[derive(Clone, Copy, Debug)]
pub(super) struct Rate2 {
    pub(super) coef: Interval,
    pub(super) factor: Option<VarId>,
    pub(super) a: usize,
    pub(super) b: usize,
}

/// Merges repeated monomials (a product met twice) into one term.
pub(super) fn merge(terms: Vec<Term>) -> Vec<Term> {
    let mut out: Vec<Term> = Vec::new();
    for t in terms {
        match out.iter_mut().find(|o| o.mono == t.mono) {
            Some(o) => o.coef += t.coef,
            None => out.push(t),
        }
    }
    out
}

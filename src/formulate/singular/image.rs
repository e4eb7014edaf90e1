//! The cusp and node systems of the type-II singular set's image in actuator space, for 2-dof
//! linkages whose actuated joints are coordinates of their own (revolute joints to the ground,
//! sliders). Builds only: `crate::analyses::loop_singular::image` runs the searches on them, certifies cusps and
//! nodes like the 3R ones (Krawczyk, as in Benoit, Delanoue, Lagrange and Wenger 2019), cuts
//! actuator space into regions and gives the verdict on non-singular assembly-mode change.
//!
//! ## Cusps
//! `S` is the input-singular set: `F(q) = 0`, `F_q v = 0`, `A v = 0`, `v_k = 1` (chart `k` of
//! `v`'s direction), a curve `Ŝ` in `(q, v)`. The actuator map `φ = A q` restricted to `C` folds
//! along `S`; its image has a cusp where the fold degenerates: the tangent `t` of `S` lies in the
//! kernel of `φ`, `A t = 0`. Differentiating `Ŝ`'s equations along a tangent `(t, w)`:
//! `F_q t = 0`, `F_qq[t, v] + F_q w = 0`, `A w = 0`, `w_k = 0`. With `A t = 0` too, `t` lies in
//! the kernel of `[F_q; A]`, which is spanned by `v` at a corank-one point: `t = μ v`, so
//!
//! > `μ · F_qq[v, v] + F_q w = 0`, `A w = 0`, `w_k = 0`, `(μ, w) ≠ 0`.
//!
//! Multiplying by the left null vector `λ` of `[F_q; A]` shows this is the classical fold
//! degeneracy `λ_Fᵀ F_qq[v, v] = 0` (the second derivative of the constraints along the kernel
//! has no component across the range); the `w` form keeps the system square. `μ = 0` (the tangent
//! of `Ŝ` is vertical, `w` a second null vector) marks corank-two points, also reported (their
//! records say `degenerate`). The tangent direction `(μ, w)` is projective like `v`: charts
//! `μ = 1` or `w_j = 1` (j ≠ k), `|·| ≤ 1.05` for the rest, ownership as for `v`. Unknowns added
//! to `S`'s chart system: `μ` and `w` (n + 1, one fixed by the chart, `w_k` fixed to 0);
//! equations: the loop rows of the second-order condition, `A w = 0` and the two normalisations
//! (n + 2): `S` is a curve, so each `(k, τ)` system is square and Krawczyk certifies its
//! isolated roots. Degree two: `F_qq[v, v]` is linear in `c, s, d·c, d·s` times `v_a v_b`
//! (`c̈ = −c φ̇²`, `(d·c)̈ = −2 s ḋ φ̇ − (d·c) φ̇²`, ...), entered through product variables
//! `u_ab = v_a v_b`, `r_ab = μ u_ab`, `factor · r_ab` (bilinear equations, squares for `a = b`).
//! A certified root with `μ ≠ 0` is a regular zero of the cusp system: a Whitney cusp of the
//! map `C → actuator space` (the fold condition degenerates transversally), whose image point
//! is a cusp of the image of `S`.
//!
//! This is the `Coordinates` formulation (any 2-dof linkage). A planar platform on three R-P-R
//! legs, one locked, takes the `Pose` one by default (`CuspFormulation::Auto`): the same
//! conditions over the two angles that place the platform (`pose`'s module doc), 4 chart pairs
//! of a two-dimensional search instead of 36 over every leg's coordinates.
//!
//! ## Nodes
//! A doubled system (`S`'s chart `k` for one point, chart `k'` for the other) whose two copies
//! *share* the actuated coordinates' variables, so the pairs have equal actuator values; it is
//! square (two curves, two equal actuator values). The diagonal (a point paired with itself) is
//! a curve of solutions, so there is no separation constraint in the system: boxes whose
//! configuration parts are disjoint are node pairs (certified when Krawczyk proves them unique;
//! undecided otherwise), and boxes that meet the diagonal are dropped by an injectivity
//! certificate, as the 3R nodes do: with the actuator values fixed, `S`'s chart system has one
//! more row than unknowns; if its interval Jacobian over the hull of both copies has full column
//! rank (a least-squares preconditioner `P` with `‖I − P·J‖ < 1`), the mean-value theorem gives
//! one point per actuator value in the hull: the two copies coincide. Near a cusp, where the map
//! is not injective on any neighbourhood, such boxes stay undecided. Charts `k ≤ k'` only (the
//! system is symmetric under swapping the copies); in chart pairs `(k, k)` a pair is kept in one
//! order.
//!
use super::pose::{PlatformTorus, PoseCusps, PoseReadout};
use super::{merge, Parts, SingularError, SingularKind, SingularProblem, CHART_REACH};
use crate::kernel::interval::{interval, point, Interval, IntervalBox};
use crate::model::Mechanism;
use crate::kernel::system::{Equation, EquationSystem, Monomial, Term, VarId, VarRole};
use std::collections::BTreeMap;

/// Adds product variables to a system, each once.
pub(super) struct Builder {
    pub(super) aug: EquationSystem,
    cache: BTreeMap<(VarId, VarId), VarId>,
}

impl Builder {
    pub(super) fn new(aug: EquationSystem) -> Self {
        Self { aug, cache: BTreeMap::new() }
    }

    /// The variable `x·y` (a square for `x = y`).
    pub(super) fn product(&mut self, x: VarId, y: VarId) -> VarId {
        let key = (x.min(y), x.max(y));
        if let Some(&p) = self.cache.get(&key) {
            return p;
        }
        let aug = &mut self.aug;
        let p = if x == y {
            let dom = aug.vars[x].domain.sqr();
            let p = aug.add_var(format!("{}^2", aug.vars[x].name), VarRole::Derived, dom);
            aug.add(Equation::new(vec![Term { coef: point(1.0), mono: Monomial::Linear(p) }, Term { coef: point(-1.0), mono: Monomial::Square(x) }], point(0.0)));
            p
        } else {
            let dom = aug.vars[x].domain * aug.vars[y].domain;
            let p = aug.add_var(format!("{}*{}", aug.vars[x].name, aug.vars[y].name), VarRole::Derived, dom);
            aug.add(Equation::bilinear(p, x, y));
            p
        };
        self.cache.insert(key, p);
        p
    }

    /// `coef · factor · m` as a linear term.
    pub(super) fn term(&mut self, coef: Interval, factor: Option<VarId>, m: VarId) -> Term {
        let v = match factor {
            Some(f) => self.product(f, m),
            None => m,
        };
        Term { coef, mono: Monomial::Linear(v) }
    }

    pub(super) fn row(&mut self, terms: Vec<Term>) {
        if !terms.is_empty() {
            self.aug.add(Equation::new(merge(terms), point(0.0)));
        }
    }
}

/// Fixes `var` to `value` in `s` (domain and equation).
pub(super) fn pin(s: &mut EquationSystem, var: VarId, value: f64) {
    s.vars[var].domain = point(value);
    s.add(Equation::new(vec![Term { coef: point(1.0), mono: Monomial::Linear(var) }], point(-value)));
}

/// What the image analyses need that a `SingularProblem` does not say.
#[derive(Debug, thiserror::Error, PartialEq)]
#[non_exhaustive]
pub enum ImageError {
    /// Building failed.
    #[error(transparent)]
    Singular(#[from] SingularError),
    /// Not an input set of a 2-dof mechanism.
    #[error("cusps, nodes and assembly-mode regions need the input (type-II) set of a mechanism with 2 degrees of freedom and 2 actuators (this one: {0} dof)")]
    NotTwoDof(isize),
    /// The pose formulation was asked for a mechanism it does not fit.
    #[error("the pose formulation of the cusp system takes a planar platform on three R-P-R legs (unrotated frames, revolute axes +z, slider axes +x, continuous revolute joints, slider limits above 0) with one slider fixed and the two others actuated")]
    NotPosePlatform,
    /// An actuated joint is not a coordinate of its own.
    #[error("actuated joint '{0}' is not a coordinate of its own (a revolute joint to the ground or a slider): nodes and regions compare actuator values through shared variables")]
    NotCoordinate(String),
}

/// A `Rate` list as terms in `m`.
fn rates_terms(b: &mut Builder, rates: &[super::Rate], m: &[VarId]) -> Vec<Term> {
    rates.iter().map(|r| b.term(r.coef, r.factor, m[r.coord])).collect()
}

/// How the cusp system is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CuspFormulation {
    /// `Torus` when the mechanism fits it, else `Coordinates`.
    Auto,
    /// A planar platform on three R-P-R legs, one locked: its actuator map on the torus of the
    /// locked leg's angle and the platform's (`pose::LockedLegMap`), searched by the 3R arms'
    /// cusp search (`arm3r::cusps`): two angles, no null vector or tangent as unknowns.
    Torus,
    /// The platform's pose as unknowns (`pose`'s module doc): a planar platform on three R-P-R
    /// legs, one locked.
    Pose,
    /// The linkage's joint coordinates (one `(c, s)` per rigid group, one travel per slider)
    /// with the null vector and tangent over all of them (this module's doc): any 2-dof linkage.
    Coordinates,
}

impl CuspFormulation {
    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            CuspFormulation::Auto => "auto",
            CuspFormulation::Torus => "torus",
            CuspFormulation::Pose => "pose",
            CuspFormulation::Coordinates => "coordinates",
        }
    }
}

/// The cusp systems of one input-singular set.
#[derive(Clone, Debug)]
pub struct CuspProblem {
    /// One system per chart pair `(k, τ)`: `v_k = 1`; `τ = 0` is `μ = 1`, `τ = j + 1` is `w_j = 1`.
    pub charts: Vec<((usize, usize), EquationSystem)>,
    /// The null vector `v`.
    pub v: Vec<VarId>,
    /// `[μ, w_0, ..., w_{n−1}]`: the tangent's direction.
    pub tangent: Vec<VarId>,
    /// Number of the configuration variables (the linkage's, or the pose's).
    pub base_vars: usize,
    /// The formulation built (`Torus`, `Pose` or `Coordinates`).
    pub formulation: CuspFormulation,
    /// Joint values of a pose box; `None` in the joint coordinates.
    pose: Option<PoseReadout>,
    /// The actuator map the `Torus` formulation searches; its boxes are written in the pose
    /// systems' variables (`charts`).
    torus: Option<PlatformTorus>,
}

/// Checks the set is an input set of a 2-dof mechanism with 2 actuators.
pub(crate) fn check(sp: &SingularProblem) -> Result<(), ImageError> {
    if sp.kind != SingularKind::Input || sp.dof != 2 || sp.actuated.len() != 2 {
        return Err(ImageError::NotTwoDof(sp.dof));
    }
    Ok(())
}

impl CuspProblem {
    /// Builds the cusp systems of `sp`, an input set of the 2-dof linkage `m`, in the pose
    /// formulation when `m` fits it (far fewer unknowns and charts), else in the joint coordinates.
    pub fn new(m: &Mechanism, sp: &SingularProblem) -> Result<Self, ImageError> {
        Self::with_formulation(m, sp, CuspFormulation::Auto)
    }

    /// Builds the cusp systems of `sp` in `formulation` (`Torus` or `Pose` on a mechanism they do
    /// not fit is an error).
    pub fn with_formulation(m: &Mechanism, sp: &SingularProblem, formulation: CuspFormulation) -> Result<Self, ImageError> {
        check(sp)?;
        if formulation == CuspFormulation::Coordinates {
            return Self::coordinates(sp);
        }
        match PoseCusps::new(m, &sp.linkage.fixed_joints, &sp.actuated) {
            Some(p) => {
                let formulation = if formulation == CuspFormulation::Pose { CuspFormulation::Pose } else { CuspFormulation::Torus };
                let torus = if formulation == CuspFormulation::Torus { PlatformTorus::new(m, &sp.linkage.fixed_joints, &sp.actuated) } else { None };
                Ok(Self { base_vars: p.base_vars, v: p.v, tangent: p.tangent, charts: p.charts, formulation, pose: Some(p.readout), torus })
            }
            None if formulation == CuspFormulation::Auto => Self::coordinates(sp),
            None => Err(ImageError::NotPosePlatform),
        }
    }

    /// The actuator map searched on the torus (`CuspFormulation::Torus`).
    pub(crate) fn torus(&self) -> Option<&PlatformTorus> {
        self.torus.as_ref()
    }

    /// Free joint values over a box of one of the charts (radians or metres), outward rounded.
    pub fn joint_values(&self, sp: &SingularProblem, b: &IntervalBox) -> BTreeMap<String, (f64, f64)> {
        match &self.pose {
            Some(p) => p.joint_values(b),
            None => sp.joint_values(b),
        }
    }

    /// Values of the actuated joints over a box of one of the charts.
    pub fn actuator_values(&self, sp: &SingularProblem, b: &IntervalBox) -> Vec<(f64, f64)> {
        let all = self.joint_values(sp, b);
        sp.actuated.iter().map(|a| all.get(a).copied().unwrap_or((f64::NAN, f64::NAN))).collect()
    }

    /// Builds the cusp systems (see the module doc) of `sp` in the joint coordinates.
    pub fn coordinates(sp: &SingularProblem) -> Result<Self, ImageError> {
        check(sp)?;
        let linkage = &sp.linkage;
        let mut aug = linkage.system.clone();
        let parts = Parts::new(linkage, &mut aug)?;
        let n = parts.coords.len();
        let names: Vec<String> = parts.coords.iter().map(|c| parts.coord_name(&linkage.system, c)).collect();
        let mut b = Builder { aug, cache: BTreeMap::new() };
        let reach = interval(-CHART_REACH, CHART_REACH);
        let v: Vec<VarId> = names.iter().map(|nm| b.aug.add_var(format!("v_{nm}"), VarRole::Primary, reach)).collect();
        let w: Vec<VarId> = names.iter().map(|nm| b.aug.add_var(format!("w_{nm}"), VarRole::Primary, reach)).collect();
        let mu = b.aug.add_var("mu", VarRole::Primary, reach);
        let actuator_rates: Vec<Vec<super::Rate>> = sp.actuated.iter().map(|a| parts.joint_rates(linkage, a)).collect();
        let loop_rates = parts.loop_rates.clone();
        // F_q v = 0, A v = 0.
        for rates in loop_rates.iter().chain(&actuator_rates) {
            let t = rates_terms(&mut b, rates, &v);
            b.row(t);
        }
        // μ F_qq[v, v] + F_q w = 0, A w = 0.
        let loop_rows = parts.loop_rows.clone();
        for (r, rates) in loop_rows.iter().zip(&loop_rates) {
            let mut t = rates_terms(&mut b, rates, &w);
            for r2 in parts.second_derivative(&linkage.system, *r)? {
                let u = b.product(v[r2.a], v[r2.b]);
                let ru = b.product(mu, u);
                t.push(b.term(r2.coef, r2.factor, ru));
            }
            b.row(t);
        }
        for rates in &actuator_rates {
            let t = rates_terms(&mut b, rates, &w);
            b.row(t);
        }
        let mut tangent = vec![mu];
        tangent.extend(&w);
        let mut charts = Vec::new();
        for k in 0..n {
            for (tau, &pinned) in tangent.iter().enumerate() {
                if tau == k + 1 {
                    continue;
                }
                let mut s = b.aug.clone();
                pin(&mut s, v[k], 1.0);
                pin(&mut s, w[k], 0.0);
                pin(&mut s, pinned, 1.0);
                charts.push(((k, tau), s));
            }
        }
        Ok(Self { charts, v, tangent, base_vars: sp.base_vars, formulation: CuspFormulation::Coordinates, pose: None, torus: None })
    }
}

/// The doubled systems of the node search.
#[derive(Clone, Debug)]
pub struct NodeProblem {
    /// `((k, k'), system, map)`: copy A is chart `k`'s variables as they are; `map[i]` is the
    /// id of chart `k'`'s variable `i` in copy B.
    pub charts: Vec<((usize, usize), EquationSystem, Vec<VarId>)>,
    /// Variables shared by the copies (the actuated coordinates).
    pub shared: Vec<VarId>,
    /// A planar platform with a locked leg: its actuator map, on which the node search runs
    /// instead of the doubled systems.
    torus: Option<PlatformTorus>,
}

impl NodeProblem {
    /// The node search of `sp`, an input set of the 2-dof linkage `m`: on the torus of the
    /// platform's two angles when `m` is a planar platform on three R-P-R legs with one locked
    /// (as the cusps' `Torus` formulation), else on the doubled systems.
    pub fn new(m: &Mechanism, sp: &SingularProblem) -> Result<Self, ImageError> {
        let mut p = Self::in_coordinates(sp)?;
        p.torus = PlatformTorus::new(m, &sp.linkage.fixed_joints, &sp.actuated);
        Ok(p)
    }

    /// The platform's torus, when the node search runs on it.
    pub(crate) fn torus(&self) -> Option<&PlatformTorus> {
        self.torus.as_ref()
    }

    /// Builds the doubled systems of `sp` (see the module doc), for the node search in the joint
    /// coordinates whatever the mechanism.
    pub fn in_coordinates(sp: &SingularProblem) -> Result<Self, ImageError> {
        check(sp)?;
        let mut scratch = sp.linkage.system.clone();
        let parts = Parts::new(&sp.linkage, &mut scratch)?;
        let mut shared = Vec::new();
        for a in &sp.actuated {
            let (_, vars) = parts.own_coordinate(&sp.linkage, a).ok_or_else(|| ImageError::NotCoordinate(a.clone()))?;
            shared.extend(vars);
        }
        let mut charts = Vec::new();
        for k in 0..sp.chart_count() {
            for k2 in k..sp.chart_count() {
                let mut s = sp.chart(k);
                let other = &sp.chart(k2);
                let map: Vec<VarId> = other
                    .vars
                    .iter()
                    .enumerate()
                    .map(|(i, var)| if shared.contains(&i) { i } else { s.add_var(format!("{}'", var.name), var.role, var.domain) })
                    .collect();
                for e in &other.equations {
                    if e.vars().all(|v| shared.contains(&v)) {
                        continue;
                    }
                    let terms = e
                        .terms
                        .iter()
                        .map(|t| Term {
                            coef: t.coef,
                            mono: match t.mono {
                                Monomial::Linear(x) => Monomial::Linear(map[x]),
                                Monomial::Square(x) => Monomial::Square(map[x]),
                                Monomial::Product(x, y) => Monomial::Product(map[x], map[y]),
                            },
                        })
                        .collect();
                    s.add(Equation::new(terms, e.constant));
                }
                charts.push(((k, k2), s, map));
            }
        }
        Ok(Self { charts, shared, torus: None })
    }
}

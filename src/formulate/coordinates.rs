//! Distance problems in placed coordinates: the "points" formulation.
//!
//! The determinants of Porta et al. (2003) (`cayley_menger`) work on squared distances only; here
//! every point without given coordinates gets three coordinate variables instead, in the frame the
//! fixed points define, and every constraint becomes a polynomial equation of degree two:
//! - a known squared distance: `‖p_a − p_b‖² − r = 0`;
//! - a point–line distance `d` of `p` from the line `a b`: with `w = p − a`, `v = b − a`,
//!   `‖w‖²‖v‖² − (w·v)² = d²‖v‖²` (Lagrange's identity) is of degree four, so `S = ‖w‖²`,
//!   `W = w·v` (and `Q = ‖v‖²` when `r_ab` is unknown) become derived variables with their own
//!   degree-two equations, and the constraint reads `S·Q − W² − d²·Q = 0`;
//! - an orientation `(toward − a)·(b − a) ≥ 0`: a derived variable with domain `[0, …]`.
//!
//! This is the point-and-direction formulation ibexsolve uses for lines tangent to spheres
//! (here the line's points `t`, `u` of the problem file), written for any distance problem.
//!
//! Why it exists: the system is square whenever the problem is well constrained (each derived
//! variable brings its own equation), so the kernel's Krawczyk operator (`contract::Newton`)
//! both contracts and certifies: a box it proves holds exactly one placement. The determinant
//! systems are not square (the four spheres: 6 unknowns, 9 equations) or singular where two
//! assembly modes share their distances (octahedral b), so their answers are certified here too
//! (`Placed::certify_near`), from the placements `cayley_menger::embed` finds.
//! It needs at least three fixed points that are not collinear: they fix the frame (with exactly
//! three, the mirror image through their plane of every placement is another placement).
//! Builds only; solving is the kernel's job.

use super::cayley_menger::{bound_smoothing, DistanceError, DistanceProblem};
use crate::kernel::contract::{Contractor, LpShrink, Newton, Propagation, Sequence};
use crate::kernel::search::{SolveError, Solver, SolverSettings};
use crate::kernel::interval::{interval, point, Interval, IntervalBox};
use crate::kernel::system::multilinear::Poly;
use crate::kernel::system::{Equation, EquationSystem, Monomial, Term, VarId, VarRole};

/// A distance problem as a system over point coordinates.
#[derive(Clone, Debug)]
pub struct Placed {
    /// The problem it came from.
    pub problem: DistanceProblem,
    /// Coordinates (primary) and the derived variables, with their equations.
    pub system: EquationSystem,
    /// Per point: its three coordinate variables, or `None` for a fixed point or a point of the
    /// line formulation (whose coordinates are `coord_polys`).
    pub coords: Vec<Option<[VarId; 3]>>,
    /// Per point: its coordinates as polynomials in the variables (a constant for a fixed point,
    /// a variable for a free one, `c + x` and `c + x + L·d` in the line formulation).
    coord_polys: Vec<[Poly; 3]>,
    /// The line formulation's frame, when built by `build_line`.
    line: Option<LineFrame>,
    /// `system` plus redundant equations for propagation only (`solver`), when there are any.
    pub pruning: Option<EquationSystem>,
    /// One label per equation.
    pub labels: Vec<String>,
    /// Derived variables and what they stand for, in order of definition.
    derived: Vec<(VarId, Poly)>,
    /// Squared distances held as derived variables (`build_with`): pair and variable.
    pub distance_vars: Vec<((usize, usize), VarId)>,
}

/// Why the points formulation does not apply (the determinant formulation still may).
#[derive(Debug, thiserror::Error, PartialEq)]
#[non_exhaustive]
pub enum PlacedError {
    /// The problem itself is bad (same checks as the determinant builder).
    #[error(transparent)]
    Problem(#[from] DistanceError),
    /// Fewer than three fixed points, or they are collinear: no frame.
    #[error("the points formulation needs three fixed points that are not collinear")]
    NoFrame,
    /// An equation of degree above two (cannot happen for the constraints above).
    #[error("internal: an equation of degree {0} in coordinates")]
    Degree(usize),
    /// The problem is not a line to place (`Placed::build_line`).
    #[error("the line formulation does not apply: {0}")]
    NotALine(String),
}

/// The line formulation's frame: `t = c + x`, `u = t + L·d` with `|d| = 1`.
#[derive(Clone, Debug)]
struct LineFrame {
    t: usize,
    u: usize,
    anchor: usize,
    length: Interval,
    x: [VarId; 3],
    d: [VarId; 3],
}

/// Coordinates of point `i` as polynomials: its constants when fixed, its variables when free.
fn coordinate_polys(p: &DistanceProblem, i: usize, ids: Option<[VarId; 3]>) -> [Poly; 3] {
    [0, 1, 2].map(|k| match (ids, p.points[i].xyz) {
        (Some(ids), _) => Poly::var(ids[k]),
        (None, Some(xyz)) => Poly::constant(point(xyz[k])),
        (None, None) => Poly::zero(),
    })
}

impl Placed {
    /// Builds the coordinate system of `problem`.
    pub fn build(problem: &DistanceProblem) -> Result<Self, PlacedError> {
        Self::build_with(problem, &[])
    }

    /// `build`, plus a derived variable `R = ‖p_a − p_b‖²` (with its equation: still square)
    /// for each pair of `pairs`: a box of the determinant formulation then bounds placements
    /// directly (`start_from`), which is how its clusters are searched again in coordinates.
    pub fn build_with(problem: &DistanceProblem, pairs: &[(usize, usize)]) -> Result<Self, PlacedError> {
        let p = problem;
        let n = p.points.len();
        let fixed: Vec<usize> = (0..n).filter(|&i| p.points[i].xyz.is_some()).collect();
        let frame = fixed.len() >= 3 && super::cayley_menger::combinations(fixed.len(), 3).into_iter().any(|t| {
            let c = |k: usize| nalgebra::Vector3::from(p.points[fixed[t[k]]].xyz.expect("fixed"));
            let (a, b, d) = (c(0), c(1), c(2));
            let s = (b - a).norm().max((d - a).norm()).max(1e-300);
            (b - a).cross(&(d - a)).norm() > 1e-9 * s * s
        });
        if !frame {
            return Err(PlacedError::NoFrame);
        }
        let smooth = bound_smoothing(p)?;
        let mut system = EquationSystem::default();
        let mut coords = vec![None; n];
        for q in 0..n {
            if p.points[q].xyz.is_some() {
                continue;
            }
            // Bound smoothing bounds q's distance to every fixed point: a cube around each.
            let mut dom = [interval(f64::NEG_INFINITY, f64::INFINITY); 3];
            for &c in &fixed {
                let reach = smooth[q][c].sqrt().sup();
                let xyz = p.points[c].xyz.expect("fixed");
                for k in 0..3 {
                    dom[k] = dom[k].intersection(interval((point(xyz[k]) - point(reach)).inf(), (point(xyz[k]) + point(reach)).sup()));
                }
            }
            let name = &p.points[q].name;
            let ids = [0, 1, 2].map(|k| system.add_var(format!("{name}.{}", ["x", "y", "z"][k]), VarRole::Primary, dom[k]));
            coords[q] = Some(ids);
        }
        let coord_polys = (0..n).map(|i| coordinate_polys(p, i, coords[i])).collect();
        let mut placed = Self { problem: p.clone(), system, coords, coord_polys, line: None, pruning: None, labels: Vec::new(), derived: Vec::new(), distance_vars: Vec::new() };
        let start = placed.system.initial_box();
        let mut equations: Vec<(Poly, String)> = Vec::new();
        // Known distances with a free end.
        for a in 0..n {
            for b in a + 1..n {
                if placed.coords[a].is_none() && placed.coords[b].is_none() {
                    continue;
                }
                if let Some(r) = p.known(a, b) {
                    equations.push((placed.sq(a, b).add(&Poly::constant(-r)), format!("|{} {}|² = {}", p.points[a].name, p.points[b].name, r.mid())));
                }
            }
        }
        // A derived variable `v = poly`: its domain is the natural enclosure of `poly` over the
        // start box cut by what bound smoothing knows (an empty cut would mean no placement, which
        // the solver proves on its own; keep the enclosure then).
        let derived = |placed: &mut Placed, equations: &mut Vec<(Poly, String)>, name: String, poly: Poly, bound: Interval| -> Poly {
            let dom = poly.eval(&start.dims).intersection(bound);
            let dom = if dom.is_empty() { poly.eval(&start.dims) } else { dom };
            let v = placed.system.add_var(name.clone(), VarRole::Derived, dom);
            equations.push((Poly::var(v).add(&poly.scale(point(-1.0))), format!("{name} defined")));
            placed.derived.push((v, poly));
            Poly::var(v)
        };
        for pl in &p.point_lines {
            let (q, a, b) = (pl.point, pl.line.0, pl.line.1);
            let nm = |i: usize| p.points[i].name.clone();
            let label = format!("dist({}, line {} {})² = {}", nm(q), nm(a), nm(b), pl.squared.mid());
            let (s_poly, w_poly) = (placed.sq(q, a), placed.dot(q, a, b, a));
            let s = if placed.coords[q].is_none() && placed.coords[a].is_none() { s_poly } else { derived(&mut placed, &mut equations, format!("S({},{})", nm(q), nm(a)), s_poly, smooth[q][a]) };
            let q_len = match p.known(a, b) {
                Some(r) => Poly::constant(r),
                None => {
                    let q_poly = placed.sq(a, b);
                    derived(&mut placed, &mut equations, format!("Q({},{})", nm(a), nm(b)), q_poly, smooth[a][b])
                }
            };
            let reach = (smooth[q][a] * smooth[a][b]).sqrt().sup();
            let w = derived(&mut placed, &mut equations, format!("W({};{},{})", nm(q), nm(a), nm(b)), w_poly, interval(-reach, reach));
            let e = s.mul(&q_len).add(&w.mul(&w).scale(point(-1.0))).add(&q_len.scale(-pl.squared));
            equations.push((e, label));
        }
        for o in &p.orientations {
            let nm = |i: usize| p.points[i].name.clone();
            let poly = placed.dot(o.toward, o.a, o.b, o.a);
            let hi = poly.eval(&start.dims).sup().max(0.0);
            derived(&mut placed, &mut equations, format!("orient({} {} toward {})", nm(o.a), nm(o.b), nm(o.toward)), poly, interval(0.0, hi));
        }
        for &(a, b) in pairs {
            let poly = placed.sq(a, b);
            let r = derived(&mut placed, &mut equations, format!("r({},{})", p.points[a].name, p.points[b].name), poly, smooth[a][b]);
            let v = r.vars()[0];
            placed.distance_vars.push(((a, b), v));
        }
        for (poly, label) in equations {
            placed.system.add(to_equation(&poly)?);
            placed.labels.push(label);
        }
        Ok(placed)
    }

    /// The line formulation: for a problem whose free points are two points
    /// `t`, `u` of one line, every constraint a distance from a fixed point to `t`, to `u`, or to
    /// the line `t u` (lines tangent to spheres), the line is placed by a point and a direction,
    /// as in ibexsolve's formulation: `t = c + x` for a fixed anchor `c` with `|c t|²` known,
    /// `u = t + L·d` with `L = |t u|`, and
    /// - `|x|² = |c t|²`, `|d|² = 1`, and `x·d = κ = (|c u|² − |c t|² − L²) / 2L` when `|c u|²` is
    ///   known (the right angle at a tangent point makes `κ = 0`);
    /// - the distance `D` of a fixed point `p` from the line: with `e = c − p` and the derived
    ///   `y = d·(t − p) = κ + d·e` (linear), `|t − p|² − y² = D` reads
    ///   `|c t|² + 2 x·e + |e|² − y² − D = 0`: linear in `x`, one square;
    /// - another known `|p t|²` is linear in `x`: `2 x·e + |c t|² + |e|² − |p t|² = 0`, and `|p u|²`
    ///   linear in `x` and `d` (with `x·d` kept as a product when `|c u|²` is unknown);
    /// - an orientation `(p − t)·(u − t) ≥ 0` is the derived `d·(t − p) ≤ 0` (with `t`, `u`
    ///   swapped: `d·(t − p) ≥ −L`).
    ///
    /// So every equation is of degree two with few terms, the primaries are the six numbers of
    /// `x` and `d`, and the system is square exactly when the line is rigid (four constraints
    /// besides `|c t|²` and `L`). All constants are intervals enclosing the exact values.
    pub fn build_line(problem: &DistanceProblem) -> Result<Self, PlacedError> {
        let p = problem;
        let n = p.points.len();
        let not = |why: &str| PlacedError::NotALine(why.to_string());
        let free: Vec<usize> = (0..n).filter(|&i| p.points[i].xyz.is_none()).collect();
        if free.len() != 2 {
            return Err(not("it needs exactly two points without coordinates"));
        }
        let fixed: Vec<usize> = (0..n).filter(|&i| p.points[i].xyz.is_some()).collect();
        for &a in &free {
            for b in 0..n {
                if b != a && p.range(a, b).is_some() {
                    return Err(not("a range is given for a distance to a point of the line"));
                }
            }
        }
        let l2 = p.known(free[0], free[1]).ok_or_else(|| not("the distance between the line's two points is not known"))?;
        // The anchor: a fixed point at a known distance from t, preferably from u too.
        let pick = |t: usize, u: usize, both: bool| fixed.iter().copied().find(|&c| p.known(c, t).is_some() && (!both || p.known(c, u).is_some())).map(|c| (t, u, c));
        let (t, u, anchor) = pick(free[0], free[1], true)
            .or_else(|| pick(free[1], free[0], true))
            .or_else(|| pick(free[0], free[1], false))
            .or_else(|| pick(free[1], free[0], false))
            .ok_or_else(|| not("no fixed point is at a known distance from a point of the line"))?;
        for pl in &p.point_lines {
            let on_line = (pl.line == (t, u) || pl.line == (u, t)) && p.points[pl.point].xyz.is_some();
            if !on_line {
                return Err(not("a point–line constraint is not about a fixed point and the line"));
            }
        }
        for o in &p.orientations {
            let on_line = ((o.a, o.b) == (t, u) || (o.a, o.b) == (u, t)) && p.points[o.toward].xyz.is_some();
            if !on_line {
                return Err(not("an orientation is not about the line and a fixed point"));
            }
        }
        let a2 = p.known(anchor, t).expect("picked");
        let b2 = p.known(anchor, u);
        let extra: Vec<(usize, usize, Interval)> = fixed.iter().filter(|&&c| c != anchor).flat_map(|&c| [(c, t), (c, u)]).filter_map(|(c, f)| p.known(c, f).map(|r| (c, f, r))).collect();
        let constraints = usize::from(b2.is_some()) + extra.len() + p.point_lines.len();
        if constraints != 4 {
            return Err(not(&format!("{constraints} constraints on the line besides the anchor, not the 4 that make it rigid")));
        }
        let len = l2.sqrt();
        let c = p.points[anchor].xyz.expect("fixed");
        let reach = a2.sqrt().sup();
        let mut system = EquationSystem::default();
        let xs = [0, 1, 2].map(|k| system.add_var(format!("x{}", ["x", "y", "z"][k]), VarRole::Primary, interval(-reach, reach)));
        let ds = [0, 1, 2].map(|k| system.add_var(format!("d{}", ["x", "y", "z"][k]), VarRole::Primary, interval(-1.0, 1.0)));
        let vx = |k: usize| Poly::var(xs[k]);
        let vd = |k: usize| Poly::var(ds[k]);
        let mut coord_polys: Vec<[Poly; 3]> = (0..n).map(|i| coordinate_polys(p, i, None)).collect();
        coord_polys[t] = [0, 1, 2].map(|k| vx(k).add(&Poly::constant(point(c[k]))));
        coord_polys[u] = [0, 1, 2].map(|k| vx(k).add(&vd(k).scale(len)).add(&Poly::constant(point(c[k]))));
        let frame = LineFrame { t, u, anchor, length: len, x: xs, d: ds };
        let mut placed = Self { problem: p.clone(), system, coords: vec![None; n], coord_polys, line: Some(frame), pruning: None, labels: Vec::new(), derived: Vec::new(), distance_vars: Vec::new() };
        let start = placed.system.initial_box();
        let nm = |i: usize| p.points[i].name.clone();
        let dot = |a: &dyn Fn(usize) -> Poly, v: [Interval; 3]| (0..3).fold(Poly::zero(), |acc, k| acc.add(&a(k).scale(v[k])));
        let sq = |a: &dyn Fn(usize) -> Poly| (0..3).fold(Poly::zero(), |acc, k| acc.add(&a(k).mul(&a(k))));
        let xd = (0..3).fold(Poly::zero(), |acc, k| acc.add(&vx(k).mul(&vd(k))));
        // e = c − q for a fixed point q, and |e|².
        let e_of = |q: usize| {
            let xyz = p.points[q].xyz.expect("fixed");
            let e = [0, 1, 2].map(|k| point(c[k]) - point(xyz[k]));
            let e2 = e.iter().fold(point(0.0), |acc, v| acc + v.sqr());
            (e, e2)
        };
        let mut equations: Vec<(Poly, String)> = Vec::new();
        equations.push((sq(&vx).add(&Poly::constant(-a2)), format!("|{} {}|² = {}", nm(anchor), nm(t), a2.mid())));
        equations.push((sq(&vd).add(&Poly::constant(point(-1.0))), "|d|² = 1".to_string()));
        // x·d as a constant κ when |c u|² is known (its own equation), else the product.
        let along = match b2 {
            Some(b2) => {
                let kappa = (b2 - a2 - l2) / (point(2.0) * len);
                equations.push((xd.add(&Poly::constant(-kappa)), format!("|{} {}|² = {}", nm(anchor), nm(u), b2.mid())));
                Poly::constant(kappa)
            }
            None => xd.clone(),
        };
        for &(q, f, r) in &extra {
            let (e, e2) = e_of(q);
            let mut poly = dot(&vx, e).scale(point(2.0)).add(&Poly::constant(a2 + e2 - r));
            if f == u {
                // |x + e + L d|² = |x + e|² + 2L d·(x + e) + L².
                poly = poly.add(&along.add(&dot(&vd, e)).scale(point(2.0) * len)).add(&Poly::constant(l2));
            }
            equations.push((poly, format!("|{} {}|² = {}", nm(q), nm(f), r.mid())));
        }
        let derived = |placed: &mut Placed, equations: &mut Vec<(Poly, String)>, name: String, poly: Poly, bound: Interval| -> Result<Poly, PlacedError> {
            let dom = poly.eval(&start.dims).intersection(bound);
            if dom.is_empty() {
                return Err(PlacedError::NotALine(format!("{name} has no room")));
            }
            let v = placed.system.add_var(name.clone(), VarRole::Derived, dom);
            equations.push((Poly::var(v).add(&poly.scale(point(-1.0))), format!("{name} defined")));
            placed.derived.push((v, poly));
            Ok(Poly::var(v))
        };
        let everything = interval(f64::NEG_INFINITY, f64::INFINITY);
        // Equations linear in x (all but the first three so far), and the definitions of the
        // derived `d·(t − p)`, linear in d: preconditioned below.
        let first_extra = if b2.is_some() { 3 } else { 2 };
        let mut in_x: Vec<Poly> = equations[first_extra..].iter().map(|(e, _)| e.clone()).collect();
        let mut in_d: Vec<Poly> = Vec::new();
        // An orientation toward p bounds d·(t − p): the derived y(p) of a point–line distance
        // when there is one, its own derived variable otherwise.
        let side = |o: &super::cayley_menger::Orientation| if o.a == t { interval(f64::NEG_INFINITY, 0.0) } else { interval(-len.sup(), f64::INFINITY) };
        for pl in &p.point_lines {
            let q = pl.point;
            let (e, e2) = e_of(q);
            let bound = p.orientations.iter().filter(|o| o.toward == q).fold(everything, |b, o| b.intersection(side(o)));
            let y = derived(&mut placed, &mut equations, format!("y({})", nm(q)), along.add(&dot(&vd, e)), bound)?;
            in_d.push(equations.last().expect("just pushed").0.clone());
            let poly = dot(&vx, e).scale(point(2.0)).add(&y.mul(&y).scale(point(-1.0))).add(&Poly::constant(a2 + e2 - pl.squared));
            in_x.push(poly.clone());
            equations.push((poly, format!("dist({}, line {} {})² = {}", nm(q), nm(pl.line.0), nm(pl.line.1), pl.squared.mid())));
        }
        for o in p.orientations.iter().filter(|o| !p.point_lines.iter().any(|pl| pl.point == o.toward)) {
            let (e, _) = e_of(o.toward);
            derived(&mut placed, &mut equations, format!("orient({} {} toward {})", nm(o.a), nm(o.b), nm(o.toward)), along.add(&dot(&vd, e)), side(o))?;
            in_d.push(equations.last().expect("just pushed").0.clone());
        }
        for (poly, label) in equations {
            placed.system.add(to_equation(&poly)?);
            placed.labels.push(label);
        }
        // Redundant equations for propagation: each equation group solved for its variables
        // (x from the distances, d from the derived dot products) by a floating-point
        // pseudo-inverse. Any real combination of equations that vanish vanishes, so these
        // hold wherever the system does; they only let propagation see x and d one at a time.
        let mut pruning = placed.system.clone();
        for (group, vars) in [(&in_x, xs), (&in_d, ds)] {
            let solved = precondition(group, &vars);
            if vars == xs && !solved.is_empty() {
                // x is then a function of d (through the y² terms): the search branches on d
                // alone, a two-dimensional sphere instead of six dimensions (measured: half the
                // boxes on the four spheres).
                for &v in &xs {
                    placed.system.vars[v].role = VarRole::Derived;
                    pruning.vars[v].role = VarRole::Derived;
                }
            }
            for poly in solved {
                pruning.add(to_equation(&poly)?);
            }
        }
        placed.pruning = Some(pruning);
        Ok(placed)
    }

    /// Coordinate `k` of point `i`: a polynomial in the variables.
    fn coord(&self, i: usize, k: usize) -> Poly {
        self.coord_polys[i][k].clone()
    }

    fn diff(&self, a: usize, b: usize, k: usize) -> Poly {
        self.coord(a, k).add(&self.coord(b, k).scale(point(-1.0)))
    }

    /// `‖p_a − p_b‖²`
    fn sq(&self, a: usize, b: usize) -> Poly {
        self.dot(a, b, a, b)
    }

    /// `(p_a − p_b)·(p_c − p_d)`
    fn dot(&self, a: usize, b: usize, c: usize, d: usize) -> Poly {
        (0..3).fold(Poly::zero(), |acc, k| acc.add(&self.diff(a, b, k).mul(&self.diff(c, d, k))))
    }

    /// The start box with each distance variable cut to `bounds` (per `distance_vars` entry);
    /// `None` when a cut is empty (no placement has these distances).
    pub fn start_from(&self, bounds: &[Interval]) -> Option<IntervalBox> {
        let mut b = self.system.initial_box();
        for (&(_, v), &r) in self.distance_vars.iter().zip(bounds) {
            let cut = b.dims[v].intersection(r);
            if cut.is_empty() {
                return None;
            }
            b.dims[v] = cut;
        }
        Some(b)
    }

    /// The kernel's solver for `system`: propagation over `pruning` (when there is one), then
    /// interval Newton and the LP shrink on `system`, as `search::default_contractor`.
    pub fn solver(&self, settings: SolverSettings) -> Result<Solver<'_>, SolveError> {
        let solver = Solver::new(&self.system, settings)?;
        let Some(pruning) = &self.pruning else { return Ok(solver) };
        let line = self.line.is_some();
        Ok(solver.with_contractor(Box::new(move |system, s| {
            // Another sweep only when the last one narrowed some component by a fifth: the
            // bisection is cheaper than slow fixpoints (measured on the four spheres).
            let mut prop = Propagation::new(pruning);
            prop.min_gain = 0.2;
            let mut steps: Vec<Box<dyn Contractor + Send + '_>> = vec![Box::new(prop)];
            if let Some(newton) = Newton::new(system, s.newton_width) {
                steps.push(Box::new(newton));
            }
            // The LP shrink cuts nothing measurable here (the same boxes with and without it),
            // so the line formulation goes without.
            if s.use_lp && !line {
                let mut lp = LpShrink::new(system);
                lp.backend = s.lp_backend;
                steps.push(Box::new(lp));
            }
            Box::new(Sequence(steps))
        })))
    }

    /// True when the system is square: Krawczyk applies, and certifies regular roots.
    pub fn is_square(&self) -> bool {
        self.system.equations.len() == self.system.vars.len()
    }

    /// Every point's coordinates at `x` (a point of the variable space).
    pub fn points(&self, x: &[f64]) -> Vec<[f64; 3]> {
        (0..self.problem.points.len())
            .map(|i| match (self.coords[i], self.problem.points[i].xyz) {
                (Some(ids), _) => ids.map(|v| x[v]),
                (None, Some(xyz)) => xyz,
                (None, None) => [0, 1, 2].map(|k| self.coord_polys[i][k].eval_point(x)),
            })
            .collect()
    }

    /// Enclosure of the squared distance between points `a` and `b` over the box `b`.
    pub fn distance_over(&self, a: usize, c: usize, b: &IntervalBox) -> Interval {
        self.sq(a, c).eval(&b.dims)
    }

    /// The variable-space point of a placement `pts` (derived variables evaluated there).
    pub fn state(&self, pts: &[[f64; 3]]) -> Vec<f64> {
        let mut x = vec![0.0; self.system.vars.len()];
        if let Some(f) = &self.line {
            // x = t − c, d = (u − t) / L.
            let (t, u) = (pts[f.t], pts[f.u]);
            let c = self.problem.points[f.anchor].xyz.expect("fixed");
            for k in 0..3 {
                x[f.x[k]] = t[k] - c[k];
                x[f.d[k]] = (u[k] - t[k]) / f.length.mid();
            }
        }
        for (i, c) in self.coords.iter().enumerate() {
            if let Some(ids) = c {
                for k in 0..3 {
                    x[ids[k]] = pts[i][k];
                }
            }
        }
        // Derived variables are polynomials in the coordinates, defined in order.
        for (v, poly) in &self.derived {
            x[*v] = poly.eval_point(&x);
        }
        x
    }

    /// Tries to prove that exactly one placement lies near `pts`: the certified box, or `None`.
    /// Needs a square system.
    ///
    /// Floating-point Newton first polishes the placement (the embedding of a box midpoint is
    /// only as close as the box is narrow); then Krawczyk with ε-inflation (`Newton::certify`)
    /// proves a tiny box around the polished point holds exactly one root. The polish needs no
    /// accuracy: only the Krawczyk test is a proof.
    pub fn certify_near(&self, pts: &[[f64; 3]]) -> Option<IntervalBox> {
        let mut newton = Newton::new(&self.system, f64::INFINITY)?;
        let mut x = self.state(pts);
        let n = x.len();
        for _ in 0..30 {
            let f: Vec<f64> = self.system.equations.iter().map(|e| e.residual(&x)).collect();
            let mut j = nalgebra::DMatrix::zeros(n, n);
            for (r, e) in self.system.equations.iter().enumerate() {
                for t in &e.terms {
                    let c = t.coef.mid();
                    match t.mono {
                        Monomial::Linear(v) => j[(r, v)] += c,
                        Monomial::Square(v) => j[(r, v)] += 2.0 * c * x[v],
                        Monomial::Product(a, b) => {
                            j[(r, a)] += c * x[b];
                            j[(r, b)] += c * x[a];
                        }
                    }
                }
            }
            let step = j.lu().solve(&nalgebra::DVector::from_vec(f))?;
            for k in 0..n {
                x[k] -= step[k];
            }
            if step.amax() <= 1e-14 * (1.0 + x.iter().fold(0.0f64, |m, v| m.max(v.abs()))) {
                break;
            }
        }
        if !x.iter().all(|v| v.is_finite()) {
            return None;
        }
        let r = |v: f64| 1e-9 * (1.0 + v.abs());
        let b = IntervalBox::new(x.iter().map(|&v| interval(v - r(v), v + r(v))).collect());
        newton.certify(&b)
    }
}

/// Combinations `Σ_i M_ji p_i` of `polys`, one per variable of `vars`, with `M` a floating-point
/// pseudo-inverse of the matrix of their coefficients in `vars` (midpoints of the linear terms):
/// each combination has coefficient about 1 on its variable and about 0 on the others. Empty when
/// that matrix has not full column rank. Sound for any `M`: a real combination of vanishing
/// polynomials vanishes (coefficients are combined in interval arithmetic).
fn precondition(polys: &[Poly], vars: &[VarId]) -> Vec<Poly> {
    let (rows, cols) = (polys.len(), vars.len());
    if rows < cols {
        return Vec::new();
    }
    let a = nalgebra::DMatrix::from_fn(rows, cols, |r, c| polys[r].terms().find(|(m, _)| m.as_slice() == [(vars[c], 1)]).map_or(0.0, |(_, k)| k.mid()));
    let ata = a.transpose() * &a;
    let Some(inv) = ata.try_inverse() else { return Vec::new() };
    let m = inv * a.transpose();
    if !m.iter().all(|v| v.is_finite()) || m.amax() > 1e8 {
        return Vec::new();
    }
    (0..cols).map(|j| (0..rows).fold(Poly::zero(), |acc, i| acc.add(&polys[i].scale(point(m[(j, i)]))))).collect()
}

/// A `Poly` of degree at most two as an `Equation` (`poly = 0`).
fn to_equation(p: &Poly) -> Result<Equation, PlacedError> {
    let mut constant = point(0.0);
    let mut terms = Vec::with_capacity(p.len());
    for (m, c) in p.terms() {
        let mono = match m.as_slice() {
            [] => {
                constant += c;
                continue;
            }
            [(v, 1)] => Monomial::Linear(*v),
            [(v, 2)] => Monomial::Square(*v),
            [(a, 1), (b, 1)] => Monomial::Product(*a, *b),
            other => return Err(PlacedError::Degree(other.iter().map(|&(_, e)| e as usize).sum())),
        };
        terms.push(Term { coef: c, mono });
    }
    Ok(Equation::new(terms, constant))
}


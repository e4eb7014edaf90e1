//! Distance problems as Cayley–Menger systems (seed 004: Porta, Thomas, Ros, Torras 2003).
//!
//! A `DistanceProblem` names points, the squared distances `r_ij = ‖p_i − p_j‖²` that are known,
//! ranges for some unknown ones, and point–line distances. `CayleyMenger::build` turns it into
//! polynomial equations over the unknown squared distances:
//! - every chosen set of five points spans no volume in R³: `Ξ(p_a, …, p_e) = 0` (Eq. 4), and of
//!   six points on request (`--redundant`);
//! - a point at distance `d` from the line through two others: `Ξ(p, a, b) + 4 r_ab d² = 0` (Eq. 5).
//!
//! Determinants are expanded symbolically once, here, into `Poly`s whose coefficients enclose the
//! exact ones: no determinant is ever evaluated in floating point on a box.
//! Two formulations: `Split` is the seed's (each unknown `r_ij` and its twin `r_ji` are separate
//! variables tied by `r_ij − r_ji = 0`, which makes every determinant multilinear), `Shared`
//! keeps one variable per distance (degree two per variable; clipped through Bernstein control
//! points). After a solve, `embed` places the points by trilateration from a solution's distances,
//! both mirror images included.
//! Builds only; solving is `solve`'s job.

use crate::kernel::contract::{ClipError, FaceBounds, TrapezoidClip};
use crate::kernel::search::{SolveError, Solver, SolverSettings};
use crate::kernel::interval::{interval, point, Interval, IntervalBox};
use crate::kernel::system::multilinear::Poly;
use crate::kernel::system::{EquationSystem, VarId, VarRole};
use nalgebra::Vector3;
use std::collections::BTreeMap;
use thiserror::Error;

/// Why a solver for a distance problem could not be made.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum DistanceSolverError {
    /// An equation the clipper cannot take.
    #[error(transparent)]
    Clip(#[from] ClipError),
    /// Bad settings or system.
    #[error(transparent)]
    Solve(#[from] SolveError),
}

/// What makes a distance problem unusable. Messages name the points at fault.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum DistanceError {
    /// Two points share a name, or a name is unknown.
    #[error("{0}")]
    Naming(String),
    /// A squared distance is not a positive finite number, or a range is inverted.
    #[error("{what}: {problem}")]
    BadValue {
        /// which value
        what: String,
        /// what is wrong with it
        problem: String,
    },
    /// Three known distances cannot form a triangle.
    #[error("the squared distances between {a}, {b} and {c} violate the triangle inequality ({ab}, {bc}, {ca}): no triangle has these sides")]
    Triangle {
        /// first point
        a: String,
        /// second point
        b: String,
        /// third point
        c: String,
        /// r_ab
        ab: f64,
        /// r_bc
        bc: f64,
        /// r_ca
        ca: f64,
    },
    /// Six known distances cannot form a tetrahedron (its Cayley–Menger determinant is negative).
    #[error("the squared distances between {0} cannot be realised in space (negative Cayley–Menger determinant)")]
    Tetrahedron(String),
    /// No value of an unknown distance is compatible with the triangle inequality.
    #[error("no squared distance between {a} and {b} is compatible with the triangle inequality and the known distances")]
    NoRoom {
        /// first point
        a: String,
        /// second point
        b: String,
    },
    /// The points with given coordinates (the base) are collinear: no frame to place the rest.
    #[error("degenerate base: {0} are collinear, so they fix no frame in space")]
    DegenerateBase(String),
    /// Fewer constraints than the shape has degrees of freedom, or fewer equations than unknowns.
    #[error("underdetermined: {unknowns} unknown squared distances but {detail}")]
    Underdetermined {
        /// number of unknowns
        unknowns: usize,
        /// what is missing
        detail: String,
    },
    /// A determinant of fewer than 2 or more than 6 points was asked for.
    #[error("a Cayley–Menger equation needs 2 to 6 distinct points, got {0}")]
    DeterminantSize(String),
}

/// A point, with coordinates when it is part of the fixed frame (the base).
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// Name used in reports and variable names.
    pub name: String,
    /// Coordinates in the fixed frame, if known.
    pub xyz: Option<[f64; 3]>,
}

/// `point` lies at squared distance `squared` from the line through `line.0` and `line.1`.
#[derive(Clone, Debug, PartialEq)]
pub struct PointLine {
    /// The point.
    pub point: usize,
    /// Two points of the line.
    pub line: (usize, usize),
    /// Squared distance from the point to the line.
    pub squared: Interval,
}

/// `(toward − a)·(b − a) ≥ 0`, i.e. `r(toward, b) ≤ r(toward, a) + r(a, b)`: picks one of the two
/// orientations of the segment `a b` when both give the same configuration up to direction
/// (the four-spheres problem's second point of a line). No configuration is lost whose other
/// orientation satisfies it.
#[derive(Clone, Debug, PartialEq)]
pub struct Orientation {
    /// Start of the segment.
    pub a: usize,
    /// End of the segment.
    pub b: usize,
    /// The point the segment must not point away from.
    pub toward: usize,
}

/// Points, known and unknown squared distances, point–line distances, and optionally which
/// determinants to use.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DistanceProblem {
    /// Name for reports.
    pub name: String,
    /// The points.
    pub points: Vec<Point>,
    known: BTreeMap<(usize, usize), Interval>,
    ranges: BTreeMap<(usize, usize), Interval>,
    /// Point–line distance constraints (the seed's Eq. 5).
    pub point_lines: Vec<PointLine>,
    /// Orientation choices (symmetry breaking, see `Orientation`).
    pub orientations: Vec<Orientation>,
    /// The Cayley–Menger determinants to use (sets of point indices); `None`: every five-point
    /// set with an unknown distance.
    pub equations: Option<Vec<Vec<usize>>>,
    /// Determinants added on request; `None`: every six-point set with an unknown distance.
    pub redundant: Option<Vec<Vec<usize>>>,
    /// Pairs of points whose line is reported for each solution.
    pub lines: Vec<(usize, usize)>,
}

fn key(a: usize, b: usize) -> (usize, usize) {
    (a.min(b), a.max(b))
}

impl DistanceProblem {
    /// An empty problem.
    pub fn new(name: impl Into<String>) -> Self {
        Self { name: name.into(), ..Default::default() }
    }

    /// Adds a point and returns its index.
    pub fn add_point(&mut self, name: impl Into<String>, xyz: Option<[f64; 3]>) -> Result<usize, DistanceError> {
        let name = name.into();
        if self.point(&name).is_some() {
            return Err(DistanceError::Naming(format!("two points are named '{name}'")));
        }
        if let Some(c) = xyz {
            if !c.iter().all(|v| v.is_finite()) {
                return Err(DistanceError::BadValue { what: format!("point {name}"), problem: "a coordinate is not a finite number".into() });
            }
        }
        self.points.push(Point { name, xyz });
        Ok(self.points.len() - 1)
    }

    /// Index of the point named `name`.
    pub fn point(&self, name: &str) -> Option<usize> {
        self.points.iter().position(|p| p.name == name)
    }

    fn pair_name(&self, a: usize, b: usize) -> String {
        format!("r({},{})", self.points[a].name, self.points[b].name)
    }

    fn check_pair(&self, a: usize, b: usize) -> Result<(), DistanceError> {
        if a >= self.points.len() || b >= self.points.len() || a == b {
            return Err(DistanceError::Naming(format!("a distance needs two distinct known points, got indices {a} and {b}")));
        }
        Ok(())
    }

    /// Sets the squared distance between `a` and `b` (an interval for uncertain values).
    pub fn set_known(&mut self, a: usize, b: usize, squared: Interval) -> Result<(), DistanceError> {
        self.check_pair(a, b)?;
        if squared.is_empty() || !(squared.inf() > 0.0) || !squared.sup().is_finite() {
            return Err(DistanceError::BadValue { what: self.pair_name(a, b), problem: "a squared distance must be a positive finite number".into() });
        }
        self.known.insert(key(a, b), squared);
        Ok(())
    }

    /// Bounds the unknown squared distance between `a` and `b` to `range`.
    pub fn set_range(&mut self, a: usize, b: usize, range: Interval) -> Result<(), DistanceError> {
        self.check_pair(a, b)?;
        if range.is_empty() || !range.inf().is_finite() || !range.sup().is_finite() || range.inf() < 0.0 {
            return Err(DistanceError::BadValue { what: self.pair_name(a, b), problem: "a range must be [lower, upper] with 0 <= lower <= upper, finite".into() });
        }
        self.ranges.insert(key(a, b), range);
        Ok(())
    }

    /// Adds the constraint "`p` lies at squared distance `squared` from the line `a b`".
    pub fn add_point_line(&mut self, p: usize, a: usize, b: usize, squared: Interval) -> Result<(), DistanceError> {
        self.check_pair(a, b)?;
        self.check_pair(p, a)?;
        self.check_pair(p, b)?;
        if squared.is_empty() || squared.inf() < 0.0 || !squared.sup().is_finite() {
            return Err(DistanceError::BadValue { what: format!("distance from {} to line {} {}", self.points[p].name, self.points[a].name, self.points[b].name), problem: "must be a nonnegative finite number".into() });
        }
        self.point_lines.push(PointLine { point: p, line: (a, b), squared });
        Ok(())
    }

    /// The known squared distance between `a` and `b`: given, or computed (outward rounded) from
    /// both points' coordinates.
    pub fn known(&self, a: usize, b: usize) -> Option<Interval> {
        if let Some(&r) = self.known.get(&key(a, b)) {
            return Some(r);
        }
        match (self.points[a].xyz, self.points[b].xyz) {
            (Some(p), Some(q)) => Some((0..3).fold(point(0.0), |acc, k| acc + (point(p[k]) - point(q[k])).sqr())),
            _ => None,
        }
    }

    /// Number of point pairs whose distance is known.
    /// The range given for the squared distance between `a` and `b`, if any.
    pub fn range(&self, a: usize, b: usize) -> Option<Interval> {
        self.ranges.get(&key(a, b)).copied()
    }

    fn known_count(&self) -> usize {
        let n = self.points.len();
        (0..n).flat_map(|a| (a + 1..n).map(move |b| (a, b))).filter(|&(a, b)| self.known(a, b).is_some()).count()
    }
}

/// Which variables stand for the unknown distances.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Formulation {
    /// The seed's: `r_ij` and `r_ji` are separate variables with `r_ij = r_ji`; every
    /// determinant is multilinear, so trapezoids come from corner values.
    Split,
    /// One variable per distance; determinants have degree two per variable.
    Shared,
}

/// How to build the system.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildOptions {
    /// Split (the seed's) or shared variables.
    pub formulation: Formulation,
    /// Add the redundant determinants (`DistanceProblem::redundant`).
    pub redundant: bool,
}

impl Default for BuildOptions {
    fn default() -> Self {
        Self { formulation: Formulation::Split, redundant: false }
    }
}

/// An unknown squared distance and its variables.
#[derive(Clone, Debug, PartialEq)]
pub struct Unknown {
    /// First point (the smaller index).
    pub a: usize,
    /// Second point.
    pub b: usize,
    /// `r(a,b)`.
    pub name: String,
    /// The variable of `r_ab`.
    pub var: VarId,
    /// The variable of `r_ba` in the split formulation.
    pub twin: Option<VarId>,
}

/// A distance problem as polynomial equations `p = 0` over the unknown squared distances.
#[derive(Clone, Debug)]
pub struct CayleyMenger {
    /// The problem it came from.
    pub problem: DistanceProblem,
    /// How it was built.
    pub options: BuildOptions,
    /// Variables (all primary) with their initial domains; no equations (they are `equations`).
    pub system: EquationSystem,
    /// The equations `p = 0`.
    pub equations: Vec<Poly>,
    /// One label per equation, e.g. `CM(p1,p3,p4,p5,p6)`.
    pub labels: Vec<String>,
    /// The unknown distances.
    pub unknowns: Vec<Unknown>,
}

/// The Cayley–Menger determinant `Ξ(p_1, …, p_n)` of `n` points (2 ≤ n ≤ 6), with the squared
/// distance between the `i`-th and `j`-th given by `entry(i, j)` (a constant or a variable),
/// expanded symbolically.
///
/// `Ξ(p1, p2) = 2 r12`, `Ξ(p1, p2, p3) = −16 A²`, `Ξ(p1, …, p4) = 288 V²`, and `Ξ = 0` for five
/// or more points in R³ (the seed's Eqs. 1–4).
///
/// # Examples
///
/// ```
/// use linkspace::kernel::interval::point;
/// use linkspace::formulate::cayley_menger_determinant;
/// use linkspace::kernel::system::Poly;
/// // Two points at squared distance r (variable 0): Ξ = 2r.
/// let d = cayley_menger_determinant(2, &|_, _| Poly::var(0)).unwrap();
/// assert_eq!(d, Poly::var(0).scale(point(2.0)));
/// ```
///
/// # References
/// K. Menger, "New foundation of Euclidean geometry", Amer. J. Math. 53, 1931; the seed, Sec. II.
pub fn cayley_menger_determinant(n: usize, entry: &dyn Fn(usize, usize) -> Poly) -> Result<Poly, DistanceError> {
    if !(2..=6).contains(&n) {
        return Err(DistanceError::DeterminantSize(n.to_string()));
    }
    // Bordered matrix: rows/columns 0..n are points, n is the border of ones.
    let size = n + 1;
    let cell = |i: usize, j: usize| -> Poly {
        if i == n && j == n || i == j {
            Poly::zero()
        } else if i == n || j == n {
            Poly::constant(point(1.0))
        } else {
            entry(i, j)
        }
    };
    // Laplace expansion along rows, memoised on the set of columns still free.
    let mut memo: BTreeMap<u32, Poly> = BTreeMap::new();
    fn minor(row: usize, cols: u32, size: usize, cell: &dyn Fn(usize, usize) -> Poly, memo: &mut BTreeMap<u32, Poly>) -> Poly {
        if row == size {
            return Poly::constant(point(1.0));
        }
        if let Some(p) = memo.get(&cols) {
            return p.clone();
        }
        let mut sum = Poly::zero();
        let mut rank = 0;
        for c in 0..size {
            if cols & (1 << c) == 0 {
                continue;
            }
            let a = cell(row, c);
            if !a.is_zero() {
                let rest = minor(row + 1, cols & !(1 << c), size, cell, memo);
                let term = a.mul(&rest);
                sum = sum.add(&if rank % 2 == 0 { term } else { term.scale(point(-1.0)) });
            }
            rank += 1;
        }
        memo.insert(cols, sum.clone());
        sum
    }
    Ok(minor(0, (1u32 << size) - 1, size, &cell, &mut memo))
}

/// Three points are collinear: `Ξ(p1, p2, p3) = 0` (zero area).
pub fn collinear(entry: &dyn Fn(usize, usize) -> Poly) -> Poly {
    cayley_menger_determinant(3, entry).expect("invariant: 3 points")
}

/// Point 0 at squared distance `d2` from the line through points 1 and 2:
/// `Ξ(p0, p1, p2) + 4 r12 d² = 0` (the seed's Eq. 5).
pub fn point_line(entry: &dyn Fn(usize, usize) -> Poly, d2: Interval) -> Poly {
    collinear(entry).add(&entry(1, 2).scale(point(4.0) * d2))
}

impl CayleyMenger {
    /// Checks the problem and builds its equations.
    ///
    /// Errors: a triangle or tetrahedron of known distances that cannot exist, collinear base
    /// points, an unknown with no room, fewer constraints than the shape's degrees of freedom
    /// (`3n − 6`), or fewer equations than unknowns.
    pub fn build(problem: &DistanceProblem, options: BuildOptions) -> Result<Self, DistanceError> {
        let p = problem;
        let n = p.points.len();
        let names = |ix: &[usize]| ix.iter().map(|&i| p.points[i].name.as_str()).collect::<Vec<_>>().join(", ");
        if n < 4 {
            return Err(DistanceError::Underdetermined { unknowns: 0, detail: format!("a problem in space needs at least 4 points, got {n}") });
        }
        let based: Vec<usize> = (0..n).filter(|&i| p.points[i].xyz.is_some()).collect();
        if based.len() >= 3 && !has_triangle(p, &based) {
            return Err(DistanceError::DegenerateBase(names(&based)));
        }
        check_triangles(p)?;
        check_tetrahedra(p)?;
        // Degrees of freedom of n points up to a rigid motion, against the constraints given.
        let dof = 3 * n - 6;
        let constraints = p.known_count() + p.point_lines.len();
        let unknown_pairs = n * (n - 1) / 2 - p.known_count();
        if constraints < dof {
            return Err(DistanceError::Underdetermined {
                unknowns: unknown_pairs,
                detail: format!("only {constraints} known distances and point-line constraints for the {dof} degrees of freedom of {n} points in space"),
            });
        }

        let subsets = |given: &Option<Vec<Vec<usize>>>, size: usize| -> Result<Vec<Vec<usize>>, DistanceError> {
            match given {
                Some(list) => {
                    for s in list {
                        let mut t = s.clone();
                        t.sort_unstable();
                        t.dedup();
                        if t.len() != s.len() || !(2..=6).contains(&s.len()) || s.iter().any(|&i| i >= n) {
                            return Err(DistanceError::DeterminantSize(format!("{s:?}")));
                        }
                    }
                    Ok(list.clone())
                }
                None => Ok(combinations(n, size).into_iter().filter(|s| has_unknown(p, s)).collect()),
            }
        };
        let mut sets = subsets(&p.equations, 5)?;
        if options.redundant {
            sets.extend(subsets(&p.redundant, 6)?);
        }

        // Unknown pairs that the equations mention, in a fixed order.
        let mut pairs: Vec<(usize, usize)> = Vec::new();
        let mut note = |a: usize, b: usize| {
            let k = key(a, b);
            if p.known(a, b).is_none() && !pairs.contains(&k) {
                pairs.push(k);
            }
        };
        for s in &sets {
            for (x, &a) in s.iter().enumerate() {
                for &b in &s[x + 1..] {
                    note(a, b);
                }
            }
        }
        for pl in &p.point_lines {
            for (a, b) in [(pl.point, pl.line.0), (pl.point, pl.line.1), pl.line] {
                note(a, b);
            }
        }
        for o in &p.orientations {
            for (a, b) in [(o.toward, o.a), (o.toward, o.b), (o.a, o.b)] {
                note(a, b);
            }
        }
        pairs.sort_unstable();
        let equation_count = sets.len() + p.point_lines.len();
        if pairs.len() > equation_count {
            return Err(DistanceError::Underdetermined {
                unknowns: pairs.len(),
                detail: format!("only {equation_count} equations constrain them"),
            });
        }
        if pairs.is_empty() {
            return Err(DistanceError::Underdetermined { unknowns: 0, detail: "nothing is unknown: there is nothing to solve".into() });
        }

        let domains = bound_smoothing(p)?;
        let mut system = EquationSystem::default();
        let mut unknowns = Vec::new();
        for &(a, b) in &pairs {
            let domain = domains[a][b];
            let name = p.pair_name(a, b);
            let var = system.add_var(name.clone(), VarRole::Primary, domain);
            unknowns.push(Unknown { a, b, name, var, twin: None });
        }
        if options.formulation == Formulation::Split {
            for u in &mut unknowns {
                u.twin = Some(system.add_var(p.pair_name(u.b, u.a), VarRole::Primary, domains[u.a][u.b]));
            }
        }
        let index: BTreeMap<(usize, usize), (VarId, Option<VarId>)> = unknowns.iter().map(|u| ((u.a, u.b), (u.var, u.twin))).collect();
        // Entry (i, j) of a determinant over points `pts`: known constant or a variable; in the
        // split formulation, the lower triangle uses the twin.
        let entry_for = |pts: Vec<usize>| {
            let index = &index;
            move |i: usize, j: usize| -> Poly {
                let (a, b) = (pts[i], pts[j]);
                if let Some(r) = p.known(a, b) {
                    return Poly::constant(r);
                }
                let (v, twin) = index[&key(a, b)];
                match twin {
                    Some(t) if a > b => Poly::var(t),
                    _ => Poly::var(v),
                }
            }
        };

        let mut equations = Vec::new();
        let mut labels = Vec::new();
        for u in &unknowns {
            if let Some(t) = u.twin {
                equations.push(Poly::var(u.var).add(&Poly::var(t).scale(point(-1.0))));
                labels.push(format!("{} = {}", u.name, p.pair_name(u.b, u.a)));
            }
        }
        for pl in &p.point_lines {
            let pts = vec![pl.point, pl.line.0, pl.line.1];
            equations.push(point_line(&entry_for(pts), pl.squared));
            labels.push(format!("dist({}, line {} {})² = {}", p.points[pl.point].name, p.points[pl.line.0].name, p.points[pl.line.1].name, pl.squared.mid()));
        }
        for s in &sets {
            equations.push(cayley_menger_determinant(s.len(), &entry_for(s.clone()))?);
            labels.push(format!("CM({})", names(s)));
        }
        for o in &p.orientations {
            // r(t,b) − r(t,a) − r(a,b) ≤ 0, as r(t,b) − r(t,a) − r(a,b) + s = 0 with a slack
            // s ∈ [0, S] folded into the constant; S bounds −(the sum) over the domains.
            let e = entry_for(vec![o.toward, o.a, o.b]);
            let lhs = e(0, 2).add(&e(0, 1).scale(point(-1.0))).add(&e(1, 2).scale(point(-1.0)));
            let range = lhs.eval(&system.initial_box().dims);
            let slack = interval(0.0, (-range.inf()).max(0.0));
            equations.push(lhs.add(&Poly::constant(slack)));
            labels.push(format!("orient {} {} toward {}", p.points[o.a].name, p.points[o.b].name, p.points[o.toward].name));
        }
        Ok(Self { problem: p.clone(), options, system, equations, labels, unknowns })
    }

    /// The seed's `Reduce_Box` over this system's equations, ready for `Solver::with_contractor`.
    pub fn contractor(&self, faces: FaceBounds) -> Result<TrapezoidClip, ClipError> {
        TrapezoidClip::new(&self.equations, faces)
    }

    /// A solver for this problem: the trapezoid clipper with `faces` as its shrink pipeline.
    /// See also `LinkageProblem::solver`.
    pub fn solver(&self, faces: FaceBounds, settings: SolverSettings) -> Result<Solver<'_>, DistanceSolverError> {
        let clip = self.contractor(faces)?;
        Ok(Solver::new(&self.system, settings)?.with_contractor(Box::new(move |_, _| Box::new(clip.clone()))))
    }

    /// The squared distance of every pair at a point `x` of the variable space (box midpoint,
    /// say): known ones at their midpoints, unknown ones from `x` (the mean of the two copies in
    /// the split formulation), `None` for pairs the equations did not involve.
    #[allow(clippy::needless_range_loop)] // a symmetric matrix filled by (row, column)
    pub fn distances(&self, x: &[f64]) -> Vec<Vec<Option<f64>>> {
        let n = self.problem.points.len();
        let mut r = vec![vec![None; n]; n];
        for a in 0..n {
            for b in 0..n {
                if a != b {
                    r[a][b] = self.problem.known(a, b).map(|i| i.mid());
                }
            }
        }
        for u in &self.unknowns {
            let v = match u.twin {
                Some(t) => 0.5 * (x[u.var] + x[t]),
                None => x[u.var],
            };
            r[u.a][u.b] = Some(v);
            r[u.b][u.a] = Some(v);
        }
        r
    }

    /// The unknown distances over a box: per unknown, the intersection of its copies (the hull if
    /// they do not meet).
    pub fn unknown_intervals(&self, b: &IntervalBox) -> Vec<(String, Interval)> {
        self.unknowns
            .iter()
            .map(|u| {
                let d = b.dims[u.var];
                let d = match u.twin {
                    Some(t) => {
                        let both = d.intersection(b.dims[t]);
                        if both.is_empty() {
                            d.convex_hull(b.dims[t])
                        } else {
                            both
                        }
                    }
                    None => d,
                };
                (u.name.clone(), d)
            })
            .collect()
    }

    /// Places every point from a solution's distances (see `embed`).
    pub fn embed(&self, x: &[f64], tol: f64) -> Vec<Vec<[f64; 3]>> {
        embed(&self.problem, &self.distances(x), tol)
    }
}

/// Positions of every point from the squared distances `r` (`None` where unknown), by
/// trilateration: the points with coordinates stay put (or, when fewer than three have them, the
/// first triangle defines the frame), then each point is placed from three placed points it has
/// distances to. Where a fourth placed point off their plane decides between the two candidates it
/// does; otherwise both are kept, so the mirror images come out as separate embeddings. Both are
/// kept too when both fit the fourth point's distance within `tol` (squared-distance units): at a
/// tangency of the determinant curves two configurations share the solved distances.
/// Returns no embedding when some point cannot be reached.
pub fn embed(p: &DistanceProblem, r: &[Vec<Option<f64>>], tol: f64) -> Vec<Vec<[f64; 3]>> {
    let n = p.points.len();
    let mut start: Vec<Option<Vector3<f64>>> = p.points.iter().map(|q| q.xyz.map(|c| Vector3::new(c[0], c[1], c[2]))).collect();
    if start.iter().flatten().count() < 3 {
        // A frame from the first triangle with all three distances: a at 0, b on +x, c in xy, y > 0.
        start = vec![None; n];
        let tri = combinations(n, 3).into_iter().find(|t| t.iter().enumerate().all(|(k, &i)| t[k + 1..].iter().all(|&j| r[i][j].is_some())));
        let Some(t) = tri else { return Vec::new() };
        let (ab, ac, bc) = (r[t[0]][t[1]].unwrap_or(0.0), r[t[0]][t[2]].unwrap_or(0.0), r[t[1]][t[2]].unwrap_or(0.0));
        let d = ab.sqrt();
        let x = (ac - bc + ab) / (2.0 * d);
        let y = (ac - x * x).max(0.0).sqrt();
        start[t[0]] = Some(Vector3::zeros());
        start[t[1]] = Some(Vector3::new(d, 0.0, 0.0));
        start[t[2]] = Some(Vector3::new(x, y, 0.0));
    }
    // When the fixed points are coplanar, the mirror image through their plane of any placement
    // is another one.
    let fixed: Vec<Vector3<f64>> = start.iter().flatten().copied().collect();
    let plane = {
        let (a, b, c) = (fixed[0], fixed[1], fixed[2]);
        let nrm = (b - a).cross(&(c - a)).normalize();
        fixed.iter().all(|q| nrm.dot(&(q - a)).abs() <= 1e-9 * (1.0 + (q - a).norm())).then_some((a, nrm))
    };
    let mut done = Vec::new();
    let mut work = vec![start];
    while let Some(mut pos) = work.pop() {
        if pos.iter().all(|v| v.is_some()) {
            done.push(pos.iter().map(|v| v.map(|v| [v.x, v.y, v.z]).expect("invariant: all placed")).collect());
            continue;
        }
        // Pick the unplaced point with the best-conditioned reference triangle.
        let mut best: Option<(f64, usize, [usize; 3])> = None;
        for q in (0..n).filter(|&i| pos[i].is_none()) {
            let refs: Vec<usize> = (0..n).filter(|&i| pos[i].is_some() && r[q][i].is_some()).collect();
            for t in combinations(refs.len(), 3) {
                let [a, b, c] = [refs[t[0]], refs[t[1]], refs[t[2]]];
                let (pa, pb, pc) = (pos[a].expect("placed"), pos[b].expect("placed"), pos[c].expect("placed"));
                let area = (pb - pa).cross(&(pc - pa)).norm();
                if best.is_none_or(|(s, _, _)| area > s) {
                    best = Some((area, q, [a, b, c]));
                }
            }
        }
        let Some((area, q, [a, b, c])) = best else { continue };
        if area < 1e-12 {
            continue;
        }
        let (pa, pb, pc) = (pos[a].expect("placed"), pos[b].expect("placed"), pos[c].expect("placed"));
        let [ra, rb, rc] = [r[q][a], r[q][b], r[q][c]].map(|v| v.expect("chosen with distances"));
        let ex = (pb - pa).normalize();
        let i = ex.dot(&(pc - pa));
        let ey = (pc - pa - ex * i).normalize();
        let ez = ex.cross(&ey);
        let d = (pb - pa).norm();
        let j = ey.dot(&(pc - pa));
        let x = (ra - rb + d * d) / (2.0 * d);
        let y = (ra - rc + i * i + j * j) / (2.0 * j) - (i / j) * x;
        let z = (ra - x * x - y * y).max(0.0).sqrt();
        let base = pa + ex * x + ey * y;
        let candidates = [base + ez * z, base - ez * z];
        // A fourth placed point off the plane with a known distance decides.
        let judge = (0..n).filter(|&e| e != a && e != b && e != c && pos[e].is_some() && r[q][e].is_some()).find(|&e| ez.dot(&(pos[e].expect("placed") - pa)).abs() > 1e-6 * d.max(1.0));
        match judge {
            Some(e) if z > 1e-9 => {
                let pe = pos[e].expect("placed");
                let re = r[q][e].expect("has distance");
                let miss = |v: &Vector3<f64>| ((v - pe).norm_squared() - re).abs();
                let (m0, m1) = (miss(&candidates[0]), miss(&candidates[1]));
                if m0 <= tol && m1 <= tol && done.len() + work.len() < 16 {
                    let mut other = pos.clone();
                    other[q] = Some(candidates[1]);
                    work.push(other);
                }
                pos[q] = Some(if m0 <= m1 { candidates[0] } else { candidates[1] });
                work.push(pos);
            }
            _ if z <= 1e-9 => {
                pos[q] = Some(base);
                work.push(pos);
            }
            _ => {
                let mut other = pos.clone();
                other[q] = Some(candidates[1]);
                pos[q] = Some(candidates[0]);
                work.push(other);
                work.push(pos);
            }
        }
    }
    // Keep the placements that fit every distance within `tol`, or about as well as the best one
    // (mirror images fit equally well; a box midpoint is not exactly on the solution, and the
    // misfit it causes can exceed `tol`), and drop near-duplicates: a branch taken on a loose
    // fit often lands next to the other one.
    let misfit = |e: &Vec<[f64; 3]>| {
        let mut worst: f64 = 0.0;
        for a in 0..n {
            for b in a + 1..n {
                if let Some(rab) = r[a][b] {
                    let d: f64 = (0..3).map(|k| (e[a][k] - e[b][k]).powi(2)).sum();
                    worst = worst.max((d - rab).abs());
                }
            }
        }
        worst
    };
    let mut scored: Vec<(f64, Vec<[f64; 3]>)> = done.into_iter().map(|e| (misfit(&e), e)).collect();
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    let near = tol.sqrt().max(1e-6);
    let accept = tol.max(4.0 * scored.first().map_or(0.0, |s| s.0));
    let mut kept: Vec<Vec<[f64; 3]>> = Vec::new();
    for (m, e) in scored {
        if m > accept {
            continue;
        }
        let mirror = plane.map(|(a, nrm)| {
            e.iter()
                .map(|q| {
                    let v = Vector3::new(q[0], q[1], q[2]);
                    let w = v - nrm * (2.0 * nrm.dot(&(v - a)));
                    [w.x, w.y, w.z]
                })
                .collect::<Vec<_>>()
        });
        for f in std::iter::once(e).chain(mirror) {
            let dup = kept.iter().any(|g| g.iter().zip(&f).all(|(x, y)| (0..3).all(|c| (x[c] - y[c]).abs() <= near)));
            if !dup {
                kept.push(f);
            }
        }
    }
    kept
}

/// All `k`-subsets of `0..n`, in lexicographic order.
pub fn combinations(n: usize, k: usize) -> Vec<Vec<usize>> {
    let mut out = Vec::new();
    let mut cur = Vec::with_capacity(k);
    fn rec(start: usize, n: usize, k: usize, cur: &mut Vec<usize>, out: &mut Vec<Vec<usize>>) {
        if cur.len() == k {
            out.push(cur.clone());
            return;
        }
        for i in start..n {
            cur.push(i);
            rec(i + 1, n, k, cur, out);
            cur.pop();
        }
    }
    rec(0, n, k, &mut cur, &mut out);
    out
}

fn has_unknown(p: &DistanceProblem, s: &[usize]) -> bool {
    s.iter().enumerate().any(|(x, &a)| s[x + 1..].iter().any(|&b| p.known(a, b).is_none()))
}

/// Known-distance triangles must satisfy the triangle inequality: Ξ(a, b, c) = −16A² ≤ 0.
fn check_triangles(p: &DistanceProblem) -> Result<(), DistanceError> {
    for t in combinations(p.points.len(), 3) {
        let (a, b, c) = (t[0], t[1], t[2]);
        let (Some(ab), Some(bc), Some(ca)) = (p.known(a, b), p.known(b, c), p.known(a, c)) else { continue };
        let r = [[point(0.0), ab, ca], [ab, point(0.0), bc], [ca, bc, point(0.0)]];
        let xi = collinear(&|i, j| Poly::constant(r[i][j])).eval(&[]);
        if xi.inf() > 0.0 {
            let name = |i: usize| p.points[i].name.clone();
            return Err(DistanceError::Triangle { a: name(a), b: name(b), c: name(c), ab: ab.mid(), bc: bc.mid(), ca: ca.mid() });
        }
    }
    Ok(())
}

/// Known-distance tetrahedra must have Ξ = 288V² ≥ 0.
fn check_tetrahedra(p: &DistanceProblem) -> Result<(), DistanceError> {
    for t in combinations(p.points.len(), 4) {
        let mut r = [[point(0.0); 4]; 4];
        let mut all = true;
        for i in 0..4 {
            for j in 0..4 {
                if i != j {
                    match p.known(t[i], t[j]) {
                        Some(v) => r[i][j] = v,
                        None => all = false,
                    }
                }
            }
        }
        if all && cayley_menger_determinant(4, &|i, j| Poly::constant(r[i][j])).expect("4 points").eval(&[]).sup() < 0.0 {
            return Err(DistanceError::Tetrahedron(t.iter().map(|&i| p.points[i].name.as_str()).collect::<Vec<_>>().join(", ")));
        }
    }
    Ok(())
}

/// True when some three of `pts` span a triangle of non-negligible area.
fn has_triangle(p: &DistanceProblem, pts: &[usize]) -> bool {
    combinations(pts.len(), 3).into_iter().any(|t| {
        let v = |k: usize| {
            let c = p.points[pts[t[k]]].xyz.expect("based points have coordinates");
            Vector3::new(c[0], c[1], c[2])
        };
        let (a, b, c) = (v(0), v(1), v(2));
        let scale = (b - a).norm().max((c - a).norm()).max(1e-300);
        (b - a).cross(&(c - a)).norm() > 1e-9 * scale * scale
    })
}

/// Domains of every pair's squared distance: known values, given ranges, and the triangle
/// inequality (bound smoothing on distances: `d_ij ≤ d_ik + d_kj`, `d_ij ≥ d_ik − d_kj`), all in
/// outward-rounded interval arithmetic.
pub(crate) fn bound_smoothing(p: &DistanceProblem) -> Result<Vec<Vec<Interval>>, DistanceError> {
    let n = p.points.len();
    let mut lo = vec![vec![0.0f64; n]; n];
    let mut hi = vec![vec![f64::INFINITY; n]; n];
    for a in 0..n {
        hi[a][a] = 0.0;
        for b in 0..n {
            if a == b {
                continue;
            }
            let r = p.known(a, b).or_else(|| p.ranges.get(&key(a, b)).copied());
            if let Some(r) = r {
                let d = r.sqrt();
                lo[a][b] = d.inf();
                hi[a][b] = d.sup();
            }
        }
    }
    for _ in 0..n + 2 {
        let mut changed = false;
        for k in 0..n {
            for a in 0..n {
                for b in 0..n {
                    if a == b || a == k || b == k {
                        continue;
                    }
                    // `point` is empty for an infinite bound: such a path bounds nothing.
                    let (hak, hkb) = (hi[a][k], hi[k][b]);
                    if hak.is_finite() && hkb.is_finite() {
                        let up = (point(hak) + point(hkb)).sup();
                        if up < hi[a][b] {
                            hi[a][b] = up;
                            changed = true;
                        }
                    }
                    let below = |l: f64, h: f64| if h.is_finite() { (point(l) - point(h)).inf() } else { 0.0 };
                    let down = below(lo[a][k], hkb).max(below(lo[k][b], hak));
                    if down > lo[a][b] {
                        lo[a][b] = down;
                        changed = true;
                    }
                }
            }
        }
        if !changed {
            break;
        }
    }
    let mut out = vec![vec![point(0.0); n]; n];
    for a in 0..n {
        for b in 0..n {
            if a == b {
                continue;
            }
            if lo[a][b] > hi[a][b] {
                return Err(DistanceError::NoRoom { a: p.points[a.min(b)].name.clone(), b: p.points[a.max(b)].name.clone() });
            }
            // A known distance keeps its own value; unknown ones get the smoothed range.
            out[a][b] = match p.known(a, b) {
                Some(r) => r,
                None => {
                    let r = interval(lo[a][b], hi[a][b]).sqr();
                    match p.ranges.get(&key(a, b)) {
                        Some(given) => r.intersection(*given),
                        None => r,
                    }
                }
            };
            if !out[a][b].sup().is_finite() && p.known(a, b).is_none() {
                return Err(DistanceError::Underdetermined {
                    unknowns: 1,
                    detail: format!("{} is unbounded: no path of known distances joins the two points; give it a range", p.pair_name(a.min(b), a.max(b))),
                });
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn random_points(seed: u64, n: usize) -> Vec<Vector3<f64>> {
        let mut s = seed;
        let mut next = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 4.0 - 2.0
        };
        (0..n).map(|_| Vector3::new(next(), next(), next())).collect()
    }

    fn entry_of(p: &[Vector3<f64>]) -> impl Fn(usize, usize) -> Poly + '_ {
        move |i, j| Poly::constant(point((p[i] - p[j]).norm_squared()))
    }

    #[test]
    fn determinants_match_the_seed_formulas() {
        for seed in 0..5 {
            let p = random_points(seed, 6);
            let e = entry_of(&p);
            let val = |n: usize| cayley_menger_determinant(n, &e).unwrap().eval(&[]).mid();
            assert!((val(2) - 2.0 * (p[0] - p[1]).norm_squared()).abs() < 1e-9);
            let area = 0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm();
            assert!((val(3) + 16.0 * area * area).abs() < 1e-8);
            let vol = (p[1] - p[0]).dot(&(p[2] - p[0]).cross(&(p[3] - p[0]))) / 6.0;
            assert!((val(4) - 288.0 * vol * vol).abs() < 1e-7 * (1.0 + val(4).abs()));
            assert!(val(5).abs() < 1e-7 * 1e3, "Ξ5 = {}", val(5));
            assert!(val(6).abs() < 1e-6 * 1e4, "Ξ6 = {}", val(6));
        }
        assert!(cayley_menger_determinant(7, &|_, _| Poly::zero()).is_err());
    }

    #[test]
    fn derived_constraints_vanish_where_they_should() {
        let p = [Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.0, 2.0, 0.0), Vector3::new(2.0, 4.0, 0.0)];
        assert!(collinear(&entry_of(&p)).eval(&[]).contains(0.0));
        // (1, 1, 0) is at distance 1 from the x-axis through (0,0,0) and (2,0,0).
        let r = [Vector3::new(1.0, 1.0, 0.0), Vector3::new(0.0, 0.0, 0.0), Vector3::new(2.0, 0.0, 0.0)];
        assert!(point_line(&entry_of(&r), point(1.0)).eval(&[]).contains(0.0));
        assert!(!point_line(&entry_of(&r), point(1.1)).eval(&[]).contains(0.0));
    }

    #[test]
    fn split_determinants_are_multilinear_and_shared_ones_quadratic() {
        let mut p = DistanceProblem::new("t");
        for (k, c) in [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]].into_iter().enumerate() {
            p.add_point(format!("b{k}"), Some(c)).unwrap();
        }
        let q = p.add_point("q", None).unwrap();
        // q at (0.5, 0.5, 0.5): the distance to b3 is the unknown.
        for (b, r) in [(0, 0.75), (1, 0.75), (2, 0.75)] {
            p.set_known(q, b, point(r)).unwrap();
        }
        let split = CayleyMenger::build(&p, BuildOptions::default()).unwrap();
        assert!(split.equations.iter().all(|e| e.is_multilinear()));
        assert_eq!(split.unknowns.len(), 1);
        let shared = CayleyMenger::build(&p, BuildOptions { formulation: Formulation::Shared, redundant: false }).unwrap();
        assert!(!shared.equations[0].is_multilinear());
        // The true value 0.75 is a root; 1.0 is not.
        assert!(shared.equations[0].eval(&[point(0.75)]).contains(0.0));
        assert!(!shared.equations[0].eval(&[point(1.0)]).contains(0.0));
    }

    #[test]
    fn embedding_recovers_the_points_up_to_mirror() {
        let pts = random_points(7, 6);
        let mut p = DistanceProblem::new("e");
        for (k, v) in pts.iter().enumerate() {
            p.add_point(format!("p{k}"), (k < 3).then_some([v.x, v.y, v.z])).unwrap();
        }
        let r: Vec<Vec<Option<f64>>> = (0..6).map(|i| (0..6).map(|j| (i != j).then(|| (pts[i] - pts[j]).norm_squared())).collect()).collect();
        let found = embed(&p, &r, 1e-9);
        assert_eq!(found.len(), 2);
        let hit = found.iter().any(|e| e.iter().zip(&pts).all(|(a, b)| (Vector3::new(a[0], a[1], a[2]) - b).norm() < 1e-6));
        assert!(hit, "{found:?} vs {pts:?}");
    }
}

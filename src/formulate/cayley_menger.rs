//! Distance problems as Cayley–Menger systems (Porta, Thomas, Ros and Torras 2003).
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
//! Two formulations: `Split` is that of Porta et al. (2003) (each unknown `r_ij` and its twin
//! `r_ji` are separate variables tied by `r_ij − r_ji = 0`, which makes every determinant
//! multilinear), `Shared` keeps one variable per distance (degree two per variable; clipped through
//! Bernstein control points). After a solve, `embed` places the points by trilateration from a
//! solution's distances, both mirror images included.
//! Builds only; solving is `solve`'s job.

mod checks;
mod embed;

use self::checks::{check_tetrahedra, check_triangles, has_triangle, has_unknown};
pub(crate) use self::checks::bound_smoothing;
pub(crate) use self::embed::embed;
use crate::kernel::contract::{ClipError, FaceBounds, TrapezoidClip};
use crate::kernel::search::{SolveError, Solver, SolverSettings};
use crate::kernel::interval::{interval, point, Interval, IntervalBox};
use crate::kernel::system::multilinear::Poly;
use crate::kernel::system::{EquationSystem, VarId, VarRole};
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
    /// Point–line distance constraints (Porta et al. 2003, Eq. 5).
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
    /// That of Porta et al. (2003): `r_ij` and `r_ji` are separate variables with `r_ij = r_ji`;
    /// every determinant is multilinear, so trapezoids come from corner values.
    Split,
    /// One variable per distance; determinants have degree two per variable.
    Shared,
}

/// How to build the system.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildOptions {
    /// Split (as in Porta et al. 2003) or shared variables.
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
/// or more points in R³ (Porta et al. 2003, Eqs. 1–4).
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
/// K. Menger, "New foundation of Euclidean geometry", Amer. J. Math. 53, 1931; Porta et al. (2003),
/// Sec. II.
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
pub(crate) fn collinear(entry: &dyn Fn(usize, usize) -> Poly) -> Poly {
    cayley_menger_determinant(3, entry).expect("invariant: 3 points")
}

/// Point 0 at squared distance `d2` from the line through points 1 and 2:
/// `Ξ(p0, p1, p2) + 4 r12 d² = 0` (Porta et al. 2003, Eq. 5).
pub(crate) fn point_line(entry: &dyn Fn(usize, usize) -> Poly, d2: Interval) -> Poly {
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

    /// The `Reduce_Box` of Porta et al. (2003) over this system's equations, ready for
    /// `Solver::with_contractor`.
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

/// All `k`-subsets of `0..n`, in lexicographic order.
pub(crate) fn combinations(n: usize, k: usize) -> Vec<Vec<usize>> {
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

#[cfg(test)]
mod tests;

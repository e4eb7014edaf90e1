//! Spatial linkages: any tree of revolute, prismatic, fixed, spherical and floating joints closed
//! by revolute, prismatic, spherical, fixed, universal and cylindrical loops, as a degree-2
//! system the LP-shrink solver takes unchanged (linear equations, circles `c² + s² = 1`,
//! bilinear definitions `z = x·y`, and a few general quadratics for propagation and Newton).
//!
//! Representation (fewer unknowns than one free frame per body, and no orthogonality equation
//! to write): a joint's motion is its own unknowns — `(c, s)` with a circle for a revolute
//! joint, a travel `d` for a prismatic one, three such pairs (Euler z-y-x, pitch cosine ≥ 0 so
//! that no rotation is counted twice) for a ball or floating joint, plus three coordinates for
//! a floating one. Each rigid group's rotation is a 3×3 matrix of linear forms in variables:
//! constant for the ground and the links welded to it, linear in `(c, s)` for a group hung on a
//! known frame by a revolute joint, and one level deeper for each further joint, where the
//! product of a rotation entry and `c` or `s` is a derived variable with a bilinear definition
//! (entries with several terms are first named by a derived variable with a linear equation).
//! Every product of rotations is then a rotation by construction: no unit-norm or
//! orthogonality equation is needed.
//!
//! Positions are sums of `G·v` (group rotation times a constant vector) and linear parts, so
//! loop closures are linear equations in these variables: points coincide (3 rows), axes
//! coincide (3 rows), welded or sliding rotations agree on two columns (6 rows), universal
//! axes stay perpendicular (one bilinear row).
//!
//! A link between two ball joints (a rod hung on a spherical tree joint and closed by one
//! spherical loop, or such a leg with a prismatic joint between its two balls) spins freely
//! about the line of its balls: it gets no rotation at all and becomes a distance constraint
//! between its two ball centres, `|B − A|² = L²`, expanded with `|G·v|² = |v|²` for each
//! rotation (exact on the solutions, where every `G` is a rotation), so that a leg whose one
//! end is on the ground is linear in the rotation variables of the other end.
//!
//! Every coefficient encloses its value in the stated model (`stated`): parsed decimals widened
//! by an ulp, rotations through sound interval trigonometry. No non-zero term is dropped.
//! Builds only; solving is `search`'s job.

use super::angles::{self, against_limits, cos_sin, reduce, stated, wrap};
use super::linkage::LinkageError;
use super::stated::{self as st, IMat3, IVec3};
use crate::kernel::contract::{Contraction, Contractor, Filtered, Propagation, Inclusion};
use crate::kernel::interval::{interval, point, Interval, IntervalBox};
use crate::kernel::interval::trig;
use crate::model::{Compound, JointKind, Mechanism};
use crate::kernel::search::{default_contractor, SolveError, Solver, SolverSettings};
use crate::kernel::system::{Equation, EquationKind, EquationSystem, Monomial, Term, VarId, VarRole};
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use std::collections::BTreeMap;

/// `constant + Σ coef·var`.
#[derive(Clone, Debug)]
struct Form {
    terms: Vec<(VarId, Interval)>,
    constant: Interval,
}

impl Form {
    fn constant(k: Interval) -> Self {
        Self { terms: Vec::new(), constant: k }
    }

    fn var(v: VarId) -> Self {
        Self { terms: vec![(v, point(1.0))], constant: point(0.0) }
    }

    fn zero() -> Self {
        Self::constant(point(0.0))
    }

    fn scaled(&self, k: Interval) -> Self {
        Self { terms: self.terms.iter().map(|&(v, c)| (v, c * k)).collect(), constant: self.constant * k }
    }

    fn add(&mut self, o: &Form) {
        self.terms.extend_from_slice(&o.terms);
        self.constant += o.constant;
    }

    fn add_scaled(&mut self, o: &Form, k: Interval) {
        if k.inf() == 0.0 && k.sup() == 0.0 {
            return;
        }
        self.add(&o.scaled(k));
    }

    /// Repeated variables merged; exactly-zero coefficients left out (a tiny one is a term
    /// like any other: dropping it could lose solutions).
    fn merged(&self) -> Form {
        let mut m: BTreeMap<VarId, Interval> = BTreeMap::new();
        for &(v, c) in &self.terms {
            let e = m.entry(v).or_insert(point(0.0));
            *e += c;
        }
        Form { terms: m.into_iter().filter(|&(_, c)| !(c.inf() == 0.0 && c.sup() == 0.0)).collect(), constant: self.constant }
    }

    fn eval(&self, b: &[Interval]) -> Interval {
        self.terms.iter().fold(self.constant, |acc, &(v, c)| acc + c * b[v])
    }
}

type Vec3F = [Form; 3];
type RotF = [[Form; 3]; 3];

fn const_rot(m: &IMat3) -> RotF {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| Form::constant(m[i][j])))
}

/// `G·K` for a constant `K`.
fn rot_times(g: &RotF, k: &IMat3) -> RotF {
    [0, 1, 2].map(|i| {
        [0, 1, 2].map(|j| {
            let mut f = Form::zero();
            for (l, gl) in g[i].iter().enumerate() {
                f.add_scaled(gl, k[l][j]);
            }
            f.merged()
        })
    })
}

/// `G·v` for a constant `v`.
fn rot_apply(g: &RotF, v: &IVec3) -> Vec3F {
    [0, 1, 2].map(|i| {
        let mut f = Form::zero();
        for (l, gl) in g[i].iter().enumerate() {
            f.add_scaled(gl, v[l]);
        }
        f.merged()
    })
}

fn sub3(a: &Vec3F, b: &Vec3F) -> Vec3F {
    [0, 1, 2].map(|i| {
        let mut f = a[i].clone();
        f.add_scaled(&b[i], point(-1.0));
        f.merged()
    })
}

/// The rotation by the stated angle `v` about the unit axis `a` (Rodrigues).
fn rot_about(a: &IVec3, v: f64) -> IMat3 {
    let (c, s) = cos_sin(reduce(stated(v)).expect("checked reducible"));
    rodrigues(a, c, s)
}

/// `aaᵀ + c(I − aaᵀ) + s[a]×`
fn rodrigues(a: &IVec3, c: Interval, s: Interval) -> IMat3 {
    let (aat, rest, skew) = rodrigues_parts(a);
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| aat[i][j] + c * rest[i][j] + s * skew[i][j]))
}

/// `(aaᵀ, I − aaᵀ, [a]×)`; components of `a` that are exactly 0 keep exact zeros.
fn rodrigues_parts(a: &IVec3) -> (IMat3, IMat3, IMat3) {
    let z = point(0.0);
    let aat = [0, 1, 2].map(|i| [0, 1, 2].map(|j| a[i] * a[j]));
    let rest = [0, 1, 2].map(|i| [0, 1, 2].map(|j| if i == j { point(1.0) - aat[i][j] } else { -aat[i][j] }));
    let skew = [[z, -a[2], a[1]], [a[2], z, -a[0]], [-a[1], a[0], z]];
    (aat, rest, skew)
}

fn imat_mul(a: &IMat3, b: &IMat3) -> IMat3 {
    st::mul(a, b)
}

/// A point as rotated parts per group plus a linear rest: `Σ G_g·v_g + rest`.
#[derive(Clone, Debug)]
struct Pos {
    rotated: Vec<(usize, IVec3)>,
    rest: Vec3F,
}

impl Pos {
    fn origin() -> Self {
        Self { rotated: Vec::new(), rest: [Form::zero(), Form::zero(), Form::zero()] }
    }

    /// Adds `G_g·v`; the ground's group (0) is the identity, so its part is a constant.
    fn add_rotated(&mut self, g: usize, v: IVec3) {
        if g == 0 {
            for (r, x) in self.rest.iter_mut().zip(v) {
                r.constant += x;
            }
        } else {
            self.rotated.push((g, v));
        }
    }

    fn minus(&self, o: &Pos) -> Pos {
        let mut out = self.clone();
        for &(g, v) in &o.rotated {
            out.rotated.push((g, v.map(|x| -x)));
        }
        out.rest = sub3(&self.rest, &o.rest);
        out
    }

    /// Parts of one group summed: `Σ_g G_g·(Σ v)`.
    fn by_group(&self) -> BTreeMap<usize, IVec3> {
        let mut m: BTreeMap<usize, IVec3> = BTreeMap::new();
        for &(g, v) in &self.rotated {
            let e = m.entry(g).or_insert([point(0.0); 3]);
            for (x, y) in e.iter_mut().zip(v) {
                *x += y;
            }
        }
        m
    }
}

/// How a joint's value is read off a box.
#[derive(Clone, Debug)]
enum Reading {
    /// `atan2(s, c)`.
    Angle { c: VarId, s: VarId },
    /// A variable (travel, floating position).
    Var(VarId),
    /// The angle of a revolute (or cylindrical) loop about its axis.
    LoopAngle(usize),
    /// The travel of a prismatic (or cylindrical) loop along its axis.
    LoopTravel(usize),
}

/// A point of a link whose world coordinates are traced.
#[derive(Clone, Debug)]
pub struct Trace3 {
    /// `LINK@X,Y,Z` (or `LINK@X,Y`) as given.
    pub name: String,
    /// World x, y, z variables.
    pub xyz: [VarId; 3],
}

/// Where a link is, as the builder knows it.
#[derive(Clone, Debug)]
struct LinkPlace {
    name: String,
    /// `(group, K)` with the link's rotation `G_group·K`; `None` for a link that spins freely
    /// between two ball joints (its orientation is not determined).
    rotation: Option<(usize, IMat3)>,
    /// Its frame origin; `None` when it depends on an undetermined spin.
    position: Option<Pos>,
}

/// A closure's frames and axes, kept to read its values back.
#[derive(Clone, Debug)]
struct LoopFrames {
    pred: (usize, IMat3),
    succ: (usize, IMat3),
    pred_at: Pos,
    succ_at: Pos,
    axis: IVec3,
    /// Two unit vectors completing `axis` to an orthonormal frame (f64, for read-outs).
    across: [Vector3<f64>; 2],
}

/// A link's pose over a box.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkPose {
    /// Frame origin in the root frame, per coordinate `[lo, hi]`; `None` when it is not
    /// determined (a leg between two ball joints spins freely).
    pub position: Option<[[f64; 2]; 3]>,
    /// `[w, x, y, z]` of the rotation at the box's midpoint (projected onto rotations); `None`
    /// for a link that spins freely between two ball joints.
    pub quaternion: Option<[f64; 4]>,
    /// The largest width of an entry of the rotation matrix over the box: how far the
    /// quaternion may be off.
    pub rotation_width: Option<f64>,
}

/// How a free joint of a spatial linkage moves in the system's unknowns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum JointMotion {
    /// Its own angle, `c = cos θ`, `s = sin θ` (a revolute tree joint, one Euler angle).
    Angle { c: VarId, s: VarId },
    /// Its own variable (a travel, a floating joint's coordinate).
    Var(VarId),
    /// A loop joint: its value is read from the closure frames' relative pose.
    Loop,
}

/// A spatial linkage as a polynomial system, with what is needed to read answers back.
#[derive(Clone, Debug)]
pub struct SpatialProblem {
    /// The system to solve.
    pub system: EquationSystem,
    /// Robot name.
    pub name: String,
    /// Joint values (tree and loop) read from each box, in file order; multi-motion joints get
    /// one entry per motion (`J.yaw`, `J.pitch`, `J.roll`, `J.x`…, `L.travel`).
    pub free_joints: Vec<String>,
    /// Joints fixed by the user, with their values.
    pub fixed_joints: Vec<(String, f64)>,
    /// Traced points.
    pub traces: Vec<Trace3>,
    /// What the builder simplified, one line each (legs reduced to distances).
    pub reductions: Vec<String>,
    groups: Vec<RotF>,
    links: Vec<LinkPlace>,
    loops: Vec<Option<LoopFrames>>,
    readings: Vec<(String, Reading)>,
    limits: Vec<(usize, Interval, Interval)>,
    /// Axis closures written with two of their three rows: the third component of both axes,
    /// which must agree in sign (see `axes_agree`).
    signs: Vec<(Form, Form)>,
    /// The same closures, for their velocity rows (`axis_velocities`).
    axis_pairs: Vec<AxisPair>,
}

/// A leg between two ball joints, reduced to a distance.
#[derive(Clone, Debug)]
struct Leg {
    /// The loop closing it.
    closure: usize,
    /// The spherical tree joint at its first ball.
    joint: usize,
    /// Squared length `|u|² + 2(u·w)d + d²` pieces: `u`, `w` and the travel.
    u: IVec3,
    w: IVec3,
    travel: Option<Travel>,
    /// The links it covers.
    links: Vec<usize>,
}

#[derive(Clone, Copy, Debug)]
enum Travel {
    Known(Interval),
    Var(VarId),
}

struct Builder {
    /// Building to judge whether loops can close at all (then a constant row that cannot hold
    /// is bad input, not an answer).
    check_closure: bool,
    system: EquationSystem,
    groups: Vec<RotF>,
    products: BTreeMap<(VarId, VarId), VarId>,
    /// Shared `n = Σ x²` variables, by their sorted variables.
    norms: BTreeMap<Vec<VarId>, VarId>,
    /// Equations that are not closures (definitions), by index.
    definitions: Vec<usize>,
    /// Magnitudes of the constant rows taken as identities (`VANISHING`), in order.
    vanished: Vec<f64>,
}

/// A closure row left with no unknown whose constant encloses 0 and lies within this (metres,
/// or unitless for axis rows) is an identity of the stated geometry, not a constraint: the same
/// written coordinates reached by two paths (a spherical linkage's centre off the origin,
/// ground joints sharing a z), whose difference interval arithmetic cannot cancel (x − x over
/// an interval is not 0). Kept, such a row makes the system non-square and no assembly is ever
/// certified. 1e-12 is a thousand times the rounding of metre-sized coordinates and far below
/// any gap a designer means; a gap beyond it, or a constant that excludes 0, stays a row, which
/// the search refutes (the loops cannot close as written).
const VANISHING: f64 = 1e-12;

impl Builder {
    fn define(&mut self, e: Equation) {
        self.definitions.push(self.system.equations.len());
        self.system.add(e);
    }

    fn initial(&self, f: &Form) -> Interval {
        f.eval(&self.system.initial_box().dims)
    }

    /// A derived variable equal to `f` (`f` itself when it is one variable).
    fn name_form(&mut self, f: &Form, name: &str, clamp: Option<Interval>) -> Form {
        let f = f.merged();
        if f.terms.len() <= 1 {
            return f;
        }
        let mut dom = self.initial(&f);
        if let Some(c) = clamp {
            dom = dom.intersection(c);
        }
        let v = self.system.add_var(name.to_string(), VarRole::Derived, dom);
        let mut terms: Vec<Term> = f.terms.iter().map(|&(x, c)| Term { coef: c, mono: Monomial::Linear(x) }).collect();
        terms.push(Term { coef: point(-1.0), mono: Monomial::Linear(v) });
        self.define(Equation::new(terms, f.constant));
        Form::var(v)
    }

    fn product(&mut self, x: VarId, y: VarId) -> VarId {
        let key = (x.min(y), x.max(y));
        if let Some(&z) = self.products.get(&key) {
            return z;
        }
        let dom = self.system.vars[x].domain * self.system.vars[y].domain;
        let name = format!("{}*{}", self.system.vars[x].name, self.system.vars[y].name);
        let z = self.system.add_var(name, VarRole::Derived, dom);
        self.define(Equation::bilinear(z, x, y));
        self.products.insert(key, z);
        z
    }

    /// `f·x`, distributed over `f`'s terms (each product a bilinear variable).
    fn times_var(&mut self, f: &Form, x: VarId) -> Form {
        let f = f.merged();
        let mut out = Form { terms: vec![(x, f.constant)], constant: point(0.0) };
        if f.constant.inf() == 0.0 && f.constant.sup() == 0.0 {
            out.terms.clear();
        }
        for &(v, c) in &f.terms {
            let z = self.product(v, x);
            out.terms.push((z, c));
        }
        out
    }

    /// `f·g` for two forms: named first when they have several terms, so one product each.
    fn times_form(&mut self, f: &Form, g: &Form, names: (&str, &str)) -> Form {
        let (f, g) = (f.merged(), g.merged());
        if f.terms.is_empty() {
            return g.scaled(f.constant);
        }
        if g.terms.is_empty() {
            return f.scaled(g.constant);
        }
        let f = self.name_form(&f, names.0, None);
        let g = self.name_form(&g, names.1, None);
        // (k1 + a x)(k2 + b y) = k1 k2 + k1 b y + k2 a x + a b xy
        let (x, a) = f.terms[0];
        let (y, b) = g.terms[0];
        let mut out = Form::constant(f.constant * g.constant);
        out.add(&Form { terms: vec![(y, f.constant * b), (x, g.constant * a)], constant: point(0.0) });
        let xy = if x == y {
            // x·x: a bilinear product needs two variables, so x gets a named copy.
            let copy = self.system.add_var(format!("{}'", self.system.vars[x].name), VarRole::Derived, self.system.vars[x].domain);
            self.define(Equation::new(vec![Term { coef: point(1.0), mono: Monomial::Linear(copy) }, Term { coef: point(-1.0), mono: Monomial::Linear(x) }], point(0.0)));
            self.product(x, copy)
        } else {
            self.product(x, y)
        };
        out.terms.push((xy, a * b));
        out.merged()
    }

    /// `M·Rot(a, θ)` with `θ` given by `(c, s)`: `M aaᵀ + c·M(I − aaᵀ) + s·M[a]×`. Entries of
    /// `M` with several terms are named first, so each entry costs one product with `c` and
    /// one with `s`.
    fn rot_by(&mut self, m: &RotF, a: &IVec3, c: VarId, s: VarId, tag: &str) -> RotF {
        let (aat, rest, skew) = rodrigues_parts(a);
        let needed = |k: usize| (0..3).any(|j| !is_zero(rest[k][j]) || !is_zero(skew[k][j]));
        let mut named = m.clone();
        for (i, row) in named.iter_mut().enumerate() {
            for (k, e) in row.iter_mut().enumerate() {
                if needed(k) {
                    *e = self.name_form(e, &format!("R{i}{k}_{tag}"), Some(interval(-1.0, 1.0)));
                }
            }
        }
        let fixed = rot_times(&named, &aat);
        let pc = rot_times(&named, &rest);
        let ps = rot_times(&named, &skew);
        let mut out = fixed;
        for i in 0..3 {
            for j in 0..3 {
                let a = self.times_var(&pc[i][j], c);
                let b = self.times_var(&ps[i][j], s);
                out[i][j].add(&a);
                out[i][j].add(&b);
                out[i][j] = out[i][j].merged();
            }
        }
        out
    }

    fn new_group(&mut self, g: RotF) -> usize {
        self.groups.push(g);
        self.groups.len() - 1
    }

    /// `Σ G_g·v_g + rest` as forms.
    fn forms(&self, p: &Pos) -> Vec3F {
        let mut out = p.rest.clone();
        for (&g, v) in &p.by_group() {
            let f = rot_apply(&self.groups[g], v);
            for i in 0..3 {
                out[i].add(&f[i]);
            }
        }
        out.map(|f| f.merged())
    }

    /// `a = b` row by row; `Err` when a row has no unknown and cannot hold.
    fn equal(&mut self, a: &Vec3F, b: &Vec3F, rows: &mut Vec<usize>) -> Result<(), Interval> {
        for f in sub3(a, b) {
            self.zero(&f, rows)?;
        }
        Ok(())
    }

    fn zero(&mut self, f: &Form, rows: &mut Vec<usize>) -> Result<(), Interval> {
        let f = f.merged();
        if f.terms.is_empty() {
            return self.constant_row(f.constant, rows);
        }
        let terms = f.terms.iter().map(|&(v, c)| Term { coef: c, mono: Monomial::Linear(v) }).collect();
        rows.push(self.system.equations.len());
        self.system.add(Equation::new(terms, f.constant));
        Ok(())
    }

    /// `|D|² − L² = 0` for `D = B − A`, with `|G·v|² = |v|²` per group (exact on solutions).
    fn distance(&mut self, d: &Pos, length2: (Interval, Option<(Interval, VarId)>), tag: &str, rows: &mut Vec<usize>) -> Result<(), Interval> {
        let groups = d.by_group();
        let rotated: Vec<(usize, Vec3F)> = groups.iter().map(|(&g, v)| (g, rot_apply(&self.groups[g], v))).collect();
        let mut lin = Form::constant(-length2.0);
        let mut squares: Vec<Term> = Vec::new();
        if let Some((k, dv)) = length2.1 {
            // L² = c0 + k·d + d²
            lin.terms.push((dv, -k));
            squares.push(Term { coef: point(-1.0), mono: Monomial::Square(dv) });
        }
        for v in groups.values() {
            lin.constant = lin.constant + v[0].sqr() + v[1].sqr() + v[2].sqr();
        }
        let two = point(2.0);
        for a in 0..rotated.len() {
            for b in a + 1..rotated.len() {
                for i in 0..3 {
                    let p = self.times_form(&rotated[a].1[i].clone(), &rotated[b].1[i].clone(), (&format!("u{i}_{tag}_{a}"), &format!("u{i}_{tag}_{b}")));
                    lin.add_scaled(&p, two);
                }
            }
        }
        for (k, (_, r)) in rotated.iter().enumerate() {
            for (i, (ri, wi)) in r.iter().zip(&d.rest).enumerate() {
                let p = self.times_form(ri, wi, (&format!("u{i}_{tag}_{k}"), &format!("w{i}_{tag}")));
                lin.add_scaled(&p, two);
            }
        }
        // Squares of the linear part: one per coordinate that holds unknowns.
        let mut wsq: Vec<(VarId, Interval)> = Vec::new();
        for i in 0..3 {
            let w = d.rest[i].merged();
            match w.terms.as_slice() {
                [] => lin.constant += w.constant.sqr(),
                [(x, a)] => {
                    wsq.push((*x, a.sqr()));
                    lin.terms.push((*x, two * *a * w.constant));
                    lin.constant += w.constant.sqr();
                }
                _ => {
                    let n = self.name_form(&w, &format!("w{i}_{tag}"), None);
                    wsq.push((n.terms[0].0, point(1.0)));
                }
            }
        }
        // Several legs ending on one translating body share the same |x|² (a platform's
        // position, a guide's travels): one derived variable `n = Σ x²` (the only row the LP
        // cannot use), so that every leg row is linear.
        let unit = |c: Interval| c.inf() == 1.0 && c.sup() == 1.0;
        if wsq.len() >= 2 && wsq.iter().all(|&(_, c)| unit(c)) {
            let mut key: Vec<VarId> = wsq.iter().map(|&(x, _)| x).collect();
            key.sort_unstable();
            let n = match self.norms.get(&key) {
                Some(&n) => n,
                None => {
                    let dom = key.iter().fold(point(0.0), |acc, &x| acc + self.system.vars[x].domain.sqr());
                    let names: Vec<&str> = key.iter().map(|&x| self.system.vars[x].name.as_str()).collect();
                    let n = self.system.add_var(format!("|{}|^2", names.join(",")), VarRole::Derived, dom);
                    let mut terms: Vec<Term> = key.iter().map(|&x| Term { coef: point(1.0), mono: Monomial::Square(x) }).collect();
                    terms.push(Term { coef: point(-1.0), mono: Monomial::Linear(n) });
                    self.define(Equation::new(terms, point(0.0)));
                    self.norms.insert(key, n);
                    n
                }
            };
            lin.terms.push((n, point(1.0)));
        } else {
            squares.extend(wsq.iter().map(|&(x, c)| Term { coef: c, mono: Monomial::Square(x) }));
        }
        let lin = lin.merged();
        let mut terms: Vec<Term> = lin.terms.iter().map(|&(v, c)| Term { coef: c, mono: Monomial::Linear(v) }).collect();
        terms.extend(squares);
        if terms.is_empty() {
            return self.constant_row(lin.constant, rows);
        }
        rows.push(self.system.equations.len());
        self.system.add(Equation::new(terms, lin.constant));
        Ok(())
    }

    /// A row with no unknown left (`--fix` values, or geometry such as the z rows of a planar
    /// mechanism). Exactly zero: an identity, dropped. Otherwise it stays an equation, so the
    /// solver refutes it (no configuration) or keeps it, and Newton cannot certify a closure
    /// that rounding cannot confirm (as the planar builder does); when judging closure alone,
    /// one that cannot hold is bad input.
    fn constant_row(&mut self, k: Interval, rows: &mut Vec<usize>) -> Result<(), Interval> {
        if is_zero(k) {
            return Ok(());
        }
        if k.contains(0.0) && k.mag() <= VANISHING {
            self.vanished.push(k.mag());
            return Ok(());
        }
        if self.check_closure && !k.contains(0.0) {
            return Err(k);
        }
        rows.push(self.system.equations.len());
        self.system.add(Equation::new(Vec::new(), k));
        Ok(())
    }
}

/// Two unit axes `u` (predecessor) and `v` (successor) coincide: two constraints, written as
/// two rows so that a closure adds as many equations as it removes freedoms (and Krawczyk can
/// certify isolated assemblies). The row left out is the component `i` largest at rest (`w`);
/// with `|u| = |v| = 1` the two rows give `u_i = ±v_i`, and the mirror `u_i = −v_i ≠ 0` is
/// removed by the sign filter (`SignFilter`): a box where they have opposite signs holds no
/// closure; a box is certified only where they provably share one. When the three rows are
/// identities or constants (planar axes), they are written as they are.
fn axes_agree(b: &mut Builder, u: &Vec3F, v: &Vec3F, w: Vector3<f64>, rows: &mut Vec<usize>, signs: &mut Vec<(Form, Form)>, pairs: &mut Vec<AxisPair>) -> Result<(), Interval> {
    let diff = sub3(u, v);
    if diff.iter().all(|f| f.terms.is_empty()) {
        for f in &diff {
            b.zero(f, rows)?;
        }
        return Ok(());
    }
    let i = (0..3).max_by(|&a, &c| w[a].abs().total_cmp(&w[c].abs())).expect("three components");
    let first = rows.len();
    for (k, f) in diff.iter().enumerate() {
        if k != i {
            b.zero(f, rows)?;
        }
    }
    signs.push((u[i].clone(), v[i].clone()));
    pairs.push(AxisPair { u: u.clone().map(|f| f.merged()), diff: diff.clone(), rows: rows[first..].to_vec() });
    Ok(())
}

/// An axis closure written with two rows, kept for its velocities: the predecessor's axis `u`,
/// `u − v` per component, and the equations written.
#[derive(Clone, Debug)]
struct AxisPair {
    u: Vec3F,
    diff: Vec3F,
    rows: Vec<usize>,
}

/// A linear form `Σ a·x + constant` over the system's variables.
pub(crate) type LinearForm = (Vec<(VarId, Interval)>, Interval);

/// What the velocity rows of an axis closure written with two rows need: with `|u| = |v| = 1`
/// and `u = v`, the derivative `δ = d/dt (u − v)` is orthogonal to `u`, so its three rows have
/// rank two everywhere on the closure (the two rows written lose rank where the component left
/// out vanishes); `δ = ν·u` with one more unknown `ν` is square and forces `ν = u·δ = 0`.
#[derive(Clone, Debug)]
pub(crate) struct AxisVelocity {
    /// The predecessor's axis, per component.
    pub u: [LinearForm; 3],
    /// `u − v`, per component.
    pub diff: [LinearForm; 3],
    /// The equations (indices) written for this closure.
    pub rows: Vec<usize>,
}

fn e_mentions(m: Monomial, v: VarId) -> bool {
    match m {
        Monomial::Linear(x) | Monomial::Square(x) => x == v,
        Monomial::Product(x, y) => x == v || y == v,
    }
}

/// The report line of the rows of loop `name` taken as identities (`VANISHING`), if any.
fn vanished_note(name: &str, magnitudes: &[f64]) -> Option<String> {
    let largest = magnitudes.iter().copied().fold(0.0, f64::max);
    (!magnitudes.is_empty()).then(|| format!("loop '{name}': {} closure row(s) left with no unknown, constant within {largest:.1e} of 0 (the same stated values reached by two paths): taken as identities", magnitudes.len()))
}

fn is_zero(x: Interval) -> bool {
    x.inf() == 0.0 && x.sup() == 0.0
}

/// The bounding box on the unit circle of the arc of angles `arc` (sound cos and sin).
fn arc_box(arc: Interval) -> (Interval, Interval) {
    let unit = interval(-1.0, 1.0);
    (trig::cos(arc).intersection(unit), trig::sin(arc).intersection(unit))
}

fn imat_t(a: &IMat3) -> IMat3 {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| a[j][i]))
}

/// Two unit vectors completing `a` to an orthonormal frame.
fn across(a: &Vector3<f64>) -> [Vector3<f64>; 2] {
    let helper = if a.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    let e1 = (helper - a * a.dot(&helper)).normalize();
    [e1, a.cross(&e1)]
}

impl SpatialProblem {
    /// Builds the spatial system of `m`, with `fixed` joint values and traced points
    /// `(link, [x, y, z])` in the link's frame.
    pub fn new(m: &Mechanism, fixed: &[(String, f64)], traces: &[(String, [f64; 3], String)]) -> Result<Self, LinkageError> {
        if let Some(j) = m.joints.iter().find(|j| j.mimic.is_some() && j.kind != JointKind::Fixed) {
            let leader = j.mimic.as_ref().map_or("", |x| x.joint.as_str());
            return Err(LinkageError::Mimic { joint: j.name.clone(), leader: leader.to_string() });
        }
        if m.loops.is_empty() {
            return Err(LinkageError::NoLoops);
        }
        // Whether a loop can close is a property of the geometry: judged with every joint
        // free and no limits (as the planar builder does).
        let limited = m.joints.iter().any(|j| matches!(j.kind, JointKind::Revolute { limits: Some(_) }));
        if fixed.is_empty() && !limited {
            return Self::build(m, fixed, traces, true, true);
        }
        Self::build(m, &[], &[], false, true)?;
        Self::build(m, fixed, traces, true, false)
    }

    fn build(m: &Mechanism, fixed: &[(String, f64)], traces: &[(String, [f64; 3], String)], respect_limits: bool, check_closure: bool) -> Result<Self, LinkageError> {
        let n_links = m.links.len();
        // --fix
        let mut fixed_tree: BTreeMap<usize, f64> = BTreeMap::new();
        let mut fixed_loop: BTreeMap<usize, f64> = BTreeMap::new();
        for (name, value) in fixed {
            if !value.is_finite() {
                return Err(LinkageError::NotFinite(name.clone()));
            }
            let (kind, compound, tree, slot) = if let Some(j) = m.joint(name) {
                (m.joints[j].kind, None, true, j)
            } else if let Some(l) = m.loops.iter().position(|l| &l.name == name) {
                (m.loops[l].kind, m.loops[l].compound, false, l)
            } else {
                return Err(LinkageError::UnknownJoint(name.clone()));
            };
            let limits = match (kind, compound) {
                (JointKind::Spherical, _) => return Err(LinkageError::NotOneValue(name.clone(), "ball")),
                (JointKind::Floating, _) => return Err(LinkageError::NotOneValue(name.clone(), "floating")),
                (JointKind::Fixed, _) | (_, Some(_)) => return Err(LinkageError::NotMovable(name.clone())),
                (JointKind::Revolute { limits }, None) => {
                    if reduce(stated(*value)).is_none() {
                        return Err(LinkageError::TooManyTurns { joint: name.clone(), value: *value });
                    }
                    limits
                }
                (JointKind::Prismatic { limits }, None) => Some(limits),
            };
            if let Some((lower, upper)) = limits {
                if *value < lower || *value > upper {
                    return Err(LinkageError::OutsideLimits { joint: name.clone(), value: *value, lower, upper });
                }
            }
            if tree { fixed_tree.insert(slot, *value) } else { fixed_loop.insert(slot, *value) };
        }

        // Which links each loop touches, children per link, traced links.
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); n_links];
        for (j, joint) in m.joints.iter().enumerate() {
            children[joint.parent].push(j);
        }
        let touching = |l: usize| -> Vec<usize> { (0..m.loops.len()).filter(|&k| m.loops[k].predecessor == l || m.loops[k].successor == l).collect() };
        let traced: Vec<usize> = traces.iter().filter_map(|(n, _, _)| m.link(n)).collect();

        // Legs between two ball joints: a link on a spherical tree joint with one spherical
        // closure (a rod), or with one prismatic child whose link has it (a leg).
        let mut legs: Vec<Leg> = Vec::new();
        let mut in_leg = vec![false; n_links];
        for (j, joint) in m.joints.iter().enumerate() {
            if joint.kind != JointKind::Spherical {
                continue;
            }
            let l = joint.child;
            let side = |k: usize, link: usize| {
                let lp = &m.loops[k];
                if lp.predecessor == link { (lp.predecessor_origin.translation.vector, lp.successor) } else { (lp.successor_origin.translation.vector, lp.predecessor) }
            };
            let ball = |k: usize| m.loops[k].kind == JointKind::Spherical && m.loops[k].compound.is_none();
            let free_of_traces = |x: usize| !traced.contains(&x);
            let (tl, kids) = (touching(l), &children[l]);
            // A rod with whatever is welded to it (frames such as a tool or marker link on
            // fixed joints): every descendant welded, one ball closure on any of them.
            let mut welded = vec![(l, st::identity(), [point(0.0); 3])];
            let mut all_fixed = true;
            let mut at = 0;
            while at < welded.len() {
                let (x, rot, pos) = welded[at];
                for &cj in &children[x] {
                    let c = &m.joints[cj];
                    if c.kind != JointKind::Fixed {
                        all_fixed = false;
                        continue;
                    }
                    let t = st::apply(&rot, &st::translation(&c.origin.translation.vector));
                    welded.push((c.child, imat_mul(&rot, &st::rpy(c.rpy)), [0, 1, 2].map(|i| pos[i] + t[i])));
                }
                at += 1;
            }
            let closures: Vec<usize> = welded.iter().flat_map(|&(x, _, _)| touching(x)).collect();
            if all_fixed && closures.len() == 1 && ball(closures[0]) && welded.iter().all(|&(x, _, _)| free_of_traces(x)) {
                let k = closures[0];
                let lp = &m.loops[k];
                let &(x, rot, pos) = welded.iter().find(|&&(x, _, _)| lp.predecessor == x || lp.successor == x).expect("the closure touches a welded link");
                let (t, _) = side(k, x);
                let tt = st::apply(&rot, &st::translation(&t));
                let u = [0, 1, 2].map(|i| pos[i] + tt[i]);
                legs.push(Leg { closure: k, joint: j, u, w: [point(0.0); 3], travel: Some(Travel::Known(point(0.0))), links: welded.iter().map(|&(x, _, _)| x).collect() });
                for &(x, _, _) in &welded {
                    in_leg[x] = true;
                }
                continue;
            }
            if let ([pj], true) = (kids.as_slice(), tl.is_empty()) {
                let pjoint = &m.joints[*pj];
                let rod = pjoint.child;
                let tr = touching(rod);
                if let (JointKind::Prismatic { limits }, true, [k]) = (pjoint.kind, children[rod].is_empty(), tr.as_slice()) {
                    if ball(*k) && free_of_traces(l) && free_of_traces(rod) {
                        let (t, _) = side(*k, rod);
                        let o = st::rpy(pjoint.rpy);
                        let ot = st::apply(&o, &st::translation(&t));
                        let tj = st::translation(&pjoint.origin.translation.vector);
                        let u = [0, 1, 2].map(|i| tj[i] + ot[i]);
                        let w = st::apply(&o, &st::axis(&pjoint.axis));
                        let _ = limits;
                        legs.push(Leg { closure: *k, joint: j, u, w, travel: None, links: vec![l, rod] });
                        in_leg[l] = true;
                        in_leg[rod] = true;
                    }
                }
            }
        }

        // Multi-motion joints that no loop constrains are refused: their links would sweep
        // a whole region of poses.
        let mut on_loop = vec![false; n_links];
        for lp in &m.loops {
            for end in [lp.predecessor, lp.successor] {
                let mut at = end;
                on_loop[at] = true;
                while let Some(j) = m.links[at].parent_joint {
                    at = m.joints[j].parent;
                    on_loop[at] = true;
                }
            }
        }
        for joint in &m.joints {
            let multi = matches!(joint.kind, JointKind::Spherical | JointKind::Floating);
            if multi && !on_loop[joint.child] {
                return Err(LinkageError::UnderConstrained(format!("joint '{}' is {} and no loop passes through link '{}': its orientation is free", joint.name, if joint.kind == JointKind::Spherical { "spherical" } else { "floating" }, m.links[joint.child].name)));
            }
            if joint.kind == JointKind::Spherical && !in_leg[joint.child] {
                let l = joint.child;
                let tl = touching(l);
                if children[l].is_empty() && tl.len() == 1 && m.loops[tl[0]].kind == JointKind::Spherical {
                    return Err(LinkageError::UnderConstrained(format!(
                        "link '{}' spins freely about the line through its two ball joints ('{}' and loop '{}'); a traced point on it has no determined position",
                        m.links[l].name, joint.name, m.loops[tl[0]].name
                    )));
                }
            }
        }

        let mut b = Builder { check_closure, system: EquationSystem::default(), groups: vec![const_rot(&st::identity())], products: BTreeMap::new(), norms: BTreeMap::new(), definitions: Vec::new(), vanished: Vec::new() };
        let mut order: Vec<usize> = (0..n_links).collect();
        order.sort_by_key(|&l| m.path_to(l).len());

        // Reach: every frame of the mechanism lies within the sum of all its offsets and
        // travels from the root (any link is reached from the root through tree joints and
        // closures), which bounds floating positions.
        let mut reach = 0.0f64;
        for j in &m.joints {
            reach += j.origin.translation.vector.norm() * (1.0 + 1e-9);
            if let JointKind::Prismatic { limits: (lo, hi) } = j.kind {
                reach += lo.abs().max(hi.abs()) * (1.0 + 1e-9);
            }
        }
        for l in &m.loops {
            reach += (l.predecessor_origin.translation.vector.norm() + l.successor_origin.translation.vector.norm()) * (1.0 + 1e-9);
            if let JointKind::Prismatic { limits: (lo, hi) } = l.kind {
                reach += lo.abs().max(hi.abs()) * (1.0 + 1e-9);
            }
        }
        let reach = reach + 1.0;

        let mut places: Vec<LinkPlace> = m.links.iter().map(|l| LinkPlace { name: l.name.clone(), rotation: None, position: None }).collect();
        places[m.root] = LinkPlace { name: m.links[m.root].name.clone(), rotation: Some((0, st::identity())), position: Some(Pos::origin()) };
        let mut readings: Vec<(String, Reading)> = Vec::new();
        let mut free_joints = Vec::new();
        let mut limit_list = Vec::new();
        let mut leg_travel: BTreeMap<usize, Travel> = BTreeMap::new();
        let travel_domain = |(lo, hi): (f64, f64)| interval(stated(lo).inf(), stated(hi).sup());
        let mut reductions = Vec::new();
        let mut floating: Vec<(usize, [VarId; 3])> = Vec::new();

        for &l in &order {
            let Some(j) = m.links[l].parent_joint else { continue };
            let joint = &m.joints[j];
            let parent = joint.parent;
            let o = st::rpy(joint.rpy);
            let t = st::translation(&joint.origin.translation.vector);
            let a = st::axis(&joint.axis);
            // A leg's rod: its travel is the leg's, and it has no place of its own.
            // A link welded to a rod between two balls: its pose is as undetermined as the rod's.
            if in_leg[l] && joint.kind == JointKind::Fixed {
                continue;
            }
            if let (true, JointKind::Prismatic { limits }) = (in_leg[l], joint.kind) {
                let tv = match fixed_tree.get(&j) {
                    Some(&v) => Travel::Known(stated(v)),
                    None => {
                        let v = b.system.add_var(format!("d_{}", joint.name), VarRole::Primary, travel_domain(limits));
                        readings.push((joint.name.clone(), Reading::Var(v)));
                        free_joints.push(joint.name.clone());
                        Travel::Var(v)
                    }
                };
                leg_travel.insert(j, tv);
                continue;
            }
            let (Some((g, k)), Some(ppos)) = (places[parent].rotation, places[parent].position.clone()) else {
                return Err(LinkageError::Unsupported(format!("joint '{}' hangs on link '{}', whose pose a ball-jointed leg leaves undetermined", joint.name, m.links[parent].name)));
            };
            let mut at = ppos.clone();
            at.add_rotated(g, st::apply(&k, &t));
            let ko = imat_mul(&k, &o);
            let name = &joint.name;
            match joint.kind {
                JointKind::Fixed => {
                    places[l].rotation = Some((g, ko));
                    places[l].position = Some(at);
                }
                JointKind::Revolute { limits } => {
                    if let Some(&v) = fixed_tree.get(&j) {
                        places[l].rotation = Some((g, imat_mul(&ko, &rot_about(&a, v))));
                    } else {
                        let (mut dc, mut ds) = (interval(-1.0, 1.0), interval(-1.0, 1.0));
                        if let (Some((lo, hi)), true) = (limits, respect_limits) {
                            (dc, ds) = arc_box(stated(lo).convex_hull(stated(hi)));
                            limit_list.push((readings.len(), stated(lo), stated(hi)));
                        }
                        let c = b.system.add_var(format!("cos_{name}"), VarRole::Primary, dc);
                        let s = b.system.add_var(format!("sin_{name}"), VarRole::Primary, ds);
                        b.define(Equation::circle(c, s));
                        let mo = rot_times(&b.groups[g], &ko);
                        let gr = b.rot_by(&mo, &a, c, s, name);
                        let ng = b.new_group(gr);
                        places[l].rotation = Some((ng, st::identity()));
                        readings.push((name.clone(), Reading::Angle { c, s }));
                        free_joints.push(name.clone());
                    }
                    places[l].position = Some(at);
                }
                JointKind::Prismatic { limits } => {
                    places[l].rotation = Some((g, ko));
                    let w = st::apply(&ko, &a);
                    match fixed_tree.get(&j) {
                        Some(&v) => at.add_rotated(g, w.map(|x| x * stated(v))),
                        None => {
                            let d = b.system.add_var(format!("d_{name}"), VarRole::Primary, travel_domain(limits));
                            if g == 0 {
                                for (r, wi) in at.rest.iter_mut().zip(w) {
                                    r.add(&Form { terms: vec![(d, wi)], constant: point(0.0) });
                                }
                            } else {
                                let dir = rot_apply(&b.groups[g], &w);
                                for (r, di) in at.rest.iter_mut().zip(&dir) {
                                    let f = b.times_var(di, d);
                                    r.add(&f);
                                }
                            }
                            readings.push((name.clone(), Reading::Var(d)));
                            free_joints.push(name.clone());
                        }
                    }
                    places[l].position = Some(at);
                }
                JointKind::Spherical if in_leg[l] => {
                    // The first ball of a leg: its centre is known, its spin is not.
                    places[l].position = Some(at);
                }
                JointKind::Spherical | JointKind::Floating => {
                    let mut gr = rot_times(&b.groups[g], &ko);
                    if joint.kind == JointKind::Floating {
                        // The pose is free: position and rotation in the root frame.
                        gr = const_rot(&st::identity());
                        at = Pos::origin();
                        let mut vars = [0; 3];
                        for (i, axis) in ["x", "y", "z"].iter().enumerate() {
                            let v = b.system.add_var(format!("{name}.{axis}"), VarRole::Primary, interval(-reach, reach));
                            at.rest[i] = Form::var(v);
                            readings.push((format!("{name}.{axis}"), Reading::Var(v)));
                            free_joints.push(format!("{name}.{axis}"));
                            vars[i] = v;
                        }
                        floating.push((l, vars));
                    }
                    let z = point(0.0);
                    let o1 = point(1.0);
                    for (part, axis, dc) in [("yaw", [z, z, o1], interval(-1.0, 1.0)), ("pitch", [z, o1, z], interval(0.0, 1.0)), ("roll", [o1, z, z], interval(-1.0, 1.0))] {
                        let c = b.system.add_var(format!("cos_{name}.{part}"), VarRole::Primary, dc);
                        let s = b.system.add_var(format!("sin_{name}.{part}"), VarRole::Primary, interval(-1.0, 1.0));
                        b.define(Equation::circle(c, s));
                        gr = b.rot_by(&gr, &axis, c, s, &format!("{name}.{part}"));
                        readings.push((format!("{name}.{part}"), Reading::Angle { c, s }));
                        free_joints.push(format!("{name}.{part}"));
                    }
                    let ng = b.new_group(gr);
                    places[l].rotation = Some((ng, st::identity()));
                    places[l].position = Some(at);
                }
            }
        }

        // A floating link closed by a leg lies within the leg's reach of the leg's first ball:
        // |p| ≤ |A| + max |u + d·w| + |t| (t: the ball on the floating link), a far tighter box
        // than the sum of every offset in the file.
        for &(f, vars) in &floating {
            let start = b.system.initial_box();
            let mut r = reach;
            for leg in &legs {
                let lp = &m.loops[leg.closure];
                let other = if leg.links.contains(&lp.predecessor) { lp.successor } else { lp.predecessor };
                if other != f {
                    continue;
                }
                let t = if lp.predecessor == f { lp.predecessor_origin.translation.vector } else { lp.successor_origin.translation.vector };
                let Some(apos) = places[m.joints[leg.joint].child].position.clone() else { continue };
                let a = b.forms(&apos).map(|x| x.eval(&start.dims));
                let na = (a[0].sqr() + a[1].sqr() + a[2].sqr()).sqrt().sup();
                let nu = (leg.u[0].sqr() + leg.u[1].sqr() + leg.u[2].sqr()).sqrt().sup();
                let travel = leg.travel.or_else(|| leg.links.get(1).and_then(|&rod| m.links[rod].parent_joint).and_then(|pj| leg_travel.get(&pj).copied()));
                let nd = match travel {
                    Some(Travel::Known(v)) => v.mag(),
                    Some(Travel::Var(v)) => b.system.vars[v].domain.mag(),
                    None => 0.0,
                };
                // w is a unit vector: |u + d·w| ≤ |u| + |d|; sums rounded up by a relative margin.
                r = r.min((na + nu + nd + t.norm()) * (1.0 + 1e-12) + 1e-12);
            }
            for v in vars {
                b.system.vars[v].domain = interval(-r, r);
            }
        }

        // Closures.
        // Rest orientation of every link (all joint values zero), to pick which axis row a
        // revolute closure can do without.
        let mut rest = vec![UnitQuaternion::identity(); n_links];
        for &l in &order {
            if let Some(j) = m.links[l].parent_joint {
                rest[l] = rest[m.joints[j].parent] * m.joints[j].origin.rotation;
            }
        }
        let mut signs: Vec<(Form, Form)> = Vec::new();
        let mut axis_pairs: Vec<AxisPair> = Vec::new();
        let mut loop_rows: Vec<(String, Vec<usize>)> = Vec::new();
        let mut frames: Vec<Option<LoopFrames>> = vec![None; m.loops.len()];
        let leg_of: BTreeMap<usize, &Leg> = legs.iter().map(|leg| (leg.closure, leg)).collect();
        for (k, lp) in m.loops.iter().enumerate() {
            let mut rows = Vec::new();
            let vanished_before = b.vanished.len();
            // A closure row left with no unknown, its constant excluding 0: the chains miss each
            // other by that much whatever the joint values.
            let cannot = |k: Interval| LinkageError::Gap { name: lp.name.clone(), lower: k.inf(), upper: k.sup() };
            if let Some(leg) = leg_of.get(&k) {
                // |B − A|² = |u + d·w|² = |u|² + 2(u·w)d + d²
                let joint = &m.joints[leg.joint];
                let other = if leg.links.contains(&lp.predecessor) { lp.successor } else { lp.predecessor };
                let (Some((go, ko)), Some(po)) = (places[other].rotation, places[other].position.clone()) else {
                    return Err(LinkageError::UnderConstrained(format!("loop '{}' joins two legs that spin between ball joints", lp.name)));
                };
                let t_other = if lp.predecessor == other { st::translation(&lp.predecessor_origin.translation.vector) } else { st::translation(&lp.successor_origin.translation.vector) };
                let mut bpos = po;
                bpos.add_rotated(go, st::apply(&ko, &t_other));
                let apos = places[joint.child].position.clone().expect("a leg's first ball is placed");
                let d = bpos.minus(&apos);
                let u = leg.u;
                let uu = u[0].sqr() + u[1].sqr() + u[2].sqr();
                let uw2 = point(2.0) * (u[0] * leg.w[0] + u[1] * leg.w[1] + u[2] * leg.w[2]);
                let travel = leg.travel.or_else(|| leg.links.get(1).and_then(|&rod| m.links[rod].parent_joint).and_then(|pj| leg_travel.get(&pj).copied()));
                let length2 = match travel {
                    Some(Travel::Known(v)) => (uu + uw2 * v + v.sqr(), None),
                    Some(Travel::Var(dv)) => (uu, Some((uw2, dv))),
                    None => (uu, None),
                };
                b.distance(&d, length2, &lp.name, &mut rows).map_err(cannot)?;
                let names: Vec<&str> = leg.links.iter().map(|&x| m.links[x].name.as_str()).collect();
                reductions.push(format!("{} (ball joints '{}' and '{}'): a distance constraint, no rotation", names.join(" + "), joint.name, lp.name));
                reductions.extend(vanished_note(&lp.name, &b.vanished[vanished_before..]));
                loop_rows.push((lp.name.clone(), rows));
                continue;
            }
            let side = |link: usize, origin: &nalgebra::Isometry3<f64>, rpy: [f64; 3]| -> Result<((usize, IMat3), Pos), LinkageError> {
                let (Some((g, kk)), Some(p)) = (places[link].rotation, places[link].position.clone()) else {
                    return Err(LinkageError::UnderConstrained(format!("loop '{}' closes on link '{}', which spins between two ball joints", lp.name, m.links[link].name)));
                };
                let mut at = p;
                at.add_rotated(g, st::apply(&kk, &st::translation(&origin.translation.vector)));
                Ok(((g, imat_mul(&kk, &st::rpy(rpy))), at))
            };
            let (fp, pp) = side(lp.predecessor, &lp.predecessor_origin, lp.predecessor_rpy)?;
            let (fs, ps) = side(lp.successor, &lp.successor_origin, lp.successor_rpy)?;
            let a = st::axis(&lp.axis);
            let rp = rot_times(&b.groups[fp.0], &fp.1);
            let rs = rot_times(&b.groups[fs.0], &fs.1);
            let (pf, sf) = (b.forms(&pp), b.forms(&ps));
            let col = |r: &RotF, j: usize| -> Vec3F { [r[0][j].clone(), r[1][j].clone(), r[2][j].clone()] };
            let axis_p = rot_apply(&rp, &a);
            let axis_s = rot_apply(&rs, &a);
            let fixed_value = fixed_loop.get(&k).copied();
            let mut travel_var = None;
            match (lp.kind, lp.compound) {
                (JointKind::Spherical, _) => b.equal(&pf, &sf, &mut rows).map_err(cannot)?,
                (JointKind::Fixed, _) => {
                    b.equal(&pf, &sf, &mut rows).map_err(cannot)?;
                    for j in 0..2 {
                        b.equal(&col(&rp, j), &col(&rs, j), &mut rows).map_err(cannot)?;
                    }
                }
                (JointKind::Revolute { .. }, Some(Compound::Universal { axis2 })) => {
                    b.equal(&pf, &sf, &mut rows).map_err(cannot)?;
                    let a2 = rot_apply(&rs, &st::axis(&axis2));
                    let mut dot = Form::zero();
                    for i in 0..3 {
                        let p = b.times_form(&axis_p[i], &a2[i], (&format!("axis{i}_{}", lp.name), &format!("axis2{i}_{}", lp.name)));
                        dot.add(&p);
                    }
                    b.zero(&dot, &mut rows).map_err(cannot)?;
                }
                (JointKind::Revolute { limits }, _) => {
                    b.equal(&pf, &sf, &mut rows).map_err(cannot)?;
                    match fixed_value {
                        Some(v) => {
                            let turned = rot_times(&rp, &rot_about(&a, v));
                            for j in 0..2 {
                                b.equal(&col(&turned, j), &col(&rs, j), &mut rows).map_err(cannot)?;
                            }
                        }
                        None => {
                            let w = rest[lp.predecessor] * (lp.predecessor_origin.rotation * lp.axis);
                            axes_agree(&mut b, &axis_p, &axis_s, w, &mut rows, &mut signs, &mut axis_pairs).map_err(cannot)?;
                            if let (Some((lo, hi)), true) = (limits, respect_limits) {
                                limit_list.push((readings.len(), stated(lo), stated(hi)));
                            }
                            readings.push((lp.name.clone(), Reading::LoopAngle(k)));
                            free_joints.push(lp.name.clone());
                        }
                    }
                }
                (JointKind::Prismatic { limits }, compound) => {
                    let cylindrical = compound == Some(Compound::Cylindrical);
                    if cylindrical {
                        let w = rest[lp.predecessor] * (lp.predecessor_origin.rotation * lp.axis);
                        axes_agree(&mut b, &axis_p, &axis_s, w, &mut rows, &mut signs, &mut axis_pairs).map_err(cannot)?;
                    } else {
                        for j in 0..2 {
                            b.equal(&col(&rp, j), &col(&rs, j), &mut rows).map_err(cannot)?;
                        }
                    }
                    // succ − pred = d·(axis in the world)
                    let mut target = pf.clone();
                    match fixed_value {
                        Some(v) => {
                            for i in 0..3 {
                                target[i].add_scaled(&axis_p[i], stated(v));
                            }
                        }
                        None => {
                            let d = b.system.add_var(format!("d_{}", lp.name), VarRole::Primary, travel_domain(limits));
                            for i in 0..3 {
                                let f = b.times_var(&axis_p[i], d);
                                target[i].add(&f);
                            }
                            travel_var = Some(d);
                        }
                    }
                    b.equal(&target, &sf, &mut rows).map_err(cannot)?;
                    if cylindrical {
                        readings.push((lp.name.clone(), Reading::LoopAngle(k)));
                        free_joints.push(lp.name.clone());
                    }
                    if travel_var.is_some() {
                        let label = if cylindrical { format!("{}.travel", lp.name) } else { lp.name.clone() };
                        readings.push((label.clone(), Reading::LoopTravel(k)));
                        free_joints.push(label);
                    }
                }
                (JointKind::Floating, _) => return Err(LinkageError::Unsupported(format!("loop '{}' is floating: it constrains nothing", lp.name))),
            }
            frames[k] = Some(LoopFrames { pred: fp, succ: fs, pred_at: pp, succ_at: ps, axis: a, across: across(&lp.axis) });
            reductions.extend(vanished_note(&lp.name, &b.vanished[vanished_before..]));
            loop_rows.push((lp.name.clone(), rows));
        }

        // Traced points.
        let mut trace_out = Vec::new();
        for (link_name, xyz, label) in traces {
            let link = m.link(link_name).ok_or_else(|| LinkageError::UnknownTraceLink(link_name.clone()))?;
            let (Some((g, kk)), Some(p)) = (places[link].rotation, places[link].position.clone()) else {
                return Err(LinkageError::UnderConstrained(format!("--trace {label}: link '{link_name}' spins between two ball joints")));
            };
            let mut at = p;
            at.add_rotated(g, st::apply(&kk, &xyz.map(stated)));
            let f = b.forms(&at);
            let mut vars = [0; 3];
            for (i, axis) in ["x", "y", "z"].iter().enumerate() {
                let dom = b.initial(&f[i]);
                let v = b.system.add_var(format!("{axis}_{label}"), VarRole::Derived, dom);
                let mut e = f[i].clone();
                e.terms.push((v, point(-1.0)));
                let e = e.merged();
                let terms = e.terms.iter().map(|&(x, c)| Term { coef: c, mono: Monomial::Linear(x) }).collect();
                b.define(Equation::new(terms, e.constant));
                vars[i] = v;
            }
            trace_out.push(Trace3 { name: label.clone(), xyz: vars });
        }

        if check_closure {
            let start = b.system.initial_box();
            for (name, rows) in &loop_rows {
                let mut sub = EquationSystem { vars: b.system.vars.clone(), equations: rows.iter().map(|&r| b.system.equations[r].clone()).collect() };
                sub.equations.extend(b.definitions.iter().map(|&r| b.system.equations[r].clone()));
                let mut probe = start.clone();
                if Propagation::new(&sub).contract(&mut probe) == Contraction::Empty {
                    return Err(LinkageError::CannotClose(name.clone()));
                }
            }
        }

        Ok(Self {
            system: b.system,
            name: m.name.clone(),
            free_joints,
            fixed_joints: fixed.to_vec(),
            traces: trace_out,
            reductions,
            groups: b.groups,
            links: places,
            loops: frames,
            readings,
            limits: limit_list,
            signs,
            axis_pairs,
        })
    }

    fn eval_rot(&self, g: usize, k: &IMat3, b: &[Interval]) -> IMat3 {
        let r = [0, 1, 2].map(|i| [0, 1, 2].map(|j| self.groups[g][i][j].eval(b)));
        st::mul(&r, k)
    }

    fn eval_pos(&self, p: &Pos, b: &[Interval]) -> IVec3 {
        let mut out = [0, 1, 2].map(|i| p.rest[i].eval(b));
        for (&g, v) in &p.by_group() {
            let r = [0, 1, 2].map(|i| [0, 1, 2].map(|j| self.groups[g][i][j].eval(b)));
            for (o, x) in out.iter_mut().zip(st::apply(&r, v)) {
                *o += x;
            }
        }
        out
    }

    fn reading(&self, r: &Reading, b: &IntervalBox) -> Interval {
        let d = &b.dims;
        match *r {
            Reading::Angle { c, s } => wrap(angles::angle_interval(d[c], d[s])),
            Reading::Var(v) => d[v],
            Reading::LoopAngle(k) => {
                let Some(f) = &self.loops[k] else { return interval(-std::f64::consts::PI, std::f64::consts::PI) };
                // Q = F_pᵀ F_s = Rot(a, ψ): cos ψ = e1ᵀQe1, sin ψ = e2ᵀQe1.
                let q = st::mul(&imat_t(&self.eval_rot(f.pred.0, &f.pred.1, d)), &self.eval_rot(f.succ.0, &f.succ.1, d));
                let [e1, e2] = f.across;
                let e1i = [e1.x, e1.y, e1.z].map(point);
                let e2i = [e2.x, e2.y, e2.z].map(point);
                let qe1 = st::apply(&q, &e1i);
                // e1, e2 are orthonormal to the axis only to rounding: widen by that.
                let slack = interval(-1e-12, 1e-12);
                let c = (0..3).fold(point(0.0), |acc, i| acc + e1i[i] * qe1[i]) + slack;
                let s = (0..3).fold(point(0.0), |acc, i| acc + e2i[i] * qe1[i]) + slack;
                wrap(angles::angle_interval(c, s))
            }
            Reading::LoopTravel(k) => {
                let Some(f) = &self.loops[k] else { return Interval::ENTIRE };
                let rp = self.eval_rot(f.pred.0, &f.pred.1, d);
                let diff = {
                    let (s, p) = (self.eval_pos(&f.succ_at, d), self.eval_pos(&f.pred_at, d));
                    [0, 1, 2].map(|i| s[i] - p[i])
                };
                let local = st::apply_transposed(&rp, &diff);
                (0..3).fold(point(0.0), |acc, i| acc + f.axis[i] * local[i])
            }
        }
    }

    /// Values of the free joints over the box (radians or metres), keyed by name; outward
    /// rounded.
    pub fn joint_values(&self, b: &IntervalBox) -> BTreeMap<String, (f64, f64)> {
        self.readings.iter().map(|(name, r)| {
            let x = self.reading(r, b);
            (name.clone(), (x.inf(), x.sup()))
        }).collect()
    }

    /// Every link's pose over the box, keyed by link name.
    pub fn link_poses(&self, b: &IntervalBox) -> BTreeMap<String, LinkPose> {
        self.link_poses_of(b, |_| true)
    }

    /// `link_poses` of the links `keep` names only (the others are not computed).
    pub fn link_poses_of(&self, b: &IntervalBox, keep: impl Fn(&str) -> bool) -> BTreeMap<String, LinkPose> {
        let d = &b.dims;
        self.links
            .iter()
            .filter(|place| keep(&place.name))
            .map(|place| {
                let position = place.position.as_ref().map(|p| self.eval_pos(p, d).map(|x| [x.inf(), x.sup()]));
                let (quaternion, rotation_width) = match place.rotation {
                    Some((g, k)) => {
                        let r = self.eval_rot(g, &k, d);
                        let mid = Matrix3::from_fn(|i, j| r[i][j].mid());
                        let width = r.iter().flatten().map(|x| x.wid()).fold(0.0, f64::max);
                        let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(&mid));
                        (Some([q.w, q.i, q.j, q.k]), Some(width))
                    }
                    None => (None, None),
                };
                (place.name.clone(), LinkPose { position, quaternion, rotation_width })
            })
            .collect()
    }

    /// Where the box lies against the limits of the limited revolute joints and loops, and
    /// against the sign agreement of the axis closures written with two rows.
    pub fn limit_verdict(&self, b: &IntervalBox) -> Inclusion {
        let mut verdict = Inclusion::Inside;
        for (u, v) in &self.signs {
            let (u, v) = (u.eval(&b.dims), v.eval(&b.dims));
            if (u.sup() < 0.0 && v.inf() > 0.0) || (u.inf() > 0.0 && v.sup() < 0.0) {
                return Inclusion::Outside;
            }
            if !((u.inf() > 0.0 && v.inf() > 0.0) || (u.sup() < 0.0 && v.sup() < 0.0)) {
                verdict = Inclusion::Straddles;
            }
        }
        for &(k, lower, upper) in &self.limits {
            verdict = verdict.and(against_limits(self.reading(&self.readings[k].1, b), lower, upper));
            if verdict == Inclusion::Outside {
                return verdict;
            }
        }
        verdict
    }

    /// How a free joint moves in the system's unknowns: its own angle `(c, s)` or variable
    /// (tree joints), or a loop joint whose value is read from its closure frames; `None` for a
    /// name that is not a free joint. The singular-set builder takes the rates of the first two.
    pub(crate) fn joint_motion(&self, name: &str) -> Option<JointMotion> {
        let (_, r) = self.readings.iter().find(|(n, _)| n == name)?;
        Some(match *r {
            Reading::Angle { c, s } => JointMotion::Angle { c, s },
            Reading::Var(v) => JointMotion::Var(v),
            Reading::LoopAngle(_) | Reading::LoopTravel(_) => JointMotion::Loop,
        })
    }

    /// The axis closures written with two rows, for faithful velocity rows (see
    /// `AxisVelocity`).
    pub(crate) fn axis_velocities(&self) -> Vec<AxisVelocity> {
        let linear = |f: &Form| -> LinearForm { (f.merged().terms, f.constant) };
        self.axis_pairs.iter().map(|p| AxisVelocity { u: [0, 1, 2].map(|i| linear(&p.u[i])), diff: [0, 1, 2].map(|i| linear(&p.diff[i])), rows: p.rows.clone() }).collect()
    }

    /// True when some axis closure written with two rows may have its left-out component at
    /// zero in `b` (configuration variables first): there the two rows lose rank where the
    /// three would not (the mirror branch the sign filter removes meets the true one).
    pub(crate) fn axis_rows_may_degenerate(&self, b: &IntervalBox) -> bool {
        self.signs.iter().any(|(u, v)| u.eval(&b.dims).contains(0.0) || v.eval(&b.dims).contains(0.0))
    }

    /// A solver for `system`, which extends this problem's system (its first variables are
    /// this problem's, as in the singular-set systems), with the joint-limit and sign filters
    /// of `solver`.
    pub fn extended_solver<'s>(&'s self, system: &'s EquationSystem, settings: SolverSettings) -> Result<Solver<'s>, SolveError> {
        debug_assert!(system.vars.len() >= self.system.vars.len());
        let solver = Solver::new(system, settings)?;
        if self.limits.is_empty() && self.signs.is_empty() {
            return Ok(solver);
        }
        Ok(solver.with_contractor(Box::new(move |system, settings| {
            Box::new(Filtered { inner: default_contractor(system, settings), filters: vec![Box::new(move |b: &IntervalBox| self.limit_verdict(b))] })
        })))
    }

    /// A solver for this problem: the default pipeline, plus a joint-limit filter when joints
    /// carry limits (it sees every box, certified ones included).
    pub fn solver(&self, settings: SolverSettings) -> Result<Solver<'_>, SolveError> {
        self.extended_solver(&self.system, settings)
    }

    /// Fills the derived variables of a point whose primaries are set (the others NaN), from
    /// their defining equations (each derived variable appears linearly in one, after the
    /// variables it depends on): for tests and references. `false` when some stay unknown.
    pub fn complete_point(&self, x: &mut [f64]) -> bool {
        loop {
            let mut progress = false;
            for e in &self.system.equations {
                let unknown: Vec<VarId> = {
                    let mut v: Vec<VarId> = e.vars().filter(|&v| x[v].is_nan()).collect();
                    v.dedup();
                    v
                };
                let [v] = unknown.as_slice() else { continue };
                let Some(coef) = e.terms.iter().find(|t| t.mono == Monomial::Linear(*v)).map(|t| t.coef.mid()) else { continue };
                if e.terms.iter().any(|t| t.mono != Monomial::Linear(*v) && e_mentions(t.mono, *v)) {
                    continue;
                }
                x[*v] = 0.0;
                x[*v] = -e.residual(x) / coef;
                progress = true;
            }
            if !progress {
                return x.iter().all(|v| !v.is_nan());
            }
        }
    }

    /// True when the system has as many equations as unknowns, so that interval Newton can
    /// certify isolated assemblies.
    pub fn is_square(&self) -> bool {
        self.system.equations.len() == self.system.vars.len()
    }

    /// How many equations are quadratics the LP relaxation does not use (distance rows).
    pub fn quadratic_rows(&self) -> usize {
        self.system.equations.iter().filter(|e| e.kind == EquationKind::Quadratic).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rodrigues_encloses_the_rotation() {
        let a = Vector3::new(1.0, 2.0, -0.5).normalize();
        let r = rot_about(&st::axis(&a), 0.7);
        let want = Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(a), 0.7);
        for i in 0..3 {
            for j in 0..3 {
                assert!(r[i][j].inf() - 1e-14 <= want[(i, j)] && want[(i, j)] <= r[i][j].sup() + 1e-14);
            }
        }
    }

    #[test]
    fn across_completes_an_orthonormal_frame() {
        for a in [Vector3::z(), Vector3::x(), Vector3::new(0.3, -0.4, 0.5).normalize()] {
            let [e1, e2] = across(&a);
            assert!(e1.dot(&a).abs() < 1e-15 && e2.dot(&a).abs() < 1e-15 && (e1.norm() - 1.0).abs() < 1e-15 && (e2.norm() - 1.0).abs() < 1e-15);
        }
    }
}

//! Platforms on six fixed legs (general 6-6 Gough–Stewart, or any six legs) as a distance
//! problem in the style of Porta, Thomas, Ros and Torras (2003): the unknowns are squared distances
//! between base and platform ball centres and signed heights, the rows Cayley–Menger conditions and
//! bilateration identities; no pose variable.
//!
//! Three legs `0, 1, 2` form the frame: base ball centres `B0, B1, B2` (a triangle) and platform
//! ball centres `P0, P1, P2` (a triangle), chosen to make the smaller of the two triangles as
//! large as possible. Leg i fixes `r(Pi, Bi) = Li²`; the other six squared distances
//! `r(Pi, Bj)` (i ≠ j) and the signed heights `hi` of `Pi` above the plane `B0 B1 B2` are the
//! primaries. In the base frame, with `x = P − B0`, `e1 = B1 − B0`, `e2 = B2 − B0`,
//! `N = e1 × e2`, a point's three squared distances to the base triangle and its height place it
//! linearly (trilateration with the sign kept):
//!
//! `x = ((r0 − r1 + |e1|²)/2 · (e2 × N) + (r0 − r2 + |e2|²)/2 · (N × e1)) / |N|² + h · N/|N|`.
//!
//! Each frame point's coordinates `ai, bi, hi` along the base triangle's orthonormal frame
//! (`f1` along `e1`, `f2` in the plane, `f3` its normal) are derived by linear rows (`hi` is the
//! primary itself). The rows:
//! - per frame point, the Cayley–Menger condition of the tetrahedron `B0 B1 B2 Pi`,
//!   `Ξ(B0, B1, B2, Pi) = 288 V² = 8 |N|² hi²` (Porta et al. 2003, Eq. 3), written as
//!   `ai² + bi² + hi² = r(Pi, B0)` (the same polynomial over `8|N|²`);
//! - the platform triangle's sides, `r(Pi, B0) + r(Pj, B0) − 2 xi·xj = r(Pi, Pj)` from the file;
//! - the platform triangle's normal `n = d1 × d2` with `d1 = x1 − x0`, `d2 = x2 − x0`;
//! - each other leg k by bilateration from the platform triangle: its platform point is
//!   `Pk = Σ wi Pi + γ n` with the weights `wi` (summing to one) and `γ` of the file's platform
//!   (the orientation is the file's: no mirror image of the platform is a solution), so
//!   `r(Pk, Bk) = Σ wi r(Pi, Bk) − Σ_{i<j} wi wj r(Pi, Pj) + γ² |n|² + 2γ n·(x0 − (Bk − B0))`,
//!   with `r(Pi, Bk) = r(Pi, B0) − 2 xi·(Bk − B0) + |Bk − B0|²`: linear in the primaries and `n`
//!   but for `n·x0`.
//!
//! Every product of two variables is a derived variable with its own row (bilinear rows, which
//! the LP relaxes by McCormick planes, and `z = x²`), so the twelve rows above are linear in
//! them, and the system stays square (one row per variable): Krawczyk certifies.
//! Measured against the pose model (README, "Platforms as distances"): the same certified
//! assemblies, more boxes and a larger LP per box.
//!
//! Every coefficient encloses the stated model (`pose::six_legs`: ball centres and leg values
//! as stated decimals), outward-rounded interval arithmetic. A box is read back as the
//! platform's pose: `R = [x1 − x0, x2 − x0, n] · [q1 − q0, q2 − q0, m]⁻¹` (the `q` in the platform
//! frame, `m` their normal) and `t = B0 + x0 − R q0`, enclosed over the box.

use super::platform::PlatformError;
use super::pose::{joint_values_of, link_pose_of, pose_of, six_legs, PoseLeg, SixLegs};
use super::stated::{IMat3, IVec3};
use crate::kernel::interval::{interval, point, Interval, IntervalBox};
use crate::model::Mechanism;
use crate::kernel::search::{SolveError, Solver, SolverSettings};
use crate::kernel::system::{Equation, EquationSystem, Monomial, Term, VarId, VarRole};
use std::collections::BTreeMap;

/// A six-legged platform with its legs fixed, as a square system over squared distances and
/// signed heights.
#[derive(Clone, Debug)]
pub struct BilaterationProblem {
    /// The robot's name.
    pub name: String,
    /// Name of the platform link.
    pub platform: String,
    /// The legs, in file order.
    pub legs: Vec<PoseLeg>,
    /// The frame legs (indices into `legs`): their base and platform points span the triangles.
    pub frame: [usize; 3],
    /// Joint values as given (`--fix`).
    pub fixed: Vec<(String, f64)>,
    /// The system.
    pub system: EquationSystem,
    /// Free joints, as reported: the floating joint's position and roll, pitch, yaw.
    pub free_joints: Vec<String>,
    /// Per frame point, the coordinates of `P − B0` along `f1`, `f2`, `f3` (variables).
    coordinates: [[VarId; 3]; 3],
    /// The platform triangle's normal along `f1`, `f2`, `f3` (derived variables).
    normal: [VarId; 3],
    /// The base triangle's orthonormal frame `f1, f2, f3` (columns: base-frame vectors).
    frame_axes: [IVec3; 3],
    /// Rows of `[q1 − q0, q2 − q0, m]⁻¹` (platform frame).
    platform_inverse: [IVec3; 3],
    /// The base's frame in the root frame, when fixed joints hold it below the root.
    base_in_root: Option<Box<(IMat3, IVec3)>>,
}

fn sub(a: &IVec3, b: &IVec3) -> IVec3 {
    [0, 1, 2].map(|k| a[k] - b[k])
}

fn dot(a: &IVec3, b: &IVec3) -> Interval {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: &IVec3, b: &IVec3) -> IVec3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn scale(c: Interval, a: &IVec3) -> IVec3 {
    a.map(|x| c * x)
}

/// The rows of the inverse of the matrix with columns `a`, `b`, `a × b`: the dual basis
/// `(b × c, c × a, c) / |c|²` with `c = a × b` (its determinant is `|c|²`).
fn dual_basis(a: &IVec3, b: &IVec3) -> [IVec3; 3] {
    let c = cross(a, b);
    let det = dot(&c, &c);
    [scale(det.recip(), &cross(b, &c)), scale(det.recip(), &cross(&c, a)), scale(det.recip(), &c)]
}

fn area2(a: &IVec3, b: &IVec3, c: &IVec3) -> f64 {
    let n = cross(&sub(b, a), &sub(c, a));
    dot(&n, &n).mid()
}

/// The frame: the three legs whose smaller triangle (base or platform) is the largest.
fn choose_frame(legs: &[PoseLeg]) -> Result<[usize; 3], PlatformError> {
    let mut best: Option<([usize; 3], f64)> = None;
    for a in 0..6 {
        for b in a + 1..6 {
            for c in b + 1..6 {
                let size = area2(&legs[a].base, &legs[b].base, &legs[c].base).min(area2(&legs[a].top, &legs[b].top, &legs[c].top));
                if best.is_none_or(|(_, s)| size > s) {
                    best = Some(([a, b, c], size));
                }
            }
        }
    }
    let (frame, size) = best.expect("six legs");
    if !(size > 0.0) {
        return Err(PlatformError::Unsupported("no three legs span a triangle on both the base and the platform: the distance model needs one".into()));
    }
    Ok(frame)
}

/// The base triangle's orthonormal frame: `f1` along `e1 = B1 − B0`, `f2` in the plane toward
/// `e2 = B2 − B0`, `f3 = f1 × f2`, with the lengths trilateration divides by.
#[derive(Clone, Copy)]
struct BaseFrame {
    e2: IVec3,
    e1_len: Interval,
    /// `e2·f1`.
    along: Interval,
    /// `|e2 − (e2·f1) f1|`.
    e2_perp_len: Interval,
    f1: IVec3,
    f2: IVec3,
    f3: IVec3,
}

impl BaseFrame {
    fn new(base: &[IVec3; 3]) -> Result<Self, PlatformError> {
        let (e1, e2) = (sub(&base[1], &base[0]), sub(&base[2], &base[0]));
        let e1_len = dot(&e1, &e1).sqrt();
        let f1 = scale(e1_len.recip(), &e1);
        let along = dot(&e2, &f1);
        let e2_perp = sub(&e2, &scale(along, &f1));
        let e2_perp_len = dot(&e2_perp, &e2_perp).sqrt();
        if !(e2_perp_len.inf() > 0.0) {
            return Err(PlatformError::Unsupported("the frame's base points are collinear".into()));
        }
        let f2 = scale(e2_perp_len.recip(), &e2_perp);
        let f3 = cross(&f1, &f2);
        Ok(Self { e2, e1_len, along, e2_perp_len, f1, f2, f3 })
    }
}

/// A squared distance: the leg's, known, or a variable.
#[derive(Clone, Copy)]
enum Squared {
    Known(Interval),
    Unknown(VarId),
}

/// A row under construction: linear terms, products of two variables (each becomes one derived
/// variable with its own row, shared between rows), and a constant; `= 0`.
struct Row {
    linear: BTreeMap<VarId, Interval>,
    products: BTreeMap<(VarId, VarId), Interval>,
    constant: Interval,
}

impl Row {
    fn new() -> Self {
        Self { linear: BTreeMap::new(), products: BTreeMap::new(), constant: point(0.0) }
    }

    fn var(&mut self, v: VarId, c: Interval) {
        *self.linear.entry(v).or_insert(point(0.0)) += c;
    }

    fn squared(&mut self, r: Squared, c: Interval) {
        match r {
            Squared::Known(x) => self.constant += c * x,
            Squared::Unknown(v) => self.var(v, c),
        }
    }

    fn product(&mut self, x: VarId, y: VarId, c: Interval) {
        *self.products.entry((x.min(y), x.max(y))).or_insert(point(0.0)) += c;
    }
}

/// The system and its derived products.
struct Rows {
    system: EquationSystem,
    products: BTreeMap<(VarId, VarId), VarId>,
}

impl Rows {
    /// The derived variable `x·y` (or `x²`), with its row, shared between rows.
    fn product(&mut self, x: VarId, y: VarId) -> VarId {
        if let Some(&z) = self.products.get(&(x, y)) {
            return z;
        }
        let (nx, ny) = (self.system.vars[x].name.clone(), self.system.vars[y].name.clone());
        let (dx, dy) = (self.system.vars[x].domain, self.system.vars[y].domain);
        let (name, dom, row) = if x == y {
            (format!("{nx}^2"), dx.sqr(), None)
        } else {
            (format!("{nx}*{ny}"), dx * dy, Some(()))
        };
        let z = self.system.add_var(name, VarRole::Derived, dom);
        self.system.add(match row {
            // z = x·y: a bilinear row, which the LP relaxes by McCormick planes.
            Some(()) => Equation::bilinear(z, x, y),
            None => Equation::new(vec![Term { coef: point(1.0), mono: Monomial::Linear(z) }, Term { coef: point(-1.0), mono: Monomial::Square(x) }], point(0.0)),
        });
        self.products.insert((x, y), z);
        z
    }

    /// Adds `row = 0`, products replaced by their derived variables (terms that cancel exactly
    /// are dropped).
    fn add(&mut self, row: Row) {
        let mut linear = row.linear;
        for ((x, y), c) in row.products {
            if c.inf() == 0.0 && c.sup() == 0.0 {
                continue;
            }
            let z = self.product(x, y);
            *linear.entry(z).or_insert(point(0.0)) += c;
        }
        let terms = linear.into_iter().filter(|(_, c)| !(c.inf() == 0.0 && c.sup() == 0.0)).map(|(v, c)| Term { coef: c, mono: Monomial::Linear(v) }).collect();
        self.system.add(Equation::new(terms, row.constant));
    }

    /// The primaries of the frame points: squared distances `r(Pi, Bj)` (the leg's own known),
    /// and signed heights `hi` above the base triangle.
    fn frame_unknowns(&mut self, squared: &[Interval; 3], base: &[IVec3; 3]) -> ([[Squared; 3]; 3], [VarId; 3]) {
        // Squared distances r(Pi, Bj): Bj's distance to Bi bounds them (triangle inequality).
        let mut r = [[Squared::Known(point(0.0)); 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                if i == j {
                    r[i][j] = Squared::Known(squared[i]);
                    continue;
                }
                let leg = squared[i].sqrt();
                let apart = dot(&sub(&base[i], &base[j]), &sub(&base[i], &base[j])).sqrt();
                let (lo, hi) = ((leg - apart).inf().max(0.0), (leg + apart).sup());
                r[i][j] = Squared::Unknown(self.system.add_var(format!("r(P{i},B{j})"), VarRole::Primary, interval(lo, hi).sqr()));
            }
        }
        // Signed heights above the base triangle: at most the leg's length.
        let h: [VarId; 3] = [0, 1, 2].map(|i| {
            let reach = squared[i].sqrt().sup();
            self.system.add_var(format!("h{i}"), VarRole::Primary, interval(-reach, reach))
        });
        (r, h)
    }

    /// Each frame point's coordinates `ai, bi, hi` along `f1, f2, f3`: `ai`, `bi` derived by
    /// trilateration rows, `hi` the height itself.
    fn frame_coordinates(&mut self, r: &[[Squared; 3]; 3], h: &[VarId; 3], bf: &BaseFrame) -> [[VarId; 3]; 3] {
        let BaseFrame { e2, e1_len, along, e2_perp_len, .. } = *bf;
        let (one, two) = (point(1.0), point(2.0));
        // In-plane coordinates by trilateration: x·e1 = (r0 − r1 + |e1|²)/2, x·e2 likewise.
        let value = |s: Squared, b: &[Interval]| match s {
            Squared::Known(x) => x,
            Squared::Unknown(v) => b[v],
        };
        let mut coordinates = [[0; 3]; 3];
        for i in 0..3 {
            let start = self.system.initial_box();
            let (r0, r1, r2) = (value(r[i][0], &start.dims), value(r[i][1], &start.dims), value(r[i][2], &start.dims));
            let a_dom = (r0 - r1 + e1_len.sqr()) / (two * e1_len);
            let a = self.system.add_var(format!("a{i}"), VarRole::Derived, a_dom);
            let mut row = Row::new();
            row.var(a, one);
            row.squared(r[i][0], -(two * e1_len).recip());
            row.squared(r[i][1], (two * e1_len).recip());
            row.constant -= e1_len / two;
            self.add(row);
            // x·f2 = (x·e2 − (e2·f1)·a) / |e2⊥|.
            let b_dom = ((r0 - r2 + dot(&e2, &e2)) / two - along * a_dom) / e2_perp_len;
            let b = self.system.add_var(format!("b{i}"), VarRole::Derived, b_dom);
            let mut row = Row::new();
            row.var(b, e2_perp_len);
            row.squared(r[i][0], -one / two);
            row.squared(r[i][2], one / two);
            row.constant -= dot(&e2, &e2) / two;
            row.var(a, along);
            self.add(row);
            coordinates[i] = [a, b, h[i]];
        }
        coordinates
    }
}

impl BilaterationProblem {
    /// Reads the platform of `m` with every leg fixed by `fixed` (leg name, its value as for
    /// `solve --fix`: the prismatic joint's travel, metres).
    pub fn new(m: &Mechanism, fixed: &[(String, f64)]) -> Result<Self, PlatformError> {
        let SixLegs { platform, floating, legs, base_in_root } = six_legs(m, fixed, "the distance model")?;
        let frame = choose_frame(&legs)?;
        let base = frame.map(|i| legs[i].base);
        let top = frame.map(|i| legs[i].top);
        let squared = frame.map(|i| legs[i].squared);
        let bf = BaseFrame::new(&base)?;
        let BaseFrame { f1, f2, f3, .. } = bf;
        let (one, two) = (point(1.0), point(2.0));

        let mut w = Rows { system: EquationSystem::default(), products: BTreeMap::new() };
        let (r, h) = w.frame_unknowns(&squared, &base);
        let coordinates = w.frame_coordinates(&r, &h, &bf);
        let x = coordinates;
        let pside = |i: usize, j: usize| dot(&sub(&top[i], &top[j]), &sub(&top[i], &top[j]));
        // Tetrahedra B0 B1 B2 Pi (Cayley–Menger): |x_i|² = r(Pi, B0).
        for (i, xi) in x.iter().enumerate() {
            let mut row = Row::new();
            for &v in xi {
                row.product(v, v, one);
            }
            row.squared(r[i][0], -one);
            w.add(row);
        }
        // The platform triangle's sides d1 = x1 − x0, d2 = x2 − x0 (derived, each component at
        // most the side's length).
        let sides: [[VarId; 3]; 2] = [1, 2].map(|i| {
            let length = pside(0, i).sqrt().sup();
            [0, 1, 2].map(|c| {
                let dom = (w.system.vars[x[i][c]].domain - w.system.vars[x[0][c]].domain).intersection(interval(-length, length));
                let d = w.system.add_var(format!("d{i}{}", c + 1), VarRole::Derived, dom);
                let mut row = Row::new();
                row.var(d, one);
                row.var(x[i][c], -one);
                row.var(x[0][c], one);
                w.add(row);
                d
            })
        });
        // The sides' rows on the frame points: r(Pi, B0) + r(Pj, B0) − 2 x_i·x_j = r(Pi, Pj).
        for i in 0..3 {
            for j in i + 1..3 {
                let mut row = Row::new();
                row.squared(r[i][0], one);
                row.squared(r[j][0], one);
                for (&u, &v) in x[i].iter().zip(&x[j]) {
                    row.product(u, v, -two);
                }
                row.constant -= pside(i, j);
                w.add(row);
            }
        }
        // The platform triangle's normal n = d1 × d2, in the base triangle's frame.
        let (qa, qb) = (sub(&top[1], &top[0]), sub(&top[2], &top[0]));
        let m_normal = cross(&qa, &qb);
        let m2 = dot(&m_normal, &m_normal);
        let m_len = m2.sqrt().sup();
        let normal = ["1", "2", "3"].map(|a| w.system.add_var(format!("n{a}"), VarRole::Derived, interval(-m_len, m_len)));
        for (c, &nc) in normal.iter().enumerate() {
            let (p, q) = ((c + 1) % 3, (c + 2) % 3);
            let mut row = Row::new();
            row.var(nc, one);
            row.product(sides[0][p], sides[1][q], -one);
            row.product(sides[0][q], sides[1][p], one);
            w.add(row);
        }
        // The other legs, by bilateration from the platform triangle.
        let platform_inverse = dual_basis(&qa, &qb);
        for (k, leg) in legs.iter().enumerate() {
            if frame.contains(&k) {
                continue;
            }
            let rel = sub(&leg.top, &top[0]);
            let (alpha, beta, gamma) = (dot(&platform_inverse[0], &rel), dot(&platform_inverse[1], &rel), dot(&platform_inverse[2], &rel));
            let weights = [one - alpha - beta, alpha, beta];
            let ek = sub(&leg.base, &base[0]);
            let ek_local = [dot(&ek, &f1), dot(&ek, &f2), dot(&ek, &f3)];
            let mut row = Row::new();
            row.constant = dot(&ek, &ek) - leg.squared + gamma.sqr() * m2;
            for i in 0..3 {
                // r(Pi, Bk) = r(Pi, B0) − 2 x_i·e_k + |e_k|² (the |e_k|² terms sum to one weight).
                row.squared(r[i][0], weights[i]);
                for c in 0..3 {
                    row.var(x[i][c], -two * weights[i] * ek_local[c]);
                }
                for j in i + 1..3 {
                    row.constant -= weights[i] * weights[j] * pside(i, j);
                }
            }
            // 2γ n·(x0 − e_k).
            for c in 0..3 {
                row.product(normal[c], x[0][c], two * gamma);
                row.var(normal[c], -two * gamma * ek_local[c]);
            }
            w.add(row);
        }
        let free_joints = ["x", "y", "z", "roll", "pitch", "yaw"].iter().map(|p| format!("{floating}.{p}")).collect();
        Ok(Self {
            name: m.name.clone(),
            platform: m.links[platform].name.clone(),
            legs,
            frame,
            fixed: fixed.to_vec(),
            system: w.system,
            free_joints,
            coordinates,
            normal,
            frame_axes: [f1, f2, f3],
            platform_inverse,
            base_in_root: base_in_root.map(Box::new),
        })
    }

    /// The solver: the kernel's default pipeline (propagation, Krawczyk on the square system,
    /// LP shrink).
    pub fn solver(&self, settings: SolverSettings) -> Result<Solver<'_>, SolveError> {
        Solver::new(&self.system, settings)
    }

    /// Enclosures of the platform's position and rotation over the box.
    fn placement(&self, b: &IntervalBox) -> ([Interval; 3], [[Interval; 3]; 3]) {
        let world = |local: [Interval; 3]| -> IVec3 { [0, 1, 2].map(|k| (0..3).fold(point(0.0), |acc, c| acc + local[c] * self.frame_axes[c][k])) };
        let x: [IVec3; 3] = self.coordinates.map(|p| world(p.map(|v| b.dims[v])));
        let cols = [sub(&x[1], &x[0]), sub(&x[2], &x[0]), world(self.normal.map(|v| b.dims[v]))];
        let r: [[Interval; 3]; 3] = [0, 1, 2].map(|i| [0, 1, 2].map(|j| (0..3).fold(point(0.0), |acc, k| acc + cols[k][i] * self.platform_inverse[k][j])));
        let b0 = self.legs[self.frame[0]].base;
        let q0 = self.legs[self.frame[0]].top;
        let t = [0, 1, 2].map(|i| b0[i] + x[0][i] - (r[i][0] * q0[0] + r[i][1] * q0[1] + r[i][2] * q0[2]));
        (t, r)
    }

    /// The floating joint's values over the box (position, roll, pitch, yaw; as the pose model).
    pub fn joint_values(&self, b: &IntervalBox) -> BTreeMap<String, (f64, f64)> {
        let (t, r) = self.placement(b);
        joint_values_of(&self.free_joints, t, &r)
    }

    /// The platform's pose at the box midpoint, as the pose model reports it.
    pub fn pose(&self, b: &IntervalBox) -> super::Pose {
        let (t, r) = self.placement(b);
        pose_of(&self.legs, t, &r)
    }

    /// The platform link's pose over the box, as the spatial model reports link poses.
    pub fn link_pose(&self, b: &IntervalBox) -> super::LinkPose {
        let (t, r) = self.placement(b);
        link_pose_of(&self.legs, t, &r, self.base_in_root.as_deref())
    }
}

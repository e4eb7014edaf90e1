//! `Builder`: the one place that adds variables and equations to a spatial system. It names
//! forms by derived variables, shares bilinear products and squared norms, and writes closure
//! rows (`equal`, `zero`, `distance`), deciding what a row left with no unknown means
//! (`constant_row`). The steps of `build` call it in a fixed order, which fixes the variable
//! and equation order of the system.

use super::forms::{const_rot, is_zero, rodrigues_parts, rot_apply, rot_times, sub3, Form, Pos, RotF, Vec3F};
use crate::formulate::stated::{self as st, IVec3};
use crate::kernel::interval::{interval, point, Interval};
use crate::kernel::system::{Equation, EquationSystem, Monomial, Term, VarId, VarRole};
use nalgebra::Vector3;
use std::collections::BTreeMap;

/// The system being written, with what its rows share: rotation groups, bilinear products
/// and squared norms already named.
pub(super) struct Builder {
    /// Building to judge whether loops can close at all (then a constant row that cannot hold
    /// is bad input, not an answer).
    check_closure: bool,
    pub(super) system: EquationSystem,
    pub(super) groups: Vec<RotF>,
    products: BTreeMap<(VarId, VarId), VarId>,
    /// Shared `n = Σ x²` variables, by their sorted variables.
    norms: BTreeMap<Vec<VarId>, VarId>,
    /// Equations that are not closures (definitions), by index.
    pub(super) definitions: Vec<usize>,
    /// Magnitudes of the constant rows taken as identities (`VANISHING`), in order.
    pub(super) vanished: Vec<f64>,
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
    /// An empty system whose only rotation group is the ground's (the identity).
    pub(super) fn new(check_closure: bool) -> Self {
        Self { check_closure, system: EquationSystem::default(), groups: vec![const_rot(&st::identity())], products: BTreeMap::new(), norms: BTreeMap::new(), definitions: Vec::new(), vanished: Vec::new() }
    }

    pub(super) fn define(&mut self, e: Equation) {
        self.definitions.push(self.system.equations.len());
        self.system.add(e);
    }

    pub(super) fn initial(&self, f: &Form) -> Interval {
        f.eval(&self.system.initial_box().dims)
    }

    /// A derived variable equal to `f` (`f` itself when it is one variable).
    pub(super) fn name_form(&mut self, f: &Form, name: &str, clamp: Option<Interval>) -> Form {
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

    pub(super) fn product(&mut self, x: VarId, y: VarId) -> VarId {
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
    pub(super) fn times_var(&mut self, f: &Form, x: VarId) -> Form {
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
    pub(super) fn times_form(&mut self, f: &Form, g: &Form, names: (&str, &str)) -> Form {
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
    pub(super) fn rot_by(&mut self, m: &RotF, a: &IVec3, c: VarId, s: VarId, tag: &str) -> RotF {
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

    pub(super) fn new_group(&mut self, g: RotF) -> usize {
        self.groups.push(g);
        self.groups.len() - 1
    }

    /// `Σ G_g·v_g + rest` as forms.
    pub(super) fn forms(&self, p: &Pos) -> Vec3F {
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
    pub(super) fn equal(&mut self, a: &Vec3F, b: &Vec3F, rows: &mut Vec<usize>) -> Result<(), Interval> {
        for f in sub3(a, b) {
            self.zero(&f, rows)?;
        }
        Ok(())
    }

    pub(super) fn zero(&mut self, f: &Form, rows: &mut Vec<usize>) -> Result<(), Interval> {
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
    pub(super) fn distance(&mut self, d: &Pos, length2: (Interval, Option<(Interval, VarId)>), tag: &str, rows: &mut Vec<usize>) -> Result<(), Interval> {
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
    pub(super) fn constant_row(&mut self, k: Interval, rows: &mut Vec<usize>) -> Result<(), Interval> {
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
pub(super) fn axes_agree(b: &mut Builder, u: &Vec3F, v: &Vec3F, w: Vector3<f64>, rows: &mut Vec<usize>, signs: &mut Vec<(Form, Form)>, pairs: &mut Vec<AxisPair>) -> Result<(), Interval> {
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
pub(super) struct AxisPair {
    pub(super) u: Vec3F,
    pub(super) diff: Vec3F,
    pub(super) rows: Vec<usize>,
}

/// The report line of the rows of loop `name` taken as identities (`VANISHING`), if any.
pub(super) fn vanished_note(name: &str, magnitudes: &[f64]) -> Option<String> {
    let largest = magnitudes.iter().copied().fold(0.0, f64::max);
    (!magnitudes.is_empty()).then(|| format!("loop '{name}': {} closure row(s) left with no unknown, constant within {largest:.1e} of 0 (the same stated values reached by two paths): taken as identities", magnitudes.len()))
}

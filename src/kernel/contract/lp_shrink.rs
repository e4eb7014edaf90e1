//! The box shrink by linear programs of Porta, Ros and Thomas (2006, Algorithm 2), with verified
//! bounds.
//!
//! Rows, all valid for every solution in the current box:
//! - every linear equation, its coefficient uncertainty moved into the row bounds;
//! - per circle `x² + y² = 1` whose box lies in one quadrant, their chord cut (the arc lies
//!   beyond the chord) with the tangent parallel to it, plus the tangents at the arc's ends;
//! - per bilinear `z = x·y`, the four McCormick planes: the faces of their tetrahedron.
//!
//! Then every primary variable is minimised and maximised (`lp::Relaxation::bound`).

use super::{Contraction, Contractor};
use crate::kernel::interval::{interval, point, Interval, IntervalBox};
use crate::kernel::lp::{LpBackend, LpCounters, LpOutcome, Relaxation, Row, Sides};
use crate::kernel::system::{EquationKind, EquationSystem, Monomial, VarId};

/// The LP shrink contractor.
pub struct LpShrink<'a> {
    system: &'a EquationSystem,
    targets: Vec<VarId>,
    /// The LP solver used.
    pub backend: LpBackend,
    /// LPs solved and answers that proved nothing.
    pub counters: LpCounters,
}

impl<'a> LpShrink<'a> {
    /// Bounds every primary variable of `system`.
    pub fn new(system: &'a EquationSystem) -> Self {
        Self { system, targets: system.primaries(), backend: LpBackend::default(), counters: LpCounters::default() }
    }
}

impl Contractor for LpShrink<'_> {
    fn contract(&mut self, b: &mut IntervalBox) -> Contraction {
        self.contract_until(b, &|| false)
    }

    fn contract_until(&mut self, b: &mut IntervalBox, stop: &dyn Fn() -> bool) -> Contraction {
        let rel = match relax(self.system, &b.dims) {
            Some(r) => r,
            None => return Contraction::Empty,
        };
        match rel.bound_with(self.backend, &b.dims, &self.targets, &mut self.counters, stop) {
            LpOutcome::Infeasible => Contraction::Empty,
            LpOutcome::Bounds(bounds) => {
                let mut outcome = Contraction::Unchanged;
                for (&t, nb) in self.targets.iter().zip(bounds) {
                    let narrowed = b.dims[t].intersection(nb);
                    if narrowed.is_empty() {
                        return Contraction::Empty;
                    }
                    if narrowed != b.dims[t] {
                        outcome = Contraction::Reduced;
                        b.dims[t] = narrowed;
                    }
                }
                outcome
            }
        }
    }

    fn name(&self) -> &'static str {
        "lp-shrink"
    }

    fn lp_counters(&self) -> LpCounters {
        self.counters
    }
}

/// Relative width below which a linear row's range is rounding, not uncertainty.
const NEGLIGIBLE_RANGE: f64 = 1e-10;

/// Builds the linear relaxation of `system` over box `b`; `None` when a row is already proven
/// unsatisfiable on `b`.
pub(crate) fn relax(system: &EquationSystem, b: &[Interval]) -> Option<Relaxation> {
    let mut rows = Vec::new();
    for e in &system.equations {
        match e.kind {
            EquationKind::Linear => {
                let mut coefs = Vec::with_capacity(e.terms.len());
                // Σ mid(c)·x ∈ −constant − Σ (c − mid(c))·x
                let mut rest = -e.constant;
                for t in &e.terms {
                    let Monomial::Linear(x) = t.mono else { unreachable!("invariant: linear kind") };
                    let m = t.coef.mid();
                    coefs.push((x, m));
                    rest -= (t.coef - point(m)) * b[x];
                }
                // A row whose range comes only from rounding (coefficients that enclose the
                // file's decimals are a few ulps wide) is handed to the LP as an equality at its
                // midpoint: a ranged row costs the simplex a bounded slack and more pivots, for
                // nothing. The LP only proposes multipliers; `safe_bound` still uses the whole
                // range, so this costs at most |μ|·width of the bound, never soundness.
                let negligible = rest.wid() <= NEGLIGIBLE_RANGE * (1.0 + rest.mag());
                rows.push(Row { coefs, bounds: rest, sides: if negligible { Sides::Equal } else { Sides::Both } });
            }
            EquationKind::Circle { x, y } => circle_cuts(x, y, b, &mut rows),
            EquationKind::Bilinear { z, x, y } => mccormick(z, x, y, b, &mut rows),
            EquationKind::Quadratic => {}
        }
    }
    // Every cut's bounds are also cropped to the row's range over the box, so both ends are finite.
    for r in &mut rows {
        let range = r.coefs.iter().fold(point(0.0), |acc, &(j, a)| acc + point(a) * b[j]);
        r.bounds = r.bounds.intersection(range);
        if r.bounds.is_empty() {
            return None;
        }
    }
    Some(Relaxation { n: b.len(), rows })
}

/// Chord and tangent cuts for `x² + y² = 1` over the box `[x]×[y]`.
///
/// The circle meets the box in arcs whose ends lie on the box's edges. Those ends are enclosed
/// by the edge candidates `(v, ±√(1−v²))` and `(±√(1−v²), v)` for each bound `v` of the box,
/// kept when they may lie in the box. Along the circle, `w·p` has its only interior minimum at
/// the antipode of `w`; when that point is outside the box, the smallest `w·p` over the
/// candidates bounds `w·p` from below on every arc: the chord cut of Porta et al. (2006), for boxes
/// in any position. The tangent at any candidate, `p·x ≤ |p|`, holds on the whole circle.
fn circle_cuts(x: VarId, y: VarId, b: &[Interval], rows: &mut Vec<Row>) {
    let (bx, by) = (b[x], b[y]);
    let one = point(1.0);
    let mut ends: Vec<(Interval, Interval)> = Vec::with_capacity(8);
    let root = |v: f64| (one - point(v).sqr()).intersection(interval(0.0, 1.0)).sqrt();
    for u in [bx.inf(), bx.sup()] {
        let r = root(u);
        for v in [r, -r] {
            if !v.is_empty() && !v.disjoint(by) {
                ends.push((point(u), v));
            }
        }
    }
    for v in [by.inf(), by.sup()] {
        let r = root(v);
        for u in [r, -r] {
            if !u.is_empty() && !u.disjoint(bx) {
                ends.push((u, point(v)));
            }
        }
    }
    if ends.is_empty() {
        return;
    }
    for (u, v) in &ends {
        let (pu, pv) = (u.mid(), v.mid());
        let plen = (point(pu).sqr() + point(pv).sqr()).sqrt().sup();
        rows.push(Row { coefs: vec![(x, pu), (y, pv)], bounds: interval(-plen, plen), sides: Sides::Upper });
    }
    let (mut mu, mut mv) = (0.0, 0.0);
    for (u, v) in &ends {
        mu += u.mid();
        mv += v.mid();
    }
    let norm = (mu * mu + mv * mv).sqrt();
    if !(norm > 1e-6) {
        return;
    }
    let (wu, wv) = (mu / norm, mv / norm);
    // The antipode must lie clearly outside the box for the endpoint argument to hold.
    let margin = 1e-6;
    let outside = |p: f64, d: Interval| p < d.inf() - margin || p > d.sup() + margin;
    if !(outside(-wu, bx) || outside(-wv, by)) {
        return;
    }
    let d = ends.iter().map(|(u, v)| (point(wu) * *u + point(wv) * *v).inf()).fold(f64::INFINITY, f64::min);
    let wlen = (point(wu).sqr() + point(wv).sqr()).sqrt().sup();
    rows.push(Row { coefs: vec![(x, wu), (y, wv)], bounds: interval(d.min(wlen), wlen), sides: Sides::Both });
}

/// The four McCormick planes of `z = x·y` over `[x]×[y]`, the faces of the tetrahedron of Porta et
/// al. (2006).
///
/// From `(x − x₀)(y − y₀)·s ≥ 0` for the corner `(x₀, y₀)` and the matching sign `s`:
/// `z − y₀·x − x₀·y` lies above (s = +1) or below (s = −1) `−x₀·y₀`.
fn mccormick(z: VarId, x: VarId, y: VarId, b: &[Interval], rows: &mut Vec<Row>) {
    let (bx, by) = (b[x], b[y]);
    for (x0, y0, above) in [
        (bx.inf(), by.inf(), true),
        (bx.sup(), by.sup(), true),
        (bx.sup(), by.inf(), false),
        (bx.inf(), by.sup(), false),
    ] {
        let c = -(point(x0) * point(y0));
        let bounds = if above { interval(c.inf(), f64::INFINITY) } else { interval(f64::NEG_INFINITY, c.sup()) };
        let sides = if above { Sides::Lower } else { Sides::Upper };
        rows.push(Row { coefs: vec![(z, 1.0), (x, -y0), (y, -x0)], bounds, sides });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::system::{Equation, Term, VarRole};
    use proptest::prelude::*;

    #[test]
    fn chord_cut_holds_on_the_arc_and_cuts_the_corner() {
        let b = [interval(0.2, 0.9), interval(0.3, 0.95)];
        let mut rows = Vec::new();
        circle_cuts(0, 1, &b, &mut rows);
        assert!(rows.len() >= 3);
        let chord = rows.last().expect("a chord row");
        for k in 0..=100 {
            let t = k as f64 / 100.0 * std::f64::consts::FRAC_PI_2;
            let (u, v) = (t.cos(), t.sin());
            if b[0].contains(u) && b[1].contains(v) {
                let val = chord.coefs[0].1 * u + chord.coefs[1].1 * v;
                assert!(chord.bounds.contains(val), "arc point {u},{v} off the cut");
            }
        }
        // The box corner (0.2, 0.3) lies inside the disc, off the arc: the chord excludes it.
        assert!(!chord.bounds.contains(chord.coefs[0].1 * 0.2 + chord.coefs[1].1 * 0.3));
    }

    proptest! {
        // Soundness: an arc point in a box of any quadrant survives the LP shrink.
        #[test]
        #[allow(clippy::approx_constant)] // angles over [-3.14, 3.14], not π
        fn lp_shrink_keeps_circle_points(t in -3.14f64..3.14, w0 in 0.001f64..0.8, w1 in 0.001f64..0.8, f0 in 0.01f64..0.99, f1 in 0.01f64..0.99) {
            let mut s = EquationSystem::default();
            let x = s.add_var("x", VarRole::Primary, interval(-1.0, 1.0));
            let y = s.add_var("y", VarRole::Primary, interval(-1.0, 1.0));
            let z = s.add_var("z", VarRole::Primary, interval(-4.0, 4.0));
            let d = s.add_var("d", VarRole::Primary, interval(0.0, 4.0));
            s.add(Equation::circle(x, y));
            s.add(Equation::bilinear(z, d, x));
            // z + 0.5 y = given, so the linear part is active too.
            let (c, sn) = (t.cos(), t.sin());
            let dv = 1.0 + f0 * 2.0;
            let zv = dv * c;
            s.add(Equation::new(vec![Term { coef: point(1.0), mono: Monomial::Linear(z) }, Term { coef: point(0.5), mono: Monomial::Linear(y) }], -(point(zv) + point(0.5) * point(sn))));
            let mut b = IntervalBox::new(vec![
                interval(c - w0 * f0, c + w0 * (1.0 - f0)),
                interval(sn - w1 * f1, sn + w1 * (1.0 - f1)),
                interval(zv - 0.5, zv + 0.5),
                interval(dv - 0.3, dv + 0.3),
            ]);
            let mut lp = LpShrink::new(&s);
            prop_assert_ne!(lp.contract(&mut b), Contraction::Empty);
            let near = |i: Interval, v: f64| i.inf() <= v + 1e-9 && i.sup() >= v - 1e-9;
            prop_assert!(near(b.dims[0], c) && near(b.dims[1], sn) && near(b.dims[3], dv));
        }
    }
}

//! The Krawczyk operator, the one interval Newton of the crate: existence, uniqueness and
//! exclusion for square systems, plus ε-inflation and tightening built on it.
//!
//! For `F: ℝⁿ → ℝⁿ`, a box `B`, a point `m ∈ B`, an enclosure `J` of the Jacobian of `F` over
//! `B` and any real matrix `Y` (we take the inverse of `mid J`):
//!
//! ```text
//! K(B) = m − Y F(m) + (I − Y J)(B − m)
//! ```
//!
//! | outcome | meaning |
//! |---|---|
//! | `K ⊂ int B` | `F` has exactly one zero in `B` (and it lies in `K`): `Step::Unique` |
//! | `K ∩ B = ∅` | `F` has no zero in `B`: `Step::Empty` |
//! | otherwise | every zero in `B` lies in `K ∩ B`: `Step::Contracted` |
//! | `mid J` singular, overflow | nothing proven: `Step::Failed` |
//!
//! `F(m)` and `J` may be enclosures over a box of parameters too: then each statement holds for
//! every parameter value in it.
//!
//! One implementation serves every dimension: `step` is generic over nalgebra's `Dim`, so the
//! 3R searches run it on stack matrices (`step_array`, `N` = 2 or 4) and `contract::Newton` on
//! heap ones (`DVector`/`DMatrix`) for an `EquationSystem` of any size. Callers evaluate `F(m)`
//! and `J(B)` (in any sound arithmetic); everything after that is one rounding discipline:
//! `interval::fast::Iv`, each operation rounded to nearest and moved one ulp outward, in
//! `B − m`, `Y·F(m)`, `I − Y·J` and the final products and sums. `Y` itself is computed in
//! floating point: it needs no accuracy, only the interval products that use it are outward.
//!
//! # References
//! R. Krawczyk, *Newton-Algorithmen zur Bestimmung von Nullstellen mit Fehlerschranken*,
//! Computing 4 (1969); R. E. Moore, *A test for existence of solutions to nonlinear systems*,
//! SIAM J. Numer. Anal. 14 (1977); A. Neumaier, *Interval methods for systems of equations*,
//! Cambridge University Press (1990), §5.2; S. M. Rump, *Solving algebraic problems with high
//! accuracy*, in *A New Approach to Scientific Computation* (1983), for ε-inflation.

use crate::kernel::interval::fast::Iv;
use crate::kernel::interval::interval;
use inari::Interval;
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, OMatrix, OVector, SMatrix, SVector};

/// What one Krawczyk step proved about a box (`V` the box type: an array, a `Vec` or an
/// nalgebra vector of intervals).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Step<V> {
    /// Exactly one zero in the box; it lies in the given (smaller) box.
    Unique(V),
    /// No zero in the box.
    Empty,
    /// Every zero lies in the given box (the intersection `K ∩ B`).
    Contracted(V),
    /// `mid J` is singular or the arithmetic overflowed: nothing proven.
    Failed,
}

impl<V> Step<V> {
    /// The same outcome with its box converted.
    pub fn map<W>(self, f: impl FnOnce(V) -> W) -> Step<W> {
        match self {
            Step::Unique(v) => Step::Unique(f(v)),
            Step::Contracted(v) => Step::Contracted(f(v)),
            Step::Empty => Step::Empty,
            Step::Failed => Step::Failed,
        }
    }
}

/// One Krawczyk step on `b`, with `fm ⊇ F(m)` at the point `m ∈ b` and `jac ⊇ J(b)` (row i =
/// ∇Fᵢ). See the module doc for the outcomes.
///
/// Zero entries of `J` (the 3R node system has four) are skipped, which only tightens.
///
/// # Examples
///
/// ```
/// use linkspace::kernel::contract::krawczyk::{step_array, Step};
/// use linkspace::kernel::interval::{interval, point};
/// // F(x) = x² − 2 on [1.3, 1.5]: one root, √2.
/// let b = [interval(1.3, 1.5)];
/// let m = [1.4];
/// let fm = [point(1.4) * point(1.4) - point(2.0)];
/// let jac = [[point(2.0) * b[0]]];
/// match step_array(&b, &m, &fm, &jac) {
///     Step::Unique(k) => assert!(k[0].contains(2f64.sqrt())),
///     other => panic!("{other:?}"),
/// }
/// ```
///
/// See also `step_array` (fixed size, arrays), `inflate`, `tighten`, `contract::Newton`.
pub fn step<D: Dim>(b: &OVector<Interval, D>, m: &OVector<f64, D>, fm: &OVector<Interval, D>, jac: &OMatrix<Interval, D, D>) -> Step<OVector<Interval, D>>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    match image(b, m, fm, jac) {
        None => Step::Failed,
        Some(k) => classify(b, k),
    }
}

/// `step` on arrays, for fixed-size callers (the 3R searches): the same implementation on
/// nalgebra's stack storage.
#[inline]
pub fn step_array<const N: usize>(b: &[Interval; N], m: &[f64; N], fm: &[Interval; N], jac: &[[Interval; N]; N]) -> Step<[Interval; N]> {
    step(&SVector::from(*b), &SVector::from(*m), &SVector::from(*fm), &SMatrix::from_fn(|i, j| jac[i][j])).map(Into::into)
}

/// `image` on arrays, as `step_array`.
#[inline]
pub fn image_array<const N: usize>(b: &[Interval; N], m: &[f64; N], fm: &[Interval; N], jac: &[[Interval; N]; N]) -> Option<[Interval; N]> {
    image(&SVector::from(*b), &SVector::from(*m), &SVector::from(*fm), &SMatrix::from_fn(|i, j| jac[i][j])).map(Into::into)
}

/// Krawczyk's image `K(b)` itself, not yet compared with `b` (what `step` classifies, and what
/// `inflate` grows from); `None` when `mid J` cannot be inverted or the image is not finite.
#[inline]
pub fn image<D: Dim>(b: &OVector<Interval, D>, m: &OVector<f64, D>, fm: &OVector<Interval, D>, jac: &OMatrix<Interval, D, D>) -> Option<OVector<Interval, D>>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    let mid = jac.map(|x| x.mid());
    if !mid.iter().all(|v| v.is_finite()) {
        return None;
    }
    let y = mid.try_inverse()?;
    if !y.iter().all(|v| v.is_finite()) {
        return None;
    }
    image_preconditioned(b, m, fm, jac, &y)
}

/// Krawczyk's image with the preconditioner `y`, for `R` equations in `C` unknowns:
/// `K = m − Y·F(m) + (I − Y·J(b))(b − m)` holds every zero in `b` of `Y·F`, so every zero of
/// `F`, whatever `y` is. `image` takes `(mid J)⁻¹`; a system with more equations than unknowns
/// takes a left pseudo-inverse, and then only `K ∩ b` (emptiness, narrowing) means anything.
/// `None` when the image is not finite.
pub fn image_preconditioned<R: Dim, C: Dim>(b: &OVector<Interval, C>, m: &OVector<f64, C>, fm: &OVector<Interval, R>, jac: &OMatrix<Interval, R, C>, y: &OMatrix<f64, C, R>) -> Option<OVector<Interval, C>>
where
    DefaultAllocator: Allocator<R> + Allocator<C> + Allocator<R, C> + Allocator<C, R>,
{
    let (rows, n) = (fm.nrows(), b.nrows());
    let jac = jac.map(Iv::from);
    let fm = fm.map(Iv::from);
    let dx = b.zip_map(m, |b, m| Iv::from(b).sub(Iv { lo: m, hi: m }));
    if dx.iter().any(|d| d.lo.is_nan()) {
        return None;
    }
    let mut k = b.clone();
    for i in 0..n {
        let mut acc = Iv { lo: m[i], hi: m[i] };
        for l in 0..rows {
            acc = acc.sub(fm[l].scale(y[(i, l)]));
        }
        for j in 0..n {
            // (I − Y J)_{ij}
            let mut e = if i == j { Iv { lo: 1.0, hi: 1.0 } } else { Iv::ZERO };
            for l in 0..rows {
                let jlj = jac[(l, j)];
                if jlj != Iv::ZERO {
                    e = e.sub(jlj.scale(y[(i, l)]));
                }
            }
            acc = acc.add(e.mul(dx[j]));
        }
        if !(acc.lo.is_finite() && acc.hi.is_finite()) {
            return None;
        }
        k[i] = acc.to();
    }
    Some(k)
}

/// Every solution `x` of every linear system `A x = r` with `A ∈ a` and `r ∈ r_box` (interval
/// matrix and right-hand side, e.g. enclosures over a box of parameters), and the proof that every
/// `A ∈ a` is regular; `None` when the preconditioned test fails. `Y ≈ (mid a)⁻¹`; see
/// `preconditioned_hull`, which this calls with `E = I − Y·a` and `z = Y·r`.
///
/// See also `step` (the nonlinear operator).
pub fn linear_hull(a: &nalgebra::DMatrix<Interval>, r_box: &nalgebra::DVector<Interval>) -> Option<nalgebra::DVector<Interval>> {
    let n = a.nrows();
    if a.ncols() != n || r_box.nrows() != n || n == 0 {
        return None;
    }
    let mid = a.map(|x| x.mid());
    if !mid.iter().all(|v| v.is_finite()) {
        return None;
    }
    let y = mid.try_inverse()?;
    if !y.iter().all(|v| v.is_finite()) {
        return None;
    }
    let a = a.map(Iv::from);
    let r = r_box.map(Iv::from);
    let e = nalgebra::DMatrix::from_fn(n, n, |i, j| (0..n).fold(if i == j { Iv { lo: 1.0, hi: 1.0 } } else { Iv::ZERO }, |x, l| x.sub(a[(l, j)].scale(y[(i, l)]))));
    let z = nalgebra::DVector::from_fn(n, |i, _| (0..n).fold(Iv::ZERO, |acc, l| acc.add(r[l].scale(y[(i, l)]))));
    preconditioned_hull(&e, &z)
}

/// The solutions of `A x = r` over families of systems, from their preconditioned form: `e`
/// encloses every `I − Y·A` and `z` every `Y·r`, for one real matrix `Y`. `‖e‖∞ ≤ δ < 1` proves
/// every `A` regular (`Y·A` is within `δ` of the identity) and gives `‖x‖∞ ≤ ‖z‖∞ / (1 − δ)`
/// from `x = Y·r + (I − Y·A)·x`; from that box, `x ∈ z + e·X` narrows it (three rounds). `None`
/// when `δ < 1` is not shown. A caller that knows the structure of `A` (entries linear in a few
/// parameters) can enclose `Y·A` far tighter than interval products would, hence this entry.
///
/// See also `linear_hull`.
pub(crate) fn preconditioned_hull(e: &nalgebra::DMatrix<Iv>, z: &nalgebra::DVector<Iv>) -> Option<nalgebra::DVector<Interval>> {
    let n = e.nrows();
    if e.ncols() != n || z.nrows() != n || n == 0 {
        return None;
    }
    let mut delta: f64 = 0.0;
    for i in 0..n {
        let row = (0..n).fold(0.0f64, |acc, j| (acc + e[(i, j)].lo.abs().max(e[(i, j)].hi.abs())).next_up());
        delta = delta.max(row);
    }
    // NaN fails this test too.
    if !(delta < 1.0) {
        return None;
    }
    let zmax = z.iter().fold(0.0f64, |m, x| m.max(x.lo.abs()).max(x.hi.abs()));
    let radius = (zmax / (1.0 - delta).next_down()).next_up().next_up();
    if !radius.is_finite() {
        return None;
    }
    let mut x: Vec<Iv> = vec![Iv { lo: -radius, hi: radius }; n];
    for _ in 0..3 {
        x = (0..n)
            .map(|i| {
                let k = (0..n).fold(z[i], |acc, j| acc.add(e[(i, j)].mul(x[j])));
                Iv { lo: k.lo.max(x[i].lo), hi: k.hi.min(x[i].hi) }
            })
            .collect();
    }
    Some(nalgebra::DVector::from_iterator(n, x.into_iter().map(Iv::to)))
}

/// Compares `K(b)` with `b`: unique when inside its interior, empty when a component misses
/// `b`, otherwise the intersection.
#[inline]
fn classify<D: Dim>(b: &OVector<Interval, D>, mut k: OVector<Interval, D>) -> Step<OVector<Interval, D>>
where
    DefaultAllocator: Allocator<D>,
{
    if k.iter().zip(b.iter()).all(|(k, b)| k.interior(*b)) {
        return Step::Unique(k);
    }
    for (k, b) in k.iter_mut().zip(b.iter()) {
        *k = k.intersection(*b);
        if k.is_empty() {
            return Step::Empty;
        }
    }
    Step::Contracted(k)
}

/// How `inflate` widens a box: component `d` grows on each side by
/// `own·wid(d) + widest·W + absolute + ulps·ε·max(|d|, 1)`, with `W` the widest of the
/// components listed in `widest_of` and `ε` the machine epsilon.
#[derive(Clone, Copy, Debug)]
pub struct Inflation<'a> {
    /// Trial boxes before giving up.
    pub rounds: usize,
    /// Fraction of a component's own width.
    pub own: f64,
    /// Fraction of the widest listed component's width (see the struct doc for why).
    pub widest: f64,
    /// The components whose width sets `W` (e.g. the primaries of a system).
    pub widest_of: &'a [usize],
    /// An absolute pad.
    pub absolute: f64,
    /// Machine epsilons of the component's magnitude (at least 1).
    pub ulps: f64,
}

impl Inflation<'_> {
    fn pad(&self, dims: &mut [Interval]) {
        let widest = self.widest_of.iter().map(|&i| dims[i].wid()).fold(0.0, f64::max);
        for d in dims.iter_mut() {
            let pad = self.own * d.wid() + self.widest * widest + self.absolute + self.ulps * f64::EPSILON * d.mag().max(1.0);
            *d = interval(d.inf() - pad, d.sup() + pad);
        }
    }
}

/// Epsilon-inflation (Rump 1983): a box that is already tight around a root, or one that
/// Krawczyk contracted without a proof, rarely shows `K(X) ⊂ int X`; so try on `X` = `b`
/// widened, then on the widened hull of `b` and `K(X)`, `policy.rounds` times. `image`
/// evaluates the system on its argument and returns Krawczyk's image (`krawczyk::image`), or
/// `None` to give up (e.g. when a side condition fails on the trial box).
///
/// Every trial box holds `b`, so when `K(X') ⊂ int X'` the returned `K(X')` holds the one root
/// of `X'`, which is every root of `b`.
///
/// Inflating by a component's own width is not always enough: a component can be far narrower
/// than the box (`c = cos φ` near φ = 0 is `w²/2` wide when `s` is `w` wide, and a box Newton
/// has shrunk to a few ulps is narrower than its coefficients' uncertainty), while `K` of that
/// component is as wide as the box's curvature or coefficients make it. Hence `widest`.
///
/// See also `tighten`, `Contractor::certify`.
pub fn inflate<V>(b: &V, policy: &Inflation, mut image: impl FnMut(&V) -> Option<V>) -> Option<V>
where
    V: AsRef<[Interval]> + AsMut<[Interval]> + Clone,
{
    let mut x = b.clone();
    for _ in 0..policy.rounds {
        policy.pad(x.as_mut());
        let k = image(&x)?;
        if k.as_ref().iter().zip(x.as_ref()).all(|(k, x)| k.interior(*x)) {
            return Some(k);
        }
        x = k;
        for (x, b) in x.as_mut().iter_mut().zip(b.as_ref()) {
            *x = x.convex_hull(*b);
        }
    }
    None
}

/// Shrinks a box by repeated Krawczyk steps (`krawczyk` as in `inflate`) until no component is
/// wider than `precision`, a step stops shrinking the widest component by 10%, or 30 steps.
/// The result holds every root of `b` (each step loses none).
///
/// See also `inflate`.
pub fn tighten<V>(mut b: V, precision: f64, mut krawczyk: impl FnMut(&V) -> Step<V>) -> V
where
    V: AsRef<[Interval]>,
{
    let width = |v: &V| v.as_ref().iter().map(|d| d.wid()).fold(0.0, f64::max);
    for _ in 0..30 {
        if width(&b) <= precision {
            break;
        }
        match krawczyk(&b) {
            Step::Unique(next) | Step::Contracted(next) if width(&next) < 0.9 * width(&b) => b = next,
            _ => break,
        }
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::interval::point;
    use nalgebra::{DMatrix, DVector};
    use proptest::prelude::*;

    #[test]
    fn linear_hull_holds_every_member_solution_and_refuses_singular_families() {
        // A = [[2, t], [1, 3]], r = (1, s) for t in [-0.5, 0.5], s in [0, 1]: every member is
        // regular (det = 6 − t ≥ 5.5), and its solution must lie in the hull.
        let a = DMatrix::from_row_slice(2, 2, &[point(2.0), interval(-0.5, 0.5), point(1.0), point(3.0)]);
        let r = DVector::from_vec(vec![point(1.0), interval(0.0, 1.0)]);
        let x = linear_hull(&a, &r).expect("a regular family");
        for t in [-0.5, -0.1, 0.0, 0.3, 0.5] {
            for s in [0.0, 0.4, 1.0] {
                let det = 6.0 - t;
                let sol = [(3.0 - t * s) / det, (2.0 * s - 1.0) / det];
                assert!(x[0].contains(sol[0]) && x[1].contains(sol[1]), "t {t} s {s}: {sol:?} not in {x:?}");
            }
        }
        // [[1, 1], [1, t]] holds the singular t = 1.
        let singular = DMatrix::from_row_slice(2, 2, &[point(1.0), point(1.0), point(1.0), interval(0.5, 1.5)]);
        assert!(linear_hull(&singular, &DVector::from_element(2, point(0.0))).is_none());
    }

    /// F(x, y) = (x² + y² − 1, x − y): zeros at ±(1/√2, 1/√2).
    fn circle_line(b: &[Interval; 2]) -> Step<[Interval; 2]> {
        let m = [b[0].mid(), b[1].mid()];
        let fm = [point(m[0]).sqr() + point(m[1]).sqr() - point(1.0), point(m[0]) - point(m[1])];
        let two = point(2.0);
        let jac = [[two * b[0], two * b[1]], [point(1.0), point(-1.0)]];
        step_array(b, &m, &fm, &jac)
    }

    fn circle_line_image(b: &[Interval; 2]) -> Option<[Interval; 2]> {
        let m = [b[0].mid(), b[1].mid()];
        let fm = [point(m[0]).sqr() + point(m[1]).sqr() - point(1.0), point(m[0]) - point(m[1])];
        let two = point(2.0);
        image_array(b, &m, &fm, &[[two * b[0], two * b[1]], [point(1.0), point(-1.0)]])
    }

    #[test]
    fn proves_the_root_excludes_the_empty_and_contracts_the_rest() {
        assert!(matches!(circle_line(&[interval(0.6, 0.8), interval(0.6, 0.8)]), Step::Unique(_)));
        assert_eq!(circle_line(&[interval(0.1, 0.2), interval(0.1, 0.2)]), Step::Empty);
        match circle_line(&[interval(0.0, 1.0), interval(0.0, 1.0)]) {
            Step::Contracted(k) | Step::Unique(k) => assert!(k[0].contains(0.5f64.sqrt())),
            other => panic!("unexpected {other:?}"),
        }
    }

    #[test]
    fn inflation_proves_a_point_box_and_tightening_keeps_the_root() {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        // A box of a few ulps beside the root: no proof on it, one after inflation.
        let tight = [interval(h, h.next_up()), interval(h, h.next_up())];
        let policy = Inflation { rounds: 4, own: 0.05, widest: 0.005, widest_of: &[0, 1], absolute: 0.0, ulps: 4.0 };
        let proven = inflate(&tight, &policy, circle_line_image).expect("inflation proves the root");
        assert!(proven.iter().all(|d| d.contains(h)));
        let wide = [interval(0.5, 0.9), interval(0.6, 0.8)];
        let t = tighten(wide, 1e-9, circle_line);
        assert!(t.iter().all(|d| d.contains(h) && d.wid() <= 1e-9));
        // Nothing to prove near a point with no root.
        assert!(inflate(&[interval(0.1, 0.1), interval(0.1, 0.1)], &policy, circle_line_image).is_none());
    }

    /// F(x) = ((x₀ − a)(x₀ − b), x₁ − c·x₀, x₂ + x₀·x₁ − d) with `a ≠ b`: roots at x₀ ∈ {a, b},
    /// x₁ = c·x₀, x₂ = d − c·x₀². Returns `F(m)` and `J(box)` in inari arithmetic.
    fn poly3(p: [f64; 4], x: &[Interval], m: &[f64]) -> (Vec<Interval>, Vec<Vec<Interval>>) {
        let [a, b, c, d] = p.map(point);
        let mp: Vec<Interval> = m.iter().map(|&v| point(v)).collect();
        let fm = vec![(mp[0] - a) * (mp[0] - b), mp[1] - c * mp[0], mp[2] + mp[0] * mp[1] - d];
        let jac = vec![
            vec![point(2.0) * x[0] - a - b, point(0.0), point(0.0)],
            vec![-c, point(1.0), point(0.0)],
            vec![x[1], x[0], point(1.0)],
        ];
        (fm, jac)
    }

    /// Parameters `k / scale` with `scale` a power of two: the roots below are then exact.
    fn dyadic(k: [i32; 4], scale: f64) -> [f64; 4] {
        k.map(|k| f64::from(k) / scale)
    }

    /// The two roots of `poly3`, exact for dyadic parameters of few bits.
    fn roots3(p: [f64; 4]) -> [[f64; 3]; 2] {
        [p[0], p[1]].map(|r| [r, p[2] * r, p[3] - p[2] * r * r])
    }

    /// Krawczyk's image for `poly3`.
    fn image3(p: [f64; 4], x: &[Interval]) -> Option<Vec<Interval>> {
        let m: Vec<f64> = x.iter().map(|d| d.mid()).collect();
        let (fm, jac) = poly3(p, x, &m);
        image(&DVector::from_column_slice(x), &DVector::from_vec(m), &DVector::from_vec(fm), &DMatrix::from_fn(3, 3, |i, j| jac[i][j])).map(|k| k.data.into())
    }

    /// The shared step in both storages, which must agree bit for bit.
    fn both(p: [f64; 4], x: &[Interval]) -> Step<Vec<Interval>> {
        let m: Vec<f64> = x.iter().map(|d| d.mid()).collect();
        let (fm, jac) = poly3(p, x, &m);
        let dynamic = step(&DVector::from_column_slice(x), &DVector::from_column_slice(&m), &DVector::from_vec(fm.clone()), &DMatrix::from_fn(3, 3, |i, j| jac[i][j]));
        let fixed = step_array(&[x[0], x[1], x[2]], &[m[0], m[1], m[2]], &[fm[0], fm[1], fm[2]], &[0, 1, 2].map(|i| [jac[i][0], jac[i][1], jac[i][2]]));
        let dynamic = dynamic.map(|v| v.iter().copied().collect::<Vec<_>>());
        assert_eq!(dynamic, fixed.map(|v| v.to_vec()));
        dynamic
    }

    fn around(r: &[f64; 3], lo: [f64; 3], hi: [f64; 3]) -> Vec<Interval> {
        (0..3).map(|i| interval(r[i] - lo[i], r[i] + hi[i])).collect()
    }

    proptest! {
        /// Soundness (parameters dyadic so that the roots are exact): a root inside the box is inside every box the step returns, and a box
        /// around a root is never declared empty.
        #[test]
        fn never_loses_a_root(
            a in -16..16i32, gap in 1..16i32, c in -24..24i32, d in -24..24i32,
            which in 0..2usize,
            lo in prop::array::uniform3(0.0..0.5f64), hi in prop::array::uniform3(0.0..0.5f64),
        ) {
            let p = dyadic([a, a + gap, c, d], 8.0);
            let r = roots3(p)[which];
            let x = around(&r, lo, hi);
            match both(p, &x) {
                Step::Empty => prop_assert!(false, "a box around a root declared empty"),
                Step::Unique(k) | Step::Contracted(k) => prop_assert!((0..3).all(|i| k[i].contains(r[i])), "root {r:?} lost: {k:?}"),
                Step::Failed => {}
            }
            // The same through inflation and tightening.
            let proven = inflate(&x, &Inflation { rounds: 4, own: 0.05, widest: 0.005, widest_of: &[0, 1, 2], absolute: 0.0, ulps: 4.0 }, |x| image3(p, x));
            if let Some(k) = proven {
                prop_assert!((0..3).all(|i| k[i].contains(r[i])));
            }
            let t = tighten(x, 1e-10, |x| both(p, x));
            prop_assert!((0..3).all(|i| t[i].contains(r[i])));
        }

        /// Uniqueness is never claimed for a box holding both roots.
        #[test]
        fn never_unique_with_two_roots(
            a in -2048..2048i32, gap in 1..1024i32, c in -3072..3072i32, d in -3072..3072i32,
            lo in prop::array::uniform3(0.0..0.5f64), hi in prop::array::uniform3(0.0..0.5f64),
        ) {
            let p = dyadic([a, a + gap, c, d], 1024.0);
            let [r, s] = roots3(p);
            let x: Vec<Interval> = (0..3).map(|i| interval(r[i].min(s[i]) - lo[i], r[i].max(s[i]) + hi[i])).collect();
            match both(p, &x) {
                Step::Unique(k) => prop_assert!(false, "unique claimed with two roots: {k:?}"),
                Step::Empty => prop_assert!(false, "a box around two roots declared empty"),
                Step::Contracted(k) => prop_assert!((0..3).all(|i| k[i].contains(r[i]) && k[i].contains(s[i]))),
                Step::Failed => {}
            }
        }
    }
}

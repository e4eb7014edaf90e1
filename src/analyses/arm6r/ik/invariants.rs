//! The first phase of 6R inverse kinematics: axis 4 seen from axis 1, from either side of the
//! split. Five invariants under turns about axis 1 (`line_invariants`) depend on joints 2, 3 on
//! one side and 6, 5 on the other (`Axis4Sides`); `invariants` writes their five equations in
//! joints 2, 3, 5, 6 alone, and `first_phase` searches them (mean-value test, one Gauss–Seidel
//! sweep, a split) while joints 1 and 4 keep their whole ranges.

use super::{dot, excludes_zero, sub3, Ik6Cell, Ik6Discard, Split, INVARIANTS};
use crate::analyses::arm6r::chain::{add, compose, cos_sin, cross, mul, mv, Affine, Side, V};
use crate::kernel::interval::fast::Iv;
use crate::kernel::interval::{interval, point, Interval};
use crate::kernel::search::Step;
use smallvec::smallvec;

/// `(a·u, u·u, a·d, u·d, (a×u)·d)` of the point `u` (from a point of axis 1) and direction `d`
/// of axis 4, `a` the direction of axis 1: unchanged by turns about axis 1, and with their
/// derivatives `(du, dd)` when given.
#[inline(always)]
fn line_invariants(a: &V, u: &V, d: &V) -> [Iv; INVARIANTS] {
    [dot(a, u), dot(u, u), dot(a, d), dot(u, d), dot(&cross(a, u), d)]
}

#[inline(always)]
fn line_invariants_derivative(a: &V, u: &V, d: &V, du: &V, dd: &V) -> [Iv; INVARIANTS] {
    [dot(a, du), dot(u, du).scale(2.0), dot(a, dd), add(dot(du, d), dot(u, dd)), add(dot(&cross(a, du), d), dot(&cross(a, u), dd))]
}

/// The five invariants of axis 4 seen from one side, over a box of that side's two joints
/// (`Side::Left`: joints 2, 3; `Side::Right`: joints 6, 5, in the right side's block order),
/// and their derivative columns in those two joints.
#[derive(Clone, Copy, Debug)]
pub(in crate::analyses::arm6r) struct SideValue {
    pub inv: [Iv; INVARIANTS],
    pub cols: [[Iv; INVARIANTS]; 2],
}

/// Which side of the invariants' equation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(in crate::analyses::arm6r) enum Half {
    /// Joints 2, 3 place axis 4 (joint 1 at 0: turning it leaves the invariants alone).
    Left,
    /// The pose and joints 6, 5 place it (joint 4 turns about axis 4 itself).
    Right,
}

/// Axis 4 seen from axis 1 from either side of the split, each side reduced to a chain of its
/// own two joints: the left side's first block is joint 1 at 0 (turning it moves axis 4 about
/// axis 1, which leaves the invariants alone), and the right side stops before joint 4 (which
/// turns about axis 4 itself).
pub(in crate::analyses::arm6r) struct Axis4Sides {
    left: Side<2>,
    right: Side<2>,
    /// A point and the direction of axis 1; the direction of axis 4 in its frame.
    c1: V,
    pub(super) a1: V,
    a4: V,
}

impl Axis4Sides {
    pub(in crate::analyses::arm6r) fn new(split: &Split) -> Axis4Sides {
        let (left, right, _, _) = split;
        let one = Iv { lo: 1.0, hi: 1.0 };
        let k0 = compose(&left.k0, &left.blocks[0].at(one, Iv::ZERO));
        Axis4Sides {
            left: Side { k0, blocks: [left.blocks[1], left.blocks[2]], axes: [left.axes[1], left.axes[2]] },
            right: Side { k0: right.k0, blocks: [right.blocks[0], right.blocks[1]], axes: [right.axes[0], right.axes[1]] },
            c1: left.k0.t,
            a1: mv(&left.k0.r, &left.axes[0]),
            a4: right.axes[2],
        }
    }

    /// One side's chain, its frames over `b` (its two joints), and axis 4 from it: its frame's
    /// origin relative to axis 1's point, and its direction (joint 1 at 0 on the left).
    #[inline(always)]
    pub(super) fn placed(&self, half: Half, b: &[[f64; 2]; 2]) -> (&Side<2>, [Affine; 7], V, V) {
        let side = match half {
            Half::Left => &self.left,
            Half::Right => &self.right,
        };
        let frames = side.frames(&[cos_sin(b[0][0], b[0][1]), cos_sin(b[1][0], b[1][1])]);
        let (u, d) = (sub3(&frames[2].t, &self.c1), mv(&frames[2].r, &self.a4));
        (side, frames, u, d)
    }

    /// One side's invariants over `b` (its two joints, see `SideValue`), with derivative
    /// columns when `cols` is set. The right side turns by −θ; its columns are the twists' all
    /// the same (the sign is the derivative's, and both uses take it with a symmetric factor
    /// or through the difference of the two sides, where the minus cancels).
    #[inline]
    pub(in crate::analyses::arm6r) fn value(&self, half: Half, b: &[[f64; 2]; 2], cols: bool) -> SideValue {
        let (side, frames, u, d) = self.placed(half, b);
        let inv = line_invariants(&self.a1, &u, &d);
        let mut out = SideValue { inv, cols: [[Iv::ZERO; INVARIANTS]; 2] };
        if cols {
            for blk in 0..2 {
                let (w, p) = side.axis(&frames, blk);
                out.cols[blk] = line_invariants_derivative(&self.a1, &u, &d, &cross(&w, &sub3(&frames[2].t, &p)), &cross(&w, &d));
            }
        }
        out
    }
}

/// Five equations in joints 2, 3, 5, 6 alone: axis 4 (its frame's origin and direction) seen
/// from axis 1 is the same from both sides (`Axis4Sides`). Residuals at `m` and Jacobian over
/// `b` as `equations`, or None when a residual's natural enclosure over `b` excludes 0.
pub(super) fn invariants(sides: &Axis4Sides, b: &[[f64; 2]; 6], m: &[f64; 6], jac: &mut [[Iv; 6]; INVARIANTS]) -> Option<[Iv; INVARIANTS]> {
    let (l, r) = (sides.value(Half::Left, &[b[1], b[2]], true), sides.value(Half::Right, &[b[5], b[4]], true));
    if (0..INVARIANTS).any(|i| excludes_zero(l.inv[i].sub(r.inv[i]))) {
        return None;
    }
    let (ml, mr) = (sides.value(Half::Left, &[[m[1]; 2], [m[2]; 2]], false), sides.value(Half::Right, &[[m[5]; 2], [m[4]; 2]], false));
    for row in jac.iter_mut() {
        *row = [Iv::ZERO; 6];
    }
    // The right side turns by −θ: its derivative is minus the twist's, and it enters with a
    // minus, so the column is the twist's.
    for i in 0..INVARIANTS {
        jac[i][1] = l.cols[0][i];
        jac[i][2] = l.cols[1][i];
        jac[i][5] = r.cols[0][i];
        jac[i][4] = r.cols[1][i];
    }
    Some([0, 1, 2, 3, 4].map(|i| ml.inv[i].sub(mr.inv[i])))
}

/// Joints 2, 3, 5, 6: the unknowns of the invariants.
pub(super) const INNER: [usize; 4] = [1, 2, 4, 5];

/// The first phase, on the invariants alone: their mean-value test, one Gauss–Seidel sweep,
/// then a split of joint 2, 3, 5 or 6 (joints 1 and 4 keep their whole ranges).
pub(super) fn first_phase(cell: &Ik6Cell, m: &[f64; 6], hm: &[Iv; INVARIANTS], jac: &[[Iv; 6]; INVARIANTS]) -> Step<Ik6Cell, ([Interval; 6], [Interval; 6]), Ik6Discard> {
    let b = cell.b;
    let mut dx: [Iv; 6] = [0, 1, 2, 3, 4, 5].map(|v| Iv { lo: b[v][0], hi: b[v][1] }.sub(Iv { lo: m[v], hi: m[v] }));
    for row in 0..INVARIANTS {
        let acc = INNER.iter().fold(hm[row], |acc, &v| add(acc, mul(jac[row][v], dx[v])));
        if excludes_zero(acc) {
            return Step::Discard(Ik6Discard::Axis4);
        }
    }
    let mut nb = b;
    for row in 0..INVARIANTS {
        for &v in &INNER {
            let a = jac[row][v];
            if !excludes_zero(a) {
                continue;
            }
            let rest = INNER.iter().filter(|&&u| u != v).fold(hm[row], |acc, &u| add(acc, mul(jac[row][u], dx[u])));
            let cut = (point(m[v]) - rest.to() / a.to()).intersection(interval(nb[v][0], nb[v][1]));
            if cut.is_empty() {
                return Step::Discard(Ik6Discard::Axis4);
            }
            nb[v] = [cut.inf(), cut.sup()];
            dx[v] = Iv { lo: nb[v][0], hi: nb[v][1] }.sub(Iv { lo: m[v], hi: m[v] });
        }
    }
    if INNER.iter().any(|&v| nb[v][1] - nb[v][0] < 0.8 * (b[v][1] - b[v][0])) {
        return Step::Split(smallvec![Ik6Cell { b: nb, ..*cell }]);
    }
    let smear = |v: usize| (0..INVARIANTS).map(|row| jac[row][v].lo.abs().max(jac[row][v].hi.abs())).sum::<f64>() * (nb[v][1] - nb[v][0]);
    let widest = INNER.into_iter().max_by(|&x, &y| (nb[x][1] - nb[x][0]).total_cmp(&(nb[y][1] - nb[y][0]))).unwrap_or(1);
    let v = match INNER.into_iter().filter(|&v| smear(v).is_finite()).max_by(|&x, &y| smear(x).total_cmp(&smear(y))) {
        Some(v) if smear(v) > 0.0 => v,
        _ => widest,
    };
    let c = 0.5 * (nb[v][0] + nb[v][1]);
    let (mut lo, mut hi) = (nb, nb);
    lo[v][1] = c;
    hi[v][0] = c;
    let child = |b| Ik6Cell { b, level: cell.level + 1, ..*cell };
    Step::Split(smallvec![child(lo), child(hi)])
}

//! Aspects (connected components of det Df ≠ 0 on the torus) and the largest number of
//! inverse-kinematics solutions, for arms outside the parallel-axes class of `verdict`.
//!
//! **Aspects**, from a cover of the singular curves by the leaves of a quadtree on a grid
//! of (θ₂, θ₃): every leaf is regular (det Df ≠ 0 on the closed leaf, one *piece* of one sign),
//! or **monotone**: for some direction k, ∂det/∂θₖ has one strict sign on the closed leaf, and
//! on each of its two edges θₖ = const det has one sign or is strictly monotone along the edge.
//! Along each segment in direction k det is then strictly monotone (say increasing), so
//! {det < 0} in the leaf is the union of the segments' lower parts, attached to the part of the
//! lower edge where det < 0, which is one interval: one connected piece, or none; likewise
//! {det > 0} with the upper edge. The argument holds for a leaf of any size, so a leaf is split
//! only while it is neither regular nor monotone (down to one grid cell): the curves are
//! covered by few large leaves where they are straight enough.
//! Pieces of one sign in two leaves sharing a stretch E of edge (the smaller leaf's side: the
//! leaves are dyadic squares) belong to one aspect exactly when det has that sign somewhere on
//! E, and the signs on E are known exactly: E lies on a regular leaf (its sign), or det over E
//! excludes zero, or det is strictly monotone along E (the signs of its two end points), or
//! these hold on each half of E (down to one grid cell's edge). A path within an aspect crosses
//! from leaf to leaf through such edge points (at a vertex, through the edges next to it), so
//! the components of the piece graph are exactly the aspects. A grid cell that is neither
//! regular nor monotone, or an edge whose signs are not decided, stops the argument (then a
//! finer grid is tried, and after that the count is `None` with the reason).
//!
//! **Largest number of IK solutions.** A 3R has at most 4 solutions at a point not on the
//! image of an internal-motion line (its inverse kinematics reduce to a quartic), and a
//! non-cuspidal one at most one per aspect. A sample point whose inverse kinematics run ends
//! complete with k solution boxes, each proven to hold exactly one, and nothing undecided, has
//! exactly k; so when a sample reaches the upper bound, the maximum is proven.

use super::curves::{det_over, Lines};
use super::drive::{drive, no_progress};
use crate::kernel::search::{Control, NoDiscard, Prune, Step};
use super::ik;
use super::Chain3R;
use crate::kernel::interval::{interval, point, strict_sign};
use inari::Interval;
use smallvec::smallvec;

/// Grid depths and shifts tried, in order. The shifts keep the grid lines off θ = 0, ±π,
/// where curves of arms symmetric in θ₂ are tangent to them (see `Cover::shifted`).
const GRIDS: [(u32, f64); 3] = [(8, 0.0123456789), (9, 0.0071234567), (10, 0.0031234567)];

/// What is known of one leaf.
#[derive(Clone, Copy, Debug)]
enum Cell {
    /// det ≠ 0 on the closed leaf, of this sign.
    Regular(bool),
    /// A monotone leaf; which signs occur in it (each as one piece).
    Arc { signs: [bool; 2] },
}

impl Cell {
    fn has(&self, s: bool) -> bool {
        match *self {
            Cell::Regular(t) => t == s,
            Cell::Arc { signs, .. } => signs[s as usize],
        }
    }
}

/// Why the aspects were not counted (on the last grid tried); `Display` is the sentence reports
/// show.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub(crate) enum AspectsUndecided {
    /// A limit stopped the cover of the singular curves.
    #[error("the singular-curve cover ({0} x {0}) was stopped by a limit")]
    CoverStopped(usize),
    /// A crossed cell is neither regular nor monotone with edges of known signs.
    #[error("a cell of the {grid} x {grid} cover around ({:.4}, {:.4}) is neither regular nor monotone in one direction with edges of known signs", at[0], at[1])]
    CellShape {
        /// cells per axis
        grid: usize,
        /// the cell's middle (θ₂, θ₃)
        at: [f64; 2],
    },
    /// The signs of det on an edge between two crossed cells were not decided.
    #[error("the signs of det on a cell edge of the {0} x {0} cover are not decided")]
    EdgeSigns(usize),
}

/// The number of aspects on the full torus, or why it is not proven.
pub(crate) fn count(chain: &Chain3R, control: &Control) -> Result<u32, AspectsUndecided> {
    let mut why = AspectsUndecided::EdgeSigns(0);
    for (depth, shift) in GRIDS {
        match count_at(chain, depth, shift, control) {
            Ok(n) => return Ok(n),
            Err(e) => why = e,
        }
    }
    Err(why)
}

/// A quadtree square: grid cells `i..i + s` (θ₂) by `j..j + s` (θ₃).
#[derive(Clone, Copy, Debug)]
struct Square {
    i: usize,
    j: usize,
    s: usize,
    level: u32,
}

/// Strict sign of det at a point.
fn sign_at(chain: &Chain3R, t2: f64, t3: f64) -> Option<bool> {
    strict_sign(chain.jets([point(t2), point(t3)], 1).det().value())
}

/// The signs det takes on an edge `e` (`free` the coordinate along it), exactly: one sign over
/// it, or strictly monotone along it (then the signs of its ends, each sign's set one interval
/// of the edge).
fn edge_signs(chain: &Chain3R, e: [Interval; 2], free: usize) -> Option<[bool; 2]> {
    let (det, grad) = det_over(chain, e);
    if let Some(s) = strict_sign(det) {
        return Some([!s, s]);
    }
    strict_sign(grad[free])?;
    let mut ends = [false; 2];
    for t in [e[free].inf(), e[free].sup()] {
        let mut p = [e[0].mid(), e[1].mid()];
        p[free] = t;
        ends[sign_at(chain, p[0], p[1])? as usize] = true;
    }
    Some(ends)
}

/// Splits a square until each leaf is regular or monotone (see the module doc); a grid cell
/// that is neither is left undecided.
struct LeafPrune<'a> {
    chain: &'a Chain3R,
    lines: &'a Lines,
}

const NOT_MONOTONE: &str = "neither regular nor monotone";

impl Prune for LeafPrune<'_> {
    type Cell = Square;
    type Found = (Square, Cell);
    type Reason = NoDiscard;

    fn process(&mut self, c: Square) -> Step<Square, (Square, Cell), NoDiscard> {
        let [a, b] = self.lines.span(c.i, c.s);
        let [d, e] = self.lines.span(c.j, c.s);
        let bx = [interval(a, b), interval(d, e)];
        let (det, grad) = det_over(self.chain, bx);
        if !det.is_empty() && !det.contains(0.0) {
            if let Some(s) = strict_sign(det) {
                return Step::Found((c, Cell::Regular(s)));
            }
        }
        // Monotone along k: each sign is one piece, attached to the part of the lower (negative)
        // or upper (positive) k-edge where det has that sign (swapped when decreasing); that
        // part is one interval of the edge.
        let arc = (0..2).find_map(|k| {
            let up = strict_sign(grad[k])?;
            let edge = |at: f64| {
                let mut x = bx;
                x[k] = point(at);
                edge_signs(self.chain, x, 1 - k)
            };
            let (lo, hi) = (edge(bx[k].inf())?, edge(bx[k].sup())?);
            let (neg_side, pos_side) = if up { (lo, hi) } else { (hi, lo) };
            Some(Cell::Arc { signs: [neg_side[0], pos_side[1]] })
        });
        if let Some(arc) = arc {
            return Step::Found((c, arc));
        }
        if c.s == 1 {
            return Step::Undecided(c, NOT_MONOTONE);
        }
        let (h, level) = (c.s / 2, c.level + 1);
        let sub = |di: usize, dj: usize| Square { i: c.i + di, j: c.j + dj, s: h, level };
        Step::Split(smallvec![sub(0, 0), sub(0, h), sub(h, 0), sub(h, h)])
    }

    fn level(&self, c: &Square) -> u32 {
        c.level
    }
}

/// `count` on one grid.
fn count_at(chain: &Chain3R, depth: u32, shift: f64, control: &Control) -> Result<u32, AspectsUndecided> {
    let n = 1usize << depth;
    let lines = Lines { n, shift };
    let run = drive(|| LeafPrune { chain, lines: &lines }, Square { i: 0, j: 0, s: n, level: 0 }, control, &mut no_progress);
    if !run.status.finished() {
        return Err(AspectsUndecided::CoverStopped(n));
    }
    // The first failing grid cell in grid order, whatever the driver's order.
    if let Some((c, _)) = run.undecided.iter().min_by_key(|(c, _)| (c.i, c.j)) {
        let mid = |i: usize| 0.5 * (lines.line(i) + lines.line(i + 1));
        return Err(AspectsUndecided::CellShape { grid: n, at: [mid(c.i), mid(c.j)] });
    }
    let mut leaves = run.found;
    leaves.sort_unstable_by_key(|(c, _)| (c.i, c.j));
    let mut leaf_of = vec![u32::MAX; n * n];
    for (k, (c, _)) in leaves.iter().enumerate() {
        for i in c.i..c.i + c.s {
            leaf_of[i * n + c.j..i * n + c.j + c.s].fill(k as u32);
        }
    }
    // The signs of det on a stretch of grid line: line `fixed` of direction `dir` (0: θ₂ =
    // const), cells `from..from + len` along it; halved where undecided, down to one cell.
    fn stretch_signs(chain: &Chain3R, lines: &Lines, dir: usize, fixed: usize, from: usize, len: usize) -> Option<[bool; 2]> {
        let mut e = [point(lines.line(fixed)); 2];
        let [a, b] = lines.span(from, len);
        e[1 - dir] = interval(a, b);
        if let Some(s) = edge_signs(chain, e, 1 - dir) {
            return Some(s);
        }
        if len == 1 {
            return None;
        }
        let h = len / 2;
        let (x, y) = (stretch_signs(chain, lines, dir, fixed, from, h)?, stretch_signs(chain, lines, dir, fixed, from + h, len - h)?);
        Some([x[0] || y[0], x[1] || y[1]])
    }
    // Pieces: node 2k + s for leaf k and sign s. Every adjacency is seen from the leaf below
    // it: walk each leaf's upper side in both directions (across the ±π seams), one stretch per
    // neighbouring leaf; the stretch is the smaller of the two sides.
    let mut pieces = Pieces::new(2 * leaves.len());
    for (ka, &(a, ca)) in leaves.iter().enumerate() {
        for dir in 0..2 {
            let (fixed_start, free_start) = if dir == 0 { (a.i, a.j) } else { (a.j, a.i) };
            let across = (fixed_start + a.s) % n;
            let mut at = free_start;
            while at < free_start + a.s {
                let cell = if dir == 0 { across * n + at } else { at * n + across };
                let kb = leaf_of[cell] as usize;
                let (b, cb) = leaves[kb];
                let b_free = if dir == 0 { b.j } else { b.i };
                let len = (free_start + a.s).min(b_free + b.s) - at;
                let signs = match (ca, cb) {
                    (Cell::Regular(s), _) | (_, Cell::Regular(s)) => [!s, s],
                    _ => stretch_signs(chain, &lines, dir, fixed_start + a.s, at, len).ok_or(AspectsUndecided::EdgeSigns(n))?,
                };
                for s in [false, true] {
                    if signs[s as usize] && ca.has(s) && cb.has(s) {
                        pieces.join(2 * ka + s as usize, 2 * kb + s as usize);
                    }
                }
                at += len;
            }
        }
    }
    // A piece that does not exist is joined to nothing and not counted.
    Ok((0..2 * leaves.len()).filter(|&p| leaves[p / 2].1.has(p % 2 == 1) && pieces.root(p) == p).count() as u32)
}

/// Union–find over the pieces.
struct Pieces {
    parent: Vec<usize>,
}

impl Pieces {
    fn new(n: usize) -> Self {
        Self { parent: (0..n).collect() }
    }

    fn root(&mut self, mut p: usize) -> usize {
        while self.parent[p] != p {
            self.parent[p] = self.parent[self.parent[p]];
            p = self.parent[p];
        }
        p
    }

    fn join(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.root(a), self.root(b));
        if ra != rb {
            self.parent[ra.max(rb)] = ra.min(rb);
        }
    }
}

/// The largest number of IK solutions of one point, proven when a sample reaches `bound`.
/// Samples: configurations around each of `near` (certified cusps: regions with more
/// solutions border their images, and may be small, as on the near-boundary robot), then the
/// (θ₂, θ₃) grid points, coarse grids first; their images are the points solved. Each inverse
/// kinematics run has `control`'s cell budget; its timeout and cancel flag bound them all.
/// Returns the best certified count seen and whether it reaches `bound`.
pub(crate) fn max_ik_solutions(chain: &Chain3R, bound: u32, near: &[[f64; 2]], control: &Control) -> (u32, bool) {
    // Each sample's IK is a tiny search on one thread; the samples are taken a batch at a time,
    // one per thread, with what the batches before left of the timeout. A batch that reaches
    // the bound ends the walk: no sample can exceed it (the bound is a theorem's), so the
    // answer is the one a sample-by-sample walk gives.
    let start = std::time::Instant::now();
    let mut best = 0u32;
    let around = near.iter().flat_map(|c| {
        [3e-2, 1e-2, 3e-3].into_iter().flat_map(move |r| (0..8).map(move |a| {
            let phi = a as f64 * std::f64::consts::FRAC_PI_4 + 0.1;
            [c[0] + r * phi.cos(), c[1] + r * phi.sin()]
        }))
    });
    // Offsets keep the grid samples off the lines of earlier grids and off symmetric spots.
    let t = |k: usize, n: usize| -std::f64::consts::PI + (k as f64 + 0.37) * std::f64::consts::TAU / n as f64;
    let grid = [8usize, 16, 32].into_iter().flat_map(move |n| (0..n * n).map(move |k| [t(k / n, n), t(k % n, n)]));
    let samples: Vec<[f64; 2]> = around.chain(grid).collect();
    let threads = control.threads.max(1);
    for batch in samples.chunks(threads) {
        let left = control.remaining_since(start);
        if left.limits.timeout.is_some_and(|t| t.is_zero()) || control.cancel.load(std::sync::atomic::Ordering::Relaxed) {
            break;
        }
        let sample = Control { threads: 1, ..left };
        let counts = crate::kernel::search::map_parallel(batch, threads, |&[t2, t3]| {
            let [rho, z] = chain.eval_f64(t2, t3);
            let s = ik::solve_with(chain, rho.max(0.0).sqrt(), z, 1e-9, &sample, &mut super::drive::no_progress).ok()?;
            (s.status.finished() && s.clusters.is_empty()).then_some(s.unique.len() as u32)
        });
        best = counts.into_iter().flatten().fold(best, u32::max);
        if best >= bound {
            return (best, true);
        }
    }
    (best, false)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::urdf;
    use crate::kernel::search::Limits;

    fn chain(text: &str) -> Chain3R {
        Chain3R::from_mechanism(&urdf::parse(text).expect("bundled"), 0.0).expect("3R")
    }

    /// Every grid that counts gives the same count (the number of aspects does not depend on
    /// the cover; robot f's 256 x 256 grid has a cell by an internal-motion line that is
    /// neither regular nor monotone, and the finer grids count), and a budget too small for
    /// the quadtree stops it with that reason.
    #[test]
    fn every_grid_counts_the_same_aspects_and_a_spent_budget_is_named() {
        let control = Control::with_limits(Limits::default());
        for (text, aspects) in [(include_str!("../../../urdf/orthogonal_3r_e.urdf"), 2), (include_str!("../../../urdf/orthogonal_3r_f.urdf"), 4)] {
            let c = chain(text);
            let counts: Vec<_> = GRIDS.iter().map(|&(depth, shift)| count_at(&c, depth, shift, &control)).collect();
            assert!(counts.iter().all(|n| matches!(n, Ok(k) if *k == aspects) || matches!(n, Err(AspectsUndecided::CellShape { .. }))), "{counts:?}");
            assert!(counts[1..].iter().all(|n| *n == Ok(aspects)), "{counts:?}");
            let tight = Control::with_limits(Limits { max_cells: 3, ..Limits::default() });
            assert_eq!(count(&c, &tight), Err(AspectsUndecided::CoverStopped(1024)));
        }
    }
}

//! Aspects (connected components of det Df ≠ 0 on the torus) and the largest number of
//! inverse-kinematics solutions, for arms outside the parallel-axes class of `verdict`.
//!
//! **Aspects**, from the singular-curve cover (`curves::Cover`): every cell of the grid is
//! regular (det Df ≠ 0 on the closed cell, one *piece* of one sign), or **monotone**: for some
//! direction k, ∂det/∂θₖ has one strict sign on the closed cell, and on each of its two edges
//! θₖ = const det has one sign or is strictly monotone along the edge. Along each segment in
//! direction k det is then strictly monotone (say increasing), so {det < 0} in the cell is the
//! union of the segments' lower parts, attached to the part of the lower edge where det < 0,
//! which is one interval: one connected piece, or none; likewise {det > 0} with the upper edge.
//! Pieces of one sign in two cells sharing an edge E belong to one aspect exactly when det has
//! that sign somewhere on E, and the signs on E are known exactly: E lies on a regular cell (its
//! sign), or det over E excludes zero, or det is strictly monotone along E (the signs of its
//! two end points). A path within an aspect crosses from cell to cell through such edge points (at a
//! vertex, through the edges next to it), so the components of the piece graph are exactly the
//! aspects. A cell that is neither regular nor an arc cell, or an end point whose sign is not
//! decided, stops the argument (then the grid is refined once, and after that the count is
//! `None` with the reason).
//!
//! **Largest number of IK solutions.** A 3R has at most 4 solutions at a point not on the
//! image of an internal-motion line (its inverse kinematics reduce to a quartic), and a
//! non-cuspidal one at most one per aspect. A sample point whose inverse kinematics run ends
//! complete with k solution boxes, each proven to hold exactly one, and nothing undecided, has
//! exactly k; so when a sample reaches the upper bound, the maximum is proven.

use super::curves::Cover;
use super::cusps::evaluate_without_tangency as evaluate;
use crate::search::Control;
use super::ik;
use super::Chain3R;
use crate::interval::{interval, point, strict_sign};
use inari::Interval;

/// Cover depths and grid shifts tried, in order. The shifts keep the grid lines off θ = 0, ±π,
/// where curves of arms symmetric in θ₂ are tangent to them (see `Cover::shifted`).
const GRIDS: [(u32, f64); 3] = [(8, 0.0123456789), (9, 0.0071234567), (10, 0.0031234567)];

/// What is known of one grid cell.
#[derive(Clone, Copy, Debug)]
enum Cell {
    /// det ≠ 0 on the closed cell, of this sign.
    Regular(bool),
    /// A monotone cell; which signs occur in it (each as one piece).
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
pub enum AspectsUndecided {
    /// A limit stopped the cover of the singular curves.
    #[error("the singular-curve cover ({0} x {0}) was stopped by a limit")]
    CoverStopped(usize),
    /// The sign of det at a regular cell was not decided.
    #[error("a regular cell's sign is not decided")]
    RegularSign,
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
pub fn count(chain: &Chain3R, control: &Control) -> Result<u32, AspectsUndecided> {
    let mut why = AspectsUndecided::RegularSign;
    for (depth, shift) in GRIDS {
        match count_at(chain, depth, shift, control) {
            Ok(n) => return Ok(n),
            Err(e) => why = e,
        }
    }
    Err(why)
}

/// `count` on one grid.
fn count_at(chain: &Chain3R, depth: u32, shift: f64, control: &Control) -> Result<u32, AspectsUndecided> {
    let cover = Cover::shifted(chain, depth, shift, control);
    if !cover.status.is_complete() {
        return Err(AspectsUndecided::CoverStopped(cover.n));
    }
    let n = cover.n;
    let side = |i: usize| {
        let [a, b] = cover.bounds(i);
        interval(a, b)
    };
    let at = |t2: f64, t3: f64| strict_sign(evaluate(chain, [point(t2), point(t3)]).det);
    // Regular regions' signs, from one cell of each.
    let mut region_sign: Vec<Option<bool>> = vec![None; cover.regions];
    for c in 0..n * n {
        let r = cover.region[c];
        if r >= 0 && region_sign[r as usize].is_none() {
            let (i, j) = (c / n, c % n);
            region_sign[r as usize] = Some(at(side(i).mid(), side(j).mid()).ok_or(AspectsUndecided::RegularSign)?);
        }
    }
    // The signs det takes on an edge (`free` the coordinate along it), exactly: one sign over
    // it, or strictly monotone along it (then the signs of its ends, each sign's set one
    // interval of the edge).
    let edge_signs = |e: [Interval; 2], free: usize| -> Option<[bool; 2]> {
        let ev = evaluate(chain, e);
        if let Some(s) = strict_sign(ev.det) {
            return Some([!s, s]);
        }
        strict_sign(ev.grad_det[free])?;
        let mut ends = [false; 2];
        for t in [e[free].inf(), e[free].sup()] {
            let mut p = [e[0].mid(), e[1].mid()];
            p[free] = t;
            ends[at(p[0], p[1])? as usize] = true;
        }
        Some(ends)
    };
    let mut cells: Vec<Cell> = (0..n * n).map(|c| Cell::Regular(region_sign.get(cover.region[c].max(0) as usize).copied().flatten().unwrap_or(false))).collect();
    // Each cover box's arc on its own (on the run's threads); the first failure in box order
    // is the one reported, as a box-by-box walk would.
    let arcs = crate::search::map_parallel(&cover.boxes, control.threads, |&(i, j)| {
        let b = [side(i), side(j)];
        let e = evaluate(chain, b);
        // Monotone along k: each sign is one piece, attached to the part of the lower (negative)
        // or upper (positive) k-edge where det has that sign (swapped when decreasing); that
        // part is one interval of the edge.
        let arc = (0..2).find_map(|k| {
            let up = strict_sign(e.grad_det[k])?;
            let edge = |at: f64| {
                let mut x = b;
                x[k] = point(at);
                edge_signs(x, 1 - k)
            };
            let (lo, hi) = (edge(b[k].inf())?, edge(b[k].sup())?);
            let (neg_side, pos_side) = if up { (lo, hi) } else { (hi, lo) };
            Some(Cell::Arc { signs: [neg_side[0], pos_side[1]] })
        });
        arc.ok_or(AspectsUndecided::CellShape { grid: n, at: [b[0].mid(), b[1].mid()] })
    });
    for (&(i, j), arc) in cover.boxes.iter().zip(arcs) {
        cells[i * n + j] = arc?;
    }
    // The signs of det on the edges between two arc cells (both sides crossed by the curve),
    // on the run's threads; edges beside a regular cell take its sign.
    let edge_of = |x: usize, dir: usize| {
        let (i, j) = (x / n, x % n);
        let mut edge = [side(i), side(j)];
        edge[dir] = point(edge[dir].sup());
        edge
    };
    let upper = |x: usize, dir: usize| if dir == 0 { ((x / n + 1) % n) * n + x % n } else { (x / n) * n + (x % n + 1) % n };
    let between_arcs: Vec<(usize, usize)> = (0..n * n).flat_map(|x| (0..2).map(move |dir| (x, dir))).filter(|&(x, dir)| matches!((cells[x], cells[upper(x, dir)]), (Cell::Arc { .. }, Cell::Arc { .. }))).collect();
    let arc_edge_signs: std::collections::HashMap<(usize, usize), Option<[bool; 2]>> =
        between_arcs.iter().copied().zip(crate::search::map_parallel(&between_arcs, control.threads, |&(x, dir)| edge_signs(edge_of(x, dir), 1 - dir))).collect();
    // Pieces: node 2c + s for cell c and sign s.
    let id = |c: usize, s: bool| 2 * c + s as usize;
    let mut joined = Vec::new();
    for x in 0..n * n {
        // For cell x = i·n + j: the upper neighbour in θ₂ (edge θ₂ = line i + 1, spanning θ₃ over
        // cell j), then in θ₃; the shared edge is seen from x: θ_dir fixed at x's upper bound.
        for dir in 0..2 {
            let y = upper(x, dir);
            let (cx, cy) = (cells[x], cells[y]);
            let signs: [bool; 2] = match (cx, cy) {
                (Cell::Regular(s), _) | (_, Cell::Regular(s)) => [!s, s],
                _ => arc_edge_signs[&(x, dir)].ok_or(AspectsUndecided::EdgeSigns(n))?,
            };
            for s in [false, true] {
                if signs[s as usize] && cx.has(s) && cy.has(s) {
                    joined.push((id(x, s), id(y, s)));
                }
            }
        }
    }
    // A piece that does not exist is joined to nothing: its own group, not counted.
    let pieces = crate::interval::components_of_edges(2 * n * n, joined);
    Ok(pieces.iter().filter(|g| cells[g[0] / 2].has(g[0] % 2 == 1)).count() as u32)
}

/// The largest number of IK solutions of one point, proven when a sample reaches `bound`.
/// Samples: configurations around each of `near` (certified cusps: regions with more
/// solutions border their images, and may be small, as on the near-boundary robot), then the
/// (θ₂, θ₃) grid points, coarse grids first; their images are the points solved. Each inverse
/// kinematics run has `control`'s cell budget; its timeout and cancel flag bound them all.
/// Returns the best certified count seen and whether it reaches `bound`.
pub fn max_ik_solutions(chain: &Chain3R, bound: u32, near: &[[f64; 2]], control: &Control) -> (u32, bool) {
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
        let counts = crate::search::map_parallel(batch, threads, |&[t2, t3]| {
            let [rho, z] = chain.eval_f64(t2, t3);
            let s = ik::solve_with(chain, rho.max(0.0).sqrt(), z, 1e-9, &sample, &mut super::drive::no_progress).ok()?;
            (s.status.is_complete() && s.clusters.is_empty()).then_some(s.unique.len() as u32)
        });
        best = counts.into_iter().flatten().fold(best, u32::max);
        if best >= bound {
            return (best, true);
        }
    }
    (best, false)
}

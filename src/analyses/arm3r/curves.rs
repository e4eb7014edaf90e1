//! The singular-curve cover of a 3R chain: the cells of a grid on (θ₂, θ₃) where det Df may
//! vanish, found by a quadtree on the kernel, and the regions between them. The ROS node's
//! `singular_curves` and `classify`, and the README's charts, all draw this one cover.

use super::drive::{drive, no_progress};
use crate::kernel::search::Control;
use super::motion::PI_UP;
use super::Chain3R;
use crate::kernel::interval::{interval, point, Bounds};
use crate::kernel::search::{Prune, Stats, Status, Step};
use inari::Interval;
use std::time::Instant;


/// The singular-curve cover: cells of an `n` × `n` grid on [-π, π]² (slightly wider: the range
/// of the searches) where det Df may vanish, and the regions between them.
///
/// A quadtree from the whole square drops a cell when the centred form of det Df over it
/// excludes zero; what survives to the finest level covers every singular configuration
/// (internal-motion lines included, where det Df = 0 too). Cells proven regular are grouped
/// into regions (4-neighbours, across the ±π seams): det Df keeps one sign on a region, which
/// therefore lies in one aspect.
#[derive(Clone, Debug)]
pub struct Cover {
    /// Cells per axis.
    pub n: usize,
    /// Cover cells (i over θ₂, j over θ₃), in grid order.
    pub boxes: Vec<(usize, usize)>,
    /// Connected component of each cover cell (8-neighbours, across the seams).
    pub cluster: Vec<usize>,
    /// Number of components.
    pub clusters: usize,
    /// Per cell (`i·n + j`): its region, or -1 for a cover cell.
    pub region: Vec<i32>,
    /// Number of regions.
    pub regions: usize,
    /// The quadtree run: `Complete` unless a limit stopped it (its pending cells are then in
    /// the cover whole, which keeps it sound).
    pub status: Status,
    /// Quadtree cells processed, and discarded as `regular`.
    pub stats: Stats,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// The grid's shift along both axes (radians; 0 for `new`): its lines are those of the
    /// unshifted grid plus `shift`.
    pub shift: f64,
}

/// A quadtree cell: grid cell (i, j) and side s (cells).
#[derive(Clone, Copy, Debug)]
pub(crate) struct QuadCell {
    i: usize,
    j: usize,
    s: usize,
    level: u32,
}

/// Drops a quadtree cell where det Df provably does not vanish.
struct CoverPrune<'a> {
    chain: &'a Chain3R,
    lines: &'a Lines,
}

/// Why the singular-curve cover discards a cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum CoverDiscard {
    /// det Df ≠ 0 on it.
    Regular,
}

impl crate::kernel::search::Reason for CoverDiscard {
    fn name(self) -> &'static str {
        match self {
            CoverDiscard::Regular => "regular",
        }
    }
}


impl Prune for CoverPrune<'_> {
    type Cell = QuadCell;
    type Found = (usize, usize);
    type Reason = CoverDiscard;

    fn process(&mut self, c: QuadCell) -> Step<QuadCell, (usize, usize), CoverDiscard> {
        let [a, b] = self.lines.span(c.i, c.s);
        let [d, e] = self.lines.span(c.j, c.s);
        if !det_may_vanish(self.chain, [interval(a, b), interval(d, e)]) {
            return Step::Discard(CoverDiscard::Regular);
        }
        if c.s == 1 {
            return Step::Found((c.i, c.j));
        }
        let h = c.s / 2;
        let level = c.level + 1;
        Step::Split([(0, 0), (0, h), (h, 0), (h, h)].into_iter().map(|(di, dj)| QuadCell { i: c.i + di, j: c.j + dj, s: h, level }).collect())
    }

    fn level(&self, c: &QuadCell) -> u32 {
        c.level
    }
}

/// The grid lines of an `n` × `n` grid (see `Cover::line`).
pub(super) struct Lines {
    pub(super) n: usize,
    pub(super) shift: f64,
}

impl Lines {
    pub(super) fn line(&self, i: usize) -> f64 {
        let base = if i == self.n { PI_UP } else { -PI_UP + (2.0 * PI_UP / self.n as f64) * i as f64 };
        base + self.shift
    }

    pub(super) fn span(&self, i: usize, s: usize) -> Bounds {
        [self.line(i), self.line(i + s)]
    }
}

impl Cover {
    /// The cover of `chain` on a `2^depth` × `2^depth` grid, within `control`.
    pub fn new(chain: &Chain3R, depth: u32, control: &Control) -> Self {
        Self::shifted(chain, depth, 0.0, control)
    }

    /// The cover on the grid shifted by `shift` along both axes (it still spans one period).
    /// Why: robots symmetric in θ₂ (det Df even in it) have singular curves tangent to the grid
    /// lines θ₂ = 0, ±π; a shift keeps such points off the lines, where `aspects` needs
    /// det monotone along cell edges.
    pub fn shifted(chain: &Chain3R, depth: u32, shift: f64, control: &Control) -> Self {
        let start = Instant::now();
        let n = 1usize << depth;
        let lines = Lines { n, shift };
        let root = QuadCell { i: 0, j: 0, s: n, level: 0 };
        let run = drive(|| CoverPrune { chain, lines: &lines }, root, control, &mut no_progress);
        let mut boxes = run.found;
        // A cell a limit left pending may hold singular points: all of it is in the cover.
        for (c, _) in &run.undecided {
            for di in 0..c.s {
                boxes.extend((0..c.s).map(|dj| (c.i + di, c.j + dj)));
            }
        }
        boxes.sort_unstable();
        let mut cover = Cover { n, shift, boxes, cluster: Vec::new(), clusters: 0, region: vec![0; n * n], regions: 0, status: run.status, stats: run.stats, seconds: 0.0 };
        for &(i, j) in &cover.boxes {
            cover.region[i * n + j] = -1;
        }
        cover.label_clusters();
        cover.label_regions();
        cover.seconds = start.elapsed().as_secs_f64();
        cover
    }

    /// Grid line `i` of `n`: -π (rounded up) + i·(2π/n), the same float for every cell that
    /// shares it, with the last line exactly π (rounded up).
    pub fn line(&self, i: usize) -> f64 {
        Lines { n: self.n, shift: self.shift }.line(i)
    }

    /// Bounds of grid column (or row) `i`.
    pub fn bounds(&self, i: usize) -> Bounds {
        Lines { n: self.n, shift: self.shift }.span(i, 1)
    }

    /// The cell holding (θ₂, θ₃), angles taken modulo 2π (rounding the reduction).
    pub fn cell_of(&self, t2: f64, t3: f64) -> Option<(usize, usize)> {
        let index = |t: f64| -> Option<usize> {
            if !t.is_finite() {
                return None;
            }
            let t = t - self.shift;
            let t = if (-PI_UP..=PI_UP).contains(&t) { t } else { t - std::f64::consts::TAU * (t / std::f64::consts::TAU).round() };
            let t = t + self.shift;
            let guess = (((t - self.shift + PI_UP) / (2.0 * PI_UP) * self.n as f64).floor() as i64).clamp(0, self.n as i64 - 1) as usize;
            // The guess may be one off at a grid line; the lines themselves decide.
            (guess.saturating_sub(1)..=(guess + 1).min(self.n - 1)).find(|&k| self.line(k) <= t && t <= self.line(k + 1))
        };
        Some((index(t2)?, index(t3)?))
    }

    /// Clusters: cover boxes touching (8-neighbours across the ±π seams), numbered by first box.
    fn label_clusters(&mut self) {
        let n = self.n;
        let mut at = vec![usize::MAX; n * n];
        for (k, &(i, j)) in self.boxes.iter().enumerate() {
            at[i * n + j] = k;
        }
        let boxes = &self.boxes;
        let groups = crate::kernel::interval::flood_fill(boxes.len(), |_| true, |k, out| {
            let (i, j) = boxes[k];
            for di in [n - 1, 0, 1] {
                for dj in [n - 1, 0, 1] {
                    let m = at[((i + di) % n) * n + (j + dj) % n];
                    if m != usize::MAX {
                        out.push(m);
                    }
                }
            }
        });
        (self.cluster, self.clusters) = crate::kernel::interval::labels(boxes.len(), &groups);
    }

    /// Regions: regular cells (region 0 until now) joined by 4-neighbours across the ±π seams,
    /// numbered by first cell; cover cells keep -1.
    fn label_regions(&mut self) {
        let n = self.n;
        let region = &self.region;
        let groups = crate::kernel::interval::flood_fill(n * n, |c| region[c] == 0, |c, out| {
            let (i, j) = (c / n, c % n);
            out.extend([((i + 1) % n, j), ((i + n - 1) % n, j), (i, (j + 1) % n), (i, (j + n - 1) % n)].map(|(a, b)| a * n + b));
        });
        for (k, g) in groups.iter().enumerate() {
            for &c in g {
                self.region[c] = k as i32;
            }
        }
        self.regions = groups.len();
    }
}

/// False when det Df provably does not vanish on `b` (centred form with the natural one).
fn det_may_vanish(chain: &Chain3R, b: [Interval; 2]) -> bool {
    det_over(chain, b).0.contains(0.0)
}

/// det Df over `b` (the centred form intersected with the natural one) and its gradient over
/// `b` (natural form).
pub(super) fn det_over(chain: &Chain3R, b: [Interval; 2]) -> (Interval, [Interval; 2]) {
    let m = [b[0].mid(), b[1].mid()];
    let over = chain.jets(b, 2).det();
    let at = chain.jets([point(m[0]), point(m[1])], 1).det().value();
    let g = over.grad();
    let centred = at + g[0] * (b[0] - point(m[0])) + g[1] * (b[1] - point(m[1]));
    (over.value().intersection(centred), g)
}


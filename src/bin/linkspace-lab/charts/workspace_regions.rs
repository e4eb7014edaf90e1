//! Workspace regions of a 3R arm in the half-section (ρ, z) with their number of inverse
//! kinematic solutions (the figures of Benoit, Delanoue, Lagrange and Wenger 2019).
//!
//! The images of the singular-curve cover's boxes (`arm3r::Cover`, enclosed by
//! `cusps::evaluate`) are rasterised on a grid of the half-plane; a cell they miss holds no
//! critical value of the map, so the number of solutions is constant on each connected component
//! of free cells (the map is proper: the torus is compact). One certified `ik::solve` at a
//! sample cell of each component gives that number, or `None` when the run leaves a cluster or
//! stops on a limit. What the raster cannot see: a region thinner than the images of the cover
//! boxes.

use linkspace::analyses::arm3r::{ik, Chain3R};

/// A region of free cells and its number of solutions.
#[derive(Clone, Debug)]
pub struct Region {
    /// The sample point (ρ, z): the region's cell nearest the mean of its cells.
    pub sample: (f64, f64),
    /// Cells in the region.
    pub cells: usize,
    /// Solutions at the sample, when every one is proven unique and nothing is left undecided.
    pub solutions: Option<usize>,
}

/// The components of the cells of a `grid × grid` raster of `[x.0, x.1] × [z.0, z.1]` that meet
/// no rectangle of `blocked` (`[ρ_lo, ρ_hi, z_lo, z_hi]`), each sampled by inverse kinematics.
pub fn regions(chain: &Chain3R, blocked: &[[f64; 4]], x: (f64, f64), z: (f64, f64), grid: usize) -> Vec<Region> {
    let (wx, wz) = ((x.1 - x.0) / grid as f64, (z.1 - z.0) / grid as f64);
    let mut free = vec![true; grid * grid];
    // Cells are closed: a rectangle touching a cell's edge blocks it, so two free neighbours
    // share an edge no image meets.
    let span = |lo: f64, hi: f64, o: f64, w: f64| -> (usize, usize) {
        let a = ((lo - o) / w).floor().max(0.0) as usize;
        let b = (((hi - o) / w).floor().max(0.0) as usize).min(grid - 1);
        (a.saturating_sub(1), (b + 1).min(grid - 1))
    };
    for r in blocked {
        if r[1] < x.0 || r[0] > x.1 || r[3] < z.0 || r[2] > z.1 {
            continue;
        }
        let (i0, i1) = span(r[0], r[1], x.0, wx);
        let (j0, j1) = span(r[2], r[3], z.0, wz);
        for i in i0..=i1 {
            let (a, b) = (x.0 + wx * i as f64, x.0 + wx * (i + 1) as f64);
            if b < r[0] || a > r[1] {
                continue;
            }
            for j in j0..=j1 {
                let (c, d) = (z.0 + wz * j as f64, z.0 + wz * (j + 1) as f64);
                if d >= r[2] && c <= r[3] {
                    free[i * grid + j] = false;
                }
            }
        }
    }
    let mut out = Vec::new();
    let free_regions = linkspace::kernel::interval::flood_fill(grid * grid, |c| free[c], |c, next| {
        let (i, j) = (c / grid, c % grid);
        if i > 0 {
            next.push(c - grid);
        }
        if i + 1 < grid {
            next.push(c + grid);
        }
        if j > 0 {
            next.push(c - 1);
        }
        if j + 1 < grid {
            next.push(c + 1);
        }
    });
    for members in free_regions {
        let centre = |c: usize| (x.0 + wx * ((c / grid) as f64 + 0.5), z.0 + wz * ((c % grid) as f64 + 0.5));
        let n = members.len() as f64;
        let (mx, mz) = members.iter().map(|&c| centre(c)).fold((0.0, 0.0), |(a, b), (p, q)| (a + p / n, b + q / n));
        let sample = members.iter().map(|&c| centre(c)).min_by(|a, b| ((a.0 - mx).powi(2) + (a.1 - mz).powi(2)).total_cmp(&((b.0 - mx).powi(2) + (b.1 - mz).powi(2)))).expect("a region has a cell");
        let solutions = ik::solve(chain, sample.0.max(0.0), sample.1, 1e-9, 200_000)
            .ok()
            .filter(|s| s.status.finished() && s.clusters.is_empty())
            .map(|s| s.unique.len());
        out.push(Region { sample, cells: members.len(), solutions });
    }
    out
}

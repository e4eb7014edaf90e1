//! Placing the points of a solved distance problem: trilateration from a solution's squared
//! distances, keeping both mirror images wherever no fourth point decides between them. Plain
//! floating point on midpoints; the certified placement is `formulate::coordinates`'.

use super::{combinations, DistanceProblem};
use nalgebra::Vector3;

/// Positions of every point from the squared distances `r` (`None` where unknown), by
/// trilateration: the points with coordinates stay put (or, when fewer than three have them, the
/// first triangle defines the frame), then each point is placed from three placed points it has
/// distances to. Where a fourth placed point off their plane decides between the two candidates it
/// does; otherwise both are kept, so the mirror images come out as separate embeddings. Both are
/// kept too when both fit the fourth point's distance within `tol` (squared-distance units): at a
/// tangency of the determinant curves two configurations share the solved distances.
/// Returns no embedding when some point cannot be reached.
pub(crate) fn embed(p: &DistanceProblem, r: &[Vec<Option<f64>>], tol: f64) -> Vec<Vec<[f64; 3]>> {
    let n = p.points.len();
    let mut start: Vec<Option<Vector3<f64>>> = p.points.iter().map(|q| q.xyz.map(|c| Vector3::new(c[0], c[1], c[2]))).collect();
    if start.iter().flatten().count() < 3 {
        // A frame from the first triangle with all three distances: a at 0, b on +x, c in xy, y > 0.
        start = vec![None; n];
        let tri = combinations(n, 3).into_iter().find(|t| t.iter().enumerate().all(|(k, &i)| t[k + 1..].iter().all(|&j| r[i][j].is_some())));
        let Some(t) = tri else { return Vec::new() };
        let (ab, ac, bc) = (r[t[0]][t[1]].unwrap_or(0.0), r[t[0]][t[2]].unwrap_or(0.0), r[t[1]][t[2]].unwrap_or(0.0));
        let d = ab.sqrt();
        let x = (ac - bc + ab) / (2.0 * d);
        let y = (ac - x * x).max(0.0).sqrt();
        start[t[0]] = Some(Vector3::zeros());
        start[t[1]] = Some(Vector3::new(d, 0.0, 0.0));
        start[t[2]] = Some(Vector3::new(x, y, 0.0));
    }
    // When the fixed points are coplanar, the mirror image through their plane of any placement
    // is another one.
    let fixed: Vec<Vector3<f64>> = start.iter().flatten().copied().collect();
    let plane = {
        let (a, b, c) = (fixed[0], fixed[1], fixed[2]);
        let nrm = (b - a).cross(&(c - a)).normalize();
        fixed.iter().all(|q| nrm.dot(&(q - a)).abs() <= 1e-9 * (1.0 + (q - a).norm())).then_some((a, nrm))
    };
    let mut done = Vec::new();
    let mut work = vec![start];
    while let Some(mut pos) = work.pop() {
        if pos.iter().all(|v| v.is_some()) {
            done.push(pos.iter().map(|v| v.map(|v| [v.x, v.y, v.z]).expect("invariant: all placed")).collect());
            continue;
        }
        // Pick the unplaced point with the best-conditioned reference triangle.
        let mut best: Option<(f64, usize, [usize; 3])> = None;
        for q in (0..n).filter(|&i| pos[i].is_none()) {
            let refs: Vec<usize> = (0..n).filter(|&i| pos[i].is_some() && r[q][i].is_some()).collect();
            for t in combinations(refs.len(), 3) {
                let [a, b, c] = [refs[t[0]], refs[t[1]], refs[t[2]]];
                let (pa, pb, pc) = (pos[a].expect("placed"), pos[b].expect("placed"), pos[c].expect("placed"));
                let area = (pb - pa).cross(&(pc - pa)).norm();
                if best.is_none_or(|(s, _, _)| area > s) {
                    best = Some((area, q, [a, b, c]));
                }
            }
        }
        let Some((area, q, [a, b, c])) = best else { continue };
        if area < 1e-12 {
            continue;
        }
        let (pa, pb, pc) = (pos[a].expect("placed"), pos[b].expect("placed"), pos[c].expect("placed"));
        let [ra, rb, rc] = [r[q][a], r[q][b], r[q][c]].map(|v| v.expect("chosen with distances"));
        let ex = (pb - pa).normalize();
        let i = ex.dot(&(pc - pa));
        let ey = (pc - pa - ex * i).normalize();
        let ez = ex.cross(&ey);
        let d = (pb - pa).norm();
        let j = ey.dot(&(pc - pa));
        let x = (ra - rb + d * d) / (2.0 * d);
        let y = (ra - rc + i * i + j * j) / (2.0 * j) - (i / j) * x;
        let z = (ra - x * x - y * y).max(0.0).sqrt();
        let base = pa + ex * x + ey * y;
        let candidates = [base + ez * z, base - ez * z];
        // A fourth placed point off the plane with a known distance decides.
        let judge = (0..n).filter(|&e| e != a && e != b && e != c && pos[e].is_some() && r[q][e].is_some()).find(|&e| ez.dot(&(pos[e].expect("placed") - pa)).abs() > 1e-6 * d.max(1.0));
        match judge {
            Some(e) if z > 1e-9 => {
                let pe = pos[e].expect("placed");
                let re = r[q][e].expect("has distance");
                let miss = |v: &Vector3<f64>| ((v - pe).norm_squared() - re).abs();
                let (m0, m1) = (miss(&candidates[0]), miss(&candidates[1]));
                if m0 <= tol && m1 <= tol && done.len() + work.len() < 16 {
                    let mut other = pos.clone();
                    other[q] = Some(candidates[1]);
                    work.push(other);
                }
                pos[q] = Some(if m0 <= m1 { candidates[0] } else { candidates[1] });
                work.push(pos);
            }
            _ if z <= 1e-9 => {
                pos[q] = Some(base);
                work.push(pos);
            }
            _ => {
                let mut other = pos.clone();
                other[q] = Some(candidates[1]);
                pos[q] = Some(candidates[0]);
                work.push(other);
                work.push(pos);
            }
        }
    }
    // Keep the placements that fit every distance within `tol`, or about as well as the best one
    // (mirror images fit equally well; a box midpoint is not exactly on the solution, and the
    // misfit it causes can exceed `tol`), and drop near-duplicates: a branch taken on a loose
    // fit often lands next to the other one.
    let misfit = |e: &Vec<[f64; 3]>| {
        let mut worst: f64 = 0.0;
        for a in 0..n {
            for b in a + 1..n {
                if let Some(rab) = r[a][b] {
                    let d: f64 = (0..3).map(|k| (e[a][k] - e[b][k]).powi(2)).sum();
                    worst = worst.max((d - rab).abs());
                }
            }
        }
        worst
    };
    let mut scored: Vec<(f64, Vec<[f64; 3]>)> = done.into_iter().map(|e| (misfit(&e), e)).collect();
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    let near = tol.sqrt().max(1e-6);
    let accept = tol.max(4.0 * scored.first().map_or(0.0, |s| s.0));
    let mut kept: Vec<Vec<[f64; 3]>> = Vec::new();
    for (m, e) in scored {
        if m > accept {
            continue;
        }
        let mirror = plane.map(|(a, nrm)| {
            e.iter()
                .map(|q| {
                    let v = Vector3::new(q[0], q[1], q[2]);
                    let w = v - nrm * (2.0 * nrm.dot(&(v - a)));
                    [w.x, w.y, w.z]
                })
                .collect::<Vec<_>>()
        });
        for f in std::iter::once(e).chain(mirror) {
            let dup = kept.iter().any(|g| g.iter().zip(&f).all(|(x, y)| (0..3).all(|c| (x[c] - y[c]).abs() <= near)));
            if !dup {
                kept.push(f);
            }
        }
    }
    kept
}

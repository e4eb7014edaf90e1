//! What `CayleyMenger::build` checks before writing a determinant, and the domains it gives
//! the unknowns: triangles and tetrahedra of known distances that can exist, a base of points
//! with coordinates that spans a plane, and bound smoothing of every pair's squared distance.
//! All in outward-rounded interval arithmetic, so a refusal is never a rounding artefact.

use super::{cayley_menger_determinant, collinear, combinations, key, DistanceError, DistanceProblem};
use crate::kernel::interval::{interval, point, Interval};
use crate::kernel::system::multilinear::Poly;
use nalgebra::Vector3;

pub(super) fn has_unknown(p: &DistanceProblem, s: &[usize]) -> bool {
    s.iter().enumerate().any(|(x, &a)| s[x + 1..].iter().any(|&b| p.known(a, b).is_none()))
}

/// Known-distance triangles must satisfy the triangle inequality: Ξ(a, b, c) = −16A² ≤ 0.
pub(super) fn check_triangles(p: &DistanceProblem) -> Result<(), DistanceError> {
    for t in combinations(p.points.len(), 3) {
        let (a, b, c) = (t[0], t[1], t[2]);
        let (Some(ab), Some(bc), Some(ca)) = (p.known(a, b), p.known(b, c), p.known(a, c)) else { continue };
        let r = [[point(0.0), ab, ca], [ab, point(0.0), bc], [ca, bc, point(0.0)]];
        let xi = collinear(&|i, j| Poly::constant(r[i][j])).eval(&[]);
        if xi.inf() > 0.0 {
            let name = |i: usize| p.points[i].name.clone();
            return Err(DistanceError::Triangle { a: name(a), b: name(b), c: name(c), ab: ab.mid(), bc: bc.mid(), ca: ca.mid() });
        }
    }
    Ok(())
}

/// Known-distance tetrahedra must have Ξ = 288V² ≥ 0.
pub(super) fn check_tetrahedra(p: &DistanceProblem) -> Result<(), DistanceError> {
    for t in combinations(p.points.len(), 4) {
        let mut r = [[point(0.0); 4]; 4];
        let mut all = true;
        for i in 0..4 {
            for j in 0..4 {
                if i != j {
                    match p.known(t[i], t[j]) {
                        Some(v) => r[i][j] = v,
                        None => all = false,
                    }
                }
            }
        }
        if all && cayley_menger_determinant(4, &|i, j| Poly::constant(r[i][j])).expect("4 points").eval(&[]).sup() < 0.0 {
            return Err(DistanceError::Tetrahedron(t.iter().map(|&i| p.points[i].name.as_str()).collect::<Vec<_>>().join(", ")));
        }
    }
    Ok(())
}

/// True when some three of `pts` span a triangle of non-negligible area.
pub(super) fn has_triangle(p: &DistanceProblem, pts: &[usize]) -> bool {
    combinations(pts.len(), 3).into_iter().any(|t| {
        let v = |k: usize| {
            let c = p.points[pts[t[k]]].xyz.expect("based points have coordinates");
            Vector3::new(c[0], c[1], c[2])
        };
        let (a, b, c) = (v(0), v(1), v(2));
        let scale = (b - a).norm().max((c - a).norm()).max(1e-300);
        (b - a).cross(&(c - a)).norm() > 1e-9 * scale * scale
    })
}

/// Domains of every pair's squared distance: known values, given ranges, and the triangle
/// inequality (bound smoothing on distances: `d_ij ≤ d_ik + d_kj`, `d_ij ≥ d_ik − d_kj`), all in
/// outward-rounded interval arithmetic.
pub(crate) fn bound_smoothing(p: &DistanceProblem) -> Result<Vec<Vec<Interval>>, DistanceError> {
    let n = p.points.len();
    let mut lo = vec![vec![0.0f64; n]; n];
    let mut hi = vec![vec![f64::INFINITY; n]; n];
    for a in 0..n {
        hi[a][a] = 0.0;
        for b in 0..n {
            if a == b {
                continue;
            }
            let r = p.known(a, b).or_else(|| p.ranges.get(&key(a, b)).copied());
            if let Some(r) = r {
                let d = r.sqrt();
                lo[a][b] = d.inf();
                hi[a][b] = d.sup();
            }
        }
    }
    for _ in 0..n + 2 {
        let mut changed = false;
        for k in 0..n {
            for a in 0..n {
                for b in 0..n {
                    if a == b || a == k || b == k {
                        continue;
                    }
                    // `point` is empty for an infinite bound: such a path bounds nothing.
                    let (hak, hkb) = (hi[a][k], hi[k][b]);
                    if hak.is_finite() && hkb.is_finite() {
                        let up = (point(hak) + point(hkb)).sup();
                        if up < hi[a][b] {
                            hi[a][b] = up;
                            changed = true;
                        }
                    }
                    let below = |l: f64, h: f64| if h.is_finite() { (point(l) - point(h)).inf() } else { 0.0 };
                    let down = below(lo[a][k], hkb).max(below(lo[k][b], hak));
                    if down > lo[a][b] {
                        lo[a][b] = down;
                        changed = true;
                    }
                }
            }
        }
        if !changed {
            break;
        }
    }
    let mut out = vec![vec![point(0.0); n]; n];
    for a in 0..n {
        for b in 0..n {
            if a == b {
                continue;
            }
            if lo[a][b] > hi[a][b] {
                return Err(DistanceError::NoRoom { a: p.points[a.min(b)].name.clone(), b: p.points[a.max(b)].name.clone() });
            }
            // A known distance keeps its own value; unknown ones get the smoothed range.
            out[a][b] = match p.known(a, b) {
                Some(r) => r,
                None => {
                    let r = interval(lo[a][b], hi[a][b]).sqr();
                    match p.ranges.get(&key(a, b)) {
                        Some(given) => r.intersection(*given),
                        None => r,
                    }
                }
            };
            if !out[a][b].sup().is_finite() && p.known(a, b).is_none() {
                return Err(DistanceError::Underdetermined {
                    unknowns: 1,
                    detail: format!("{} is unbounded: no path of known distances joins the two points; give it a range", p.pair_name(a.min(b), a.max(b))),
                });
            }
        }
    }
    Ok(out)
}

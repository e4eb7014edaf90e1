//! `linkspace-lab bench`: the bundled double butterfly, rigid and mobile, with the simplex
//! proposing the LP multipliers against clarabel (the baseline), both measured in the same run.
//! CuikSuite's figures were measured elsewhere and are printed as references, never as ratios.

use anyhow::{Context, Result};
use linkspace::model::urdf;
use linkspace::formulate::LinkageProblem;
use linkspace::kernel::search::SolverSettings;
use linkspace::app::LpBackend;
use std::io::Write;
use std::sync::atomic::AtomicBool;

#[derive(clap::Args)]
pub struct BenchArgs {
    /// Runs per case; the median is reported.
    #[arg(long, default_value_t = 5)]
    repeat: usize,
    /// Mobile-case sigma.
    #[arg(long, default_value_t = 0.05)]
    mobile_sigma: f64,
}

/// The bundled butterfly, compiled in so `bench` runs from anywhere.
const BUTTERFLY: &str = include_str!("../../../urdf/double_butterfly.urdf");

/// Where the peer figures come from, printed beside them.
const CUIK_SOURCE: &str = "reference, not run here: CPU s on the same 2-vCPU machine kind, recorded by 2026-11-22; README, \"Beside the peers\"";

pub fn run(args: BenchArgs) -> Result<()> {
    crate::check_repeat(args.repeat)?;
    let mechanism = urdf::parse(BUTTERFLY).context("bundled double_butterfly.urdf")?;
    let rigid = LinkageProblem::new(&mechanism, &[("joint6".to_string(), 12f64.atan2(5.0))], &[])?;
    let mobile = LinkageProblem::new(&mechanism, &[], &[])?;
    // CuikSuite's time, boxes and solution boxes, and the sigma it was run at.
    let cases = [("rigid, theta6 = atan2(12,5), sigma 1e-4", &rigid, 1e-4, (0.15, 15, 6, 1e-4)), ("mobile", &mobile, args.mobile_sigma, (28.9, 2523, 1229, 0.05))];
    let mut out = std::io::stdout().lock();
    writeln!(out, "case | LP backend | median CPU s | boxes processed | solution boxes | clusters | LPs | vs clarabel (same run)").ok();
    for (name, problem, sigma, (cuik_s, cuik_boxes, cuik_sol, cuik_sigma)) in cases {
        let mut baseline = None;
        for backend in [LpBackend::Clarabel, LpBackend::Simplex] {
            let settings = SolverSettings { sigma, lp_backend: backend, ..Default::default() };
            let solver = problem.solver(settings)?;
            let mut times = Vec::new();
            let mut last = None;
            for _ in 0..args.repeat {
                let e = solver.enclose(&AtomicBool::new(false), &mut |_| {});
                times.push(e.stats.cpu_seconds);
                last = Some(e);
            }
            let median = crate::median(times);
            let e = last.expect("repeat >= 1");
            let clusters = linkspace::kernel::interval::components(&e.solutions).1;
            let ratio = baseline.map_or("1.00x (baseline)".to_string(), |base: f64| crate::speed_against(base, median));
            writeln!(out, "{name} | {backend:?} | {median:.4} | {} | {} | {clusters} | {} | {ratio}", e.stats.processed, e.solutions.len(), e.stats.lp.solved).ok();
            baseline.get_or_insert(median);
        }
        writeln!(out, "{name} | CuikSuite, sigma {cuik_sigma:e} ({CUIK_SOURCE}) | {cuik_s} | {cuik_boxes} | {cuik_sol} | | | -").ok();
    }
    Ok(())
}

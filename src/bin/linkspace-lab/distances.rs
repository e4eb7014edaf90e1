//! `linkspace-lab bench-distances`: Tables I and II of Porta, Thomas, Ros and Torras (2003) in one
//! run. Their determinants as plain searches (split or shared variables, corner or
//! interval-arithmetic faces) against the certified pipeline
//! (`linkspace::analyses::distances::solve`), each row's CPU time against the case's baseline
//! measured in the same run; the paper's own figures (measured on a Pentium IV 1.8 GHz) are printed
//! beside them as references only.

use anyhow::{bail, Context, Result};
use linkspace::kernel::contract::FaceBounds;
use linkspace::analyses::distances::{solve as certified_solve, Choice};
use linkspace::model::urdf;
use linkspace::formulate::{BuildOptions, CayleyMenger, DistanceProblem as Problem, Formulation};
use linkspace::formulate::Placed;
use linkspace::analyses::distances::file as distance_file;
use linkspace::formulate::PlatformProblem;
use linkspace::kernel::search::{Enclosure, SolverSettings};
use std::io::Write;
use std::sync::atomic::AtomicBool;
use std::time::Duration;


#[derive(clap::Args)]
pub struct BenchArgs {
    /// Runs per case; the median CPU time is reported (the baselines run once).
    #[arg(long, default_value_t = 5)]
    repeat: usize,
    /// Time limit per baseline run (seconds): octahedral, the split formulation of
    /// Porta et al. (2003) with interval-arithmetic faces; four spheres, their split formulation
    /// with corners.
    #[arg(long, default_value_t = 30.0)]
    baseline_timeout: f64,
}

const OCTAHEDRAL: &str = include_str!("../../../urdf/octahedral.urdf");
const FOUR_SPHERES: &str = include_str!("../../../urdf/four_spheres.json");

/// One way of running a case.
#[derive(Clone, Copy)]
enum Method {
    /// The kernel on the determinants, no settling: boxes are neither certified nor labelled.
    Search(Formulation, FaceBounds),
    /// `distances::solve`: the search, then every cluster settled (certified or undecided).
    Settled(Choice),
    /// The line formulation's search alone (`Placed::build_line`, then its solver).
    Line,
}

/// What one run measured.
struct Measured {
    cpu: f64,
    complete: bool,
    processed: u64,
    solution_boxes: usize,
    clusters: usize,
    /// Proven and undecided; `None` when the run settles nothing.
    verdict: Option<(usize, usize)>,
    /// CPU seconds per phase (settled runs).
    phases: Vec<(&'static str, f64)>,
}

fn measure(p: &Problem, method: Method, redundant: bool, settings: &SolverSettings) -> Result<Measured> {
    let cancel = AtomicBool::new(false);
    let c0 = linkspace::kernel::search::process_cpu_seconds();
    let from_search = |e: Enclosure, cpu: f64| Measured {
        cpu,
        complete: e.status == linkspace::app::Status::Finished,
        processed: e.stats.processed,
        solution_boxes: e.solutions.len(),
        clusters: linkspace::kernel::interval::components(&e.solutions).1,
        verdict: None,
        phases: Vec::new(),
    };
    Ok(match method {
        Method::Search(formulation, faces) => {
            let cm = CayleyMenger::build(p, BuildOptions { formulation, redundant })?;
            let e = cm.solver(faces, settings.clone())?.enclose(&cancel, &mut |_| {});
            from_search(e, linkspace::kernel::search::process_cpu_seconds() - c0)
        }
        Method::Line => {
            let e = Placed::build_line(p)?.solver(settings.clone())?.enclose(&cancel, &mut |_| {});
            from_search(e, linkspace::kernel::search::process_cpu_seconds() - c0)
        }
        Method::Settled(choice) => {
            let c = certified_solve(p, choice, redundant, FaceBounds::Corners, settings.clone(), &cancel)?;
            Measured {
                cpu: c.stats.cpu_seconds,
                complete: c.status == linkspace::app::Status::Finished,
                processed: c.stats.processed,
                solution_boxes: c.solutions.len(),
                clusters: c.clusters.len(),
                verdict: Some((c.proven(), c.undecided_regions())),
                phases: c.phases,
            }
        }
    })
}

/// Tables I and II of Porta et al. (2003) in one run (see the module's doc): the line formulation
/// for the spheres, the settled shared determinants for the platforms.
pub fn bench(args: BenchArgs) -> Result<()> {
    crate::check_repeat(args.repeat)?;
    if !(args.baseline_timeout > 0.0) {
        bail!("--baseline-timeout must be positive");
    }
    let mut out = std::io::stdout().lock();
    writeln!(out, "case | method | CPU s (median) | boxes processed | solution boxes | clusters | proven | undecided | vs baseline (same run) | seed's published figures (Pentium IV 1.8 GHz; reference, not run here) | where the time goes").ok();
    // Runs `repeat` times (a baseline once, under its time limit) and keeps the median.
    let run = |p: &Problem, method: Method, redundant: bool, settings: &SolverSettings, repeat: usize| -> Result<Measured> {
        let mut all = (0..repeat).map(|_| measure(p, method, redundant, settings)).collect::<Result<Vec<_>>>()?;
        all.sort_by(|a, b| a.cpu.total_cmp(&b.cpu));
        Ok(all.swap_remove(all.len() / 2))
    };
    let limit = args.baseline_timeout;
    let row = |out: &mut std::io::StdoutLock, case: &str, label: &str, m: &Measured, base: Option<(f64, bool)>, seed: &str| {
        // The limit is wall-clock time (the kernel's); on a loaded machine the CPU time is less.
        let t = if m.complete { format!("{:.4}", m.cpu) } else { format!("> {:.1} (stopped by the {limit} s wall-clock limit)", m.cpu) };
        let ratio = match base {
            None => "1.00x (baseline)".to_string(),
            Some((b, true)) => format!("{:.1}x", b / m.cpu),
            Some((b, false)) => format!("> {:.1}x", b / m.cpu),
        };
        let (proven, undecided) = m.verdict.map_or(("-".to_string(), "-".to_string()), |(p, u)| (p.to_string(), u.to_string()));
        let phases: Vec<String> = m.phases.iter().filter(|(_, s)| *s >= 0.0005).map(|(n, s)| format!("{n} {s:.3}")).collect();
        writeln!(out, "{case} | {label} | {t} | {} | {} | {} | {proven} | {undecided} | {ratio} | {seed} | {}", m.processed, m.solution_boxes, m.clusters, phases.join("; ")).ok();
    };
    let baseline_limit = Some(Duration::from_secs_f64(args.baseline_timeout));
    let legs = ["leg15", "leg16", "leg26", "leg24", "leg34", "leg35"];
    let configs = [("a", [4.25, 5.75, 4.25, 5.75, 4.25, 5.75]), ("b", [4.75; 6])];
    // Table I: t, b_p, n_s, for corners and (in parentheses) interval arithmetic.
    let seed_table = [[("<0.01", 7, 2, "0.09", 851, 86), ("<0.01", 3, 2, "0.35", 1477, 67)], [("0.03", 65, 27, "0.28", 2173, 680), ("0.03", 39, 8, "2.15", 6841, 764)]];
    for (ci, (cname, lengths)) in configs.iter().enumerate() {
        let fixed: Vec<(String, f64)> = legs.iter().map(|l| l.to_string()).zip(lengths.iter().copied()).collect();
        let m = urdf::parse(OCTAHEDRAL).context("bundled octahedral.urdf")?;
        let p = PlatformProblem::new(&m, &fixed)?;
        for (ri, redundant) in [false, true].into_iter().enumerate() {
            let settings = SolverSettings { sigma: 0.1, rho: 0.9, ..Default::default() };
            let case = format!("octahedral {cname}{}, sigma 0.1", if redundant { ", redundant" } else { "" });
            let s = seed_table[ci][ri];
            let baseline = run(&p.distances, Method::Search(Formulation::Split, FaceBounds::IntervalArithmetic), redundant, &SolverSettings { timeout: baseline_limit, ..settings.clone() }, 1)?;
            row(&mut out, &case, "split, interval faces, search only (baseline)", &baseline, None, &format!("t {} s, b_p {}, n_s {}", s.3, s.4, s.5));
            let base = Some((baseline.cpu, baseline.complete));
            for (label, method, seed) in [
                ("split, corners, search only (Porta, Thomas, Ros and Torras 2003)", Method::Search(Formulation::Split, FaceBounds::Corners), format!("t {} s, b_p {}, n_s {}", s.0, s.1, s.2)),
                ("shared, Bernstein, search only (no settling)", Method::Search(Formulation::Shared, FaceBounds::Corners), String::new()),
                ("shared, Bernstein, settled (certified; the default)", Method::Settled(Choice::Auto), String::new()),
            ] {
                let m = run(&p.distances, method, redundant, &settings, args.repeat)?;
                row(&mut out, &case, label, &m, base, &seed);
            }
        }
    }
    // Table II: the four spheres, rho 0.99 for the determinants (C1-C4 of Porta et al. 2003), the
    // `distances` command's default for the coordinate formulations (0.9) for the line.
    let d = distance_file::parse(FOUR_SPHERES, &[])?;
    for (sigma, seed) in [(0.1, "t 315 s, b_p 7875, n_s 870"), (0.01, "t 385 s, b_p 14579, n_s 813")] {
        let case = format!("four spheres, sigma {sigma}");
        let cm_settings = SolverSettings { sigma, rho: 0.99, ..Default::default() };
        let line_settings = SolverSettings { sigma, rho: 0.9, ..Default::default() };
        let baseline = run(&d, Method::Search(Formulation::Split, FaceBounds::Corners), true, &SolverSettings { timeout: baseline_limit, ..cm_settings.clone() }, 1)?;
        row(&mut out, &case, "split, corners, C1-C4, search only (Porta, Thomas, Ros and Torras 2003; baseline)", &baseline, None, seed);
        let base = Some((baseline.cpu, baseline.complete));
        for (label, method, settings) in [
            ("shared, Bernstein, C1-C4, search only (no settling)", Method::Search(Formulation::Shared, FaceBounds::Corners), &cm_settings),
            ("shared, Bernstein, C1-C4, settled (certified)", Method::Settled(Choice::Shared), &cm_settings),
            ("line, search only", Method::Line, &line_settings),
            ("line, settled (certified; the default)", Method::Settled(Choice::Auto), &line_settings),
        ] {
            let m = run(&d, method, true, settings, args.repeat)?;
            row(&mut out, &case, label, &m, base, "");
        }
    }
    Ok(())
}

//! `linkspace-lab bench3r`: cusp and node searches on the bundled 3R robots in CPU seconds, the
//! Krawczyk cusp search against bisection alone (the baseline) in the same run, and against Ibex
//! when `ibexsolve` is on PATH: run here on the same cusp systems, at the same precision and with
//! the same internal-motion exclusion (`ibex`). Ibex's stored figures, measured elsewhere, are
//! printed as dated references with their settings, never as ratios. The last columns time
//! the `singularities` job as the CLI runs it (`app::singularities`: the cusp search, then the
//! cuspidality verdict with its aspects and IK counts; no nodes), in the same process.

use anyhow::Result;
use linkspace::analyses::arm3r::{
    self,
    cusps::{self, CuspSettings, Method},
    nodes::{self, NodeSettings},
    Chain3R,
};
use linkspace::app;
use linkspace::analyses::arm3r::LoadOptions;
use linkspace::model::urdf;
use linkspace::kernel::search::{Control, Limits};
use std::io::Write;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Bench3rArgs {
    /// Runs per case; the median is reported.
    #[arg(long, default_value_t = 5)]
    pub repeat: usize,
    /// Precision of every search.
    #[arg(long, default_value_t = 1e-4)]
    pub precision: f64,
    /// Instead: per bundled real arm (PUMA 560, KR 16, UR5, iiwa 14 with joint_3 locked) and
    /// robot of Benoit et al. (2019), `linkspace singularities FILE` as it ships against the
    /// previous behaviour on the same chain (interval cusp and node searches, full torus, bounded),
    /// each run as a child process: wall time, peak RSS, status, undecided count, ratios.
    #[arg(long)]
    pub arms: bool,
    /// With --arms: the baseline's time limit (seconds, per run).
    #[arg(long, default_value_t = 20.0)]
    pub timeout: f64,
    /// With --arms: the baseline's box limit (boxes, box pairs for nodes; per search).
    #[arg(long, default_value_t = 2_000_000)]
    pub max_boxes: u64,
    /// Internal: one baseline run of --arms on this file (one JSON line).
    #[arg(long, hide = true, value_name = "URDF")]
    pub baseline_child: Option<PathBuf>,
    /// Internal, with --baseline-child: joints to lock.
    #[arg(long, hide = true, value_name = "JOINT=VALUE", allow_hyphen_values = true)]
    pub lock: Vec<String>,
}

/// The bundled 3R robots, compiled in so `bench3r` runs from anywhere, with Ibex's CPU seconds
/// for the cusps (D&G2, robot f with the internal-motion lines excluded, as linkspace does) and
/// for the nodes (separation 1e-2): references, printed with `IBEX_REFERENCE`, never divided.
pub const ROBOTS: [(&str, &str, f64, f64); 5] = [
    ("a", include_str!("../../../urdf/orthogonal_3r_a.urdf"), 0.0354, 0.4632),
    ("b", include_str!("../../../urdf/orthogonal_3r_b.urdf"), 0.0408, 0.8278),
    ("d", include_str!("../../../urdf/orthogonal_3r_d.urdf"), 0.0153, 0.0990),
    ("e", include_str!("../../../urdf/orthogonal_3r_e.urdf"), 0.0304, 0.4202),
    ("f", include_str!("../../../urdf/orthogonal_3r_f.urdf"), 0.0318, 0.2216),
];

/// Where the stored Ibex figures come from and how they were run.
const IBEX_REFERENCE: &str = "Ibex 2.9.1 ibexsolve -e 1e-4, CPU s of the child (user + system), median of 3, recorded 2026-11-25 on 2 shared vCPUs (docs/peers.md), not run here: cusps on D&G2 (det Df = 0 and the second row of Benoit, Delanoue, Lagrange and Wenger 2019; its extra roots are not cusps), robot f with the internal-motion lines excluded as linkspace excludes them (without the exclusion: 59 s and 186,320 unknown boxes); nodes with the separation (t2 - u2)^2 + (t3 - u3)^2 >= 1e-2, which linkspace's node search does not need (a different problem)";

/// CPU seconds of `f` (this process, every thread) and its value.
fn cpu<T>(f: impl FnOnce() -> T) -> (f64, T) {
    let c0 = linkspace::kernel::search::process_cpu_seconds();
    let r = f();
    (linkspace::kernel::search::process_cpu_seconds() - c0, r)
}

pub fn run(args: Bench3rArgs) -> Result<()> {
    crate::check_repeat(args.repeat)?;
    arm3r::check_precision(args.precision)?;
    if let Some(file) = &args.baseline_child {
        return crate::bench_arms::baseline_child(&args, file);
    }
    if args.arms {
        return crate::bench_arms::run(&args);
    }
    let ibex = crate::ibex::on_path();
    let mut out = std::io::stdout().lock();
    match &ibex {
        Some(exe) => writeln!(out, "baseline peer: {} (run here on the same cusp systems, same precision, same internal-motion exclusion)", exe.display()),
        None => writeln!(out, "baseline peer: ibexsolve not on PATH, so no ratio against Ibex (its stored figures follow as references)"),
    }
    .ok();
    writeln!(
        out,
        "robot | cusps: Krawczyk CPU s | found | undecided | bisection baseline CPU s | clusters | speed-up (same run) | Ibex D&G2 CPU s (same run) | Ibex solutions, unknown | vs Ibex (same run, CPU/CPU) | nodes CPU s | found | undecided | job: cusps and verdict CPU s | verdict"
    )
    .ok();
    for (name, xml, _, _) in ROBOTS {
        let chain = Chain3R::from_mechanism(&urdf::parse(xml)?, 0.0)?;
        let run = |method| {
            let settings = CuspSettings { precision: args.precision, method };
            let mut times = Vec::new();
            let mut last = None;
            for _ in 0..args.repeat {
                let (t, r) = cpu(|| cusps::search(&chain, &settings).expect("validated precision"));
                times.push(t);
                last = Some(r);
            }
            (crate::median(times), last.expect("repeat >= 1"))
        };
        let (t_base, base) = run(Method::Bisection);
        let (t_k, k) = run(Method::Krawczyk);
        let peer = match &ibex {
            Some(exe) => {
                // The θ₃ ranges linkspace decides: the internal-motion strips set aside.
                let strips: Vec<[f64; 2]> = k.bands.iter().map(|b| b.strip).collect();
                let pieces = crate::ibex::outside(&strips);
                let mut times = Vec::new();
                let mut last = None;
                for _ in 0..args.repeat {
                    let r = crate::ibex::run(exe, &chain, &pieces, args.precision)?;
                    times.push(r.cpu);
                    last = Some(r);
                }
                let (t, r) = (crate::median(times), last.expect("repeat >= 1"));
                format!("{t:.4} | {}, {} | {}", r.solutions, r.unknown, crate::speed_against(t, t_k))
            }
            None => "- | - | -".to_string(),
        };
        let mut node_times = Vec::new();
        let mut node_run = None;
        for _ in 0..args.repeat {
            let (t, r) = cpu(|| nodes::search(&chain, &k.cusps, &k.bands, &NodeSettings { precision: args.precision }));
            node_times.push(t);
            node_run = Some(r?);
        }
        let (t_n, n) = (crate::median(node_times), node_run.expect("repeat >= 1"));
        let arm = app::Arm::load(&urdf::parse(xml)?, &LoadOptions::default(), 0.0)?;
        let request = app::SingularitiesRequest { precision: args.precision, nodes: false, search_anyway: false, verdict: true };
        let control = Control::with_limits(Limits { max_cells: cusps::DEFAULT_MAX_BOXES, ..Limits::default() });
        let mut job_times = Vec::new();
        let mut job = None;
        for _ in 0..args.repeat {
            let (t, r) = cpu(|| app::singularities(&arm, &request, &control, &mut |_| {}));
            job_times.push(t);
            job = Some(r?);
        }
        let t_job = crate::median(job_times);
        let verdict = job.and_then(|j| j.verdict).map_or("-".to_string(), |v| {
            let c = match v.cuspidal {
                Some(true) => "cuspidal",
                Some(false) => "non-cuspidal",
                None => "undecided",
            };
            let n = |x: Option<u32>| x.map_or("?".to_string(), |v| v.to_string());
            format!("{c}, {} aspects, {} IK", n(v.aspects), n(v.max_ik_solutions))
        });
        writeln!(
            out,
            "{name} | {t_k:.4} | {} | {} | {t_base:.4} | {} | {} | {peer} | {t_n:.4} | {} | {} | {t_job:.4} | {verdict}",
            k.cusps.len(),
            k.undecided.len(),
            base.cusps.len(),
            crate::speed_against(t_base, t_k),
            n.nodes.len(),
            n.undecided.len(),
        )
        .ok();
    }
    let refs: Vec<String> = ROBOTS.iter().map(|(name, _, c, n)| format!("{name}: cusps {c} s, nodes {n} s")).collect();
    writeln!(out, "references: {}. {IBEX_REFERENCE}.", refs.join("; ")).ok();
    Ok(())
}

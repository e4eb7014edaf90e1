//! `linkspace-lab bench3r`: cusp and node searches on the bundled 3R robots, the Krawczyk cusp
//! search against bisection alone (the baseline) in the same run. Ibex's figures were measured
//! elsewhere, in CPU seconds; they are printed as references beside ours, never as ratios.

use anyhow::Result;
use linkspace::manip3r::{
    self,
    cusps::{self, CuspSettings, Method},
    nodes::{self, NodeSettings},
    Chain3R,
};
use linkspace::model::urdf;
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
    /// seed robot, `linkspace singularities FILE` as it ships against the previous behaviour on
    /// the same chain (interval cusp and node searches, full torus, bounded), each run as a
    /// child process: wall time, peak RSS, status, undecided count, ratios.
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
/// for the cusps and for the nodes (README, "Beside the peers").
pub const ROBOTS: [(&str, &str, f64, f64); 5] = [
    ("a", include_str!("../../../urdf/orthogonal_3r_a.urdf"), 0.034, 0.32),
    ("b", include_str!("../../../urdf/orthogonal_3r_b.urdf"), 0.077, 0.54),
    ("d", include_str!("../../../urdf/orthogonal_3r_d.urdf"), 0.019, 0.08),
    ("e", include_str!("../../../urdf/orthogonal_3r_e.urdf"), 0.031, 0.44),
    ("f", include_str!("../../../urdf/orthogonal_3r_f.urdf"), 59.0, 0.21),
];

pub fn run(args: Bench3rArgs) -> Result<()> {
    crate::check_repeat(args.repeat)?;
    manip3r::check_precision(args.precision)?;
    if let Some(file) = &args.baseline_child {
        return crate::bench_arms::baseline_child(&args, file);
    }
    if args.arms {
        return crate::bench_arms::run(&args);
    }
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "robot | cusps: Krawczyk wall s | found | undecided | bisection baseline wall s | clusters | speed-up (same run) | Ibex cusps CPU s (reference) | nodes wall s | found | undecided | Ibex nodes CPU s, separated (reference)"
    )
    .ok();
    for (name, xml, ibex_cusps, ibex_nodes) in ROBOTS {
        let chain = Chain3R::from_mechanism(&urdf::parse(xml)?, 0.0)?;
        let run = |method| {
            let settings = CuspSettings { precision: args.precision, method };
            let mut times = Vec::new();
            let mut last = None;
            for _ in 0..args.repeat {
                let r = cusps::search(&chain, &settings).expect("validated precision");
                times.push(r.seconds);
                last = Some(r);
            }
            (crate::median(times), last.expect("repeat >= 1"))
        };
        let (t_base, base) = run(Method::Bisection);
        let (t_k, k) = run(Method::Krawczyk);
        let mut node_times = Vec::new();
        let mut node_run = None;
        for _ in 0..args.repeat {
            let r = nodes::search(&chain, &k.cusps, &k.bands, &NodeSettings { precision: args.precision })?;
            node_times.push(r.seconds);
            node_run = Some(r);
        }
        let (t_n, n) = (crate::median(node_times), node_run.expect("repeat >= 1"));
        writeln!(
            out,
            "{name} | {t_k:.4} | {} | {} | {t_base:.4} | {} | {:.1}x | {ibex_cusps} | {t_n:.4} | {} | {} | {ibex_nodes}",
            k.cusps.len(),
            k.undecided.len(),
            base.cusps.len(),
            t_base / t_k,
            n.nodes.len(),
            n.undecided.len(),
        )
        .ok();
    }
    writeln!(
        out,
        "Ibex: CPU seconds at precision 1e-4, best formulation, nodes with a separation constraint, recorded by 2026-11-22 on the same 2-vCPU machine kind, not run here (README, \"Beside the peers\"); case f's cusp figure ends with 186,320 undecided boxes. Wall and CPU seconds are not comparable, so no ratio is given."
    )
    .ok();
    Ok(())
}

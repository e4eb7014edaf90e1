//! `linkspace loop-singularities`: certified singular sets of closed-loop linkages (issue 13),
//! planar or spatial (the model `solve --model auto` picks), on the polynomial solver through
//! `singular` (the searches on the systems of `problems::singular`).

use super::{parse_fix, LimitArgs};
use anyhow::{bail, Context, Result};
use linkspace::model::urdf;
use linkspace::problems::singular::image::{CuspProblem, NodeProblem};
use linkspace::problems::singular::{Output, SingularKind, SingularProblem};
use linkspace::singular::image;
use linkspace::singular::sets::{all_kinds, Actuation, SingularSets};
use linkspace::report::singular::SingularReport;
use linkspace::search::SolverSettings;
use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

#[derive(Clone, Copy, clap::ValueEnum)]
pub(crate) enum Kind {
    /// C-space singularities (bifurcations): the loop constraints lose rank.
    Cspace,
    /// Input (type II): locked actuators, the mechanism still moves.
    Input,
    /// Output (type I): the output stands still, the mechanism moves.
    Output,
    /// All three.
    All,
    /// 2-dof mechanisms: cusps and nodes of the type-II image in actuator space, the regions it
    /// cuts with their assembly modes, and the verdict on non-singular assembly-mode change.
    Image,
}

#[derive(clap::Args)]
pub(crate) struct LoopSingularitiesArgs {
    /// URDF file of a closed-loop linkage, planar or spatial (loops closed with <loop>, see README).
    urdf: PathBuf,
    /// Which singular set(s).
    #[arg(long, value_enum, default_value_t = Kind::All)]
    kind: Kind,
    /// Actuated joints, comma separated. Default: the joints of the URDF's <transmission> elements.
    #[arg(long, value_name = "J1,J2,...")]
    actuated: Option<String>,
    /// Output of type-I singularities: a point LINK@X,Y, or joints J1,J2 (default: every passive joint).
    #[arg(long, value_name = "LINK@X,Y | J1,J2")]
    output: Option<String>,
    /// Fix a joint value (radians or metres). Repeatable.
    #[arg(long = "fix", value_name = "JOINT=VALUE")]
    fix: Vec<String>,
    /// Boxes are at most this wide in every primary variable (configuration and null vector).
    #[arg(long, default_value_t = 1e-4)]
    sigma: f64,
    #[command(flatten)]
    limits: LimitArgs,
    /// Write the reports (one per set, as a JSON array; `--kind image`: one image report) here.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// `--kind image`: cells per actuator axis of the raster that finds the regions.
    #[arg(long, default_value_t = 128)]
    grid: usize,
}

/// `LINK@X,Y` or `J1,J2`.
pub(crate) fn parse_output(s: &str) -> Result<Output> {
    if let Some((link, xy)) = s.split_once('@') {
        let (x, y) = xy.split_once(',').with_context(|| format!("--output '{s}': expected LINK@X,Y"))?;
        let x: f64 = x.trim().parse().with_context(|| format!("--output '{s}': '{x}' is not a number"))?;
        let y: f64 = y.trim().parse().with_context(|| format!("--output '{s}': '{y}' is not a number"))?;
        if !(x.is_finite() && y.is_finite()) || link.trim().is_empty() {
            bail!("--output '{s}': expected LINK@X,Y with finite coordinates");
        }
        return Ok(Output::Point { link: link.trim().to_string(), x, y });
    }
    Ok(Output::Joints(names(s, "--output")?))
}

fn names(s: &str, flag: &str) -> Result<Vec<String>> {
    let v: Vec<String> = s.split(',').map(|x| x.trim().to_string()).collect();
    if v.iter().any(|x| x.is_empty()) {
        bail!("{flag} '{s}': expected joint names separated by commas");
    }
    Ok(v)
}

pub(crate) fn run(args: LoopSingularitiesArgs) -> Result<()> {
    let base = SolverSettings { sigma: args.sigma, ..SolverSettings::default() };
    let settings = args.limits.solver_settings(SolverSettings::default().max_boxes, base)?;
    settings.validate()?;
    let fixed = args.fix.iter().map(|s| parse_fix(s)).collect::<Result<Vec<_>>>()?;
    let output = args.output.as_deref().map(parse_output).transpose()?;
    let xml = std::fs::read_to_string(&args.urdf).with_context(|| format!("reading {}", args.urdf.display()))?;
    let mechanism = urdf::parse(&xml).with_context(|| format!("loading {}", args.urdf.display()))?;
    // The node's default too (`LinkageAnalysis`): one function.
    let actuated = match &args.actuated {
        Some(a) => Actuation::given(names(a, "--actuated")?),
        None => Actuation::from_transmissions(&mechanism, &fixed),
    }
    .joints;
    if matches!(args.kind, Kind::Image) {
        return run_image(&args, &mechanism, &fixed, &actuated, &settings);
    }
    let kinds: Vec<SingularKind> = match args.kind {
        Kind::Cspace => vec![SingularKind::Cspace],
        Kind::Input => vec![SingularKind::Input],
        Kind::Output => vec![SingularKind::Output],
        Kind::All => all_kinds(&actuated),
        Kind::Image => unreachable!("handled above"),
    };
    // The orchestration the node runs as well: every problem built first, one timeout for all.
    let sets = SingularSets::new(&mechanism, &fixed, &kinds, &actuated, output).with_context(|| format!("building {}", args.urdf.display()))?;
    let solved = sets.solve(&settings, &AtomicBool::new(false))?;
    let mut reports = Vec::new();
    let mut out = std::io::stdout().lock();
    if sets.model == "spatial" {
        writeln!(out, "{}: spatial model ({})", mechanism.name, sets.model_reason).ok();
    }
    for (p, set) in sets.problems.iter().zip(&solved) {
        let r = SingularReport::new(p, &settings, set);
        let s = &r.summary;
        let shape = match r.expected_dimension {
            0 => "points",
            1 => "curves",
            d if d < 0 => "generically none",
            _ => "surfaces",
        };
        writeln!(
            out,
            "{} {}: {} clusters ({} certified, {} unproven), {} boxes, {} undecided, status {}, {} charts, {} dof ({shape}), {:.3} s",
            r.mechanism,
            r.kind,
            s.clusters,
            s.certified_clusters,
            s.unproven_clusters,
            s.boxes,
            s.undecided_boxes,
            match r.status {
                linkspace::Status::Complete => "complete".to_string(),
                linkspace::Status::Incomplete(l) => format!("incomplete ({l:?} limit)"),
            },
            r.charts,
            r.dof,
            r.seconds
        )
        .ok();
        if r.clusters.len() <= 40 {
            for c in &r.clusters {
                let joints: Vec<String> = c.joints.iter().map(|(n, b)| format!("{n}={:.6}", 0.5 * (b[0] + b[1]))).collect();
                let tag = if c.certified { "certified" } else if c.undecided { "undecided" } else { "unproven" };
                writeln!(out, "  {tag} ({} boxes): {}", c.boxes, joints.join(" ")).ok();
            }
        }
        reports.push(r);
    }
    if let Some(path) = args.json {
        std::fs::write(&path, serde_json::to_string_pretty(&reports)?).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// The type-II cover, then cusps, nodes, regions and the verdict; one summary and one JSON report.
fn run_image(args: &LoopSingularitiesArgs, mechanism: &linkspace::model::Mechanism, fixed: &[(String, f64)], actuated: &[String], settings: &SolverSettings) -> Result<()> {
    if args.grid < 2 {
        bail!("--grid must be at least 2");
    }
    let r = image::analyse(mechanism, fixed, actuated, settings, args.grid, &AtomicBool::new(false)).with_context(|| format!("analysing {}", args.urdf.display()))?;
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "{} type-II image: cusps {} proven, {} undecided; nodes {} proven, {} undecided ({} diagonal boxes injective); {} regions; status {}; {:.3} s (cover {:.3}, cusps {:.3}, nodes {:.3}, regions {:.3})",
        r.mechanism,
        r.cusp_counts.proven,
        r.cusp_counts.undecided,
        r.node_counts.proven,
        r.node_counts.undecided,
        r.injective,
        r.regions.regions.len(),
        r.status,
        r.seconds.iter().sum::<f64>(),
        r.seconds[0],
        r.seconds[1],
        r.seconds[2],
        r.seconds[3]
    )
    .ok();
    for (i, g) in r.regions.regions.iter().enumerate() {
        let count = g.configurations.map_or("undecided".to_string(), |c| c.to_string());
        let signs = g.signs.map_or(String::new(), |[p, n]| format!(" ({p} with det F_p > 0, {n} < 0)"));
        writeln!(out, "  region {i}: {} cells, sample {:?}: {count} assembly modes{signs}", g.cells, g.sample).ok();
    }
    for c in r.cusps.iter().take(20) {
        writeln!(out, "  cusp{}{}: {:?}", if c.unique { " (certified)" } else { " (undecided)" }, if c.degenerate { " degenerate" } else { "" }, c.workspace).ok();
    }
    for n in r.nodes.iter().take(20) {
        writeln!(out, "  node{}: {:?}", if n.unique { " (certified)" } else { " (undecided)" }, n.workspace).ok();
    }
    writeln!(out, "  can change assembly mode without crossing a type-II singularity: {} ({})", r.verdict.answer, r.verdict.reason).ok();
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(&r)?).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

#[derive(clap::Args)]
pub(crate) struct BenchArgs {
    /// Runs per case; the median is reported.
    #[arg(long, default_value_t = 3)]
    repeat: usize,
    /// Also time the double butterfly's turning points of θ6 (about half a minute a run).
    #[arg(long)]
    butterfly: bool,
    /// Also time the type-II image of the five-bar with unequal rods (cusps, nodes, regions;
    /// about a minute a run), each search against the cover of the type-II set in the same run.
    #[arg(long)]
    image: bool,
}

const FOUR_BAR: &str = include_str!("../../urdf/four_bar.urdf");
const FIVE_BAR: &str = include_str!("../../urdf/five_bar.urdf");
const BUTTERFLY: &str = include_str!("../../urdf/double_butterfly.urdf");
const FIVE_BAR_UNEQUAL: &str = include_str!("../../urdf/five_bar_unequal.urdf");
const RSSR: &str = include_str!("../../urdf/rssr.urdf");
const SPHERICAL: &str = include_str!("../../urdf/spherical_four_bar.urdf");

/// A bench case: name, URDF text, set, actuated joints, output, sigma.
type Case = (&'static str, &'static str, SingularKind, Vec<String>, Option<Output>, f64);

/// Singular-set searches against a baseline in the same run: the same search with propagation
/// only (no LP shrink), which shows what the LP relaxation of the bilinear null-vector rows buys.
pub(crate) fn bench(args: BenchArgs) -> Result<()> {
    if args.repeat == 0 {
        bail!("--repeat must be at least 1");
    }
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
                let c0 = linkspace::search::process_cpu_seconds();
                let set = p.solve(&settings, &AtomicBool::new(false))?;
                times.push(linkspace::search::process_cpu_seconds() - c0);
                last = Some(set);
            }
            times.sort_by(|a, b| a.total_cmp(b));
            let median = times[times.len() / 2];
            let set = last.expect("repeat >= 1");
            let processed: u64 = set.stats.iter().map(|s| s.processed).sum();
            let ratio = medians.first().map_or("1.00x (baseline)".to_string(), |base: &f64| format!("{:.2}x faster", base / median));
            let status = if set.status == linkspace::Status::Complete { "" } else { " (incomplete)" };
            writeln!(out, "{name} | {} | {median:.4}{status} | {processed} | {} | {} ({}) | {ratio}", if use_lp { "propagation + LP" } else { "propagation" }, set.boxes.len(), set.clusters.len(), set.certified_clusters()).ok();
            medians.push(median);
        }
    }
    if args.image {
        bench_image(&mut out, args.repeat)?;
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
    let cusp_problem = CuspProblem::new(&p)?;
    let node_problem = NodeProblem::new(&p)?;
    let median = |f: &mut dyn FnMut() -> Result<String>| -> Result<(f64, String)> {
        let mut times = Vec::new();
        let mut what = String::new();
        for _ in 0..repeat {
            let c0 = linkspace::search::process_cpu_seconds();
            what = f()?;
            times.push(linkspace::search::process_cpu_seconds() - c0);
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
        Ok(format!("{} proven, {} undecided, {} chart pairs", c.proven(), c.points.len() - c.proven(), cusp_problem.charts.len()))
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

//! `linkspace loop-singularities`: certified singular sets of closed-loop linkages,
//! planar or spatial (the model `solve --model auto` picks), on the polynomial solver through
//! `singular` (the searches on the systems of `formulate::singular`).

use super::{parse_fix, LimitArgs};
use anyhow::{bail, Context, Result};
use linkspace::model::urdf;
use linkspace::formulate::{Output, SingularKind};
use linkspace::formulate::Model;
use linkspace::app::{check_input_motion, motion_joints, MotionRequest, all_kinds, analyse_image, image_points, Actuation, ImageSearch, SingularSets};
use linkspace::edges::report::singular::SingularReport;
use linkspace::kernel::search::{Control, Limits, SolverSettings};
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
    /// 2-dof mechanisms: the cusps of the type-II image alone (no cover, nodes or regions).
    Cusps,
    /// 2-dof mechanisms: the nodes of the type-II image alone (no cover, cusps or regions).
    Nodes,
    /// 1-dof planar loops: a motion of the actuated joint (`--from`, `--to`) from an assembly
    /// (`--assembly`) checked against the input (type II) singularities by tube following.
    Motion,
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
    /// `--kind motion`: the actuated joint's start value (radians or metres).
    #[arg(long, allow_hyphen_values = true)]
    from: Option<f64>,
    /// `--kind motion`: its end value.
    #[arg(long, allow_hyphen_values = true)]
    to: Option<f64>,
    /// `--kind motion`: an approximate configuration at the start, one value per free joint in
    /// file order (a wrong count names them).
    #[arg(long, value_name = "Q1,Q2,...", allow_hyphen_values = true)]
    assembly: Option<String>,
    /// `--kind motion`: the largest step of the input.
    #[arg(long, default_value_t = 0.05)]
    max_step: f64,
    /// `--kind motion`: steps are halved down to this before the motion is left undecided.
    #[arg(long, default_value_t = 1e-6)]
    min_step: f64,
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
    match args.kind {
        Kind::Image => return run_image(&args, &mechanism, &fixed, &actuated, &settings),
        Kind::Cusps => return run_points(&args, &mechanism, &fixed, &actuated, ImageSearch::Cusps, &settings),
        Kind::Nodes => return run_points(&args, &mechanism, &fixed, &actuated, ImageSearch::Nodes, &settings),
        Kind::Motion => return run_motion(&args, &mechanism, &fixed, &actuated, &settings),
        _ => {}
    }
    let kinds: Vec<SingularKind> = match args.kind {
        Kind::Cspace => vec![SingularKind::Cspace],
        Kind::Input => vec![SingularKind::Input],
        Kind::Output => vec![SingularKind::Output],
        Kind::All => all_kinds(&actuated),
        Kind::Image | Kind::Cusps | Kind::Nodes | Kind::Motion => unreachable!("handled above"),
    };
    // The orchestration the node runs as well: every problem built first, one timeout for all.
    let sets = SingularSets::new(&mechanism, &fixed, &kinds, &actuated, output).with_context(|| format!("building {}", args.urdf.display()))?;
    let solved = sets.solve(&settings, &AtomicBool::new(false))?;
    let mut reports = Vec::new();
    let mut out = std::io::stdout().lock();
    if sets.model == Model::Spatial {
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
            "{} {}: {} clusters ({} certified, {} unproven), {} boxes, {} undecided, status {}, {}, {} dof ({shape}), {:.3} s",
            r.mechanism,
            r.kind,
            s.clusters,
            s.certified_clusters,
            s.unproven_clusters,
            s.boxes,
            s.undecided_boxes,
            match r.status {
                linkspace::Status::Finished => "complete".to_string(),
                linkspace::Status::Stopped(l) => format!("incomplete ({l:?} limit)"),
            },
            match s.unsearched_charts {
                0 => format!("{} charts", r.charts),
                n => format!("{} charts ({n} left unsearched, held by one undecided box)", r.charts),
            },
            r.dof,
            r.seconds
        )
        .ok();
        if r.clusters.len() <= 40 {
            for c in &r.clusters {
                // A line a reader can take in: the first joints, then how many more (the JSON
                // report has them all).
                const SHOWN: usize = 12;
                let mut joints: Vec<String> = c.joints.iter().take(SHOWN).map(|(n, b)| format!("{n}={:.6}", 0.5 * (b[0] + b[1]))).collect();
                if c.joints.len() > SHOWN {
                    joints.push(format!("and {} more joints (--json)", c.joints.len() - SHOWN));
                }
                let tag = if c.certified { "certified" } else if c.undecided { "undecided" } else { "unproven" };
                writeln!(out, "  {tag} ({} boxes): {}", c.boxes, joints.join(" ")).ok();
            }
        }
        reports.push(r);
    }
    if let Some(path) = args.json {
        super::write_file(&path, serde_json::to_string_pretty(&reports)?)?;
    }
    Ok(())
}

/// The type-II cover, then cusps, nodes, regions and the verdict; one summary and one JSON report.
fn run_image(args: &LoopSingularitiesArgs, mechanism: &linkspace::model::Mechanism, fixed: &[(String, f64)], actuated: &[String], settings: &SolverSettings) -> Result<()> {
    if args.grid < 2 {
        bail!("--grid must be at least 2");
    }
    let r = analyse_image(mechanism, fixed, actuated, settings, args.grid, &AtomicBool::new(false)).with_context(|| format!("analysing {}", args.urdf.display()))?;
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
        let signs = g.signs.map_or(String::new(), |[p, n]| format!(" ({p} with {} > 0, {n} < 0)", r.regions.sign));
        writeln!(out, "  region {i}: {} cells, sample {:?}: {count} assembly modes{signs}", g.cells, g.sample).ok();
    }
    for c in r.cusps.iter().take(20) {
        let why = c.reason.as_ref().map_or(String::new(), |r| format!(" ({r})"));
        writeln!(out, "  cusp{}{}: {:?}{why}", if c.unique { " (certified)" } else { " (undecided)" }, if c.degenerate { " degenerate" } else { "" }, c.workspace).ok();
    }
    for n in r.nodes.iter().take(20) {
        writeln!(out, "  node{}: {:?}", if n.unique { " (certified)" } else { " (undecided)" }, n.workspace).ok();
    }
    writeln!(out, "  can change assembly mode without crossing a type-II singularity: {} ({})", r.verdict.answer, r.verdict.reason).ok();
    if let Some(path) = &args.json {
        super::write_file(path, serde_json::to_string_pretty(&linkspace::edges::report::image::ImageJson(&r))?)?;
    }
    Ok(())
}

/// One search of the type-II image (cusps or nodes); one summary and one JSON report.
fn run_points(args: &LoopSingularitiesArgs, mechanism: &linkspace::model::Mechanism, fixed: &[(String, f64)], actuated: &[String], search: ImageSearch, settings: &SolverSettings) -> Result<()> {
    let r = image_points(mechanism, fixed, actuated, search, settings, &AtomicBool::new(false)).with_context(|| format!("analysing {}", args.urdf.display()))?;
    let mut out = std::io::stdout().lock();
    writeln!(out, "{} type-II image {}: {} proven, {} undecided; status {}; {:.3} s", r.mechanism, r.search, r.counts.proven, r.counts.undecided, r.status, r.seconds).ok();
    for c in r.cusps.iter().take(20) {
        let why = c.reason.as_ref().map_or(String::new(), |r| format!(" ({r})"));
        writeln!(out, "  cusp{}{}: {:?}{why}", if c.unique { " (certified)" } else { " (undecided)" }, if c.degenerate { " degenerate" } else { "" }, c.workspace).ok();
    }
    for n in r.nodes.iter().take(20) {
        writeln!(out, "  node{}: {:?}", if n.unique { " (certified)" } else { " (undecided)" }, n.workspace).ok();
    }
    if let Some(path) = &args.json {
        super::write_file(path, serde_json::to_string_pretty(&linkspace::edges::report::image::ImagePointsJson(&r))?)?;
    }
    Ok(())
}

/// An input motion checked by tube following; one summary and one JSON report.
fn run_motion(args: &LoopSingularitiesArgs, mechanism: &linkspace::model::Mechanism, fixed: &[(String, f64)], actuated: &[String], settings: &SolverSettings) -> Result<()> {
    let [joint] = actuated else { bail!("--kind motion: one actuated joint (--actuated J), got {}", actuated.len()) };
    let (Some(from), Some(to), Some(assembly)) = (args.from, args.to, args.assembly.as_deref()) else {
        bail!("--kind motion needs --from A --to B --assembly Q1,Q2,... (the free joints: {})", motion_joints(mechanism, fixed).map(|j| j.join(", ")).unwrap_or_default());
    };
    let assembly = assembly.split(',').map(|v| v.trim().parse::<f64>().with_context(|| format!("--assembly: '{v}' is not a number"))).collect::<Result<Vec<f64>>>()?;
    let request = MotionRequest { actuated: joint.clone(), from, to, assembly, max_step: args.max_step, min_step: args.min_step, name_turning_point: true };
    let cancel = AtomicBool::new(false);
    let control = Control { limits: Limits { timeout: settings.timeout, ..Limits::default() }, threads: 1, cancel: &cancel };
    let found = check_input_motion(mechanism, fixed, &request, &control).with_context(|| format!("checking {}", args.urdf.display()))?;
    let r = linkspace::edges::report::motion::MotionReport::of(&found);
    let mut out = std::io::stdout().lock();
    writeln!(out, "{}: {} from {} to {}: {} ({} steps, {:.3} s)", r.singular_set, r.actuated, r.from, r.to, r.verdict, r.steps.len(), r.seconds).ok();
    writeln!(out, "  {}", r.reason).ok();
    if let Some(path) = &args.json {
        super::write_file(path, serde_json::to_string_pretty(&r)?)?;
    }
    Ok(())
}

//! `linkspace distances`: distance problems (seed 004) from a URDF platform or a JSON distance
//! file.

use super::parse_fix;
use anyhow::{Context, Result};
use linkspace::app::{DistancesRun, DistancesRequest};
use linkspace::kernel::contract::FaceBounds;
use linkspace::analyses::distances::Choice;
use linkspace::model::urdf;
use linkspace::edges::report::distances::{report_certified, DistancesReport};
use linkspace::kernel::search::SolverSettings;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
pub enum Form {
    /// Let the builder pick: points when the problem has a frame and a square coordinate
    /// system, else shared.
    Auto,
    /// Coordinates of the free points (degree two; interval Newton certifies).
    Points,
    /// A point and a direction of the line through the two free points (lines tangent to
    /// spheres; degree two; interval Newton certifies).
    Line,
    /// One variable per distance (degree two; Bernstein control points).
    Shared,
    /// The seed's: r_ij and r_ji separate, multilinear (corner values).
    Split,
}

#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
pub enum Faces {
    /// Trapezoid sides from control points (the seed's method).
    Corners,
    /// Trapezoid sides by interval evaluation (the seed's comparison).
    Interval,
}

#[derive(clap::Args)]
pub struct DistancesArgs {
    /// A platform in URDF (.urdf) or a distance problem in JSON (schema in README).
    file: PathBuf,
    /// Squared length of a leg (platform) or of a named distance (JSON). Repeatable.
    #[arg(long = "fix", value_name = "LEG=VALUE")]
    fix: Vec<String>,
    /// Solution boxes are at most this wide in every unknown squared distance.
    #[arg(long, default_value_t = 0.01)]
    sigma: f64,
    /// Keep clipping a box while a round leaves less than this share of its volume. Default
    /// 0.99 (the seed's) for the determinants, 0.9 for the coordinate formulations (points,
    /// line), where bisecting is cheaper than slow propagation fixpoints.
    #[arg(long)]
    rho: Option<f64>,
    /// Add the redundant determinants (platform: the seed's Eq. 7; JSON: six-point ones).
    #[arg(long)]
    redundant: bool,
    /// Variables for the unknown distances.
    #[arg(long, value_enum, default_value_t = Form::Auto)]
    formulation: Form,
    /// How the trapezoid sides are bounded.
    #[arg(long, value_enum, default_value_t = Faces::Corners)]
    faces: Faces,
    #[command(flatten)]
    limits: super::LimitArgs,
    /// Write the full report as JSON here.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

/// The distance job of a URDF platform or a distance file (a file starting with '<' is URDF).
pub fn load(path: &Path, text: &str, fixed: &[(String, f64)]) -> Result<DistancesRun> {
    let is_urdf = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("urdf")) || text.trim_start().starts_with('<');
    if is_urdf {
        let m = urdf::parse(text).with_context(|| format!("loading {}", path.display()))?;
        DistancesRun::platform(&m, fixed).with_context(|| format!("building {}", path.display()))
    } else {
        DistancesRun::file(text, fixed).with_context(|| format!("loading {}", path.display()))
    }
}

fn choice(form: Form) -> Choice {
    match form {
        Form::Auto => Choice::Auto,
        Form::Points => Choice::Points,
        Form::Line => Choice::Line,
        Form::Shared => Choice::Shared,
        Form::Split => Choice::Split,
    }
}

fn face_bounds(f: Faces) -> FaceBounds {
    if f == Faces::Corners {
        FaceBounds::Corners
    } else {
        FaceBounds::IntervalArithmetic
    }
}

pub fn run(args: DistancesArgs) -> Result<()> {
    // Settings are checked before the file is read (rho's default depends on the formulation).
    args.limits.solver_settings(SolverSettings::default().max_boxes, SolverSettings { sigma: args.sigma, rho: args.rho.unwrap_or(0.99), ..Default::default() })?.validate()?;
    let fixed = args.fix.iter().map(|s| parse_fix(s)).collect::<Result<Vec<_>>>()?;
    let text = std::fs::read_to_string(&args.file).with_context(|| format!("reading {}", args.file.display()))?;
    let job = load(&args.file, &text, &fixed)?;
    let request = DistancesRequest { formulation: job.formulation(choice(args.formulation)), redundant: args.redundant, faces: face_bounds(args.faces) };
    let rho = args.rho.unwrap_or(DistancesRun::default_rho(request.formulation));
    let settings = args.limits.solver_settings(SolverSettings::default().max_boxes, SolverSettings { sigma: args.sigma, rho, ..Default::default() })?;
    settings.validate()?;
    let certified = job.run(&request, &settings, &AtomicBool::new(false)).with_context(|| format!("solving {}", args.file.display()))?;
    let rep = report_certified(&certified, job.platform_problem(), job.fixed().iter().cloned().collect(), request.faces, &settings);
    summarize(&rep)?;
    if let Some(path) = args.json {
        let text = serde_json::to_string_pretty(&rep)?;
        super::write_file(&path, text)?;
    }
    Ok(())
}

fn summarize(rep: &DistancesReport) -> Result<()> {
    let mut out = std::io::stdout().lock();
    let platform = rep.solutions.iter().any(|s| !s.poses.is_empty());
    let status = match rep.status {
        linkspace::Status::Finished if rep.complete => "complete".to_string(),
        linkspace::Status::Finished => format!("not complete ({} regions undecided)", rep.undecided_regions),
        linkspace::Status::Stopped(l) => format!("incomplete ({l:?} limit, {} boxes undecided)", rep.undecided.len()),
    };
    writeln!(
        out,
        "{}: {} proven, {} undecided ({} solution boxes in {} clusters, {} distinct {}; {} formulation), status {status}, {} boxes processed ({} empty, {} bisected), {:.4} s",
        rep.problem,
        rep.proven,
        rep.undecided_regions,
        rep.solutions.len(),
        rep.clusters,
        rep.placements,
        if platform { "poses" } else { "placements" },
        rep.formulation.name(),
        rep.stats.processed,
        rep.stats.empty,
        rep.stats.bisected,
        rep.stats.seconds
    )
    .ok();
    // One line per cluster: the hull of its distances and what its first box places.
    for c in 0..rep.clusters.min(40) {
        let members: Vec<_> = rep.solutions.iter().filter(|s| s.cluster == c).collect();
        let mut hull: BTreeMap<&String, [f64; 2]> = BTreeMap::new();
        for m in &members {
            for (n, [lo, hi]) in &m.distances {
                let h = hull.entry(n).or_insert([*lo, *hi]);
                h[0] = h[0].min(*lo);
                h[1] = h[1].max(*hi);
            }
        }
        let d: Vec<String> = hull.iter().map(|(n, [lo, hi])| format!("{n}={:.5}", 0.5 * (lo + hi))).collect();
        let verdict = match rep.cluster_verdicts.get(c) {
            Some(v) => match v.undecided {
                None => format!("{} proven", v.proven),
                Some(why) => format!("{} proven, undecided: {why}", v.proven),
            },
            None => "undecided".to_string(),
        };
        writeln!(out, "  cluster {c} ({} boxes; {verdict}): {}", members.len(), d.join(" ")).ok();
        let first = members[0];
        for p in &first.poses {
            writeln!(
                out,
                "    pose: position ({:.5}, {:.5}, {:.5}) rpy ({:.5}, {:.5}, {:.5}) leg residual {:.1e}",
                p.position[0], p.position[1], p.position[2], p.rpy[0], p.rpy[1], p.rpy[2], p.leg_residual
            )
            .ok();
        }
        for l in &first.lines {
            let dist: Vec<String> = l.distance_from.iter().map(|(n, d)| format!("{n} {d:.5}")).collect();
            writeln!(
                out,
                "    line {}-{}: point ({:.5}, {:.5}, {:.5}) direction ({:.5}, {:.5}, {:.5}); distance from {}",
                l.through[0], l.through[1], l.point[0], l.point[1], l.point[2], l.direction[0], l.direction[1], l.direction[2], dist.join(", ")
            )
            .ok();
        }
    }
    Ok(())
}

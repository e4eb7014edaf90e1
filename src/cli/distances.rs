//! `linkspace distances` and `linkspace bench-distances`: distance problems (seed 004) from a
//! URDF platform or a JSON distance file.

use super::parse_fix;
use anyhow::{bail, Context, Result};
use linkspace::contract::FaceBounds;
use linkspace::model::urdf;
use linkspace::problems::cayley_menger::{BuildOptions, CayleyMenger, DistanceProblem, Formulation};
use linkspace::problems::coordinates::Placed;
use linkspace::distances::file as distance_file;
use linkspace::problems::PlatformProblem;
use linkspace::distances::{solve as certified_solve, Choice};
use linkspace::problems::cayley_menger::DistanceProblem as Problem;
use linkspace::report::distances::{report_certified, DistancesReport};
use linkspace::search::{Enclosure, SolverSettings};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Duration;

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

/// A loaded problem: the distances, and the platform when it came from URDF.
pub struct Loaded {
    pub distances: DistanceProblem,
    pub platform: Option<PlatformProblem>,
}

pub fn load(path: &Path, text: &str, fixed: &[(String, f64)]) -> Result<Loaded> {
    let is_urdf = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("urdf")) || text.trim_start().starts_with('<');
    if is_urdf {
        let m = urdf::parse(text).with_context(|| format!("loading {}", path.display()))?;
        let p = PlatformProblem::new(&m, fixed).with_context(|| format!("building {}", path.display()))?;
        Ok(Loaded { distances: p.distances.clone(), platform: Some(p) })
    } else {
        let d = distance_file::parse(text, fixed).with_context(|| format!("loading {}", path.display()))?;
        Ok(Loaded { distances: d, platform: None })
    }
}

pub fn solve(cm: &CayleyMenger, faces: FaceBounds, settings: SolverSettings) -> Result<Enclosure> {
    Ok(cm.solver(faces, settings)?.enclose(&AtomicBool::new(false), &mut |_| {}))
}

/// The default rho of a formulation: the seed's 0.99 for the determinants, 0.9 in coordinates.
pub fn default_rho(c: Choice) -> f64 {
    if matches!(c, Choice::Points | Choice::Line) {
        0.9
    } else {
        0.99
    }
}

pub fn choice(form: Form) -> Choice {
    match form {
        Form::Auto => Choice::Auto,
        Form::Points => Choice::Points,
        Form::Line => Choice::Line,
        Form::Shared => Choice::Shared,
        Form::Split => Choice::Split,
    }
}

pub fn options(form: Form, redundant: bool) -> BuildOptions {
    BuildOptions { formulation: if form == Form::Split { Formulation::Split } else { Formulation::Shared }, redundant }
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
    let loaded = load(&args.file, &text, &fixed)?;
    let chosen = match choice(args.formulation) {
        Choice::Auto => linkspace::distances::choose(&loaded.distances),
        c => c,
    };
    let rho = args.rho.unwrap_or(default_rho(chosen));
    let settings = args.limits.solver_settings(SolverSettings::default().max_boxes, SolverSettings { sigma: args.sigma, rho, ..Default::default() })?;
    settings.validate()?;
    let faces = face_bounds(args.faces);
    let c = certified_solve(&loaded.distances, chosen, args.redundant, faces, settings.clone(), &AtomicBool::new(false)).with_context(|| format!("solving {}", args.file.display()))?;
    let fixed_map: BTreeMap<String, f64> = fixed.into_iter().collect();
    let rep = report_certified(&c, loaded.platform.as_ref(), fixed_map, faces, &settings);
    summarize(&rep)?;
    if let Some(path) = args.json {
        let text = serde_json::to_string_pretty(&rep)?;
        std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

fn summarize(rep: &DistancesReport) -> Result<()> {
    let mut out = std::io::stdout().lock();
    let platform = rep.solutions.iter().any(|s| !s.poses.is_empty());
    let status = match rep.status {
        linkspace::Status::Complete if rep.complete => "complete".to_string(),
        linkspace::Status::Complete => format!("not complete ({} regions undecided)", rep.undecided_regions),
        linkspace::Status::Incomplete(l) => format!("incomplete ({l:?} limit, {} boxes undecided)", rep.undecided.len()),
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
        serde_json::to_value(rep.formulation).ok().and_then(|v| v.as_str().map(str::to_string)).unwrap_or_default(),
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

#[derive(clap::Args)]
pub struct BenchArgs {
    /// Runs per case; the median CPU time is reported (the baselines run once).
    #[arg(long, default_value_t = 5)]
    repeat: usize,
    /// Time limit per baseline run (seconds): octahedral, the seed's split formulation with
    /// interval-arithmetic faces; four spheres, the seed's split formulation with corners.
    #[arg(long, default_value_t = 30.0)]
    baseline_timeout: f64,
}

const OCTAHEDRAL: &str = include_str!("../../urdf/octahedral.urdf");
const FOUR_SPHERES: &str = include_str!("../../urdf/four_spheres.json");

/// One way of running a case.
#[derive(Clone, Copy)]
enum Method {
    /// The kernel on the determinants, no settling: boxes are neither certified nor labelled.
    Search(Formulation, FaceBounds),
    /// `distances::solve`: the search, then every cluster settled (certified or undecided).
    Settled(Form),
    /// The coordinate formulation's search alone (`Placed::solver`).
    Coordinates(Form),
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
    let c0 = linkspace::search::process_cpu_seconds();
    let from_search = |e: Enclosure, cpu: f64| Measured {
        cpu,
        complete: e.status == linkspace::Status::Complete,
        processed: e.stats.processed,
        solution_boxes: e.solutions.len(),
        clusters: linkspace::interval::components(&e.solutions).1,
        verdict: None,
        phases: Vec::new(),
    };
    Ok(match method {
        Method::Search(formulation, faces) => {
            let cm = CayleyMenger::build(p, BuildOptions { formulation, redundant })?;
            let e = solve(&cm, faces, settings.clone())?;
            from_search(e, linkspace::search::process_cpu_seconds() - c0)
        }
        Method::Coordinates(form) => {
            let placed = if form == Form::Line { Placed::build_line(p)? } else { Placed::build(p)? };
            let e = placed.solver(settings.clone())?.enclose(&cancel, &mut |_| {});
            from_search(e, linkspace::search::process_cpu_seconds() - c0)
        }
        Method::Settled(form) => {
            let c = certified_solve(p, choice(form), redundant, FaceBounds::Corners, settings.clone(), &cancel)?;
            Measured {
                cpu: c.stats.cpu_seconds,
                complete: c.status == linkspace::Status::Complete,
                processed: c.stats.processed,
                solution_boxes: c.solutions.len(),
                clusters: c.clusters.len(),
                verdict: Some((c.proven(), c.undecided_regions())),
                phases: c.phases,
            }
        }
    })
}

/// The seed's Tables I and II in one run: the seed's determinants as plain searches (the
/// previous configurations: split or shared variables, corner or interval-arithmetic faces)
/// against the certified pipeline of issue 15 (`distances::solve`: the line formulation for the
/// spheres, the settled shared determinants for the platforms), each row's CPU time against the
/// case's baseline measured in the same run.
pub fn bench(args: BenchArgs) -> Result<()> {
    if args.repeat == 0 {
        bail!("--repeat must be at least 1");
    }
    if !(args.baseline_timeout > 0.0) {
        bail!("--baseline-timeout must be positive");
    }
    let mut out = std::io::stdout().lock();
    writeln!(out, "case | method | CPU s (median) | boxes processed | solution boxes | clusters | proven | undecided | vs baseline (same run) | seed (Pentium IV 1.8 GHz) | where the time goes").ok();
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
                ("split, corners, search only (the seed's)", Method::Search(Formulation::Split, FaceBounds::Corners), format!("t {} s, b_p {}, n_s {}", s.0, s.1, s.2)),
                ("shared, Bernstein, search only (before issue 15)", Method::Search(Formulation::Shared, FaceBounds::Corners), String::new()),
                ("shared, Bernstein, settled (certified; the default)", Method::Settled(Form::Auto), String::new()),
            ] {
                let m = run(&p.distances, method, redundant, &settings, args.repeat)?;
                row(&mut out, &case, label, &m, base, &seed);
            }
        }
    }
    // Table II: the four spheres, rho 0.99 for the determinants (the seed's C1-C4), the CLI's
    // default rho for the line formulation.
    let d = distance_file::parse(FOUR_SPHERES, &[])?;
    for (sigma, seed) in [(0.1, "t 315 s, b_p 7875, n_s 870"), (0.01, "t 385 s, b_p 14579, n_s 813")] {
        let case = format!("four spheres, sigma {sigma}");
        let cm_settings = SolverSettings { sigma, rho: 0.99, ..Default::default() };
        let line_settings = SolverSettings { sigma, rho: default_rho(Choice::Line), ..Default::default() };
        let baseline = run(&d, Method::Search(Formulation::Split, FaceBounds::Corners), true, &SolverSettings { timeout: baseline_limit, ..cm_settings.clone() }, 1)?;
        row(&mut out, &case, "split, corners, C1-C4, search only (the seed's; baseline)", &baseline, None, seed);
        let base = Some((baseline.cpu, baseline.complete));
        for (label, method, settings) in [
            ("shared, Bernstein, C1-C4, search only (before issue 15)", Method::Search(Formulation::Shared, FaceBounds::Corners), &cm_settings),
            ("shared, Bernstein, C1-C4, settled (certified)", Method::Settled(Form::Shared), &cm_settings),
            ("line, search only", Method::Coordinates(Form::Line), &line_settings),
            ("line, settled (certified; the default)", Method::Settled(Form::Auto), &line_settings),
        ] {
            let m = run(&d, method, true, settings, args.repeat)?;
            row(&mut out, &case, label, &m, base, "");
        }
    }
    Ok(())
}

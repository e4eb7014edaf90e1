//! Solving distance problems with every answer certified or labelled.
//!
//! `solve` picks a formulation (`Choice`), runs the kernel on it, then settles every cluster of
//! solution boxes (connected component of touching boxes) as follows:
//! - **points** (`formulate::coordinates::Placed`, square): the kernel's Krawczyk already marks
//!   boxes holding exactly one placement (`unique`). Each box it could not prove is searched
//!   again, deeper (sigma / 16, bounded): the box is replaced by what that search certifies, or
//!   removed when the search proves it empty, or stays with the reason it is undecided.
//! - **shared / split** (the determinants of Porta et al. 2003, not square or singular where two
//!   assembly modes share their distances): placements are embedded from each box midpoint,
//!   polished by Newton in coordinates and certified by Krawczyk on the points system; a certified
//!   placement is attributed to the cluster whose boxes its distance enclosure meets (the root
//!   exists and the solver never loses one, so its distances lie in some solution box). Boxes that
//!   meet no certified placement are searched again with every determinant (the redundant ones
//!   settle the singular tangent of octahedral b), then in coordinates: removed when proven empty,
//!   undecided otherwise.
//!
//! A cluster then counts its proven solutions (distinct certified placements) and is undecided
//! when some box of it is still unproven, with the reason. "Complete" means nothing undecided.
//!
//! `file` reads the JSON format of distance problems into a `DistanceProblem`.

pub mod file;

use crate::kernel::outcome::BoxStatus;
use crate::kernel::contract::{Contractor, FaceBounds, Newton};
use crate::kernel::interval::{components, IntervalBox};
use inari::Interval;
use crate::formulate::cayley_menger::{BuildOptions, CayleyMenger, DistanceError, DistanceProblem, DistanceSolverError, Formulation};
use crate::formulate::coordinates::{Placed, PlacedError};
use crate::kernel::search::{Collect, Limit, SolveStats, Solver, SolverSettings, Status};
use std::time::Instant;
use std::sync::atomic::AtomicBool;

/// Which formulation to solve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Choice {
    /// Let the builder pick (see `choose`).
    Auto,
    /// Coordinates of the free points (`Placed`).
    Points,
    /// A point and a direction of the line through the two free points (`Placed::build_line`).
    Line,
    /// Determinants, one variable per distance.
    Shared,
    /// Determinants, the split variables of Porta, Thomas, Ros and Torras (2003).
    Split,
}

impl Choice {
    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Choice::Auto => "auto",
            Choice::Points => "points",
            Choice::Line => "line",
            Choice::Shared => "shared",
            Choice::Split => "split",
        }
    }
}

/// Why a problem cannot be solved.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DistancesError {
    /// Bad problem.
    #[error(transparent)]
    Problem(#[from] DistanceError),
    /// The points formulation was asked for but does not apply.
    #[error(transparent)]
    Placed(#[from] PlacedError),
    /// The solver could not be made.
    #[error(transparent)]
    Solver(#[from] DistanceSolverError),
}

/// What was settled about one cluster.
#[derive(Clone, Debug, PartialEq)]
pub struct ClusterVerdict {
    /// Distinct solutions proven (certified placements) in the cluster.
    pub proven: usize,
    /// `None` when every box of the cluster is accounted for by a proof; otherwise why not.
    pub undecided: Option<&'static str>,
    /// Solution boxes in the cluster.
    pub boxes: usize,
}

/// A placement proven to be the only one in its coordinate box.
#[derive(Clone, Debug)]
pub struct Root {
    /// Cluster it belongs to.
    pub cluster: usize,
    /// The certified box over `Placed::system`'s variables.
    pub certified: IntervalBox,
    /// Coordinates of every point at the box midpoint.
    pub points: Vec<[f64; 3]>,
}

/// The result of `solve`.
#[derive(Clone, Debug)]
pub struct Certified {
    /// The formulation solved: `points`, `shared` or `split`.
    pub formulation: Choice,
    /// Determinant system (always built: it names the unknown distances in reports).
    pub cm: CayleyMenger,
    /// Coordinate system, when the problem has a frame.
    pub placed: Option<Placed>,
    /// How the kernel's run ended.
    pub status: Status,
    /// Counters of the run (the deeper searches' boxes are added to `processed`).
    pub stats: SolveStats,
    /// Solution boxes over the solved system's variables.
    pub solutions: Vec<IntervalBox>,
    /// Per box: `Unique` when proven (Krawczyk) to hold exactly one solution, else `Solution`.
    pub tags: Vec<BoxStatus>,
    /// Per box: its cluster.
    pub cluster: Vec<usize>,
    /// Per cluster: the verdict.
    pub clusters: Vec<ClusterVerdict>,
    /// Certified placements, each once.
    pub roots: Vec<Root>,
    /// Boxes a limit left unprocessed.
    pub undecided: Vec<IntervalBox>,
    /// CPU seconds per phase of the call (`search`, then the settling steps), where the time goes.
    pub phases: Vec<(&'static str, f64)>,
}

impl Certified {
    /// Proven solutions in all clusters.
    pub fn proven(&self) -> usize {
        self.clusters.iter().map(|c| c.proven).sum()
    }

    /// True when the search finished and nothing is undecided.
    pub fn complete(&self) -> bool {
        self.completeness().is_complete()
    }

    /// The one rule: the limit that stopped the search, else the undecided regions.
    pub fn completeness(&self) -> crate::kernel::outcome::Completeness {
        crate::kernel::outcome::Completeness::of(self.status, self.undecided_regions(), false)
    }

    /// Clusters with something unproven (regions that may or may not hold solutions).
    pub fn undecided_regions(&self) -> usize {
        self.clusters.iter().filter(|c| c.undecided.is_some()).count()
    }
}

/// The formulation `Auto` picks: the line formulation when the problem is a line to place
/// (`Placed::build_line`: lines tangent to spheres), else the shared determinants, certified in
/// coordinates.
///
/// Measured (`bench-distances`): on the four spheres at sigma 0.01 the line
/// formulation takes 843 boxes and 0.04 s CPU with every solution box proven, against 885
/// boxes plus a settling of 0.6 s (1.6 s in all) for the shared determinants, and over a
/// million boxes for the points formulation (expanding `‖p_a − p_b‖²` into monomials loses the
/// dependency between the squares and the products that interval propagation needs). On the
/// platforms the determinants prune far better than the points (octahedral b: 20 to 100 boxes
/// against 130 000). `--formulation` keeps every one available.
pub fn choose(problem: &DistanceProblem) -> Choice {
    match Placed::build_line(problem) {
        Ok(line) if line.is_square() => Choice::Line,
        _ => Choice::Shared,
    }
}

/// `stats.seconds` and `stats.cpu_seconds` cover the whole call: build, search and settling.
/// So does the timeout: the search takes `SEARCH_SHARE` of it, and the settling's deeper
/// searches share what is left up to it (a box they do not reach stays unproven, and the answer
/// names the limit).
pub fn solve(problem: &DistanceProblem, choice: Choice, redundant: bool, faces: FaceBounds, settings: SolverSettings, cancel: &AtomicBool) -> Result<Certified, DistancesError> {
    let t0 = std::time::Instant::now();
    let c0 = crate::kernel::search::process_cpu_seconds();
    let deadlines = Deadlines { search: settings.timeout.map(|t| t0 + t.mul_f64(SEARCH_SHARE)), settling: settings.timeout.map(|t| t0 + t) };
    let mut out = solve_inner(problem, choice, redundant, faces, settings, cancel, deadlines)?;
    if out.stats.post_processing_cut_short && out.status.finished() {
        out.status = Status::Stopped(if cancel.load(std::sync::atomic::Ordering::Relaxed) { Limit::Cancelled } else { Limit::Time });
    }
    out.stats.seconds = t0.elapsed().as_secs_f64();
    out.stats.cpu_seconds = crate::kernel::search::process_cpu_seconds() - c0;
    Ok(out)
}

/// The share of the timeout the search takes; the settling of its boxes has the rest.
const SEARCH_SHARE: f64 = 0.9;

/// When the search, and then the settling, must end.
#[derive(Clone, Copy)]
struct Deadlines {
    search: Option<Instant>,
    settling: Option<Instant>,
}

fn solve_inner(problem: &DistanceProblem, choice: Choice, redundant: bool, faces: FaceBounds, settings: SolverSettings, cancel: &AtomicBool, deadlines: Deadlines) -> Result<Certified, DistancesError> {
    let c0 = crate::kernel::search::process_cpu_seconds();
    let choice = if choice == Choice::Auto { choose(problem) } else { choice };
    let formulation = if choice == Choice::Split { Formulation::Split } else { Formulation::Shared };
    let cm = CayleyMenger::build(problem, BuildOptions { formulation, redundant })?;
    let placed = match choice {
        Choice::Line => Some(Placed::build_line(problem)?),
        _ => match Placed::build(problem) {
            Ok(p) => Some(p),
            Err(e) if choice == Choice::Points => return Err(e.into()),
            Err(_) => None,
        },
    };
    if matches!(choice, Choice::Points | Choice::Line) {
        let placed = placed.expect("built above");
        let mut out = {
            let solver = placed.solver(settings.clone()).map_err(DistanceSolverError::from)?.until(deadlines.search);
            let e = solver.enclose(cancel, &mut |_| {});
            let solvers = DEEPER.iter().map(|&f| placed.solver(deeper_settings(&settings, f)).map(|s| s.until(deadlines.settling))).collect::<Result<Vec<_>, _>>().map_err(DistanceSolverError::from)?;
            let mut out = Certified { formulation: choice, cm, placed: None, status: e.status, stats: e.stats, solutions: e.solutions, tags: e.tags, cluster: Vec::new(), clusters: Vec::new(), roots: Vec::new(), undecided: e.undecided, phases: vec![("search", crate::kernel::search::process_cpu_seconds() - c0)] };
            let c1 = crate::kernel::search::process_cpu_seconds();
            settle_points(&placed, &solvers, &mut out, cancel);
            out.phases.push(("deeper searches in coordinates", crate::kernel::search::process_cpu_seconds() - c1));
            out
        };
        out.placed = Some(placed);
        Ok(out)
    } else {
        let solver = cm.solver(faces, settings.clone())?.until(deadlines.search);
        let e = solver.enclose(cancel, &mut |_| {});
        let solver = cm.solver(faces, deeper_settings(&settings, DEEPER[0]))?.until(deadlines.settling);
        // Every determinant, shared variables and control points (whatever was solved): the
        // settling's first test of a box no certified placement meets (see `settle_determinants`).
        let all = CayleyMenger::build(problem, BuildOptions { formulation: Formulation::Shared, redundant: true })?;
        let all_solver = all.solver(FaceBounds::Corners, deeper_settings(&settings, DEEPER[0]))?.until(deadlines.settling);
        let tags = vec![BoxStatus::Solution; e.solutions.len()];
        let mut out = Certified { formulation: choice, cm: cm.clone(), placed: None, status: e.status, stats: e.stats, solutions: e.solutions, tags, cluster: Vec::new(), clusters: Vec::new(), roots: Vec::new(), undecided: e.undecided, phases: vec![("search", crate::kernel::search::process_cpu_seconds() - c0)] };
        settle_determinants(&cm, placed.as_ref(), &solver, (&all, &all_solver), settings.threads, &mut out, (cancel, deadlines.settling));
        out.placed = placed;
        Ok(out)
    }
}

/// The deeper searches' sigmas, as fractions of the run's: each unproven box of one is searched
/// again by the next (a box that shrinks to the finer sigma in one round is accepted there
/// unproven, and is usually proven empty or unique one step further).
const DEEPER: [f64; 3] = [1.0 / 16.0, 1.0 / 256.0, 1.0 / 4096.0];

/// A deeper search's settings: sigma times `fraction`, at most 4000 boxes per search, one thread
/// (the searches are small), and the run's time limit (its solvers also end by the run's
/// deadline, `Solver::until`).
fn deeper_settings(s: &SolverSettings, fraction: f64) -> SolverSettings {
    SolverSettings { sigma: s.sigma * fraction, max_boxes: 4_000, threads: 1, ..s.clone() }
}

/// Why a box is left unproven when the run's deadline (or a cancel) stopped its deeper search.
const CUT_SHORT: &str = "the run's time limit (or a cancel) came before a deeper search of it finished";

/// Bounded deeper searches of one box, by `solvers` in turn on what the previous one left
/// unproven: `Ok(certified boxes)` when every box found is proven unique (none: the box held no
/// solution), `Err(reason)` otherwise.
fn deeper(solvers: &[Solver<'_>], b: &IntervalBox, cancel: &AtomicBool, stats: &mut SolveStats) -> Result<Vec<IntervalBox>, &'static str> {
    let mut pending = vec![b.clone()];
    let mut proven = Vec::new();
    for solver in solvers {
        let mut next = Vec::new();
        for p in pending {
            let mut found = Collect::default();
            let (status, st) = solver.run_from(p, cancel, &mut found);
            stats.processed += st.processed;
            stats.certified += st.certified;
            match status {
                Status::Finished => {}
                Status::Stopped(Limit::Time | Limit::Cancelled) => {
                    stats.post_processing_cut_short = true;
                    return Err(CUT_SHORT);
                }
                Status::Stopped(_) => return Err("a deeper search hit its box limit"),
            }
            for (f, u) in found.solutions.into_iter().zip(found.tags.into_iter().map(|t| t == BoxStatus::Unique)) {
                if u {
                    proven.push(f);
                } else {
                    next.push(f);
                }
            }
        }
        if next.is_empty() {
            return Ok(proven);
        }
        pending = next;
    }
    Err("no proof of a single solution, nor of none, after deeper searches")
}

fn settle_points(placed: &Placed, solvers: &[Solver<'_>], out: &mut Certified, cancel: &AtomicBool) {
    // Unproven boxes: replace each by what a deeper search certifies in it, or keep it with why.
    let mut boxes = Vec::new();
    let mut unique = Vec::new();
    let mut why: Vec<Option<&'static str>> = Vec::new();
    for (b, u) in std::mem::take(&mut out.solutions).into_iter().zip(std::mem::take(&mut out.tags).into_iter().map(|t| t == BoxStatus::Unique)) {
        if u {
            boxes.push(b);
            unique.push(true);
            why.push(None);
            continue;
        }
        match deeper(solvers, &b, cancel, &mut out.stats) {
            Ok(found) => {
                for f in found {
                    boxes.push(f);
                    unique.push(true);
                    why.push(None);
                }
            }
            Err(reason) => {
                boxes.push(b);
                unique.push(false);
                why.push(Some(reason));
            }
        }
    }
    let (labels, n) = components(&boxes);
    let mut newton = Newton::new(&placed.system, f64::INFINITY);
    let mut clusters = vec![ClusterVerdict { proven: 0, undecided: None, boxes: 0 }; n];
    for (c, cluster) in clusters.iter_mut().enumerate() {
        let members: Vec<usize> = (0..boxes.len()).filter(|&i| labels[i] == c).collect();
        cluster.boxes = members.len();
        if let Some(r) = members.iter().find_map(|&i| why[i]) {
            cluster.undecided = Some(r);
        }
        // Certified boxes that overlap may hold the same placement: one root when Krawczyk
        // certifies their hull, otherwise the cluster is left undecided about the count.
        let certified: Vec<&IntervalBox> = members.iter().filter(|&&i| unique[i]).map(|&i| &boxes[i]).collect();
        let (groups, _) = components(&certified.iter().map(|b| (*b).clone()).collect::<Vec<_>>());
        let mut seen = Vec::new();
        for (k, &g) in groups.iter().enumerate() {
            if seen.contains(&g) {
                continue;
            }
            seen.push(g);
            let group: Vec<&IntervalBox> = certified.iter().zip(&groups).filter(|(_, &h)| h == g).map(|(b, _)| *b).collect();
            let hull = group.iter().skip(1).fold(group[0].clone(), |h, b| IntervalBox { dims: h.dims.iter().zip(&b.dims).map(|(x, y)| x.convex_hull(*y)).collect(), level: h.level });
            let single = group.len() == 1 || newton.as_mut().and_then(|nw| nw.certify(&hull)).is_some();
            if !single {
                cluster.undecided.get_or_insert("overlapping certified boxes: one solution or two");
            }
            cluster.proven += 1;
            // The certified box may be up to sigma wide: its placement is polished and proven
            // again in a tiny box (kept when that fails: the wide box is still a proof).
            let rough = placed.points(&certified[k].midpoint());
            let (certified, points) = match placed.certify_near(&rough).filter(|x| x.intersects(certified[k])) {
                Some(x) => {
                    let points = placed.points(&x.midpoint());
                    (x, points)
                }
                None => (certified[k].clone(), rough),
            };
            out.roots.push(Root { cluster: c, certified, points });
        }
    }
    out.solutions = boxes;
    out.tags = unique.iter().map(|&u| if u { BoxStatus::Unique } else { BoxStatus::Solution }).collect();
    out.cluster = labels;
    out.clusters = clusters;
}

/// A certified placement found while settling the determinants: its certified box (in the
/// variables of the coordinate system that proved it), its points, and the enclosure of every
/// squared distance over that box (so boxes of any determinant system can be tested against it).
struct Placement {
    certified: IntervalBox,
    points: Vec<[f64; 3]>,
    distance: Vec<Vec<Interval>>,
}

impl Placement {
    fn new(system: &Placed, certified: IntervalBox, points: Vec<[f64; 3]>) -> Self {
        let n = points.len();
        let distance = (0..n).map(|a| (0..n).map(|b| if a == b { crate::kernel::interval::point(0.0) } else { system.distance_over(a, b, &certified) }).collect()).collect();
        Self { certified, points, distance }
    }

    /// True when the placement's distances meet box `b` of `cm` in every unknown (both copies
    /// in the split formulation).
    fn meets(&self, cm: &CayleyMenger, b: &IntervalBox) -> bool {
        cm.unknowns.iter().all(|u| {
            let d = self.distance[u.a][u.b];
            !b.dims[u.var].intersection(d).is_empty() && u.twin.is_none_or(|t| !b.dims[t].intersection(d).is_empty())
        })
    }
}

/// Box `b` of `from` as a start box of `to` (every unknown both systems share cut to the box's
/// interval; the others keep their domains): `None` when a cut is empty.
fn restrict(from: &CayleyMenger, b: &IntervalBox, to: &CayleyMenger) -> Option<IntervalBox> {
    let bounds = from.unknown_intervals(b);
    let mut start = to.system.initial_box();
    for u in &to.unknowns {
        let Some(k) = from.unknowns.iter().position(|v| (v.a, v.b) == (u.a, u.b)) else { continue };
        for var in std::iter::once(u.var).chain(u.twin) {
            let cut = start.dims[var].intersection(bounds[k].1);
            if cut.is_empty() {
                return None;
            }
            start.dims[var] = cut;
        }
    }
    Some(start)
}

/// Settles the boxes of a determinant search. `all` is the system of every determinant (the
/// redundant ones too) in shared variables, with its solver at sigma / 16. The re-searches of
/// unmet boxes run on `threads` threads.
fn settle_determinants(cm: &CayleyMenger, placed: Option<&Placed>, solver: &Solver<'_>, all: (&CayleyMenger, &Solver<'_>), threads: usize, out: &mut Certified, (cancel, deadline): (&AtomicBool, Option<Instant>)) {
    let clock = crate::kernel::search::process_cpu_seconds;
    let t0 = clock();
    let stopped = || cancel.load(std::sync::atomic::Ordering::Relaxed) || deadline.is_some_and(|d| Instant::now() >= d);
    let (mut roots, mut meets, cut) = certified_placements(cm, placed, &out.solutions, &stopped);
    out.stats.post_processing_cut_short |= cut;
    let t1 = clock();
    out.phases.push(("embedding and certifying placements", t1 - t0));
    // Boxes that meet no certified placement are tested twice, cheapest first:
    // 1. searched again with every determinant (`all`: the redundant ones prune where the
    //    system solved is singular, e.g. along the common tangent of octahedral b's curves) from
    //    the box's distances: removed when that search proves the box empty, covered when every
    //    box it finds meets a certified placement (so do the boxes the main search keeps);
    // 2. otherwise searched again in coordinates, with the box's distances as bounds (square,
    //    so Krawczyk certifies what it finds): removed when proven empty, gains the placements
    //    it certifies, or stays undecided. The determinants cannot certify near a tangency
    //    (singular) or when not square.
    let (all_cm, all_solver) = all;
    let covered: Vec<bool> = (0..out.solutions.len()).map(|i| meets.iter().any(|m| m.contains(&i))).collect();
    let pairs: Vec<(usize, usize)> = cm.unknowns.iter().map(|u| (u.a, u.b)).collect();
    let with_r = placed.filter(|p| p.is_square()).and_then(|_| Placed::build_with(&cm.problem, &pairs).ok());
    let s = solver.settings();
    let coordinate_solvers: Vec<Solver<'_>> = match &with_r {
        Some(pr) => [1.0, 1.0 / 16.0].iter().filter_map(|&f| Solver::new(&pr.system, SolverSettings { sigma: s.sigma.min(1e-3) * f, ..s.clone() }).ok().map(|s| s.until(deadline))).collect(),
        None => Vec::new(),
    };
    // The searches of different boxes are independent, so they run on the run's threads, in
    // two passes; the decisions are then taken in box order exactly as one thread would take
    // them. Which boxes need the coordinate search depends on the placements earlier boxes
    // add, and placements only accumulate: a box that is covered with the placements known
    // before the passes is covered then too, so pass 2 searches every box that may need it (a
    // few searches may go unused) and only the searches used are counted.
    let threads = threads.max(1);
    let covered_by = |found: &[IntervalBox], roots: &[Placement]| found.iter().all(|f| roots.iter().any(|r| r.meets(all_cm, f)));
    let t = clock();
    let unmet: Vec<usize> = (0..out.solutions.len()).filter(|&i| !covered[i]).collect();
    // The first pass is shared with the other processes of a shared run, as the search was.
    let firsts: Vec<(Option<Vec<IntervalBox>>, u64)> = crate::kernel::search::map_shared(&unmet, threads, |&i| match restrict(cm, &out.solutions[i], all_cm) {
        None => (Some(Vec::new()), 0),
        Some(start) => {
            let mut found = Collect::default();
            let (status, st) = all_solver.run_from(start, cancel, &mut found);
            ((status == Status::Finished).then_some(found.solutions), st.processed)
        }
    });
    let in_determinants = clock() - t;
    let t = clock();
    let may_need: Vec<usize> = unmet.iter().zip(&firsts).filter(|(_, (first, _))| first.as_ref().is_none_or(|f| !f.is_empty() && !covered_by(f, &roots))).map(|(&i, _)| i).collect();
    let coordinates: Vec<(Result<Vec<Placement>, &'static str>, SolveStats)> = crate::kernel::search::map_parallel(&may_need, threads, |&i| {
        let b = &out.solutions[i];
        let mut stats = SolveStats::default();
        let verdict = match &with_r {
            Some(pr) => {
                let bounds: Vec<_> = cm.unknown_intervals(b).into_iter().map(|(_, d)| d).collect();
                match pr.start_from(&bounds) {
                    None => Ok(Vec::new()),
                    Some(_) if coordinate_solvers.is_empty() => Err("the coordinate search could not be set up"),
                    Some(start) => deeper(&coordinate_solvers, &start, cancel, &mut stats).map(|found| found.into_iter().map(|f| Placement::new(pr, f.clone(), pr.points(&f.midpoint()))).collect()),
                }
            }
            None => deeper(std::slice::from_ref(solver), b, cancel, &mut stats).and_then(|f| if f.is_empty() { Ok(Vec::new()) } else { Err("no frame to certify placements in (fewer than three fixed points)") }),
        };
        (verdict, stats)
    });
    let in_coordinates = clock() - t;
    let mut firsts = unmet.iter().copied().zip(firsts);
    let mut coordinates = may_need.iter().copied().zip(coordinates);
    let mut keep = Vec::new();
    let mut why: Vec<Option<&'static str>> = Vec::new();
    for (i, &is_covered) in covered.iter().enumerate() {
        if is_covered {
            keep.push(i);
            why.push(None);
            continue;
        }
        let (_, (first, processed)) = firsts.next().expect("invariant: one first search per unmet box");
        out.stats.processed += processed;
        match first {
            Some(found) if found.is_empty() => continue,
            Some(found) => {
                let hits: Vec<Vec<usize>> = found.iter().map(|f| (0..roots.len()).filter(|&r| roots[r].meets(all_cm, f)).collect()).collect();
                if hits.iter().all(|h| !h.is_empty()) {
                    keep.push(i);
                    why.push(None);
                    for r in hits.into_iter().flatten() {
                        meets[r].push(i);
                    }
                    continue;
                }
            }
            None => {}
        }
        let (verdict, stats) = loop {
            let (j, searched) = coordinates.next().expect("invariant: pass 2 searched every box that may need it");
            if j == i {
                break searched;
            }
        };
        out.stats.processed += stats.processed;
        out.stats.certified += stats.certified;
        out.stats.post_processing_cut_short |= stats.post_processing_cut_short;
        match verdict {
            Ok(found) if found.is_empty() => {}
            Ok(found) => {
                keep.push(i);
                why.push(None);
                for root in found {
                    // Placements are compared by their points (the two systems' variables differ).
                    match roots.iter().position(|q| q.points.iter().zip(&root.points).all(|(a, b)| (0..3).all(|k| (a[k] - b[k]).abs() <= 1e-6))) {
                        Some(r) => meets[r].push(i),
                        None => {
                            roots.push(root);
                            meets.push(vec![i]);
                        }
                    }
                }
            }
            Err(reason) => {
                keep.push(i);
                why.push(Some(reason));
            }
        }
    }
    out.phases.push(("unmet boxes searched again with every determinant", in_determinants));
    out.phases.push(("unmet boxes searched again in coordinates", in_coordinates));
    cluster_kept(out, &keep, &why, roots, meets);
}

/// Certified placements from every box midpoint of `solutions` (embedded from `cm`'s
/// distances, certified in coordinates by `placed` when it is square), each once, with the
/// boxes each meets, and whether `stopped` ended the walk before the last box (the boxes
/// after it then meet only the placements found before, and are searched again as unmet).
fn certified_placements(cm: &CayleyMenger, placed: Option<&Placed>, solutions: &[IntervalBox], stopped: &dyn Fn() -> bool) -> (Vec<Placement>, Vec<Vec<usize>>, bool) {
    let mut roots: Vec<Placement> = Vec::new();
    let mut meets: Vec<Vec<usize>> = Vec::new();
    if let Some(pl) = placed.filter(|p| p.is_square()) {
        for b in solutions {
            if stopped() {
                return (roots, meets, true);
            }
            let width = cm.unknowns.iter().map(|u| b.width(u.var)).fold(0.0, f64::max);
            for pts in cm.embed(&b.midpoint(), 1e-7 + 10.0 * width) {
                let Some(x) = pl.certify_near(&pts) else { continue };
                if roots.iter().any(|r| r.certified.intersects(&x)) {
                    continue;
                }
                let pts = pl.points(&x.midpoint());
                let root = Placement::new(pl, x, pts);
                let hit: Vec<usize> = (0..solutions.len()).filter(|&i| root.meets(cm, &solutions[i])).collect();
                if hit.is_empty() {
                    // Not a solution of the determinant system as solved (an orientation
                    // choice excludes it): not counted.
                    continue;
                }
                roots.push(root);
                meets.push(hit);
            }
        }
    }
    (roots, meets, false)
}

/// The boxes settling kept (`keep`, indices into `out.solutions`, with why each is undecided),
/// clustered: touching boxes, and boxes that hold the same certified placement (a root on the
/// boundary of two clusters' boxes is one solution, counted once). Each placement in `roots`
/// (meeting the boxes `meets`) is counted in the cluster of the first kept box it meets.
fn cluster_kept(out: &mut Certified, keep: &[usize], why: &[Option<&'static str>], roots: Vec<Placement>, meets: Vec<Vec<usize>>) {
    let old_index: Vec<usize> = keep.to_vec();
    out.solutions = keep.iter().map(|&i| out.solutions[i].clone()).collect();
    out.tags = vec![BoxStatus::Solution; out.solutions.len()];
    let (touch, n0) = components(&out.solutions);
    let pos = |i: usize| old_index.iter().position(|&j| j == i);
    let same_placement = meets.iter().flat_map(|hit| {
        let ks: Vec<usize> = hit.iter().filter_map(|&i| pos(i)).collect();
        ks.windows(2).map(|w| (touch[w[0]], touch[w[1]])).collect::<Vec<_>>()
    });
    // Touch components are numbered by first box, so numbering their unions by smallest
    // member numbers the clusters by first box too.
    let (merged, n) = crate::kernel::interval::labels(n0, &crate::kernel::interval::components_of_edges(n0, same_placement));
    let labels: Vec<usize> = touch.iter().map(|&t| merged[t]).collect();
    let mut clusters = vec![ClusterVerdict { proven: 0, undecided: None, boxes: 0 }; n];
    for (k, &l) in labels.iter().enumerate() {
        clusters[l].boxes += 1;
        if let Some(r) = why[k] {
            clusters[l].undecided.get_or_insert(r);
        }
    }
    for (root, hit) in roots.into_iter().zip(meets) {
        let Some(k) = hit.iter().find_map(|&i| pos(i)) else { continue };
        let c = labels[k];
        clusters[c].proven += 1;
        out.roots.push(Root { cluster: c, certified: root.certified, points: root.points });
    }
    out.cluster = labels;
    out.clusters = clusters;
}


//! The front door's two steps: `prepare` checks a `Job` against its `Input` (every check that
//! needs no search happens here, so a bad request is answered at once), and `Prepared::run`
//! answers it within a `Control`, the only bound of a run (cells, time, memory, threads,
//! cancellation).

use crate::analyses::arm3r::{self, Manip3rError};
use crate::analyses::arm6r::{Chain6R, Manip6rError};
use crate::analyses::distances::DistancesError;
use crate::formulate::cayley_menger::DistanceError;
use crate::formulate::{LinkageError, PlatformError, SingularError};
use crate::kernel::search::{Control, Progress, SettingsError, SolveError, SolverSettings};
use crate::model::{JointKind, Mechanism, ModelError};
use thiserror::Error;

use super::answer::{Answer, CollisionsAnswer, DistancesAnswer, Ik6Answer, IkAnswer, LoopAnswer, PathCheckAnswer, SingularitiesAnswer, SolveAnswer};
use super::arm::{self, Arm, SingularitiesRequest};
use super::distances::{DistancesRequest, DistancesRun};
use super::job::{DistancesJob, Job, LoopQuestion, LoopSingularitiesJob, PathCheckJob, SingularitiesJob, SweepTaskJob};
use super::solve::SolveRun;
use super::loops::{self, Actuation, ImageAnalysisError, ImageSearch};
use crate::analyses::loop_singular::SingularSets;
use crate::analyses::input_motion::{self as motion, MotionError, MotionRequest};
use super::path::{self, PathSet};
use super::six;
use super::AnalysisError;

/// What a job is asked about: a mechanism read from URDF, or a distance problem read from a
/// distance file (which only `Job::Distances` takes).
#[derive(Clone, Debug)]
pub enum Input {
    /// A robot description.
    Mechanism(Mechanism),
    /// The text of a distance file (JSON).
    DistanceFile(String),
}

impl Input {
    /// A robot description from URDF text.
    pub fn urdf(text: &str) -> Result<Self, JobError> {
        Ok(Input::Mechanism(crate::model::urdf::parse(text)?))
    }

    /// URDF when the file's name ends in `.urdf` or its text starts with `<`, else a distance
    /// file.
    pub fn read(name: &str, text: &str) -> Result<Self, JobError> {
        if name.to_ascii_lowercase().ends_with(".urdf") || text.trim_start().starts_with('<') {
            Self::urdf(text)
        } else {
            Ok(Input::DistanceFile(text.to_string()))
        }
    }

    /// The mechanism, for every job but a distance file's.
    pub fn mechanism(&self) -> Result<&Mechanism, JobError> {
        match self {
            Input::Mechanism(m) => Ok(m),
            Input::DistanceFile(_) => Err(JobError::Bad("a distance file holds no mechanism: only `distances` reads it".into())),
        }
    }
}

/// Why a job cannot be prepared or run. Expected outcomes of a search (nothing found, a limit
/// reached) are answers, not errors.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum JobError {
    /// The robot description does not parse.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// A serial arm cannot be read as asked.
    #[error(transparent)]
    Arm(#[from] Manip3rError),
    /// A six-revolute arm cannot be read as asked.
    #[error(transparent)]
    Arm6(#[from] Manip6rError),
    /// A linkage cannot be formulated.
    #[error(transparent)]
    Linkage(#[from] LinkageError),
    /// A platform cannot be formulated.
    #[error(transparent)]
    Platform(#[from] PlatformError),
    /// A distance file cannot be read.
    #[error(transparent)]
    DistanceFile(#[from] DistanceError),
    /// A distance problem cannot be solved as asked.
    #[error(transparent)]
    Distances(#[from] DistancesError),
    /// A singular set cannot be formulated.
    #[error(transparent)]
    Singular(#[from] SingularError),
    /// The type-II image cannot be analysed.
    #[error(transparent)]
    Image(#[from] ImageAnalysisError),
    /// The input motion cannot be followed.
    #[error(transparent)]
    Motion(#[from] MotionError),
    /// Settings out of range.
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// A solver refused its settings.
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// An analysis refused the request.
    #[error(transparent)]
    Analysis(#[from] AnalysisError),
    /// Anything else wrong with the request, named.
    #[error("{0}")]
    Bad(String),
}

impl JobError {
    /// True when the mechanism lies outside what the question's analysis takes (not a serial
    /// chain, not planar, no collision geometry, ...), rather than the request being wrong for
    /// it: front ends that sort their errors (the Python package's `UnsupportedError`) ask this.
    pub fn is_unsupported(&self) -> bool {
        fn linkage(e: &LinkageError) -> bool {
            matches!(e, LinkageError::NonPlanar(_) | LinkageError::Mimic { .. } | LinkageError::UnderConstrained(_) | LinkageError::Unsupported(_) | LinkageError::NoLoops)
        }
        match self {
            JobError::Arm(e) => matches!(e, Manip3rError::NotSerial(_) | Manip3rError::NotThreeR(_) | Manip3rError::Selection(_) | Manip3rError::NoCollisionGeometry(_) | Manip3rError::UnsupportedShape { .. } | Manip3rError::BaseBodyOffAxis(_)),
            JobError::Arm6(e) => matches!(e, Manip6rError::NotSixR(_)),
            JobError::Linkage(e) => linkage(e),
            JobError::Platform(e) => matches!(e, PlatformError::NotAPlatform(_) | PlatformError::Unsupported(_)),
            JobError::Singular(SingularError::Linkage(e)) | JobError::Motion(MotionError::Linkage(e)) => linkage(e),
            JobError::Motion(e) => matches!(e, MotionError::NotOneDof { .. }),
            JobError::Analysis(e) => matches!(e, AnalysisError::NotAvailable { .. }),
            _ => false,
        }
    }
}

/// A job checked against its input, holding what its run needs.
#[derive(Clone, Debug)]
pub struct Prepared {
    job: Ready,
    notice: Option<String>,
}

#[derive(Clone, Debug)]
enum Ready {
    Solve { run: Box<SolveRun>, freedom: String, rigid_links: std::collections::BTreeMap<String, String> },
    Singularities { arm: Box<Arm>, mechanism: Box<Mechanism>, job: Box<SingularitiesJob> },
    Ik { arm: Box<Arm>, point: arm::IkPoint, precision: f64 },
    Ik6 { chain: Box<Chain6R>, pose: crate::analyses::arm6r::PoseInput, precision: f64 },
    SelfMotion { mechanism: Box<Mechanism>, job: Box<super::SelfMotionJob> },
    Path6 { chain: Box<Chain6R>, waypoints: Vec<[f64; 6]>, precision: f64 },
    Path3 { arm: Box<Arm>, waypoints: Vec<Vec<f64>>, precision: f64 },
    Collisions { mechanism: Box<Mechanism>, options: Box<arm3r::LoadOptions>, precision: f64 },
    Distances { run: Box<DistancesRun>, request: DistancesRequest, settings: SolverSettings },
    LoopSets { mechanism: String, sets: Box<SingularSets>, settings: SolverSettings },
    LoopImage { mechanism: Box<Mechanism>, fixed: Vec<(String, f64)>, actuated: Vec<String>, search: Option<ImageSearch>, grid: usize, settings: SolverSettings },
    LoopMotion { mechanism: Box<Mechanism>, fixed: Vec<(String, f64)>, request: MotionRequest },
    SweepTask { mechanism: Box<Mechanism>, job: Box<SweepTaskJob> },
}

/// Checks `job` against `input`: every check that needs no search.
pub fn prepare(input: &Input, job: Job) -> Result<Prepared, JobError> {
    let mut notice = None;
    let ready = match job {
        Job::Solve(j) => {
            let m = input.mechanism()?;
            let settings = SolverSettings { sigma: j.precision, rho: j.rho, use_lp: j.use_lp, newton_width: j.newton_width, lp_backend: j.lp_backend, ..SolverSettings::default() };
            settings.validate()?;
            let run = SolveRun::build(m, j.model, &j.fixed, &j.traces, settings)?;
            let (freedom, line) = run.freedom();
            // Covering a continuum of two or more dimensions takes long: said before the run.
            if freedom.at_point.is_some_and(|l| l.dof >= 2) {
                notice = Some(format!("{}: {line}", m.name));
            }
            Ready::Solve { run: Box::new(run), freedom: line, rigid_links: m.rigid_links() }
        }
        Job::Singularities(j) => {
            let m = input.mechanism()?;
            arm3r::check_precision(j.precision)?;
            if !(j.arm_budget.is_finite() && j.arm_budget >= 0.0) {
                return Err(JobError::Bad(format!("--arm-budget must be a number of seconds >= 0, got {}", j.arm_budget)));
            }
            let arm = Arm::load(m, &j.arm, j.uncertainty)?;
            Ready::Singularities { arm: Box::new(arm), mechanism: Box::new(m.clone()), job: Box::new(j) }
        }
        Job::Ik(j) => {
            let m = input.mechanism()?;
            if let arm::IkPoint::Root(p) = j.point {
                if p.iter().any(|v| !v.is_finite()) {
                    return Err(Manip3rError::BadTarget(p).into());
                }
            }
            arm3r::check_precision(j.precision)?;
            Ready::Ik { arm: Box::new(Arm::load(m, &j.arm, j.uncertainty)?), point: j.point, precision: j.precision }
        }
        Job::Ik6(j) => {
            let m = input.mechanism()?;
            let chain = six_joint_chain(m, &j.arm)?;
            j.pose.target()?;
            Ready::Ik6 { chain: Box::new(chain), pose: j.pose, precision: j.precision }
        }
        Job::SelfMotion(j) => {
            j.pose.target()?;
            if let Some((joint, _)) = j.arm.spec.locks.first() {
                return Err(JobError::Bad(format!("--fix {joint}: self-motion holds no joint (its parameter joint is cut into cells; choose it with --parameter)")));
            }
            if !(j.precision > 0.0 && j.precision < 1.0) {
                return Err(JobError::Bad(format!("precision must be a number in (0, 1), got {}", j.precision)));
            }
            Ready::SelfMotion { mechanism: Box::new(input.mechanism()?.clone()), job: Box::new(j) }
        }
        Job::PathCheck(j) => prepare_path(input.mechanism()?, j)?,
        Job::Collisions(j) => {
            arm3r::check_precision(j.precision)?;
            Ready::Collisions { mechanism: Box::new(input.mechanism()?.clone()), options: Box::new(j.arm), precision: j.precision }
        }
        Job::Distances(j) => prepare_distances(input, j)?,
        Job::LoopSingularities(j) => prepare_loops(input.mechanism()?, j)?,
        Job::SweepTask(j) => Ready::SweepTask { mechanism: Box::new(input.mechanism()?.clone()), job: Box::new(j) },
    };
    Ok(Prepared { job: ready, notice })
}

/// The six revolute joints of `m` as `options` read them; a longer revolute chain is refused
/// rather than cut to its first six joints.
fn six_joint_chain(m: &Mechanism, options: &arm3r::LoadOptions) -> Result<Chain6R, JobError> {
    if options.spec.tip.is_none() {
        let held = |j: usize| options.spec.locks.iter().any(|(n, _)| *n == m.joints[j].name);
        let revolute = |l: usize| m.path_to(l).into_iter().filter(|&j| matches!(m.joints[j].kind, JointKind::Revolute { .. }) && !held(j)).count();
        if let Some((n, tip)) = (0..m.links.len()).map(|l| (revolute(l), l)).max().filter(|(n, _)| *n > 6) {
            let on_path = m.path_to(tip).into_iter().filter(|&j| matches!(m.joints[j].kind, JointKind::Revolute { .. }) && !held(j)).map(|j| m.joints[j].name.clone()).collect::<Vec<_>>();
            return Err(JobError::Bad(format!(
                "'{}' has {n} revolute joints from its root to '{}' ({}): hold {} of them with --fix JOINT=VALUE (e.g. --fix {}=0) so that six remain, or choose a six-joint sub-chain with --tip LINK (of a seven-joint arm, `linkspace self-motion` gives every configuration at a pose)",
                m.name,
                m.links[tip].name,
                on_path.join(", "),
                n - 6,
                on_path.get(2).map_or("JOINT", String::as_str)
            )));
        }
    }
    Ok(six::chain6(m, options)?)
}

/// Waypoints one request may check: a path of more is refused rather than held in memory.
pub(crate) const MAX_WAYPOINTS: usize = 100_000;

/// Joint values beyond this many radians are refused: no joint turns 1,600 times.
const MAX_JOINT_VALUE: f64 = 1e4;

/// The waypoints' values of `joints`, in that order, taken from the columns `names` (or in
/// order when `names` is empty).
fn columns(waypoints: Vec<Vec<f64>>, names: &[String], joints: &[String]) -> Result<Vec<Vec<f64>>, JobError> {
    if waypoints.len() > MAX_WAYPOINTS {
        return Err(JobError::Bad(format!("{} waypoints: at most {MAX_WAYPOINTS} are checked in one request", waypoints.len())));
    }
    if let Some((k, x)) = waypoints.iter().enumerate().find_map(|(k, w)| w.iter().find(|x| !(x.abs() <= MAX_JOINT_VALUE)).map(|x| (k, *x))) {
        return Err(JobError::Bad(format!("waypoint {}: joint value {x} is not a number within ±{MAX_JOINT_VALUE} rad", k + 1)));
    }
    if names.is_empty() {
        return match waypoints.iter().enumerate().find(|(_, w)| w.len() != joints.len()) {
            Some((k, w)) => Err(JobError::Bad(format!("waypoint {} has {} joint values: expected {}", k + 1, w.len(), joints.len()))),
            None => Ok(waypoints),
        };
    }
    let shown = |v: &[String]| if v.len() > 12 { format!("{}, and {} more", v[..12].join(", "), v.len() - 12) } else { v.join(", ") };
    let mut column = Vec::with_capacity(joints.len());
    for joint in joints {
        match names.iter().position(|n| n == joint) {
            Some(i) => column.push(i),
            None => return Err(JobError::Bad(format!("the trajectory has no joint '{joint}' (the arm's joints: {}; given: {})", joints.join(", "), shown(names)))),
        }
    }
    waypoints
        .into_iter()
        .enumerate()
        .map(|(k, w)| if w.len() == names.len() { Ok(column.iter().map(|&i| w[i]).collect()) } else { Err(JobError::Bad(format!("point {k} has {} positions for {} joint names", w.len(), names.len()))) })
        .collect()
}

fn prepare_path(m: &Mechanism, j: PathCheckJob) -> Result<Ready, JobError> {
    let sub_chain_chosen = j.arm.spec.tip_point.is_some() || !j.arm.spec.locks.is_empty();
    let set = match j.set {
        Some(set) => set,
        None if !sub_chain_chosen && six::chain6(m, &j.arm).is_ok() => PathSet::Arm6R,
        None => PathSet::Positioning3R,
    };
    match set {
        PathSet::Arm6R => {
            if sub_chain_chosen {
                return Err(JobError::Bad("--fix and --tip-point choose a 3R sub-chain and its point: they apply with --singular-set 3r".into()));
            }
            let chain = six_joint_chain(m, &j.arm).map_err(|e| match e {
                JobError::Arm6(e) => JobError::Bad(format!("'{}' is not an arm with six revolute joints from base to tip ({e})", m.name)),
                e => e,
            })?;
            let waypoints = columns(j.waypoints, &j.joint_names, &chain.joints)?;
            let waypoints = waypoints.iter().map(|w| <[f64; 6]>::try_from(w.as_slice()).expect("invariant: six values checked")).collect();
            Ok(Ready::Path6 { chain: Box::new(chain), waypoints, precision: j.precision })
        }
        PathSet::Positioning3R => {
            let arm = Arm::load(m, &j.arm, 0.0)?;
            let waypoints = columns(j.waypoints, &j.joint_names, &path::positioning_joints(&arm))?;
            Ok(Ready::Path3 { arm: Box::new(arm), waypoints, precision: j.precision })
        }
    }
}

fn prepare_distances(input: &Input, j: DistancesJob) -> Result<Ready, JobError> {
    // Checked before the file is read: rho's default depends on the formulation.
    SolverSettings { sigma: j.precision, rho: j.rho.unwrap_or(0.99), ..SolverSettings::default() }.validate()?;
    let run = match input {
        Input::Mechanism(m) => DistancesRun::platform_with(m, &j.fixed, j.legs)?,
        Input::DistanceFile(text) => DistancesRun::file(text, &j.fixed)?,
    };
    let request = DistancesRequest { formulation: run.formulation(j.formulation), redundant: j.redundant, faces: j.faces };
    let rho = j.rho.unwrap_or(DistancesRun::default_rho(request.formulation));
    let settings = SolverSettings { sigma: j.precision, rho, ..SolverSettings::default() };
    settings.validate()?;
    Ok(Ready::Distances { run: Box::new(run), request, settings })
}

fn prepare_loops(m: &Mechanism, j: LoopSingularitiesJob) -> Result<Ready, JobError> {
    let settings = SolverSettings { sigma: j.precision, ..SolverSettings::default() };
    settings.validate()?;
    // The node's default too (`LinkageAnalysis`): one function.
    let actuated = match j.actuated {
        Some(a) => Actuation::given(a),
        None => Actuation::from_transmissions(m, &j.fixed),
    }
    .joints;
    let image = |search: Option<ImageSearch>, grid: usize| Ready::LoopImage { mechanism: Box::new(m.clone()), fixed: j.fixed.clone(), actuated: actuated.clone(), search, grid, settings: settings.clone() };
    Ok(match j.question {
        LoopQuestion::Sets(kinds) => {
            let kinds = if kinds.is_empty() { loops::all_kinds(&actuated) } else { kinds };
            // Every problem built first, one timeout for all: the orchestration the node runs too.
            let sets = SingularSets::new(m, &j.fixed, &kinds, &actuated, j.output)?;
            Ready::LoopSets { mechanism: m.name.clone(), sets: Box::new(sets), settings }
        }
        LoopQuestion::Image { grid } if grid < 2 => return Err(JobError::Bad("--grid must be at least 2".into())),
        LoopQuestion::Image { grid } => image(None, grid),
        LoopQuestion::Cusps => image(Some(ImageSearch::Cusps), 0),
        LoopQuestion::Nodes => image(Some(ImageSearch::Nodes), 0),
        LoopQuestion::Motion(span) => {
            let [joint] = actuated.as_slice() else {
                return Err(JobError::Bad(format!("--kind motion: one actuated joint (--actuated J), got {}", actuated.len())));
            };
            let request = MotionRequest { actuated: joint.clone(), from: span.from, to: span.to, assembly: span.assembly, max_step: span.max_step, min_step: span.min_step, name_turning_point: true };
            Ready::LoopMotion { mechanism: Box::new(m.clone()), fixed: j.fixed, request }
        }
    })
}

/// `settings` bounded by `control` instead of their own limits.
fn within(settings: &SolverSettings, control: &Control) -> SolverSettings {
    SolverSettings { max_boxes: control.limits.max_cells, timeout: control.limits.timeout, max_memory: control.limits.max_memory, threads: control.threads, ..settings.clone() }
}

impl Prepared {
    /// What a front end should say before the run starts (a continuum of two or more
    /// dimensions to cover, which takes long), if anything.
    pub fn notice(&self) -> Option<&str> {
        self.notice.as_deref()
    }

    /// Answers the job within `control`, reporting progress where the search gives it. An
    /// error here is one only the analysis itself could find (a geometry degenerate where it
    /// looked); a limit reached is an answer, incomplete.
    pub fn run(self, control: &Control, progress: &mut dyn FnMut(&Progress)) -> Result<Answer, JobError> {
        Ok(match self.job {
            Ready::Solve { run, freedom, rigid_links } => {
                let settings = within(run.settings(), control);
                let run = run.within(settings);
                let (result, links) = run.run_reading(control.cancel, progress, Some(&rigid_links));
                Answer::Solve(Box::new(SolveAnswer { run, result, links, freedom, rigid_links }))
            }
            Ready::Singularities { arm, mechanism, job } => {
                let request = SingularitiesRequest { precision: job.precision, nodes: job.nodes, search_anyway: job.search_anyway, verdict: job.verdict };
                let t0 = std::time::Instant::now();
                let found = arm::singularities(&arm, &request, control, progress)?;
                let whole_arm = if job.verdict && job.arm_budget > 0.0 {
                    // Within what the 3R searches left of the run's timeout too.
                    let left = control.remaining_since(t0);
                    let budget = std::time::Duration::from_secs_f64(job.arm_budget);
                    let budget = left.limits.timeout.map_or(budget, |t| t.min(budget));
                    six::arm_cuspidality(&mechanism, &arm, &job.arm, budget, &left)
                } else {
                    None
                };
                Answer::Singularities(Box::new(SingularitiesAnswer { arm: *arm, found, whole_arm }))
            }
            Ready::Ik { arm, point, precision } => {
                let found = arm::inverse_kinematics(&arm, point, precision, control, progress)?;
                Answer::Ik(Box::new(IkAnswer { arm: *arm, found }))
            }
            Ready::Ik6 { chain, pose, precision } => {
                let found = six::inverse_kinematics6(&chain, pose, precision, control)?;
                Answer::Ik6(Box::new(Ik6Answer { chain: *chain, found }))
            }
            Ready::SelfMotion { mechanism, job } => Answer::SelfMotion(Box::new(six::self_motion(&mechanism, &job.arm, &job, control)?)),
            Ready::Path6 { chain, waypoints, precision } => Answer::PathCheck(Box::new(PathCheckAnswer { found: path::check_path(&chain, &waypoints, precision, control)?, chain: None })),
            Ready::Path3 { arm, waypoints, precision } => {
                let found = path::check_path3(&arm, &waypoints, precision, control)?;
                Answer::PathCheck(Box::new(PathCheckAnswer { found, chain: Some(arm.prepared.choice.reason.clone()) }))
            }
            Ready::Collisions { mechanism, options, precision } => {
                let found = arm::collisions(&mechanism, &options, precision, control, progress)?;
                Answer::Collisions(Box::new(CollisionsAnswer { found, precision }))
            }
            Ready::Distances { run, request, settings } => {
                let settings = within(&settings, control);
                let certified = run.run(&request, &settings, control.cancel)?;
                Answer::Distances(Box::new(DistancesAnswer { run: *run, request, settings, certified }))
            }
            Ready::LoopSets { mechanism, sets, settings } => {
                let settings = within(&settings, control);
                let solved = sets.solve(&settings, control.cancel)?;
                Answer::LoopSingularities(Box::new(LoopAnswer::Sets { mechanism, sets: *sets, solved, settings }))
            }
            Ready::LoopImage { mechanism, fixed, actuated, search, grid, settings } => {
                let settings = within(&settings, control);
                Answer::LoopSingularities(Box::new(match search {
                    None => LoopAnswer::Image(Box::new(loops::analyse_image(&mechanism, &fixed, &actuated, &settings, grid, control.cancel)?)),
                    Some(search) => LoopAnswer::Points(Box::new(loops::image_points(&mechanism, &fixed, &actuated, search, &settings, control.cancel)?)),
                }))
            }
            Ready::LoopMotion { mechanism, fixed, request } => Answer::LoopSingularities(Box::new(LoopAnswer::Motion(Box::new(motion::check_input_motion(&mechanism, &fixed, &request, control)?)))),
            Ready::SweepTask { mechanism, job } => Answer::SweepTask(Box::new(super::sweep::sweep_task(&job.plan, &mechanism, &job.task, &control.limits, control.cancel))),
        })
    }
}

//! The service requests: their decoded form (`Request`), the servers that answer them, and one
//! handler per service (solve, cancel, singularities, inverse_kinematics, classify,
//! inverse_kinematics6, path_check, collisions, self_motion, list_mechanisms).
//!
//! A handler checks the request on the event loop and either answers at once (a refusal with
//! its reason, or an answer the node already holds) or starts a run and returns `None`: the
//! reply then waits in the run's `waiters` until `runs` sends it. Every handler runs under
//! `catch_unwind` (`State::request`), so a bug answers with an error instead of taking the
//! node down; none of them blocks on a search.

use super::runs::{Outcome, RunKind, Work};
use super::{panic_text, seconds};
use crate::app::{AnalysisError, IkQuery, Service, SingularityQuery};
use crate::edges::ros::convert;
use crate::edges::ros::msgs::*;
use crate::app::{SolverSettings, Status};
use ros2_client::{RmwRequestId, Server};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::Ordering;
use std::time::Instant;

/// Poses one InverseKinematics6 request may carry (its reply holds an answer per pose).
const MAX_POSES: usize = 1000;

/// A decoded service request with the id its reply must carry.
pub(super) enum Request {
    Solve(RmwRequestId, SolveRequest),
    Cancel(RmwRequestId, CancelRequest),
    Singularities(RmwRequestId, SingularitiesRequest),
    InverseKinematics(RmwRequestId, InverseKinematicsRequest),
    Classify(RmwRequestId, ClassifyRequest),
    InverseKinematics6(RmwRequestId, InverseKinematics6Request),
    PathCheck(RmwRequestId, PathCheckRequest),
    Collisions(RmwRequestId, CollisionsRequest),
    SelfMotion(RmwRequestId, SelfMotionRequest),
    List(RmwRequestId),
}

/// The node's service servers, shared (`Rc`) with the tasks that forward their requests.
pub(super) struct Servers {
    pub(super) solve: Server<SolveRequest, SolveResponse>,
    pub(super) cancel: Server<CancelRequest, CancelResponse>,
    pub(super) singularities: Server<SingularitiesRequest, SingularitiesResponse>,
    pub(super) inverse_kinematics: Server<InverseKinematicsRequest, InverseKinematicsResponse>,
    pub(super) classify: Server<ClassifyRequest, ClassifyResponse>,
    pub(super) inverse_kinematics6: Server<InverseKinematics6Request, InverseKinematics6Response>,
    pub(super) path_check: Server<PathCheckRequest, PathCheckResponse>,
    pub(super) collisions: Server<CollisionsRequest, CollisionsResponse>,
    pub(super) self_motion: Server<SelfMotionRequest, SelfMotionResponse>,
    pub(super) list: Server<ListMechanismsRequest, ListMechanismsResponse>,
}

pub(super) fn solve_error(message: String) -> SolveResponse {
    SolveResponse { ok: false, message, ..Default::default() }
}

/// A Singularities reply carrying the whole `report` (the patched RustDDS sends replies of any
/// size: vendor/README.md).
pub(super) fn singularity_reply(report: &SingularityReport) -> SingularitiesResponse {
    SingularitiesResponse { ok: true, message: report.message.clone(), report: report.clone() }
}

impl super::State {
    /// An error reply of the service that `kind` answers.
    pub(super) fn reply_error(&self, kind: RunKind, id: RmwRequestId, message: String) {
        match kind {
            RunKind::Solve | RunKind::SolveAction | RunKind::ConfigurationSpace => self.reply_solve(id, solve_error(message)),
            RunKind::Singularities { .. } => self.reply_singularities(id, SingularitiesResponse { ok: false, message, report: convert::no_report() }),
            RunKind::InverseKinematics => self.reply_ik(id, InverseKinematicsResponse { ok: false, message, ..Default::default() }),
            RunKind::InverseKinematics6 => self.reply_ik6(id, InverseKinematics6Response { ok: false, message, ..Default::default() }),
            RunKind::PathCheck => self.reply_path_check(id, PathCheckResponse { ok: false, message, ..Default::default() }),
            RunKind::Collisions => self.reply_collisions(id, CollisionsResponse { ok: false, message, ..Default::default() }),
            RunKind::SelfMotion => self.reply_self_motion(id, SelfMotionResponse { ok: false, message, ..Default::default() }),
        }
    }

    pub(super) fn reply_self_motion(&self, id: RmwRequestId, reply: SelfMotionResponse) {
        if let Err(e) = self.servers.self_motion.send_response(id, reply) {
            say!("linkspace: sending a self_motion reply: {e:?}");
        }
    }

    pub(super) fn reply_collisions(&self, id: RmwRequestId, reply: CollisionsResponse) {
        if let Err(e) = self.servers.collisions.send_response(id, reply) {
            say!("linkspace: sending a collisions reply: {e:?}");
        }
    }

    pub(super) fn reply_path_check(&self, id: RmwRequestId, reply: PathCheckResponse) {
        if let Err(e) = self.servers.path_check.send_response(id, reply) {
            say!("linkspace: sending a path_check reply: {e:?}");
        }
    }

    pub(super) fn reply_singularities(&self, id: RmwRequestId, reply: SingularitiesResponse) {
        if let Err(e) = self.servers.singularities.send_response(id, reply) {
            say!("linkspace: sending a singularities reply: {e:?}");
        }
    }

    pub(super) fn reply_ik(&self, id: RmwRequestId, reply: InverseKinematicsResponse) {
        if let Err(e) = self.servers.inverse_kinematics.send_response(id, reply) {
            say!("linkspace: sending an inverse_kinematics reply: {e:?}");
        }
    }

    pub(super) fn reply_ik6(&self, id: RmwRequestId, reply: InverseKinematics6Response) {
        if let Err(e) = self.servers.inverse_kinematics6.send_response(id, reply) {
            say!("linkspace: sending an inverse_kinematics6 reply: {e:?}");
        }
    }

    pub(super) fn reply_solve(&self, id: RmwRequestId, reply: SolveResponse) {
        if let Err(e) = self.servers.solve.send_response(id, reply) {
            say!("linkspace: sending a solve reply: {e:?}");
        }
    }
    /// Handles one request under `catch_unwind`: a bug answers with an error and the node goes on.
    pub(super) fn request(&mut self, request: Request) {
        let servers = self.servers.clone();
        let internal = |p: Box<dyn std::any::Any + Send>| format!("internal error while handling the request: {}", panic_text(p.as_ref()));
        let sent = match request {
            Request::Solve(id, q) => match catch_unwind(AssertUnwindSafe(|| self.solve(id, q))) {
                Ok(None) => Ok(()),
                Ok(Some(a)) => servers.solve.send_response(id, a),
                Err(p) => servers.solve.send_response(id, solve_error(internal(p))),
            },
            Request::Cancel(id, q) => {
                let a = catch_unwind(AssertUnwindSafe(|| self.cancel(q))).unwrap_or_else(|p| CancelResponse { ok: false, message: internal(p) });
                servers.cancel.send_response(id, a)
            }
            Request::Singularities(id, q) => match catch_unwind(AssertUnwindSafe(|| self.singularities(id, q))) {
                Ok(None) => Ok(()),
                Ok(Some(a)) => servers.singularities.send_response(id, a),
                Err(p) => servers.singularities.send_response(id, SingularitiesResponse { ok: false, message: internal(p), report: convert::no_report() }),
            },
            Request::InverseKinematics(id, q) => match catch_unwind(AssertUnwindSafe(|| self.inverse_kinematics(id, q))) {
                Ok(None) => Ok(()),
                Ok(Some(a)) => servers.inverse_kinematics.send_response(id, a),
                Err(p) => servers.inverse_kinematics.send_response(id, InverseKinematicsResponse { ok: false, message: internal(p), ..Default::default() }),
            },
            Request::Classify(id, q) => {
                let a = catch_unwind(AssertUnwindSafe(|| self.classify(q))).unwrap_or_else(|p| ClassifyResponse { ok: false, message: internal(p), component: -1, ..Default::default() });
                servers.classify.send_response(id, a)
            }
            Request::InverseKinematics6(id, q) => match catch_unwind(AssertUnwindSafe(|| self.inverse_kinematics6(id, q))) {
                Ok(None) => Ok(()),
                Ok(Some(a)) => servers.inverse_kinematics6.send_response(id, a),
                Err(p) => servers.inverse_kinematics6.send_response(id, InverseKinematics6Response { ok: false, message: internal(p), ..Default::default() }),
            },
            Request::PathCheck(id, q) => match catch_unwind(AssertUnwindSafe(|| self.path_check(id, q))) {
                Ok(None) => Ok(()),
                Ok(Some(a)) => servers.path_check.send_response(id, a),
                Err(p) => servers.path_check.send_response(id, PathCheckResponse { ok: false, message: internal(p), ..Default::default() }),
            },
            Request::Collisions(id, q) => match catch_unwind(AssertUnwindSafe(|| self.collisions(id, q))) {
                Ok(None) => Ok(()),
                Ok(Some(a)) => servers.collisions.send_response(id, a),
                Err(p) => servers.collisions.send_response(id, CollisionsResponse { ok: false, message: internal(p), ..Default::default() }),
            },
            Request::SelfMotion(id, q) => match catch_unwind(AssertUnwindSafe(|| self.self_motion(id, q))) {
                Ok(None) => Ok(()),
                Ok(Some(a)) => servers.self_motion.send_response(id, a),
                Err(p) => servers.self_motion.send_response(id, SelfMotionResponse { ok: false, message: internal(p), ..Default::default() }),
            },
            Request::List(id) => {
                let a = catch_unwind(AssertUnwindSafe(|| self.list())).unwrap_or_else(|_| ListMechanismsResponse::default());
                servers.list.send_response(id, a)
            }
        };
        if let Err(e) = sent {
            say!("linkspace: sending a reply: {e:?}");
        }
    }
    fn mechanism(&self, name: &str) -> Result<usize, String> {
        self.mechanisms.iter().position(|m| m.loaded.analysis.mechanism() == name).ok_or_else(|| {
            let names: Vec<&str> = self.mechanisms.iter().map(|m| m.loaded.analysis.mechanism()).collect();
            format!("no mechanism named '{}' is loaded (loaded: {})", convert::bounded(name, convert::ECHO_NAME), names.join(", "))
        })
    }
    /// The index of mechanism `name` when its analysis answers `service`; otherwise why not.
    fn serving(&self, name: &str, service: Service) -> Result<usize, String> {
        let k = self.mechanism(name)?;
        let a = &self.mechanisms[k].loaded.analysis;
        if !a.services().contains(&service) {
            return Err(a.not_available(service).to_string());
        }
        Ok(k)
    }
    /// Validates and starts a run; `None` when the reply waits for the run.
    fn solve(&mut self, id: RmwRequestId, q: SolveRequest) -> Option<SolveResponse> {
        let (k, job) = match self.solve_job(&q) {
            Ok(j) => j,
            Err(e) => return Some(solve_error(e)),
        };
        let run = self.start(k, RunKind::Solve, job);
        if q.wait > 0.0 {
            let r = self.runs.get_mut(&run).expect("invariant: just started");
            r.waiters.push((id, Instant::now() + seconds(q.wait)));
            None
        } else {
            Some(SolveResponse { ok: true, message: format!("run {run} started; its result will be published on {}/solve_result", self.mechanisms[k].prefix), run_id: run, done: false, ..Default::default() })
        }
    }

    /// A Solve request checked and prepared (the mechanism and the run), or why not.
    pub(super) fn solve_job(&self, q: &SolveRequest) -> Result<(usize, Work), String> {
        let k = self.mechanism(&q.mechanism)?;
        let limits = &self.limits;
        let s = &q.settings;
        if q.fixed_joint_names.len() != q.fixed_joint_values.len() {
            return Err(format!("{} fixed joint names but {} values", q.fixed_joint_names.len(), q.fixed_joint_values.len()));
        }
        if let Some((i, name)) = q.fixed_joint_names.iter().enumerate().find(|(i, n)| q.fixed_joint_names[..*i].contains(n)) {
            return Err(format!("joint '{}' is fixed twice (fixed_joint_names[{i}])", convert::bounded(name, convert::ECHO_NAME)));
        }
        if s.max_boxes == 0 {
            return Err(format!("settings.max_boxes must be given: every run is bounded (1 to {})", limits.max_boxes));
        }
        if s.max_boxes > limits.max_boxes {
            return Err(format!("settings.max_boxes {} is larger than this node's limit {} (--max-request-boxes)", s.max_boxes, limits.max_boxes));
        }
        // Settings.msg: timeout 0 means no time limit of the request's own; the node's
        // --max-request-timeout still bounds the run (and max_boxes always does).
        if !(s.timeout >= 0.0 && s.timeout <= limits.max_timeout) {
            return Err(format!("settings.timeout {} s is out of range: give 0 (the node's limit) to {} s (--max-request-timeout)", s.timeout, limits.max_timeout));
        }
        let timeout = if s.timeout == 0.0 { limits.max_timeout } else { s.timeout };
        if !(q.wait >= 0.0 && q.wait <= limits.max_wait) {
            return Err(format!("wait {} s is out of range: give 0 <= wait <= {} s", q.wait, limits.max_wait));
        }
        if let Some(busy) = self.busy() {
            return Err(busy);
        }
        let settings = SolverSettings { sigma: s.sigma, rho: s.rho, max_boxes: s.max_boxes, timeout: Some(seconds(timeout)), ..self.settings.clone() };
        let fixed: Vec<(String, f64)> = q.fixed_joint_names.iter().cloned().zip(q.fixed_joint_values.iter().copied()).collect();
        let prepared = match self.mechanisms[k].loaded.analysis.solve(&fixed, &settings) {
            Ok(p) => p,
            // The error may quote the request (a joint name): bounded.
            Err(e) => return Err(convert::bounded(&e.to_string(), convert::ECHO_MESSAGE)),
        };
        Ok((k, Box::new(move |c, p| prepared.run(c, p).map(Outcome::BoxSet).map_err(|e| e.to_string()))))
    }
    fn cancel(&mut self, q: CancelRequest) -> CancelResponse {
        match self.runs.get(&q.run_id) {
            Some(r) if r.kind.requested() => {
                r.cancel.store(true, Ordering::Relaxed);
                let prefix = &self.mechanisms[r.mechanism].prefix;
                let whereto = match r.kind {
                    RunKind::Solve => format!("will be published on {prefix}/solve_result"),
                    RunKind::SolveAction => format!("will be the action's result (status CANCELED) and published on {prefix}/solve_result"),
                    _ => "will be in the reply to its request".to_string(),
                };
                CancelResponse { ok: true, message: format!("run {} cancelled; its incomplete result {whereto}", q.run_id) }
            }
            Some(_) => CancelResponse { ok: false, message: format!("run {} is a load-time analysis and cannot be cancelled", q.run_id) },
            None if self.finished.contains(&q.run_id) => CancelResponse { ok: false, message: format!("run {} has already finished", q.run_id) },
            None => CancelResponse { ok: false, message: format!("no run {}", q.run_id) },
        }
    }
    /// A request's box limit: 0 means the node's limit; more is refused.
    fn box_limit(&self, max_boxes: u64) -> Result<u64, String> {
        match max_boxes {
            0 => Ok(self.limits.max_boxes),
            n if n > self.limits.max_boxes => Err(format!("max_boxes {n} is larger than this node's limit {} (--max-request-boxes)", self.limits.max_boxes)),
            n => Ok(n),
        }
    }
    /// Answers with the load-time report, or starts a run with the request's settings; `None`
    /// when the reply waits for a run.
    fn singularities(&mut self, id: RmwRequestId, q: SingularitiesRequest) -> Option<SingularitiesResponse> {
        let refuse = |message: String| Some(SingularitiesResponse { ok: false, message, report: convert::no_report() });
        let k = match self.mechanism(&q.mechanism) {
            Ok(k) => k,
            Err(e) => return refuse(e),
        };
        let m = &self.mechanisms[k];
        let a = &m.loaded.analysis;
        if !a.services().contains(&Service::Singularities) {
            return refuse(a.not_available(Service::Singularities).to_string());
        }
        if q.precision == 0.0 {
            if let Some((report, _)) = &m.published_singularities {
                return Some(singularity_reply(report));
            }
            let Some(run) = m.singularity_run else { return refuse(format!("no singularity report for '{}': {}", q.mechanism, m.message)) };
            let deadline = Instant::now() + seconds(self.limits.max_wait);
            self.runs.get_mut(&run).expect("invariant: the load-time run is going").waiters.push((id, deadline));
            return None;
        }
        let max_boxes = match self.box_limit(q.max_boxes) {
            Ok(n) => n,
            Err(e) => return refuse(e),
        };
        let longest = self.limits.max_timeout.min(self.limits.max_wait);
        if !(q.timeout >= 0.0 && q.timeout <= longest) {
            return refuse(format!("timeout {} s is out of range: give 0 (the node's limit) to {longest} s (--max-request-timeout and --max-wait)", q.timeout));
        }
        let timeout = if q.timeout == 0.0 { longest } else { q.timeout };
        let query = SingularityQuery { precision: q.precision, nodes: q.nodes, max_boxes, timeout: Some(seconds(timeout)), threads: self.settings.threads };
        let prepared = match a.singularities(&query) {
            Ok(p) => p,
            Err(e) => return refuse(e.to_string()),
        };
        if let Some(busy) = self.busy() {
            return refuse(busy);
        }
        let run = self.start(k, RunKind::Singularities { load_time: false }, Box::new(move |c, p| prepared.run(c, p).map(Outcome::Singularities).map_err(|e| e.to_string())));
        // The searches stop at `timeout`; the margin covers building the report.
        let deadline = Instant::now() + seconds(timeout + 10.0);
        self.runs.get_mut(&run).expect("invariant: just started").waiters.push((id, deadline));
        None
    }

    /// Validates and starts an inverse-kinematics run; `None` when the reply waits for it.
    fn inverse_kinematics(&mut self, id: RmwRequestId, q: InverseKinematicsRequest) -> Option<InverseKinematicsResponse> {
        let refuse = |message: String| Some(InverseKinematicsResponse { ok: false, message, ..Default::default() });
        let k = match self.mechanism(&q.mechanism) {
            Ok(k) => k,
            Err(e) => return refuse(e),
        };
        let p = [q.point.x, q.point.y, q.point.z];
        if p.iter().any(|v| !v.is_finite()) {
            return refuse(format!("point ({}, {}, {}) is not finite", p[0], p[1], p[2]));
        }
        // Squares of the coordinates must stay finite (the analysis works with radius²); no
        // manipulator reaches that far anyway.
        const FARTHEST: f64 = 1e100;
        if p.iter().any(|v| v.abs() > FARTHEST) {
            return refuse(format!("point ({:e}, {:e}, {:e}) is out of range: give coordinates of at most {FARTHEST:e} m in magnitude", p[0], p[1], p[2]));
        }
        if !(q.sigma.is_finite() && q.sigma > 0.0) {
            return refuse(format!("sigma must be a positive finite number, got {}", q.sigma));
        }
        let max_boxes = match self.box_limit(q.max_boxes) {
            Ok(n) => n,
            Err(e) => return refuse(e),
        };
        let prepared = match self.mechanisms[k].loaded.analysis.inverse_kinematics(&IkQuery { point: p, precision: q.sigma, max_boxes, timeout: Some(seconds(self.limits.max_wait)), threads: self.settings.threads }) {
            Ok(p) => p,
            Err(e) => return refuse(convert::bounded(&e.to_string(), convert::ECHO_MESSAGE)),
        };
        if let Some(busy) = self.busy() {
            return refuse(busy);
        }
        let run = self.start(k, RunKind::InverseKinematics, Box::new(move |c, p| prepared.run(c, p).map(Outcome::InverseKinematics).map_err(|e| e.to_string())));
        // Bounded by boxes and by the node's longest wait, after which its reply could not be sent.
        let deadline = Instant::now() + seconds(self.limits.max_wait);
        self.runs.get_mut(&run).expect("invariant: just started").waiters.push((id, deadline));
        None
    }
    /// Prepares `job` for mechanism `k` on the event loop (every check that needs no search:
    /// a bad request is answered at once) and starts its run on a thread of its own, bounded by
    /// `limits` and the node's threads; the reply waits at most the node's longest wait.
    fn start_job(&mut self, id: RmwRequestId, k: usize, kind: RunKind, job: crate::app::Job, limits: crate::app::Limits) -> Result<(), String> {
        let prepared = crate::app::prepare(&self.mechanisms[k].loaded.input, job).map_err(|e| e.to_string())?;
        let threads = self.settings.threads.max(1);
        self.launch(
            id,
            k,
            kind,
            Box::new(move |cancel, progress| {
                let control = crate::app::Control { limits, threads, cancel };
                Ok(Outcome::Answer(prepared.run(&control, progress).map_err(|e| e.to_string())))
            }),
        )
    }
    /// Starts `work` for mechanism `k` unless the node is busy, the reply `id` waiting for it at
    /// most the node's longest wait.
    fn launch(&mut self, id: RmwRequestId, k: usize, kind: RunKind, work: Work) -> Result<(), String> {
        if let Some(busy) = self.busy() {
            return Err(busy);
        }
        let run = self.start(k, kind, work);
        let deadline = Instant::now() + seconds(self.limits.max_wait);
        self.runs.get_mut(&run).expect("invariant: just started").waiters.push((id, deadline));
        Ok(())
    }
    /// As `start_job` for several jobs answered in turn on one thread, all within `limits`
    /// counted from the start (a job left without time answers incomplete, naming the limit).
    /// Every job is prepared before the first runs; a refusal names the job as `items[i]`.
    fn start_jobs(&mut self, id: RmwRequestId, k: usize, kind: RunKind, jobs: Vec<crate::app::Job>, limits: crate::app::Limits, items: &str) -> Result<(), String> {
        let input = &self.mechanisms[k].loaded.input;
        let prepared = jobs.into_iter().enumerate().map(|(i, job)| crate::app::prepare(input, job).map_err(|e| format!("{items}[{i}]: {e}"))).collect::<Result<Vec<_>, _>>()?;
        let threads = self.settings.threads.max(1);
        self.launch(
            id,
            k,
            kind,
            Box::new(move |cancel, progress| {
                let start = Instant::now();
                let answers = prepared.into_iter().map(|p| p.run(&crate::app::Control { limits, threads, cancel }.remaining_since(start), progress).map_err(|e| e.to_string())).collect();
                Ok(Outcome::Answers(answers))
            }),
        )
    }
    /// Certified inverse kinematics of a six-revolute arm's tip pose (or of each of `poses`), run
    /// as every search of the node on a thread of its own; `None` when the reply waits for it.
    /// Bounded by the request's boxes and the node's longest wait, and counted against
    /// `--max-runs`.
    fn inverse_kinematics6(&mut self, id: RmwRequestId, q: InverseKinematics6Request) -> Option<InverseKinematics6Response> {
        let refuse = |message: String| Some(InverseKinematics6Response { ok: false, message, ..Default::default() });
        let k = match self.mechanism(&q.mechanism) {
            Ok(k) => k,
            Err(e) => return refuse(e),
        };
        if q.poses.len() > MAX_POSES {
            return refuse(format!("{} poses: at most {MAX_POSES} in one request", q.poses.len()));
        }
        let many = !q.poses.is_empty();
        let mut poses = Vec::with_capacity(q.poses.len().max(1));
        for (i, pose) in if many { q.poses.iter() } else { std::slice::from_ref(&q.pose).iter() }.enumerate() {
            match pose_input(pose) {
                Ok(pose) => poses.push(pose),
                Err(e) if many => return refuse(format!("poses[{i}]: {e}")),
                Err(e) => return refuse(e),
            }
        }
        if !(q.sigma.is_finite() && q.sigma > 0.0 && q.sigma < 1.0) {
            return refuse(format!("sigma must be a number in (0, 1), got {}", q.sigma));
        }
        let max_boxes = match self.box_limit(q.max_boxes) {
            Ok(n) => n,
            Err(e) => return refuse(e),
        };
        let limits = crate::app::Limits { max_cells: max_boxes, timeout: Some(seconds(self.limits.max_wait)), ..Default::default() };
        let job = |pose| crate::app::Job::Ik6(crate::app::Ik6Job { arm: crate::app::LoadOptions::default(), pose, precision: q.sigma });
        let started = if many { self.start_jobs(id, k, RunKind::InverseKinematics6, poses.into_iter().map(job).collect(), limits, "poses") } else { self.start_job(id, k, RunKind::InverseKinematics6, job(poses[0]), limits) };
        started.err().and_then(|e| refuse(format!("inverse_kinematics6: {e}")))
    }

    /// A joint path's singularities, run on a thread of its own as every search of the node,
    /// within the request's timeout (at most the node's longest wait); `None` when the reply
    /// waits for it.
    fn path_check(&mut self, id: RmwRequestId, q: PathCheckRequest) -> Option<PathCheckResponse> {
        let refuse = |message: String| Some(PathCheckResponse { ok: false, message, ..Default::default() });
        let k = match self.mechanism(&q.mechanism) {
            Ok(k) => k,
            Err(e) => return refuse(e),
        };
        let set = match q.singular_set.as_str() {
            "6r" => Some(crate::app::PathSet::Arm6R),
            "3r" => Some(crate::app::PathSet::Positioning3R),
            "" => None,
            other => return refuse(format!("singular_set must be \"6r\", \"3r\" or empty, got \"{}\"", convert::bounded(other, convert::ECHO_NAME))),
        };
        let t = &q.trajectory;
        let mut waypoints: Vec<Vec<f64>> = Vec::with_capacity(t.points.len().min(1 << 16));
        for (k, point) in t.points.iter().enumerate() {
            if point.positions.len() != t.joint_names.len() {
                return refuse(format!("point {k} has {} positions for {} joint names", point.positions.len(), t.joint_names.len()));
            }
            waypoints.push(point.positions.clone());
        }
        let precision = if q.tolerance == 0.0 { crate::app::Job::default_precision("path-check") } else { q.tolerance };
        if !(q.timeout.is_finite() && q.timeout >= 0.0) {
            return refuse(format!("timeout must be a number of seconds >= 0, got {}", q.timeout));
        }
        let timeout = if q.timeout == 0.0 { self.limits.max_wait } else { q.timeout.min(self.limits.max_wait) };
        let limits = crate::app::Limits { timeout: Some(seconds(timeout)), ..crate::app::Job::default_limits("path-check") };
        let job = crate::app::Job::PathCheck(crate::app::PathCheckJob { arm: crate::app::LoadOptions::default(), waypoints, joint_names: t.joint_names.clone(), set, precision });
        let name = convert::bounded(&q.mechanism, convert::ECHO_NAME);
        self.start_job(id, k, RunKind::PathCheck, job, limits).err().and_then(|e| refuse(format!("path_check: '{name}': {e}")))
    }

    /// Where an arm's collision bodies meet, run on a thread of its own as every search of the
    /// node; `None` when the reply waits for it. Bounded by the request's boxes and the node's
    /// longest wait.
    fn collisions(&mut self, id: RmwRequestId, q: CollisionsRequest) -> Option<CollisionsResponse> {
        let refuse = |message: String| Some(CollisionsResponse { ok: false, message, ..Default::default() });
        let k = match self.serving(&q.mechanism, Service::Collisions) {
            Ok(k) => k,
            Err(e) => return refuse(e),
        };
        let precision = if q.precision == 0.0 { crate::app::Job::default_precision("collisions") } else { q.precision };
        let max_boxes = match self.box_limit(q.max_boxes) {
            Ok(n) => n,
            Err(e) => return refuse(e),
        };
        let limits = crate::app::Limits { max_cells: max_boxes, timeout: Some(seconds(self.limits.max_wait)), ..crate::app::Job::default_limits("collisions") };
        let job = crate::app::Job::Collisions(crate::app::CollisionsJob { arm: crate::app::LoadOptions::default(), precision });
        let name = convert::bounded(&q.mechanism, convert::ECHO_NAME);
        self.start_job(id, k, RunKind::Collisions, job, limits).err().and_then(|e| refuse(format!("collisions: '{name}': {e}")))
    }

    /// The self-motion set of a seven-revolute arm at a pose, run on a thread of its own as every
    /// search of the node; `None` when the reply waits for it. Bounded by the request's boxes per
    /// cell and the node's longest wait (cells not started by then are answered undecided).
    fn self_motion(&mut self, id: RmwRequestId, q: SelfMotionRequest) -> Option<SelfMotionResponse> {
        let refuse = |message: String| Some(SelfMotionResponse { ok: false, message, ..Default::default() });
        let k = match self.serving(&q.mechanism, Service::SelfMotion) {
            Ok(k) => k,
            Err(e) => return refuse(e),
        };
        let pose = match pose_input(&q.pose) {
            Ok(pose) => pose,
            Err(e) => return refuse(e),
        };
        let max_boxes = match self.box_limit(q.max_boxes) {
            Ok(n) => n,
            Err(e) => return refuse(e),
        };
        let or = |x: f64, default: f64| if x == 0.0 { default } else { x };
        let range = (q.range_lower != 0.0 || q.range_upper != 0.0).then_some((q.range_lower, q.range_upper));
        let parameter = (!q.parameter.is_empty()).then(|| q.parameter.clone());
        let job = crate::app::SelfMotionJob { arm: crate::app::LoadOptions::default(), pose, parameter, range, cell: or(q.cell, 0.002), precision: or(q.precision, crate::app::Job::default_precision("self-motion")) };
        let limits = crate::app::Limits { max_cells: max_boxes, timeout: Some(seconds(self.limits.max_wait)), ..crate::app::Job::default_limits("self-motion") };
        let name = convert::bounded(&q.mechanism, convert::ECHO_NAME);
        self.start_job(id, k, RunKind::SelfMotion, crate::app::Job::SelfMotion(job), limits).err().and_then(|e| refuse(format!("self_motion: '{name}': {e}")))
    }

    fn classify(&mut self, q: ClassifyRequest) -> ClassifyResponse {
        let refuse = |message: String| ClassifyResponse { ok: false, message, component: -1, ..Default::default() };
        let k = match self.serving(&q.mechanism, Service::Classify) {
            Ok(k) => k,
            Err(e) => return refuse(e),
        };
        let m = &self.mechanisms[k];
        let a = &m.loaded.analysis;
        if q.joint_names.len() != q.joint_values.len() {
            return refuse(format!("{} joint names but {} values", q.joint_names.len(), q.joint_values.len()));
        }
        if let Some((i, name)) = q.joint_names.iter().enumerate().find(|(i, n)| q.joint_names[..*i].contains(n)) {
            return refuse(format!("joint '{}' is given twice (joint_names[{i}])", convert::bounded(name, convert::ECHO_NAME)));
        }
        let free = a.free_joints();
        let mut values = vec![f64::NAN; free.len()];
        for (name, &v) in q.joint_names.iter().zip(&q.joint_values) {
            let Some(i) = free.iter().position(|f| f == name) else {
                return refuse(format!("'{}' is not a free joint of '{}' (free joints: {})", convert::bounded(name, convert::ECHO_NAME), q.mechanism, free.join(", ")));
            };
            if !v.is_finite() {
                return refuse(format!("joint '{name}': {v} is not a finite number"));
            }
            values[i] = v;
        }
        if let Some(i) = values.iter().position(|v| v.is_nan()) {
            return refuse(format!("no value for free joint '{}' (give every free joint: {})", free[i], free.join(", ")));
        }
        let c = match a.classify(&values, m.configuration_space.as_deref(), m.singularities.as_deref()) {
            Ok(c) => c,
            Err(AnalysisError::NotReady { what }) => {
                return refuse(format!("the {} of '{}' is not known yet ({}); retry when {}/{what} is published", what.replace('_', " "), q.mechanism, m.state.name(), m.prefix));
            }
            Err(e) => return refuse(e.to_string()),
        };
        let mut message = match c.component {
            Some(comp) if c.inside => format!("inside component {comp} of {}", c.components),
            Some(comp) => format!("outside every box; nearest is component {comp} of {} at distance {:.6}", c.components, c.distance),
            None if c.inside => format!("in no component of {}", c.components),
            None => "the configuration space is empty".to_string(),
        };
        match c.singular_distance {
            // The note says why when the analysis has singularities but no bound yet.
            None if a.services().contains(&Service::Singularities) => message.push_str("; distance to singularities unknown"),
            None => message.push_str(&format!("; distance to singularities unknown: {}", a.not_available(Service::Singularities))),
            Some(d) if d.is_infinite() => message.push_str("; no singular configuration"),
            Some(d) => message.push_str(&format!("; at least {d:.6} from every singular configuration")),
        }
        if !c.note.is_empty() {
            message.push_str(&format!(" ({})", c.note));
        }
        if m.configuration_space.as_ref().is_some_and(|cs| cs.status != Status::Finished) {
            message.push_str("; the configuration space is incomplete (undecided boxes are not classified)");
        }
        ClassifyResponse {
            ok: true,
            message,
            inside: c.inside,
            component: c.component.map_or(-1, |x| x as i32),
            components: c.components as u32,
            distance: c.distance,
            singular_distance_known: c.singular_distance.is_some(),
            singular_distance: c.singular_distance.unwrap_or(f64::NAN),
        }
    }

    fn list(&self) -> ListMechanismsResponse {
        ListMechanismsResponse {
            mechanisms: self
                .mechanisms
                .iter()
                .map(|m| {
                    let a = &m.loaded.analysis;
                    let fixed = a.fixed_joints();
                    MechanismInfo {
                        name: a.mechanism().to_string(),
                        kind: a.kind().name().to_string(),
                        services: a.services().iter().map(|s| s.name().to_string()).collect(),
                        free_joints: a.free_joints(),
                        fixed_joint_names: fixed.iter().map(|(n, _)| n.clone()).collect(),
                        fixed_joint_values: fixed.iter().map(|(_, v)| *v).collect(),
                        state: m.state.name().to_string(),
                        message: if m.message.is_empty() && a.services().is_empty() { a.limitation() } else { m.message.clone() },
                        topic_prefix: m.prefix.clone(),
                    }
                })
                .collect(),
        }
    }
}

/// A request's pose as the front door takes it (the quaternion normalised, zero refused).
fn pose_input(pose: &Pose) -> Result<crate::app::PoseInput, String> {
    let (p, o) = (&pose.position, &pose.orientation);
    crate::app::PoseInput::from_numbers(&[p.x, p.y, p.z, o.x, o.y, o.z, o.w]).map_err(|e| e.to_string())
}

//! The Solve action (`~/solve`, `linkspace_msgs/action/Solve`): its server, the tasks that
//! forward its goals and cancel requests into the event channel, and their handling.
//!
//! A goal runs as a Solve request would (`State::solve_job` checks it), with its progress as
//! feedback; `runs` ends it with the run's result. Results are sent off the event loop, so a
//! client that never asks for one cannot hold the loop up.

use super::publish::latched;
use super::runs::RunKind;
use super::setup::service_qos;
use super::{panic_text, Event};
use crate::edges::ros::msgs::{SolveActionResult, SolveFeedback, SolveGoal, SolveRequest};
use anyhow::{Context as _, Result};
use ros2_client::action::{ActionServerQosPolicies, AsyncActionServer, CancelHandle, ExecutingGoalHandle, GoalEndStatus, GoalError, NewGoalHandle};
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{ActionTypeName, Name, Node, QosProfile, ServiceMapping};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Duration;

/// The Solve action server (`~/solve`, `linkspace_msgs/action/Solve`).
pub(super) type SolveAction = AsyncActionServer<SolveGoal, SolveActionResult, SolveFeedback>;

/// Creates the Solve action server under `base`, its services as deep as the node's services.
pub(super) fn action_server(node: &mut Node, mapping: ServiceMapping, base: &str) -> Result<Arc<SolveAction>> {
    let action_qos = ActionServerQosPolicies {
        goal_service: service_qos(),
        result_service: service_qos(),
        cancel_service: service_qos(),
        feedback_publisher: QosProfile::publisher_default().reliability_reliable(WhenFull::Wait(Duration::from_secs(1))).durability(Durability::Volatile).history(History::KeepLast { depth: 16 }),
        status_publisher: latched(1),
    };
    let action_name = Name::new(base, "solve").context("action name solve")?;
    Ok(Arc::new(AsyncActionServer::new(
        node.create_action_server::<SolveGoal, SolveActionResult, SolveFeedback>(mapping, &action_name, &ActionTypeName::new("linkspace_msgs", "Solve"), action_qos).context("creating the Solve action")?,
    )))
}

/// Forwards every new goal and every cancel request of `action` into the event channel.
pub(super) fn forward_goals(ex: &smol::LocalExecutor<'_>, action: &Arc<SolveAction>, tx: &smol::channel::Sender<Event>) {
    let (goals, events) = (action.clone(), tx.clone());
    ex.spawn(async move {
        loop {
            match goals.receive_new_goal().await {
                Ok(h) => {
                    if events.send(Event::Goal(h)).await.is_err() {
                        break;
                    }
                }
                Err(e) => say!("linkspace: dropped an undecodable Solve goal: {e:?}"),
            }
        }
    })
    .detach();
    let (cancels, events) = (action.clone(), tx.clone());
    ex.spawn(async move {
        loop {
            match cancels.receive_cancel_request().await {
                Ok(c) => {
                    if events.send(Event::GoalCancel(c)).await.is_err() {
                        break;
                    }
                }
                Err(e) => say!("linkspace: dropped an undecodable Solve cancel request: {e:?}"),
            }
        }
    })
    .detach();
}

impl super::State {
    /// A goal of the Solve action: accepted and executed at once; a goal the Solve service
    /// would refuse ends ABORTED with the reason in its result (a rejected goal carries none).
    pub(super) async fn goal(&mut self, h: NewGoalHandle<SolveGoal>) {
        let Some(goal) = self.action.get_new_goal(h.clone()) else { return };
        let q = SolveRequest { mechanism: goal.mechanism, fixed_joint_names: goal.fixed_joint_names, fixed_joint_values: goal.fixed_joint_values, settings: goal.settings, wait: 0.0 };
        let prepared = catch_unwind(AssertUnwindSafe(|| self.solve_job(&q))).unwrap_or_else(|p| Err(format!("internal error while handling the goal: {}", panic_text(p.as_ref()))));
        let executing = match self.action.accept_goal(h).await {
            Ok(accepted) => self.action.start_executing_goal(accepted).await,
            Err(e) => Err(e),
        };
        let executing = match executing {
            Ok(x) => x,
            Err(e) => return say!("linkspace: a Solve goal could not be started: {e:?}"),
        };
        match prepared {
            Err(message) => self.goal_result(executing, GoalEndStatus::Aborted, SolveActionResult { ok: false, message, ..Default::default() }),
            Ok((k, job)) => {
                let run = self.start(k, RunKind::SolveAction, job);
                self.runs.get_mut(&run).expect("invariant: just started").goal = Some(executing);
            }
        }
    }

    /// Sends a goal's result when its client asks for it (on smol's global executor, so the
    /// loop does not wait for the client); a client that never asks is given up after 60 s.
    pub(super) fn goal_result(&self, h: ExecutingGoalHandle<SolveGoal>, end: GoalEndStatus, result: SolveActionResult) {
        let action = self.action.clone();
        smol::spawn(async move {
            let send = action.send_result_response(h, end, result);
            let give_up = async {
                smol::Timer::after(Duration::from_secs(60)).await;
                Err(GoalError::NoSuchGoal)
            };
            if let Err(e) = futures::future::select(Box::pin(send), Box::pin(give_up)).await.factor_first().0 {
                say!("linkspace: sending a Solve action result: {e:?}");
            }
        })
        .detach();
    }

    /// A cancel request of the Solve action: the runs of the goals it names are cancelled
    /// (their incomplete results end the goals as CANCELED).
    pub(super) async fn goal_cancel(&mut self, c: CancelHandle) {
        let mut cancelling = Vec::new();
        for r in self.runs.values() {
            if let Some(h) = &r.goal {
                if c.contains_goal(&h.goal_id()) {
                    r.cancel.store(true, Ordering::Relaxed);
                    cancelling.push(h.goal_id());
                }
            }
        }
        if let Err(e) = self.action.respond_to_cancel_requests(&c, cancelling.into_iter()).await {
            say!("linkspace: answering a Solve action cancel: {e:?}");
        }
    }
}

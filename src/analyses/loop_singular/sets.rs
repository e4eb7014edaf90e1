//! Several singular sets of one linkage built together and solved within one timeout: what
//! `loop-singularities` asks for its sets, the node's load-time run, and the input-motion
//! check's search of turning points.

use super::SingularSet;
use crate::formulate::singular::velocity::point_label;
use crate::formulate::singular::{Output, SingularError, SingularKind, SingularProblem};
use crate::formulate::{Linkage, Model, ModelChoice};
use crate::kernel::search::{SolveError, SolverSettings};
use crate::model::Mechanism;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// The built problems of several singular sets of one linkage, in the order asked.
#[derive(Clone, Debug)]
pub struct SingularSets {
    /// One per kind.
    pub problems: Vec<SingularProblem<Linkage>>,
    /// The builder every set was built with.
    pub model: Model,
    /// Why the spatial model was chosen; empty for planar linkages.
    pub model_reason: String,
}

impl SingularSets {
    /// Builds the problem of every kind of `kinds` for `m` with joints `fixed`, on the model
    /// `solve --model auto` picks among the joint-coordinate models (`Linkage::build_in_joints`; see `SingularProblem::with_linkage`); the
    /// first that does not build is the error. A point output is traced in the output set's
    /// linkage only, as `SingularProblem::new` does.
    pub fn new(m: &Mechanism, fixed: &[(String, f64)], kinds: &[SingularKind], actuated: &[String], output: Option<Output>) -> Result<Self, SingularError> {
        let build = |kind: SingularKind| -> Result<SingularProblem<Linkage>, SingularError> {
            let traces = match (&output, kind) {
                (Some(Output::Point { link, x, y }), SingularKind::Output) => vec![(link.clone(), [*x, *y, 0.0], point_label(link, *x, *y))],
                _ => Vec::new(),
            };
            let linkage = Linkage::build_in_joints(m, ModelChoice::Auto, fixed, &traces)?;
            SingularProblem::with_linkage(linkage, kind, actuated, output.clone())
        };
        let problems: Vec<SingularProblem<Linkage>> = kinds.iter().map(|&k| build(k)).collect::<Result<_, _>>()?;
        let (model, model_reason) = match problems.first().map(|p| &p.linkage) {
            Some(Linkage::Spatial(_, why)) => (Model::Spatial, why.clone()),
            _ => (Model::Planar, String::new()),
        };
        Ok(Self { problems, model, model_reason })
    }

    /// Solves every set in order. `settings.max_boxes` applies per chart of each set;
    /// `settings.timeout` to the whole call (a set that starts with no time left reports one
    /// undecided box holding all its charts, so nothing is dropped unsearched). Raising `cancel`
    /// ends every set.
    pub fn solve(&self, settings: &SolverSettings, cancel: &AtomicBool) -> Result<Vec<SingularSet>, SolveError> {
        let t0 = Instant::now();
        self.problems
            .iter()
            .map(|p| {
                let remaining = settings.timeout.map(|t| t.saturating_sub(t0.elapsed()));
                p.solve(&SolverSettings { timeout: remaining, ..settings.clone() }, cancel)
            })
            .collect()
    }
}

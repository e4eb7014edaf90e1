//! A pose the closed form answered in part (`closed_form::Partly`): its certified candidates
//! kept, the search run on the boxes about the candidates it could not certify (near an elbow
//! or wrist singularity, or a copy meeting a joint limit), each box alone, and its boxes about
//! an elbow's double root kept undecided.
//!
//! Why this is complete: every solution within the ranges lies in a certified box or in a box
//! to search (the closed form's enclosures, `closed_form` module doc), and the search finds
//! every solution in the box it is given. A certified box that also lies in a searched box is
//! found twice and claimed once (`answer`: a box inside the other's proof region). Two boxes
//! left overlapping without that proof leave the count unproven: the caller then searches the
//! whole pose.

use super::boxes::overlapping;
use super::closed_form::{Degeneracy, Partly};
use super::answer::{answer, Searched};
use super::{search_within, Ik6Curve, Ik6Method, Ik6Solutions, PoseTarget, INFLATE_WIDTH};
use crate::analyses::arm6r::chain::Chain6R;
use crate::kernel::search::{Control, Progress, Stats, Status};

/// The answer from `partly` and a search of each of its boxes within `control` (the cells'
/// budget shared by the searches); `Overlap` when two boxes of the answer overlap.
pub(super) fn finish(chain: &Chain6R, target: &PoseTarget, precision: f64, partly: Partly, control: &Control, progress: &mut dyn FnMut(&Progress)) -> Result<Ik6Solutions, Degeneracy> {
    let start = std::time::Instant::now();
    let n = partly.certified.len() as u64;
    let processed = n + partly.undecided.len() as u64;
    let mut all = Searched { found: partly.certified, undecided: partly.undecided, status: Status::Finished, stats: Stats { processed, found: n, ..Stats::default() } };
    // Nothing searched: the closed form answered alone, its undecided boxes at double roots.
    let method = if partly.search.is_empty() { Ik6Method::ClosedForm } else { Ik6Method::ClosedFormAndSearch(partly.why) };
    for b in partly.search {
        let left = control.limits.max_cells.saturating_sub(all.stats.processed);
        let run = search_within(chain, target, precision, INFLATE_WIDTH, b, &control.remaining_since(start).max_cells(left), progress);
        all.found.extend(run.found);
        all.undecided.extend(run.undecided);
        all.status = all.status.and(run.status);
        all.stats.add(&run.stats);
    }
    all.stats.seconds = start.elapsed().as_secs_f64();
    let mut found = answer(chain, all, method);
    if overlapping(found.unique.iter()) {
        return Err(Degeneracy::Overlap);
    }
    found.curves = Ik6Curve::all(partly.curves);
    Ok(found)
}

//! Test idea: what runs after branch and prune (the spurious-box check, clustering, the report)
//! keeps the run's limits. No clock is read here: the properties are that a
//! deadline already passed does no work and says so, and that nothing is dropped unexamined.

use crate::util::problem;
use linkspace::kernel::interval::interval;
use linkspace::kernel::search::SolverSettings;
use linkspace::kernel::interval::IntervalBox;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

/// Two lone boxes of sigma's width where the fixed-crank four-bar has no assembly: the
/// spurious check proves them empty when it has time.
fn lone_misses(p: &linkspace::formulate::LinkageProblem, sigma: f64) -> Vec<IntervalBox> {
    let primaries = p.system.primaries();
    let start = p.system.initial_box();
    [0.1, 0.9]
        .iter()
        .map(|&t| {
            let mut b = start.clone();
            for &v in &primaries {
                // A point inside the initial box, away from every assembly (cos and sin of one
                // angle cannot both be 0.1 or both 0.9: the circle equation fails).
                let x = start.dims[v].inf() + t * start.dims[v].wid();
                b.dims[v] = interval(x, x + 0.5 * sigma);
            }
            b
        })
        .collect()
}

#[test]
fn spurious_check_with_a_passed_deadline_keeps_every_box_and_says_so() {
    let p = problem("four_bar.urdf", &[("crank_joint", 0.5)], &[]);
    let sigma = 1e-3;
    let solver = p.solver(SolverSettings { sigma, ..Default::default() }).expect("valid");
    let boxes = lone_misses(&p, sigma);
    let cancel = AtomicBool::new(false);

    // With time, both lone boxes are proven empty and dropped: the check has work to skip.
    let (kept, _, dropped, cut_short) = solver.drop_spurious(boxes.clone(), vec![linkspace::app::BoxStatus::Solution; 2], 2, &cancel, None);
    assert_eq!((kept.len(), dropped, cut_short), (0, 2, false));
    let later = Instant::now() + Duration::from_secs(3600);
    let (kept, _, dropped, cut_short) = solver.drop_spurious(boxes.clone(), vec![linkspace::app::BoxStatus::Solution; 2], 2, &cancel, Some(later));
    assert_eq!((kept.len(), dropped, cut_short), (0, 2, false));

    // Past the deadline: nothing is searched, nothing is dropped, and the result says so.
    let passed = Instant::now();
    let (kept, unique, dropped, cut_short) = solver.drop_spurious(boxes.clone(), vec![linkspace::app::BoxStatus::Solution; 2], 2, &cancel, Some(passed));
    assert_eq!(kept, boxes);
    assert_eq!((unique, dropped, cut_short), (vec![linkspace::app::BoxStatus::Solution, linkspace::app::BoxStatus::Solution], 0, true));

    // Cancelled: the same.
    let (kept, _, dropped, cut_short) = solver.drop_spurious(boxes.clone(), vec![linkspace::app::BoxStatus::Solution; 2], 2, &AtomicBool::new(true), None);
    assert_eq!((kept.len(), dropped, cut_short), (2, 0, true));

    // Nothing to examine is not cut short, deadline or not.
    let (kept, _, dropped, cut_short) = solver.drop_spurious(Vec::new(), Vec::new(), 2, &cancel, Some(passed));
    assert_eq!((kept.len(), dropped, cut_short), (0, 0, false));
}

/// Reading boxes out (their joint values, an angle enclosure per joint) is inside the run's
/// deadline too: a run whose deadline has passed, or that is cancelled, when its boxes are read
/// out reports every box (bounds and status) with its joints unread (NaN), and names the limit.
#[test]
fn read_outs_past_the_deadline_keep_every_box_and_name_the_limit() {
    use linkspace::app::{BoxStatus, Limit, ModelChoice, SolveRun, Status};
    let m = linkspace::model::urdf::parse(&crate::util::urdf_text("four_bar.urdf")).expect("fixture");
    let run = |timeout: Option<Duration>, cancel: bool| {
        let settings = SolverSettings { sigma: 0.05, timeout, ..Default::default() };
        SolveRun::build(&m, ModelChoice::Auto, &[], &[], settings).expect("builds").run(&AtomicBool::new(cancel), &mut |_| {})
    };
    let read = run(None, false);
    assert!(read.status.finished() && !read.boxes.is_empty());
    assert!(read.boxes.iter().all(|b| b.joints.iter().all(|j| j[0].is_finite() && j[1].is_finite())), "with time every box is read out");
    for (timeout, cancel, limit) in [(Some(Duration::ZERO), false, Limit::Time), (None, true, Limit::Cancelled)] {
        let cut = run(timeout, cancel);
        assert_eq!(cut.status, Status::Stopped(limit));
        assert!(cut.stats.post_processing_cut_short);
        // The search stopped at once: its start box, undecided and unread, stands for the rest.
        assert_eq!(cut.boxes.len(), 1);
        assert_eq!(cut.boxes[0].status, BoxStatus::Undecided);
        assert!(cut.boxes[0].joints.iter().all(|j| j[0].is_nan() && j[1].is_nan()), "{:?}", cut.boxes[0].joints);
    }
}

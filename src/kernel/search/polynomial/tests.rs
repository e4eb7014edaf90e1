//! Unit tests of the polynomial search: isolated roots found and certified, certificates of
//! one root merged, refinement, limits and cancellation.

use super::*;
use crate::kernel::interval::{interval, point};
use crate::kernel::system::{Equation, Monomial, Term, VarRole};

/// x² + y² = 1, x = y: two solutions at ±(1/√2, 1/√2).
fn two_points() -> EquationSystem {
    let mut s = EquationSystem::default();
    let x = s.add_var("x", VarRole::Primary, interval(-1.0, 1.0));
    let y = s.add_var("y", VarRole::Primary, interval(-1.0, 1.0));
    s.add(Equation::circle(x, y));
    s.add(Equation::new(
        vec![Term { coef: point(1.0), mono: Monomial::Linear(x) }, Term { coef: point(-1.0), mono: Monomial::Linear(y) }],
        point(0.0),
    ));
    s
}

#[test]
fn two_certificates_of_one_root_count_once() {
    // Roots (h, h) and (−h, −h), h = 1/√2. Two certified boxes around (h, h) that overlap are
    // merged into one inside both; two overlapping certified boxes each holding one root stay
    // two; a certified box disjoint from the rest is left as it is.
    let s = two_points();
    let solver = Solver::new(&s, SolverSettings { sigma: 1e-6, ..Default::default() }).expect("valid");
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let square = |lo: f64, hi: f64| IntervalBox::new(vec![interval(lo, hi), interval(lo, hi)]);
    let around_h = [square(h - 1e-3, h + 2e-3), square(h - 2e-3, h + 1e-3)];
    let (boxes, tags, merged) = solver.merge_shared_certificates(around_h.to_vec(), vec![BoxStatus::Unique, BoxStatus::Unique]);
    assert_eq!((boxes.len(), merged), (1, 1), "{boxes:?}");
    assert!(tags[0] == BoxStatus::Unique && boxes[0].contains(&[h, h]));
    assert!(boxes[0].dims.iter().all(|d| d.subset(interval(h - 1e-3, h + 1e-3))), "{boxes:?}");

    let both_roots = [square(-0.8, 0.1), square(-0.1, 0.8)];
    let (boxes, tags, merged) = solver.merge_shared_certificates(both_roots.to_vec(), vec![BoxStatus::Unique, BoxStatus::Unique]);
    assert_eq!((boxes.len(), merged, tags), (2, 0, vec![BoxStatus::Unique, BoxStatus::Unique]));

    let apart = [square(h - 1e-3, h + 1e-3), square(-h - 1e-3, -h + 1e-3)];
    let (boxes, _, merged) = solver.merge_shared_certificates(apart.to_vec(), vec![BoxStatus::Unique, BoxStatus::Unique]);
    assert_eq!((boxes, merged), (apart.to_vec(), 0));
    // An uncertified box is never merged or dropped: it only encloses.
    let (boxes, tags, merged) = solver.merge_shared_certificates(around_h.to_vec(), vec![BoxStatus::Unique, BoxStatus::Solution]);
    assert_eq!((boxes.len(), tags, merged), (2, vec![BoxStatus::Unique, BoxStatus::Solution], 0));
}

#[test]
fn refining_proves_a_root_a_coarse_sigma_leaves_unproven() {
    // x² − y² = 0, x² + y² = 1 on [0, 1]²: one root at (1/√2, 1/√2). Propagation cannot
    // narrow the whole box (in x² and y² the system is linear, [0, 1]² a fixed point of
    // HC4), so at sigma 1 it is one solution box, where the Jacobian's range holds singular
    // matrices and Krawczyk proves nothing.
    let mut s = EquationSystem::default();
    let x = s.add_var("x", VarRole::Primary, interval(0.0, 1.0));
    let y = s.add_var("y", VarRole::Primary, interval(0.0, 1.0));
    let sq = |v, c| Term { coef: point(c), mono: Monomial::Square(v) };
    s.add(Equation::new(vec![sq(x, 1.0), sq(y, -1.0)], point(0.0)));
    s.add(Equation::new(vec![sq(x, 1.0), sq(y, 1.0)], point(-1.0)));
    let cancel = AtomicBool::new(false);
    let coarse = Solver::new(&s, SolverSettings { sigma: 1.0, use_lp: false, ..Default::default() }).expect("valid");
    let mut out = Collect::default();
    assert_eq!(coarse.run(&cancel, &mut out).0, Status::Finished);
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let cluster = out.solutions.clone();
    assert!(cluster.iter().any(|b| b.contains(&[h, h])), "{cluster:?} {:?}", out.tags);
    assert!(out.tags.iter().all(|t| *t != BoxStatus::Unique), "{:?}", out.tags);
    let all_certified = |_: &[IntervalBox], t: &[BoxStatus]| t.iter().all(|t| *t == BoxStatus::Unique);
    match coarse.refine(&cluster, &RefinePlan::default(), None, &all_certified, &cancel) {
        Refinement::Settled(c) => {
            assert!(!c.solutions.is_empty() && c.tags.iter().all(|t| *t == BoxStatus::Unique));
            assert!(c.solutions.iter().any(|b| b.contains(&[h, h])));
        }
        other => panic!("not settled: {other:?}"),
    }
    // A cluster wider than the plan allows is not tried; a round stopped by its budget
    // says so, and settles nothing.
    let narrow = RefinePlan { max_width: 0.1, ..RefinePlan::default() };
    assert!(matches!(coarse.refine(&cluster, &narrow, None, &all_certified, &cancel), Refinement::TooWide));
    let starved = RefinePlan { max_boxes: 1, ..RefinePlan::default() };
    match coarse.refine(&cluster, &starved, None, &all_certified, &cancel) {
        Refinement::Unsettled(why) => assert!(why.contains("boxes limit"), "{why}"),
        other => panic!("settled on one box: {other:?}"),
    }
}

#[test]
fn finds_both_isolated_solutions() {
    let s = two_points();
    let solver = Solver::new(&s, SolverSettings { sigma: 1e-6, ..Default::default() }).expect("valid");
    let mut out = Collect::default();
    let (status, stats) = solver.run(&AtomicBool::new(false), &mut out);
    assert_eq!(status, Status::Finished);
    let h = std::f64::consts::FRAC_1_SQRT_2;
    assert!(out.solutions.iter().any(|b| b.contains(&[h, h])));
    assert!(out.solutions.iter().any(|b| b.contains(&[-h, -h])));
    assert!(out.solutions.iter().all(|b| b.width(0) <= 1e-6 && b.width(1) <= 1e-6));
    assert_eq!(stats.solutions as usize, out.solutions.len());
}

#[test]
fn a_limit_reports_every_pending_box() {
    let s = two_points();
    let solver = Solver::new(&s, SolverSettings { sigma: 1e-9, max_boxes: 2, ..Default::default() }).expect("valid");
    let mut out = Collect::default();
    let (status, _) = solver.run(&AtomicBool::new(false), &mut out);
    assert_eq!(status, Status::Stopped(Limit::Boxes));
    let h = std::f64::consts::FRAC_1_SQRT_2;
    for p in [[h, h], [-h, -h]] {
        assert!(out.solutions.iter().chain(&out.undecided).any(|b| b.contains(&p)), "lost {p:?}");
    }
}

#[test]
fn cancellation_stops_at_once() {
    let s = two_points();
    let solver = Solver::new(&s, SolverSettings::default()).expect("valid");
    let mut out = Collect::default();
    let (status, stats) = solver.run(&AtomicBool::new(true), &mut out);
    assert_eq!(status, Status::Stopped(Limit::Cancelled));
    assert_eq!(stats.processed, 0);
    assert_eq!(out.undecided.len(), 1);
}

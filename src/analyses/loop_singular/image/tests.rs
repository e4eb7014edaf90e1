//! Unit tests of the image searches' records.

use super::*;
use crate::kernel::interval::interval;

fn point_of(boxes: &[(f64, f64)], kinds: &[BoxStatus], degenerate: bool) -> FoundPoint {
    let boxes = boxes.iter().map(|&(a, b)| IntervalBox::new(vec![interval(a, b)])).collect();
    FoundPoint { boxes, kinds: kinds.to_vec(), degenerate, ..Default::default() }
}

#[test]
fn an_unproven_cusp_says_why() {
    let reason = |p: &FoundPoint, s: Status| p.unproven_reason(s).unwrap_or_default();
    let proven = point_of(&[(0.0, 1.0), (0.5, 2.0)], &[BoxStatus::Unique; 2], false);
    assert_eq!(proven.unproven_reason(Status::Finished), None);
    let cut = point_of(&[(0.0, 1.0)], &[BoxStatus::Undecided], false);
    assert!(reason(&cut, Status::Stopped(Limit::Time)).contains("its time limit"), "{}", reason(&cut, Status::Stopped(Limit::Time)));
    let flat = point_of(&[(0.0, 1.0)], &[BoxStatus::Unique], true);
    assert!(reason(&flat, Status::Finished).contains("μ may vanish"));
    let open = point_of(&[(0.0, 1.0), (1.0, 2.0)], &[BoxStatus::Unique, BoxStatus::Solution], false);
    assert!(reason(&open, Status::Finished).starts_with("1 of its 2 boxes"), "{}", reason(&open, Status::Finished));
    let two = point_of(&[(0.0, 1.0), (1.5, 2.0)], &[BoxStatus::Unique; 2], false);
    assert!(reason(&two, Status::Finished).contains("possibly more than one cusp"));
}

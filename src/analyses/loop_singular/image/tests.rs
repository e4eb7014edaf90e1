//! Unit tests of the image searches' records.

use super::*;
use crate::kernel::interval::interval;

fn point_of(boxes: &[(f64, f64)], kinds: &[BoxKind], degenerate: bool) -> FoundPoint {
    let boxes = boxes.iter().map(|&(a, b)| IntervalBox::new(vec![interval(a, b)])).collect();
    FoundPoint { boxes, kinds: kinds.to_vec(), degenerate, ..Default::default() }
}

#[test]
fn an_unproven_cusp_says_why() {
    let reason = |p: &FoundPoint, s: Status| p.unproven_reason(s).unwrap_or_default();
    let proven = point_of(&[(0.0, 1.0), (0.5, 2.0)], &[BoxKind::Certified; 2], false);
    assert_eq!(proven.unproven_reason(Status::Complete), None);
    let cut = point_of(&[(0.0, 1.0)], &[BoxKind::Undecided], false);
    assert!(reason(&cut, Status::Incomplete(Limit::Time)).contains("its time limit"), "{}", reason(&cut, Status::Incomplete(Limit::Time)));
    let flat = point_of(&[(0.0, 1.0)], &[BoxKind::Certified], true);
    assert!(reason(&flat, Status::Complete).contains("μ may vanish"));
    let open = point_of(&[(0.0, 1.0), (1.0, 2.0)], &[BoxKind::Certified, BoxKind::Solution], false);
    assert!(reason(&open, Status::Complete).starts_with("1 of its 2 boxes"), "{}", reason(&open, Status::Complete));
    let two = point_of(&[(0.0, 1.0), (1.5, 2.0)], &[BoxKind::Certified; 2], false);
    assert!(reason(&two, Status::Complete).contains("possibly more than one cusp"));
}

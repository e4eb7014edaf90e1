//! Unit tests of the node search: the tree's condition search against plain recursion, its
//! limits, and the size of a tree box.

use super::*;
use std::sync::atomic::AtomicBool;

/// The plain recursion `everywhere` runs on the kernel, counting the tests made.
fn recursive(b: [Interval; 2], depth: u32, test: &mut impl FnMut(&[Interval; 2]) -> bool) -> bool {
    if test(&b) {
        return true;
    }
    if depth == 0 {
        return false;
    }
    let (lo, hi) = cusps::bisect(b, false);
    recursive(lo, depth - 1, test) && recursive(hi, depth - 1, test)
}

#[test]
fn everywhere_decides_as_the_recursion_with_the_same_tests() {
    let full = [motion::full_range(), motion::full_range()];
    let tests: [fn(&[Interval; 2]) -> bool; 4] = [
        |b| b[0].wid() < 0.5 && b[1].wid() < 0.5,
        |b| !(b[0].contains(1.0) && b[1].contains(-2.0)),
        |b| b[0].sup() < 2.0 || b[1].inf() > 0.0 || b[0].wid() < 1e-3,
        |_| false,
    ];
    let control = Control::with_limits(Limits::default());
    for (i, test) in tests.iter().enumerate() {
        let (mut by_kernel, mut by_recursion) = (Vec::new(), Vec::new());
        let got = everywhere(full, &control, Instant::now(), |b| {
            by_kernel.push(*b);
            test(b)
        });
        let want = recursive(full, DEPTH, &mut |b| {
            by_recursion.push(*b);
            test(b)
        });
        assert_eq!(got, Ok(want), "test {i}");
        assert_eq!(by_kernel, by_recursion, "test {i}");
    }
}

#[test]
fn everywhere_stops_on_the_runs_limits() {
    let full = [motion::full_range(), motion::full_range()];
    let cancel = AtomicBool::new(true);
    let cancelled = Control { cancel: &cancel, ..Control::with_limits(Limits::default()) };
    assert_eq!(everywhere(full, &cancelled, Instant::now(), |_| true), Err(Limit::Cancelled));
    let late = Control::with_limits(Limits { timeout: Some(std::time::Duration::ZERO), ..Limits::default() });
    assert_eq!(everywhere(full, &late, Instant::now(), |_| true), Err(Limit::Time));
}

/// The tree's box count is capped by the memory limit over this size; README's figures for
/// flooding arms rest on it.
#[test]
fn a_tree_box_is_under_400_bytes() {
    assert!(std::mem::size_of::<super::TreeBox>() < 400, "{}", std::mem::size_of::<super::TreeBox>());
}

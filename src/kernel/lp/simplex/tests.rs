//! The simplex against clarabel and against points known feasible.

use super::*;
use crate::kernel::lp::{clarabel_lp, Row};
use proptest::prelude::*;

fn segment() -> Relaxation {
    // x + y = 1, x − y ∈ [0, 0.5]: on [0,1]², x ∈ [0.5, 0.75], y ∈ [0.25, 0.5].
    Relaxation {
        n: 2,
        rows: vec![
            Row { coefs: vec![(0, 1.0), (1, 1.0)], bounds: interval(1.0, 1.0), sides: Sides::Equal },
            Row { coefs: vec![(0, 1.0), (1, -1.0)], bounds: interval(0.0, 0.5), sides: Sides::Both },
        ],
    }
}

#[test]
fn one_sided_rows_and_fixed_variables() {
    // x + y ≤ 1 (Upper; the row's lower end 0.5 is not enforced), z = 0.25 fixed,
    // x − z ≥ 0 (Lower): x ∈ [0.25, 1], y ∈ [0, 0.75] on [0,1]³.
    let rel = Relaxation {
        n: 3,
        rows: vec![
            Row { coefs: vec![(0, 1.0), (1, 1.0)], bounds: interval(0.5, 1.0), sides: Sides::Upper },
            Row { coefs: vec![(0, 1.0), (2, -1.0)], bounds: interval(0.0, 1.0), sides: Sides::Lower },
        ],
    };
    let b = [interval(0.0, 1.0), interval(0.0, 1.0), interval(0.25, 0.25)];
    let mut c = LpCounters::default();
    let LpOutcome::Bounds(v) = bound(&rel, &b, &[0, 1, 2], &mut c, &|| false) else { panic!("feasible") };
    assert!((v[0].inf() - 0.25).abs() < 1e-12 && v[0].sup() == 1.0, "{v:?}");
    assert!(v[1].inf() == 0.0 && (v[1].sup() - 0.75).abs() < 1e-12, "{v:?}");
    assert_eq!(v[2], interval(0.25, 0.25));
    assert_eq!(c.unverified, 0);
}

#[test]
fn no_rows_and_empty_boxes() {
    let rel = Relaxation { n: 2, rows: vec![] };
    let b = [interval(-1.0, 2.0), interval(3.0, 4.0)];
    let mut c = LpCounters::default();
    assert_eq!(bound(&rel, &b, &[1, 0], &mut c, &|| false), LpOutcome::Bounds(vec![b[1], b[0]]));
    assert_eq!(bound(&segment(), &[Interval::EMPTY, b[0]], &[0], &mut c, &|| false), LpOutcome::Infeasible);
}

/// Dyadic numbers `k / 2^s`: sums of their products stay exact in `f64`, so `x0` satisfies
/// the equality rows built from it exactly.
fn dyadic(range: i32, s: i32) -> impl Strategy<Value = f64> {
    (-range..=range).prop_map(move |k| f64::from(k) / f64::from(1 << s))
}

#[derive(Debug, Clone)]
struct Case {
    lo: Vec<f64>,
    width: Vec<f64>,
    frac: Vec<f64>,
    eq: Vec<Vec<f64>>,
    ineq: Vec<(Vec<f64>, f64, f64, u8)>,
}

fn case() -> impl Strategy<Value = Case> {
    let n = 6;
    (
        prop::collection::vec(dyadic(128, 6), n),
        prop::collection::vec(prop_oneof![1 => Just(0.0), 6 => (1..=192i32).prop_map(|k| f64::from(k) / 64.0)], n),
        prop::collection::vec((0..=64i32).prop_map(|k| f64::from(k) / 64.0), n),
        prop::collection::vec(prop::collection::vec(dyadic(16, 3), n), 3),
        prop::collection::vec(
            (
                prop::collection::vec(dyadic(16, 3), n),
                (0..=64i32).prop_map(|k| f64::from(k) / 32.0),
                (0..=64i32).prop_map(|k| f64::from(k) / 32.0),
                0u8..4,
            ),
            0..6,
        ),
    )
        .prop_map(|(lo, width, frac, eq, ineq)| Case { lo, width, frac, eq, ineq })
}

fn dot(a: &[f64], x: &[f64]) -> f64 {
    a.iter().zip(x).map(|(a, x)| a * x).sum()
}

fn coefs(a: &[f64]) -> Vec<(usize, f64)> {
    a.iter().copied().enumerate().filter(|&(_, v)| v != 0.0).collect()
}

/// The box, the point `x0` and the rows, the inequality rows' ends shifted by `shift`
/// (negative shifts may cut `x0` off).
fn build(c: &Case, shift: f64) -> (Vec<Interval>, Vec<f64>, Relaxation) {
    let b: Vec<Interval> = c.lo.iter().zip(&c.width).map(|(&l, &w)| interval(l, l + w)).collect();
    let x0: Vec<f64> = b.iter().zip(&c.frac).map(|(x, &f)| x.inf() + f * x.wid()).collect();
    let mut rows = Vec::new();
    for a in &c.eq {
        let v = dot(a, &x0);
        rows.push(Row { coefs: coefs(a), bounds: interval(v, v), sides: Sides::Equal });
    }
    for (a, below, above, s) in &c.ineq {
        let v = dot(a, &x0);
        let sides = [Sides::Upper, Sides::Lower, Sides::Both, Sides::Both][usize::from(*s)];
        rows.push(Row { coefs: coefs(a), bounds: interval(v - below - shift, v + above + shift), sides });
    }
    let n = x0.len();
    (b, x0, Relaxation { n, rows })
}

fn satisfies(rel: &Relaxation, x: &[f64]) -> bool {
    rel.rows.iter().all(|r| {
        let v: f64 = r.coefs.iter().map(|&(j, a)| a * x[j]).sum();
        match r.sides {
            Sides::Equal | Sides::Both => r.bounds.contains(v),
            Sides::Upper => v <= r.bounds.sup(),
            Sides::Lower => v >= r.bounds.inf(),
        }
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn simplex_is_sound_and_as_tight_as_clarabel(c in case()) {
        let (b, x0, rel) = build(&c, 0.0);
        prop_assert!(satisfies(&rel, &x0));
        let targets: Vec<usize> = (0..6).collect();
        let (mut cs, mut cc) = (LpCounters::default(), LpCounters::default());
        let s = bound(&rel, &b, &targets, &mut cs, &|| false);
        let k = clarabel_lp::bound(&rel, &b, &targets, &mut cc, &|| false);
        let LpOutcome::Bounds(s) = s else { return Err(TestCaseError::fail("simplex: x0 is feasible")) };
        prop_assert_eq!(cs.unverified, 0);
        for (j, v) in s.iter().enumerate() {
            prop_assert!(v.contains(x0[j]), "simplex bound {j} {v:?} misses {}", x0[j]);
        }
        let LpOutcome::Bounds(k) = k else { return Err(TestCaseError::fail("clarabel: x0 is feasible")) };
        for (j, (sv, kv)) in s.iter().zip(&k).enumerate() {
            prop_assert!(kv.contains(x0[j]));
            // A side is left alone when it would move by less than NEGLIGIBLE_GAIN of the
            // target's width.
            let slack = 1e-6 + NEGLIGIBLE_GAIN * b[j].wid();
            prop_assert!(
                sv.inf() >= kv.inf() - slack && sv.sup() <= kv.sup() + slack,
                "target {j}: simplex {sv:?} looser than clarabel {kv:?}"
            );
        }
    }

    #[test]
    fn perturbed_rows_never_cut_a_feasible_point(c in case(), shift in -1.0f64..0.0) {
        // Shifted inequality rows may cut x0 off or make the LP infeasible; whenever x0 still
        // satisfies every row, no answer may exclude it.
        let (b, x0, rel) = build(&c, shift);
        let targets: Vec<usize> = (0..6).collect();
        let mut cs = LpCounters::default();
        let s = bound(&rel, &b, &targets, &mut cs, &|| false);
        if satisfies(&rel, &x0) {
            let LpOutcome::Bounds(s) = s else { return Err(TestCaseError::fail("x0 is feasible")) };
            for (j, v) in s.iter().enumerate() {
                prop_assert!(v.contains(x0[j]));
            }
        }
    }

    #[test]
    fn an_equality_outside_the_box_is_proven_infeasible(c in case(), far in 1.0f64..10.0) {
        // Row 0 pushed beyond its range over the box.
        let (b, _, mut rel) = build(&c, 0.0);
        let r = &mut rel.rows[0];
        let range: Interval = r.coefs.iter().fold(interval(0.0, 0.0), |acc, &(j, a)| acc + interval(a, a) * b[j]);
        prop_assume!(!r.coefs.is_empty());
        let v = range.sup() + far;
        r.bounds = interval(v, v);
        let mut cs = LpCounters::default();
        prop_assert_eq!(bound(&rel, &b, &[0, 1, 2], &mut cs, &|| false), LpOutcome::Infeasible);
    }
}

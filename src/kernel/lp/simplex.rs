//! A dense bounded-variable primal simplex for the tiny LPs of `Relaxation::bound`.
//!
//! Columns are the `n` variables and one slack per row: `A x − s = 0`, so every constraint is a
//! variable bound (`l ≤ x ≤ u` from the box, `s_k` bounded by the enforced sides of row `k`).
//! The tableau is kept condensed: only the `n` nonbasic columns of `B⁻¹ [A | −I]` are stored
//! (`m × n`, basic values `x_B = −T x_N`), starting from the slack basis (`B = −I`, `T = −A`).
//! It is stored by columns: the ratio test, the hottest loop, reads one column, and a pivot
//! skips every column whose entry in the pivot row is zero.
//! Phase 1 (minimise the sum of infeasibilities, one breakpoint per step) runs once; every
//! objective `±x_t` then re-optimises from the previous optimal basis, only the cost row changes.
//! Pricing is Dantzig's rule, switching to Bland's rule after a run of degenerate steps; the
//! ratio test is Harris' two-pass test. Every phase has an iteration cap, on which the objective
//! proves nothing.
//!
//! The answer is only a proposal: the row duals `y = c_Bᵀ B⁻¹` become the multipliers of
//! `safe_bound`, which proves what they imply (a lower bound, or a Farkas certificate).

use super::{safe_bound, LpCounters, LpOutcome, Relaxation, Sides};
use crate::kernel::interval::{interval, Interval};
use crate::kernel::system::VarId;

/// Primal feasibility tolerance (absolute).
const TOL_P: f64 = 1e-9;
/// Optimality tolerance on reduced costs.
const TOL_D: f64 = 1e-9;
/// Smallest tableau entry accepted as a pivot.
const TOL_PIV: f64 = 1e-9;
/// Fraction of a target's width below which narrowing it is not worth the pivots: a side the
/// relaxation cannot move by more than this is left as it is. That is sound (the box only stays
/// wider) and cheap: on the bundled loops and platforms 3% takes half the LPs of 1%, for a few
/// percent more boxes. Larger fractions save more LPs but cost tightness where it matters most:
/// at 5% a box beside a double root (a four-bar's rocker at its limit) is no longer proven
/// empty, and the root's cover splits into two clusters.
const NEGLIGIBLE_GAIN: f64 = 0.03;
/// Consecutive degenerate steps after which pricing falls back to Bland's rule.
const DEGENERATE_RUN: usize = 12;

/// Where a variable (structural or slack) stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    /// Basic in the given tableau row.
    Basic(usize),
    /// Nonbasic at its lower bound, in the given tableau column.
    Lower(usize),
    /// Nonbasic at its upper bound, in the given tableau column.
    Upper(usize),
    /// Nonbasic free variable held at 0, in the given tableau column.
    Free(usize),
}

/// Entries of the largest dense tableau built: 4 Mi (32 MiB of `f64`).
const MAX_TABLEAU_ENTRIES: usize = 1 << 22;

/// Pivots between two looks at the run's deadline: one LP of a large system (thousands of
/// columns) takes seconds, and a look costs about as much as one pivot of a small one.
const PIVOTS_PER_STOP_CHECK: usize = 16;

/// How a phase ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Status {
    Optimal,
    /// Phase 1 only: no improving column while some basic variable is out of bounds.
    Infeasible,
    Unbounded,
    /// Iteration cap, or no usable step.
    Stalled,
    /// Phase 2 only: a feasible point already lies within `NEGLIGIBLE_GAIN` of the box's end,
    /// so the optimum cannot narrow the target by more than that.
    NoGain,
}

/// One step of the ratio test.
enum Step {
    /// The entering column moves to its other bound; the basis is unchanged.
    Flip,
    /// The basic variable of `row` leaves at its upper (`true`) or lower bound, after `theta`.
    Pivot {
        row: usize,
        theta: f64,
        at_upper: bool,
    },
    Unbounded,
}

struct Tableau {
    n: usize,
    m: usize,
    /// Nonbasic columns of `B⁻¹ [A | −I]`, column-major `m × n`: entry `(i, c)` at `c·m + i`.
    t: Vec<f64>,
    /// The basic variable of each row.
    head: Vec<usize>,
    /// The nonbasic variable of each column.
    nb: Vec<usize>,
    /// Per variable (`n` structural, then `m` slacks).
    state: Vec<State>,
    lo: Vec<f64>,
    hi: Vec<f64>,
    val: Vec<f64>,
    /// Reduced costs of the nonbasic columns.
    d: Vec<f64>,
    /// Phase-1 costs of the basic variables.
    cb: Vec<f64>,
    /// Rates of change of the basic variables along the entering direction.
    alpha: Vec<f64>,
    /// Exact blocking ratio of each row and whether it blocks at its upper bound.
    exact: Vec<(f64, bool)>,
    /// Per row, work space of `pivot` and `refresh_values`.
    scratch: Vec<f64>,
    /// Per nonbasic column, whether its variable may rise and may fall (1.0 or 0.0): pricing
    /// reads these instead of the variable's state and bounds.
    moves: Vec<[f64; 2]>,
    degenerate: usize,
    /// The targets of `bound`, and the lowest and highest value each took at a feasible vertex
    /// so far: a side some vertex already came within `NEGLIGIBLE_GAIN` of needs no LP.
    watched: Vec<usize>,
    reach: Vec<[f64; 2]>,
}

/// Which ways a nonbasic variable in `state` with bounds `[lo, hi]` may move.
fn moves_of(state: State, lo: f64, hi: f64) -> [f64; 2] {
    let movable = f64::from(u8::from(hi > lo));
    match state {
        State::Lower(_) => [movable, 0.0],
        State::Upper(_) => [0.0, movable],
        State::Free(_) => [1.0, 1.0],
        State::Basic(_) => [0.0, 0.0],
    }
}

impl Tableau {
    fn new(rel: &Relaxation, b: &[Interval]) -> Self {
        let (n, m) = (rel.n, rel.rows.len());
        let w = n + m;
        let mut t = vec![0.0; m * n];
        let (mut lo, mut hi) = (vec![0.0; w], vec![0.0; w]);
        let mut val = vec![0.0; w];
        let mut state: Vec<State> = (0..m).map(State::Basic).collect();
        state.splice(0..0, (0..n).map(State::Lower));
        for (j, x) in b.iter().enumerate().take(n) {
            lo[j] = x.inf();
            hi[j] = x.sup();
            (state[j], val[j]) = if lo[j].is_finite() {
                (State::Lower(j), lo[j])
            } else if hi[j].is_finite() {
                (State::Upper(j), hi[j])
            } else {
                (State::Free(j), 0.0)
            };
        }
        for (k, row) in rel.rows.iter().enumerate() {
            // Slack basis: B⁻¹ = −I, so the row of s_k is −a_k.
            let mut s = 0.0;
            for &(j, a) in &row.coefs {
                t[j * m + k] -= a;
                s += a * val[j];
            }
            val[n + k] = s;
            let (l, u) = (row.bounds.inf(), row.bounds.sup());
            (lo[n + k], hi[n + k]) = match row.sides {
                Sides::Equal => (row.bounds.mid(), row.bounds.mid()),
                Sides::Upper => (f64::NEG_INFINITY, u),
                Sides::Lower => (l, f64::INFINITY),
                Sides::Both => (l, u),
            };
        }
        let moves = (0..n).map(|j| moves_of(state[j], lo[j], hi[j])).collect();
        Tableau {
            moves,
            n,
            m,
            t,
            head: (n..w).collect(),
            nb: (0..n).collect(),
            state,
            lo,
            hi,
            val,
            d: vec![0.0; n],
            cb: vec![0.0; m],
            alpha: vec![0.0; m],
            exact: vec![(f64::INFINITY, false); m],
            scratch: vec![0.0; m],
            degenerate: 0,
            watched: Vec::new(),
            reach: Vec::new(),
        }
    }

    fn column(&self, c: usize) -> &[f64] {
        &self.t[c * self.m..(c + 1) * self.m]
    }

    /// Entry `(i, c)` of the tableau.
    fn at(&self, i: usize, c: usize) -> f64 {
        self.t[c * self.m + i]
    }

    /// The tableau row of `v` when it is basic.
    fn basic_row(&self, v: usize) -> Option<usize> {
        match self.state[v] {
            State::Basic(r) => Some(r),
            _ => None,
        }
    }

    /// Starts recording the range of `targets` over the feasible vertices visited.
    fn watch(&mut self, targets: &[VarId]) {
        self.watched = targets.to_vec();
        self.reach = vec![[f64::INFINITY, f64::NEG_INFINITY]; targets.len()];
    }

    /// Records the current vertex, which must be feasible, in `reach`.
    fn note_vertex(&mut self) {
        for (r, &v) in self.reach.iter_mut().zip(&self.watched) {
            let x = self.val[v];
            *r = [r[0].min(x), r[1].max(x)];
        }
    }

    /// Recomputes the basic values from the nonbasic ones: `x_B = −T x_N`.
    fn refresh_values(&mut self) {
        let m = self.m;
        if m == 0 {
            return;
        }
        self.scratch.iter_mut().for_each(|s| *s = 0.0);
        for (col, &v) in self.t.chunks_exact(m).zip(&self.nb) {
            let x = self.val[v];
            self.scratch.iter_mut().zip(col).for_each(|(s, a)| *s += a * x);
        }
        for (&p, s) in self.head.iter().zip(&self.scratch) {
            self.val[p] = -s;
        }
    }

    /// The entering column and its direction (`+1` increases it), by the current reduced costs:
    /// a column may enter when moving it the way it may move lowers the cost.
    fn entering(&self) -> Option<(usize, f64)> {
        let bland = self.degenerate >= DEGENERATE_RUN;
        let mut best: Option<(usize, f64)> = None;
        let mut best_score = TOL_D;
        for (c, (&dc, &[up, down])) in self.d.iter().zip(&self.moves).enumerate() {
            let (rise, fall) = (-dc * up, dc * down);
            let score = rise.max(fall);
            if score <= TOL_D {
                continue;
            }
            let better = match best {
                None => true,
                Some((bc, _)) if bland => self.nb[c] < self.nb[bc],
                Some(_) => score > best_score,
            };
            if better {
                best_score = score;
                best = Some((c, if rise >= fall { 1.0 } else { -1.0 }));
            }
        }
        best
    }

    /// Phase 1's blocking bound of basic row `i` moving at rate `a`, whether it is the upper
    /// one, and the Harris tolerance to relax it by (feasible variables only): an infeasible
    /// variable stops where it becomes feasible, and never blocks when moving away. Infinite
    /// bounds give infinite ratios, which never block.
    #[inline(always)]
    fn target(&self, i: usize, a: f64, phase1: bool) -> (f64, bool, f64) {
        let p = self.head[i];
        let (x, l, u) = (self.val[p], self.lo[p], self.hi[p]);
        if phase1 && x < l - TOL_P {
            return if a > 0.0 { (l, false, 0.0) } else { (f64::NEG_INFINITY, false, 0.0) };
        }
        if phase1 && x > u + TOL_P {
            return if a < 0.0 { (u, true, 0.0) } else { (f64::INFINITY, true, 0.0) };
        }
        if a > 0.0 {
            (u, true, TOL_P)
        } else {
            (l, false, -TOL_P)
        }
    }

    /// Harris' two-pass ratio test along column `c` in direction `dir`.
    fn ratio(&mut self, c: usize, dir: f64, phase1: bool) -> Step {
        let bland = self.degenerate >= DEGENERATE_RUN;
        let q = self.nb[c];
        let range = self.hi[q] - self.lo[q];
        let mut theta_max = if range.is_finite() { range } else { f64::INFINITY };
        // Pass 1: the largest step keeping every blocking variable within its relaxed bound;
        // the exact ratios are kept for pass 2. An infinite bound gives an infinite ratio; a tiny
        // rate never blocks.
        let col = &self.t[c * self.m..(c + 1) * self.m];
        for (i, &entry) in col.iter().enumerate() {
            let a = -dir * entry;
            self.alpha[i] = a;
            let (bound, at_upper, tol) = self.target(i, a, phase1);
            let x = self.val[self.head[i]];
            let (relaxed, exact) = if a.abs() < TOL_PIV {
                (f64::INFINITY, f64::INFINITY)
            } else {
                (((bound + tol - x) / a).max(0.0), ((bound - x) / a).max(0.0))
            };
            theta_max = theta_max.min(relaxed);
            self.exact[i] = (exact, at_upper);
        }
        if theta_max == f64::INFINITY {
            return Step::Unbounded;
        }
        if range <= theta_max {
            return Step::Flip;
        }
        // Pass 2: among the rows blocking within that step, the largest pivot (Bland: the
        // smallest leaving variable).
        let mut chosen: Option<usize> = None;
        let mut best = 0.0;
        for i in 0..self.m {
            if self.exact[i].0 > theta_max {
                continue;
            }
            let a = self.alpha[i].abs();
            let better = match chosen {
                None => true,
                Some(ci) if bland => self.head[i] < self.head[ci],
                Some(_) => a > best,
            };
            if better {
                best = a;
                chosen = Some(i);
            }
        }
        match chosen {
            Some(row) => Step::Pivot { row, theta: self.exact[row].0, at_upper: self.exact[row].1 },
            // Only reachable through rounding in the two passes: treat as a flip if possible.
            None if range.is_finite() => Step::Flip,
            None => Step::Unbounded,
        }
    }

    /// Moves along column `c` as the ratio test says; false when no step was possible.
    fn apply(&mut self, c: usize, dir: f64, step: Step) -> bool {
        let q = self.nb[c];
        let theta = match step {
            Step::Unbounded => return false,
            Step::Flip => self.hi[q] - self.lo[q],
            Step::Pivot { theta, .. } => theta,
        };
        for i in 0..self.m {
            let a = self.alpha[i];
            if a != 0.0 {
                self.val[self.head[i]] += a * theta;
            }
        }
        self.degenerate = if theta <= 1e-12 { self.degenerate + 1 } else { 0 };
        match step {
            Step::Flip => {
                (self.state[q], self.val[q]) =
                    if dir > 0.0 { (State::Upper(c), self.hi[q]) } else { (State::Lower(c), self.lo[q]) };
                self.moves[c] = moves_of(self.state[q], self.lo[q], self.hi[q]);
            }
            Step::Pivot { row, at_upper, .. } => {
                self.val[q] += dir * theta;
                let p = self.head[row];
                (self.state[p], self.val[p]) =
                    if at_upper { (State::Upper(c), self.hi[p]) } else { (State::Lower(c), self.lo[p]) };
                self.state[q] = State::Basic(row);
                self.head[row] = q;
                self.nb[c] = p;
                self.moves[c] = moves_of(self.state[p], self.lo[p], self.hi[p]);
                self.pivot(row, c);
            }
            Step::Unbounded => unreachable!("handled above"),
        }
        true
    }

    /// Condensed-tableau pivot on `(r, c)`: column `c` now holds the leaving variable. The
    /// reduced costs transform as one more row.
    fn pivot(&mut self, r: usize, c: usize) {
        let m = self.m;
        let inv = 1.0 / self.at(r, c);
        // The pivot column, its pivot entry zeroed so the pivot row is left as scaled.
        self.scratch.copy_from_slice(&self.t[c * m..(c + 1) * m]);
        self.scratch[r] = 0.0;
        for (j, col) in self.t.chunks_exact_mut(m).enumerate() {
            if j == c {
                continue;
            }
            col[r] *= inv;
            let p = col[r];
            if p != 0.0 {
                col.iter_mut().zip(&self.scratch).for_each(|(v, f)| *v -= f * p);
            }
        }
        let pc = &mut self.t[c * m..(c + 1) * m];
        pc.iter_mut().zip(&self.scratch).for_each(|(v, f)| *v = -f * inv);
        pc[r] = inv;
        let f = self.d[c];
        if f != 0.0 {
            let prow = |j: usize| self.t[j * m + r];
            for j in (0..self.n).filter(|&j| j != c) {
                self.d[j] -= f * prow(j);
            }
            self.d[c] = -f * inv;
        }
    }

    /// Phase 1: minimises the sum of infeasibilities from the current basis.
    fn phase1(&mut self, cap: usize, stop: &dyn Fn() -> bool) -> Status {
        self.degenerate = 0;
        for k in 0..cap {
            if k % PIVOTS_PER_STOP_CHECK == PIVOTS_PER_STOP_CHECK - 1 && stop() {
                return Status::Stalled;
            }
            let mut any = false;
            for i in 0..self.m {
                let p = self.head[i];
                let x = self.val[p];
                self.cb[i] = if x < self.lo[p] - TOL_P {
                    -1.0
                } else if x > self.hi[p] + TOL_P {
                    1.0
                } else {
                    0.0
                };
                any |= self.cb[i] != 0.0;
            }
            if !any {
                return Status::Optimal;
            }
            // d_N = c_N − T_Nᵀ c_B with c_N = 0.
            // Few rows are infeasible: only theirs are read.
            self.d.iter_mut().for_each(|v| *v = 0.0);
            for (i, &cost) in self.cb.iter().enumerate().filter(|(_, cost)| **cost != 0.0) {
                let row = self.t.iter().skip(i).step_by(self.m);
                self.d.iter_mut().zip(row).for_each(|(v, a)| *v -= cost * a);
            }
            let Some((c, dir)) = self.entering() else { return Status::Infeasible };
            let step = self.ratio(c, dir, true);
            if !self.apply(c, dir, step) {
                return Status::Stalled;
            }
        }
        Status::Stalled
    }

    /// Widens the working bounds of out-of-bounds basic variables to their values, so the basis
    /// is feasible for phase 2 (the answers remain mere proposals for `safe_bound`).
    fn relax_infeasible(&mut self) {
        for &p in &self.head {
            self.lo[p] = self.lo[p].min(self.val[p]);
            self.hi[p] = self.hi[p].max(self.val[p]);
        }
    }

    /// Row duals `y = c_Bᵀ B⁻¹` for basic costs `cost(row)`: `B⁻¹` is minus the slack columns
    /// of the full tableau, unit columns for basic slacks.
    fn duals_for(&self, cost: impl Fn(usize) -> f64, mu: &mut [f64]) {
        for (k, y) in mu.iter_mut().enumerate() {
            *y = match self.state[self.n + k] {
                State::Basic(i) => -cost(i),
                State::Lower(c) | State::Upper(c) | State::Free(c) => {
                    -self.column(c).iter().enumerate().map(|(i, a)| cost(i) * a).sum::<f64>()
                }
            };
        }
    }

    /// Row duals for the phase-1 costs.
    fn phase1_duals(&self, mu: &mut [f64]) {
        self.duals_for(|i| self.cb[i], mu);
    }

    /// Reduced costs for the objective `sign·x_t`.
    fn set_objective(&mut self, t: usize, sign: f64) {
        self.d.iter_mut().for_each(|v| *v = 0.0);
        match self.state[t] {
            State::Basic(r) => {
                for c in 0..self.n {
                    self.d[c] = -sign * self.at(r, c);
                }
            }
            State::Lower(c) | State::Upper(c) | State::Free(c) => self.d[c] = sign,
        }
        self.degenerate = 0;
    }

    /// Phase 2 from a feasible basis for the cost `sign·x_t` set by `set_objective`, given up
    /// as soon as a vertex has `sign·x_t ≤ worth` (the optimum cannot beat it).
    fn phase2(&mut self, cap: usize, stop: &dyn Fn() -> bool, t: usize, sign: f64, worth: f64) -> Status {
        for k in 0..cap {
            if k % PIVOTS_PER_STOP_CHECK == PIVOTS_PER_STOP_CHECK - 1 && stop() {
                return Status::Stalled;
            }
            if sign * self.val[t] <= worth {
                return Status::NoGain;
            }
            let Some((c, dir)) = self.entering() else { return Status::Optimal };
            let step = self.ratio(c, dir, false);
            if matches!(step, Step::Unbounded) {
                return Status::Unbounded;
            }
            self.apply(c, dir, step);
            self.note_vertex();
        }
        Status::Stalled
    }

    /// Row duals for the objective `sign·x_t` at the current basis: only `x_t` has a cost.
    fn duals(&self, t: usize, sign: f64, mu: &mut [f64]) {
        match self.basic_row(t) {
            Some(r) => {
                for (k, y) in mu.iter_mut().enumerate() {
                    *y = match self.state[self.n + k] {
                        State::Basic(_) => 0.0,
                        State::Lower(c) | State::Upper(c) | State::Free(c) => -sign * self.at(r, c),
                    };
                }
            }
            None => mu.iter_mut().for_each(|v| *v = 0.0),
        }
    }
}

/// Verified bounds of each target over the rows and the box `b`: see `Relaxation::bound`.
pub(super) fn bound(rel: &Relaxation, b: &[Interval], targets: &[VarId], counters: &mut LpCounters, stop: &dyn Fn() -> bool) -> LpOutcome {
    let unchanged = || LpOutcome::Bounds(targets.iter().map(|&t| b[t]).collect());
    if b.iter().take(rel.n).any(|x| x.is_empty()) {
        return LpOutcome::Infeasible; // the box itself holds no point
    }
    let well_formed = b.len() >= rel.n
        && rel.rows.iter().all(|r| !r.bounds.is_empty() && r.coefs.iter().all(|&(j, a)| j < rel.n && a.is_finite()));
    if !well_formed {
        counters.unverified += 2 * targets.len() as u64;
        return unchanged();
    }
    // The tableau is dense: past a few million entries it costs more memory and time than
    // propagation alone would (a loop through a chain of thousands of joints), so the box is
    // left to the other contractors.
    if rel.n.saturating_mul(rel.rows.len()) > MAX_TABLEAU_ENTRIES {
        return unchanged();
    }
    let mut tab = Tableau::new(rel, b);
    let cap = 50 * (tab.n + tab.m + 1);
    let mut mu = vec![0.0; tab.m];
    match tab.phase1(cap, stop) {
        Status::Optimal => {}
        Status::Infeasible => {
            tab.phase1_duals(&mut mu);
            if safe_bound::certified_infeasible(rel, b, &mu) {
                return LpOutcome::Infeasible;
            }
            counters.unverified += 1;
            tab.relax_infeasible();
        }
        Status::Unbounded | Status::Stalled | Status::NoGain => {
            counters.unverified += 2 * targets.len() as u64;
            return unchanged();
        }
    }

    tab.watch(targets);
    tab.note_vertex();
    let mut current: Vec<Interval> = b.to_vec();
    let mut result = Vec::with_capacity(targets.len());
    for (k, &t) in targets.iter().enumerate() {
        for sign in [1.0, -1.0] {
            if stop() {
                break;
            }
            let x = current[t];
            // The vertex must beat the box's end by a fraction of its width to be worth pivots.
            let worth = if sign > 0.0 { x.inf() + NEGLIGIBLE_GAIN * x.wid() } else { -(x.sup() - NEGLIGIBLE_GAIN * x.wid()) };
            let [lowest, highest] = tab.reach[k];
            if (sign > 0.0 && lowest <= worth) || (sign < 0.0 && -highest <= worth) {
                continue;
            }
            tab.refresh_values();
            tab.set_objective(t, sign);
            counters.solved += 1;
            match tab.phase2(cap, stop, t, sign, worth) {
                Status::Optimal => {}
                Status::NoGain => continue,
                _ => {
                    counters.unverified += 1;
                    continue;
                }
            }
            tab.duals(t, sign, &mut mu);
            let lb = safe_bound::lower_bound(rel, &current, &[(t, sign)], &mu);
            let narrowed =
                if sign > 0.0 { interval(lb.max(x.inf()), x.sup()) } else { interval(x.inf(), (-lb).min(x.sup())) };
            if narrowed.is_empty() {
                return LpOutcome::Infeasible;
            }
            if narrowed == x {
                counters.unverified += u64::from(lb == f64::NEG_INFINITY);
            }
            current[t] = narrowed;
        }
        result.push(current[t]);
    }
    LpOutcome::Bounds(result)
}

#[cfg(test)]
mod tests;

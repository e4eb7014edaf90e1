//! Cusps: singular points where the kernel of Df is tangent to the singular curve.
//!
//! Branch and prune over (θ₂, θ₃) ∈ [-π, π]². A box is discarded when det Df provably does not
//! vanish on it, or when a row of the system (2) of Benoit et al. (2019), `gₖ = ∇fₖ · T` with
//! `T = (−∂det/∂θ₃, ∂det/∂θ₂)`, provably does not vanish (both rows vanish at a cusp).
//! Otherwise Krawczyk runs on the square system `(det Df, gₖ)`, with `k` a row of Df that is
//! provably non-zero on the box. Why that system and not (2) itself:
//!
//! - (2) alone also vanishes at every critical point of det Df, singular or not; adding
//!   `det Df = 0` removes those.
//! - `(det Df, gₖ)` also vanishes where row k of Df is zero (then `gₖ ≡ 0`); choosing `k` with
//!   row k proven non-zero on the box removes those.
//! - On a box where `det = 0`, row k ≠ 0 and `gₖ = 0`, Df has rank one with kernel ⊥ row k, so
//!   `T ⊥ row k` puts `T` in the kernel: both rows of (2) vanish.
//!
//! A box is reported as a cusp when Krawczyk proves a unique zero of `(det, gₖ)` in it and
//! interval arithmetic proves `∇det ≠ 0` (so the singular curve is smooth and `T` is its tangent)
//! and row k ≠ 0 on it; the box is then shrunk by Krawczyk to the precision.
//! The remaining spurious zeros of the square system are points where `∇det = 0` (crossings of
//! the singular curve), which are never cusps: a box proven to hold one but where `∇det` may
//! vanish is bisected, and if it reaches the precision so, it is left undecided with that reason.
//! Boxes inside an internal-motion strip are set aside (see `motion`).

use super::map::TorusMap;
use super::drive::{drive_shared, no_progress, Order, Outcome};
use crate::kernel::search::Wire;
use crate::kernel::search::Control;
use crate::kernel::contract::krawczyk::{self, Inflation, Step as K};
use super::motion::{self, Band};
use crate::kernel::interval::{interval, merge_touching, point};
use crate::kernel::search::{self, Limits, Progress, Prune, Stats, Status, Step};
use inari::Interval;
use smallvec::smallvec;
use std::time::Instant;

/// How boxes are decided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Exclusion tests plus Krawczyk proofs (the default).
    Krawczyk,
    /// Exclusion tests and bisection only, down to the precision: the baseline for benchmarks.
    /// Cusp boxes are then candidates, not proven.
    Bisection,
}

/// Settings of a cusp search (its bounds are a `Control`).
#[derive(Clone, Copy, Debug)]
pub struct CuspSettings {
    /// Largest width of a reported box (radians); undecided boxes are at most this wide.
    pub precision: f64,
    /// Krawczyk or the bisection baseline.
    pub method: Method,
}

impl Default for CuspSettings {
    fn default() -> Self {
        CuspSettings { precision: 1e-4, method: Method::Krawczyk }
    }
}

/// Boxes a cusp search processes at most unless told otherwise (`search`).
pub const DEFAULT_MAX_BOXES: u64 = 5_000_000;

/// A certified cusp.
#[derive(Clone, Copy, Debug)]
pub struct Cusp {
    /// (θ₂, θ₃) box holding exactly one cusp.
    pub theta: [Interval; 2],
    /// ρ over the box.
    pub rho: Interval,
    /// z over the box.
    pub z: Interval,
    /// True when uniqueness (and existence) is proven; false for bisection-baseline candidates.
    pub unique: bool,
}

/// Why a box was left undecided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reason {
    /// A zero of (det, gₖ) is proven but ∇det Df may vanish there: a crossing, not a cusp, if
    /// ∇det = 0 exactly.
    GradDetMayVanish,
    /// Reached the precision with nothing proven.
    Precision,
    /// Left pending by a limit.
    Limit,
}

/// An undecided box.
#[derive(Clone, Copy, Debug)]
pub struct Undecided {
    /// (θ₂, θ₃)
    pub theta: [Interval; 2],
    /// Why.
    pub reason: Reason,
}

/// The outcome of a cusp search.
#[derive(Clone, Debug)]
pub struct CuspSearch {
    /// Certified cusps (candidates for `Method::Bisection`), one per cusp point of the torus.
    pub cusps: Vec<Cusp>,
    /// Undecided boxes.
    pub undecided: Vec<Undecided>,
    /// Internal-motion strips that were set aside.
    pub bands: Vec<Band>,
    /// `Complete` when every box was decided or set aside; otherwise the limit that stopped it.
    pub status: Status,
    /// The kernel's counters; discards by reason: `in_strips`, `regular` (det Df ≠ 0),
    /// `not_tangent` (a row of system (2) ≠ 0), `krawczyk_empty`.
    pub stats: Stats,
    /// Krawczyk contractions among the kernel's splits (the others are bisections).
    pub contracted: u64,
    /// Wall-clock seconds, the strips included.
    pub seconds: f64,
}

/// Enclosures over a box, each the intersection of the natural and the mean-value form.
#[derive(Clone, Copy, Debug)]
pub struct BoxEval {
    /// det Df
    pub det: Interval,
    /// ∇det Df
    pub grad_det: [Interval; 2],
    /// rows of Df: `df[k] = ∇fₖ`
    pub df: [[Interval; 2]; 2],
    /// system (2): `g[k] = ∇fₖ · T`
    pub g: [Interval; 2],
    /// ∇gₖ
    pub grad_g: [[Interval; 2]; 2],
    /// ρ and z
    pub f: [Interval; 2],
    /// det Df at the midpoint
    pub det_mid: Interval,
    /// system (2) at the midpoint
    pub g_mid: [Interval; 2],
    /// (ρ, z) at the midpoint
    pub f_mid: [Interval; 2],
}

/// Evaluates everything a cusp or node test needs over `b`.
pub fn evaluate<M: TorusMap + ?Sized>(chain: &M, b: [Interval; 2]) -> BoxEval {
    evaluate_to(chain, b, 3)
}

/// As `evaluate`, but from second-order jets over the box: everything but `grad_g` (left
/// whole) and the centred form of `g` (natural only). The node search needs no more, and
/// second-order jets cost about half as much.
pub fn evaluate_without_tangency<M: TorusMap + ?Sized>(chain: &M, b: [Interval; 2]) -> BoxEval {
    evaluate_to(chain, b, 2)
}

fn evaluate_to<M: TorusMap + ?Sized>(chain: &M, b: [Interval; 2], order: usize) -> BoxEval {
    let m = [b[0].mid(), b[1].mid()];
    let over = chain.derived(b, order);
    let at = chain.derived([point(m[0]), point(m[1])], 2);
    let dx = [b[0] - point(m[0]), b[1] - point(m[1])];
    let centred = |whole: Interval, grad: [Interval; 2], mid: Interval| whole.intersection(mid + grad[0] * dx[0] + grad[1] * dx[1]);
    let det = centred(over.det.value(), over.det.grad(), at.det.value());
    let mut g = [Interval::EMPTY; 2];
    let mut grad_g = [[Interval::EMPTY; 2]; 2];
    let mut df = [[Interval::EMPTY; 2]; 2];
    let mut f = [Interval::EMPTY; 2];
    for k in 0..2 {
        if order >= 3 {
            g[k] = centred(over.g[k].value(), over.g[k].grad(), at.g[k].value());
            grad_g[k] = over.g[k].grad();
        } else {
            g[k] = over.g[k].value();
            grad_g[k] = [Interval::ENTIRE; 2];
        }
        df[k] = over.f[k].grad();
        f[k] = centred(over.f[k].value(), df[k], at.f[k].value());
    }
    BoxEval { det, grad_det: over.det.grad(), df, g, grad_g, f, det_mid: at.det.value(), g_mid: [at.g[0].value(), at.g[1].value()], f_mid: [at.f[0].value(), at.f[1].value()] }
}

fn excludes_zero(v: &[Interval]) -> bool {
    v.iter().any(|x| !x.contains(0.0))
}

fn width(b: &[Interval; 2]) -> f64 {
    b[0].wid().max(b[1].wid())
}

/// Bisects the widest side (θ₂ on ties), or θ₃ when `cut_theta3`. Midpoint cuts keep every θ₃
/// interval one of the dyadic cells of `motion`.
pub fn bisect(b: [Interval; 2], cut_theta3: bool) -> ([Interval; 2], [Interval; 2]) {
    let i = if cut_theta3 || b[1].wid() > b[0].wid() { 1 } else { 0 };
    let m = b[i].mid();
    let (mut lo, mut hi) = (b, b);
    lo[i] = interval(b[i].inf(), m);
    hi[i] = interval(m, b[i].sup());
    (lo, hi)
}

/// The square system (det, gₖ) linearised over `b` with `e` its evaluation: midpoint, values
/// there and Jacobian over `b`, as `krawczyk::step_array` takes them.
fn cusp_system(b: &[Interval; 2], e: &BoxEval, k: usize) -> ([f64; 2], [Interval; 2], [[Interval; 2]; 2]) {
    ([b[0].mid(), b[1].mid()], [e.det_mid, e.g_mid[k]], [e.grad_det, e.grad_g[k]])
}

/// Krawczyk on (det, gₖ) over `b` with `e` its evaluation.
fn krawczyk_cusp(b: &[Interval; 2], e: &BoxEval, k: usize) -> K<[Interval; 2]> {
    let (m, fm, jac) = cusp_system(b, e, k);
    krawczyk::step_array(b, &m, &fm, &jac)
}

/// Shrinks a proven cusp box by repeated Krawczyk steps until it is no wider than `precision`.
fn refine<M: TorusMap + ?Sized>(chain: &M, b: [Interval; 2], k: usize, precision: f64) -> [Interval; 2] {
    krawczyk::tighten(b, precision, |b| krawczyk_cusp(b, &evaluate(chain, *b), k))
}

/// Epsilon-inflation (Rump, the shared `krawczyk::inflate`): from a box `x` that Krawczyk
/// contracted but could not prove, try slightly larger boxes around it. With uncertain lengths
/// the cusp moves with the geometry, so only a box wider than that motion can hold "one cusp
/// for every geometry"; bisection alone would never produce one. A trial box where `∇det` or
/// row `k` of Df may vanish ends the search. Returns the proven box.
fn inflate<M: TorusMap + ?Sized>(chain: &M, x: [Interval; 2], k: usize) -> Option<[Interval; 2]> {
    let policy = Inflation { rounds: 8, own: 0.1, widest: 0.0, widest_of: &[], absolute: 1e-12, ulps: 0.0 };
    krawczyk::inflate(&x, &policy, |grown| {
        let e = evaluate(chain, *grown);
        if !excludes_zero(&e.grad_det) || !excludes_zero(&e.df[k]) {
            return None;
        }
        let (m, fm, jac) = cusp_system(grown, &e, k);
        krawczyk::image_array(grown, &m, &fm, &jac)
    })
}

/// True when the two boxes share a point of the torus (angles modulo 2π).
pub fn meet_on_torus(a: &[Interval; 2], b: &[Interval; 2]) -> bool {
    let tau = Interval::TAU;
    (0..2).all(|i| [point(0.0), tau, -tau].iter().any(|s| !a[i].disjoint(b[i] + *s)))
}

/// True when the two boxes share a point of the torus only through the ±π seam.
fn meet_across_seam(a: &[Interval; 2], b: &[Interval; 2]) -> bool {
    meet_on_torus(a, b) && (0..2).any(|i| a[i].disjoint(b[i]))
}

/// A box of the cusp search, with its place in the depth-first walk.
#[derive(Clone, Copy, Debug)]
pub struct CuspCell {
    theta: [Interval; 2],
    order: Order,
    level: u32,
}

/// How a reported box was proven.
#[derive(Clone, Copy, Debug)]
enum Proof {
    /// Krawczyk proved a unique zero and ∇det ≠ 0 on the box.
    Krawczyk,
    /// ε-inflation proved one around a contracted box, with Df's row `k` (uncertain chains).
    Inflated(usize),
    /// Bisection baseline: a candidate at the precision, nothing proven.
    Candidate,
}

impl Wire for CuspCell {
    fn put(&self, out: &mut Vec<u8>) {
        (self.theta, self.order, self.level).put(out)
    }
    fn take(input: &mut &[u8]) -> Self {
        let (theta, order, level) = Wire::take(input);
        CuspCell { theta, order, level }
    }
}

impl Wire for Proof {
    fn put(&self, out: &mut Vec<u8>) {
        match *self {
            Proof::Krawczyk => (0u8, 0usize),
            Proof::Inflated(k) => (1, k),
            Proof::Candidate => (2, 0),
        }
        .put(out)
    }
    fn take(input: &mut &[u8]) -> Self {
        match <(u8, usize)>::take(input) {
            (0, _) => Proof::Krawczyk,
            (1, k) => Proof::Inflated(k),
            _ => Proof::Candidate,
        }
    }
}

impl Wire for CuspFound {
    fn put(&self, out: &mut Vec<u8>) {
        ((self.order, self.source), (self.theta, self.proof)).put(out)
    }
    fn take(input: &mut &[u8]) -> Self {
        let ((order, source), (theta, proof)) = Wire::take(input);
        CuspFound { order, source, theta, proof }
    }
}

/// What one box yielded: a cusp box, before the decisions that look at other cusps.
#[derive(Clone, Copy, Debug)]
pub struct CuspFound {
    order: Order,
    /// The box of the search that yielded it.
    source: [Interval; 2],
    theta: [Interval; 2],
    proof: Proof,
}

/// The cusp test of the module doc, one box at a time.
struct CuspPrune<'a, M: TorusMap + ?Sized> {
    chain: &'a M,
    bands: &'a [Band],
    eps: f64,
    method: Method,
    /// Krawczyk contractions (splits into one child), which the report does not count as
    /// bisections.
    contracted: u64,
}

/// Measure of the start box, for progress.
fn full_area() -> f64 {
    (2.0 * motion::PI_UP) * (2.0 * motion::PI_UP)
}

/// Why the cusp search discards a box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CuspDiscard {
    /// It lies in an internal-motion strip (reported with the strip).
    InStrips,
    /// det Df ≠ 0 on it.
    Regular,
    /// A row of system (2) ≠ 0 on it.
    NotTangent,
    /// Krawczyk proves it holds no zero.
    KrawczykEmpty,
}

impl crate::kernel::search::Reason for CuspDiscard {
    fn name(self) -> &'static str {
        match self {
            CuspDiscard::InStrips => "in_strips",
            CuspDiscard::Regular => "regular",
            CuspDiscard::NotTangent => "not_tangent",
            CuspDiscard::KrawczykEmpty => "krawczyk_empty",
        }
    }
}


impl<M: TorusMap + ?Sized> Prune for CuspPrune<'_, M> {
    type Cell = CuspCell;
    type Found = CuspFound;
    type Reason = CuspDiscard;

    fn process(&mut self, cell: CuspCell) -> Step<CuspCell, CuspFound, CuspDiscard> {
        let (chain, eps) = (self.chain, self.eps);
        let b = cell.theta;
        if self.bands.iter().any(|band| band.holds(b[1])) {
            return Step::Discard(CuspDiscard::InStrips);
        }
        let e = evaluate(chain, b);
        if !e.det.contains(0.0) {
            return Step::Discard(CuspDiscard::Regular);
        }
        if !e.g[0].contains(0.0) || !e.g[1].contains(0.0) {
            return Step::Discard(CuspDiscard::NotTangent);
        }
        let grad_det_ok = excludes_zero(&e.grad_det);
        let row = (0..2).filter(|&k| excludes_zero(&e.df[k])).max_by(|&i, &j| {
            let mig = |k: usize| e.df[k][0].mig().max(e.df[k][1].mig());
            mig(i).total_cmp(&mig(j))
        });
        let small = width(&b) <= eps;
        let found = |theta, proof| Step::Found(CuspFound { order: cell.order, source: b, theta, proof });
        if self.method == Method::Krawczyk {
            if let Some(k) = row {
                match krawczyk_cusp(&b, &e, k) {
                    K::Empty => return Step::Discard(CuspDiscard::KrawczykEmpty),
                    K::Unique(inner) if grad_det_ok => return found(refine(chain, inner, k, eps), Proof::Krawczyk),
                    K::Unique(_) if small => return Step::Undecided(cell, GRAD_DET_MAY_VANISH),
                    K::Contracted(k_box) if small && grad_det_ok && chain.uncertainty() > 0.0 => {
                        if let Some(inner) = inflate(chain, k_box, k) {
                            return found(refine(chain, inner, k, eps), Proof::Inflated(k));
                        }
                    }
                    // Contraction moves box edges off the dyadic grid, which only matters near
                    // strips.
                    K::Contracted(k) if width(&k) < 0.7 * width(&b) && self.bands.is_empty() => {
                        self.contracted += 1;
                        return Step::Split(smallvec![CuspCell { theta: k, order: cell.order.child(0, 1), level: cell.level + 1 }]);
                    }
                    _ => {}
                }
            }
        } else if small {
            // Baseline: a box at the precision that passed every exclusion test is a candidate.
            return found(b, Proof::Candidate);
        }
        if small {
            return Step::Undecided(cell, PRECISION);
        }
        let (lo, hi) = bisect(b, motion::straddles(self.bands, b[1]));
        let child = |theta, i| CuspCell { theta, order: cell.order.child(i, 2), level: cell.level + 1 };
        Step::Split(smallvec![child(lo, 0), child(hi, 1)])
    }

    fn share(&self, cell: &CuspCell) -> f64 {
        cell.theta[0].wid() * cell.theta[1].wid() / full_area()
    }

    fn level(&self, cell: &CuspCell) -> u32 {
        cell.level
    }
}

const GRAD_DET_MAY_VANISH: &str = "grad_det_may_vanish";
const PRECISION: &str = "precision";

fn reason(why: search::Undecided) -> Reason {
    match why {
        search::Undecided::Precision(GRAD_DET_MAY_VANISH) => Reason::GradDetMayVanish,
        search::Undecided::Precision(_) => Reason::Precision,
        search::Undecided::Pending => Reason::Limit,
    }
}

fn inside(outer: &[Interval; 2], inner: &[Interval; 2]) -> bool {
    (0..2).all(|i| outer[i].inf() <= inner[i].inf() && inner[i].sup() <= outer[i].sup())
}

/// Finds every cusp in [-π, π]² (see the module doc), depth first on one thread, with at most
/// `DEFAULT_MAX_BOXES` boxes.
pub fn search<M: TorusMap + ?Sized>(chain: &M, settings: &CuspSettings) -> Result<CuspSearch, super::Manip3rError> {
    let control = Control::with_limits(Limits { max_cells: DEFAULT_MAX_BOXES, ..Limits::default() });
    search_with(chain, settings, &control, &mut no_progress)
}

/// Finds every cusp in [-π, π]² within `control`, reporting progress.
pub fn search_with<M: TorusMap + ?Sized>(chain: &M, settings: &CuspSettings, control: &Control, progress: &mut dyn FnMut(&Progress)) -> Result<CuspSearch, super::Manip3rError> {
    super::check_precision(settings.precision)?;
    let t0 = Instant::now();
    let eps = settings.precision;
    let (bands, walk) = chain.bands(eps, control);
    let start = CuspCell { theta: [motion::full_range(), motion::full_range()], order: Order::ROOT, level: 0 };
    let Outcome { status, stats, found, undecided: pending, workers } = drive_shared(|| CuspPrune { chain, bands: &bands, eps, method: settings.method, contracted: 0 }, start, &control.remaining_since(t0), progress);
    // A walk for the strips cut short leaves the answer incomplete, whatever the search did.
    let status = walk.and(status);
    // Each process counted the boxes it decided.
    let contracted = search::total(&[workers.iter().map(|p| p.contracted).sum::<u64>() as f64])[0] as u64;
    drop(workers);
    // The decisions that look at other cusps, in depth-first order (see `drive`).
    enum Event {
        Found(CuspFound),
        Undecided(CuspCell, search::Undecided),
    }
    let mut events: Vec<(Order, Event)> = found.into_iter().map(|f| (f.order, Event::Found(f))).collect();
    events.extend(pending.into_iter().map(|(c, why)| (c.order, Event::Undecided(c, why))));
    events.sort_by_key(|(order, _)| *order);
    let mut cusps: Vec<Cusp> = Vec::new();
    let mut undecided = Vec::new();
    for (_, event) in events {
        // A box inside one already proven to hold exactly one cusp holds nothing more.
        let proven = |cusps: &[Cusp], b: &[Interval; 2]| cusps.iter().any(|c| c.unique && inside(&c.theta, b));
        match event {
            Event::Undecided(cell, why) => {
                if !proven(&cusps, &cell.theta) {
                    undecided.push(Undecided { theta: cell.theta, reason: reason(why) });
                }
            }
            Event::Found(f) if proven(&cusps, &f.source) => {}
            Event::Found(CuspFound { theta, proof: Proof::Krawczyk, .. }) => {
                // Proven boxes lie in disjoint box interiors; only the ±π seam, where the range
                // overlaps itself by an ulp, can show one cusp twice.
                if !cusps.iter().any(|c| meet_across_seam(&c.theta, &theta)) {
                    let j = TorusMap::jets(chain, theta, 0);
                    cusps.push(Cusp { theta, rho: j.rho.value(), z: j.z.value(), unique: true });
                }
            }
            Event::Found(CuspFound { theta, proof: Proof::Inflated(k), .. }) => {
                let j = TorusMap::jets(chain, theta, 0);
                // A second proof of an overlapping box is the same cusp only if the hull is
                // proven too; otherwise both are kept, marked not unique.
                match cusps.iter().position(|c| (0..2).all(|i| !c.theta[i].disjoint(theta[i]))) {
                    None => cusps.push(Cusp { theta, rho: j.rho.value(), z: j.z.value(), unique: true }),
                    Some(at) => {
                        let hull = [cusps[at].theta[0].convex_hull(theta[0]), cusps[at].theta[1].convex_hull(theta[1])];
                        match inflate(chain, hull, k) {
                            Some(h) => {
                                let j = TorusMap::jets(chain, h, 0);
                                cusps[at] = Cusp { theta: h, rho: j.rho.value(), z: j.z.value(), unique: true };
                            }
                            None => {
                                cusps[at].unique = false;
                                cusps.push(Cusp { theta, rho: j.rho.value(), z: j.z.value(), unique: false });
                            }
                        }
                    }
                }
            }
            Event::Found(CuspFound { theta, proof: Proof::Candidate, .. }) => {
                let j = TorusMap::jets(chain, theta, 0);
                cusps.push(Cusp { theta, rho: j.rho.value(), z: j.z.value(), unique: false });
            }
        }
    }
    if settings.method == Method::Bisection {
        cusps = merge_candidates(chain, cusps);
    }
    Ok(CuspSearch { cusps, undecided, bands, status, stats, contracted, seconds: t0.elapsed().as_secs_f64() })
}

/// Merges touching candidate boxes (baseline only) into one hull per cluster, listed by their
/// first candidate.
fn merge_candidates<M: TorusMap + ?Sized>(chain: &M, boxes: Vec<Cusp>) -> Vec<Cusp> {
    let thetas: Vec<[Interval; 2]> = boxes.iter().map(|c| c.theta).collect();
    let hull = |a: &[Interval; 2], b: &[Interval; 2]| (0..2).all(|d| !a[d].disjoint(b[d])).then(|| [a[0].convex_hull(b[0]), a[1].convex_hull(b[1])]);
    merge_touching(&thetas, hull)
        .into_iter()
        .map(|(theta, _)| {
            let j = TorusMap::jets(chain, theta, 0);
            Cusp { theta, rho: j.rho.value(), z: j.z.value(), unique: false }
        })
        .collect()
}

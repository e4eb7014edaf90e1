//! Nodes: pairs of distinct singular points with the same image, the system (3) of Benoit,
//! Delanoue, Lagrange and Wenger (2019).
//!
//! The search runs on pairs of boxes `(P, Q)` of a binary tree over [-π, π]² (unordered, `P = Q`
//! allowed), starting from the pair (whole range, whole range). A pair is dropped when
//!
//! 1. det Df ≠ 0 on `P` or on `Q` (proven), or their images are disjoint;
//! 2. f restricted to the singular set `S` is proven injective on the hull `H` of `P ∪ Q`
//!    (taken across the ±π seam when shorter). Two certificates:
//!    - **mean value**: for a direction `m` of the workspace, the interval matrix with rows
//!      `∇det(H)` and `mᵀDf(H)` is regular, i.e. `0 ∉ ∇det(H) × mᵀDf(H)`. If `x₁, x₂ ∈ S ∩ H`
//!      had the same image, the mean value theorem along the segment gives `MΔ = 0` for some
//!      `M` in that matrix and `Δ = x₂ − x₁`, so `Δ = 0`. No connectivity of `S ∩ H` is needed.
//!      This fails near cusps, where `m·g` vanishes for every `m`.
//!    - **cusp**: around each certified cusp `c` a box `U` where (a) `∇det ≠ 0`, (b) `S ∩ U` is
//!      one arc (`∂det/∂θ₃ ≠ 0` on `U` and `det ≠ 0` on its lower and upper edges, or the same
//!      with θ₂), and (c) `0 ∉ F''(U) × F'''(U)`, where `F(s) = f(γ(s))` along the flow
//!      `γ' = T(γ)` of the tangent field `T = (−∂det/∂θ₃, ∂det/∂θ₂)`, so `F' = Df·T = g`,
//!      `F'' = ∇g·T`, `F''' = ∇(∇g·T)·T` (fourth-order jets). Then with `F'(c) = 0`,
//!      `F''(c) × (F(b) − F(a)) = ∫ₐᵇ ∫_c^σ (σ − τ) F''(c) × F'''(τ) dτ dσ`, whose weight is
//!      positive for `a < b`: no two points of the arc share an image. Pairs inside `U` go.
//! 3. Krawczyk on the four equations `f(x₁) − f(x₂) = 0, det(x₁) = 0, det(x₂) = 0` over
//!    `P × Q` proves there is no zero (dropped) or exactly one (a node, when `P` and `Q` are
//!    disjoint on the torus, so `x₁ ≠ x₂`).
//!
//! Otherwise the wider box is bisected (`P = Q` gives three pairs). So the diagonal `x₁ = x₂`,
//! a whole curve of zeros of system (3), never reaches Krawczyk, and no separation constraint
//! between the two points is assumed: every node, however close its two points, is found.
//! Pairs touching an internal-motion strip are set aside.

use super::map::TorusMap;
use super::cusps::{self, evaluate_without_tangency as evaluate, meet_on_torus, BoxEval, Cusp};
use super::drive::{drive, no_progress, Order};
use crate::kernel::search::Control;
use crate::kernel::contract::krawczyk::{self, Step as K};
use super::motion::{self, Band};
use crate::kernel::interval::{interval, point, strict_sign};
use crate::kernel::search::{Limit, Limits, Progress, Prune, Stats, Status, Step, Store};
use std::ops::ControlFlow;
use inari::Interval;
use smallvec::SmallVec;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;
use std::time::Instant;

mod settle;

use self::settle::settle;

/// Settings of a node search (its bounds are a `Control`).
#[derive(Clone, Copy, Debug)]
pub struct NodeSettings {
    /// Largest width of a reported box (radians); undecided pairs are at most this wide.
    pub precision: f64,
}

impl Default for NodeSettings {
    fn default() -> Self {
        NodeSettings { precision: 1e-4 }
    }
}

/// Pairs a node search processes at most unless told otherwise (`search`).
pub const DEFAULT_MAX_PAIRS: u64 = 20_000_000;

/// A certified node: exactly one pair of singular points `x₁ ∈ theta[0]`, `x₂ ∈ theta[1]` with
/// `f(x₁) = f(x₂)`.
#[derive(Clone, Copy, Debug)]
pub struct Node {
    /// The two joint boxes.
    pub theta: [[Interval; 2]; 2],
    /// ρ of the shared image.
    pub rho: Interval,
    /// z of the shared image.
    pub z: Interval,
}

/// The outcome of a node search.
#[derive(Clone, Debug)]
pub struct NodeSearch {
    /// Certified nodes, one per node point.
    pub nodes: Vec<Node>,
    /// Undecided pairs of boxes.
    pub undecided: Vec<[[Interval; 2]; 2]>,
    /// `Complete` when every pair was decided or set aside; otherwise the limit that stopped it.
    pub status: Status,
    /// The kernel's counters (pairs); discards by reason: `regular`, `in_strips`, `apart`,
    /// `near_cusp`, `injective`, `krawczyk_empty`.
    pub stats: Stats,
    /// Boxes of the tree.
    pub cells: u64,
    /// Cusp neighbourhoods certified (of all cusps given).
    pub cusp_regions: u64,
    /// Clusters of pairs left at the precision that were settled afterwards (`settle`): a
    /// node proven in a box holding the whole cluster.
    pub settled: u64,
    /// Wall-clock seconds, the cusp neighbourhoods included.
    pub seconds: f64,
}

/// Why a pair is left undecided when the box tree reached the memory limit.
const TREE_FULL: &str = "memory";

/// A box of the binary tree over [-π, π]², with its enclosures computed once: a box meets
/// many others in pairs. The tree grows as the search asks for children (`children`); workers
/// share it, and the children of a box are the same whoever makes them. Boxes are never freed
/// before the search ends, so cells hold plain references (no reference counts to update in
/// the inner loop).
struct TreeBox {
    b: [Interval; 2],
    eval: BoxEval,
    singular: bool,
    in_strip: bool,
    children: OnceLock<[Box<TreeBox>; 2]>,
}

/// What the workers of a node search share.
struct Tree<'a, M: TorusMap + ?Sized> {
    chain: &'a M,
    bands: &'a [Band],
    /// Cusp neighbourhoods on which f restricted to S is proven injective.
    regions: &'a [[Interval; 2]],
    eps: f64,
    /// Boxes made so far.
    boxes: AtomicU64,
    /// Boxes the tree may hold: the run's memory limit (`Limits::max_memory`) covers the tree,
    /// which is kept whole until the run ends, as well as the pending pairs.
    max_boxes: u64,
}

impl<M: TorusMap + ?Sized> Tree<'_, M> {
    fn make(&self, b: [Interval; 2]) -> Box<TreeBox> {
        self.boxes.fetch_add(1, Ordering::Relaxed);
        let eval = evaluate(self.chain, b);
        let in_strip = self.bands.iter().any(|band| band.holds(b[1]));
        Box::new(TreeBox { b, eval, singular: eval.det.contains(0.0), in_strip, children: OnceLock::new() })
    }

    /// The singular children of `x` (made on first use).
    fn children<'r>(&self, x: &'r TreeBox) -> SmallVec<[&'r TreeBox; 2]> {
        let ch = x.children.get_or_init(|| {
            let (lo, hi) = cusps::bisect(x.b, motion::straddles(self.bands, x.b[1]));
            [self.make(lo), self.make(hi)]
        });
        ch.iter().map(|c| &**c).filter(|c| c.singular).collect()
    }
}

/// A pair of tree boxes (`p` may be `q`), with the smallest tree box holding both: its cached
/// enclosures hold on their hull. When `p` is split, the pairs `(child, q)` keep that box (`q`
/// is never inside `p`); the pairs of `p` with itself get `p`, or the child itself.
#[derive(Clone, Copy)]
pub struct NodeCell<'r> {
    p: &'r TreeBox,
    q: &'r TreeBox,
    ancestor: &'r TreeBox,
    order: Order,
    level: u32,
}

impl NodeCell<'_> {
    /// The two joint boxes.
    pub fn boxes(&self) -> [[Interval; 2]; 2] {
        [self.p.b, self.q.b]
    }
}

/// A node proven in one pair, before the seam check against the others.
pub struct NodeFound {
    order: Order,
    node: Node,
}

fn width(b: &[Interval; 2]) -> f64 {
    b[0].wid().max(b[1].wid())
}

/// `q` shifted by multiples of 2π per coordinate so that its hull with `p` is smallest.
fn nearest_copy(p: &[Interval; 2], q: &[Interval; 2]) -> [Interval; 2] {
    let tau = Interval::TAU;
    [0, 1].map(|i| {
        [q[i], q[i] + tau, q[i] - tau]
            .into_iter()
            .min_by(|a, b| p[i].convex_hull(*a).wid().total_cmp(&p[i].convex_hull(*b).wid()))
            .expect("three candidates")
    })
}

/// The mean-value injectivity certificate on `h` (see the module doc); `tangent` is the image
/// tangent `g` somewhere near `h`, the first direction tried.
fn injective_mean_value<M: TorusMap + ?Sized>(chain: &M, h: [Interval; 2], tangent: [Interval; 2]) -> bool {
    let d = chain.derived(h, 2);
    let df = [[d.df[0][0].value(), d.df[0][1].value()], [d.df[1][0].value(), d.df[1][1].value()]];
    injective_from(d.det.grad(), df, tangent)
}

/// The mean-value certificate from enclosures of ∇det and Df over a box holding the hull.
fn injective_from(grad_det: [Interval; 2], df: [[Interval; 2]; 2], tangent: [Interval; 2]) -> bool {
    // Directions: the image tangent at the midpoint (best where it is known), then the axes.
    let g = [tangent[0].mid(), tangent[1].mid()];
    let norm = (g[0] * g[0] + g[1] * g[1]).sqrt();
    let along = if norm.is_finite() && norm > 0.0 { Some([g[0] / norm, g[1] / norm]) } else { None };
    along.into_iter().chain([[1.0, 0.0], [0.0, 1.0]]).any(|m| {
        let row = [point(m[0]) * df[0][0] + point(m[1]) * df[1][0], point(m[0]) * df[0][1] + point(m[1]) * df[1][1]];
        let cross = grad_det[0] * row[1] - grad_det[1] * row[0];
        !cross.contains(0.0)
    })
}

/// A part of a cusp neighbourhood, with the bisections left to it.
#[derive(Clone, Copy, Debug)]
struct Part {
    b: [Interval; 2],
    depth: u32,
}

/// Why a part leaves the check of a certificate condition: the condition holds on it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Holds;

impl crate::kernel::search::Reason for Holds {
    fn name(self) -> &'static str {
        "holds"
    }
}

/// The check of one certificate condition on the kernel: a part goes when `test` holds on it,
/// is bisected while it has depth left, and is left undecided (the condition fails) otherwise.
struct ConditionPrune<T> {
    test: T,
}

impl<T: FnMut(&[Interval; 2]) -> bool> Prune for ConditionPrune<T> {
    type Cell = Part;
    type Found = std::convert::Infallible;
    type Reason = Holds;

    fn process(&mut self, part: Part) -> Step<Part, Self::Found, Holds> {
        if (self.test)(&part.b) {
            Step::Discard(Holds)
        } else if part.depth == 0 {
            Step::Undecided(part, "fails")
        } else {
            let (lo, hi) = cusps::bisect(part.b, false);
            Step::Split(smallvec::smallvec![Part { b: lo, depth: part.depth - 1 }, Part { b: hi, depth: part.depth - 1 }])
        }
    }
}

/// Stops a condition's check at the first part where it fails.
struct FirstFailure;

impl crate::kernel::search::Sink<Part, std::convert::Infallible> for FirstFailure {
    fn found(&mut self, found: std::convert::Infallible) -> ControlFlow<()> {
        match found {}
    }

    fn undecided(&mut self, _: Part, _: crate::kernel::search::Undecided) -> ControlFlow<()> {
        ControlFlow::Break(())
    }
}

/// Whether `test` holds on every part of `b`, trying `b` whole and then its halves down to
/// `DEPTH` bisections, depth first (halves in order): the conditions of the cusp certificate are
/// local, so most of a neighbourhood is decided on large cells and only the hard spots are
/// refined. `Err` names the limit of `control` (the time left since `start`, the cancel flag)
/// that stopped the check first; its own cell budget is one full tree of `DEPTH` bisections.
fn everywhere(b: [Interval; 2], control: &Control, start: Instant, test: impl FnMut(&[Interval; 2]) -> bool) -> Result<bool, Limit> {
    let control = control.remaining_since(start);
    let limits = Limits { max_cells: CONDITION_CELLS, ..control.limits };
    let (status, _) = crate::kernel::search::run(&mut ConditionPrune { test }, Part { b, depth: DEPTH }, Store::DepthFirst, &limits, control.cancel, &mut FirstFailure);
    match status {
        Status::Finished => Ok(true),
        Status::Stopped(Limit::Sink) => Ok(false),
        Status::Stopped(limit) => Err(limit),
    }
}

/// Widest box of a pair on which the node search tries Krawczyk (radians).
const KRAWCZYK_WIDTH: f64 = 1.0;

/// Bisections allowed per certificate condition: cells down to 1/256 of the neighbourhood. The
/// larger the neighbourhood certified, the fewer pairs near the cusp are left to the mean-value
/// certificate, which fails there; at 1/64 the 3-RPR's cusp neighbourhoods stopped short of the
/// pairs the search reaches at its precision, which stayed undecided.
const DEPTH: u32 = 16;

/// Cells of one condition's check at most: the full tree of `DEPTH` bisections.
const CONDITION_CELLS: u64 = (2 << DEPTH) - 1;

/// F'' = ∇g·T and F''' = ∇(∇g·T)·T over `b` (see the module doc).
fn flow_derivatives<M: TorusMap + ?Sized>(chain: &M, b: [Interval; 2]) -> ([Interval; 2], [Interval; 2]) {
    let jets = chain.derived(b, 4);
    let t = [-jets.det.d(1), jets.det.d(0)];
    let along = |h: &crate::kernel::taylor::Taylor| h.d(0) * t[0] + h.d(1) * t[1];
    let f2 = [along(&jets.g[0]), along(&jets.g[1])];
    ([f2[0].value(), f2[1].value()], [along(&f2[0]).value(), along(&f2[1]).value()])
}

/// The cusp certificate on `u` around the certified cusp box `c` ⊂ `u` (see the module doc).
/// Each condition is checked on adaptive sub-boxes (`everywhere`), with one strict sign over
/// all of them, and F''(c) on the cusp box itself, which keeps the enclosures tight. `Err`: a
/// limit of `control` stopped a check before the certificate was decided.
pub fn injective_near_cusp<M: TorusMap + ?Sized>(chain: &M, u: [Interval; 2], c: [Interval; 2], control: &Control, start: Instant) -> Result<bool, Limit> {
    let at_c = evaluate(chain, c);
    // (a) and (b): with ∂det/∂θₖ of one strict sign on u, every segment along θₖ meets S at most
    // once; with det ≠ 0 on the two edges θₖ = const, the signs there are fixed, so S ∩ u is
    // empty or one arc across u.
    let mut arc = false;
    for k in 0..2 {
        let Some(s) = strict_sign(at_c.grad_det[k]) else { continue };
        if !everywhere(u, control, start, |b| strict_sign(evaluate(chain, *b).grad_det[k]) == Some(s))? {
            continue;
        }
        let mut edges = true;
        for at in [u[k].inf(), u[k].sup()] {
            let mut edge = u;
            edge[k] = point(at);
            if !everywhere(edge, control, start, |b| !evaluate(chain, *b).det.contains(0.0))? {
                edges = false;
                break;
            }
        }
        if edges {
            arc = true;
            break;
        }
    }
    if !arc {
        return Ok(false);
    }
    // (c) F''(c) × F'''(τ) of one strict sign for τ on S ∩ u.
    let (f2c, f3c) = flow_derivatives(chain, c);
    let Some(want) = strict_sign(f2c[0] * f3c[1] - f2c[1] * f3c[0]) else { return Ok(false) };
    everywhere(u, control, start, |b| {
        if !evaluate(chain, *b).det.contains(0.0) {
            return true;
        }
        let (_, f3) = flow_derivatives(chain, *b);
        strict_sign(f2c[0] * f3[1] - f2c[1] * f3[0]) == Some(want)
    })
}

/// A box around `c` on which `injective_near_cusp` holds, trying radii from 0.4 down by a
/// factor 0.85 (a finer ladder certifies a neighbourhood nearer the largest one that holds); `Err` when
/// a limit stopped the trials.
fn cusp_region<M: TorusMap + ?Sized>(chain: &M, c: &Cusp, control: &Control, start: Instant) -> Result<Option<[Interval; 2]>, Limit> {
    let mut r = 0.4;
    while r > 1e-7 {
        let u = [0, 1].map(|i| interval(c.theta[i].inf() - r, c.theta[i].sup() + r));
        if injective_near_cusp(chain, u, c.theta, control, start)? {
            return Ok(Some(u));
        }
        r *= 0.85;
    }
    Ok(None)
}

fn contains(outer: &[Interval; 2], inner: &[Interval; 2]) -> bool {
    (0..2).all(|i| outer[i].inf() <= inner[i].inf() && inner[i].sup() <= outer[i].sup())
}

/// Krawczyk on system (3) over `p × q`.
fn krawczyk_node(p: &[Interval; 2], ep: &BoxEval, q: &[Interval; 2], eq: &BoxEval) -> K<[Interval; 4]> {
    let b = [p[0], p[1], q[0], q[1]];
    let m = b.map(|x| x.mid());
    let (fm, jac) = node_system(ep, eq);
    krawczyk::step_array(&b, &m, &fm, &jac)
}

/// System (3) at the midpoints of `p × q` and its interval Jacobian over `p × q`, from the two
/// boxes' evaluations: `f(p) − f(q) = 0`, `det(p) = 0`, `det(q) = 0`.
#[inline]
fn node_system(ep: &BoxEval, eq: &BoxEval) -> ([Interval; 4], [[Interval; 4]; 4]) {
    let fm = [ep.f_mid[0] - eq.f_mid[0], ep.f_mid[1] - eq.f_mid[1], ep.det_mid, eq.det_mid];
    let z = point(0.0);
    let jac = [
        [ep.df[0][0], ep.df[0][1], -eq.df[0][0], -eq.df[0][1]],
        [ep.df[1][0], ep.df[1][1], -eq.df[1][0], -eq.df[1][1]],
        [ep.grad_det[0], ep.grad_det[1], z, z],
        [z, z, eq.grad_det[0], eq.grad_det[1]],
    ];
    (fm, jac)
}

/// Krawczyk's image of system (3) over `x = P × Q` (for `krawczyk::inflate`).
fn node_image<M: TorusMap + ?Sized>(chain: &M, x: &[Interval; 4]) -> Option<[Interval; 4]> {
    let (p, q) = ([x[0], x[1]], [x[2], x[3]]);
    let (ep, eq) = (evaluate(chain, p), evaluate(chain, q));
    let m = x.map(|d| d.mid());
    let (fm, jac) = node_system(&ep, &eq);
    krawczyk::image_array(x, &m, &fm, &jac)
}

/// Shrinks a proven node to the precision.
fn refine<M: TorusMap + ?Sized>(chain: &M, p: [Interval; 2], q: [Interval; 2], precision: f64) -> ([Interval; 2], [Interval; 2]) {
    let k = krawczyk::tighten([p[0], p[1], q[0], q[1]], precision, |k| {
        let (p, q) = ([k[0], k[1]], [k[2], k[3]]);
        krawczyk_node(&p, &evaluate(chain, p), &q, &evaluate(chain, q))
    });
    ([k[0], k[1]], [k[2], k[3]])
}

/// The node test of the module doc, one pair at a time.
struct NodePrune<'t, 'a, 'r, M: TorusMap + ?Sized> {
    tree: &'t Tree<'a, M>,
    _boxes: std::marker::PhantomData<&'r TreeBox>,
}

/// Why the node search discards a pair of boxes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeDiscard {
    /// det Df ≠ 0 on one of the boxes.
    Regular,
    /// A box lies in an internal-motion strip.
    InStrips,
    /// Their images are disjoint.
    Apart,
    /// A cusp-neighbourhood certificate excludes a node there.
    NearCusp,
    /// The mean-value injectivity certificate holds on them.
    Injective,
    /// Krawczyk proves the pair holds no node.
    KrawczykEmpty,
}

impl crate::kernel::search::Reason for NodeDiscard {
    fn name(self) -> &'static str {
        match self {
            NodeDiscard::Regular => "regular",
            NodeDiscard::InStrips => "in_strips",
            NodeDiscard::Apart => "apart",
            NodeDiscard::NearCusp => "near_cusp",
            NodeDiscard::Injective => "injective",
            NodeDiscard::KrawczykEmpty => "krawczyk_empty",
        }
    }
}


impl<'r, M: TorusMap + ?Sized> Prune for NodePrune<'_, '_, 'r, M> {
    type Cell = NodeCell<'r>;
    type Found = NodeFound;
    type Reason = NodeDiscard;

    fn process(&mut self, cell: NodeCell<'r>) -> Step<NodeCell<'r>, NodeFound, NodeDiscard> {
        let tree = self.tree;
        let (chain, eps) = (tree.chain, tree.eps);
        let (p, q) = (cell.p, cell.q);
        let same = std::ptr::eq(p, q);
        if !p.singular || !q.singular {
            return Step::Discard(NodeDiscard::Regular);
        }
        if p.in_strip || q.in_strip {
            return Step::Discard(NodeDiscard::InStrips);
        }
        if (0..2).any(|k| p.eval.f[k].disjoint(q.eval.f[k])) {
            return Step::Discard(NodeDiscard::Apart);
        }
        let (pb, qb) = (p.b, q.b);
        let near = nearest_copy(&pb, &qb);
        let hull = [pb[0].convex_hull(near[0]), pb[1].convex_hull(near[1])];
        if tree.regions.iter().any(|u| contains(u, &hull)) {
            return Step::Discard(NodeDiscard::NearCusp);
        }
        let disjoint = !same && !meet_on_torus(&pb, &qb);
        // The smallest tree box holding both boxes holds their hull too (unless the hull goes
        // across the ±π seam); its cached enclosures often already prove injectivity, for
        // siblings and for a box with itself exactly on the hull.
        let unshifted = near[0] == qb[0] && near[1] == qb[1];
        let g_mid = p.eval.g_mid;
        let injective = || {
            if unshifted {
                let e = &cell.ancestor.eval;
                if injective_from(e.grad_det, e.df, g_mid) {
                    return true;
                }
            }
            // Enclosures over the hull contain those over each box, so the certificate can
            // only hold on the hull if it holds on both boxes (cached): skip hopeless hulls.
            let (ep, eq) = (&p.eval, &q.eval);
            if !(injective_from(ep.grad_det, ep.df, g_mid) && injective_from(eq.grad_det, eq.df, g_mid)) {
                return false;
            }
            injective_mean_value(chain, hull, g_mid)
        };
        // Far pairs first meet Krawczyk, which is cheap on cached evaluations; near ones the
        // injectivity certificate, for which Krawczyk cannot work (the diagonal is a curve of zeros).
        if !disjoint && injective() {
            return Step::Discard(NodeDiscard::Injective);
        }
        // Krawczyk only below a width: on the bundled robots it never concluded on boxes a
        // radian wide or more (thousands of calls on robot f), as its linearisation is too loose.
        if disjoint && width(&pb).max(width(&qb)) < KRAWCZYK_WIDTH {
            match krawczyk_node(&pb, &p.eval, &qb, &q.eval) {
                K::Empty => return Step::Discard(NodeDiscard::KrawczykEmpty),
                K::Unique(k) => {
                    let (a, b) = refine(chain, [k[0], k[1]], [k[2], k[3]], eps);
                    let (ja, jb) = (TorusMap::jets(chain, a, 0), TorusMap::jets(chain, b, 0));
                    let node = Node { theta: [a, b], rho: ja.rho.value().intersection(jb.rho.value()), z: ja.z.value().intersection(jb.z.value()) };
                    return Step::Found(NodeFound { order: cell.order, node });
                }
                _ => {}
            }
            if width(&hull) < 0.5 && injective() {
                return Step::Discard(NodeDiscard::Injective);
            }
        }
        let (wp, wq) = (width(&pb), width(&qb));
        if wp.max(wq) <= eps {
            return Step::Undecided(cell, "precision");
        }
        // A full tree splits no more: the pair stays undecided and the run is reported
        // stopped by its memory limit.
        if tree.boxes.load(Ordering::Relaxed) >= tree.max_boxes {
            return Step::Undecided(cell, TREE_FULL);
        }
        // Children in the order the depth-first walk explores them: the loop this replaces
        // pushed the pairs on a stack and took the last first.
        let (level, order) = (cell.level + 1, cell.order);
        let pair = |p, q, ancestor, i, n| NodeCell { p, q, ancestor, order: order.child(i, n), level };
        let mut next: SmallVec<[NodeCell<'r>; 4]> = SmallVec::new();
        if same {
            match tree.children(p).as_slice() {
                [] => {}
                &[a] => next.push(pair(a, a, a, 0, 1)),
                &[a, b] => {
                    next.push(pair(b, b, b, 0, 3));
                    next.push(pair(a, b, p, 1, 3));
                    next.push(pair(a, a, a, 2, 3));
                }
                _ => unreachable!("a box has two children"),
            }
        } else if wp >= wq {
            let ch = tree.children(p);
            let n = ch.len();
            next.extend(ch.into_iter().rev().enumerate().map(|(i, a)| pair(a, q, cell.ancestor, i, n)));
        } else {
            let ch = tree.children(q);
            let n = ch.len();
            next.extend(ch.into_iter().rev().enumerate().map(|(i, b)| pair(p, b, cell.ancestor, i, n)));
        }
        Step::Split(next)
    }

    fn level(&self, cell: &NodeCell<'r>) -> u32 {
        cell.level
    }
}

/// Finds every node whose two points lie outside the internal-motion strips, depth first on
/// one thread with at most `DEFAULT_MAX_PAIRS` pairs. `cusps` are the certified cusps (from
/// `cusps::search` at any precision); they let pairs near a cusp go.
pub fn search<M: TorusMap + ?Sized>(chain: &M, cusps: &[Cusp], bands: &[Band], settings: &NodeSettings) -> Result<NodeSearch, super::Manip3rError> {
    let control = Control::with_limits(Limits { max_cells: DEFAULT_MAX_PAIRS, ..Limits::default() });
    search_with(chain, cusps, bands, settings, &control, &mut no_progress)
}

/// As `search`, within `control`, reporting progress. The cusp neighbourhoods are certified
/// first, on `control.threads` threads.
pub fn search_with<M: TorusMap + ?Sized>(chain: &M, cusps: &[Cusp], bands: &[Band], settings: &NodeSettings, control: &Control, progress: &mut dyn FnMut(&Progress)) -> Result<NodeSearch, super::Manip3rError> {
    super::check_precision(settings.precision)?;
    let start = Instant::now();
    let unique: Vec<&Cusp> = cusps.iter().filter(|c| c.unique).collect();
    // A neighbourhood a limit left uncertified only lets fewer pairs go; the limit is reported.
    let mut regions: Vec<[Interval; 2]> = Vec::new();
    let mut certificates = Status::Finished;
    for region in crate::kernel::search::map_parallel(&unique, control.threads, |c| cusp_region(chain, c, control, start)) {
        match region {
            Ok(u) => regions.extend(u),
            Err(limit) => certificates = certificates.and(Status::Stopped(limit)),
        }
    }
    // One deadline: the pair search gets what the certificates left.
    let control = &control.remaining_since(start);
    let max_boxes = (control.limits.max_memory / std::mem::size_of::<TreeBox>()) as u64;
    let tree = Tree { chain, bands, regions: &regions, eps: settings.precision, boxes: AtomicU64::new(0), max_boxes };
    let root = tree.make([motion::full_range(), motion::full_range()]);
    let start_cell = NodeCell { p: &root, q: &root, ancestor: &root, order: Order::ROOT, level: 0 };
    let mut run = drive(|| NodePrune { tree: &tree, _boxes: std::marker::PhantomData }, start_cell, control, progress);
    run.status = certificates.and(run.status);
    if run.undecided.iter().any(|(_, why)| *why == crate::kernel::search::Undecided::Precision(TREE_FULL)) {
        run.status = run.status.and(Status::Stopped(Limit::Memory));
    }
    // Only the ±π seam (where the range overlaps itself by an ulp) can repeat a node: the first
    // in depth-first order is kept.
    run.found.sort_by_key(|f| f.order);
    let mut nodes: Vec<Node> = Vec::new();
    for NodeFound { node, .. } in run.found {
        let [a, b] = node.theta;
        let seen = nodes.iter().any(|n| (meet_on_torus(&n.theta[0], &a) && meet_on_torus(&n.theta[1], &b)) || (meet_on_torus(&n.theta[0], &b) && meet_on_torus(&n.theta[1], &a)));
        if !seen {
            nodes.push(node);
        }
    }
    run.undecided.sort_by_key(|(c, _)| c.order);
    let cells = tree.boxes.load(Ordering::Relaxed);
    // Pairs a limit left pending are not settled: they are not at the precision, and the
    // limit's reason must stand.
    let pairs: Vec<[[Interval; 2]; 2]> = run.undecided.iter().map(|(c, _)| c.boxes()).collect();
    let eligible: Vec<bool> = run.undecided.iter().map(|(_, why)| matches!(why, crate::kernel::search::Undecided::Precision(r) if *r != TREE_FULL)).collect();
    let (keep, settled) = settle(chain, settings.precision, &mut nodes, &pairs, &eligible);
    let undecided = pairs.into_iter().zip(keep).filter_map(|(p, k)| k.then_some(p)).collect();
    Ok(NodeSearch { nodes, undecided, status: run.status, stats: run.stats, cells, cusp_regions: regions.len() as u64, settled, seconds: start.elapsed().as_secs_f64() })
}

#[cfg(test)]
mod tests;

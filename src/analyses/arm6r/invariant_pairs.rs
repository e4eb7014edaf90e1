//! The first phase of the 6R inverse kinematics (`ik`) as a traversal of pairs of boxes.
//!
//! The five invariants of axis 4 seen from axis 1 are `f(θ₂, θ₃) = g(θ₆, θ₅)`: each side
//! depends on two joints only. A 4-dimensional box of joints 2, 3, 5, 6 is a pair (left box,
//! right box), and the test that discards it compares an enclosure of `f` over the left box
//! with one of `g` over the right box, row by row. Each side's boxes form a binary tree
//! (halves of halves of the joint ranges), and a box's enclosure is computed once, when the
//! box is first met, whatever pairs it is part of: measured on a general 6R, the pairs
//! processed outnumber the distinct boxes of either side 20 to 70 times, so the test of a pair
//! costs ten comparisons instead of two evaluations of the invariants.
//!
//! A box's enclosure is its natural enclosure intersected with its mean-value form (both hold
//! every value over the box), and once the box is halved, intersected with the hull of its
//! halves' enclosures (measured: half the pairs examined). A pair with disjoint enclosures in some row holds no solution.
//! The wider of the two boxes of a surviving pair is halved (across the joint whose width moves
//! its invariants most) until both are `narrow`; such pairs are the traversal's leaves. No IO;
//! the caller bounds the work (`budget`, `stop`) and gets back the pairs not yet decided.

use super::ik::{Axis4Sides, Half, INVARIANTS};
use crate::kernel::contract::krawczyk;
use crate::kernel::interval::fast::Iv;
use crate::kernel::interval::{interval, Interval};
use nalgebra::SVector;

/// A box of one side's two joints, its enclosure of the invariants, and its children.
#[derive(Clone, Copy, Debug)]
struct Node {
    b: [[f64; 2]; 2],
    enc: [Iv; INVARIANTS],
    /// The joint (0 or 1) whose halving moves the invariants most.
    cut: usize,
    /// Index of the first of its two children in the tree, once made (0: not yet).
    children: u32,
}

/// One side's binary tree of boxes, made as the traversal needs them.
struct Tree<'a> {
    sides: &'a Axis4Sides,
    half: Half,
    nodes: Vec<Node>,
}

impl<'a> Tree<'a> {
    fn new(sides: &'a Axis4Sides, half: Half, b: [[f64; 2]; 2]) -> Tree<'a> {
        let mut tree = Tree { sides, half, nodes: Vec::new() };
        let root = tree.node(b);
        tree.nodes.push(root);
        tree
    }

    /// The enclosure of the invariants over `b`: natural ∩ mean-value form.
    fn node(&self, b: [[f64; 2]; 2]) -> Node {
        let over = self.sides.value(self.half, &b, true);
        let m = b.map(|x| 0.5 * (x[0] + x[1]));
        let at = self.sides.value(self.half, &m.map(|x| [x, x]), false);
        let dx = [0, 1].map(|k| Iv { lo: b[k][0], hi: b[k][1] }.sub(Iv { lo: m[k], hi: m[k] }));
        let enc: [Iv; INVARIANTS] = std::array::from_fn(|i| {
            let natural = over.inv[i];
            let form = at.inv[i].add(over.cols[0][i].mul(dx[0])).add(over.cols[1][i].mul(dx[1]));
            // Both enclose every value over the box, so they meet; should rounding ever leave
            // them apart, the natural one is kept.
            let meet = Iv { lo: natural.lo.max(form.lo), hi: natural.hi.min(form.hi) };
            if meet.lo <= meet.hi {
                meet
            } else {
                natural
            }
        });
        let smear = |k: usize| (0..INVARIANTS).map(|i| over.cols[k][i].lo.abs().max(over.cols[k][i].hi.abs())).sum::<f64>() * (b[k][1] - b[k][0]);
        let (s0, s1) = (smear(0), smear(1));
        let cut = if s0.is_finite() && s1.is_finite() && (s0 > 0.0 || s1 > 0.0) {
            usize::from(s1 > s0)
        } else {
            usize::from(b[1][1] - b[1][0] > b[0][1] - b[0][0])
        };
        Node { b, enc, cut, children: 0 }
    }

    fn width(&self, n: u32) -> f64 {
        let b = &self.nodes[n as usize].b;
        (b[0][1] - b[0][0]).max(b[1][1] - b[1][0])
    }

    /// The two halves of node `n`, made on first use.
    fn children(&mut self, n: u32) -> [u32; 2] {
        let node = self.nodes[n as usize];
        if node.children == 0 {
            let (k, b) = (node.cut, node.b);
            let c = 0.5 * (b[k][0] + b[k][1]);
            let (mut lo, mut hi) = (b, b);
            lo[k][1] = c;
            hi[k][0] = c;
            let first = self.nodes.len() as u32;
            let (lo, hi) = (self.node(lo), self.node(hi));
            // Every value over the box is one over a half: the hull of the halves' enclosures
            // holds them all, and is often tighter (for the pairs still to meet this box).
            let enc = std::array::from_fn(|i| {
                let e = node.enc[i];
                Iv { lo: e.lo.max(lo.enc[i].lo.min(hi.enc[i].lo)), hi: e.hi.min(lo.enc[i].hi.max(hi.enc[i].hi)) }
            });
            self.nodes.push(lo);
            self.nodes.push(hi);
            self.nodes[n as usize].children = first;
            self.nodes[n as usize].enc = enc;
        }
        let first = self.nodes[n as usize].children;
        [first, first + 1]
    }
}

/// A left box (joints 2, 3) and a right box (joints 6, 5).
pub(super) type Pair = ([[f64; 2]; 2], [[f64; 2]; 2]);

/// Pairs of boxes that may hold solutions.
#[derive(Debug, Default)]
pub(super) struct Pairs {
    /// Pairs with both boxes at most `narrow` wide.
    pub leaves: Vec<Pair>,
    /// Pairs not examined when the budget ran out or `stop` said so.
    pub pending: Vec<Pair>,
    /// Pairs examined.
    pub examined: u64,
    /// Pairs discarded (their enclosures disjoint in some row).
    pub discarded: u64,
}

/// How much work a traversal may do before it hands its pending pairs back.
#[derive(Clone, Copy, Debug)]
pub(super) struct Budget {
    /// Pairs examined.
    pub pairs: u64,
    /// Boxes made on either side (each holds its enclosure: about 130 bytes).
    pub boxes: usize,
}

/// Pairs `narrow` wide that `contract_leaf` neither discards nor narrows are halved on down
/// to `narrow / FINER`.
const FINER: f64 = 8.0;

/// How often (pairs examined) the traversal asks `stop`.
const STOP_EVERY: u64 = 4096;

/// Every pair of a left box within `left` (joints 2, 3) and a right box within `right` (joints
/// 6, 5) that may hold a solution of the invariants, each side halved down to `narrow`
/// (radians). Once `budget` is spent, pairs not examined then, or once `stop`
/// says so, are returned as `pending`, none lost.
pub(super) fn pairs(sides: &Axis4Sides, left: [[f64; 2]; 2], right: [[f64; 2]; 2], narrow: f64, budget: Budget, stop: &dyn Fn() -> bool) -> Pairs {
    let mut trees = [Tree::new(sides, Half::Left, left), Tree::new(sides, Half::Right, right)];
    let mut out = Pairs::default();
    let mut stack: Vec<[u32; 2]> = vec![[0, 0]];
    while let Some(pair) = stack.pop() {
        let spent = out.examined >= budget.pairs || trees.iter().any(|t| t.nodes.len() >= budget.boxes);
        if spent || (out.examined % STOP_EVERY == 0 && out.examined > 0 && stop()) {
            stack.push(pair);
            out.pending = stack.iter().map(|&[a, b]| (trees[0].nodes[a as usize].b, trees[1].nodes[b as usize].b)).collect();
            break;
        }
        out.examined += 1;
        let (ea, eb) = (&trees[0].nodes[pair[0] as usize].enc, &trees[1].nodes[pair[1] as usize].enc);
        if (0..INVARIANTS).any(|i| ea[i].hi < eb[i].lo || eb[i].hi < ea[i].lo) {
            out.discarded += 1;
            continue;
        }
        let (wa, wb) = (trees[0].width(pair[0]), trees[1].width(pair[1]));
        if wa <= narrow && wb <= narrow {
            let boxes = (trees[0].nodes[pair[0] as usize].b, trees[1].nodes[pair[1] as usize].b);
            match contract_leaf(sides, &boxes) {
                None => {
                    out.discarded += 1;
                    continue;
                }
                // Narrowed about a solution, or as fine as the traversal goes: a leaf.
                Some(leaf) if pair_width(&leaf) <= narrow / FINER || (wa <= narrow / FINER && wb <= narrow / FINER) => {
                    out.leaves.push(leaf);
                    continue;
                }
                // Neither: halved further, where the combined rows' slopes shrink with the
                // width while a near miss stays.
                Some(_) => {}
            }
        }
        let side = usize::from(wb > wa);
        let kids = trees[side].children(pair[side]);
        // Pushed in reverse: the first half is examined first (a depth-first walk).
        for &k in kids.iter().rev() {
            let mut p = pair;
            p[side] = k;
            stack.push(p);
        }
    }
    out
}

/// Rounds of `contract_leaf` at most; it stops earlier once a round shrinks no width by a
/// tenth, or the pair is `SETTLED` wide (radians).
const LEAF_ROUNDS: usize = 8;
const SETTLED: f64 = 1e-7;

/// A narrow pair tested on the invariants `h` (left minus right) with the Jacobian at its
/// centre, `None` when it holds no solution, else the pair narrowed. Two tests, each sound
/// for any matrix taken from the centre:
/// - the rows combined along each left singular vector `n` of that Jacobian, by the
///   mean-value form: where the two sides' surfaces of invariants nearly touch along a curve
///   (measured on a general 6R: a miss of about 3e-3, a smallest singular value of 1e-3 to
///   1e-2, thousands of pairs along it), the combination along the smallest keeps the miss
///   while its slope over the pair nearly vanishes, and excludes what no single row can;
/// - Krawczyk's operator (`krawczyk::image_preconditioned`) with the pseudo-inverse `C` of
///   that Jacobian (the five rows have rank at most four: both sides' axis 4 has a unit
///   direction), which holds every zero of `h` in `X`; near a solution it narrows the pair to
///   a few ulps in a few rounds.
fn contract_leaf(sides: &Axis4Sides, (l, r): &Pair) -> Option<Pair> {
    // Unknowns (θ₂, θ₃, θ₆, θ₅) as in `ik::invariants`, whose Jacobian columns these are.
    let mut x = [l[0], l[1], r[0], r[1]];
    for _ in 0..LEAF_ROUNDS {
        let m = x.map(|v| 0.5 * (v[0] + v[1]));
        let (over_l, over_r) = (sides.value(Half::Left, &[x[0], x[1]], true), sides.value(Half::Right, &[x[2], x[3]], true));
        let (at_l, at_r) = (sides.value(Half::Left, &[[m[0]; 2], [m[1]; 2]], false), sides.value(Half::Right, &[[m[2]; 2], [m[3]; 2]], false));
        let cols = [over_l.cols[0], over_l.cols[1], over_r.cols[0], over_r.cols[1]];
        let h: [Iv; INVARIANTS] = std::array::from_fn(|i| at_l.inv[i].sub(at_r.inv[i]));
        let jm = nalgebra::SMatrix::<f64, INVARIANTS, 4>::from_fn(|i, j| 0.5 * (cols[j][i].lo + cols[j][i].hi));
        if !jm.iter().all(|v| v.is_finite()) {
            return Some(pair_of(&x));
        }
        let svd = jm.svd(true, true);
        let dx = [0, 1, 2, 3].map(|j| Iv { lo: x[j][0], hi: x[j][1] }.sub(Iv { lo: m[j], hi: m[j] }));
        // The rows combined along each left singular vector `n`: `n·h` vanishes at a solution,
        // and over `X` lies in `n·h(m) + Σ (n·J_j(X))(X_j − m_j)`.
        if let Some(u) = &svd.u {
            let excluded = (0..u.ncols()).any(|k| {
                let n = u.column(k);
                let mut acc = (0..INVARIANTS).fold(Iv::ZERO, |a, i| a.add(h[i].scale(n[i])));
                for j in 0..4 {
                    acc = acc.add((0..INVARIANTS).fold(Iv::ZERO, |a, i| a.add(cols[j][i].scale(n[i]))).mul(dx[j]));
                }
                acc.lo > 0.0 || acc.hi < 0.0
            });
            if excluded {
                return None;
            }
        }
        let Ok(c) = svd.pseudo_inverse(1e-12 * jm.norm()) else {
            return Some(pair_of(&x));
        };
        let jac = nalgebra::SMatrix::<Interval, INVARIANTS, 4>::from_fn(|i, j| cols[j][i].to());
        let image = krawczyk::image_preconditioned(&SVector::from(x.map(|v| interval(v[0], v[1]))), &SVector::from(m), &SVector::from(h.map(Iv::to)), &jac, &c);
        let Some(k) = image else {
            return Some(pair_of(&x));
        };
        let mut next = x;
        for j in 0..4 {
            let (lo, hi) = (x[j][0].max(k[j].inf()), x[j][1].min(k[j].sup()));
            if !(lo <= hi) {
                return None;
            }
            next[j] = [lo, hi];
        }
        let shrunk = (0..4).any(|k| next[k][1] - next[k][0] < 0.9 * (x[k][1] - x[k][0]));
        x = next;
        // The second phase's Krawczyk takes it on from here.
        if !shrunk || pair_width(&pair_of(&x)) <= SETTLED {
            break;
        }
    }
    Some(pair_of(&x))
}

fn pair_width((l, r): &Pair) -> f64 {
    l.iter().chain(r).map(|x| x[1] - x[0]).fold(0.0, f64::max)
}

fn pair_of(x: &[[f64; 2]; 4]) -> Pair {
    ([x[0], x[1]], [x[2], x[3]])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analyses::arm6r::cuspidal::Rng;
    use crate::analyses::arm6r::ik::PoseTarget;
    use crate::analyses::arm6r::three_parallel::tests::{chain, family};

    /// Random joint vectors within the limits of the general 6R fixture and of random arms (a
    /// UR-like layout with axis 1 tilted by 0.7 rad, so no closed form applies), the pose of each: some leaf pair holds the generating joints
    /// (2, 3; 6, 5), and every box's enclosure holds the invariants' values at points inside it.
    #[test]
    fn a_leaf_holds_the_joints_that_made_the_pose() {
        let mut rng = Rng(777);
        let general = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/ik6_general_6r.urdf")).expect("fixture");
        for seed in 0..=4 {
            let c = if seed == 0 { chain(&general) } else { chain(&family(seed, 0.7, true)) };
            for _ in 0..3 {
                let q: [f64; 6] = std::array::from_fn(|k| rng.uniform(c.ranges[k].0.max(-3.0), c.ranges[k].1.min(3.0)));
                let target = PoseTarget::around(&c.pose(&q), 1e-12).expect("finite");
                let sides = Axis4Sides::new(&c.split(&target.0, 0));
                let range = |k: usize| [c.ranges[k].0, c.ranges[k].1];
                let found = pairs(&sides, [range(1), range(2)], [range(5), range(4)], 0.02, Budget { pairs: 10_000_000, boxes: 500_000 }, &|| false);
                assert!(found.pending.is_empty() && !found.leaves.is_empty() && found.discarded > 0);
                let holds = |b: &[[f64; 2]; 2], a: f64, z: f64| b[0][0] <= a && a <= b[0][1] && b[1][0] <= z && z <= b[1][1];
                assert!(found.leaves.iter().any(|(l, r)| holds(l, q[1], q[2]) && holds(r, q[5], q[4])), "seed {seed}, q {q:?}");
                // Enclosures hold point values: a few boxes about q of several widths.
                for half in [Half::Left, Half::Right] {
                    let (a, z) = if half == Half::Left { (q[1], q[2]) } else { (q[5], q[4]) };
                    let tree = Tree::new(&sides, half, [[a - 0.3, a + 0.2], [z - 0.1, z + 0.4]]);
                    let at = sides.value(half, &[[a + 0.1; 2], [z + 0.05; 2]], false);
                    for i in 0..INVARIANTS {
                        let (e, v) = (tree.nodes[0].enc[i], at.inv[i]);
                        assert!(e.lo <= v.lo && v.hi <= e.hi, "seed {seed}: row {i}: {v:?} outside {e:?}");
                    }
                }
            }
        }
    }
}

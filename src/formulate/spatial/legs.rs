//! Legs between two ball joints: a link on a spherical tree joint closed by one spherical loop
//! (a rod, with whatever is welded to it), or such a link whose one prismatic child is (a leg
//! with a travel). Each spins freely about the line of its balls, so `build` gives it no
//! rotation and writes it as one distance row. This module finds them, and refuses the
//! multi-motion joints no loop constrains before anything is written.

use super::forms::imat_mul;
use crate::formulate::linkage::LinkageError;
use crate::formulate::stated::{self as st, IVec3};
use crate::kernel::interval::{point, Interval};
use crate::kernel::system::{EquationSystem, VarId};
use crate::model::{JointKind, Mechanism};
use std::collections::BTreeMap;

/// A leg between two ball joints, reduced to a distance.
#[derive(Clone, Debug)]
pub(super) struct Leg {
    /// The loop closing it.
    pub(super) closure: usize,
    /// The spherical tree joint at its first ball.
    pub(super) joint: usize,
    /// Squared length `|u|² + 2(u·w)d + d²` pieces: `u`, `w` and the travel.
    pub(super) u: IVec3,
    pub(super) w: IVec3,
    pub(super) travel: Option<Travel>,
    /// The links it covers.
    pub(super) links: Vec<usize>,
}

/// A leg's travel: a stated value (`--fix`, or 0 for a rod) or the prismatic joint's variable.
#[derive(Clone, Copy, Debug)]
pub(super) enum Travel {
    Known(Interval),
    Var(VarId),
}

impl Leg {
    /// The link at the far end of the leg's closure (the one the leg does not cover).
    pub(super) fn far_link(&self, m: &Mechanism) -> usize {
        let lp = &m.loops[self.closure];
        if self.links.contains(&lp.predecessor) { lp.successor } else { lp.predecessor }
    }

    /// The leg's travel: its own, or that of the prismatic joint of its rod as placed
    /// (`leg_travel`, by tree joint).
    pub(super) fn travel_in(&self, m: &Mechanism, leg_travel: &BTreeMap<usize, Travel>) -> Option<Travel> {
        self.travel.or_else(|| self.links.get(1).and_then(|&rod| m.links[rod].parent_joint).and_then(|pj| leg_travel.get(&pj).copied()))
    }

    /// `max |d|` over the travel's values (0 without a travel).
    pub(super) fn travel_bound(travel: Option<Travel>, system: &EquationSystem) -> f64 {
        match travel {
            Some(Travel::Known(v)) => v.mag(),
            Some(Travel::Var(v)) => system.vars[v].domain.mag(),
            None => 0.0,
        }
    }
}

/// The loops that close on link `l`.
pub(super) fn touching(m: &Mechanism, l: usize) -> Vec<usize> {
    (0..m.loops.len()).filter(|&k| m.loops[k].predecessor == l || m.loops[k].successor == l).collect()
}

/// The legs of `m` and, per link, whether a leg covers it. `children` lists the tree joints
/// hung on each link; a leg covers no traced link (`traced`), whose point would have no
/// determined position.
pub(super) fn find(m: &Mechanism, children: &[Vec<usize>], traced: &[usize]) -> (Vec<Leg>, Vec<bool>) {
    let mut legs: Vec<Leg> = Vec::new();
    let mut in_leg = vec![false; m.links.len()];
    for (j, joint) in m.joints.iter().enumerate() {
        if joint.kind != JointKind::Spherical {
            continue;
        }
        if let Some(leg) = rod(m, children, traced, j).or_else(|| sliding(m, children, traced, j)) {
            for &x in &leg.links {
                in_leg[x] = true;
            }
            legs.push(leg);
        }
    }
    (legs, in_leg)
}

/// The translation to loop `k`'s frame on `link`, and the loop's other link.
fn side(m: &Mechanism, k: usize, link: usize) -> (nalgebra::Vector3<f64>, usize) {
    let lp = &m.loops[k];
    if lp.predecessor == link { (lp.predecessor_origin.translation.vector, lp.successor) } else { (lp.successor_origin.translation.vector, lp.predecessor) }
}

/// Whether loop `k` is a plain ball joint.
fn ball(m: &Mechanism, k: usize) -> bool {
    m.loops[k].kind == JointKind::Spherical && m.loops[k].compound.is_none()
}

/// A rod on the spherical tree joint `j` with whatever is welded to it (frames such as a tool
/// or marker link on fixed joints): every descendant welded, one ball closure on any of them.
fn rod(m: &Mechanism, children: &[Vec<usize>], traced: &[usize], j: usize) -> Option<Leg> {
    let l = m.joints[j].child;
    let free_of_traces = |x: usize| !traced.contains(&x);
    let mut welded = vec![(l, st::identity(), [point(0.0); 3])];
    let mut all_fixed = true;
    let mut at = 0;
    while at < welded.len() {
        let (x, rot, pos) = welded[at];
        for &cj in &children[x] {
            let c = &m.joints[cj];
            if c.kind != JointKind::Fixed {
                all_fixed = false;
                continue;
            }
            let t = st::apply(&rot, &st::translation(&c.origin.translation.vector));
            welded.push((c.child, imat_mul(&rot, &st::rpy(c.rpy)), [0, 1, 2].map(|i| pos[i] + t[i])));
        }
        at += 1;
    }
    let closures: Vec<usize> = welded.iter().flat_map(|&(x, _, _)| touching(m, x)).collect();
    if !(all_fixed && closures.len() == 1 && ball(m, closures[0]) && welded.iter().all(|&(x, _, _)| free_of_traces(x))) {
        return None;
    }
    let k = closures[0];
    let lp = &m.loops[k];
    let &(x, rot, pos) = welded.iter().find(|&&(x, _, _)| lp.predecessor == x || lp.successor == x).expect("the closure touches a welded link");
    let (t, _) = side(m, k, x);
    let tt = st::apply(&rot, &st::translation(&t));
    let u = [0, 1, 2].map(|i| pos[i] + tt[i]);
    Some(Leg { closure: k, joint: j, u, w: [point(0.0); 3], travel: Some(Travel::Known(point(0.0))), links: welded.iter().map(|&(x, _, _)| x).collect() })
}

/// A leg on the spherical tree joint `j` whose link has one prismatic child, a rod with no
/// children closed by one ball joint: `|u + d·w|` between the balls.
fn sliding(m: &Mechanism, children: &[Vec<usize>], traced: &[usize], j: usize) -> Option<Leg> {
    let l = m.joints[j].child;
    let free_of_traces = |x: usize| !traced.contains(&x);
    let (tl, kids) = (touching(m, l), &children[l]);
    let ([pj], true) = (kids.as_slice(), tl.is_empty()) else { return None };
    let pjoint = &m.joints[*pj];
    let rod = pjoint.child;
    let tr = touching(m, rod);
    let (JointKind::Prismatic { .. }, true, [k]) = (pjoint.kind, children[rod].is_empty(), tr.as_slice()) else { return None };
    if !(ball(m, *k) && free_of_traces(l) && free_of_traces(rod)) {
        return None;
    }
    let (t, _) = side(m, *k, rod);
    let o = st::rpy(pjoint.rpy);
    let ot = st::apply(&o, &st::translation(&t));
    let tj = st::translation(&pjoint.origin.translation.vector);
    let u = [0, 1, 2].map(|i| tj[i] + ot[i]);
    let w = st::apply(&o, &st::axis(&pjoint.axis));
    Some(Leg { closure: *k, joint: j, u, w, travel: None, links: vec![l, rod] })
}

/// Multi-motion joints that no loop constrains are refused: their links would sweep a whole
/// region of poses. So is a ball-jointed link that spins freely outside any leg.
pub(super) fn refuse_undetermined(m: &Mechanism, children: &[Vec<usize>], in_leg: &[bool]) -> Result<(), LinkageError> {
    let mut on_loop = vec![false; m.links.len()];
    for lp in &m.loops {
        for end in [lp.predecessor, lp.successor] {
            let mut at = end;
            on_loop[at] = true;
            while let Some(j) = m.links[at].parent_joint {
                at = m.joints[j].parent;
                on_loop[at] = true;
            }
        }
    }
    for joint in &m.joints {
        let multi = matches!(joint.kind, JointKind::Spherical | JointKind::Floating);
        if multi && !on_loop[joint.child] {
            return Err(LinkageError::UnderConstrained(format!("joint '{}' is {} and no loop passes through link '{}': its orientation is free", joint.name, if joint.kind == JointKind::Spherical { "spherical" } else { "floating" }, m.links[joint.child].name)));
        }
        if joint.kind == JointKind::Spherical && !in_leg[joint.child] {
            let l = joint.child;
            let tl = touching(m, l);
            if children[l].is_empty() && tl.len() == 1 && m.loops[tl[0]].kind == JointKind::Spherical {
                return Err(LinkageError::UnderConstrained(format!(
                    "link '{}' spins freely about the line through its two ball joints ('{}' and loop '{}'); a traced point on it has no determined position",
                    m.links[l].name, joint.name, m.loops[tl[0]].name
                )));
            }
        }
    }
    Ok(())
}

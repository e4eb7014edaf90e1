//! Joint limits of the three analysed joints, applied to search results.
//!
//! The searches run on the whole torus [-π, π]² (the map is 2π-periodic); results are then
//! read against the limits: a box is *outside* when no 2π-translate of it meets [lower, upper]
//! (proven with an outward-rounded 2π), *inside* when one translate lies within them, and *on a
//! limit* otherwise. Outside boxes are dropped and counted; boxes on a limit are kept and
//! counted. Joint 1 does not enter (θ₂, θ₃): its limits restrict θ₁ where a result fixes it (inverse
//! kinematics of a point of the root frame), and are listed otherwise.

use super::ik::IkSolutions;
use super::Singularities;
use crate::model::{JointKind, Mechanism};
use inari::Interval;

/// Limits of joints 1–3 (radians).
#[derive(Clone, Debug, Default)]
pub struct JointLimits {
    /// Joint names, base first.
    pub joints: [String; 3],
    /// `[lower, upper]` per joint, `None` for continuous joints or when ignored.
    pub limits: [Option<[f64; 2]>; 3],
    /// `--ignore-limits` was given while the file has limits.
    pub ignored: bool,
}

/// What applying the limits did, for the report.
#[derive(Clone, Debug, Default)]
pub struct LimitEffect {
    /// The limits used.
    pub limits: JointLimits,
    /// Results dropped as outside the limits: cusps, nodes, internal-motion lines, undecided
    /// boxes (or pairs), IK solutions.
    pub dropped: u64,
    /// Results kept that straddle a limit (a cusp or node there may lie just outside).
    pub on_limit: u64,
    /// One line for the report.
    pub text: String,
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Place {
    Inside,
    OnLimit,
    Outside,
}

fn place(limit: Option<[f64; 2]>, x: Interval) -> Place {
    let Some([lo, hi]) = limit else { return Place::Inside };
    if hi - lo >= 2.0 * std::f64::consts::PI + 1e-9 {
        return Place::Inside;
    }
    // x lies within [-π, π] up to a cell; translates by k·2π for the few k that can matter.
    let mut best = Place::Outside;
    for k in -3i32..=3 {
        let y = x + Interval::TAU * crate::kernel::interval::point(f64::from(k));
        if y.sup() < lo || y.inf() > hi {
            continue;
        }
        if lo <= y.inf() && y.sup() <= hi {
            return Place::Inside;
        }
        best = Place::OnLimit;
    }
    best
}

impl JointLimits {
    /// The limits of the named joints in `m` (none when `ignore`).
    pub fn of(m: &Mechanism, joints: &[String; 3], ignore: bool) -> Self {
        let read = |n: &str| m.joint(n).and_then(|j| match m.joints[j].kind {
            JointKind::Revolute { limits: Some((lo, hi)) } => Some([lo, hi]),
            _ => None,
        });
        let file = [0, 1, 2].map(|k| read(&joints[k]));
        let any = file.iter().any(Option::is_some);
        JointLimits { joints: joints.clone(), limits: if ignore { [None; 3] } else { file }, ignored: ignore && any }
    }

    /// True when joints 2 and 3 have limits narrower than a full turn.
    pub fn restrict(&self) -> bool {
        self.limits[1..].iter().flatten().any(|[lo, hi]| hi - lo < 2.0 * std::f64::consts::PI + 1e-9)
    }

    fn of_box(&self, b: &[Interval; 2]) -> Place {
        match (place(self.limits[1], b[0]), place(self.limits[2], b[1])) {
            (Place::Outside, _) | (_, Place::Outside) => Place::Outside,
            (Place::Inside, Place::Inside) => Place::Inside,
            _ => Place::OnLimit,
        }
    }

    /// True when the (θ₂, θ₃) box lies strictly inside the limits.
    pub fn holds(&self, b: &[Interval; 2]) -> bool {
        self.of_box(b) == Place::Inside
    }

    fn describe(&self) -> String {
        let text: Vec<String> = (0..3).filter_map(|k| self.limits[k].map(|[lo, hi]| format!("{} in [{lo}, {hi}]", self.joints[k]))).collect();
        if text.is_empty() {
            if self.ignored { "joint limits ignored (--ignore-limits): full torus".into() } else { "no joint limits: full torus".into() }
        } else {
            format!("joint limits honoured: {}", text.join(", "))
        }
    }

    /// Joint `k`'s angle `x` (read modulo 2π) translated by a multiple of 2π into the joint's
    /// range: a translate inside the limits if there is one, else one that meets them; `x`
    /// itself for a joint without limits or when no translate meets them.
    pub fn in_range(&self, k: usize, x: Interval) -> Interval {
        let Some([lo, hi]) = self.limits[k] else { return x };
        let translates = [0i32, 1, -1, 2, -2, 3, -3].map(|n| x + Interval::TAU * crate::kernel::interval::point(f64::from(n)));
        let inside = translates.iter().find(|y| lo <= y.inf() && y.sup() <= hi);
        let meets = || translates.iter().find(|y| y.inf() <= hi && lo <= y.sup());
        inside.or_else(meets).copied().unwrap_or(x)
    }

    /// Drops what lies outside the limits from a singularity run; counts what is on a limit.
    pub fn apply(&self, run: &mut Singularities) -> LimitEffect {
        let (mut dropped, mut on_limit) = (0u64, 0u64);
        let mut keep = |p: Place| tally(p, &mut dropped, &mut on_limit);
        run.cusps.cusps.retain(|c| keep(self.of_box(&c.theta)));
        run.cusps.undecided.retain(|u| keep(self.of_box(&u.theta)));
        // An internal-motion line is the whole θ₂ circle at θ₃ in the band.
        let full = super::motion::full_range();
        run.cusps.bands.retain(|b| keep(self.of_box(&[full, crate::kernel::interval::interval(b.theta3[0], b.theta3[1])])));
        if let Some(n) = &mut run.nodes {
            // A node is two configurations with one image: both must be reachable.
            let pair = |t: &[[Interval; 2]; 2]| match (self.of_box(&t[0]), self.of_box(&t[1])) {
                (Place::Outside, _) | (_, Place::Outside) => Place::Outside,
                (Place::Inside, Place::Inside) => Place::Inside,
                _ => Place::OnLimit,
            };
            n.nodes.retain(|x| keep(pair(&x.theta)));
            n.undecided.retain(|x| keep(pair(x)));
        }
        let text = format!("{}; {dropped} results outside dropped, {on_limit} on a limit kept", self.describe());
        LimitEffect { limits: self.clone(), dropped, on_limit, text }
    }

    /// Drops inverse-kinematics solutions outside the limits and states the others' (θ₂, θ₃)
    /// in the joints' ranges (`in_range`). `theta1` encloses the first joint's angle of a
    /// solution box over (θ₂, θ₃) when the query fixes it (a point of the root frame); `None`
    /// leaves joint 1 free.
    pub fn apply_ik(&self, s: &mut IkSolutions, theta1: impl Fn(&[Interval; 2]) -> Option<Interval>) -> LimitEffect {
        let (mut dropped, mut on_limit) = (0u64, 0u64);
        let mut keep = |p: Place| tally(p, &mut dropped, &mut on_limit);
        // All three joints when θ₁ is fixed by the point, joints 2 and 3 otherwise.
        let of_solution = |b: &[Interval; 2]| match (theta1(b).map(|t| place(self.limits[0], t)), self.of_box(b)) {
            (Some(Place::Outside), _) | (_, Place::Outside) => Place::Outside,
            (Some(Place::OnLimit), _) | (_, Place::OnLimit) => Place::OnLimit,
            _ => Place::Inside,
        };
        s.unique.retain(|b| keep(of_solution(b)));
        s.clusters.retain(|c| keep(of_solution(&c.hull)));
        // The map is 2π-periodic: the kept boxes are stated in the joints' own ranges.
        let in_range = |b: &mut [Interval; 2]| *b = [self.in_range(1, b[0]), self.in_range(2, b[1])];
        s.unique.iter_mut().for_each(in_range);
        s.clusters.iter_mut().for_each(|c| in_range(&mut c.hull));
        let text = format!("{}; {dropped} solutions outside dropped, {on_limit} on a limit kept", self.describe());
        LimitEffect { limits: self.clone(), dropped, on_limit, text }
    }
}

/// Whether a result in place `p` is kept (inside, or on a limit: it may hold admissible points),
/// counting what is dropped and what sits on a limit.
fn tally(p: Place, dropped: &mut u64, on_limit: &mut u64) -> bool {
    match p {
        Place::Outside => {
            *dropped += 1;
            false
        }
        Place::OnLimit => {
            *on_limit += 1;
            true
        }
        Place::Inside => true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::interval::interval;

    #[test]
    fn places_modulo_two_pi() {
        let lim = Some([-1.0, 1.0]);
        assert_eq!(place(lim, interval(0.0, 0.5)), Place::Inside);
        assert_eq!(place(lim, interval(0.9, 1.1)), Place::OnLimit);
        assert_eq!(place(lim, interval(2.0, 3.0)), Place::Outside);
        // [5.5, 7] holds θ = 2.9 + … : the box [-0.7, -0.6] is inside it modulo 2π.
        assert_eq!(place(Some([5.5, 7.0]), interval(-0.7, -0.6)), Place::Inside);
        assert_eq!(place(Some([-4.0, 4.0]), interval(3.0, 3.1)), Place::Inside);
        assert_eq!(place(None, interval(3.0, 3.1)), Place::Inside);
    }

    #[test]
    fn angles_are_stated_in_the_joint_range() {
        let limits = JointLimits { joints: Default::default(), limits: [Some([0.82, 5.46]), Some([-0.087, 6.196]), None], ignored: false };
        let x = limits.in_range(0, interval(-3.09, -3.08));
        assert!(x.inf() > 3.19 && x.sup() < 3.21, "{x:?}");
        // Already inside: unchanged; meeting a limit only: the translate that meets it.
        assert_eq!(limits.in_range(1, interval(0.5, 0.6)), interval(0.5, 0.6));
        let y = limits.in_range(1, interval(-0.1, -0.05));
        assert!(y.inf() <= -0.087 && y.sup() >= -0.087, "{y:?}");
        assert_eq!(limits.in_range(2, interval(-3.0, -2.9)), interval(-3.0, -2.9));
    }
}


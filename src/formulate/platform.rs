//! Parallel platforms from a `Mechanism`: the distance formulation of their forward kinematics
//! (Porta, Thomas, Ros and Torras 2003, Sec. V-A).
//!
//! The mechanism is read as: a ground link (the base); a platform, child of the ground through a
//! `floating` joint (its pose is what the legs decide); and legs, each a `spherical` joint on the
//! base, a `prismatic` joint along the leg, and a `<loop type="spherical">` closing the rod onto
//! the platform. The ball centres are the points; their squared distances within the base and
//! within the platform are known from the file, the legs' from `--fix` (squared lengths, as in
//! Porta et al. 2003), and the base–platform pairs without a leg are the unknowns.
//! Only the octahedral (3-3) topology is built: three base and three platform points, each on two
//! legs, six legs in all. For it the Eqs. (6) of Porta et al. (2003) are two five-point
//! determinants in two unknowns; `redundant` adds the other four (Eq. 7), which bring in the third
//! unknown. After a solve, `poses` places the platform by trilateration and reports every pose.

use super::cayley_menger::{CayleyMenger, DistanceError, DistanceProblem};
use crate::kernel::interval::{point, IntervalBox};
use crate::model::{JointKind, Mechanism};
use nalgebra::{Matrix3, Point3, UnitQuaternion, Vector3};
use thiserror::Error;

/// What stops a mechanism from becoming a platform problem.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum PlatformError {
    /// No floating platform, or legs that are not spherical–prismatic–spherical chains.
    #[error("not a parallel platform: {0}")]
    NotAPlatform(String),
    /// A topology other than octahedral (3-3).
    #[error("unsupported platform: {0} (only octahedral 3-3 platforms are built so far)")]
    Unsupported(String),
    /// `--fix` names no leg.
    #[error("--fix: no leg (prismatic joint) named '{0}'")]
    UnknownLeg(String),
    /// A leg without a value: the determinants cannot decide its length.
    #[error("leg '{0}' has no --fix value: its length is one more unknown than the Cayley–Menger determinants constrain")]
    NotFixed(String),
    /// A squared length outside what the prismatic joint's limits allow.
    #[error("leg {leg}: the squared length {value} must lie in [{lower}, {upper}] (the joint limits)")]
    OutsideLimits {
        /// leg
        leg: String,
        /// value given
        value: f64,
        /// smallest squared length
        lower: f64,
        /// largest squared length
        upper: f64,
    },
    /// A value that is not a finite number.
    #[error("--fix {0}: the value is not a finite number")]
    NotFinite(String),
    /// The distances themselves are inconsistent (triangle inequality, degenerate base, ...).
    #[error(transparent)]
    Distance(#[from] DistanceError),
}

/// One leg: which points it joins and how long it may be.
#[derive(Clone, Debug, PartialEq)]
pub struct Leg {
    /// Name of the prismatic joint.
    pub name: String,
    /// Index of its base point (0..3).
    pub base: usize,
    /// Index of its platform point (3..6).
    pub top: usize,
    /// Range of its squared length allowed by the joint limits.
    pub squared_range: (f64, f64),
}

/// A pose of the platform frame in the base frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    /// Origin of the platform frame, in base coordinates.
    pub position: [f64; 3],
    /// Orientation as a unit quaternion `[w, x, y, z]`.
    pub quaternion: [f64; 4],
    /// Orientation as URDF roll, pitch, yaw (radians).
    pub rpy: [f64; 3],
    /// Largest misfit of a leg's squared length measured on this pose.
    pub leg_residual: f64,
}

/// An octahedral platform as a distance problem.
#[derive(Clone, Debug)]
pub struct PlatformProblem {
    /// The robot's name.
    pub name: String,
    /// Name of the platform link.
    pub platform: String,
    /// The legs, in file order.
    pub legs: Vec<Leg>,
    /// Squared leg lengths from `--fix`, in leg order.
    pub lengths: Vec<f64>,
    /// Ball centres on the base, in the base frame (points p1..p3).
    pub base_points: Vec<[f64; 3]>,
    /// Ball centres on the platform, in the platform frame (points p4..p6).
    pub platform_points: Vec<[f64; 3]>,
    /// The distance problem (points p1..p6) with the equations of Porta et al. (2003) and redundant
    /// ones.
    pub distances: DistanceProblem,
}

/// How the values fixing a platform's legs are given: squared lengths (m², the distance
/// problem's own quantity, as `linkspace distances --fix` takes them) or lengths (m, REP 103, as
/// ROS messages carry them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LegValues {
    /// Squared lengths, m².
    Squared,
    /// Lengths, m.
    Lengths,
}

/// One leg as the file states it: a ball joint on the base, a prismatic joint, and a spherical
/// loop onto the platform.
#[derive(Clone, Debug)]
pub(crate) struct RawLeg {
    /// Name of the prismatic joint.
    pub name: String,
    /// Index of the prismatic joint.
    pub joint: usize,
    /// Index of the spherical loop closing the leg on the platform.
    pub closure: usize,
    /// The link the ball joint hangs from: the base, or a link fixed to it (a mounting plate).
    pub mount: usize,
    /// Base ball centre, in the mount's frame (the ball joint's origin).
    pub base: Vector3<f64>,
    /// The rod's ball centre in the rod frame.
    pub on_rod: Vector3<f64>,
    /// Platform ball centre, in the platform frame.
    pub on_platform: Vector3<f64>,
    /// Range of the squared ball-to-ball length allowed by the joint limits.
    pub squared_range: (f64, f64),
}

/// The base, the platform link (child of the base through a floating joint) and its legs, in
/// file order: what the platform builders read.
///
/// The base is the link the platform's floating joint hangs from: the root, or a link held to
/// the root by fixed joints only (a `world` link above the base, at any placement, changes
/// nothing: the platform's pose and the ball centres are read in the base's frame).
pub(crate) fn read_legs(m: &Mechanism) -> Result<(usize, usize, Vec<RawLeg>), PlatformError> {
    let held = |link: usize| m.path_to(link).into_iter().all(|j| m.joints[j].kind == JointKind::Fixed);
    let floating: Vec<usize> = (0..m.joints.len()).filter(|&j| m.joints[j].kind == JointKind::Floating && held(m.joints[j].parent)).collect();
    let (base, platform) = match floating.as_slice() {
        [j] => (m.joints[*j].parent, m.joints[*j].child),
        [] => return Err(PlatformError::NotAPlatform("no link hangs from the base by a floating joint (the platform)".into())),
        _ => return Err(PlatformError::NotAPlatform("more than one floating link".into())),
    };
    // A leg may hang from the base or from a link fixed below it.
    let above_base = m.path_to(base);
    let mounted = |link: usize| {
        let path = m.path_to(link);
        path.starts_with(&above_base) && path[above_base.len()..].iter().all(|&j| m.joints[j].kind == JointKind::Fixed)
    };
    let mut legs = Vec::new();
    for (index, joint) in m.joints.iter().enumerate() {
        let JointKind::Prismatic { limits } = joint.kind else { continue };
        let element = format!("leg '{}'", joint.name);
        // Below: the cylinder, on a ball joint of the base.
        let cylinder = joint.parent;
        let ball = match m.links[cylinder].parent_joint {
            Some(b) if m.joints[b].kind == JointKind::Spherical && mounted(m.joints[b].parent) => b,
            _ => return Err(PlatformError::NotAPlatform(format!("{element}: its cylinder must hang from the base by a spherical joint"))),
        };
        let ball_centre = m.joints[ball].origin.translation.vector;
        // Above: the rod, closed onto the platform by a spherical loop.
        let rod = joint.child;
        let index_of_closure = m.loops.iter().position(|l| l.kind == JointKind::Spherical && (l.predecessor == rod && l.successor == platform || l.successor == rod && l.predecessor == platform));
        let Some(closure_index) = index_of_closure else {
            return Err(PlatformError::NotAPlatform(format!("{element}: no <loop type=\"spherical\"> joins its rod '{}' to the platform", m.links[rod].name)));
        };
        let closure = &m.loops[closure_index];
        let (on_rod, on_platform) = if closure.predecessor == rod {
            (closure.predecessor_origin.translation.vector, closure.successor_origin.translation.vector)
        } else {
            (closure.successor_origin.translation.vector, closure.predecessor_origin.translation.vector)
        };
        // Top ball in the cylinder frame: o.t + o.R (q·axis + on_rod); a line in q.
        let dir = joint.origin.rotation * joint.axis;
        let at0 = joint.origin.translation.vector + joint.origin.rotation * on_rod;
        if at0.cross(&dir).norm() > 1e-9 * (1.0 + at0.norm()) {
            return Err(PlatformError::NotAPlatform(format!("{element}: the two ball centres must lie on the prismatic axis")));
        }
        let offset = at0.dot(&dir);
        let (lo, hi) = (offset + limits.0, offset + limits.1);
        let squared_range = if lo <= 0.0 && hi >= 0.0 { (0.0, (lo * lo).max(hi * hi)) } else { ((lo * lo).min(hi * hi), (lo * lo).max(hi * hi)) };
        legs.push(RawLeg { name: joint.name.clone(), joint: index, closure: closure_index, mount: m.joints[ball].parent, base: ball_centre, on_rod, on_platform, squared_range });
    }
    Ok((base, platform, legs))
}

fn same(a: &Vector3<f64>, b: &Vector3<f64>) -> bool {
    (a - b).norm() <= 1e-9 * (1.0 + a.norm())
}

impl PlatformProblem {
    /// Reads the platform from `m` with the squared leg lengths `fixed` (leg name, value).
    pub fn new(m: &Mechanism, fixed: &[(String, f64)]) -> Result<Self, PlatformError> {
        Self::with_legs(m, fixed, LegValues::Squared)
    }

    /// Reads the platform from `m` with the legs `fixed` given as `values` say. A length `l`
    /// enters the distance problem as the interval square `[l]²`, so the problem solved is
    /// exactly the one with that length.
    pub fn with_legs(m: &Mechanism, fixed: &[(String, f64)], values: LegValues) -> Result<Self, PlatformError> {
        let (base, platform, read) = read_legs(m)?;
        if let Some(leg) = read.iter().find(|l| l.mount != base) {
            return Err(PlatformError::Unsupported(format!("leg '{}' hangs from '{}', a link fixed to the base: the distance formulation reads every ball centre in the base's frame", leg.name, m.links[leg.mount].name)));
        }
        let mut base_points: Vec<Vector3<f64>> = Vec::new();
        let mut platform_points: Vec<Vector3<f64>> = Vec::new();
        let mut legs = Vec::new();
        let mut tops = Vec::new();
        for leg in &read {
            let base = leg.base;
            let bi = base_points.iter().position(|p| same(p, &base)).unwrap_or_else(|| {
                base_points.push(base);
                base_points.len() - 1
            });
            legs.push(Leg { name: leg.name.clone(), base: bi, top: 0, squared_range: leg.squared_range });
            tops.push((leg.closure, leg.on_platform));
        }
        // Platform points are numbered in the order of their loops in the file.
        let mut order: Vec<usize> = (0..legs.len()).collect();
        order.sort_by_key(|&k| tops[k].0);
        for k in order {
            let p = tops[k].1;
            let ti = platform_points.iter().position(|q| same(q, &p)).unwrap_or_else(|| {
                platform_points.push(p);
                platform_points.len() - 1
            });
            legs[k].top = 3 + ti;
        }
        if legs.len() != 6 || base_points.len() != 3 || platform_points.len() != 3 {
            return Err(PlatformError::Unsupported(format!("{} legs between {} base and {} platform ball centres", legs.len(), base_points.len(), platform_points.len())));
        }
        for pt in 0..6 {
            let count = legs.iter().filter(|l| l.base == pt || l.top == pt).count();
            if count != 2 {
                return Err(PlatformError::Unsupported(format!("point p{} carries {count} legs, not two", pt + 1)));
            }
        }
        if legs.iter().enumerate().any(|(i, a)| legs[i + 1..].iter().any(|b| a.base == b.base && a.top == b.top)) {
            return Err(PlatformError::Unsupported("two legs join the same pair of points".into()));
        }

        // Leg values as given (squared below when given as lengths).
        let mut lengths = vec![f64::NAN; legs.len()];
        for (name, value) in fixed {
            let k = legs.iter().position(|l| &l.name == name).ok_or_else(|| PlatformError::UnknownLeg(name.clone()))?;
            if !value.is_finite() {
                return Err(PlatformError::NotFinite(name.clone()));
            }
            let (lower, upper) = legs[k].squared_range;
            let squared = match values {
                LegValues::Squared => *value,
                LegValues::Lengths => value * value,
            };
            if squared < lower || squared > upper || *value <= 0.0 {
                return Err(PlatformError::OutsideLimits { leg: name.clone(), value: squared, lower, upper });
            }
            lengths[k] = *value;
        }
        if let Some(k) = lengths.iter().position(|v| v.is_nan()) {
            return Err(PlatformError::NotFixed(legs[k].name.clone()));
        }

        let mut d = DistanceProblem::new(m.name.clone());
        for (k, p) in base_points.iter().enumerate() {
            d.add_point(format!("p{}", k + 1), Some([p.x, p.y, p.z]))?;
        }
        for k in 0..3 {
            d.add_point(format!("p{}", k + 4), None)?;
        }
        for a in 0..3 {
            for b in a + 1..3 {
                let r = (0..3).fold(point(0.0), |acc, c| acc + (point(platform_points[a][c]) - point(platform_points[b][c])).sqr());
                d.set_known(3 + a, 3 + b, r)?;
            }
        }
        for (leg, &v) in legs.iter().zip(&lengths) {
            let r = match values {
                LegValues::Squared => point(v),
                LegValues::Lengths => point(v).sqr(),
            };
            d.set_known(leg.base, leg.top, r)?;
        }
        // Squared lengths from here on (pose residuals are measured against them).
        if values == LegValues::Lengths {
            lengths.iter_mut().for_each(|l| *l *= *l);
        }
        // The three base–platform pairs without a leg; Eqs. (6) of Porta et al. (2003) take the
        // first and the last: Ξ(base ∪ {t1, t3}) and Ξ({b1, b3} ∪ platform), both in exactly those
        // two unknowns.
        let mut free: Vec<(usize, usize)> = (0..3).flat_map(|b| (3..6).map(move |t| (b, t))).filter(|&(b, t)| !legs.iter().any(|l| l.base == b && l.top == t)).collect();
        free.sort_unstable();
        let (u1, u3) = (free[0], free[2]);
        let mut e1 = vec![0, 1, 2, u1.1, u3.1];
        let mut e2 = vec![u1.0, u3.0, 3, 4, 5];
        e1.sort_unstable();
        e2.sort_unstable();
        let all: Vec<Vec<usize>> = super::cayley_menger::combinations(6, 5);
        d.redundant = Some(all.into_iter().filter(|s| *s != e1 && *s != e2).collect());
        d.equations = Some(vec![e2, e1]);
        Ok(Self {
            name: m.name.clone(),
            platform: m.links[platform].name.clone(),
            legs,
            lengths,
            base_points: base_points.iter().map(|v| [v.x, v.y, v.z]).collect(),
            platform_points: platform_points.iter().map(|v| [v.x, v.y, v.z]).collect(),
            distances: d,
        })
    }

    /// Every pose of the platform for a solution box of `cm` (built from `self.distances`): the
    /// box midpoint's distances, trilateration from the base (both mirror images, and both
    /// placements where two configurations share the solved distances), then the rigid motion
    /// taking the platform's ball centres onto the placed ones.
    pub fn poses(&self, cm: &CayleyMenger, b: &IntervalBox) -> Vec<Pose> {
        let x = b.midpoint();
        let width = cm.unknowns.iter().map(|u| b.width(u.var)).fold(0.0, f64::max);
        let tol = 1e-7 + 10.0 * width;
        cm.embed(&x, tol).into_iter().filter_map(|pts| self.pose_of(&pts)).collect()
    }

    /// The rigid motion (Kabsch) taking the platform points onto `pts[3..6]`.
    pub fn pose_of(&self, pts: &[[f64; 3]]) -> Option<Pose> {
        let q: Vec<Vector3<f64>> = self.platform_points.iter().map(|p| Vector3::new(p[0], p[1], p[2])).collect();
        let p: Vec<Vector3<f64>> = pts[3..6].iter().map(|p| Vector3::new(p[0], p[1], p[2])).collect();
        let qc = q.iter().sum::<Vector3<f64>>() / 3.0;
        let pc = p.iter().sum::<Vector3<f64>>() / 3.0;
        let h: Matrix3<f64> = q.iter().zip(&p).map(|(a, b)| (a - qc) * (b - pc).transpose()).sum();
        let svd = h.svd(true, true);
        let (u, vt) = (svd.u?, svd.v_t?);
        let mut v = vt.transpose();
        if (v * u.transpose()).determinant() < 0.0 {
            // Three points are planar: flipping the least singular direction gives the proper
            // rotation that fits them as well.
            let k = (0..3).min_by(|&i, &j| svd.singular_values[i].total_cmp(&svd.singular_values[j])).expect("three");
            v.column_mut(k).neg_mut();
        }
        let r = v * u.transpose();
        let rot = UnitQuaternion::from_matrix(&r);
        let t = pc - rot * qc;
        let leg_residual = self
            .legs
            .iter()
            .zip(&self.lengths)
            .map(|(l, &len)| {
                let top = rot * Point3::from(q[l.top - 3]) + t;
                let base = Vector3::from(self.base_points[l.base]);
                ((top.coords - base).norm_squared() - len).abs()
            })
            .fold(0.0, f64::max);
        let (roll, pitch, yaw) = rot.euler_angles();
        Some(Pose { position: [t.x, t.y, t.z], quaternion: [rot.w, rot.i, rot.j, rot.k], rpy: [roll, pitch, yaw], leg_residual })
    }
}

//! The loop-singularity jobs: the singular sets of one linkage in one call (which kinds, the
//! default actuated joints, one deadline for all of them), and the analysis of a 2-dof
//! mechanism's type-II image. `linkspace loop-singularities` and the node's `LinkageAnalysis`
//! both run `SingularSets`, so a topic and a `--json` file of the same URDF and settings hold the
//! same boxes.
//!
//! The model is `formulate::Linkage::build_in_joints`'s, as `solve --model auto` chooses among
//! the joint-coordinate models: planar when the planar builder accepts the mechanism, spatial
//! otherwise (`formulate::singular::velocity`), with the reason.
//!
//! Building every set's problem comes first (`SingularSets::new`), so a bad request (unknown
//! actuated joint, wrong actuator count) is answered before any search starts; `solve` then runs
//! the sets in order under one timeout: what the first set leaves of it goes to the next.

use crate::formulate::singular::image::{CuspProblem, ImageError, NodeProblem};
use crate::analyses::loop_singular::image::{regions, scaled, ImagePoints, ImageReport, RASTER_BYTES_PER_CELL};
use crate::model::Mechanism;
use crate::formulate::singular::{SingularError, SingularKind, SingularProblem};

use crate::kernel::search::{SolveError, SolverSettings};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// The actuated joints of a mechanism by default, and where they come from.
#[derive(Clone, Debug, PartialEq)]
pub struct Actuation {
    /// Joint names, in file order.
    pub joints: Vec<String>,
    /// One line: where they come from (for reports and the node's topic).
    pub source: String,
}

impl Actuation {
    /// The default: the joints of the URDF's `<transmission>` elements
    /// (`Mechanism::transmission_joints`), minus those `fixed` (a fixed joint is locked already,
    /// so it is no longer a free joint to actuate); none when the URDF has no transmission.
    pub fn from_transmissions(m: &Mechanism, fixed: &[(String, f64)]) -> Self {
        let named = m.transmission_joints.clone();
        if named.is_empty() {
            return Actuation { joints: Vec::new(), source: "none (the URDF has no <transmission> element)".to_string() };
        }
        let (locked, joints): (Vec<String>, Vec<String>) = named.into_iter().partition(|j| fixed.iter().any(|(f, _)| f == j));
        let mut source = "the URDF's <transmission> elements".to_string();
        if !locked.is_empty() {
            source.push_str(&format!(" (fixed, so left out: {})", locked.join(", ")));
        }
        Actuation { joints, source }
    }

    /// Joints given by name (`--actuated`).
    pub fn given(joints: Vec<String>) -> Self {
        Actuation { joints, source: "given".to_string() }
    }
}

/// The sets that "all" means for `actuated`: C-space, input and output; input singularities
/// need actuators, so without any "all" is C-space and output.
pub fn all_kinds(actuated: &[String]) -> Vec<SingularKind> {
    if actuated.is_empty() {
        vec![SingularKind::Cspace, SingularKind::Output]
    } else {
        vec![SingularKind::Cspace, SingularKind::Input, SingularKind::Output]
    }
}

/// What `analyse_image` can fail on.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ImageAnalysisError {
    /// The set does not build.
    #[error(transparent)]
    Singular(#[from] SingularError),
    /// Not a 2-dof mechanism with coordinate actuators.
    #[error(transparent)]
    Image(#[from] ImageError),
    /// Bad settings.
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// The raster of regions would hold more than the memory limit.
    #[error("a {grid} × {grid} raster of regions needs about {need_mib} MiB, over the memory limit of {limit_mib} MiB (use a smaller grid or raise the limit)")]
    Raster {
        /// cells per axis
        grid: usize,
        /// what it would hold
        need_mib: usize,
        /// the limit
        limit_mib: usize,
    },
}

/// The whole analysis of `m`'s type-II image: the cover of `S` (the input set at `settings`),
/// cusps, nodes, regions on a `grid × grid` raster and the verdict. `settings.timeout` bounds
/// the whole analysis, as it bounds every set of `SingularSets`: each search gets what the
/// ones before it left (at least a millisecond, so a search that finds no time still reports its
/// pending cells instead of being skipped silently).
pub fn analyse_image(m: &Mechanism, fixed: &[(String, f64)], actuated: &[String], settings: &SolverSettings, grid: usize, cancel: &AtomicBool) -> Result<ImageReport, ImageAnalysisError> {
    let need = grid.saturating_mul(grid).saturating_mul(RASTER_BYTES_PER_CELL);
    if need > settings.max_memory {
        return Err(ImageAnalysisError::Raster { grid, need_mib: need >> 20, limit_mib: settings.max_memory >> 20 });
    }
    let t0 = Instant::now();
    let left = || SolverSettings {
        timeout: settings.timeout.map(|t| t.saturating_sub(t0.elapsed()).max(std::time::Duration::from_millis(1))),
        ..settings.clone()
    };
    let p = SingularProblem::new(m, fixed, SingularKind::Input, actuated, None)?;
    let cover = p.solve(&scaled(&left()), cancel)?;
    let cusps = CuspProblem::new(m, &p)?.solve(&p, &left(), cancel)?;
    let nodes = NodeProblem::new(m, &p)?.solve(&p, &left(), cancel)?;
    let regions = regions(m, &p, &cover, grid, &left(), cancel)?;
    Ok(ImageReport::new(&p, &cover, &cusps, &nodes, regions))
}

/// One search of a 2-dof mechanism's type-II image on its own.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageSearch {
    /// Its cusps (the extended system with the second determinant), nothing else.
    Cusps,
    /// Its nodes (pairs of configurations with one image), nothing else.
    Nodes,
}

/// The cusps or the nodes of `m`'s type-II image, without the cover and the regions: what a user
/// who wants only the points pays for. `settings.timeout` bounds the search.
pub fn image_points(m: &Mechanism, fixed: &[(String, f64)], actuated: &[String], search: ImageSearch, settings: &SolverSettings, cancel: &AtomicBool) -> Result<ImagePoints, ImageAnalysisError> {
    let p = SingularProblem::new(m, fixed, SingularKind::Input, actuated, None)?;
    Ok(match search {
        ImageSearch::Cusps => ImagePoints::cusps(&p, &CuspProblem::new(m, &p)?.solve(&p, settings, cancel)?),
        ImageSearch::Nodes => ImagePoints::nodes(&p, &NodeProblem::new(m, &p)?.solve(&p, settings, cancel)?),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analyses::loop_singular::SingularSets;

    const FOUR_BAR: &str = include_str!("../../urdf/four_bar.urdf");

    fn with_transmission(joint: &str) -> String {
        FOUR_BAR.replace("</robot>", &format!("<transmission name=\"t\"><type>transmission_interface/SimpleTransmission</type><joint name=\"{joint}\"/></transmission></robot>"))
    }

    #[test]
    fn actuated_joints_default_to_transmissions_minus_fixed_ones() {
        let parse = |xml: &str| crate::model::urdf::parse(xml).expect("bundled");
        assert_eq!(Actuation::from_transmissions(&parse(FOUR_BAR), &[]).joints, Vec::<String>::new());
        let m = parse(&with_transmission("rocker_joint"));
        assert_eq!(Actuation::from_transmissions(&m, &[]).joints, vec!["rocker_joint".to_string()]);
        let fixed = Actuation::from_transmissions(&m, &[("rocker_joint".into(), 0.3)]);
        assert_eq!(fixed.joints, Vec::<String>::new());
        assert!(fixed.source.contains("left out: rocker_joint"), "{}", fixed.source);
        assert_eq!(all_kinds(&[]), vec![SingularKind::Cspace, SingularKind::Output]);
    }

    #[test]
    fn one_timeout_covers_every_set() {
        let m = crate::model::urdf::parse(FOUR_BAR).expect("bundled");
        let actuated = vec!["rocker_joint".to_string()];
        let sets = SingularSets::new(&m, &[], &all_kinds(&actuated), &actuated, None).expect("builds");
        assert_eq!(sets.problems.len(), 3);
        // No time at all: every set reports its charts undecided, none is skipped: one box
        // holds every chart, each chart's box (m_k = 1) inside it.
        let settings = SolverSettings { timeout: Some(std::time::Duration::ZERO), ..Default::default() };
        let solved = sets.solve(&settings, &AtomicBool::new(false)).expect("valid");
        for (p, s) in sets.problems.iter().zip(&solved) {
            assert!(!s.status.finished(), "{:?}", p.kind);
            assert_eq!(s.unsearched_charts, p.chart_count());
            assert_eq!(s.boxes.len(), 1);
            assert_eq!(s.boxes[0].status, crate::kernel::outcome::BoxStatus::Undecided);
            for k in 0..p.chart_count() {
                let chart = p.chart(k).initial_box();
                assert!(chart.dims.iter().zip(&s.boxes[0].b.dims).all(|(c, b)| c.subset(*b)), "chart {k} of {:?} is not held", p.kind);
            }
        }
        // A bad actuator list fails before any search.
        let err = SingularSets::new(&m, &[], &all_kinds(&["nope".to_string()]), &["nope".to_string()], None).expect_err("refused");
        assert!(err.to_string().contains("'nope' is not a free joint"), "{err}");
    }
}

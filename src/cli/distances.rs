//! `linkspace distances`: distance problems by Cayley–Menger determinants and trapezoid
//! clipping (Porta, Thomas, Ros and Torras 2003), from a URDF platform or a JSON distance file.

use super::parse_fix;
use anyhow::Result;
use linkspace::app::{DistanceFormulation, DistancesJob, FaceBounds, Job, LegValues};
use std::path::PathBuf;

#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
pub enum Form {
    /// Let the builder pick: points when the problem has a frame and a square coordinate
    /// system, else shared.
    Auto,
    /// Coordinates of the free points (degree two; interval Newton certifies).
    Points,
    /// A point and a direction of the line through the two free points (lines tangent to
    /// spheres; degree two; interval Newton certifies).
    Line,
    /// One variable per distance (degree two; Bernstein control points).
    Shared,
    /// As Porta, Thomas, Ros and Torras (2003): r_ij and r_ji separate, multilinear (corner values).
    Split,
}

#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
pub enum Faces {
    /// Trapezoid sides from control points (the method of Porta, Thomas, Ros and Torras (2003)).
    Corners,
    /// Trapezoid sides by interval evaluation (the comparison Porta, Thomas, Ros and Torras (2003) make).
    Interval,
}

#[derive(clap::Args)]
pub struct DistancesArgs {
    /// A platform in URDF (.urdf) or a distance problem in JSON (schema in README).
    file: PathBuf,
    /// Squared length of a leg (platform) or of a named distance (JSON). Repeatable.
    #[arg(long = "fix", value_name = "LEG=VALUE")]
    fix: Vec<String>,
    /// Solution boxes are at most this wide in every unknown squared distance.
    #[arg(long, alias = "sigma", default_value_t = 0.01)]
    precision: f64,
    /// Keep clipping a box while a round leaves less than this share of its volume. Default
    /// 0.99 (as Porta, Thomas, Ros and Torras (2003)) for the determinants, 0.9 for the coordinate formulations (points,
    /// line), where bisecting is cheaper than slow propagation fixpoints.
    #[arg(long)]
    rho: Option<f64>,
    /// Add the redundant determinants (platform: Eq. 7 of Porta, Thomas, Ros and Torras (2003); JSON: six-point ones).
    #[arg(long)]
    redundant: bool,
    /// Variables for the unknown distances.
    #[arg(long, value_enum, default_value_t = Form::Auto)]
    formulation: Form,
    /// How the trapezoid sides are bounded.
    #[arg(long, value_enum, default_value_t = Faces::Corners)]
    faces: Faces,
    #[command(flatten)]
    limits: super::LimitArgs,
    /// Write the full report as JSON here.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

fn choice(form: Form) -> DistanceFormulation {
    match form {
        Form::Auto => DistanceFormulation::Auto,
        Form::Points => DistanceFormulation::Points,
        Form::Line => DistanceFormulation::Line,
        Form::Shared => DistanceFormulation::Shared,
        Form::Split => DistanceFormulation::Split,
    }
}

fn face_bounds(f: Faces) -> FaceBounds {
    if f == Faces::Corners {
        FaceBounds::Corners
    } else {
        FaceBounds::IntervalArithmetic
    }
}

pub fn run(args: DistancesArgs) -> Result<()> {
    let fixed = args.fix.iter().map(|s| parse_fix(s)).collect::<Result<Vec<_>>>()?;
    let job = DistancesJob { fixed, legs: LegValues::Squared, precision: args.precision, rho: args.rho, redundant: args.redundant, formulation: choice(args.formulation), faces: face_bounds(args.faces) };
    super::execute(&args.file, Job::Distances(job), &args.limits, args.json.as_deref())
}

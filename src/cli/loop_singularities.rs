//! `linkspace loop-singularities`: certified singular sets of closed-loop linkages,
//! planar or spatial (the model `solve --model auto` picks), on the polynomial solver through
//! `analyses::loop_singular` (the searches on the systems of `formulate::singular`).

use super::{parse_fix, LimitArgs};
use anyhow::{bail, Context, Result};
use linkspace::app::{self, Job, LoopQuestion, LoopSingularitiesJob, MotionSpan, Output, SingularKind};
use std::path::PathBuf;

#[derive(Clone, Copy, clap::ValueEnum)]
pub(crate) enum Kind {
    /// C-space singularities (bifurcations): the loop constraints lose rank.
    Cspace,
    /// Input (type II): locked actuators, the mechanism still moves.
    Input,
    /// Output (type I): the output stands still, the mechanism moves.
    Output,
    /// All three.
    All,
    /// 2-dof mechanisms: cusps and nodes of the type-II image in actuator space, the regions it
    /// cuts with their assembly modes, and the verdict on non-singular assembly-mode change.
    Image,
    /// 2-dof mechanisms: the cusps of the type-II image alone (no cover, nodes or regions).
    Cusps,
    /// 2-dof mechanisms: the nodes of the type-II image alone (no cover, cusps or regions).
    Nodes,
    /// 1-dof planar loops: a motion of the actuated joint (`--from`, `--to`) from an assembly
    /// (`--assembly`) checked against the input (type II) singularities by tube following.
    Motion,
}

#[derive(clap::Args)]
pub(crate) struct LoopSingularitiesArgs {
    /// URDF file of a closed-loop linkage, planar or spatial (loops closed with <loop>, see README).
    urdf: PathBuf,
    /// Which singular set(s).
    #[arg(long, value_enum, default_value_t = Kind::All)]
    kind: Kind,
    /// Actuated joints, comma separated. Default: the joints of the URDF's <transmission> elements.
    #[arg(long, value_name = "J1,J2,...")]
    actuated: Option<String>,
    /// Output of type-I singularities: a point LINK@X,Y, or joints J1,J2 (default: every passive joint).
    #[arg(long, value_name = "LINK@X,Y | J1,J2")]
    output: Option<String>,
    /// Fix a joint value (radians or metres). Repeatable.
    #[arg(long = "fix", value_name = "JOINT=VALUE")]
    fix: Vec<String>,
    /// Boxes are at most this wide in every primary variable (configuration and null vector).
    #[arg(long, alias = "sigma", default_value_t = 1e-4)]
    precision: f64,
    #[command(flatten)]
    limits: LimitArgs,
    /// Write the reports (one per set, as a JSON array; `--kind image`: one image report) here.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// `--kind image`: cells per actuator axis of the raster that finds the regions.
    #[arg(long, default_value_t = 128)]
    grid: usize,
    /// `--kind motion`: the actuated joint's start value (radians or metres).
    #[arg(long, allow_hyphen_values = true)]
    from: Option<f64>,
    /// `--kind motion`: its end value.
    #[arg(long, allow_hyphen_values = true)]
    to: Option<f64>,
    /// `--kind motion`: an approximate configuration at the start, one value per free joint in
    /// file order (angles modulo 2π; a wrong count names them): the values `solve --fix J=A`
    /// prints for an assembly, with A for J, are one.
    #[arg(long, value_name = "Q1,Q2,...", allow_hyphen_values = true)]
    assembly: Option<String>,
    /// `--kind motion`: the largest step of the input.
    #[arg(long, default_value_t = 0.05)]
    max_step: f64,
    /// `--kind motion`: steps are halved down to this before the motion is left undecided.
    #[arg(long, default_value_t = 1e-6)]
    min_step: f64,
}

/// `LINK@X,Y` or `J1,J2`.
pub(crate) fn parse_output(s: &str) -> Result<Output> {
    if let Some((link, xy)) = s.split_once('@') {
        let (x, y) = xy.split_once(',').with_context(|| format!("--output '{s}': expected LINK@X,Y"))?;
        let x: f64 = x.trim().parse().with_context(|| format!("--output '{s}': '{x}' is not a number"))?;
        let y: f64 = y.trim().parse().with_context(|| format!("--output '{s}': '{y}' is not a number"))?;
        if !(x.is_finite() && y.is_finite()) || link.trim().is_empty() {
            bail!("--output '{s}': expected LINK@X,Y with finite coordinates");
        }
        return Ok(Output::Point { link: link.trim().to_string(), x, y });
    }
    Ok(Output::Joints(names(s, "--output")?))
}

fn names(s: &str, flag: &str) -> Result<Vec<String>> {
    let v: Vec<String> = s.split(',').map(|x| x.trim().to_string()).collect();
    if v.iter().any(|x| x.is_empty()) {
        bail!("{flag} '{s}': expected joint names separated by commas");
    }
    Ok(v)
}

pub(crate) fn run(args: LoopSingularitiesArgs) -> Result<()> {
    let fixed = args.fix.iter().map(|s| parse_fix(s)).collect::<Result<Vec<_>>>()?;
    let output = args.output.as_deref().map(parse_output).transpose()?;
    let actuated = args.actuated.as_deref().map(|a| names(a, "--actuated")).transpose()?;
    let question = match args.kind {
        Kind::Cspace => LoopQuestion::Sets(vec![SingularKind::Cspace]),
        Kind::Input => LoopQuestion::Sets(vec![SingularKind::Input]),
        Kind::Output => LoopQuestion::Sets(vec![SingularKind::Output]),
        Kind::All => LoopQuestion::Sets(Vec::new()),
        Kind::Image => LoopQuestion::Image { grid: args.grid },
        Kind::Cusps => LoopQuestion::Cusps,
        Kind::Nodes => LoopQuestion::Nodes,
        Kind::Motion => {
            let (Some(from), Some(to), Some(assembly)) = (args.from, args.to, args.assembly.as_deref()) else {
                let text = std::fs::read_to_string(&args.urdf).with_context(|| format!("reading {}", args.urdf.display()))?;
                let joints = app::Input::urdf(&text).ok().and_then(|i| i.mechanism().ok().and_then(|m| app::motion_joints(m, &fixed).ok())).map(|j| j.join(", ")).unwrap_or_default();
                bail!("--kind motion needs --from A --to B --assembly Q1,Q2,... (the free joints: {joints})");
            };
            let assembly = assembly.split(',').map(|v| v.trim().parse::<f64>().with_context(|| format!("--assembly: '{v}' is not a number"))).collect::<Result<Vec<f64>>>()?;
            LoopQuestion::Motion(MotionSpan { from, to, assembly, max_step: args.max_step, min_step: args.min_step })
        }
    };
    let job = LoopSingularitiesJob { question, fixed, actuated, output, precision: args.precision };
    super::execute(&args.urdf, Job::LoopSingularities(job), &args.limits, args.json.as_deref())
}

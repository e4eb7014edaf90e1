//! `linkspace self-motion`: every configuration of a seven-revolute arm at a tip pose.

use super::ik6::parse_pose;
use super::{ChainArgs, LimitArgs};
use anyhow::{bail, Result};
use linkspace::app::{Job, SelfMotionJob};
use std::path::PathBuf;

#[derive(clap::Args)]
pub(crate) struct SelfMotionArgs {
    /// URDF file of an arm with seven revolute joints from base to tip (fixed joints merged).
    urdf: PathBuf,
    #[command(flatten)]
    chain: ChainArgs,
    /// The tip frame's pose in the base frame, in any form `ik6 --pose` takes (6, 7 or 16
    /// comma-separated numbers).
    #[arg(long, value_name = "6|7|16 NUMBERS", allow_hyphen_values = true)]
    pose: String,
    /// The joint whose range is cut into cells, the curves' parameter. Default: the third
    /// revolute joint from the base.
    #[arg(long, value_name = "JOINT")]
    parameter: Option<String>,
    /// Search only this part of the parameter's range (radians, within its limits): how far the
    /// arm can swing from a configuration, say. Default: the whole range.
    #[arg(long, value_name = "LO,HI", allow_hyphen_values = true)]
    range: Option<String>,
    /// Width (radians) of the parameter's cells, in (0, 1]: on a narrower cell more boxes are
    /// certified as pieces of arc, and more cells are searched.
    #[arg(long, default_value_t = 0.002, allow_hyphen_values = true)]
    cell: f64,
    /// Largest width (radians) of the other joints' boxes that are not certified, in (0, 1) (a
    /// certified box is as narrow as its piece of arc).
    #[arg(long, default_value_t = 0.1, allow_hyphen_values = true)]
    precision: f64,
    #[command(flatten)]
    limits: LimitArgs,
    /// Write the report as JSON here.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

pub(crate) fn run(args: SelfMotionArgs) -> Result<()> {
    let pose = parse_pose(&args.pose, "--pose")?;
    let range = match &args.range {
        None => None,
        Some(text) => match text.split(',').map(|t| t.trim().parse::<f64>()).collect::<Result<Vec<f64>, _>>().as_deref() {
            Ok([lo, hi]) => Some((*lo, *hi)),
            _ => bail!("--range '{text}': expected two numbers LO,HI"),
        },
    };
    let job = SelfMotionJob { arm: args.chain.options()?, pose, parameter: args.parameter, range, cell: args.cell, precision: args.precision };
    super::execute(&args.urdf, Job::SelfMotion(job), &args.limits, args.json.as_deref())
}

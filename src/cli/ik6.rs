//! `linkspace ik6`: certified inverse kinematics of a six-revolute arm at one pose (`--pose`)
//! or at every pose of a file (`--poses`), the file read once and every pose answered in turn.

use super::{read_input, run_job, write_file, ChainArgs, LimitArgs};
use anyhow::{bail, Context, Result};
use linkspace::app::{Ik6Job, Job, PoseInput};
use linkspace::edges::report;
use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(clap::Args)]
pub(crate) struct Ik6Args {
    /// URDF file of an arm with six revolute joints from base to tip (fixed joints merged).
    urdf: PathBuf,
    #[command(flatten)]
    chain: ChainArgs,
    /// The tip frame's pose in the base frame (metres, radians), comma-separated; the count of
    /// numbers names the form: 6 = X,Y,Z,ROLL,PITCH,YAW (URDF convention, Rz·Ry·Rx); 7 =
    /// X,Y,Z,QX,QY,QZ,QW (a quaternion, normalised; zero refused); 16 = a 4x4 homogeneous
    /// transform, row-major (rotation block orthonormal and last row 0,0,0,1 to within 1e-6).
    #[arg(long, value_name = "6|7|16 NUMBERS", allow_hyphen_values = true, required_unless_present = "poses", conflicts_with = "poses")]
    pose: Option<String>,
    /// A file of poses, one per line in any form `--pose` takes (blank lines and lines starting
    /// with `#` skipped; `-` reads standard input). Every line is checked before the first pose
    /// is solved; the answers come in the file's order, each within the limits (`--timeout`
    /// bounds each pose's answer), and `--json` writes one JSON object per line (JSON Lines).
    #[arg(long, value_name = "FILE")]
    poses: Option<PathBuf>,
    /// Largest width (radians) of reported boxes, in (0, 1).
    #[arg(long, default_value_t = 1e-9, allow_hyphen_values = true)]
    precision: f64,
    #[command(flatten)]
    limits: LimitArgs,
    /// Write the report as JSON here.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

/// The pose of `text` (what `--pose` or one line of `--poses` holds); `what` names it in errors.
pub(crate) fn parse_pose(text: &str, what: &str) -> Result<PoseInput> {
    let values: Vec<f64> = text
        .split(',')
        .map(|t| t.trim().parse::<f64>().map_err(|_| anyhow::anyhow!("{what} '{}': '{}' is not a number", text.trim(), t.trim())))
        .collect::<Result<_>>()?;
    PoseInput::from_numbers(&values).map_err(|e| anyhow::anyhow!("{what} '{}': {e}", text.trim()))
}

/// The poses of a `--poses` file with their line numbers, every line checked.
fn read_poses(path: &Path) -> Result<Vec<(usize, PoseInput)>> {
    let reader: Box<dyn BufRead> = if path == Path::new("-") {
        Box::new(std::io::stdin().lock())
    } else {
        Box::new(std::io::BufReader::new(std::fs::File::open(path).with_context(|| format!("reading {}", path.display()))?))
    };
    let mut poses = Vec::new();
    for (k, line) in reader.lines().enumerate() {
        let line = line.with_context(|| format!("reading {}", path.display()))?;
        let text = line.trim();
        if text.is_empty() || text.starts_with('#') {
            continue;
        }
        poses.push((k + 1, parse_pose(text, &format!("--poses {} line {}:", path.display(), k + 1))?));
    }
    if poses.is_empty() {
        bail!("--poses {}: no pose in the file (one per line, as --pose takes it)", path.display());
    }
    Ok(poses)
}

pub(crate) fn run(args: Ik6Args) -> Result<()> {
    let arm = args.chain.options()?;
    let job = |pose: PoseInput| Job::Ik6(Ik6Job { arm: arm.clone(), pose, precision: args.precision });
    // clap holds exactly one of --pose and --poses.
    let Some(file) = &args.poses else {
        let pose = parse_pose(args.pose.as_deref().unwrap_or_default(), "--pose")?;
        return super::execute(&args.urdf, job(pose), &args.limits, args.json.as_deref());
    };
    let poses = read_poses(file)?;
    let limits = args.limits.limits(Job::default_limits("ik6"))?;
    let input = read_input(&args.urdf, &job(poses[0].1))?;
    let mut json = Vec::new();
    let mut out = std::io::stdout().lock();
    for (k, (line, pose)) in poses.into_iter().enumerate() {
        let answer = run_job(&args.urdf, &input, job(pose), limits, &args.limits, Instant::now())?;
        // A closed pipe ends the printing quietly; the JSON report is still written.
        write!(out, "pose {k} (line {line}): {}", report::text(&answer)).ok();
        if args.json.is_some() {
            json.push(report::json_line(&answer)?);
        }
    }
    if let Some(path) = &args.json {
        json.push(String::new());
        write_file(path, json.join("\n"))?;
    }
    Ok(())
}

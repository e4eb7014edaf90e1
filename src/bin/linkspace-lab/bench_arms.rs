//! `linkspace-lab bench3r --arms`: per robot, the shipped `linkspace singularities` path
//! (rounding, chain selection, structural or generic verdict, certified branches) against the
//! previous behaviour on the same chain (the interval cusp and node searches on the full torus,
//! bounded by `--timeout` and `--max-boxes`), both measured in the same run. Every case runs as a
//! child process, so its peak resident memory is the child's own (`wait4`'s `ru_maxrss`): the
//! shipped path as the `linkspace` binary beside this one, the baseline as this executable's
//! hidden `--baseline-child` mode. Wall time and peak memory include each binary's own start
//! and footprint (the product also carries the ROS 2 node), a few milliseconds and megabytes.

use crate::bench3r::{Bench3rArgs, ROBOTS};
use crate::median;
use anyhow::{bail, Context, Result};
use linkspace::analyses::arm3r::{self, ChainSpec, LoadOptions};
use linkspace::kernel::search::Control;
use linkspace::model::urdf;
use linkspace::kernel::search::{Limits, Status};
use std::io::{Read, Write};
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

/// The bundled real arms, with the joint a 7R arm needs locked (README, "Real arms").
const ARMS: [(&str, &str, &[&str]); 4] = [
    ("puma560", include_str!("../../../urdf/puma560.urdf"), &[]),
    ("kuka_kr16", include_str!("../../../urdf/kuka_kr16.urdf"), &[]),
    ("ur5", include_str!("../../../urdf/ur5.urdf"), &[]),
    ("iiwa14", include_str!("../../../urdf/iiwa14.urdf"), &["joint_3=0"]),
];

/// The baseline's bound on pending cells: `linkspace singularities`' default `--max-memory`.
const BASELINE_MAX_MEMORY: usize = 256 << 20;

/// One child run: wall seconds, peak RSS (bytes), stdout.
pub(crate) struct Measured {
    seconds: f64,
    /// The child's own CPU seconds, user + system.
    pub(crate) cpu: f64,
    rss: u64,
    pub(crate) stdout: String,
}

/// Runs `exe args` and reaps it with `wait4`, which gives the child's own peak RSS and CPU time.
pub(crate) fn measure(exe: &Path, args: &[String]) -> Result<Measured> {
    let start = Instant::now();
    let mut child = Command::new(exe).args(args).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().context("starting a bench child")?;
    let mut stdout = String::new();
    let mut stderr = String::new();
    child.stdout.take().expect("piped").read_to_string(&mut stdout).ok();
    child.stderr.take().expect("piped").read_to_string(&mut stderr).ok();
    let pid = child.id() as libc::pid_t;
    let mut status: libc::c_int = 0;
    // SAFETY: rusage is plain data, written by the kernel; pid is our own unreaped child.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let rc = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    let seconds = start.elapsed().as_secs_f64();
    if rc != pid {
        bail!("wait4 on the bench child failed: {}", std::io::Error::last_os_error());
    }
    if !(libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0) {
        bail!("bench child `{}` failed (status {status}): {}", args.join(" "), stderr.trim());
    }
    // Linux reports ru_maxrss in KiB.
    let cpu = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    Ok(Measured { seconds, cpu: cpu(usage.ru_utime) + cpu(usage.ru_stime), rss: usage.ru_maxrss.max(0) as u64 * 1024, stdout })
}

/// What one path gave: status text, undecided count, and a short note (verdict or counts).
struct Outcome {
    status: String,
    undecided: u64,
    note: String,
}

/// Median time and memory over `repeat` runs, and the last run's outcome.
fn repeated(exe: &Path, args: &[String], repeat: usize, read: &dyn Fn(&Measured) -> Result<Outcome>) -> Result<(f64, f64, Outcome)> {
    let mut times = Vec::new();
    let mut rss = Vec::new();
    let mut last = None;
    for _ in 0..repeat {
        let m = measure(exe, args)?;
        times.push(m.seconds);
        rss.push(m.rss as f64);
        last = Some(read(&m)?);
    }
    Ok((median(times), median(rss), last.expect("repeat >= 1")))
}

/// Two significant digits, in scientific notation below 0.01 (new/baseline can be 1e-4).
fn ratio(r: f64) -> String {
    if r < 0.01 { format!("{r:.1e}") } else { format!("{r:.2}") }
}

fn status_text(complete: bool, limit: Option<&str>) -> String {
    match (complete, limit) {
        (true, _) => "complete".into(),
        (false, Some(l)) => format!("incomplete ({l})"),
        (false, None) => "incomplete".into(),
    }
}

/// `bench3r --arms`.
pub fn run(args: &Bench3rArgs) -> Result<()> {
    let lab = std::env::current_exe().context("locating this executable")?;
    let shipped = lab.parent().context("locating this executable's folder")?.join(format!("linkspace{}", std::env::consts::EXE_SUFFIX));
    if !shipped.is_file() {
        bail!("bench3r --arms runs the product binary, not found at {} (build it: cargo build --release --bins)", shipped.display());
    }
    let dir = std::env::temp_dir().join(format!("linkspace-bench-arms-{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let result = table(args, &shipped, &lab, &dir);
    std::fs::remove_dir_all(&dir).ok();
    result
}

/// The table: `shipped` runs the new path, `lab` (this executable) the baseline.
fn table(args: &Bench3rArgs, shipped: &Path, lab: &Path, dir: &Path) -> Result<()> {
    let robots = ARMS.iter().map(|&(n, x, l)| (n, x, l)).chain(ROBOTS.iter().map(|&(n, x, _, _)| (n, x, &[][..])));
    let mut out = std::io::stdout().lock();
    let timeout = args.timeout;
    writeln!(
        out,
        "bench3r --arms: precision {:e}, median of {} runs; baseline = interval cusp + node searches, --ignore-limits, timeout {timeout} s, max boxes {} (per search)",
        args.precision, args.repeat, args.max_boxes
    )
    .ok();
    writeln!(out, "robot | new s | new MB | new status | new undecided | verdict | baseline s | baseline MB | baseline status | baseline undecided (cusp boxes + node pairs) | time new/baseline | memory new/baseline").ok();
    let total = Instant::now();
    for (name, xml, locks) in robots {
        let file = dir.join(format!("{name}.urdf"));
        std::fs::write(&file, xml).with_context(|| format!("writing {}", file.display()))?;
        let lock_args: Vec<String> = locks.iter().flat_map(|l| ["--lock".to_string(), l.to_string()]).collect();
        let json = dir.join(format!("{name}.json"));
        let mut new_args = vec!["singularities".to_string(), file.display().to_string(), "--precision".into(), args.precision.to_string(), "--json".into(), json.display().to_string()];
        new_args.extend(lock_args.iter().cloned());
        let read_new = |_: &Measured| -> Result<Outcome> {
            let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json)?)?;
            let complete = v["status"] == "complete";
            let undecided = v["undecided_total"].as_array().map_or(0, |a| a.iter().filter_map(|x| x.as_u64()).sum());
            let verdict = &v["verdict"];
            let note = match verdict["cuspidal"].as_bool() {
                Some(true) => "cuspidal",
                Some(false) => "non-cuspidal",
                None => "undecided",
            };
            let note = format!("{note}{}", if verdict["certified"].as_bool() == Some(true) { " (certified)" } else { "" });
            Ok(Outcome { status: status_text(complete, v["limit"].as_str()), undecided, note })
        };
        let (t_new, m_new, new) = repeated(shipped, &new_args, args.repeat, &read_new)?;
        let mut base_args = vec![
            "bench3r".to_string(),
            "--baseline-child".into(),
            file.display().to_string(),
            "--precision".into(),
            args.precision.to_string(),
            "--timeout".into(),
            timeout.to_string(),
            "--max-boxes".into(),
            args.max_boxes.to_string(),
        ];
        base_args.extend(lock_args.iter().cloned());
        let read_base = |m: &Measured| -> Result<Outcome> {
            let v: serde_json::Value = serde_json::from_str(m.stdout.trim()).context("reading the baseline child's line")?;
            let complete = v["status"] == "complete";
            let (uc, un) = (v["undecided_cusp_boxes"].as_u64().unwrap_or(0), v["undecided_node_pairs"].as_u64().unwrap_or(0));
            Ok(Outcome { status: status_text(complete, v["limit"].as_str()), undecided: uc + un, note: format!("{uc} + {un}") })
        };
        let (t_base, m_base, base) = repeated(lab, &base_args, args.repeat, &read_base)?;
        let mb = |b: f64| b / (1024.0 * 1024.0);
        writeln!(
            out,
            "{name} | {t_new:.3} | {:.0} | {} | {} | {} | {t_base:.3} | {:.0} | {} | {} = {} | {} | {}",
            mb(m_new),
            new.status,
            new.undecided,
            new.note,
            mb(m_base),
            base.status,
            base.undecided,
            base.note,
            ratio(t_new / t_base),
            ratio(m_new / m_base)
        )
        .ok();
    }
    writeln!(out, "total {:.1} s", total.elapsed().as_secs_f64()).ok();
    Ok(())
}

/// The hidden `bench3r --baseline-child FILE` mode: the previous behaviour on the chain the
/// shipped path selects (same rounding and chain choice), the full torus, both interval
/// searches run whatever the structure, nothing attributed afterwards. One JSON line.
pub fn baseline_child(args: &Bench3rArgs, file: &Path) -> Result<()> {
    arm3r::check_precision(args.precision)?;
    let locks = args
        .lock
        .iter()
        .map(|text| {
            let (joint, value) = text.split_once('=').with_context(|| format!("--lock '{text}': expected JOINT=VALUE"))?;
            let value: f64 = value.trim().parse().with_context(|| format!("--lock '{text}': '{value}' is not a number"))?;
            Ok((joint.to_string(), value))
        })
        .collect::<Result<Vec<_>>>()?;
    // What `linkspace singularities FILE --fix ... --ignore-limits` reads: the same rounding
    // and chain choice.
    let options = LoadOptions { spec: ChainSpec { locks, length_tolerance: 0.0, ..Default::default() }, exact_geometry: false, ignore_limits: true, ..Default::default() };
    let xml = std::fs::read_to_string(file).with_context(|| format!("reading {}", file.display()))?;
    let mechanism = urdf::parse(&xml).with_context(|| format!("loading {}", file.display()))?;
    let chain = linkspace::app::Arm::load(&mechanism, &options, 0.0).with_context(|| format!("loading {}", file.display()))?.chain;
    if !(args.timeout.is_finite() && args.timeout > 0.0) {
        bail!("--timeout must be a positive number of seconds, got {}", args.timeout);
    }
    let limits = Limits { max_cells: args.max_boxes, timeout: Some(Duration::from_secs_f64(args.timeout.min(1e9))), max_memory: BASELINE_MAX_MEMORY };
    let cancel = AtomicBool::new(false);
    let control = Control { limits, threads: 1, cancel: &cancel };
    let run = arm3r::singularities(&chain, args.precision, true, &control, &mut |_| {})?;
    let limit = match run.status {
        Status::Finished => None,
        Status::Stopped(l) => Some(l.name()),
    };
    let line = serde_json::json!({
        "status": if run.status.finished() { "complete" } else { "incomplete" },
        "limit": limit,
        "cusps": run.cusps.cusps.len(),
        "undecided_cusp_boxes": run.cusps.undecided.len(),
        "nodes": run.nodes.as_ref().map_or(0, |n| n.nodes.len()),
        "undecided_node_pairs": run.nodes.as_ref().map_or(0, |n| n.undecided.len()),
        "seconds": run.seconds,
    });
    println!("{line}");
    Ok(())
}

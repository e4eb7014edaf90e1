//! Every assembly `solve --fix J=v` certifies is a start `loop-singularities --kind motion
//! --actuated J --from v` accepts, and the motion check's first step box holds it.
//!
//! The assemblies are the library's own certified clusters (`app::load`, default settings as
//! `solve` runs), each given back as the start the way a user types it: its joint values to 6
//! and to 17 significant digits, and every angle shifted by whole turns. The check must accept
//! each, and its first proven step, which starts at `v`, must hold the certified configuration
//! (the cluster's hull, compared modulo 2π): the motion starts on the assembly given, not on a
//! neighbour. A start with one angle a radian off is refused, naming a joint: around a cycle of
//! the loop the joint angles sum to a constant modulo 2π, so no configuration lies within the
//! check's slack (0.1) of it in every joint.
//!
//! Mechanisms: random four-bars of every Grashof class, slider-cranks and Watt six-bars
//! (`random_linkages`' seeded generator: random yaws, flipped frames, axis signs, values turns
//! away), each with a seeded choice of the actuated joint, and the bundled four-bar,
//! slider-crank, Watt six-bar and double butterfly at seeded inputs; then the command line on
//! the crank-rocker at crank −2.1 and the double butterfly at joint6 = −1.2 (all 6 assemblies).

use super::random_linkages::sample;
use super::util::{urdf_text, SplitMix};
use linkspace::app::{self, check_input_motion, motion_joints, BoxStatus, Control, InputMotionCheck, MotionError, MotionRequest, SolverSettings, Status};
use linkspace::model::{urdf, JointKind, Mechanism};
use std::collections::BTreeMap;
use std::f64::consts::{PI, TAU};
use std::process::Command;
use std::sync::atomic::AtomicBool;

/// A certified configuration: per joint (the fixed one included) the middle of the cluster's
/// hull and its half-width.
type Assembly = BTreeMap<String, (f64, f64)>;

/// The assemblies `solve --fix joint=value` certifies: clusters with a member proven to hold
/// exactly one configuration. `None` when the run did not finish.
fn certified(m: &Mechanism, joint: &str, value: f64) -> Option<Vec<Assembly>> {
    let a = app::load(m, &[(joint.to_string(), value)], &[]).expect("loads");
    let r = a.configuration_space(&SolverSettings::default()).expect("valid settings").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
    if r.status != Status::Finished {
        return None;
    }
    let mut out = Vec::new();
    for c in 0..r.clusters {
        let members: Vec<_> = r.boxes.iter().filter(|b| b.cluster == Some(c)).collect();
        if !members.iter().any(|b| b.status == BoxStatus::Unique) {
            continue;
        }
        let mut a: Assembly = BTreeMap::new();
        for (i, name) in r.joint_names.iter().enumerate() {
            let lo = members.iter().map(|b| b.joints[i][0]).fold(f64::INFINITY, f64::min);
            let hi = members.iter().map(|b| b.joints[i][1]).fold(f64::NEG_INFINITY, f64::max);
            a.insert(name.clone(), (0.5 * (lo + hi), 0.5 * (hi - lo)));
        }
        a.insert(joint.to_string(), (value, 0.0));
        out.push(a);
    }
    Some(out)
}

/// Whether `name` is an angle (a revolute tree joint or loop).
fn revolute(m: &Mechanism, name: &str) -> bool {
    let kind = m.joint(name).map(|j| m.joints[j].kind).or_else(|| m.loops.iter().find(|l| l.name == name).map(|l| l.kind));
    matches!(kind, Some(JointKind::Revolute { .. }))
}

/// The literal limits of `name`, when it has any.
fn limits(m: &Mechanism, name: &str) -> Option<(f64, f64)> {
    let kind = m.joint(name).map(|j| m.joints[j].kind).or_else(|| m.loops.iter().find(|l| l.name == name).map(|l| l.kind))?;
    match kind {
        JointKind::Revolute { limits } => limits,
        JointKind::Prismatic { limits } => Some(limits),
        _ => None,
    }
}

/// Whether the box `b` holds `x` (within `slack`; modulo 2π for an angle).
fn holds(b: [f64; 2], x: f64, slack: f64, angle: bool) -> bool {
    let x = if angle { x + TAU * ((0.5 * (b[0] + b[1]) - x) / TAU).round() } else { x };
    b[0] - slack <= x && x <= b[1] + slack
}

fn motion(m: &Mechanism, joint: &str, from: f64, to: f64, assembly: Vec<f64>) -> Result<InputMotionCheck, MotionError> {
    let cancel = AtomicBool::new(false);
    let control = Control { limits: Default::default(), threads: 1, cancel: &cancel };
    let request = MotionRequest { actuated: joint.to_string(), from, to, assembly, max_step: 0.05, min_step: 1e-12, name_turning_point: false };
    check_input_motion(m, &[], &request, &control)
}

/// `format!` to `digits` significant digits, parsed back: the number as typed.
fn typed(x: f64, digits: usize) -> f64 {
    format!("{x:.*e}", digits - 1).parse().expect("number")
}

/// The certified assembly `a` of `m` (`joint` fixed at `value`) given back as starts: accepted,
/// its first step holding it, and refused a radian off. `Err` says what failed. Steps are
/// halved down to 1e-12: an input value picked from an assembly may lie a hair from a turning
/// point (a long rocker driving a short dyad turns back within 1e-6 rad).
fn check_starts(m: &Mechanism, joint: &str, value: f64, a: &Assembly, rng: &mut SplitMix) -> Result<(), String> {
    let joints = motion_joints(m, &[]).expect("a planar loop");
    let to = value + if rng.unit() < 0.5 { 0.02 } else { -0.02 };
    let exact: Vec<f64> = joints.iter().map(|j| a[j].0).collect();
    let turns: Vec<f64> = joints.iter().map(|j| if revolute(m, j) { (rng.next_u64() % 7) as f64 - 3.0 } else { 0.0 }).collect();
    // The actuated joint keeps the value `--fix` gave it, as a user copies it.
    let at = |digits: usize, k: &[f64]| -> Vec<f64> { joints.iter().zip(&exact).zip(k).map(|((j, &x), k)| if j == joint { x + k * TAU } else { typed(x + k * TAU, digits) }).collect() };
    let none = vec![0.0; joints.len()];
    let starts = [("6 digits", at(6, &none)), ("17 digits", at(17, &none)), ("whole turns away", at(17, &turns))];
    for (what, start) in starts {
        let shown = || format!("{joint} {value} -> {to}, start {what} {start:?}");
        let found = motion(m, joint, value, to, start.clone()).map_err(|e| format!("{}: refused: {e}", shown()))?;
        let first = found.steps.first().ok_or_else(|| format!("{}: no step proven ({:?})", shown(), found.verdict))?;
        if first.input[0].min(first.input[1]) > value || first.input[0].max(first.input[1]) < value {
            return Err(format!("{}: the first step {:?} does not start at the input", shown(), first.input));
        }
        for j in &joints {
            let (x, half) = a[j];
            if !holds(first.joints[j], x, half + 1e-12, revolute(m, j)) {
                return Err(format!("{}: the first step's {j} {:?} misses the certified {x} ± {half:e}", shown(), first.joints[j]));
            }
        }
    }
    // One angle a radian off: no configuration within 0.1 in every joint.
    let angles: Vec<usize> = (0..joints.len()).filter(|&k| joints[k] != joint && revolute(m, &joints[k])).collect();
    if angles.is_empty() {
        return Ok(());
    }
    let k = angles[(rng.next_u64() % angles.len() as u64) as usize];
    let mut off = exact.clone();
    off[k] += 1.0;
    match motion(m, joint, value, to, off) {
        Err(MotionError::NoAssembly { why, .. }) if why.contains("off the mechanism") && joints.iter().any(|j| why.contains(&format!("{j} = "))) => Ok(()),
        Err(e) => Err(format!("{joint} at {value}, {} a radian off: refused without naming the joint: {e}", joints[k])),
        Ok(found) => Err(format!("{joint} at {value}, {} a radian off: accepted, {:?}", joints[k], found.verdict)),
    }
}

/// The Grashof classes by the bar that is shortest when `s + l < p + q` (ground, crank,
/// coupler, rocker), then the non-Grashof triple rocker (`s + l > p + q`).
const CLASSES: [&str; 5] = ["double-crank", "crank-rocker", "double-rocker", "rocker-crank", "triple-rocker"];

/// Bar lengths (ground, crank, coupler, rocker) of the class `CLASSES[class]`, all at one
/// log-uniform scale: the shortest `s`, the longest `l` and the others `p ≤ q` with
/// `s + l < p + q` (Grashof) or `p + q < s + l < s + p + q` (a triple rocker, which still
/// assembles), kept a tenth of `s` away from the change point `s + l = p + q`.
fn bars(class: usize, rng: &mut SplitMix) -> [f64; 4] {
    let scale = 10f64.powf(rng.uniform(-2.0, 2.0));
    let (p, q) = (rng.uniform(1.5, 4.0), rng.uniform(1.5, 4.0));
    let (p, q) = (p.min(q), p.max(q));
    let s = rng.uniform(0.3, 1.0);
    let l = if class < 4 { rng.uniform(q, p + q - 1.1 * s) } else { rng.uniform(p + q - 0.9 * s, s + p + q - 0.1 * s) };
    assert!(l >= q, "the longest bar");
    // The shortest bar in its place, the others in seeded places.
    let mut rest = [p, q, l];
    for k in (1..3).rev() {
        rest.swap(k, (rng.next_u64() % (k as u64 + 1)) as usize);
    }
    let short = if class < 4 { class } else { (rng.next_u64() % 4) as usize };
    let mut out = [0.0; 4];
    let mut others = rest.iter();
    for (k, x) in out.iter_mut().enumerate() {
        *x = scale * if k == short { s } else { *others.next().expect("three others") };
    }
    out
}

/// A four-bar with bars (ground, crank, coupler, rocker) as URDF, its frames in seeded
/// conventions: every origin at a random direction and yaw, every axis +z or −z.
fn four_bar(bars: [f64; 4], rng: &mut SplitMix) -> String {
    let mut origin = |length: f64| {
        let (a, yaw) = (rng.uniform(-PI, PI), if rng.unit() < 0.2 { 0.0 } else { rng.uniform(-PI, PI) });
        format!("<origin xyz=\"{} {} 0\" rpy=\"0 0 {yaw}\"/>", length * a.cos(), length * a.sin())
    };
    let (crank, coupler, rocker, on_coupler, on_rocker) = (origin(0.0), origin(bars[1]), origin(bars[0]), origin(bars[2]), origin(bars[3]));
    let mut axis = || if rng.unit() < 0.5 { "0 0 1" } else { "0 0 -1" };
    let axes = [axis(), axis(), axis(), axis()];
    let joint = |name: &str, parent: &str, child: &str, origin: &str, axis: &str| {
        format!("  <joint name=\"{name}\" type=\"continuous\"><parent link=\"{parent}\"/><child link=\"{child}\"/>{origin}<axis xyz=\"{axis}\"/></joint>\n")
    };
    let mut u = String::from("<?xml version=\"1.0\"?>\n<robot name=\"random_four_bar\">\n");
    for l in ["ground", "crank", "coupler", "rocker"] {
        u += &format!("  <link name=\"{l}\"/>\n");
    }
    u += &joint("crank_joint", "ground", "crank", &crank, axes[0]);
    u += &joint("coupler_joint", "crank", "coupler", &coupler, axes[1]);
    u += &joint("rocker_joint", "ground", "rocker", &rocker, axes[2]);
    u += &format!(
        "  <loop name=\"loop_coupler_rocker\" type=\"revolute\"><predecessor link=\"coupler\">{on_coupler}</predecessor><successor link=\"rocker\">{on_rocker}</successor><axis xyz=\"{}\"/></loop>\n</robot>\n",
        axes[3]
    );
    u
}

/// A seeded free joint of `m` and a value of it, seeded turns out, at which `solve --fix`
/// certifies assemblies (up to 20 tries), with them.
fn seeded_input(m: &Mechanism, rng: &mut SplitMix) -> Option<(String, f64, Vec<Assembly>)> {
    let joints = motion_joints(m, &[]).ok()?;
    for _ in 0..20 {
        let joint = joints[(rng.next_u64() % joints.len() as u64) as usize].clone();
        let value = match limits(m, &joint) {
            Some((lo, hi)) if !revolute(m, &joint) => typed(rng.uniform(lo, hi), 6),
            Some(_) => continue,
            None => typed(rng.uniform(-PI, PI) + TAU * ((rng.next_u64() % 5) as f64 - 2.0), 6),
        };
        if let Some(a) = certified(m, &joint, value).filter(|a| !a.is_empty()) {
            return Some((joint, value, a));
        }
    }
    None
}

/// Runs `check_starts` on every assembly, collecting failures under `name`; how many.
fn check_all(m: &Mechanism, joint: &str, value: f64, assemblies: &[Assembly], rng: &mut SplitMix, name: &str, failures: &mut Vec<String>) -> usize {
    for a in assemblies {
        if let Err(why) = check_starts(m, joint, value, a, rng) {
            failures.push(format!("{name}: {why}"));
        }
    }
    assemblies.len()
}

/// The actuated joint of a generated mechanism and its value: a seeded free joint, at the value
/// it has in an assembly with the crank at `crank`, shifted by seeded whole turns while inside
/// its limits; `None` when the mechanism cannot close or the value is outside the joint's
/// limits.
fn pick_input(m: &Mechanism, crank: f64, rng: &mut SplitMix) -> Option<(String, f64)> {
    // A stretched mechanism that cannot close has no start to check.
    let joints = motion_joints(m, &[]).ok()?;
    let joint = joints[(rng.next_u64() % joints.len() as u64) as usize].clone();
    if joint == "crank_joint" {
        return Some((joint, crank));
    }
    let at_crank = certified(m, "crank_joint", crank)?;
    let mut v = at_crank.first()?.get(&joint)?.0;
    if revolute(m, &joint) {
        v += TAU * ((rng.next_u64() % 5) as f64 - 2.0);
        if let Some((lo, _)) = limits(m, &joint) {
            // The least value of the joint at or above its lower limit.
            v += TAU * ((lo - v) / TAU).ceil();
        }
    }
    let v = typed(v, 8);
    limits(m, &joint).is_none_or(|(lo, hi)| lo <= v && v <= hi).then_some((joint, v))
}

/// Four-bars per Grashof class, and generated slider-cranks, Watt six-bars and four-bars.
const PER_CLASS: usize = 8;
const PER_FAMILY: usize = 10;

#[test]
fn every_certified_assembly_of_random_loops_starts_the_motion_check() {
    let mut failures = Vec::new();
    let mut checked = 0;
    for (class, name) in CLASSES.iter().enumerate() {
        let mut rng = SplitMix(0x4752_4153 + class as u64);
        let mut cases = 0;
        for _ in 0..4 * PER_CLASS {
            let urdf = four_bar(bars(class, &mut rng), &mut rng);
            let m = urdf::parse(&urdf).expect("the four-bar parses");
            let Some((joint, value, assemblies)) = seeded_input(&m, &mut rng) else { continue };
            checked += check_all(&m, &joint, value, &assemblies, &mut rng, &format!("{name}, --fix {joint}={value}\n{urdf}"), &mut failures);
            cases += 1;
            if cases == PER_CLASS {
                break;
            }
        }
        assert_eq!(cases, PER_CLASS, "{name}: four-bars with certified assemblies");
    }
    // The generator of `random_linkages`: flipped frames, z offsets, limits turns away.
    let mut cases: BTreeMap<&str, usize> = BTreeMap::new();
    for seed in 0..20 * PER_FAMILY as u64 {
        let s = sample(seed);
        if cases.get(s.family).copied().unwrap_or(0) >= PER_FAMILY {
            continue;
        }
        let m = urdf::parse(&s.urdf).expect("generated URDF parses");
        let mut rng = SplitMix(seed ^ 0x5747_4152_5453);
        let Some((joint, value)) = pick_input(&m, s.crank, &mut rng) else { continue };
        let Some(assemblies) = certified(&m, &joint, value).filter(|a| !a.is_empty()) else { continue };
        checked += check_all(&m, &joint, value, &assemblies, &mut rng, &format!("seed {seed} ({}), --fix {joint}={value}\n{}", s.family, s.urdf), &mut failures);
        *cases.entry(s.family).or_default() += 1;
    }
    assert!(failures.is_empty(), "{} of {checked} assemblies:\n{}", failures.len(), failures.join("\n"));
    assert!(cases.values().all(|&n| n == PER_FAMILY) && cases.len() == 3, "generated mechanisms with certified assemblies: {cases:?}");
}

#[test]
fn every_certified_assembly_of_the_bundled_loops_starts_the_motion_check() {
    let mut failures = Vec::new();
    let mut checked = 0;
    for (k, name) in ["four_bar.urdf", "slider_crank.urdf", "watt_six_bar.urdf", "double_butterfly.urdf"].into_iter().enumerate() {
        let m = urdf::parse(&urdf_text(name)).expect("bundled URDF parses");
        let mut rng = SplitMix(0xB0B + k as u64);
        for _ in 0..3 {
            let (joint, value, assemblies) = seeded_input(&m, &mut rng).expect("a seeded input with certified assemblies");
            checked += check_all(&m, &joint, value, &assemblies, &mut rng, &format!("{name}, --fix {joint}={value}"), &mut failures);
        }
    }
    assert!(failures.is_empty(), "{} of {checked} assemblies:\n{}", failures.len(), failures.join("\n"));
}

fn linkspace(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_linkspace")).args(args).output().expect("runs")
}

fn repo(path: &str) -> String {
    format!("{}/{path}", env!("CARGO_MANIFEST_DIR"))
}

/// The crank-rocker at crank −2.1: both assemblies `solve` prints, typed back in the order
/// the motion check names, turn the crank clear to −2.0 (it turns fully); the coupler half a
/// radian off is refused, naming it and the distance.
#[test]
fn the_crank_rockers_printed_assemblies_start_its_crank_motion() {
    let out = linkspace(&["solve", &repo("urdf/four_bar.urdf"), "--fix", "crank_joint=-2.1"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout);
    let printed: Vec<BTreeMap<&str, &str>> =
        text.lines().filter_map(|l| l.trim().strip_prefix('#')).map(|l| l.split_whitespace().skip(1).filter_map(|p| p.split_once('=')).collect()).collect();
    assert_eq!(printed.len(), 2, "{text}");
    let motion = |assembly: &str| linkspace(&["loop-singularities", &repo("urdf/four_bar.urdf"), "--kind", "motion", "--actuated", "crank_joint", "--from", "-2.1", "--to", "-2.0", "--assembly", assembly]);
    let mut typed_back = Vec::new();
    for p in &printed {
        let assembly = format!("-2.1,{},{},{}", p["coupler_joint"], p["rocker_joint"], p["loop_coupler_rocker"]);
        let out = motion(&assembly);
        assert!(out.status.success(), "{assembly}: {}", String::from_utf8_lossy(&out.stderr));
        assert!(String::from_utf8_lossy(&out.stdout).contains(": clear"), "{assembly}: {}", String::from_utf8_lossy(&out.stdout));
        typed_back.push(assembly);
    }
    assert!(typed_back.contains(&"-2.1,-3.138090,2.474642,1.429547".to_string()), "{typed_back:?}");
    let out = motion("-2.1,-2.638090,2.474642,1.429547");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("off the mechanism") && err.contains("coupler_joint = -2.63809 is 0.500 from -3.138090"), "{err}");
}

/// The double butterfly at joint6 = −1.2: each of the 6 assemblies `solve --json` certifies,
/// typed back with 6 and 17 digits, starts the motion to −1.15, and the first step box of the
/// `--json` certificate holds the solve's box.
#[test]
fn the_double_butterflys_six_assemblies_at_joint6_start_its_motion() {
    let dir = std::env::temp_dir().join(format!("linkspace-motion-starts-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let (solved, motion_json) = (dir.join("solve.json"), dir.join("motion.json"));
    let urdf = repo("urdf/double_butterfly.urdf");
    let out = linkspace(&["solve", &urdf, "--fix", "joint6=-1.2", "--json", solved.to_str().expect("utf-8")]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&solved).expect("written")).expect("JSON");
    let solutions: Vec<&serde_json::Value> = r["solutions"].as_array().expect("solutions").iter().filter(|s| s["unique"] == true).collect();
    assert_eq!(solutions.len(), 6);
    let order = ["joint7", "joint2", "joint1", "joint5", "joint6", "joint3", "joint4", "loop15", "loop13", "loop24"];
    for s in &solutions {
        let bound = |j: &str| -> [f64; 2] {
            if j == "joint6" {
                return [-1.2, -1.2];
            }
            let b = &s["joints"][j];
            [b[0].as_f64().expect("number"), b[1].as_f64().expect("number")]
        };
        for digits in [6, 17] {
            let assembly: Vec<String> = order.iter().map(|j| format!("{:.*e}", digits - 1, 0.5 * (bound(j)[0] + bound(j)[1]))).collect();
            let args = ["--kind", "motion", "--actuated", "joint6", "--from", "-1.2", "--to", "-1.15", "--assembly", &assembly.join(","), "--json", motion_json.to_str().expect("utf-8")];
            let out = linkspace(&[&["loop-singularities", urdf.as_str()][..], &args[..]].concat());
            assert!(out.status.success(), "{}: {}", assembly.join(","), String::from_utf8_lossy(&out.stderr));
            let found: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&motion_json).expect("written")).expect("JSON");
            let first = &found["steps"][0];
            assert_eq!(first["input"][0].as_f64(), Some(-1.2), "{first}");
            for j in order {
                let step = [first["joints"][j][0].as_f64().expect("number"), first["joints"][j][1].as_f64().expect("number")];
                let b = bound(j);
                assert!(holds(step, 0.5 * (b[0] + b[1]), 0.5 * (b[1] - b[0]) + 1e-12, true), "{j}: step {step:?}, solve {b:?}");
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

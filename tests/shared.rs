//! Searches shared by MPI ranks (`mpirun -np N linkspace ...`, the `mpi` feature) report what
//! one process reports: the same boxes in the same order, the same counts and status.
//!
//! The default build has no MPI, so these tests build the `mpi` binary themselves, in its own
//! target directory (`target/mpi`), after `scripts/mpi_env.sh` has installed OpenMPI and
//! libclang (Debian packages).

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The `linkspace` binary built with `--features mpi` (built once per test run).
fn mpi_binary() -> &'static Path {
    static BIN: OnceLock<PathBuf> = OnceLock::new();
    BIN.get_or_init(|| {
        let env = Command::new("sh").arg(repo().join("scripts/mpi_env.sh")).output().expect("sh runs");
        assert!(env.status.success(), "scripts/mpi_env.sh failed (it installs OpenMPI with apt, as root or with sudo): {}", String::from_utf8_lossy(&env.stderr));
        let target = repo().join("target/mpi");
        // Seeded from the default build: the dependencies are the same, so only the `mpi`
        // crates and linkspace itself compile (minutes less on a fresh machine).
        let seed = repo().join("target/release");
        if !target.exists() && seed.exists() {
            std::fs::create_dir_all(&target).expect("target/mpi");
            let copied = Command::new("cp").arg("-a").arg(&seed).arg(target.join("release")).status().expect("cp runs");
            assert!(copied.success(), "seeding target/mpi from target/release");
        }
        let build = Command::new(env!("CARGO"))
            .current_dir(repo())
            .args(["build", "--release", "--features", "mpi", "--bin", "linkspace", "--target-dir"])
            .arg(&target)
            .output()
            .expect("cargo runs");
        assert!(build.status.success(), "building with --features mpi failed: {}", String::from_utf8_lossy(&build.stderr));
        target.join("release/linkspace")
    })
}

/// The `mpi` binary under `mpirun -np ranks` (alone for 0), in the repository.
fn linkspace_on(ranks: usize) -> Command {
    let bin = mpi_binary();
    let mut cmd = if ranks == 0 {
        Command::new(bin)
    } else {
        let mut c = Command::new("mpirun");
        // CI runs as root, and on 2 cores: both need saying to OpenMPI.
        c.env("OMPI_ALLOW_RUN_AS_ROOT", "1").env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1");
        c.args(["--oversubscribe", "-np", &ranks.to_string()]).arg(bin);
        c
    };
    cmd.current_dir(repo());
    cmd
}

/// Runs `linkspace ARGS --json F` under `mpirun -np ranks` (or alone for 0), and returns the
/// report and stdout.
fn report(ranks: usize, args: &[&str]) -> (Value, String) {
    let json = std::env::temp_dir().join(format!("linkspace-shared-{}-{ranks}-{}.json", std::process::id(), args.join("_").replace(['/', '='], "-")));
    let out = linkspace_on(ranks).args(args).arg("--json").arg(&json).output().expect("mpirun runs");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "{ranks} ranks, {args:?}: {stdout}{}", String::from_utf8_lossy(&out.stderr));
    let value = serde_json::from_str(&std::fs::read_to_string(&json).expect("rank 0 writes the report")).expect("json");
    let _ = std::fs::remove_file(&json);
    (value, stdout)
}

/// The report without what depends on the run rather than the problem, at any depth: times
/// and counters of the machine, and the thread count.
fn answer(mut v: Value) -> Value {
    fn strip(v: &mut Value) {
        match v {
            Value::Object(o) => {
                for key in ["stats", "seconds", "cpu_seconds", "threads"] {
                    o.remove(key);
                }
                o.values_mut().for_each(strip);
            }
            Value::Array(a) => a.iter_mut().for_each(strip),
            _ => {}
        }
    }
    strip(&mut v);
    v
}

/// The same answer from one process on two threads and from two and three ranks on one thread
/// each.
fn same_everywhere(args: &[&str]) -> Value {
    let mut alone = args.to_vec();
    alone.extend(["--threads", "2"]);
    let (reference, _) = report(0, &alone);
    let reference = answer(reference);
    let mut shared = args.to_vec();
    shared.extend(["--threads", "1"]);
    for ranks in [2, 3] {
        let (got, _) = report(ranks, &shared);
        assert!(answer(got) == reference, "{ranks} ranks differ from one process: {args:?}");
    }
    reference
}

#[test]
fn planar_solve_is_the_same_on_ranks() {
    let r = same_everywhere(&["solve", "urdf/double_butterfly.urdf", "--sigma", "0.05"]);
    assert!(r["solutions"].as_array().is_some_and(|s| s.len() > 1000), "the mobile butterfly's curve");
    let r = same_everywhere(&["solve", "urdf/double_butterfly.urdf", "--fix", "joint6=1.1760052070951352", "--sigma", "1e-4"]);
    assert_eq!(r["status"], "complete");
    // The five-bar's configuration surface.
    let r = same_everywhere(&["solve", "urdf/five_bar.urdf", "--sigma", "0.1"]);
    assert!(r["solutions"].as_array().is_some_and(|s| s.len() > 1000), "the five-bar's surface");
}

/// A rank that dies mid-run ends the whole run with an error, well before its timeout: the
/// other ranks are not left waiting for it.
#[test]
fn a_rank_killed_mid_run_ends_the_run_with_an_error() {
    let mut run = linkspace_on(2)
        .args(["solve", "urdf/five_bar.urdf", "--sigma", "0.001", "--timeout", "120", "--threads", "1"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("mpirun starts");
    // The ranks are mpirun's children; kill one of them once both are searching.
    std::thread::sleep(std::time::Duration::from_secs(3));
    let ranks: Vec<u32> = std::fs::read_dir("/proc")
        .expect("/proc")
        .filter_map(|e| e.ok()?.file_name().to_str()?.parse::<u32>().ok())
        .filter(|pid| {
            let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
            // pid (comm) state ppid ...
            let after = stat.rsplit_once(')').map_or("", |(_, rest)| rest);
            stat.contains("(linkspace)") && after.split_whitespace().nth(1).and_then(|p| p.parse::<u32>().ok()) == Some(run.id())
        })
        .collect();
    assert_eq!(ranks.len(), 2, "two ranks under mpirun");
    let killed = Command::new("kill").args(["-9", &ranks[1].to_string()]).status().expect("kill runs");
    assert!(killed.success());
    let t0 = std::time::Instant::now();
    let status = loop {
        if let Some(s) = run.try_wait().expect("mpirun waits") {
            break s;
        }
        if t0.elapsed().as_secs() > 60 {
            let _ = run.kill();
            panic!("mpirun still running 60 s after a rank was killed");
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    };
    let out = run.wait_with_output().expect("output");
    assert!(!status.success(), "a killed rank fails the run");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("signal 9") || stderr.contains("Killed") || stderr.contains("exited on signal"), "mpirun names the dead rank: {stderr}");
}

#[test]
fn spatial_solve_distances_and_loop_singularities_are_the_same_on_ranks() {
    let r = same_everywhere(&["solve", "urdf/bennett.urdf", "--model", "spatial", "--sigma", "0.02"]);
    assert_eq!(r["model"], "spatial");
    same_everywhere(&["distances", "urdf/four_spheres.json", "--sigma", "0.01"]);
    same_everywhere(&["loop-singularities", "urdf/five_bar.urdf", "--sigma", "0.01"]);
    same_everywhere(&["loop-singularities", "urdf/five_bar_unequal.urdf", "--actuated", "crank1_joint,crank2_joint", "--kind", "cusps", "--sigma", "1e-2"]);
    same_everywhere(&["singularities", "urdf/orthogonal_3r_e.urdf", "--nodes"]);
    same_everywhere(&["ik", "urdf/orthogonal_3r_a.urdf", "--point", "3,1"]);
}

/// A box limit stops every rank at the same box: the same boxes reported and the same left
/// undecided as one process; a time limit ends the run on every rank, with rank 0 reporting it.
#[test]
fn limits_hold_for_the_whole_run() {
    let r = same_everywhere(&["solve", "urdf/double_butterfly.urdf", "--sigma", "0.05", "--max-boxes", "300"]);
    assert_eq!(r["status"], "incomplete");
    assert!(r["undecided"].as_array().is_some_and(|u| !u.is_empty()));
    let (r, out) = report(3, &["solve", "urdf/five_bar.urdf", "--sigma", "0.002", "--timeout", "1", "--threads", "1"]);
    assert_eq!(r["status"], "incomplete", "{out}");
    assert!(out.matches("five_bar").count() == 1, "rank 0 alone prints: {out}");
}

/// A sweep on ranks: each rank runs its share of the tasks, and rank 0 writes the same table as
/// one process; a sweep stopped on ranks resumes from every rank's results file.
#[test]
fn a_sweep_on_ranks_gives_the_table_of_one_process_and_resumes_from_rank_files() {
    let spec = "examples/sweeps/three_rpr_assembly_modes.json";
    let dir = |name: &str| std::env::temp_dir().join(format!("linkspace-sweep-{}-{name}", std::process::id()));
    let sweep = |ranks: usize, out: &Path, extra: &[&str]| {
        let o = linkspace_on(ranks).args(["sweep", spec, "--out"]).arg(out).args(extra).output().expect("runs");
        assert!(o.status.success(), "{ranks} ranks: {}", String::from_utf8_lossy(&o.stderr));
    };
    // The table without its time column (the last but one; `error` is last).
    let table = |out: &Path| -> Vec<String> {
        let text = std::fs::read_to_string(out.join("results.csv")).expect("results.csv");
        text.lines().map(|l| l.split(',').collect::<Vec<_>>()).map(|f| [&f[..f.len() - 2], &f[f.len() - 1..]].concat().join(",")).collect()
    };
    let (alone, shared, resumed) = (dir("alone"), dir("ranks"), dir("resumed"));
    for d in [&alone, &shared, &resumed] {
        let _ = std::fs::remove_dir_all(d);
    }
    sweep(0, &alone, &[]);
    sweep(2, &shared, &[]);
    assert_eq!(table(&shared), table(&alone));
    assert!(table(&alone).len() > 200);
    let left: Vec<_> = std::fs::read_dir(&shared).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).filter(|n| n.contains("rank")).collect();
    assert!(left.is_empty(), "rank files left: {left:?}");
    // A run on 2 ranks stopped midway: rank 0 had written the even tasks up to 100, rank 1 the
    // odd ones up to 50 (in its own file).
    std::fs::create_dir_all(&resumed).unwrap();
    let lines: Vec<String> = std::fs::read_to_string(alone.join("results.jsonl")).unwrap().lines().map(String::from).collect();
    let index = |l: &str| serde_json::from_str::<Value>(l).ok().and_then(|v| v["index"].as_u64());
    let header = &lines[0];
    let pick = |keep: &dyn Fn(u64) -> bool| -> String { std::iter::once(header.clone()).chain(lines[1..].iter().filter(|l| index(l).is_some_and(keep)).cloned()).collect::<Vec<_>>().join("\n") + "\n" };
    std::fs::write(resumed.join("results.jsonl"), pick(&|i| i % 2 == 0 && i <= 100)).unwrap();
    std::fs::write(resumed.join("results.rank-1.jsonl"), pick(&|i| i % 2 == 1 && i <= 50)).unwrap();
    sweep(2, &resumed, &["--resume"]);
    assert_eq!(table(&resumed), table(&alone));
    assert!(!resumed.join("results.rank-1.jsonl").exists());
    for d in [&alone, &shared, &resumed] {
        let _ = std::fs::remove_dir_all(d);
    }
}

//! Test idea: the invariants of ARCHITECTURE.md that can be read off the source are checked
//! here, so the map stays true: the layers point down (kernel, model, formulate, analyses, app,
//! edges), each foreign crate sits behind its one module, builders never solve, serde only where
//! results are written, the front ends reach the library through the front door alone, one
//! outcome vocabulary, every question reachable from both front ends, and files and functions of
//! a readable size.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every `.rs` file under `dir`.
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).expect("readable source tree") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// A file's path under `src/`, with `/` separators.
fn rel(path: &Path) -> String {
    path.strip_prefix(src()).expect("under src").to_string_lossy().replace('\\', "/")
}

/// The library's layers, bottom first: a module may name only the layers below its own.
const LAYERS: [&str; 6] = ["kernel", "model", "formulate", "analyses", "app", "edges"];

/// The library layer of a file under `src/` (`None` for the binaries' files and `lib.rs`).
fn layer(path: &Path) -> Option<&'static str> {
    let r = rel(path);
    let first = r.split('/').next()?.trim_end_matches(".rs");
    LAYERS.iter().copied().find(|l| *l == first)
}

/// The code of a file without comment lines and without its unit-test module (which may use
/// anything), as (line number, text). A `#[cfg(test)]` item other than a module (a test-only
/// helper) does not end the file.
fn code_lines(path: &Path) -> Vec<(usize, String)> {
    let text = std::fs::read_to_string(path).expect("readable");
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (k, line) in lines.iter().enumerate() {
        let t = line.trim_start();
        if t.starts_with("#[cfg(test)]") && lines.get(k + 1).is_some_and(|next| next.trim_start().starts_with("mod ")) {
            break;
        }
        if t.starts_with("//") {
            continue;
        }
        out.push((k + 1, line.to_string()));
    }
    out
}

/// Every `prefix::a::b` path named in `line` (outside string literals), as `a::b`.
fn paths_after<'a>(line: &'a str, prefix: &str) -> Vec<&'a str> {
    let mut found = Vec::new();
    let mut in_string = false;
    let bytes = line.as_bytes();
    for (k, c) in line.char_indices() {
        if c == '"' && (k == 0 || bytes[k - 1] != b'\\') {
            in_string = !in_string;
        } else if !in_string && line[k..].starts_with(prefix) && (k == 0 || !(bytes[k - 1].is_ascii_alphanumeric() || bytes[k - 1] == b'_' || bytes[k - 1] == b':')) {
            let rest = &line[k + prefix.len()..];
            let end = rest.find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':')).unwrap_or(rest.len());
            found.push(&rest[..end]);
        }
    }
    found
}

/// Which layers each layer names (`crate::x`), with one line naming it as evidence.
fn dependencies() -> BTreeMap<&'static str, BTreeMap<&'static str, String>> {
    let mut deps: BTreeMap<&'static str, BTreeMap<&'static str, String>> = BTreeMap::new();
    for path in files(&src()) {
        let Some(from) = layer(&path) else { continue };
        for (n, line) in code_lines(&path) {
            for p in paths_after(&line, "crate::") {
                let to = p.split("::").next().unwrap_or("");
                if let Some(to) = LAYERS.iter().copied().find(|l| *l == to && *l != from) {
                    deps.entry(from).or_default().entry(to).or_insert_with(|| format!("src/{}:{n}: {}", rel(&path), line.trim()));
                }
            }
        }
    }
    deps
}

#[test]
fn the_layers_point_down() {
    let deps = dependencies();
    let rank = |l: &str| LAYERS.iter().position(|x| *x == l).expect("a layer");
    let mut upward = Vec::new();
    for (from, tos) in &deps {
        for (to, evidence) in tos {
            if rank(to) > rank(from) {
                upward.push(format!("{from} names {to}: {evidence}"));
            }
        }
    }
    assert!(upward.is_empty(), "a layer names one above it:\n{}", upward.join("\n"));
    // The test sees the layers at all: the front door names the analyses.
    assert!(deps.get("app").is_some_and(|t| t.contains_key("analyses")), "{deps:?}");
}

/// Lines of library files outside `allowed` (path prefixes under src/) that name `needle`.
fn uses_outside(needle: &str, allowed: &[&str]) -> Vec<String> {
    let mut found = Vec::new();
    for path in files(&src()) {
        let r = rel(&path);
        if allowed.iter().any(|a| r.starts_with(a)) {
            continue;
        }
        for (n, line) in code_lines(&path) {
            if line.contains(needle) {
                found.push(format!("src/{r}:{n}: {}", line.trim()));
            }
        }
    }
    found
}

#[test]
fn each_foreign_crate_is_behind_one_module() {
    for (krate, home) in [
        ("clarabel::", &["kernel/lp/"][..]),
        ("urdf_rs::", &["model/urdf.rs"][..]),
        ("roxmltree::", &["model/"][..]),
        ("ros2_client::", &["edges/ros/"][..]),
        ("rustdds::", &["edges/ros/"][..]),
        ("plotters::", &["bin/"][..]),
        ("yaml_rust2::", &["cli/ros_args.rs"][..]),
        ("mpi::", &["cli/ranks.rs"][..]),
    ] {
        let outside = uses_outside(krate, home);
        assert!(outside.is_empty(), "{krate} outside {home:?}:\n{}", outside.join("\n"));
    }
}

#[test]
fn builders_never_solve() {
    let builders: Vec<PathBuf> = files(&src().join("formulate"));
    assert!(builders.len() > 5, "the builders are under src/formulate");
    for call in [".enclose(", "search::run", "run_by_level", "drop_spurious("] {
        let hits: Vec<String> = builders.iter().flat_map(|p| code_lines(p).into_iter().filter(|(_, l)| l.contains(call)).map(move |(n, l)| format!("src/{}:{n}: {}", rel(p), l.trim()))).collect();
        assert!(hits.is_empty(), "a builder runs a search ({call}):\n{}", hits.join("\n"));
    }
}

/// Where serde may be named: the JSON writers (`edges/report`), the node (`edges/ros`), the
/// binaries, the reader of the distance file format, and the sweep's own file formats (its spec
/// and its result lines, which it reads back to resume).
const SERDE_HOMES: [&str; 8] = ["edges/report", "edges/ros/", "main.rs", "cli", "bin/", "analyses/distances/file.rs", "analyses/sweep/spec.rs", "analyses/sweep/records.rs"];

#[test]
fn only_the_edges_know_serde() {
    let outside = uses_outside("serde", &SERDE_HOMES);
    assert!(outside.is_empty(), "serde outside the edges (library types are plain data; `report` says how they are written, with remote definitions where a type is more than a record):\n{}", outside.join("\n"));
}

/// What the front ends may name of the library: the front door (`app`, which re-exports the
/// outcome vocabulary and the options jobs take), the outcome model, and their edge: the JSON
/// writers for the CLI and the Python package, the node itself for `serve`.
#[test]
fn the_front_ends_use_only_the_front_door() {
    let cli: Vec<PathBuf> = files(&src()).into_iter().filter(|p| {
        let r = rel(p);
        r == "main.rs" || r == "cli.rs" || r.starts_with("cli/")
    }).collect();
    let ros: Vec<PathBuf> = files(&src().join("edges/ros"));
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let python: Vec<PathBuf> = files(&repo.join("python/linkspace/src"));
    assert!(cli.len() > 5 && ros.len() > 3 && python.len() >= 3, "the front ends are where the map says");
    let mut wrong = Vec::new();
    for (files, prefix, allowed) in [
        (&cli, "linkspace::", &["app", "edges::report", "edges::ros"][..]),
        (&ros, "crate::", &["app", "kernel::outcome", "edges::ros"][..]),
        (&python, "linkspace::", &["app", "edges::report"][..]),
    ] {
        for path in files {
            for (n, line) in code_lines(path) {
                for p in paths_after(&line, prefix) {
                    if !allowed.iter().any(|a| p == *a || p.starts_with(&format!("{a}::"))) {
                        wrong.push(format!("{}:{n}: {prefix}{p}", path.strip_prefix(repo).unwrap_or(path).display()));
                    }
                }
            }
        }
    }
    // The check sees the binding's names at all: it names the front door.
    assert!(python.iter().any(|p| code_lines(p).iter().any(|(_, l)| l.contains("linkspace::app::"))), "the Python package names app");
    assert!(wrong.is_empty(), "a front end reaches past the front door:\n{}", wrong.join("\n"));
}

/// Items of `kind` (`enum`, `struct`) declared in library code, as (file, name, body).
fn items(kind: &str) -> Vec<(String, String, String)> {
    let mut out = Vec::new();
    for path in files(&src()) {
        if rel(&path).starts_with("bin/") {
            continue;
        }
        let code: Vec<String> = code_lines(&path).into_iter().map(|(_, l)| l).collect();
        for (k, line) in code.iter().enumerate() {
            let t = line.trim_start();
            let t = t.strip_prefix("pub(crate) ").or_else(|| t.strip_prefix("pub(super) ")).or_else(|| t.strip_prefix("pub ")).unwrap_or(t);
            let Some(rest) = t.strip_prefix(&format!("{kind} ")) else { continue };
            let name: String = rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
            let body: Vec<&str> = code[k..].iter().take_while(|l| !l.starts_with('}') && !l.starts_with("    }")).map(String::as_str).take(60).collect();
            out.push((rel(&path), name, body.join("\n")));
        }
    }
    out
}

#[test]
fn one_outcome_vocabulary() {
    // One completeness type: no other enum has a `Complete` variant, and only the outcome
    // module spells the word.
    let complete: Vec<String> = items("enum")
        .into_iter()
        .filter(|(_, _, body)| body.lines().any(|l| matches!(l.trim().trim_end_matches(','), "Complete" | "Incomplete")))
        .map(|(file, name, _)| format!("{file}: {name}"))
        .collect();
    assert_eq!(complete, ["kernel/outcome.rs: Completeness"], "completeness types");
    let spelled = uses_outside("\"complete\"", &["kernel/outcome.rs", "bin/"]);
    assert!(spelled.is_empty(), "\"complete\" spelled outside the outcome module:\n{}", spelled.join("\n"));
    // One box tag: no second enum of unique / solution / undecided, no flags beside box lists.
    let tags: Vec<String> = items("enum")
        .into_iter()
        .filter(|(_, _, body)| body.contains("Undecided") && (body.contains("Unique") || body.contains("Certified")) && body.contains("Solution"))
        .map(|(file, name, _)| format!("{file}: {name}"))
        .collect();
    assert_eq!(tags, ["kernel/outcome.rs: BoxStatus"], "box tags");
    let flags = uses_outside("unique: Vec<bool>", &["edges/ros/msgs.rs"]);
    assert!(flags.is_empty(), "a list of flags beside a list of boxes:\n{}", flags.join("\n"));
    // Verdicts are typed: no verdict held as text outside the edges' records.
    let text_verdicts: Vec<String> = ["verdict: &'static str", "verdict: String", "answer: &'static str"].iter().flat_map(|n| uses_outside(n, &["edges/", "analyses/sweep/records.rs", "bin/"])).collect();
    assert!(text_verdicts.is_empty(), "a verdict as text:\n{}", text_verdicts.join("\n"));
}

/// Every question, the CLI subcommand that asks it, and the node's service that asks it with
/// where the node's `Job` is built (`None`: no node service asks it).
/// The node's service of a question, and the file (or folder) where the node's job is built.
type NodeRoute = Option<(&'static str, &'static str)>;

const QUESTIONS: [(&str, &str, NodeRoute); 10] = [
    ("Solve", "solve", Some(("solve", "app/linkage.rs"))),
    ("Singularities", "singularities", Some(("singularities", "app/arm_analysis.rs"))),
    ("Ik", "ik", Some(("inverse_kinematics", "app/arm_analysis.rs"))),
    ("Ik6", "ik6", Some(("inverse_kinematics6", "edges/ros"))),
    ("PathCheck", "path-check", Some(("path_check", "edges/ros"))),
    ("SelfMotion", "self-motion", Some(("self_motion", "edges/ros"))),
    ("Collisions", "collisions", Some(("collisions", "edges/ros"))),
    // A platform's configuration space and Solve requests.
    ("Distances", "distances", Some(("solve", "app/platform.rs"))),
    // A linkage's singular sets.
    ("LoopSingularities", "loop-singularities", Some(("singularities", "app/linkage.rs"))),
    ("SweepTask", "sweep", None),
];

/// Questions whose `Job` the front ends build through one function of `app` (the call, and the
/// file that builds the job): a sweep's tasks, each a failed row rather than an error.
const CLI_THROUGH: [(&str, &str, &str); 1] = [("SweepTask", "answer_task(", "app/sweep.rs")];

#[test]
fn every_question_is_reachable_from_the_front_ends() {
    let job = std::fs::read_to_string(src().join("app/job.rs")).expect("the jobs");
    let variants: BTreeSet<String> = job
        .split("pub enum Job {")
        .nth(1)
        .and_then(|b| b.split("\n}").next())
        .expect("the Job enum")
        .lines()
        .map(str::trim)
        .filter(|l| !l.starts_with("//"))
        .filter_map(|l| l.split_once('(').map(|(v, _)| v.to_string()))
        .collect();
    let table: BTreeSet<String> = QUESTIONS.iter().map(|(v, _, _)| v.to_string()).collect();
    assert_eq!(variants, table, "the table lists every Job variant");
    let read_all = |paths: Vec<PathBuf>| paths.iter().map(|p| std::fs::read_to_string(p).expect("readable")).collect::<Vec<_>>().join("\n");
    let cli = read_all(files(&src()).into_iter().filter(|p| rel(p) == "cli.rs" || rel(p).starts_with("cli/")).collect());
    let ros = read_all(files(&src().join("edges/ros")));
    // The node's queries on a loaded mechanism become jobs in its `Analysis`, and every one of
    // them runs through the front door (`JobRun` prepares it).
    let results = std::fs::read_to_string(src().join("app/results.rs")).expect("readable");
    assert!(results.contains("prepare(input, job)"), "the node's runs are prepared by the front door");
    for (variant, command, node) in QUESTIONS {
        match CLI_THROUGH.iter().find(|(v, _, _)| *v == variant) {
            Some((_, call, builder)) => {
                assert!(cli.contains(call), "the CLI never calls {call}");
                let built = std::fs::read_to_string(src().join(builder)).expect("readable");
                assert!(built.contains(&format!("Job::{variant}(")), "{builder} never builds Job::{variant}");
            }
            None => assert!(cli.contains(&format!("Job::{variant}(")), "the CLI never builds Job::{variant}"),
        }
        let kebab = command.replace('-', "_");
        assert!(cli.contains(&format!("Command::{}(", kebab.split('_').map(|w| w[..1].to_uppercase() + &w[1..]).collect::<String>())), "no CLI subcommand {command}");
        if let Some((service, builder)) = node {
            let built = if builder.ends_with(".rs") { std::fs::read_to_string(src().join(builder)).expect("readable") } else { read_all(files(&src().join(builder))) };
            assert!(built.contains(&format!("Job::{variant}(")), "{builder} never builds Job::{variant} for the node");
            assert!(ros.contains(&format!("\"{service}\"")), "the node serves no {service}");
        }
    }
}

/// The longest function of a file: (name, lines), by matching braces from each `fn` line.
fn longest_function(text: &str) -> Option<(String, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut best: Option<(String, usize)> = None;
    for (k, line) in lines.iter().enumerate() {
        let t = line.trim_start();
        let Some(at) = t.find("fn ") else { continue };
        if !(at == 0 || t[..at].ends_with(' ')) || t.starts_with("//") || !t.contains('(') {
            continue;
        }
        let name: String = t[at + 3..].chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
        let mut depth = 0i64;
        let mut opened = false;
        let mut end = k;
        for (j, l) in lines.iter().enumerate().skip(k) {
            for c in l.chars() {
                match c {
                    '{' => {
                        depth += 1;
                        opened = true;
                    }
                    '}' => depth -= 1,
                    ';' if !opened && depth == 0 => break,
                    _ => {}
                }
            }
            end = j;
            if opened && depth <= 0 {
                break;
            }
            if !opened && l.trim_end().ends_with(';') {
                break;
            }
        }
        let length = end - k + 1;
        if opened && best.as_ref().is_none_or(|(_, n)| length > *n) {
            best = Some((name, length));
        }
    }
    best
}

#[test]
fn files_and_functions_stay_readable() {
    let mut long = Vec::new();
    for path in files(&src()) {
        let text = std::fs::read_to_string(&path).expect("readable");
        let n = text.lines().count();
        if n > 700 {
            long.push(format!("src/{}: {n} lines", rel(&path)));
        }
        if let Some((name, length)) = longest_function(&text).filter(|(_, l)| *l > 150) {
            long.push(format!("src/{}: fn {name} has {length} lines", rel(&path)));
        }
    }
    assert!(long.is_empty(), "over 700 lines per file or 150 per function:\n{}", long.join("\n"));
}

#[test]
fn the_function_measure_sees_functions() {
    let text = "fn a() {\n    let x = 1;\n}\n\nfn b() -> u8 {\n    if true {\n        1\n    } else {\n        2\n    }\n}\n";
    assert_eq!(longest_function(text), Some(("b".to_string(), 7)));
}

/// The ROS packages a colcon workspace holding this clone finds, by colcon's rule: every
/// `package.xml` in a folder tree, except below a folder that holds `COLCON_IGNORE`.
fn colcon_packages(dir: &Path, found: &mut Vec<String>) {
    if dir.join("COLCON_IGNORE").exists() {
        return;
    }
    if dir.join("package.xml").exists() {
        found.push(dir.strip_prefix(env!("CARGO_MANIFEST_DIR")).map_or_else(|_| dir.display().to_string(), |p| p.display().to_string()));
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut dirs: Vec<PathBuf> = entries.flatten().map(|e| e.path()).filter(|p| p.is_dir() && !p.is_symlink()).collect();
    dirs.sort();
    for d in dirs {
        colcon_packages(&d, found);
    }
}

#[test]
fn a_colcon_workspace_finds_only_the_two_ros_packages() {
    // The venv that scripts/ros_env.sh makes (under target/) holds copies of interface
    // packages, `ros/tf2_msgs` only the TFMessage the venv lacks, `vendor/` a DDS interop tree:
    // a workspace building this clone must see none of them, or `colcon build` meets duplicate
    // packages and a partial tf2_msgs that shadows the distribution's.
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut found = Vec::new();
    colcon_packages(root, &mut found);
    assert_eq!(found, ["msgs", "ros/linkspace_bringup"], "packages a colcon workspace finds");
    let script = std::fs::read_to_string(root.join("scripts/ros_env.sh")).expect("readable");
    assert!(script.contains("touch \"$VENV/COLCON_IGNORE\""), "the ROS venv is hidden from colcon");
}

/// The names `pub` items and re-exports give a module file (column 0 only: methods and items of
/// inline blocks are not names of the module), with `pub mod` followed into its file or block.
fn public_names_of(path: &Path, prefix: &str, out: &mut BTreeSet<String>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|_| panic!("{} is readable", path.display()));
    let lines: Vec<&str> = text.lines().collect();
    let mut k = 0;
    while k < lines.len() {
        let line = lines[k];
        k += 1;
        if line.starts_with("#[cfg(test)]") {
            break;
        }
        let Some(rest) = line.strip_prefix("pub ") else { continue };
        if let Some(list) = rest.strip_prefix("use ") {
            // `pub use a::{b, c as d};` (possibly over several lines) names b and d.
            let mut all = list.to_string();
            while !all.contains(';') && k < lines.len() {
                all.push_str(lines[k]);
                k += 1;
            }
            let inner = all.split_once('{').map_or(all.as_str(), |(_, r)| r).trim_end_matches(';').trim_end_matches('}');
            for part in inner.split(',') {
                let part = part.trim();
                let name = part.rsplit(" as ").next().unwrap_or(part).rsplit("::").next().unwrap_or(part).trim();
                if !name.is_empty() && name != "self" {
                    out.insert(format!("{prefix}{name}"));
                }
            }
            continue;
        }
        let word = |s: &str| s.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect::<String>();
        if let Some(m) = rest.strip_prefix("mod ") {
            let name = word(m);
            out.insert(format!("{prefix}{name}"));
            if m.trim_end().ends_with('{') {
                // An inline module: its re-exports are indented by four spaces.
                while k < lines.len() && !lines[k].starts_with('}') {
                    if let Some(r) = lines[k].strip_prefix("    pub use ") {
                        let inner = r.split_once('{').map_or(r, |(_, r)| r).trim_end_matches(';').trim_end_matches('}');
                        for part in inner.split(',') {
                            let n = part.trim().rsplit("::").next().unwrap_or("").trim();
                            if !n.is_empty() {
                                out.insert(format!("{prefix}{name}::{n}"));
                            }
                        }
                    }
                    k += 1;
                }
            } else {
                let dir = path.parent().expect("a folder");
                let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("");
                let base = if stem == "mod" || stem == "lib" { dir.to_path_buf() } else { dir.join(stem) };
                let file = [base.join(format!("{name}.rs")), base.join(name.clone()).join("mod.rs")].into_iter().find(|p| p.exists()).expect("the module's file");
                public_names_of(&file, &format!("{prefix}{name}::"), out);
            }
            continue;
        }
        for kind in ["struct ", "enum ", "fn ", "const ", "static ", "type ", "trait "] {
            if let Some(r) = rest.strip_prefix(kind) {
                out.insert(format!("{prefix}{}", word(r)));
            }
        }
    }
}

/// The library's public names, reviewed: what a program using linkspace can name without the
/// `internals` feature (which opens the layers below `app` to the lab and the tests). A name
/// added to the surface is added here, on purpose.
const PUBLIC_NAMES: &[&str] = &[
    "app", "edges",
    "app::Answer", "app::ArmOptions", "app::BoxStatus", "app::ChainSpec", "app::CollisionsAnswer",
    "app::CollisionsJob", "app::Completeness", "app::Control", "app::DistanceFormulation",
    "app::DistancesAnswer", "app::DistancesJob", "app::FaceBounds", "app::Ik6Answer", "app::Ik6Job",
    "app::IkAnswer", "app::IkJob", "app::IkPoint", "app::ImagePoints", "app::ImageReport",
    "app::Incompleteness", "app::Input", "app::InputMotionCheck", "app::Job", "app::JobError",
    "app::JointInfo", "app::LegValues", "app::Limit", "app::Limits", "app::LinkageModel",
    "app::LoopAnswer", "app::LoopInfo", "app::LoopQuestion", "app::LoopSingularitiesJob",
    "app::LpBackend", "app::Mechanism", "app::MechanismInfo", "app::ModelChoice", "app::MotionSpan",
    "app::Output", "app::PathCheckAnswer", "app::PathCheckJob", "app::PathSet", "app::Peers",
    "app::PoseInput", "app::Prepared", "app::Progress", "app::SNAP_TOLERANCE", "app::Scope",
    "app::SingularKind", "app::SingularitiesAnswer", "app::SelfMotionJob", "app::SingularitiesJob", "app::SolveAnswer",
    "app::SolveJob", "app::SolverSettings", "app::Status", "app::SweepTaskJob", "app::TracedPoint",
    "app::Questions", "app::check_precision", "app::describe", "app::motion_joints", "app::prepare", "app::questions",
    "app::rank_and_size", "app::share_searches", "app::sweeps",
    "app::sweeps::DEFAULT_MAX_TASKS", "app::sweeps::Header", "app::sweeps::Plan",
    "app::sweeps::Summary", "app::sweeps::Sweep", "app::sweeps::Task", "app::sweeps::TaskResult",
    "app::sweeps::TaskStatus", "app::sweeps::answer_task", "app::sweeps::check_sweep",
    "app::sweeps::csv", "app::sweeps::map_svg", "app::sweeps::parse", "app::sweeps::read_done",
    "app::sweeps::run_tasks",
    "edges::report", "edges::ros",
    "edges::report::json", "edges::report::json_line", "edges::report::text",
    "edges::ros::DEFAULT_MAX_HISTORY_MB", "edges::ros::Mapping", "edges::ros::Network",
    "edges::ros::NodeLimits", "edges::ros::ServeConfig", "edges::ros::ServeError",
    "edges::ros::Severity", "edges::ros::Source", "edges::ros::bounded", "edges::ros::serve",
];

#[test]
fn the_public_surface_is_the_reviewed_list() {
    let lib = std::fs::read_to_string(src().join("lib.rs")).expect("lib.rs");
    for layer in ["kernel", "model", "formulate", "analyses"] {
        assert!(lib.contains(&format!("\nlayer!({layer});")), "{layer} is declared as a layer (private without `internals`)");
        assert!(!lib.contains(&format!("pub mod {layer};")), "{layer} is public only with `internals`");
    }
    let manifest = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml")).expect("Cargo.toml");
    let default = manifest.lines().find(|l| l.starts_with("default = ")).expect("default features");
    assert!(!default.contains("internals"), "internals is not a default feature");
    let mut names = BTreeSet::new();
    public_names_of(&src().join("lib.rs"), "", &mut names);
    // The layers' `pub mod` lines are inside the macro (indented), so the walk does not see them.
    assert!(names.contains("app::prepare") && names.contains("edges::report::json"), "the walk sees the surface: {names:?}");
    let reviewed: BTreeSet<String> = PUBLIC_NAMES.iter().map(|s| s.to_string()).collect();
    let added: Vec<&String> = names.difference(&reviewed).collect();
    let gone: Vec<&String> = reviewed.difference(&names).collect();
    assert!(added.is_empty() && gone.is_empty(), "the public surface changed: new {added:?}, gone {gone:?}");
    assert!(names.len() < 100, "{} public names: the surface is tens of names, not hundreds", names.len());
}

//! Test idea: the invariants of ARCHITECTURE.md that can be read off the source are checked
//! here, so the map stays true: the layers of the library's top-level modules (the kernel knows
//! nothing above it, no module cycle), each foreign crate behind its one module, builders that
//! never solve, and serde only where results are written.

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

/// The library's top-level module of a file under `src/` (`None` for the binaries' files).
fn top_module(path: &Path) -> Option<String> {
    let rel = path.strip_prefix(src()).expect("under src");
    let first = rel.components().next()?.as_os_str().to_str()?.trim_end_matches(".rs").to_string();
    match first.as_str() {
        "main" | "cli" | "bin" | "lib" => None,
        _ => Some(first),
    }
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

/// The files of the library's top-level module `name` (`src/name.rs` and `src/name/`).
fn module_files(name: &str) -> Vec<PathBuf> {
    files(&src()).into_iter().filter(|p| top_module(p).as_deref() == Some(name)).collect()
}

/// Lines of `paths` that name `needle`, as `path:line: text`.
fn lines_naming(paths: &[PathBuf], needle: &str) -> Vec<String> {
    paths.iter().flat_map(|p| code_lines(p).into_iter().filter(|(_, l)| l.contains(needle)).map(move |(n, l)| format!("{}:{n}: {}", p.display(), l.trim()))).collect()
}

/// Which top-level modules each library module names (`crate::x`).
fn dependencies() -> BTreeMap<String, BTreeSet<String>> {
    let mut deps: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for path in files(&src()) {
        let Some(from) = top_module(&path) else { continue };
        let entry = deps.entry(from.clone()).or_default();
        for (_, line) in code_lines(&path) {
            for (k, _) in line.match_indices("crate::") {
                let before = line[..k].chars().last();
                if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
                    continue;
                }
                let name: String = line[k + 7..].chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
                let is_module = src().join(&name).is_dir() || src().join(format!("{name}.rs")).is_file();
                if !name.is_empty() && name != from && is_module {
                    entry.insert(name);
                }
            }
        }
    }
    deps
}

#[test]
fn the_kernel_knows_nothing_above_it() {
    let kernel = ["interval", "system", "contract", "lp", "search"];
    let deps = dependencies();
    for m in kernel {
        let above: Vec<&String> = deps.get(m).into_iter().flatten().filter(|d| !kernel.contains(&d.as_str())).collect();
        assert!(above.is_empty(), "kernel module `{m}` names {above:?}");
    }
}

#[test]
fn top_level_modules_form_no_cycle() {
    let deps = dependencies();
    // Depth-first search for a back edge; the cycle found is named.
    fn visit(m: &str, deps: &BTreeMap<String, BTreeSet<String>>, path: &mut Vec<String>, done: &mut BTreeSet<String>) -> Option<Vec<String>> {
        if let Some(at) = path.iter().position(|p| p == m) {
            return Some(path[at..].to_vec());
        }
        if done.contains(m) {
            return None;
        }
        path.push(m.to_string());
        for d in deps.get(m).into_iter().flatten() {
            if let Some(cycle) = visit(d, deps, path, done) {
                return Some(cycle);
            }
        }
        path.pop();
        done.insert(m.to_string());
        None
    }
    let mut done = BTreeSet::new();
    for m in deps.keys() {
        let cycle = visit(m, &deps, &mut Vec::new(), &mut done);
        assert!(cycle.is_none(), "module cycle: {:?}", cycle.unwrap_or_default());
    }
}

/// Lines of library files outside `allowed` (path prefixes under src/) that name `needle`.
fn uses_outside(needle: &str, allowed: &[&str]) -> Vec<String> {
    let mut found = Vec::new();
    for path in files(&src()) {
        let rel = path.strip_prefix(src()).expect("under src").to_string_lossy().replace('\\', "/");
        if allowed.iter().any(|a| rel.starts_with(a)) {
            continue;
        }
        for (n, line) in code_lines(&path) {
            if line.contains(needle) {
                found.push(format!("src/{rel}:{n}: {}", line.trim()));
            }
        }
    }
    found
}

#[test]
fn each_foreign_crate_is_behind_one_module() {
    for (krate, home) in [("clarabel::", &["lp/"][..]), ("urdf_rs::", &["model/urdf.rs"][..]), ("roxmltree::", &["model/"][..]), ("ros2_client::", &["ros/"][..]), ("rustdds::", &["ros/"][..]), ("plotters::", &["bin/"][..]), ("yaml_rust2::", &["cli/ros_args.rs"][..]), ("mpi::", &["cli/ranks.rs"][..])] {
        let outside = uses_outside(krate, home);
        assert!(outside.is_empty(), "{krate} outside {home:?}:\n{}", outside.join("\n"));
    }
}

#[test]
fn builders_never_solve() {
    let problems = module_files("problems");
    for call in [".enclose(", "search::run", "run_by_level", "drop_spurious("] {
        let hits = lines_naming(&problems, call);
        assert!(hits.is_empty(), "a builder runs a search ({call}):\n{}", hits.join("\n"));
    }
}

/// Where serde may be named: the JSON writers (`report`), the node (`ros`), the binaries, the
/// reader of the distance file format, and the sweep's own file formats (its spec and its
/// result lines, which it reads back to resume).
const SERDE_HOMES: [&str; 9] = ["report.rs", "report/", "ros/", "main.rs", "cli", "bin/", "distances/file.rs", "sweep/spec.rs", "sweep/records.rs"];

#[test]
fn only_the_edges_know_serde() {
    let outside = uses_outside("serde", &SERDE_HOMES);
    assert!(outside.is_empty(), "serde outside the edges (library types are plain data; `report` says how they are written, with remote definitions where a type is more than a record):\n{}", outside.join("\n"));
}

//! The Python package (`python/linkspace`) through its own pytest suite: `scripts/python_env.sh`
//! makes the venv and builds the wheel from this checkout (on the dependencies this build
//! compiled), then pytest runs `python/linkspace/tests` against the `linkspace` binary built
//! here (its answers equal the CLI's `--json`, references without the solver, Ctrl-C and the
//! limits, errors with the CLI's messages, mypy --strict on the stubs, the example notebooks).

use std::path::Path;
use std::process::Command;

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn the_python_package_passes_its_suite() {
    let env = Command::new("sh").arg(repo().join("scripts/python_env.sh")).output().expect("sh runs");
    assert!(env.status.success(), "scripts/python_env.sh failed: {}", String::from_utf8_lossy(&env.stderr));
    let stdout = String::from_utf8_lossy(&env.stdout);
    let python = stdout.lines().last().expect("the script prints the venv's python").trim().to_string();
    let out = Command::new(&python)
        .args(["-m", "pytest", "-q", "-p", "no:cacheprovider", "python/linkspace/tests"])
        .env("LINKSPACE_CLI", env!("CARGO_BIN_EXE_linkspace"))
        .current_dir(repo())
        .output()
        .expect("pytest runs");
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "the Python package's tests failed:\n{text}");
    // The suite ran, and skipped nothing: every tool it needs is in the venv.
    let summary = text.lines().rev().find(|l| l.contains(" passed")).unwrap_or_default();
    assert!(!summary.contains("skipped") && !summary.contains("failed"), "pytest: {summary}");
}

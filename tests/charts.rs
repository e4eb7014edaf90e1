//! Test idea: `linkspace-lab chart --quick --only loops,singular3r` draws the singular-set charts
//! of closed loops and the 3R workspace regions from fresh runs. The runs' summary lines must show what the independent references of
//! the other modules establish (the double butterfly's 10 turning points of θ6 on its 4
//! branches, by continuation in `closed_loop_singularities`; the unequal five-bar's empty cusp
//! and node sets and its verdict), every turning point must land on a branch drawn beside it,
//! and the 3R workspace regions must carry certified solution counts of the kind of Benoit et al.
//! (2019): 0, 2 or 4 for these generic arms, with 2 and 4 both present for the cuspidal robot a.

use std::process::Command;

fn line<'a>(stdout: &'a str, prefix: &str) -> &'a str {
    stdout.lines().find(|l| l.starts_with(prefix)).unwrap_or_else(|| panic!("no line '{prefix}' in:\n{stdout}"))
}

#[test]
fn loop_singularity_and_workspace_region_charts() {
    let dir = std::env::temp_dir().join(format!("linkspace-charts-{}", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_linkspace-lab")).args(["chart", dir.to_str().expect("utf-8 temp dir"), "--quick", "--only", "loops,singular3r"]).output().expect("binary runs");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "chart failed: {}\n{stdout}", String::from_utf8_lossy(&out.stderr));

    let butterfly = line(&stdout, "double butterfly:");
    assert!(butterfly.contains("4 branches") && butterfly.contains("10 turning-point clusters of joint6 (10 certified"), "{butterfly}");
    assert!(butterfly.contains(", 0 on no branch"), "{butterfly}");
    let five = line(&stdout, "five-bar (rods 2.5, 2) type-II image:");
    assert!(five.contains("cusps 0 proven 0 undecided, nodes 0 proven 0 undecided") && five.ends_with("verdict no"), "{five}");
    // The one region with assembly modes has two (opposite signs of det F_p); the rest none.
    assert!(five.contains("Some(2)") && !five.contains("None") && !five.contains("Some(1)") && !five.contains("Some(3)"), "{five}");
    let work = line(&stdout, "five-bar (rods 2.5, 2) workspace:");
    assert!(work.contains("status Finished"), "{work}");

    for robot in ["a", "e", "f"] {
        let l = line(&stdout, &format!("robot {robot} workspace regions:"));
        let counts = l.split_once('{').expect("counts").1;
        for key in counts.split(',').map(|kv| kv.split(':').next().expect("key").trim().trim_matches(|c| c == '"' || c == '}')) {
            assert!(["0", "2", "4"].contains(&key), "robot {robot}: a region with '{key}' solutions: {l}");
        }
        assert!(counts.contains("\"0\"") && counts.contains("\"2\""), "{l}");
        if robot == "a" {
            assert!(counts.contains("\"4\""), "{l}");
        }
    }
    for name in ["five_bar_actuator_space.svg", "five_bar_workspace.svg", "butterfly_turning_points.svg", "workspace_regions_3r.svg"] {
        let svg = std::fs::read_to_string(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(svg.starts_with("<svg") && svg.contains("<rect"), "{name}");
    }
    // Region labels are drawn as text.
    let regions = std::fs::read_to_string(dir.join("workspace_regions_3r.svg")).expect("written").replace('\n', "");
    assert!(regions.contains(">4</text>") && regions.contains(">2</text>"));
    let _ = std::fs::remove_dir_all(&dir);
}

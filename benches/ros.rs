//! Benchmark (not a test) of the ROS 2 node against real rclpy on loopback: box-set topic
//! throughput and latency for a 10,752-box set, against a 2-box set measured in the same run
//! as the baseline, and service round trips. `cargo bench --bench ros`.
//!
//! The node republishes its configuration space at an offered rate (`--republish`); the
//! Python side (`scripts/bench_ros.py`) counts what arrives and how late.

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn main() {
    let out = Command::new("sh").arg(format!("{ROOT}/scripts/ros_env.sh")).arg(format!("{ROOT}/target/ros-venv")).stderr(Stdio::inherit()).output().expect("ros_env.sh runs");
    assert!(out.status.success(), "scripts/ros_env.sh failed");
    let python = String::from_utf8_lossy(&out.stdout).lines().last().expect("python path").trim().to_string();
    let domain = 90;
    let cases: [(&str, Vec<&str>, &str, &str); 2] = [
        ("2 boxes (baseline)", vec!["urdf/four_bar.urdf", "--fix", "crank_joint=0.5", "--sigma", "1e-3"], "four_bar", r#"{"coupler_joint": 0.2668, "rocker_joint": 1.5145, "loop_coupler_rocker": 0.7477}"#),
        ("10,752 boxes", vec!["urdf/slider_crank.urdf", "--sigma", "8.5e-4"], "slider_crank", r#"{"crank_joint": 1.0, "rod_joint": -1.285, "slider_joint": 3.42, "loop_rod_slider": 0.285}"#),
    ];
    println!("set | offered Hz | received msg/s | MB/s | latency median ms | p90 ms | list_mechanisms RTT median/p90 ms | classify RTT median/p90 ms");
    let mut baseline_rate = std::collections::BTreeMap::new();
    for (name, args, mechanism, joints) in cases {
        for hz in [20.0, 100.0] {
            let mut node = Command::new(env!("CARGO_BIN_EXE_linkspace"))
                .current_dir(ROOT)
                .arg("serve")
                .args(&args)
                .args(["--domain", &domain.to_string(), "--network", "loopback", "--republish", &format!("{}", 1.0 / hz)])
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .expect("node starts");
            let t = Instant::now();
            let out = Command::new(&python)
                .arg(format!("{ROOT}/scripts/bench_ros.py"))
                .args(["--topic", &format!("/linkspace/{mechanism}/configuration_space"), "--mechanism", mechanism, "--joints", joints, "--seconds", "8", "--calls", "200"])
                .env("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp")
                .env("ROS_AUTOMATIC_DISCOVERY_RANGE", "SYSTEM_DEFAULT")
                .env("FASTRTPS_DEFAULT_PROFILES_FILE", format!("{ROOT}/scripts/fastdds_loopback.xml"))
                .env("ROS_DOMAIN_ID", domain.to_string())
                .output()
                .expect("bench_ros.py runs");
            let _ = node.kill();
            let _ = node.wait();
            assert!(t.elapsed() < Duration::from_secs(300));
            let text = String::from_utf8_lossy(&out.stdout);
            let Some(v) = text.lines().last().and_then(|l| serde_json::from_str::<serde_json::Value>(l).ok()) else {
                println!("{name} | {hz} | failed: {}", String::from_utf8_lossy(&out.stderr));
                continue;
            };
            let f = |k: &str| v[k].as_f64().unwrap_or(f64::NAN);
            let rtt = |k: &str| format!("{:.2}/{:.2}", v[k]["median_ms"].as_f64().unwrap_or(f64::NAN), v[k]["p90_ms"].as_f64().unwrap_or(f64::NAN));
            let rate = f("rate");
            let ratio = match baseline_rate.get(&(hz as u32)) {
                Some(b) => format!(" ({:.2}x the baseline's rate)", rate / b),
                None => {
                    baseline_rate.insert(hz as u32, rate);
                    String::new()
                }
            };
            println!("{name} ({} boxes) | {hz} | {rate:.1}{ratio} | {:.1} | {:.2} | {:.2} | {} | {}", v["boxes"], f("mb_per_s"), f("latency_ms_median"), f("latency_ms_p90"), rtt("list_mechanisms"), rtt("classify"));
        }
    }
}

use linkspace::model::urdf;
use linkspace::formulate::LinkageProblem;
use linkspace::kernel::search::{SolverSettings, Status};
use linkspace::kernel::interval::IntervalBox;
use std::sync::atomic::AtomicBool;

pub fn urdf_text(name: &str) -> String {
    std::fs::read_to_string(format!("{}/urdf/{name}", env!("CARGO_MANIFEST_DIR"))).expect("bundled URDF")
}

pub fn problem(name: &str, fixed: &[(&str, f64)], traces: &[(&str, f64, f64)]) -> LinkageProblem {
    let m = urdf::parse(&urdf_text(name)).expect("bundled URDF parses");
    let fixed: Vec<(String, f64)> = fixed.iter().map(|(n, v)| (n.to_string(), *v)).collect();
    let traces: Vec<(String, f64, f64)> = traces.iter().map(|(n, x, y)| (n.to_string(), *x, *y)).collect();
    LinkageProblem::new(&m, &fixed, &traces).expect("bundled mechanism builds")
}

pub struct Run {
    pub status: Status,
    pub solutions: Vec<IntervalBox>,
    pub unique: Vec<bool>,
}

pub fn solve(p: &LinkageProblem, sigma: f64) -> Run {
    let settings = SolverSettings { sigma, ..Default::default() };
    let solver = p.solver(settings).expect("valid settings");
    let e = solver.enclose(&AtomicBool::new(false), &mut |_| {});
    assert!(e.undecided.is_empty() || e.status != Status::Finished);
    Run { status: e.status, solutions: e.solutions, unique: e.tags.iter().map(|t| *t == linkspace::app::BoxStatus::Unique).collect() }
}

/// Does some box contain `x`, allowing `slack` for the rounding of the reference point itself?
pub fn covered(boxes: &[IntervalBox], x: &[f64], slack: f64) -> bool {
    boxes.iter().any(|b| b.dims.iter().zip(x).all(|(d, &v)| d.inf() - slack <= v && v <= d.sup() + slack))
}

/// splitmix64: a fixed, dependency-free stream per seed, the same on every run.
pub struct SplitMix(pub u64);

impl SplitMix {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

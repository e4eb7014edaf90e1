//! Ibex (`ibexsolve`) as a baseline run in the same invocation, when it is on PATH: the 3R cusp
//! system "D&G2" of docs/peers.md (det Df = 0 and the second row of the system (2) of Benoit et al.
//! 2019, `∂z/∂θ₂·(−∂D/∂θ₃) + ∂z/∂θ₃·∂D/∂θ₂ = 0`) written in Minibex from the arm's own
//! coefficients, over the same θ₃ ranges linkspace searches (the internal-motion strips left out),
//! solved at the same precision; its CPU time is the child's (user + system, from `wait4`).
//!
//! The coefficients are read off the library in `f64` (`Chain3R::perp` and `eval_f64` at nine
//! sample points, the map being bilinear in (cos θ₂, sin θ₂, 1) ⊗ (cos θ₃, sin θ₃, 1)), as a
//! peer's model of the same arm would state them.

use anyhow::{Context, Result};
use linkspace::kernel::interval::point;
use linkspace::analyses::arm3r::Chain3R;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The `ibexsolve` executable on PATH, if any.
pub fn on_path() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path).map(|d| d.join("ibexsolve")).find(|p| is_executable(p))
}

fn is_executable(p: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt;
    std::fs::metadata(p).is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
}

/// A bilinear form `Σ c[a][b] e₂[a] e₃[b]`, `e = (cos, sin, 1)`.
type Bilinear = [[f64; 3]; 3];

/// The end point's perpendicular components (three) and its component along the first axis,
/// as bilinear forms, recovered from samples at θ = 0, π/2, π in each joint.
pub fn coefficients(chain: &Chain3R) -> [Bilinear; 4] {
    use std::f64::consts::{FRAC_PI_2, PI};
    let angles = [0.0, FRAC_PI_2, PI];
    let mut samples = [[[0.0; 3]; 3]; 4];
    for (i, &t2) in angles.iter().enumerate() {
        for (j, &t3) in angles.iter().enumerate() {
            let perp = chain.perp([point(t2), point(t3)]);
            for k in 0..3 {
                samples[k][i][j] = perp[k].mid();
            }
            samples[3][i][j] = chain.eval_f64(t2, t3)[1];
        }
    }
    // e(0) = (1, 0, 1), e(π/2) = (0, 1, 1), e(π) = (−1, 0, 1): solve each axis in turn.
    let solve = |v: [f64; 3]| {
        let one = 0.5 * (v[0] + v[2]);
        [0.5 * (v[0] - v[2]), v[1] - one, one]
    };
    let forms = samples.map(|s| {
        let rows: [[f64; 3]; 3] = [0, 1, 2].map(|i| solve(s[i]));
        let mut c = [[0.0; 3]; 3];
        for b in 0..3 {
            let col = solve([rows[0][b], rows[1][b], rows[2][b]]);
            for a in 0..3 {
                c[a][b] = col[a];
            }
        }
        c
    });
    // cos(π/2) and sin(π) are not 0 in f64: the samples carry errors of about 1e-16 of the
    // arm's size, which a peer's model would not state. Coefficients under 1e-12 of the largest
    // are 0; the rest are written to 12 significant digits (`form`).
    let scale = forms.iter().flatten().flatten().fold(0.0f64, |m, c| m.max(c.abs()));
    forms.map(|f| f.map(|row| row.map(|c| if c.abs() < 1e-12 * scale { 0.0 } else { c })))
}

/// The Minibex text of a form's derivative of order `d2` in θ₂ and `d3` in θ₃ (0 to 2).
fn form(c: &Bilinear, d2: usize, d3: usize) -> String {
    let basis = |j: &str, d: usize| -> [String; 3] {
        match d {
            0 => [format!("c{j}"), format!("s{j}"), "1".into()],
            1 => [format!("(-s{j})"), format!("c{j}"), "0".into()],
            _ => [format!("(-c{j})"), format!("(-s{j})"), "0".into()],
        }
    };
    let (e2, e3) = (basis("2", d2), basis("3", d3));
    let mut terms = Vec::new();
    for a in 0..3 {
        for b in 0..3 {
            if c[a][b] == 0.0 || e2[a] == "0" || e3[b] == "0" {
                continue;
            }
            terms.push(format!("({:.12e})*{}*{}", c[a][b], e2[a], e3[b]));
        }
    }
    if terms.is_empty() {
        "0".into()
    } else {
        format!("({})", terms.join("+"))
    }
}

/// The body shared by both functions of the model: the map's derivatives up to order two,
/// `D = det Df` and its gradient.
fn body(coef: &[Bilinear; 4]) -> String {
    let mut s = String::from("  c2 = cos(t2); s2 = sin(t2); c3 = cos(t3); s3 = sin(t3);\n");
    let orders = [(0, 0, ""), (1, 0, "_2"), (0, 1, "_3"), (2, 0, "_22"), (1, 1, "_23"), (0, 2, "_33")];
    for (k, c) in coef.iter().enumerate() {
        let name = if k == 3 { "z".to_string() } else { format!("p{k}") };
        for (d2, d3, suffix) in orders {
            if k == 3 && (d2, d3) == (0, 0) {
                continue;
            }
            writeln!(s, "  {name}{suffix} = {};", form(c, d2, d3)).ok();
        }
    }
    // f1 = |p|²: its derivatives by the product rule.
    let sum = |f: &dyn Fn(usize) -> String| (0..3).map(f).collect::<Vec<_>>().join(" + ");
    writeln!(s, "  f_2 = 2*({});", sum(&|i| format!("p{i}*p{i}_2"))).ok();
    writeln!(s, "  f_3 = 2*({});", sum(&|i| format!("p{i}*p{i}_3"))).ok();
    writeln!(s, "  f_22 = 2*({});", sum(&|i| format!("p{i}_2*p{i}_2 + p{i}*p{i}_22"))).ok();
    writeln!(s, "  f_23 = 2*({});", sum(&|i| format!("p{i}_3*p{i}_2 + p{i}*p{i}_23"))).ok();
    writeln!(s, "  f_33 = 2*({});", sum(&|i| format!("p{i}_3*p{i}_3 + p{i}*p{i}_33"))).ok();
    s.push_str("  d = f_2*z_3 - f_3*z_2;\n");
    s.push_str("  d_2 = f_22*z_3 + f_2*z_23 - f_23*z_2 - f_3*z_22;\n");
    s.push_str("  d_3 = f_23*z_3 + f_2*z_33 - f_33*z_2 - f_3*z_23;\n");
    s
}

/// The Minibex model of the cusp system over θ₂ ∈ [−π, π], θ₃ ∈ `t3`.
pub fn cusp_model(chain: &Chain3R, t3: [f64; 2]) -> String {
    let b = body(&coefficients(chain));
    let pi = linkspace::analyses::arm3r::PI_UP;
    format!(
        "// {name}: det Df = 0 and the second row of Benoit, Delanoue, Lagrange and Wenger 2019 (D&G2), written by linkspace-lab bench3r\n\
         function det_df(t2, t3)\n{b}  return d;\nend\n\
         function g2(t2, t3)\n{b}  return z_2*(-d_3) + z_3*d_2;\nend\n\
         Variables\n  t2 in [{lo2:.17e}, {hi2:.17e}];\n  t3 in [{lo3:.17e}, {hi3:.17e}];\n\
         Constraints\n  det_df(t2, t3) = 0;\n  g2(t2, t3) = 0;\nend\n",
        name = chain.name,
        lo2 = -pi,
        hi2 = pi,
        lo3 = t3[0],
        hi3 = t3[1],
    )
}

/// The θ₃ ranges of [−π, π] outside `strips` (sorted, possibly touching the ends).
pub fn outside(strips: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let pi = linkspace::analyses::arm3r::PI_UP;
    let mut out = Vec::new();
    let mut lo = -pi;
    for s in strips {
        if s[0] > lo {
            out.push([lo, s[0]]);
        }
        lo = lo.max(s[1]);
    }
    if lo < pi {
        out.push([lo, pi]);
    }
    out
}

/// What one `ibexsolve` run (all pieces) gave.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IbexRun {
    /// CPU seconds of the children (user + system), summed over the pieces.
    pub cpu: f64,
    /// Solution boxes (inner and boundary), summed.
    pub solutions: u64,
    /// Unknown and pending boxes, summed.
    pub unknown: u64,
}

/// Reads the counts from `ibexsolve`'s report (the lines "number of inner boxes", "boundary",
/// "unknown", "pending", or "number of solutions" in older releases); `None` when none is there.
pub fn parse_report(text: &str) -> Option<(u64, u64)> {
    let mut solutions = None::<u64>;
    let mut unknown = 0;
    for line in text.lines() {
        let l = line.to_ascii_lowercase();
        if !l.contains("number of") {
            continue;
        }
        let Some(n) = l.split_whitespace().last().and_then(|w| w.parse::<u64>().ok()) else { continue };
        if l.contains("inner") || l.contains("boundary") || l.contains("solution") {
            *solutions.get_or_insert(0) += n;
        } else if l.contains("unknown") || l.contains("pending") {
            unknown += n;
        }
    }
    solutions.map(|s| (s, unknown))
}

/// Runs `exe -e precision` on one model per θ₃ piece, in a scratch folder.
pub fn run(exe: &Path, chain: &Chain3R, pieces: &[[f64; 2]], precision: f64) -> Result<IbexRun> {
    let dir = std::env::temp_dir().join(format!("linkspace-lab-ibex-{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut total = IbexRun::default();
    for (i, piece) in pieces.iter().enumerate() {
        let model = dir.join(format!("{}_{i}.mbx", chain.name));
        std::fs::write(&model, cusp_model(chain, *piece)).with_context(|| format!("writing {}", model.display()))?;
        let cov = dir.join(format!("{}_{i}.cov", chain.name));
        let args = vec!["-e".to_string(), format!("{precision:e}"), "-o".to_string(), cov.display().to_string(), model.display().to_string()];
        let m = crate::bench_arms::measure(exe, &args)?;
        let (solutions, unknown) = parse_report(&m.stdout).with_context(|| format!("reading the report of {} {}", exe.display(), args.join(" ")))?;
        total.cpu += m.cpu;
        total.solutions += solutions;
        total.unknown += unknown;
    }
    std::fs::remove_dir_all(&dir).ok();
    Ok(total)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chain(name: &str) -> Chain3R {
        let xml = crate::bench3r::ROBOTS.iter().find(|r| r.0 == name).expect("bundled").1;
        Chain3R::from_mechanism(&linkspace::model::urdf::parse(xml).expect("parses"), 0.0).expect("3R")
    }

    /// The recovered forms give back the library's map at points off the samples.
    #[test]
    fn coefficients_reproduce_the_map() {
        for name in ["a", "f"] {
            let ch = chain(name);
            let c = coefficients(&ch);
            let eval = |c: &Bilinear, t2: f64, t3: f64| {
                let (e2, e3) = ([t2.cos(), t2.sin(), 1.0], [t3.cos(), t3.sin(), 1.0]);
                (0..3).flat_map(|a| (0..3).map(move |b| (a, b))).map(|(a, b)| c[a][b] * e2[a] * e3[b]).sum::<f64>()
            };
            for (t2, t3) in [(0.3, -1.2), (2.5, 0.7), (-2.9, 3.0)] {
                let want = ch.eval_f64(t2, t3);
                let rho2: f64 = (0..3).map(|k| eval(&c[k], t2, t3).powi(2)).sum();
                assert!((rho2 - want[0]).abs() < 1e-9 * (1.0 + want[0].abs()), "{name}: {rho2} vs {}", want[0]);
                assert!((eval(&c[3], t2, t3) - want[1]).abs() < 1e-9, "{name}");
            }
        }
    }

    #[test]
    fn reports_of_both_layouts_are_read() {
        let new = " solving successful!\n\n number of inner boxes:\t\t6\n number of boundary boxes:\t0\n number of unknown boxes:\t2\n number of pending boxes:\t1\n cpu time used:\t\t\t0.02s\n";
        assert_eq!(parse_report(new), Some((6, 3)));
        assert_eq!(parse_report(" number of solutions:\t4\n cpu time used: 0.1s\n"), Some((4, 0)));
        assert_eq!(parse_report("error: syntax"), None);
    }

    #[test]
    fn strips_are_left_out() {
        let pi = linkspace::analyses::arm3r::PI_UP;
        assert_eq!(outside(&[]), vec![[-pi, pi]]);
        assert_eq!(outside(&[[-1.0, -0.5], [0.5, 1.0]]), vec![[-pi, -1.0], [-0.5, 0.5], [1.0, pi]]);
        assert_eq!(outside(&[[-pi, -3.0], [3.0, pi]]), vec![[-3.0, 3.0]]);
    }

    #[test]
    fn the_model_names_both_equations_and_the_ranges() {
        let m = cusp_model(&chain("a"), [-1.0, 1.0]);
        assert!(m.contains("det_df(t2, t3) = 0;") && m.contains("g2(t2, t3) = 0;"), "{m}");
        assert!(m.contains("t3 in [-1.00000000000000000e0, 1.00000000000000000e0]"), "{m}");
    }
}

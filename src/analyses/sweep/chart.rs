//! The map of a sweep: the outcome of each task (verdict or count) over two parameters, as SVG
//! written with plain text formatting. Each distinct value of a parameter is one column (row),
//! in increasing order: a grid's spacing is kept, a list of tuples is shown by rank.

use super::records::outcome;
use super::TaskResult;
use std::collections::BTreeMap;
use std::fmt::Write;

/// Colours of the named outcomes; counts take `COUNT_COLOURS` in increasing order.
fn named_colour(name: &str) -> Option<&'static str> {
    Some(match name {
        "cuspidal" => "#d62728",
        "non_cuspidal" => "#1f77b4",
        "undecided" => "#bdbdbd",
        "failed" => "#252525",
        "mixed" => "#9467bd",
        _ => return None,
    })
}

const COUNT_COLOURS: [&str; 8] = ["#fff7bc", "#fee391", "#fec44f", "#fe9929", "#ec7014", "#cc4c02", "#993404", "#662506"];

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// The map of `results` over parameters `axes` (indices into `labels`), titled `title`. A cell
/// where several tasks fall (other parameters vary) with different outcomes is `mixed`.
pub fn map_svg(title: &str, labels: &[String], axes: [usize; 2], results: &[TaskResult]) -> String {
    let [xi, yi] = axes;
    let distinct = |k: usize| {
        let mut v: Vec<f64> = results.iter().filter_map(|r| r.values.get(k).copied()).collect();
        v.sort_by(f64::total_cmp);
        v.dedup();
        v
    };
    let (xs, ys) = (distinct(xi), distinct(yi));
    let rank = |v: &[f64], x: f64| v.iter().position(|&a| a == x);
    let mut cells: BTreeMap<(usize, usize), String> = BTreeMap::new();
    for r in results {
        let (Some(cx), Some(cy)) = (r.values.get(xi).and_then(|&x| rank(&xs, x)), r.values.get(yi).and_then(|&y| rank(&ys, y))) else { continue };
        let o = outcome(r);
        cells.entry((cx, cy)).and_modify(|c| if *c != o { *c = "mixed".into() }).or_insert(o);
    }
    let mut kinds: Vec<String> = cells.values().cloned().collect();
    kinds.sort_by_key(|k| (k.parse::<u64>().map_or(1, |_| 0), k.parse::<u64>().unwrap_or(0), k.clone()));
    kinds.dedup();
    let counts: Vec<&String> = kinds.iter().filter(|k| named_colour(k).is_none()).collect();
    let colour = |k: &str| named_colour(k).unwrap_or_else(|| COUNT_COLOURS[counts.iter().position(|c| *c == k).unwrap_or(0) * (COUNT_COLOURS.len() - 1) / counts.len().saturating_sub(1).max(1) % COUNT_COLOURS.len()]);

    let (left, top, plot_w, plot_h) = (80.0, 50.0, 480.0, 400.0);
    let (cw, ch) = (plot_w / xs.len().max(1) as f64, plot_h / ys.len().max(1) as f64);
    let mut s = String::new();
    let width = left + plot_w + 200.0;
    let height = top + plot_h + 70.0;
    let _ = writeln!(s, r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="12">"#);
    let _ = writeln!(s, r#"<rect width="{width}" height="{height}" fill="white"/>"#);
    let _ = writeln!(s, r#"<text x="{}" y="25" text-anchor="middle" font-size="15">{}</text>"#, left + plot_w / 2.0, escape(title));
    for (&(cx, cy), kind) in &cells {
        let (x, y) = (left + cx as f64 * cw, top + plot_h - (cy + 1) as f64 * ch);
        let _ = writeln!(
            s,
            r##"<rect x="{x:.2}" y="{y:.2}" width="{cw:.2}" height="{ch:.2}" fill="{}" stroke="#ffffff" stroke-width="0.5"><title>{} = {}, {} = {}: {}</title></rect>"##,
            colour(kind),
            escape(&labels[xi]),
            xs[cx],
            escape(&labels[yi]),
            ys[cy],
            escape(kind)
        );
    }
    let _ = writeln!(s, r#"<rect x="{left}" y="{top}" width="{plot_w}" height="{plot_h}" fill="none" stroke="black"/>"#);
    // At most about ten tick labels per axis.
    let every = |n: usize| n.div_ceil(10).max(1);
    for (k, v) in xs.iter().enumerate().filter(|(k, _)| k % every(xs.len()) == 0) {
        let x = left + (k as f64 + 0.5) * cw;
        let _ = writeln!(s, r#"<text x="{x:.2}" y="{}" text-anchor="middle">{}</text>"#, top + plot_h + 18.0, tick(*v));
    }
    for (k, v) in ys.iter().enumerate().filter(|(k, _)| k % every(ys.len()) == 0) {
        let y = top + plot_h - (k as f64 + 0.5) * ch;
        let _ = writeln!(s, r#"<text x="{}" y="{:.2}" text-anchor="end">{}</text>"#, left - 6.0, y + 4.0, tick(*v));
    }
    let _ = writeln!(s, r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#, left + plot_w / 2.0, top + plot_h + 45.0, escape(&labels[xi]));
    let _ = writeln!(s, r#"<text x="20" y="{}" text-anchor="middle" transform="rotate(-90 20 {})">{}</text>"#, top + plot_h / 2.0, top + plot_h / 2.0, escape(&labels[yi]));
    for (k, kind) in kinds.iter().enumerate() {
        let y = top + 10.0 + 22.0 * k as f64;
        let n = cells.values().filter(|c| *c == kind).count();
        let _ = writeln!(s, r##"<rect x="{}" y="{y}" width="14" height="14" fill="{}" stroke="#555555"/>"##, left + plot_w + 20.0, colour(kind));
        let _ = writeln!(s, r#"<text x="{}" y="{}">{} ({n} cells)</text>"#, left + plot_w + 42.0, y + 11.0, escape(kind));
    }
    s.push_str("</svg>\n");
    s
}

/// A tick label: short, exact for round values.
fn tick(v: f64) -> String {
    let t = format!("{v:.3}");
    let t = t.trim_end_matches('0').trim_end_matches('.');
    if t == "-0" { "0".into() } else { t.to_string() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analyses::sweep::TaskStatus;

    #[test]
    fn each_cell_is_coloured_by_its_outcome() {
        let r = |index: usize, x: f64, y: f64, verdict: &str| TaskResult {
            index,
            values: vec![x, y],
            status: TaskStatus::Ran(crate::kernel::outcome::Completeness::Complete),
            limit: None,
            verdict: Some(verdict.into()),
            count: None,
            proven: 0,
            undecided: 0,
            error: None,
            seconds: 0.0,
        };
        let svg = map_svg("t <1>", &["d3".into(), "d4".into()], [0, 1], &[r(0, 1.0, 1.0, "cuspidal"), r(1, 2.0, 1.0, "non_cuspidal"), r(2, 1.0, 2.0, "cuspidal")]);
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert_eq!(svg.matches("fill=\"#d62728\"").count(), 3, "two cells and the legend");
        assert!(svg.contains("t &lt;1&gt;") && svg.contains("cuspidal (2 cells)"));
        assert_eq!((tick(1.0), tick(0.125), tick(-0.0)), ("1".into(), "0.125".into(), "0".into()));
    }
}

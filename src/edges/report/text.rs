//! The one text renderer of an `Answer`: what each command prints on stdout. Reads the answer
//! and its JSON records (the sibling modules), never the analyses.

use crate::app::{Answer, BoxStatus, LoopAnswer, ResultBox};
use crate::edges::report;
use std::collections::BTreeMap;
use std::fmt::Write;

type Out = String;

/// The text of `answer`, as the CLI prints it: a summary line per result and the first boxes
/// of each kind, never the whole set (that is `json`'s).
pub fn text(answer: &Answer) -> String {
    let mut out = String::new();
    render(&mut out, answer);
    out
}

fn render(out: &mut Out, answer: &Answer) {
    match answer {
        Answer::Solve(a) => solve(out, a),
        Answer::Singularities(a) => singularities(out, a),
        Answer::Ik(a) => ik(out, a),
        Answer::Ik6(a) => ik6(out, a),
        Answer::PathCheck(a) => path_check(out, a),
        Answer::Collisions(a) => collisions(out, a),
        Answer::SelfMotion(a) => self_motion(out, a),
        Answer::Distances(a) => distances(out, &report::distances::DistancesReport::of(a)),
        Answer::LoopSingularities(a) => match a.as_ref() {
            LoopAnswer::Sets { .. } => loop_sets(out, a),
            LoopAnswer::Image(r) => image(out, r),
            LoopAnswer::Points(r) => image_points(out, r),
            LoopAnswer::Motion(m) => motion(out, m),
        },
        Answer::SweepTask(t) => {
            writeln!(out, "task {}: {}", t.index, t.status.name()).ok();
        }
    }
}

fn mid(b: &[f64; 2]) -> f64 {
    0.5 * (b[0] + b[1])
}

fn solve(out: &mut Out, a: &crate::app::SolveAnswer) {
    let result = &a.result;
    let solutions: Vec<&ResultBox> = result.boxes.iter().filter(|b| b.status.is_solution()).collect();
    let proven = result.boxes.iter().filter(|b| b.status == BoxStatus::Unique).count();
    let undecided = result.boxes.len() - solutions.len();
    let stats = &result.stats;
    let status = match result.status.limit() {
        None => a.completeness().text(),
        Some(l) => format!("incomplete ({} limit, {undecided} boxes undecided)", l.name()),
    };
    writeln!(
        out,
        "{}: {proven} proven, {undecided} undecided ({} solution boxes in {} clusters), status {status}, {} boxes processed ({} empty, {} bisected), {} LPs, {:.3} s",
        result.mechanism,
        solutions.len(),
        result.clusters,
        stats.processed,
        stats.empty,
        stats.bisected,
        stats.lp.solved,
        stats.seconds
    )
    .ok();
    // "Proven": a box certified (Krawczyk) to hold exactly one configuration; the other solution
    // boxes are not refuted at the precision (points of a curve, or roots not yet proven).
    writeln!(out, "  model: {} ({})", a.model_name(), a.model_reason()).ok();
    writeln!(out, "  freedom: {}", a.freedom).ok();
    for r in a.reductions() {
        writeln!(out, "  reduced: {r}").ok();
    }
    if result.status.finished() && solutions.is_empty() {
        // A complete run with no box is a proof, and says something about the input.
        let why = if result.fixed_joints.is_empty() { "the loops cannot close as written, within the joint limits" } else { "no assembly has the fixed values given" };
        writeln!(out, "  no configuration: every box was proven empty, so {why}").ok();
    }
    if stats.post_processing_cut_short {
        // What the limit cost: boxes reported without the deeper search that drops near misses
        // (the count may include a few spurious ones), or without their joint values.
        let limit = result.status.limit().map_or("time", |l| l.name());
        let unread = result.boxes.iter().filter(|b| b.joints.iter().any(|j| j[0].is_nan())).count();
        let unread = if unread > 0 { format!("; {unread} boxes were not read out (their joints are NaN, null in the JSON)") } else { String::new() };
        writeln!(out, "  the {limit} limit cut the post-processing short: some lone boxes may be kept without the spurious-box check{unread}").ok();
    }
    if solutions.len() <= 20 {
        for (k, s) in solutions.iter().enumerate() {
            // By joint name, as the JSON lists them.
            let mut joints: Vec<(&String, &[f64; 2])> = result.joint_names.iter().zip(&s.joints).collect();
            joints.sort_by(|a, b| a.0.cmp(b.0));
            let joints: Vec<String> = joints.iter().map(|(n, b)| format!("{n}={:.6}", mid(b))).collect();
            writeln!(out, "  #{k}: {}", joints.join(" ")).ok();
        }
    }
}

fn singularities(out: &mut Out, a: &crate::app::SingularitiesAnswer) {
    let report = report::manip3r::SingularityReport::of(a);
    let (arm, found) = (&a.arm, &a.found);
    let prepared = &arm.prepared;
    let scope = &prepared.choice.scope;
    let arm_section = report.arm_cuspidality.as_ref();
    if let Some(v) = &found.verdict {
        writeln!(out, "{}", v.headline(scope)).ok();
    }
    if let Some(open) = scope.not_answered.as_ref().filter(|_| found.verdict.is_some() && !scope.stands_for_arm) {
        match arm_section {
            Some(s) => writeln!(out, "  not the arm's verdict: the whole arm's is the line `arm {}` below", s.arm).ok(),
            None => writeln!(out, "  {open}").ok(),
        };
    }
    let node_text = report.nodes.as_ref().map_or("nodes not searched".to_string(), |n| format!("{} nodes", n.len()));
    let undecided = report.undecided_total[0] + report.undecided_total[1];
    let strips = match report.internal_motions.iter().filter(|m| m.near_degenerate.is_some()).count() {
        0 => String::new(),
        n => format!("{n} near-degenerate strips (undecided), "),
    };
    writeln!(
        out,
        "{}: {} cusps, {node_text}, {} internal-motion lines, {strips}{undecided} undecided, status {}, {:.3} s",
        report.robot,
        report.cusps.len(),
        found.internal_motion_lines(),
        report.completeness.text(),
        report.stats.seconds
    )
    .ok();
    let fmt = |j: &BTreeMap<String, [f64; 2]>| j.iter().map(|(n, b)| format!("{n}={:.6}", mid(b))).collect::<Vec<_>>().join(" ");
    if let Some(why) = &report.not_searched {
        writeln!(out, "  not searched: {why}").ok();
    }
    writeln!(out, "  chain: {}", prepared.choice.reason).ok();
    for line in report.singular_branches.iter().flat_map(|b| b.lines()) {
        writeln!(out, "  {line}").ok();
    }
    if let Some(u) = &report.explained_undecided {
        writeln!(out, "  undecided cusp boxes: {}", u.text).ok();
    }
    if prepared.exact_geometry {
        let why = if prepared.snap_tolerance == 0.0 { "--snap-tolerance 0" } else { "--exact-geometry" };
        writeln!(out, "  rounding: off ({why}): angles taken as written").ok();
    } else {
        writeln!(out, "  rounding: {} values snapped to quarter turns / coordinate axes (tolerance {:e} rad)", prepared.snaps.len(), prepared.snap_tolerance).ok();
        for sn in &prepared.snaps {
            if sn.what == "lock" {
                writeln!(out, "    {} lock: {} -> {}", sn.joint, sn.original[0], sn.snapped[0]).ok();
            } else {
                writeln!(out, "    {} {}: {:?} -> {:?}", sn.joint, sn.what, sn.original, sn.snapped).ok();
            }
        }
    }
    writeln!(out, "  {}", found.limit_effect.text).ok();
    for c in &report.cusps {
        writeln!(out, "  cusp {} -> radius {:.6} z {:.6}", fmt(&c.joints), mid(&c.workspace.radius), mid(&c.workspace.z)).ok();
    }
    for n in report.nodes.iter().flatten() {
        writeln!(out, "  node {} & {} -> radius {:.6} z {:.6}", fmt(&n.points[0]), fmt(&n.points[1]), mid(&n.workspace.radius), mid(&n.workspace.z)).ok();
    }
    for m in &report.internal_motions {
        let kind = if m.near_degenerate.is_some() { "near-degenerate strip (undecided)" } else { "internal motion" };
        writeln!(out, "  {kind} {}", m.joints.iter().map(|(n, b)| format!("{n} in [{:.6}, {:.6}]", b[0], b[1])).collect::<Vec<_>>().join(", ")).ok();
    }
    if let Some(s) = arm_section {
        writeln!(out, "arm {}: {} ({})", s.arm, s.verdict, s.reason).ok();
        if let Some(proof) = &s.proof {
            writeln!(out, "  proof: {proof}").ok();
        }
        if let Some(w) = &s.witness {
            writeln!(out, "  witness pose translation {:?}; solutions {} and {}; min |det J| on the path {:.3e}", w.pose_translation, fmt(&w.from), fmt(&w.to), w.min_abs_det).ok();
        }
        if let Some(m) = &s.most_solutions {
            writeln!(out, "  at least {} inverse-kinematics solutions at one pose (each certified in its own box; pose translation {:?}, the most the search solved)", m.count, m.pose_translation).ok();
        }
    }
}

fn ik(out: &mut Out, a: &crate::app::IkAnswer) {
    let report = report::manip3r::IkReport::of(&a.arm, &a.found);
    let s = &a.found.solutions;
    writeln!(out, "{}: {} solutions proven unique, {} clusters undecided, status {}", report.robot, s.unique.len(), s.clusters.len(), report.completeness.text()).ok();
    writeln!(out, "  chain: {}", a.arm.prepared.choice.reason).ok();
    writeln!(out, "  {}", a.found.limit_effect.text).ok();
    for sol in &report.solutions {
        let text: Vec<String> = sol.joints.iter().map(|(n, b)| format!("{n} in [{:.9}, {:.9}]", b[0], b[1])).collect();
        let tag = match (sol.unique, sol.boxes) {
            (true, _) => "unique".to_string(),
            (false, 0) => format!("internal-motion line: every {} solves the point; the strip about it is not searched", a.arm.chain.joints[1]),
            (false, n) => format!("cluster of {n} boxes (one or more solutions)"),
        };
        writeln!(out, "  {} ({tag})", text.join(", ")).ok();
    }
}

fn ik6(out: &mut Out, a: &crate::app::Ik6Answer) {
    let report = report::six::Ik6Report::of(&a.chain, &a.found);
    let chain = &a.chain;
    writeln!(
        out,
        "{} -> {}: {} solutions proven unique, {}{} clusters undecided, status {}, {} boxes ({}), {:.3} s",
        report.base,
        report.tip,
        report.unique.len(),
        match report.curves.len() {
            0 => String::new(),
            n => format!("{n} singular curves, "),
        },
        report.clusters.len(),
        report.completeness.text(),
        report.processed,
        report.method.replace('_', " "),
        report.seconds
    )
    .ok();
    writeln!(out, "  joint ranges: {}", chain.joints.iter().zip(&chain.ranges).map(|(n, r)| format!("{n} [{:.6}, {:.6}]", r.0, r.1)).collect::<Vec<_>>().join(", ")).ok();
    for (tag, boxes) in [("unique", &report.unique), ("cluster (may hold solutions)", &report.clusters)] {
        for b in boxes {
            // In the file's joint order, each in its own range.
            let text: Vec<String> = chain.joints.iter().map(|n| (n, b[n])).map(|(n, x)| format!("{n} in [{:.9}, {:.9}]", x[0], x[1])).collect();
            writeln!(out, "  {} ({tag})", text.join(", ")).ok();
        }
    }
    for c in &report.curves {
        let text: Vec<String> = chain.joints.iter().map(|n| (n, c.ranges[n])).map(|(n, x)| format!("{n} in [{:.9}, {:.9}]", x[0], x[1])).collect();
        writeln!(out, "  {} ({}: {} move together along a curve; {} boxes cover it)", text.join(", "), c.kind.replace('_', " "), c.moving.join(", "), c.cover.len()).ok();
    }
}

fn self_motion(out: &mut Out, a: &crate::app::ArmSelfMotion) {
    let report = report::self_motion::SelfMotionReport::of(a);
    writeln!(out, "{}, {:.3} s", a.headline(), a.seconds).ok();
    for (k, c) in report.clusters.iter().enumerate() {
        let ranges: Vec<String> = report.joints.iter().map(|n| format!("{n} [{:.6}, {:.6}]", c.ranges[n][0], c.ranges[n][1])).collect();
        writeln!(out, "  cluster {k}: {} boxes ({} certified): {}", c.boxes, c.certified, ranges.join(", ")).ok();
    }
}

fn path_check(out: &mut Out, a: &crate::app::PathCheckAnswer) {
    if let Some(chain) = &a.chain {
        eprintln!("chain: {chain}");
    }
    let report = report::six::PathCheckReport::of(&a.found);
    writeln!(out, "{}", report.headline()).ok();
    for (k, s) in report.segments.iter().enumerate() {
        writeln!(out, "  segment {} ({} -> {}): {}: {}", k + 1, k + 1, k + 2, s.verdict, s.reason).ok();
        for c in &s.crossings {
            let text: Vec<String> = report.joints.iter().map(|n| format!("{n} in [{:.9}, {:.9}]", c.joints[n][0], c.joints[n][1])).collect();
            writeln!(out, "    crossing at t in [{:.12}, {:.12}]: {}", c.t[0], c.t[1], text.join(", ")).ok();
        }
    }
}

fn collisions(out: &mut Out, a: &crate::app::CollisionsAnswer) {
    eprintln!("chain: {}", a.found.prepared.choice.reason);
    let report = report::collisions::CollisionReport::of(&a.found, a.precision);
    writeln!(out, "{}, {:.3} s", a.found.headline(), a.found.set.seconds).ok();
    for (k, p) in report.pairs.iter().enumerate() {
        let boxes = a.found.set.colliding.iter().filter(|c| c.pair == k).count();
        writeln!(out, "  {} x {}: proven colliding on {boxes} boxes", p[0], p[1]).ok();
    }
}

fn distances(out: &mut Out, rep: &report::distances::DistancesReport) {
    let platform = rep.solutions.iter().any(|s| !s.poses.is_empty());
    let status = match rep.status.limit() {
        None if rep.complete => crate::app::Completeness::Complete.word().to_string(),
        None => format!("incomplete ({} regions undecided)", rep.undecided_regions),
        Some(l) => format!("incomplete ({} limit, {} boxes undecided)", l.name(), rep.undecided.len()),
    };
    writeln!(
        out,
        "{}: {} proven, {} undecided ({} solution boxes in {} clusters, {} distinct {}; {} formulation), status {status}, {} boxes processed ({} empty, {} bisected), {:.4} s",
        rep.problem,
        rep.proven,
        rep.undecided_regions,
        rep.solutions.len(),
        rep.clusters,
        rep.placements,
        if platform { "poses" } else { "placements" },
        rep.formulation.name(),
        rep.stats.processed,
        rep.stats.empty,
        rep.stats.bisected,
        rep.stats.seconds
    )
    .ok();
    // One line per cluster: the hull of its distances and what its first box places.
    for c in 0..rep.clusters.min(40) {
        let members: Vec<_> = rep.solutions.iter().filter(|s| s.cluster == c).collect();
        let mut hull: BTreeMap<&String, [f64; 2]> = BTreeMap::new();
        for m in &members {
            for (n, [lo, hi]) in &m.distances {
                let h = hull.entry(n).or_insert([*lo, *hi]);
                h[0] = h[0].min(*lo);
                h[1] = h[1].max(*hi);
            }
        }
        let d: Vec<String> = hull.iter().map(|(n, b)| format!("{n}={:.5}", mid(b))).collect();
        let verdict = match rep.cluster_verdicts.get(c) {
            Some(v) => match &v.undecided {
                None => format!("{} proven", v.proven),
                Some(why) => format!("{} proven, undecided: {why}", v.proven),
            },
            None => "undecided".to_string(),
        };
        writeln!(out, "  cluster {c} ({} boxes; {verdict}): {}", members.len(), d.join(" ")).ok();
        let Some(first) = members.first() else { continue };
        for p in &first.poses {
            writeln!(
                out,
                "    pose: position ({:.5}, {:.5}, {:.5}) rpy ({:.5}, {:.5}, {:.5}) leg residual {:.1e}",
                p.position[0], p.position[1], p.position[2], p.rpy[0], p.rpy[1], p.rpy[2], p.leg_residual
            )
            .ok();
        }
        for l in &first.lines {
            let dist: Vec<String> = l.distance_from.iter().map(|(n, d)| format!("{n} {d:.5}")).collect();
            writeln!(
                out,
                "    line {}-{}: point ({:.5}, {:.5}, {:.5}) direction ({:.5}, {:.5}, {:.5}); distance from {}",
                l.through[0], l.through[1], l.point[0], l.point[1], l.point[2], l.direction[0], l.direction[1], l.direction[2], dist.join(", ")
            )
            .ok();
        }
    }
}

fn loop_sets(out: &mut Out, a: &LoopAnswer) {
    let LoopAnswer::Sets { mechanism, sets, solved, settings } = a else { return };
    if sets.model == crate::app::LinkageModel::Spatial {
        writeln!(out, "{mechanism}: spatial model ({})", sets.model_reason).ok();
    }
    for (p, set) in sets.problems.iter().zip(solved) {
        let r = report::singular::SingularReport::new(p, settings, set);
        let s = &r.summary;
        let shape = match r.expected_dimension {
            0 => "points",
            1 => "curves",
            d if d < 0 => "generically none",
            _ => "surfaces",
        };
        let status = match r.status.limit() {
            None => crate::app::Completeness::Complete.word().to_string(),
            Some(l) => format!("incomplete ({} limit)", l.name()),
        };
        let charts = match s.unsearched_charts {
            0 => format!("{} charts", r.charts),
            n => format!("{} charts ({n} left unsearched, held by one undecided box)", r.charts),
        };
        writeln!(
            out,
            "{} {}: {} clusters ({} certified, {} unproven), {} boxes, {} undecided, status {status}, {charts}, {} dof ({shape}), {:.3} s",
            r.mechanism, r.kind, s.clusters, s.certified_clusters, s.unproven_clusters, s.boxes, s.undecided_boxes, r.dof, r.seconds
        )
        .ok();
        if r.clusters.len() <= 40 {
            for c in &r.clusters {
                // A line a reader can take in: the first joints, then how many more (the JSON
                // report has them all).
                const SHOWN: usize = 12;
                let mut joints: Vec<String> = c.joints.iter().take(SHOWN).map(|(n, b)| format!("{n}={:.6}", mid(b))).collect();
                if c.joints.len() > SHOWN {
                    joints.push(format!("and {} more joints (--json)", c.joints.len() - SHOWN));
                }
                let tag = if c.certified { "certified" } else if c.undecided { "undecided" } else { "unproven" };
                writeln!(out, "  {tag} ({} boxes): {}", c.boxes, joints.join(" ")).ok();
            }
        }
    }
}

fn image_records(out: &mut Out, cusps: &[crate::app::ImageCusp], nodes: &[crate::app::ImageNode]) {
    let tag = |unique: bool| if unique { " (certified)" } else { " (undecided)" };
    for c in cusps.iter().take(20) {
        let why = c.reason.as_ref().map_or(String::new(), |r| format!(" ({r})"));
        writeln!(out, "  cusp{}{}: {:?}{why}", tag(c.unique), if c.degenerate { " degenerate" } else { "" }, c.workspace).ok();
    }
    for n in nodes.iter().take(20) {
        writeln!(out, "  node{}: {:?}", tag(n.unique), n.workspace).ok();
    }
}

fn image(out: &mut Out, r: &crate::app::ImageReport) {
    writeln!(
        out,
        "{} type-II image: cusps {} proven, {} undecided; nodes {} proven, {} undecided ({} diagonal boxes injective); {} regions; status {}; {:.3} s (cover {:.3}, cusps {:.3}, nodes {:.3}, regions {:.3})",
        r.mechanism,
        r.cusp_counts.proven,
        r.cusp_counts.undecided,
        r.node_counts.proven,
        r.node_counts.undecided,
        r.injective,
        r.regions.regions.len(),
        r.status.text(),
        r.seconds.iter().sum::<f64>(),
        r.seconds[0],
        r.seconds[1],
        r.seconds[2],
        r.seconds[3]
    )
    .ok();
    for (i, g) in r.regions.regions.iter().enumerate() {
        let count = g.configurations.map_or("undecided".to_string(), |c| c.to_string());
        let signs = g.signs.map_or(String::new(), |[p, n]| format!(" ({p} with {} > 0, {n} < 0)", r.regions.sign));
        writeln!(out, "  region {i}: {} cells, sample {:?}: {count} assembly modes{signs}", g.cells, g.sample).ok();
    }
    image_records(out, &r.cusps, &r.nodes);
    writeln!(out, "  can change assembly mode without crossing a type-II singularity: {} ({})", r.verdict.word(), r.verdict.reason).ok();
}

fn image_points(out: &mut Out, r: &crate::app::ImagePoints) {
    writeln!(out, "{} type-II image {}: {} proven, {} undecided; status {}; {:.3} s", r.mechanism, r.search, r.counts.proven, r.counts.undecided, r.status.text(), r.seconds).ok();
    image_records(out, &r.cusps, &r.nodes);
}

fn motion(out: &mut Out, m: &crate::app::InputMotionCheck) {
    let r = report::motion::MotionReport::of(m);
    writeln!(out, "{}: {} from {} to {}: {} ({} steps, {:.3} s)", r.singular_set, r.actuated, r.from, r.to, r.verdict, r.steps.len(), r.seconds).ok();
    writeln!(out, "  {}", r.reason).ok();
}

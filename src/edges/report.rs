//! The JSON writers: what the CLI's `--json` options write (schemas in README), one module per
//! command, built from the typed results of `app` and the analyses. Pure data: no IO here.
//!
//! Only this module and `ros` know serde: `kernel` states how the kernel's and `model`'s values
//! are written.

/// `fn $name(&[$ty], Serializer)`: a list of `$ty` written through its remote definition `$def`.
macro_rules! list_with {
    ($name:ident, $ty:ty, $def:literal) => {
        fn $name<S: serde::Serializer>(items: &[$ty], s: S) -> Result<S::Ok, S::Error> {
            #[derive(serde::Serialize)]
            struct One<'a>(#[serde(with = $def)] &'a $ty);
            s.collect_seq(items.iter().map(One))
        }
    };
}

/// `fn $name(&Option<$ty>, Serializer)`: an optional `$ty` written through its remote definition
/// `$def` (with `skip_serializing_if = "Option::is_none"`, only `Some` is ever written).
macro_rules! some_with {
    ($name:ident, $ty:ty, $def:literal) => {
        fn $name<S: serde::Serializer>(item: &Option<$ty>, s: S) -> Result<S::Ok, S::Error> {
            #[derive(serde::Serialize)]
            struct One<'a>(#[serde(with = $def)] &'a $ty);
            match item {
                Some(v) => s.serialize_some(&One(v)),
                None => s.serialize_none(),
            }
        }
    };
}

use crate::kernel::interval::Bounds;

layer!(collisions);
layer!(distances);
layer!(image);
mod kernel;
layer!(manip3r);
layer!(motion);
layer!(self_motion);
layer!(singular);
layer!(six);
layer!(solve);
mod text;
layer!(verdicts);

pub use text::text;
use distances::DistancesReport;
use solve::SolveReport;

use crate::app::{Answer, LoopAnswer};

/// The JSON report of an answer, as `--json` writes it, written to `out` as it is encoded (a
/// box set of a million boxes is never held as text): the one writer of every question.
pub fn json(answer: &Answer, out: impl std::io::Write) -> Result<(), serde_json::Error> {
    encode(answer, Layout::Pretty(out))
}

/// The same report on one line, for streams of answers (JSON Lines: `ik6 --poses --json`
/// writes one per pose).
pub fn json_line(answer: &Answer) -> Result<String, serde_json::Error> {
    let mut line = Vec::new();
    encode(answer, Layout::Line(&mut line))?;
    Ok(String::from_utf8(line).expect("invariant: serde_json writes UTF-8"))
}

/// How a report is laid out, and where it goes.
enum Layout<W> {
    Pretty(W),
    Line(W),
}

fn encode<W: std::io::Write>(answer: &Answer, layout: Layout<W>) -> Result<(), serde_json::Error> {
    fn put<W: std::io::Write, T: serde::Serialize + ?Sized>(layout: Layout<W>, value: &T) -> Result<(), serde_json::Error> {
        match layout {
            Layout::Pretty(w) => serde_json::to_writer_pretty(w, value),
            Layout::Line(w) => serde_json::to_writer(w, value),
        }
    }
    match answer {
        Answer::Solve(a) => put(layout, &SolveReport::new(a.run.problem(), &a.result, &a.links, a.rigid_links.clone())),
        Answer::Singularities(a) => put(layout, &manip3r::SingularityReport::of(a)),
        Answer::Ik(a) => put(layout, &manip3r::IkReport::of(&a.arm, &a.found)),
        Answer::Ik6(a) => put(layout, &six::Ik6Report::of(&a.chain, &a.found)),
        Answer::SelfMotion(a) => put(layout, &self_motion::SelfMotionReport::of(a)),
        Answer::PathCheck(a) => put(layout, &six::PathCheckReport::of(&a.found)),
        Answer::Collisions(a) => put(layout, &collisions::CollisionReport::of(&a.found, a.precision)),
        Answer::Distances(a) => put(layout, &DistancesReport::of(a)),
        Answer::LoopSingularities(a) => match a.as_ref() {
            LoopAnswer::Sets { sets, solved, settings, .. } => put(layout, &sets.problems.iter().zip(solved).map(|(p, s)| singular::SingularReport::new(p, settings, s)).collect::<Vec<_>>()),
            LoopAnswer::Image(r) => put(layout, &image::ImageJson(r)),
            LoopAnswer::Points(r) => put(layout, &image::ImagePointsJson(r)),
            LoopAnswer::Motion(m) => put(layout, &motion::MotionReport::of(m)),
        },
        Answer::SweepTask(t) => put(layout, t),
    }
}

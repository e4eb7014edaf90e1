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

/// The JSON report of an answer, as `--json` writes it: the one writer of every question.
pub fn json(answer: &Answer) -> Result<String, serde_json::Error> {
    encode(answer, true)
}

/// The same report on one line, for streams of answers (JSON Lines: `ik6 --poses --json`
/// writes one per pose).
pub fn json_line(answer: &Answer) -> Result<String, serde_json::Error> {
    encode(answer, false)
}

fn encode(answer: &Answer, pretty: bool) -> Result<String, serde_json::Error> {
    fn put<T: serde::Serialize + ?Sized>(pretty: bool, value: &T) -> Result<String, serde_json::Error> {
        if pretty {
            serde_json::to_string_pretty(value)
        } else {
            serde_json::to_string(value)
        }
    }
    match answer {
        Answer::Solve(a) => put(pretty, &SolveReport::new(a.run.problem(), &a.result, &a.links, a.rigid_links.clone())),
        Answer::Singularities(a) => put(pretty, &manip3r::SingularityReport::of(a)),
        Answer::Ik(a) => put(pretty, &manip3r::IkReport::of(&a.arm, &a.found)),
        Answer::Ik6(a) => put(pretty, &six::Ik6Report::of(&a.chain, &a.found)),
        Answer::SelfMotion(a) => put(pretty, &self_motion::SelfMotionReport::of(a)),
        Answer::PathCheck(a) => put(pretty, &six::PathCheckReport::of(&a.found)),
        Answer::Collisions(a) => put(pretty, &collisions::CollisionReport::of(&a.found, a.precision)),
        Answer::Distances(a) => put(pretty, &DistancesReport::of(a)),
        Answer::LoopSingularities(a) => match a.as_ref() {
            LoopAnswer::Sets { sets, solved, settings, .. } => put(pretty, &sets.problems.iter().zip(solved).map(|(p, s)| singular::SingularReport::new(p, settings, s)).collect::<Vec<_>>()),
            LoopAnswer::Image(r) => put(pretty, &image::ImageJson(r)),
            LoopAnswer::Points(r) => put(pretty, &image::ImagePointsJson(r)),
            LoopAnswer::Motion(m) => put(pretty, &motion::MotionReport::of(m)),
        },
        Answer::SweepTask(t) => put(pretty, t),
    }
}

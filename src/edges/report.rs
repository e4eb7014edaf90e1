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

pub mod distances;
pub mod image;
pub(crate) mod kernel;
pub mod manip3r;
pub mod motion;
pub mod singular;
pub mod six;
pub mod solve;

pub use crate::kernel::interval::Bounds;
pub use solve::{BoxRecord, SolveReport, TracedPoint, VariableInfo};

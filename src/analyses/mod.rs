//! The questions linkspace answers, one folder each: kernel clients that search a formulated
//! system and decide what its boxes mean. `app` is their only caller outside the library's
//! own tests.

pub mod arm3r;
pub mod arm6r;
pub mod distances;
pub mod input_motion;
pub mod joint_path;
pub mod loop_singular;
pub mod sweep;

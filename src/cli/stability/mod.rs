//! `stickslip stability`: the stability limits of the fixed-step scheme at a scene's
//! parameters, as a table (docs/stability.md); the analysis is
//! [`crate::engine::fixed::stability`], its text is [`report`].

pub mod report;

use std::process::ExitCode;

use super::args::{SceneArgs, load_scene};
use super::stdout::emit;
use crate::engine::fixed::stability::analyse;

pub use report::{explain, flips_line, integrator_name, issues, num, relaxation_line, table, validate_block, warning};

pub(crate) fn stability(args: &SceneArgs) -> ExitCode {
    let scene = match load_scene(args, &[]) {
        Ok(s) => s,
        Err(code) => return code,
    };
    emit(&table(&analyse(&scene), &scene.name))
}

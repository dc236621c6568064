//! `stickslip stability`: the stability limits of the fixed-step scheme at a scene's
//! parameters, as a table (docs/stability.md).

use std::process::ExitCode;

use super::SceneArgs;
use super::run::load_scene;
use super::stdout::emit;

pub(crate) fn stability(args: &SceneArgs) -> ExitCode {
    let scene = match load_scene(args, &[]) {
        Ok(s) => s,
        Err(code) => return code,
    };
    emit(&crate::stability::analyse(&scene).table(&scene.name))
}

//! What the commands share: the exit codes, the one-line error, the scene arguments and
//! the scene they load.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::ValueEnum;

use crate::scene::Scene;

/// Exit code for bad input.
pub const EXIT_BAD_INPUT: u8 = 2;
/// Exit code for a run that failed.
pub const EXIT_RUN_FAILED: u8 = 1;

/// Scene selection shared by the commands that read a scene.
#[derive(clap::Args, Debug, Clone)]
pub struct SceneArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Override a scene field, e.g. `--set plate.v=0.1` (repeatable; checked like the file).
    #[arg(long = "set", value_name = "SECTION.KEY=VALUE")]
    pub set: Vec<String>,
}

#[derive(ValueEnum, Clone, Copy, Debug)]
pub enum EngineArg {
    Exact,
    Fixed,
}

/// Prints a one-line error and returns the exit code.
pub(crate) fn fail(code: u8, message: impl std::fmt::Display) -> ExitCode {
    // One line whatever the message holds (a path or a `--set` with a newline in it).
    eprintln!("error: {}", crate::scene::error::printable(&message.to_string()));
    ExitCode::from(code)
}

/// clap's message as one line: its first paragraph (which names the argument and, on the
/// lines after the first, the missing argument or the allowed values), joined by spaces.
pub(crate) fn clap_one_line(e: &clap::Error) -> String {
    use clap::error::ErrorKind;
    if matches!(e.kind(), ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand | ErrorKind::MissingSubcommand) {
        return "a command is required: `run`, `resume`, `validate`, `stability`, `sweep`, `compare`, `bench`, `friction-law` or `fit` (try --help)"
            .to_string();
    }
    let text = e.to_string();
    let first: Vec<&str> = text.lines().map(str::trim).take_while(|l| !l.is_empty()).collect();
    let line = first.join(" ");
    let line = line.trim_start_matches("error: ");
    if line.is_empty() { "invalid arguments (try --help)".to_string() } else { line.to_string() }
}

/// Reads and validates the scene with `--set` overrides and the flag overrides after them.
pub(crate) fn load_scene(args: &SceneArgs, extra: &[String]) -> Result<Scene, ExitCode> {
    let mut overrides = args.set.clone();
    overrides.extend_from_slice(extra);
    Scene::from_file(&args.scene, &overrides).map_err(|e| fail(EXIT_BAD_INPUT, e))
}

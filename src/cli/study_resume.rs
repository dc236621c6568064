//! `stickslip resume DIR` for a study: `DIR` holds a `sweep` or `compare` journal, whose
//! header records the command line that started it; that command is run again into `DIR`,
//! which runs only the runs the journal does not hold and writes the files an uninterrupted
//! study writes.

use std::path::Path;
use std::process::ExitCode;

use clap::Parser;

use super::args::{EXIT_BAD_INPUT, clap_one_line, fail};
use super::command::{Cli, Command};
use super::{compare, fit, friction_law, sweep};
use crate::studies::journal::{self, Header};

/// Resumes the study in `dir` if it holds a study journal; `None` if it holds none (a
/// single run's directory). `checkpoint_every` is refused for a study.
pub(crate) fn resume(dir: &Path, checkpoint_every: Option<f64>) -> Option<ExitCode> {
    if !dir.is_dir() {
        return None; // reported as a run's resume reports it
    }
    let header = match journal::read_header(dir) {
        Ok(Some(h)) => h,
        Ok(None) => return None,
        Err(e) => return Some(fail(EXIT_BAD_INPUT, e)),
    };
    let path = journal::path_in(dir);
    if checkpoint_every.is_some() {
        return Some(fail(
            EXIT_BAD_INPUT,
            format!(
                "--checkpoint-every: {} is a study's journal; a study resumes run by run, without checkpoints",
                path.display()
            ),
        ));
    }
    Some(match rerun(dir, &header) {
        Ok(code) => code,
        Err(m) => fail(EXIT_BAD_INPUT, format!("{}: {m}", path.display())),
    })
}

/// Runs the journal's command again, into `dir`.
fn rerun(dir: &Path, header: &Header) -> Result<ExitCode, String> {
    let Some(command) = &header.command else {
        return Err(format!(
            "written by stickslip.sweep in Python; continue it by calling stickslip.sweep with the same arguments and out={}",
            dir.display()
        ));
    };
    let cli = Cli::try_parse_from(&command.argv)
        .map_err(|e| format!("its command line does not parse: {}", clap_one_line(&e)))?;
    match cli.command {
        Command::Sweep(mut args) => {
            args.scene.scene = command.cwd.join(&args.scene.scene);
            args.out = Some(dir.to_path_buf());
            Ok(sweep::sweep(&args))
        }
        Command::Compare(mut args) => {
            args.scene.scene = command.cwd.join(&args.scene.scene);
            args.out = Some(dir.to_path_buf());
            Ok(compare::compare_as(&args, &compare::quoted(&command.argv)))
        }
        Command::FrictionLaw(mut args) if args.from.is_none() => {
            args.scene = args.scene.map(|s| command.cwd.join(s));
            args.out = Some(dir.to_path_buf());
            Ok(friction_law::friction_law(&args))
        }
        Command::Fit(mut args) => {
            args.scene.scene = command.cwd.join(&args.scene.scene);
            args.data = command.cwd.join(&args.data);
            args.out = Some(dir.to_path_buf());
            Ok(fit::fit(&args))
        }
        _ => Err(format!(
            "its command line is not a sweep, a compare, a friction law or a fit ({})",
            header.study.as_str()
        )),
    }
}

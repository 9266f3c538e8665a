//! An argument vector (the input split at NUL bytes, each argument any bytes, as Unix allows)
//! → the command line's clap parser → for `render` and `inspect`, the settings the arguments
//! resolve to and their validation; the kernels' name (`--isa`). Nothing is rendered, no
//! file is read or written (`--settings FILE` is parsed but not opened).
//!
//! The `Cli` definitions live in the binary (src/cli.rs), not the library, so the file is
//! included here as a module as it is: moving the clap definitions into the library would
//! pull clap into it and touch a file other work is changing. src/cli.rs calls
//! `crate::start_workbench()` (in src/main.rs) for `raylab` with no command; the stub below
//! stands in for it and is never called.
#![no_main]

use std::ffi::OsString;
use std::os::unix::ffi::OsStringExt as _;

use clap::Parser as _;
use libfuzzer_sys::fuzz_target;

// src/cli.rs is loaded as the binary loads it, as a file of the folder src/, so that its own
// submodules (src/cli/*.rs) are found where they are.
#[allow(dead_code)]
#[path = "../../src"]
mod src {
    pub mod cli;
}
use src::cli;

use cli::{Cli, Command, RenderOptions};

/// What src/main.rs provides to src/cli.rs; the target never runs a command.
fn start_workbench() -> anyhow::Result<()> {
    unreachable!("the fuzz target never runs a command")
}

/// src/main.rs's signal handling, which src/cli.rs starts before a render; never called here.
mod signals {
    pub fn remove_temporary_files_when_stopped() {
        unreachable!("the fuzz target never runs a command")
    }
    pub fn unblock() {
        unreachable!("the fuzz target never runs a command")
    }
}

/// At most this many arguments: a command line longer than any a person types, and clap's
/// work grows with it.
const MAX_ARGS: usize = 64;

fuzz_target!(|data: &[u8]| {
    let args: Vec<OsString> = std::iter::once(OsString::from("raylab"))
        .chain(
            data.split(|b| *b == 0)
                .map(|arg| OsString::from_vec(arg.to_vec())),
        )
        .take(MAX_ARGS + 1)
        .collect();
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            // The message the user would see (usage, --help and --version included).
            let _ = e.render().to_string();
            return;
        }
    };
    let _ = raylab_core::shapes::accel::Isa::by_name(&cli.isa);
    match cli.command {
        Some(Command::Render(args)) => resolve(&args.options),
        Some(Command::Inspect(args)) => resolve(&args.options),
        Some(Command::Check(args)) => resolve(&args.options),
        Some(Command::Bench(_)) | None => {}
    }
});

/// The settings the options describe, as `run_render` and `run_inspect` resolve them, minus
/// reading a `--settings` file.
fn resolve(options: &RenderOptions) {
    let _ = options.scene_choice();
    if options.settings.is_some() {
        return;
    }
    let settings = options.settings();
    if settings.validate().is_ok() {
        let _ = settings.summary();
    }
}

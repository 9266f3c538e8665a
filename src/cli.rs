//! The command line: `raylab render` writes an image, `raylab inspect` explains one pixel of
//! it, `raylab bench` measures the tracer; with no command, `raylab` starts the workbench.
//!
//! A thin layer over the library: arguments become a [`RenderSettings`], which is validated,
//! rendered and saved. Every bad value ends the program with one line naming it and a non-zero
//! exit code, before anything is written.

use std::io::Write as _;
use std::process::ExitCode;

use anyhow::Context as _;
use clap::{Parser, Subcommand};
use raylab_core::shapes::accel::Isa;
use raylab_core::teaching::inspect::InspectError;

mod bench;
mod check;
mod equations;
mod inspect;
mod options;
mod overwrite;
mod parse;
mod pool;
mod render;
mod terminal;
#[cfg(test)]
mod tests;

use bench::{BenchArgs, run_bench};
use check::{CheckArgs, run_check};
use inspect::{InspectArgs, run_inspect};
use render::{RenderArgs, run_render};
use terminal::{one_line, print_error_line, printable_lines};

#[derive(Debug, Parser)]
#[command(
    name = "raylab",
    version,
    about = "A raytracing workbench for learning"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Kernels: best (the fastest measured on this CPU at start-up), avx512, avx2 or scalar.
    /// Every set gives the same image; this changes only the speed. Also RAYLAB_ISA.
    #[arg(long, global = true, default_value = "best", value_name = "ISA")]
    pub isa: String,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Render an image of the scene to a PNG or EXR file (defaults: the lab's figure 7, 512×512).
    Render(RenderArgs),
    /// Explain one pixel of the render: each step of its computation beside the lab equation
    /// it evaluates, with the numbers (sample 0: the pixel's centre).
    Inspect(InspectArgs),
    /// Measure the tracer per scene: BVH build time, Mrays/s of primary and shadow rays, and
    /// the milliseconds of one lab pass (medians over repeated passes).
    Bench(BenchArgs),
    /// Check your own render of the lab against the exact figure: how much of it matches,
    /// where it differs most, and the classic mistake that explains the difference (or none,
    /// or unknown). The figure is rendered at the image's size, with the lab's focal length
    /// (the image's width) unless --focal says otherwise.
    Check(CheckArgs),
}

/// `--isa NAME`: the kernels of every structure this process builds (`best`: measured).
fn choose_kernels(name: &str) -> anyhow::Result<()> {
    if name == "best" {
        return Ok(());
    }
    let isa = Isa::by_name(name).with_context(|| {
        format!(
            "kernels '{name}' are unknown or not supported by this CPU (expected best, avx512, avx2 or scalar)"
        )
    })?;
    isa.force().map_err(anyhow::Error::msg)
}

/// Parses the arguments and runs the command; the one place errors become exit codes.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => {
            // --help and --version: a success only if the text was written (not to a full
            // disk, `> /dev/full`).
            let mut out = std::io::stdout();
            let text = e.render();
            let printed = if std::io::IsTerminal::is_terminal(&out) {
                write!(out, "{}", text.ansi())
            } else {
                write!(out, "{text}")
            }
            .and_then(|()| out.flush());
            return match printed {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
                Err(_) => ExitCode::FAILURE,
            };
        }
        Err(e) => {
            // Nothing here may panic on a stderr that cannot be written (`2> /dev/full`):
            // the exit code says what happened.
            print_error_line(&one_line(&e.render().to_string()));
            return ExitCode::from(2);
        }
    };
    if matches!(cli.command, Some(Command::Render(_))) {
        // First: the threads started below inherit the signals it blocks.
        crate::signals::remove_temporary_files_when_stopped();
    } else {
        // `main` blocked them; other commands are stopped by them as by default.
        crate::signals::unblock();
    }
    // Whatever runs outside the commands' own pools (the kernels' calibration, for one) runs
    // on rayon's global pool: its thread count is given too, so `RAYON_NUM_THREADS` cannot
    // ask for more than the cap.
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(raylab_core::transport::progressive::default_threads())
        .thread_name(|i| format!("raylab-{i}"))
        .stack_size(raylab_core::base::memory::WORKER_STACK_BYTES)
        .build_global();
    if cli.isa == "best"
        && let Some(note) = Isa::environment_note()
    {
        print_error_line(&format!("warning: {note}"));
    }
    let result = match choose_kernels(&cli.isa) {
        Err(e) => Err(e),
        Ok(()) => match cli.command {
            Some(Command::Render(args)) => run_render(&args),
            Some(Command::Inspect(args)) => run_inspect(&args),
            Some(Command::Bench(args)) => run_bench(&args),
            Some(Command::Check(args)) => run_check(&args),
            None => crate::start_workbench(),
        },
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            match e.downcast_ref::<equations::CompileErrors>() {
                // A compiler's errors: a location and message, the line and a caret, each.
                Some(errors) => eprint!("{}", printable_lines(&errors.0)),
                None => print_error_line(&format!("error: {e:#}")),
            }
            // A pixel outside the image is a bad argument, as clap's refusals are.
            let bad_argument = e
                .downcast_ref::<InspectError>()
                .is_some_and(|e| matches!(e, InspectError::OutsideImage { .. }));
            if bad_argument {
                ExitCode::from(2)
            } else {
                ExitCode::FAILURE
            }
        }
    }
}

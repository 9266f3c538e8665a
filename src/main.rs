//! The `raylab` binary: the workbench window and the command line, thin layers over the library.

mod app;
mod cli;
mod signals;

fn main() -> std::process::ExitCode {
    cli::main()
}

/// `raylab` with no command: opens the workbench window on the lab's Cornell box (figure 7).
fn start_workbench() -> anyhow::Result<()> {
    app::run()
}

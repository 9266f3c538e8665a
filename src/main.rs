//! The `raylab` binary: the workbench window and the command line, thin layers over the library.

mod app;
mod cli;
mod signals;

/// Runs the program on a thread whose stack raylab sets ([`raylab_core::base::memory::MAIN_STACK_BYTES`])
/// and waits for it: the first thread's stack is whatever `ulimit -s` says, which may be too
/// small even for parsing the arguments. (On Linux only: elsewhere the
/// window must run on the first thread, and does, as the rest of the program.)
fn main() -> std::process::ExitCode {
    if !cfg!(target_os = "linux") {
        return cli::main();
    }
    // Before any thread starts: see `signals::block`.
    signals::block();
    let started = std::thread::Builder::new()
        .name("raylab-main".to_owned())
        .stack_size(raylab_core::base::memory::MAIN_STACK_BYTES)
        .spawn(cli::main);
    match started {
        // Its panic was reported where it happened; it ends the program as it would have.
        Ok(thread) => thread
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic)),
        Err(e) => {
            signals::unblock();
            eprintln!("error: could not start raylab's main thread ({e}); running on this one");
            cli::main()
        }
    }
}

/// `raylab` with no command: opens the workbench window on the lab's Cornell box (figure 7).
fn start_workbench() -> anyhow::Result<()> {
    app::run()
}

//! Signals that stop a render: whatever stops it, no temporary file is left behind.
//!
//! Images and scene files are written to a temporary file and renamed into place
//! ([`raylab_core::transport::film::write_atomically`]); a signal between the two would leave the
//! temporary file. So:
//!
//! * SIGINT (Ctrl+C), SIGTERM (`kill`) and SIGHUP (the terminal closed) are handled by the
//!   `ctrlc` crate: the files on [`raylab_core::base::temp_files`]' list are removed and the program
//!   exits with code 130;
//! * on Unix, the other signals whose default is to end the program and that another process
//!   or a limit sends — SIGQUIT, SIGUSR1, SIGUSR2, SIGALRM, SIGVTALRM, SIGPROF and SIGXCPU
//!   (`ulimit -t`) — are blocked in every thread and waited for by one thread of their own,
//!   which removes the files and exits with code 128 + the signal's number, as the shell
//!   reports a program the signal killed;
//! * SIGXFSZ (a write past `ulimit -f`) is ignored, so the write fails with EFBIG ("File too
//!   large") and the temporary file is removed as any failed write's is.
//!
//! Faults (SIGSEGV, SIGBUS, …) and SIGKILL cannot be handled this way.

use std::io::Write as _;

/// Blocks the signals waited for in this thread and in every thread it starts from now on.
/// `main` calls it first, before it starts the thread the program runs on
/// (`memory::MAIN_STACK_BYTES`) and waits for that: a render's signals are then blocked in
/// every thread, the waiting one too. A command other than render lets them act again
/// ([`unblock`]).
pub fn block() {
    #[cfg(unix)]
    unix::mask(nix::sys::signal::SigmaskHow::SIG_BLOCK);
}

/// Undoes [`block`] in this thread and those it starts: the signals end the program as by
/// default.
pub fn unblock() {
    #[cfg(unix)]
    unix::mask(nix::sys::signal::SigmaskHow::SIG_UNBLOCK);
}

/// Installs the handling described in the module docs. Call it before any other thread is
/// started: threads inherit the blocked signals from the thread that starts them, and a
/// thread started earlier would still die of them.
pub fn remove_temporary_files_when_stopped() {
    #[cfg(unix)]
    unix::install();
    let installed = ctrlc::set_handler(|| {
        raylab_core::base::temp_files::remove_all();
        let _ = writeln!(
            std::io::stderr(),
            "raylab: interrupted; its temporary files are removed"
        );
        std::process::exit(130);
    });
    if let Err(e) = installed {
        let _ = writeln!(std::io::stderr(), "note: Ctrl+C is not handled: {e}");
    }
}

#[cfg(unix)]
mod unix {
    use std::io::Write as _;

    use nix::sys::signal::{SigHandler, SigSet, SigmaskHow, Signal, pthread_sigmask, signal};

    /// The signals waited for (see the module docs).
    pub const WAITED_FOR: [Signal; 7] = [
        Signal::SIGQUIT,
        Signal::SIGUSR1,
        Signal::SIGUSR2,
        Signal::SIGALRM,
        Signal::SIGVTALRM,
        Signal::SIGPROF,
        Signal::SIGXCPU,
    ];

    /// Blocks or unblocks [`WAITED_FOR`] in this thread.
    pub fn mask(how: SigmaskHow) {
        let mut set = SigSet::empty();
        for s in WAITED_FOR {
            set.add(s);
        }
        if let Err(e) = pthread_sigmask(how, Some(&set), None) {
            note(&format!("SIGQUIT and the like are not handled: {e}"));
        }
    }

    pub fn install() {
        // SAFETY: ignoring a signal installs no handler; nothing else in the program sets
        // SIGXFSZ's disposition.
        if let Err(e) = unsafe { signal(Signal::SIGXFSZ, SigHandler::SigIgn) } {
            note(&format!("SIGXFSZ is not ignored: {e}"));
        }
        let mut set = SigSet::empty();
        for s in WAITED_FOR {
            set.add(s);
        }
        if let Err(e) = pthread_sigmask(SigmaskHow::SIG_BLOCK, Some(&set), None) {
            note(&format!("SIGQUIT and the like are not handled: {e}"));
            return;
        }
        let spawned = std::thread::Builder::new()
            .name("raylab-signals".to_owned())
            .stack_size(raylab_core::base::memory::WORKER_STACK_BYTES)
            .spawn(move || {
                loop {
                    // Only fails on EINTR, a signal outside the set: wait again.
                    if let Ok(received) = set.wait() {
                        raylab_core::base::temp_files::remove_all();
                        let _ = writeln!(
                            std::io::stderr(),
                            "raylab: stopped by {}; its temporary files are removed",
                            received.as_str()
                        );
                        std::process::exit(128 + received as i32);
                    }
                }
            });
        if let Err(e) = spawned {
            // Nobody would wait for them: let them act as before.
            let _ = pthread_sigmask(SigmaskHow::SIG_UNBLOCK, Some(&set), None);
            note(&format!("SIGQUIT and the like are not handled: {e}"));
        }
    }

    fn note(text: &str) {
        let _ = writeln!(std::io::stderr(), "note: {text}");
    }
}

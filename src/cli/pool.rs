//! The commands' thread pools.

use super::terminal::print_error_line;
use anyhow::Context as _;

/// A pool of `threads` threads named `raylab-{what}-N`, or by default
/// [`raylab_core::transport::progressive::default_threads`] (`RAYON_NUM_THREADS` up to four threads a
/// core, else one per core; a value beyond it is warned of). The count is always given
/// explicitly, so rayon never reads `RAYON_NUM_THREADS` itself.
pub(super) fn thread_pool(
    what: &'static str,
    threads: Option<u16>,
) -> anyhow::Result<rayon::ThreadPool> {
    let threads = match threads {
        Some(n) => usize::from(n),
        None => {
            if let Some(note) = raylab_core::transport::progressive::default_threads_note() {
                print_error_line(&format!("warning: {note}"));
            }
            raylab_core::transport::progressive::default_threads()
        }
    };
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(move |i| format!("raylab-{what}-{i}"))
        .stack_size(raylab_core::base::memory::WORKER_STACK_BYTES)
        .build()
        .with_context(|| format!("could not start the {what} threads"))
}

//! How much memory a request may use, and failing clearly when it would not fit.
//!
//! A 16384 × 16384 image of linear floats alone is 3 GiB. Asking the allocator for more than
//! the process can get used to abort the program ("memory allocation of … bytes failed", exit
//! code 134) after minutes of rendering. Now the command line estimates what a request needs
//! ([`crate::RenderSettings::memory_estimate`], [`crate::bench::memory_estimate`]) and compares
//! it with what the process can get ([`available`]) before it starts, and the big buffers are
//! reserved with `try_reserve_exact` ([`try_vec`]), so that a failed allocation is an error
//! ([`AllocError`]), not an abort.
//!
//! What the process can get is the smallest of the limits that are known (Linux; elsewhere
//! none is, and only the allocations' own failures stop a request):
//!
//! * the address-space limit (`ulimit -v`: "Max address space" in `/proc/self/limits`), less
//!   the address space the process already uses (`VmSize` in `/proc/self/status`);
//! * the control group's memory limit (cgroup v2 `/sys/fs/cgroup/memory.max` less
//!   `memory.current`; cgroup v1 `memory/memory.limit_in_bytes` less `memory.usage_in_bytes`);
//! * the memory the kernel says is available to start new work (`MemAvailable` in
//!   `/proc/meminfo`).

use std::cell::RefCell;
use std::fmt;
use std::thread::LocalKey;

/// One gibibyte, the unit sizes are given in.
pub const GIB: u64 = 1 << 30;

/// The stack of each worker thread raylab starts (the render pools', the render controller's,
/// the window's loaders): set here rather than left to `RUST_MIN_STACK`, which std's and
/// rayon's threads otherwise take it from. A render's rows need under 512 KiB
/// (`render::tests::a_tall_image_fits_in_a_small_stack`).
pub const WORKER_STACK_BYTES: usize = 4 << 20;

/// The stack of the thread the command line and the window run on: what Linux gives a first
/// thread by default, set here rather than taken from `ulimit -s` (a debug build's argument
/// parsing alone needs more than 64 KiB).
pub const MAIN_STACK_BYTES: usize = 8 << 20;

/// What the process can still get, and the limit that says so.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Available {
    pub bytes: u64,
    /// Which limit: "address-space limit: ulimit -v", "control group's memory limit" or
    /// "memory the system has available".
    pub limit: &'static str,
}

/// The smallest of the known limits (see the module docs), or `None` where none is known.
pub fn available() -> Option<Available> {
    let read = |path: &str| std::fs::read_to_string(path).ok();
    let address_space = read("/proc/self/limits")
        .and_then(|limits| address_space_limit(&limits))
        .map(|limit| {
            let used = read("/proc/self/status")
                .and_then(|status| kib_field(&status, "VmSize:"))
                .unwrap_or(0);
            limit.saturating_sub(used)
        });
    let cgroup = cgroup_room(
        read("/sys/fs/cgroup/memory.max").as_deref(),
        read("/sys/fs/cgroup/memory.current").as_deref(),
    )
    .or_else(|| {
        cgroup_room(
            read("/sys/fs/cgroup/memory/memory.limit_in_bytes").as_deref(),
            read("/sys/fs/cgroup/memory/memory.usage_in_bytes").as_deref(),
        )
    });
    let system = read("/proc/meminfo").and_then(|meminfo| kib_field(&meminfo, "MemAvailable:"));
    [
        (address_space, "address-space limit: ulimit -v"),
        (cgroup, "control group's memory limit"),
        (system, "memory the system has available"),
    ]
    .into_iter()
    .filter_map(|(bytes, limit)| bytes.map(|bytes| Available { bytes, limit }))
    .min_by_key(|a| a.bytes)
}

/// The soft "Max address space" of `/proc/self/limits`, in bytes; `None` when unlimited.
fn address_space_limit(limits: &str) -> Option<u64> {
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    let soft = line["Max address space".len()..]
        .split_whitespace()
        .next()?;
    soft.parse().ok()
}

/// A `Name:   123 kB` field of `/proc/self/status` or `/proc/meminfo`, in bytes.
fn kib_field(text: &str, name: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(name))?;
    let kib: u64 = line[name.len()..].split_whitespace().next()?.parse().ok()?;
    Some(kib * 1024)
}

/// A control group's limit less its use, from the two files' text; `None` without a limit
/// ("max", or v1's "unlimited" of nearly 2⁶³).
fn cgroup_room(limit: Option<&str>, used: Option<&str>) -> Option<u64> {
    let limit: u64 = limit?.trim().parse().ok()?;
    if limit >= 1 << 60 {
        return None;
    }
    let used: u64 = used.and_then(|u| u.trim().parse().ok()).unwrap_or(0);
    Some(limit.saturating_sub(used))
}

/// A size for people: "3.0 GiB", "512 MiB", "12 KiB".
pub fn format_bytes(bytes: u64) -> String {
    let b = bytes as f64;
    if bytes >= GIB {
        format!("{:.1} GiB", b / GIB as f64)
    } else if bytes >= 1 << 20 {
        format!("{:.0} MiB", b / (1u64 << 20) as f64)
    } else {
        format!("{:.0} KiB", (b / 1024.0).ceil())
    }
}

/// A request that needs more memory than the process can get.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "{what} needs about {} but only {} is available ({})",
    format_bytes(*.needed),
    format_bytes(.available.bytes),
    .available.limit
)]
pub struct MemoryError {
    /// What was asked for: "a 16384×16384 render".
    pub what: String,
    pub needed: u64,
    pub available: Available,
}

/// Refuses `what` when it needs more than the process can get ([`available`]); passes when no
/// limit is known.
pub fn check(what: impl Into<String>, needed: u64) -> Result<(), MemoryError> {
    check_against(what, needed, available())
}

/// [`check`] against a given limit.
pub fn check_against(
    what: impl Into<String>,
    needed: u64,
    available: Option<Available>,
) -> Result<(), MemoryError> {
    match available {
        Some(available) if needed > available.bytes => Err(MemoryError {
            what: what.into(),
            needed,
            available,
        }),
        _ => Ok(()),
    }
}

/// A buffer the allocator would not give.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub struct AllocError {
    /// What it was for: "the 16384×16384 image".
    pub what: String,
    /// Its size in bytes; `None` when it does not even fit in the address space's numbers.
    pub bytes: Option<u64>,
}

impl fmt::Display for AllocError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.bytes {
            Some(bytes) => write!(
                f,
                "could not allocate {} for {}: not enough memory",
                format_bytes(bytes),
                self.what
            ),
            None => write!(f, "could not allocate {}: it is too large", self.what),
        }
    }
}

/// `len` copies of `value` in a vector reserved with `try_reserve_exact`: an allocation that
/// fails is an [`AllocError`] naming `what`, where `vec![value; len]` aborts the program.
pub fn try_vec<T: Clone>(
    value: T,
    len: usize,
    what: impl Fn() -> String,
) -> Result<Vec<T>, AllocError> {
    let mut v = try_with_capacity(len, what)?;
    v.resize(len, value);
    Ok(v)
}

/// An empty vector with room for `len` items, reserved as [`try_vec`] does.
pub fn try_with_capacity<T>(len: usize, what: impl Fn() -> String) -> Result<Vec<T>, AllocError> {
    let bytes = len.checked_mul(std::mem::size_of::<T>()).map(|b| b as u64);
    let mut v = Vec::new();
    v.try_reserve_exact(len).map_err(|_| AllocError {
        what: what(),
        bytes,
    })?;
    Ok(v)
}

/// `work` with this thread's value in `key`, or with `fresh()` if that is in use (a caller
/// inside another's work): working memory made once a thread and reused, where making it for
/// every call (a row, a job) would fill it again each time.
#[inline(always)]
pub(crate) fn with_thread_memory<T: 'static, R>(
    key: &'static LocalKey<RefCell<T>>,
    fresh: impl FnOnce() -> T,
    work: impl FnOnce(&mut T) -> R,
) -> R {
    key.with(|memory| {
        // One call of `work` for both cases: it is inlined, and is often a whole row loop.
        let (mut borrowed, mut made);
        let memory: &mut T = match memory.try_borrow_mut() {
            Ok(memory) => {
                borrowed = memory;
                &mut borrowed
            }
            Err(_) => {
                made = fresh();
                &mut made
            }
        };
        work(memory)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const LIMITS: &str = "Limit                     Soft Limit           Hard Limit           Units     \n\
        Max cpu time              unlimited            unlimited            seconds   \n\
        Max address space         4096000000           4096000000           bytes     \n\
        Max open files            1024                 1048576              files     \n";

    #[test]
    fn the_limits_are_read_from_the_kernels_files() {
        // `ulimit -v 4000000` is 4,000,000 KiB.
        assert_eq!(address_space_limit(LIMITS), Some(4_096_000_000));
        let unlimited = LIMITS.replace(
            "4096000000           4096000000",
            "unlimited            unlimited ",
        );
        assert_eq!(address_space_limit(&unlimited), None);
        let status = "Name:\traylab\nVmPeak:\t  20000 kB\nVmSize:\t   16384 kB\n";
        assert_eq!(kib_field(status, "VmSize:"), Some(16 << 20));
        let meminfo = "MemTotal:       24000000 kB\nMemAvailable:   3000000 kB\n";
        assert_eq!(kib_field(meminfo, "MemAvailable:"), Some(3_072_000_000));
        assert_eq!(cgroup_room(Some("max\n"), Some("100\n")), None);
        assert_eq!(cgroup_room(Some("9223372036854771712\n"), Some("1")), None);
        assert_eq!(
            cgroup_room(Some("4294967296\n"), Some("1073741824\n")),
            Some(3 << 30)
        );
        assert_eq!(cgroup_room(None, Some("1")), None);
    }

    #[test]
    fn sizes_read_as_people_write_them() {
        assert_eq!(format_bytes(3 << 30), "3.0 GiB");
        assert_eq!(format_bytes(3_221_225_472 + (200 << 20)), "3.2 GiB");
        assert_eq!(format_bytes(512 << 20), "512 MiB");
        assert_eq!(format_bytes(1000), "1 KiB");
    }

    #[test]
    fn a_request_beyond_the_limit_is_refused_saying_both_sizes() {
        // `ulimit -v 3000000` (KiB), less 16 MiB in use: 3,055,222,784 bytes, 2.85 GiB.
        let limit = Some(Available {
            bytes: 3_072_000_000 - (16 << 20),
            limit: "address-space limit: ulimit -v",
        });
        assert_eq!(check_against("a small render", 1 << 30, limit), Ok(()));
        assert_eq!(check_against("anything", u64::MAX, None), Ok(()));
        // A 16384² render: 3,288,334,336 bytes, 3.06 GiB.
        let e = check_against("a 16384×16384 render", 3_288_334_336, limit).unwrap_err();
        assert_eq!(
            e.to_string(),
            "a 16384×16384 render needs about 3.1 GiB but only 2.8 GiB is available \
             (address-space limit: ulimit -v)"
        );
    }

    /// A buffer too large to exist is an error, not an abort.
    #[test]
    fn an_impossible_buffer_is_an_error() {
        let e = try_vec(0u64, usize::MAX / 4, || "a huge buffer".into()).unwrap_err();
        assert_eq!(e.bytes, None);
        assert_eq!(
            e.to_string(),
            "could not allocate a huge buffer: it is too large"
        );
        let e = try_with_capacity::<u8>(usize::MAX / 2, || "half the address space".into())
            .unwrap_err();
        assert_eq!(e.bytes, Some((usize::MAX / 2) as u64));
        assert!(e.to_string().starts_with("could not allocate "), "{e}");
        assert_eq!(try_vec(7u8, 3, || unreachable!()).unwrap(), [7, 7, 7]);
    }
}

//! What slows raylab down when the host is busy: a probe that runs the lab pass beside small
//! kernels that each lean on one part of the core, round after round, and prints each second's
//! medians.
//!
//! On a virtual machine without hardware counters (`perf stat` says "not supported") this is how
//! to tell what a slow minute takes away: the clock (the dependent `add` chain slows), the
//! execution units (the independent FMAs and adds slow at the same clock, as when another
//! hardware thread shares the core), the branch predictor (the learnable branch patterns slow),
//! or the caches and memory (the pointer chases slow). PERFORMANCE.md ("How to measure": a busy minute)
//! reports what it showed.
//!
//! ```text
//! cargo run --release --example host_probe -- [seconds]      # default 60
//! taskset -c 1 target/release/examples/host_probe 120        # one vCPU
//! ```
//!
//! Each line: the second, the lab pass (Cornell box, 512², one thread) in ms, then the clock in
//! GHz measured by the chain, then each kernel as work per cycle at that clock (so a figure that
//! drops while the clock holds lost its resource, not its clock), then the chases in ns a load.

use std::hint::black_box;
use std::time::Instant;

use raylab_core::transport::render::render_pass;
use raylab_core::transport::settings::RenderSettings;

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let seconds = match args.first().and_then(|s| s.parse().ok()) {
        Some(seconds) => {
            args.remove(0);
            seconds
        }
        None => 60,
    };
    #[cfg(target_arch = "x86_64")]
    {
        if args.is_empty() {
            args = x86::KERNELS
                .iter()
                .map(|(name, _)| name.to_string())
                .collect();
        }
        if let Some(unknown) = args
            .iter()
            .find(|a| !x86::KERNELS.iter().any(|(n, _)| n == a))
        {
            eprintln!("host_probe: no kernel {unknown:?}; the kernels:");
            for (name, what) in x86::KERNELS {
                eprintln!("  {name:8} {what}");
            }
            std::process::exit(2);
        }
        x86::run(seconds, &args);
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = seconds;
        eprintln!("host_probe: its kernels are written for x86-64 only");
    }
}

/// One pass of the Cornell box, 512², on the pool's one thread, in nanoseconds.
fn pass_ns(
    pool: &rayon::ThreadPool,
    scene: &raylab_core::shapes::scene::Scene,
    settings: &RenderSettings,
    pass: &mut u32,
) -> f64 {
    *pass += 1;
    pool.install(|| {
        let start = Instant::now();
        let image = render_pass(scene, settings, *pass, &|| false).expect("the default renders");
        black_box(&image);
        start.elapsed().as_nanos() as f64
    })
}

/// Writes 3 MB (a 512² image of RGB floats), as a pass does; nanoseconds.
fn stream_ns(buffer: &mut [u32]) -> f64 {
    let start = Instant::now();
    for (i, word) in buffer.iter_mut().enumerate() {
        *word = i as u32;
    }
    black_box(buffer);
    start.elapsed().as_nanos() as f64
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// A random cyclic permutation of `len` slots, for a chase whose every load depends on the last
/// and that no prefetcher can follow.
fn chase_ring(len: usize, seed: u64) -> Vec<u32> {
    let mut order: Vec<u32> = (0..len as u32).collect();
    let mut state = seed;
    for i in (1..len).rev() {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let j = ((state >> 33) % (i as u64 + 1)) as usize;
        order.swap(i, j);
    }
    let mut next = vec![0u32; len];
    for w in 0..len {
        next[order[w] as usize] = order[(w + 1) % len];
    }
    next
}

/// Follows the ring `steps` times; nanoseconds a load.
fn chase_ns(ring: &[u32], steps: usize) -> f64 {
    let start = Instant::now();
    let mut at = 0u32;
    for _ in 0..steps {
        at = ring[at as usize];
    }
    black_box(at);
    start.elapsed().as_nanos() as f64 / steps as f64
}

/// Sums the bytes that are set, with a real conditional jump per byte (no `cmov`): a pattern of
/// `bits.len()` random outcomes repeated, which a predictor learns if it has room for it.
fn branches_ns(bits: &[u8], repeats: usize) -> f64 {
    let start = Instant::now();
    let mut count = 0u64;
    for _ in 0..repeats {
        count = count.wrapping_add(x86_branches(bits));
    }
    black_box(count);
    start.elapsed().as_nanos() as f64 / (bits.len() * repeats) as f64
}

#[cfg(target_arch = "x86_64")]
fn x86_branches(bits: &[u8]) -> u64 {
    let mut count: u64 = 0;
    // SAFETY: reads `bits.len()` bytes from `bits.as_ptr()`, all within the slice.
    unsafe {
        std::arch::asm!(
            "test {n}, {n}",
            "jz 3f",
            "2:",
            "cmp byte ptr [{p}], 0",
            "je 4f",
            "add {c}, 1",
            "4:",
            "add {p}, 1",
            "sub {n}, 1",
            "jnz 2b",
            "3:",
            p = inout(reg) bits.as_ptr() => _,
            n = inout(reg) bits.len() => _,
            c = inout(reg) count,
            options(nostack, readonly),
        );
    }
    count
}

#[cfg(not(target_arch = "x86_64"))]
fn x86_branches(bits: &[u8]) -> u64 {
    bits.iter().filter(|&&b| b != 0).count() as u64
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::*;

    /// Iterations of each arithmetic kernel: enough that each run is far longer than the
    /// clock's resolution.
    const ITERATIONS: u64 = 1_000_000;

    /// Eight dependent adds an iteration: one a cycle on any x86 core, so the time is the clock.
    fn chain_ns() -> f64 {
        let start = Instant::now();
        let mut x: u64 = 0;
        // SAFETY: register arithmetic only.
        unsafe {
            std::arch::asm!(
                "2:",
                "add {x}, 1", "add {x}, 1", "add {x}, 1", "add {x}, 1",
                "add {x}, 1", "add {x}, 1", "add {x}, 1", "add {x}, 1",
                "sub {n}, 1",
                "jnz 2b",
                x = inout(reg) x,
                n = inout(reg) ITERATIONS => _,
                options(nostack, nomem),
            );
        }
        black_box(x);
        start.elapsed().as_nanos() as f64
    }

    /// Four independent chains of four adds: as many adds a cycle as the integer units give.
    fn alu_ns() -> f64 {
        let start = Instant::now();
        let (mut a, mut b, mut c, mut d) = (0u64, 0u64, 0u64, 0u64);
        // SAFETY: register arithmetic only.
        unsafe {
            std::arch::asm!(
                "2:",
                "add {a}, 1", "add {b}, 1", "add {c}, 1", "add {d}, 1",
                "add {a}, 1", "add {b}, 1", "add {c}, 1", "add {d}, 1",
                "add {a}, 1", "add {b}, 1", "add {c}, 1", "add {d}, 1",
                "add {a}, 1", "add {b}, 1", "add {c}, 1", "add {d}, 1",
                "sub {n}, 1",
                "jnz 2b",
                a = inout(reg) a, b = inout(reg) b, c = inout(reg) c, d = inout(reg) d,
                n = inout(reg) ITERATIONS => _,
                options(nostack, nomem),
            );
        }
        black_box((a, b, c, d));
        start.elapsed().as_nanos() as f64
    }

    /// `$name`: ten independent FMAs an iteration on registers `$r`0–11 (`zmm`: 512 bits,
    /// `ymm`: 256), the vector units' throughput; compiled with `$features`.
    macro_rules! fma_kernel {
        ($name:ident, $features:literal, $r:literal) => {
            #[target_feature(enable = $features)]
            fn $name() -> f64 {
                let start = Instant::now();
                // SAFETY: register arithmetic only; the caller checked the features.
                unsafe {
                    std::arch::asm!(
                        concat!("vxorps ", $r, "10, ", $r, "10, ", $r, "10"),
                        concat!("vxorps ", $r, "11, ", $r, "11, ", $r, "11"),
                        "2:",
                        concat!("vfmadd231ps ", $r, "0, ", $r, "10, ", $r, "11"),
                        concat!("vfmadd231ps ", $r, "1, ", $r, "10, ", $r, "11"),
                        concat!("vfmadd231ps ", $r, "2, ", $r, "10, ", $r, "11"),
                        concat!("vfmadd231ps ", $r, "3, ", $r, "10, ", $r, "11"),
                        concat!("vfmadd231ps ", $r, "4, ", $r, "10, ", $r, "11"),
                        concat!("vfmadd231ps ", $r, "5, ", $r, "10, ", $r, "11"),
                        concat!("vfmadd231ps ", $r, "6, ", $r, "10, ", $r, "11"),
                        concat!("vfmadd231ps ", $r, "7, ", $r, "10, ", $r, "11"),
                        concat!("vfmadd231ps ", $r, "8, ", $r, "10, ", $r, "11"),
                        concat!("vfmadd231ps ", $r, "9, ", $r, "10, ", $r, "11"),
                        "sub {n}, 1",
                        "jnz 2b",
                        "vzeroupper",
                        n = inout(reg) ITERATIONS => _,
                        out("xmm0") _, out("xmm1") _, out("xmm2") _, out("xmm3") _,
                        out("xmm4") _, out("xmm5") _, out("xmm6") _, out("xmm7") _,
                        out("xmm8") _, out("xmm9") _, out("xmm10") _, out("xmm11") _,
                        options(nostack, nomem),
                    );
                }
                start.elapsed().as_nanos() as f64
            }
        };
    }

    fma_kernel!(fma512_ns, "avx512f", "zmm");
    fma_kernel!(fma256_ns, "avx2,fma", "ymm");

    /// 1000 independent 512-bit FMAs in one loop body (6 KB of code, about the size of a
    /// traversal kernel with its shading): the front end's throughput from the op cache.
    #[target_feature(enable = "avx512f")]
    fn big_body_ns() -> f64 {
        let start = Instant::now();
        // SAFETY: register arithmetic only; the caller checked AVX-512F.
        unsafe {
            std::arch::asm!(
                "vxorps zmm0, zmm0, zmm0", "vxorps zmm1, zmm1, zmm1",
                "vxorps zmm2, zmm2, zmm2", "vxorps zmm3, zmm3, zmm3",
                "vxorps zmm4, zmm4, zmm4", "vxorps zmm5, zmm5, zmm5",
                "vxorps zmm6, zmm6, zmm6", "vxorps zmm7, zmm7, zmm7",
                "vxorps zmm8, zmm8, zmm8", "vxorps zmm9, zmm9, zmm9",
                "vxorps zmm10, zmm10, zmm10", "vxorps zmm11, zmm11, zmm11",
                "2:",
                ".rept 100",
                "vfmadd231ps zmm0, zmm10, zmm11", "vfmadd231ps zmm1, zmm10, zmm11",
                "vfmadd231ps zmm2, zmm10, zmm11", "vfmadd231ps zmm3, zmm10, zmm11",
                "vfmadd231ps zmm4, zmm10, zmm11", "vfmadd231ps zmm5, zmm10, zmm11",
                "vfmadd231ps zmm6, zmm10, zmm11", "vfmadd231ps zmm7, zmm10, zmm11",
                "vfmadd231ps zmm8, zmm10, zmm11", "vfmadd231ps zmm9, zmm10, zmm11",
                ".endr",
                "sub {n}, 1",
                "jnz 2b",
                "vzeroupper",
                n = inout(reg) 1000u64 => _,
                out("zmm0") _, out("zmm1") _, out("zmm2") _, out("zmm3") _,
                out("zmm4") _, out("zmm5") _, out("zmm6") _, out("zmm7") _,
                out("zmm8") _, out("zmm9") _, out("zmm10") _, out("zmm11") _,
                options(nostack, nomem),
            );
        }
        start.elapsed().as_nanos() as f64
    }

    /// 1024 always-taken jumps one after the other (each to the next, 16 bytes on): one target
    /// buffer entry each, so their cost is the predictor's room for taken branches.
    fn jumps_ns() -> f64 {
        let start = Instant::now();
        // SAFETY: jumps forward within the block, register arithmetic only.
        unsafe {
            std::arch::asm!(
                "2:",
                ".rept 1024",
                "jmp 3f",
                ".p2align 4",
                "3:",
                ".endr",
                "sub {n}, 1",
                "jnz 2b",
                n = inout(reg) 1000u64 => _,
                options(nostack, nomem),
            );
        }
        start.elapsed().as_nanos() as f64
    }

    /// An inner loop of exactly 30 trips (the Cornell box's triangles), run 100,000 times: its
    /// exit is predicted only by a predictor that keeps 30 outcomes of history.
    fn loop30_ns() -> f64 {
        let start = Instant::now();
        // SAFETY: register arithmetic only.
        unsafe {
            std::arch::asm!(
                "2:",
                "mov {i}, 30",
                "3:",
                "add {x}, {i}",
                "sub {i}, 1",
                "jnz 3b",
                "sub {n}, 1",
                "jnz 2b",
                n = inout(reg) 100_000u64 => _,
                i = out(reg) _,
                x = inout(reg) 0u64 => _,
                options(nostack, nomem),
            );
        }
        start.elapsed().as_nanos() as f64
    }

    /// Four integer adds, two 512-bit integer adds and two loads, all independent, over and
    /// over: as many instructions a cycle as the core dispatches to one thread.
    #[target_feature(enable = "avx512f")]
    fn ipc_ns(buffer: &[u64]) -> f64 {
        let start = Instant::now();
        // SAFETY: reads the first 128 bytes of `buffer` (2048 words); the caller checked
        // AVX-512F.
        unsafe {
            std::arch::asm!(
                "vpxord zmm0, zmm0, zmm0", "vpxord zmm1, zmm1, zmm1", "vpxord zmm2, zmm2, zmm2",
                "2:",
                ".rept 64",
                "add {a}, 1", "add {b}, 1", "add {c}, 1", "add {d}, 1",
                "vpaddd zmm0, zmm0, zmm2", "vpaddd zmm1, zmm1, zmm2",
                "mov {e}, [{p}]", "mov {e}, [{p} + 64]",
                ".endr",
                "sub {n}, 1",
                "jnz 2b",
                "vzeroupper",
                a = inout(reg) 0u64 => _, b = inout(reg) 0u64 => _,
                c = inout(reg) 0u64 => _, d = inout(reg) 0u64 => _,
                e = out(reg) _,
                p = in(reg) buffer.as_ptr(),
                n = inout(reg) 10_000u64 => _,
                out("zmm0") _, out("zmm1") _, out("zmm2") _,
                options(nostack, readonly),
            );
        }
        start.elapsed().as_nanos() as f64
    }

    /// Sums a 16 KB buffer (in L1) many times over: the load units' throughput.
    fn l1_ns(buffer: &[u64]) -> f64 {
        let start = Instant::now();
        let mut sum = [0u64; 8];
        for _ in 0..64 {
            for chunk in black_box(buffer).chunks_exact(8) {
                for (s, v) in sum.iter_mut().zip(chunk) {
                    *s = s.wrapping_add(*v);
                }
            }
        }
        black_box(sum);
        start.elapsed().as_nanos() as f64
    }

    /// The kernels by name, with what their column shows.
    pub const KERNELS: [(&str, &str); 18] = [
        ("lab", "lab pass, ms"),
        ("path", "path pass, ms"),
        ("ghz", "clock, GHz"),
        ("alu", "adds a cycle"),
        ("fma512", "512-bit FMAs a cycle"),
        ("fma256", "256-bit FMAs a cycle"),
        ("l1", "bytes loaded a cycle"),
        ("br64", "ns a branch, 64 learnable"),
        ("br2k", "ns a branch, 2048 learnable"),
        ("brrand", "ns a branch, random"),
        ("l2", "ns a load, 256 KB chase"),
        ("l3", "ns a load, 8 MB chase"),
        ("dram", "ns a load, 256 MB chase"),
        ("stream", "ns to write 3 MB"),
        ("bigbody", "512-bit FMAs a cycle, 1000 in a loop body"),
        ("jumps", "cycles a taken jump, 1024 jumps in a row"),
        ("loop30", "cycles an iteration of a 30-trip inner loop"),
        (
            "ipc",
            "instructions a cycle, eight independent ones after another",
        ),
    ];

    pub fn run(seconds: u64, names: &[String]) {
        let avx512 = is_x86_feature_detected!("avx512f");
        let avx2 = is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma");
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("a one-thread pool");
        let scene = raylab_core::shapes::scene::cornell_box();
        let lab = RenderSettings::default();
        let mut path = RenderSettings::default();
        path.shading = raylab_core::transport::integrator::Shading::for_stage(
            raylab_core::transport::integrator::Stage::Path,
        );
        let l1 = vec![1u64; 2048];
        let l2 = chase_ring(64 << 10, 1); // 256 KB of u32
        let l3 = chase_ring(2 << 20, 2); // 8 MB
        let dram = chase_ring(64 << 20, 3); // 256 MB
        let mut stream = vec![0u32; 3 << 18]; // 3 MB
        let mut state = 7u64;
        let mut random_bits = |len: usize| -> Vec<u8> {
            (0..len)
                .map(|_| {
                    state = state
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    (state >> 63) as u8
                })
                .collect()
        };
        let short_pattern = random_bits(64);
        let long_pattern = random_bits(2048);
        let unlearnable = random_bits(1 << 20);

        print!("  s");
        for name in names {
            print!(" {name:>8}");
        }
        println!();
        let begin = Instant::now();
        let mut pass = 0;
        for second in 0..seconds {
            let mut columns: Vec<Vec<f64>> = vec![Vec::new(); names.len()];
            while begin.elapsed().as_secs() <= second {
                let ghz = (8 * ITERATIONS) as f64 / chain_ns();
                let cycles = |ns: f64| ns * ghz;
                for (name, column) in names.iter().zip(&mut columns) {
                    // SAFETY (the FMAs): their features are checked first.
                    let value = match name.as_str() {
                        "lab" => pass_ns(&pool, &scene, &lab, &mut pass) / 1e6,
                        "path" => pass_ns(&pool, &scene, &path, &mut pass) / 1e6,
                        "ghz" => ghz,
                        "alu" => (16 * ITERATIONS) as f64 / cycles(alu_ns()),
                        "fma512" if avx512 => {
                            (10 * ITERATIONS) as f64 / cycles(unsafe { fma512_ns() })
                        }
                        "fma256" if avx2 => {
                            (10 * ITERATIONS) as f64 / cycles(unsafe { fma256_ns() })
                        }
                        "l1" => (64 * l1.len() * 8) as f64 / cycles(l1_ns(&l1)),
                        "br64" => branches_ns(&short_pattern, 4096),
                        "br2k" => branches_ns(&long_pattern, 128),
                        "brrand" => branches_ns(&unlearnable, 1),
                        "l2" => chase_ns(&l2, 100_000),
                        "l3" => chase_ns(&l3, 50_000),
                        "dram" => chase_ns(&dram, 10_000),
                        "stream" => stream_ns(&mut stream),
                        "bigbody" if avx512 => {
                            (1000 * 1000) as f64 / cycles(unsafe { big_body_ns() })
                        }
                        "jumps" => cycles(jumps_ns()) / (1024 * 1000) as f64,
                        "loop30" => cycles(loop30_ns()) / (30 * 100_000) as f64,
                        "ipc" if avx512 => {
                            (8 * 64 * 10_000) as f64 / cycles(unsafe { ipc_ns(&l1) })
                        }
                        _ => f64::NAN,
                    };
                    column.push(value);
                }
            }
            print!("{:3}", second + 1);
            for column in &mut columns {
                print!(" {:8.3}", median(column));
            }
            println!();
        }
    }
}

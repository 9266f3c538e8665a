#!/usr/bin/env python3
"""Times Mitsuba 3 (llvm_ad_rgb) on the lab's Cornell box: paths (camera samples) per second.

    python3 scripts/mitsuba/time.py --threads 1 [--launches 6] [--width 512 --height 512 --spp 64]

Renders the box with the `path` integrator (max_depth -1, rr_depth 5) and the `direct`
integrator, each `--launches` times at WIDTH x HEIGHT x SPP samples per launch. The first launch
of each is reported but left out of the median: it includes the JIT compilation of the kernel
(later launches reuse it; each launch has a new seed, passed as an opaque value so that it does
not change the kernel). Threads: dr.set_thread_count(N) (drjit reads no environment variable for
this; by default it uses every core of the process's CPU affinity, so `taskset` limits it too).
Prints one line per launch, the medians, and one JSON line.

`--isa avx2` holds Dr.Jit's LLVM back end to AVX2 and FMA with 8-wide vectors on a CPU that has
AVX-512 (`jit_llvm_set_target` from libdrjit-core, called before the first kernel is compiled),
so that Mitsuba is measured beside raylab's `--isa avx2`; the default, `native`, lets Dr.Jit
target the whole CPU (16-wide with AVX-512).
"""

import argparse
import ctypes
import json
import os
import platform
import re
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cornell import dr, mi, scene_dict  # noqa: E402  (sets DRJIT_LIBLLVM_PATH first)


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor()


# The CPU model and features LLVM is given for `--isa avx2`: Haswell's set, AVX-512 off.
AVX2_CPU = b"haswell"
AVX2_FEATURES = (b"+avx2,+fma,+f16c,+bmi,+bmi2,+lzcnt,+popcnt,+avx,+sse4.2,+sse4.1,+ssse3,"
                 b"+sse3,+sse2,-avx512f")


def hold_to_avx2():
    """Sets Dr.Jit's LLVM target to AVX2 + FMA, 8 lanes; its kernels compiled after this use it.

    The function is exported from libdrjit-core.so under its C++ name only."""
    lib = ctypes.CDLL(os.path.join(os.path.dirname(dr.__file__), "libdrjit-core.so"))
    set_target = getattr(lib, "_Z19jit_llvm_set_targetPKcS0_j")
    set_target.argtypes = [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_uint32]
    set_target.restype = None
    set_target(AVX2_CPU, AVX2_FEATURES, 8)


def vector_widths():
    """The float vector widths in the IR of the kernels compiled so far (clears the history)."""
    widths = set()
    for kernel in dr.kernel_history():
        ir = kernel.get("ir")
        text = ir.read() if hasattr(ir, "read") else str(ir or "")
        widths.update(int(w) for w in re.findall(r"<(\d+) x float>", text))
    return widths


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--threads", type=int, default=None, help="drjit threads (default: all)")
    p.add_argument("--launches", type=int, default=6, help="including the first (JIT) one")
    p.add_argument("--width", type=int, default=512)
    p.add_argument("--height", type=int, default=512)
    p.add_argument("--spp", type=int, default=64)
    p.add_argument("--integrators", default="path,direct")
    p.add_argument("--isa", choices=["native", "avx2"], default="native",
                   help="LLVM target: the whole CPU, or AVX2+FMA with 8 lanes")
    a = p.parse_args()

    mi.set_variant("llvm_ad_rgb")
    if a.isa == "avx2":
        hold_to_avx2()
    # The kernels' IR says which vector width LLVM was really given (`<8 x float>` for AVX2).
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    mi.set_log_level(mi.LogLevel.Warn)
    if a.threads:
        dr.set_thread_count(a.threads)
    paths = a.width * a.height * a.spp
    result = {"renderer": f"mitsuba {mi.__version__} llvm_ad_rgb", "cpu": cpu_model(),
              "threads": dr.thread_count(), "isa": a.isa, "width": a.width, "height": a.height,
              "spp": a.spp, "paths_per_launch": paths}
    for integrator in a.integrators.split(","):
        scene = mi.load_dict(scene_dict(a.width, a.height, a.spp, integrator))
        rates = []
        for i in range(a.launches):
            seed = dr.opaque(mi.UInt32, i)
            t0 = time.perf_counter()
            img = mi.render(scene, spp=a.spp, seed=seed)
            dr.eval(img)
            dr.sync_thread()
            dt = time.perf_counter() - t0
            rates.append(paths / dt)
            note = " (first: JIT compile, excluded)" if i == 0 else ""
            print(f"{integrator} launch {i}: {dt * 1e3:8.1f} ms  {paths / dt / 1e6:7.3f} Mpaths/s"
                  f"{note}", flush=True)
        result.setdefault("llvm_vector_widths", sorted(vector_widths()))
        median = statistics.median(rates[1:]) if len(rates) > 1 else rates[0]
        print(f"{integrator}: median {median / 1e6:.3f} Mpaths/s on {dr.thread_count()} "
              f"thread(s)")
        result[integrator] = {"median_paths_per_s": round(median),
                              "first_launch_paths_per_s": round(rates[0]),
                              "paths_per_s": [round(r) for r in rates[1:]]}
    print(json.dumps(result))


if __name__ == "__main__":
    main()

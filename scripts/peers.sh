#!/usr/bin/env bash
# raylab beside Mitsuba 3 on the lab's Cornell box at 512², alternating, a few rounds.
#
#   scripts/peers.sh [--threads N] [--rounds R] [--launches L] [--isa native|avx2]
#
# `--isa avx2` holds both to AVX2 on a CPU with AVX-512: raylab runs `--isa avx2`, and Mitsuba's
# LLVM back end is given an AVX2 + FMA target with 8-wide vectors (scripts/mitsuba/time.py
# --isa avx2). The default, native, lets each use the whole CPU.
#
#   scripts/peers.sh --obvhs [--threads N] [--rounds R] [--isa native|avx2] [SCENE ...]
#
# runs the BVH-level peer instead: `cargo bench --bench peers` (the same rays through raylab
# and obvhs's CWBVH), R rounds, summarised by scripts/peers-table.py. obvhs has no run-time
# dispatch, so both are compiled for the instruction set asked: `-C target-cpu=native`, or
# `-C target-cpu=x86-64-v3` (AVX2, FMA) with raylab's kernels held to AVX2 (RAYLAB_ISA=avx2),
# each in a target folder of its own (target/peers-native, target/peers-avx2).
#
# Each round runs `raylab bench --scene cornell --stage path --threads N --json` (the lab pass
# and the path pass, medians of 61 passes), `raylab render --stage shadows --samples 64` three
# times (the `direct` integrator's equivalent, at Mitsuba's 64 samples a pixel in one go; the
# render alone is timed, not writing the file, and the median of the three taken: one render
# is short enough that one hiccup of the shared host would move it) and then
# scripts/mitsuba/time.py --threads N (the `direct` and `path` integrators, 64 samples per
# pixel a launch, L launches of which the first, the JIT compilation, is left out, and their
# median taken), so both see the same minute of this shared machine. Prints one line per round
# and pair:
#
#   lab pass (figure 7, one sample a pixel) samples/s  vs  Mitsuba `direct` samples/s
#   shadows stage, 64 spp render, samples/s            vs  Mitsuba `direct` samples/s
#   path pass samples/s                                vs  Mitsuba `path` samples/s
#
# A sample is one camera ray's whole estimate (a path, for `path`). Mitsuba must be installed
# (scripts/mitsuba/install.sh); the release binary is built if missing.
# BVH-level comparison with another Rust library: `cargo bench --bench peers` (PERFORMANCE.md,
# "Against obvhs").
set -euo pipefail

cd "$(dirname "$0")/.."
THREADS=2
ROUNDS=3
LAUNCHES=5
ISA=native
OBVHS=0
SCENES=()
while [ $# -gt 0 ]; do
    case "$1" in
        --threads) THREADS=$2; shift 2 ;;
        --rounds) ROUNDS=$2; shift 2 ;;
        --launches) LAUNCHES=$2; shift 2 ;;
        --isa) ISA=$2; shift 2 ;;
        --obvhs) OBVHS=1; shift ;;
        -*) echo "usage: $0 [--threads N] [--rounds R] [--launches L] [--isa native|avx2]" >&2
           exit 2 ;;
        *) SCENES+=("$1"); shift ;;
    esac
done
case "$ISA" in
    native) RAYLAB_ISA_ARG=best ;;
    avx2) RAYLAB_ISA_ARG=avx2 ;;
    *) echo "peers.sh: --isa is native or avx2, not $ISA" >&2; exit 2 ;;
esac
PY=${PYTHON:-python3}

if [ "$OBVHS" = 1 ]; then
    case "$ISA" in
        native) FLAGS="-C target-cpu=native"; FORCE="" ;;
        avx2) FLAGS="-C target-cpu=x86-64-v3"; FORCE=avx2 ;;
    esac
    threads=1
    [ "$THREADS" = 1 ] || threads="1,$THREADS"
    out=$(mktemp --suffix=.jsonl)
    for _ in $(seq 1 "$ROUNDS"); do
        env RUSTFLAGS="$FLAGS" CARGO_TARGET_DIR="target/peers-$ISA" ${FORCE:+RAYLAB_ISA=$FORCE} \
            cargo bench --quiet -p raylab-core --bench peers -- --json --threads "$threads" \
            "${SCENES[@]}" >>"$out"
    done
    echo "# obvhs and raylab, both built with $FLAGS${FORCE:+, RAYLAB_ISA=$FORCE}; $ROUNDS round(s)"
    "$PY" scripts/peers-table.py "$out"
    rm -f "$out"
    exit 0
fi

RAYLAB=target/release/raylab
[ -x "$RAYLAB" ] || cargo build --release --quiet
"$PY" -c "import mitsuba" 2>/dev/null || {
    echo "peers.sh: Mitsuba is not installed: scripts/mitsuba/install.sh" >&2
    exit 1
}

echo "# $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //'), family" \
    "$(grep -m1 'cpu family' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //'), $(nproc) CPUs;" \
    "$THREADS thread(s), isa $ISA, 512x512, $(date -u +%Y-%m-%dT%H:%MZ)"
printf '%-6s %-24s %14s %14s %8s\n' round pair "raylab/s" "mitsuba/s" ratio
for round in $(seq 1 "$ROUNDS"); do
    # 61 passes: the median then spans seconds, as Mitsuba's launches do (with the default 15
    # a lab pass's figure spans a fraction of a second, and one hiccup of the shared host
    # could decide the round: PERFORMANCE.md, "Against Mitsuba 3").
    raylab_json=$("$RAYLAB" --isa "$RAYLAB_ISA_ARG" bench --scene cornell --stage path \
        --threads "$THREADS" --passes 61 --json)
    out=$(mktemp --suffix=.exr)
    raylab_render=""
    for _ in 1 2 3; do
        raylab_render+=$("$RAYLAB" --isa "$RAYLAB_ISA_ARG" render --stage shadows --samples 64 \
            --threads "$THREADS" --out "$out")$'\n'
    done
    rm -f "$out"
    mitsuba_json=$("$PY" scripts/mitsuba/time.py --threads "$THREADS" --isa "$ISA" \
        --launches "$LAUNCHES" | tail -n 1)
    RAYLAB_JSON=$raylab_json RAYLAB_RENDER=$raylab_render MITSUBA_JSON=$mitsuba_json \
        ROUND=$round "$PY" - <<'EOF'
import json, os, re
r = json.loads(os.environ["RAYLAB_JSON"])
renders = re.findall(r"64 spp\) in ([0-9.]+) ms", os.environ["RAYLAB_RENDER"])
render_ms = sorted(float(t) for t in renders)[len(renders) // 2]
m = json.loads(os.environ["MITSUBA_JSON"])
pixels = r["width"] * r["height"]
lab = pixels / (r["lab_pass_ms"] / 1e3)
rows = [("lab pass / direct", lab, m["direct"]["median_paths_per_s"]),
        ("shadows 64 spp / direct", 64 * pixels / (render_ms / 1e3),
         m["direct"]["median_paths_per_s"]),
        ("path / path", r["path_samples_per_s"], m["path"]["median_paths_per_s"])]
for name, a, b in rows:
    print(f"{os.environ['ROUND']:<6} {name:<24} {a / 1e6:12.2f} M {b / 1e6:12.2f} M {a / b:7.2f}x")
EOF
done

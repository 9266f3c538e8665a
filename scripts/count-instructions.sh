#!/usr/bin/env bash
# Instructions and taken branches a pixel of one render pass, counted exactly by single-stepping
# (scripts/stepcount.c): the measure of work that does not depend on what else the host runs,
# for machines without hardware counters. PERFORMANCE.md ("How to measure": a busy minute) says why.
#
#   scripts/count-instructions.sh [lab|path] [WIDTH HEIGHT [SAMPLE]] [-- report options]
#
# Defaults: lab, 512 × 32 (a strip through the middle of the default view; a 512-pixel row
# makes the same batches as the full image), sample 0. Needs cc and binutils (addr2line).
# Single-stepping is slow: the default lab strip takes minutes.
set -euo pipefail
cd "$(dirname "$0")/.."
STAGE=${1:-lab}
WIDTH=${2:-512}
HEIGHT=${3:-32}
SAMPLE=${4:-0}
shift $(( $# < 4 ? $# : 4 ))
[ "${1:-}" = "--" ] && shift
OUT=target/stepcount
mkdir -p "$OUT"
cc -O2 -o "$OUT/stepcount" scripts/stepcount.c
cargo build --release --quiet -p raylab-core --example marked_pass
EXE=target/release/examples/marked_pass
"$OUT/stepcount" "$OUT/histogram.txt" "$EXE" "$STAGE" "$WIDTH" "$HEIGHT" "$SAMPLE"
python3 scripts/stepcount-report.py "$OUT/histogram.txt" "$EXE" $((WIDTH * HEIGHT)) "$@"

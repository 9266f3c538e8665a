#!/usr/bin/env bash
# How long `raylab check` takes over a class: 200 submissions of 512² (the class_folder
# example's set, repeated) checked and reported (--report, --gradescope) on 2 threads, the
# release build, three runs. Prints each run's wall time; PERFORMANCE.md ("In the window, and
# a class check") has the figures.
#
# Usage: scripts/measure-class.sh [COUNT] [SIDE] [THREADS]
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
count="${1:-200}"
side="${2:-512}"
threads="${3:-2}"
work="$root/target/measure-class"

cargo build --release --quiet
bin="${CARGO_TARGET_DIR:-$root/target}/release/raylab"
rm -rf "$work"
mkdir -p "$work"
cargo run --quiet --release --example class_folder -- "$work" "$side" "$count"
for run in 1 2 3; do
  rm -rf "$work/report"
  start=$(date +%s.%N)
  "$bin" check "$work/submissions" --csv "$work/list.csv" --report "$work/report" \
    --gradescope --threads "$threads" >"$work/check.txt"
  end=$(date +%s.%N)
  printf 'measure-class: run %d: %d submissions of %s² on %s threads in %.2f s\n' \
    "$run" "$count" "$side" "$threads" "$(awk -v a="$start" -v b="$end" 'BEGIN { print b - a }')"
done
tail -n 1 "$work/check.txt"

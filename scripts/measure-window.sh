#!/usr/bin/env bash
# Measures the workbench's responsiveness in the real window, under Xvfb: starts the release
# binary on a SIDE × SIDE image (default 1024), waits for its sample target, then drags the
# "Light x" slider for a few seconds with xdotool (each step re-traces) and reports, from the
# app's per-frame log (RAYLAB_LOG_FRAMES):
#   - UI frame CPU time (egui + painting) while passes run: mean, max, frames of 20 ms or more,
#   - the interval between UI frames while dragging,
#   - the time from a change to its first image on screen (the preview) and in how many frames.
# Usage: scripts/measure-window.sh [SIDE]. Needs what scripts/install-display-tools.sh installs.
# The log and a screenshot taken mid-drag go to target/measure/.
set -euo pipefail
cd "$(dirname "$0")/.."
side=${1:-1024}
root=$(pwd)
out="$root/target/measure"
mkdir -p "$out"
cargo build --release --quiet
bin="$root/target/release/raylab"

# shellcheck source=scripts/xvfb-common.sh
source "$root/scripts/xvfb-common.sh"
start_xvfb measure-window 151 199 "$out"
display=$DISPLAY

# A settings file for a SIDE² image (eframe keeps its storage as RON: a map of strings).
rm -rf "$out/xdg"
mkdir -p "$out/xdg/data/raylab" "$out/xdg/runtime"
chmod 700 "$out/xdg/runtime"
cat >"$out/xdg/data/raylab/app.ron" <<EOF
{"raylab-workbench": "{\"version\": 1, \"settings\": {\"camera\": {\"width\": $side, \"height\": $side, \"focal_length\": $side}, \"samples_per_pixel\": 16}}"}
EOF
export XDG_DATA_HOME="$out/xdg/data" XDG_RUNTIME_DIR="$out/xdg/runtime"

log="$out/app.log"
RAYLAB_LOG_FRAMES=1 "$bin" >"$log" 2>&1 &
app_pid=$!
window=$(timeout 30 xdotool search --sync --onlyvisible --name '^raylab$' | head -n 1)
for _ in $(seq 600); do
  grep -Eq "samples=16 target=16 preview=false" "$log" && break
  sleep 0.1
done
grep -q "full_pass_ms" "$log" || { echo "measure-window: no frames logged" >&2; exit 1; }
echo "measure-window: $side² reached 16 samples; dragging the Light x slider"

# The Light x slider's handle (value 0 in -1.5..1.5) in the default layout.
xdotool mousemove --window "$window" 75 338
before=$(wc -l <"$log")
xdotool mousedown 1
for i in $(seq 0 40); do
  xdotool mousemove_relative -- 1 0
  sleep 0.05
done
xwd -root -display "$display" | /usr/bin/convert xwd:- "$out/mid-drag.png"
for i in $(seq 0 40); do
  xdotool mousemove_relative -- -1 0
  sleep 0.05
done
xdotool mouseup 1
# Let the last change render its first full pass.
sleep 2
after=$(wc -l <"$log")

tail -n +"$((before + 1))" "$log" | head -n "$((after - before))" | awk '
  function field(name,   i, kv) { for (i = 2; i <= NF; i++) { split($i, kv, "="); if (kv[1] == name) return kv[2] } }
  /^raylab-frame/ {
    cpu = field("frame_cpu_ms"); t = field("t_ms")
    if (cpu != "NaN") { n++; sum += cpu; if (cpu + 0 > max) max = cpu + 0; if (cpu + 0 >= 20) over++ }
    if (last_t != "") { gap = t - last_t; if (gap > maxgap) maxgap = gap; gaps += gap; ng++ }
    last_t = t
    ch = field("change_to_image_ms") " " field("change_frames")
    if (ch != prev_ch && field("change_to_image_ms") != "NaN") { nc++; cms += field("change_to_image_ms"); cf += field("change_frames"); if (field("change_frames") + 0 > maxcf) maxcf = field("change_frames") + 0; if (field("change_to_image_ms") + 0 > maxcms) maxcms = field("change_to_image_ms") + 0 }
    prev_ch = ch
    fp = field("full_pass_ms")
  }
  END {
    printf "measure-window: %d UI frames while dragging: CPU mean %.1f ms, max %.1f ms, %d of 20 ms or more\n", n, sum / n, max, over
    printf "measure-window: interval between frames: mean %.1f ms, max %.1f ms\n", gaps / ng, maxgap
    printf "measure-window: change to first image: %d changes, mean %.1f ms, max %.1f ms; mean %.2f frames, max %d\n", nc, cms / nc, maxcms, cf / nc, maxcf
    printf "measure-window: last full pass %.1f ms\n", fp
  }'
echo "measure-window: log $log, screenshot mid-drag $out/mid-drag.png"

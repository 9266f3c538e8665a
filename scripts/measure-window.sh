#!/usr/bin/env bash
# Measures the workbench in the real window, under Xvfb.
#
# scripts/measure-window.sh [SIDE]: responsiveness. Starts the release binary on a SIDE × SIDE
# image (default 1024), waits for its sample target, then drags the "Light x" slider for a few
# seconds with xdotool (each step re-traces) and reports, from the app's per-frame log
# (RAYLAB_LOG_FRAMES):
#   - UI frame CPU time (egui + painting) while passes run: mean, max, frames of 20 ms or more,
#   - the interval between UI frames while dragging,
#   - the time from a change to its first image on screen (the preview) and in how many frames.
# The log and a screenshot taken mid-drag go to target/measure/.
#
# scripts/measure-window.sh --throughput [SIDE] [THREADS] [RUNS]: the path stage's throughput in
# the window against `raylab bench --stage path`, at SIDE² (default 512) on THREADS render
# threads (default 2), RUNS times (default 3). Each run starts the window on the path stage
# with a sample target it will not reach, lets it accumulate for a few seconds, then measures
# samples per second from the frame log over a steady span (THROUGHPUT_SPAN seconds, default 8),
# with each thread's CPU use over that span. The benchmark runs at the same size and threads
# just before and just after the window (their mean is taken: the machine's load drifts); both
# are printed in camera paths per second, and their ratio (window / bench). The window's
# denoiser is on, as a student starts it; THROUGHPUT_DENOISE=off measures it off.
#
# scripts/measure-window.sh --clean [SIDE] [THREADS] [RUNS]: how long the path-traced box takes
# to look clean after a change. Starts the window on the path stage at SIDE² (default 512) with
# the denoiser on (the window's default), waits until it shows a denoised image, then clicks the
# "Light x" slider (one change, a new job) and reports from the frame log the time from the
# click to the first frame showing a denoised image of at least CLEAN_SAMPLES samples (default
# 16: PERFORMANCE.md's denoiser table gives their quality), RUNS times (default 3). With
# CLEAN_SLIDER=camera it clicks "Camera x" instead: a new view, whose denoiser features must be
# found anew.
#
# Needs what scripts/install-display-tools.sh installs. Honours CARGO_TARGET_DIR; RAYLAB_BIN
# names a binary to measure instead of building one (to compare two builds).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
target_dir=${CARGO_TARGET_DIR:-$root/target}
out="$target_dir/measure"
mkdir -p "$out"
mode=drag
if [ "${1:-}" = "--throughput" ]; then
  mode=throughput
  shift
elif [ "${1:-}" = "--clean" ]; then
  mode=clean
  shift
fi
if [ -n "${RAYLAB_BIN:-}" ]; then
  bin=$RAYLAB_BIN
else
  cargo build --release --quiet
  bin="$target_dir/release/raylab"
fi

# shellcheck source=scripts/xvfb-common.sh
source "$root/scripts/xvfb-common.sh"
start_xvfb measure-window 151 199 "$out"
display=$DISPLAY

# CPU ticks of each thread of process $1, one line each: "tid name ticks" (user + system).
thread_ticks() {
  local task stat
  for task in /proc/"$1"/task/*; do
    stat=$(cat "$task/stat" 2>/dev/null) || continue
    # Fields after the name (which is in parentheses): state is 3, utime 14, stime 15.
    set -- ${stat##*) }
    echo "${task##*/} $(cat "$task/comm" 2>/dev/null | tr ' ' _) $((${12} + ${13}))"
  done
}

# Starts the binary on settings of its own: WORKBENCH is the workbench's saved state as JSON (what
# eframe keeps in app.ron), LOG receives its frame log (RAYLAB_LOG_FRAMES). Waits for the window,
# then until a line of LOG matches PATTERN (at most a minute). Sets app_pid and window.
export XDG_DATA_HOME="$out/xdg/data" XDG_RUNTIME_DIR="$out/xdg/runtime"
start_app() {
  local workbench=$1 pattern=$3
  log=$2
  rm -rf "$out/xdg"
  mkdir -p "$out/xdg/data/raylab" "$out/xdg/runtime"
  chmod 700 "$out/xdg/runtime"
  printf '{"raylab-workbench": "%s"}\n' "${workbench//\"/\\\"}" >"$out/xdg/data/raylab/app.ron"
  RAYLAB_LOG_FRAMES=1 "$bin" >"$log" 2>&1 &
  app_pid=$!
  window=$(timeout 30 xdotool search --sync --onlyvisible --name '^raylab( |$)' | head -n 1)
  for _ in $(seq 600); do
    grep -Eq "$pattern" "$log" && break
    sleep 0.1
  done
}

# The path stage at SIDE² on THREADS render threads (as `bench --stage path` renders it: the
# default camera, unlimited bounces) with a sample target no run reaches; then any further
# fields of the workbench's state.
path_stage() {
  echo "{\"version\": 1, \"render_threads\": $2${3:-}, \"settings\": {\"camera\": {\"width\": $1, \"height\": $1, \"focal_length\": $1}, \"shading\": {\"stage\": \"path\", \"shadows\": true, \"indirect\": true}, \"samples_per_pixel\": 4096}}"
}

if [ "$mode" = throughput ]; then
  side=${1:-512}
  threads=${2:-2}
  runs=${3:-3}
  span=${THROUGHPUT_SPAN:-8}
  hz=$(getconf CLK_TCK)
  echo "measure-window: path stage, $side², $threads render threads, $runs runs of ${span} s;" \
    "$(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: //'), $(nproc) cores," \
    "load $(cut -d' ' -f1-3 /proc/loadavg)"
  # `raylab bench --stage path` at the same size and threads: camera paths per second.
  bench_paths() {
    "$bin" bench --stage path --scene cornell --width "$side" --height "$side" \
      --threads "$threads" --passes 20 --json | sed 's/.*"path_samples_per_s":\([0-9.e+]*\).*/\1/'
  }
  summary="$out/throughput.txt"
  : >"$summary"
  for run in $(seq "$runs"); do
    bench_before=$(bench_paths)
    denoise=true
    [ "${THROUGHPUT_DENOISE:-on}" = off ] && denoise=false
    start_app "$(path_stage "$side" "$threads" ", \"denoise\": $denoise")" "$out/throughput-$run.log" \
      "samples=[1-9][0-9]* target=[0-9]+ preview=false"
    grep -Eq "samples=[1-9]" "$log" || { echo "measure-window: no samples logged" >&2; exit 1; }
    # Past the start (the preview, the first passes, the window's first frames).
    sleep 2
    before=$(wc -l <"$log")
    ticks_before=$(thread_ticks "$app_pid")
    sleep "$span"
    ticks_after=$(thread_ticks "$app_pid")
    xwd -root -display "$display" | /usr/bin/convert xwd:- "$out/throughput-$run.png"
    after=$(wc -l <"$log")
    kill "$app_pid"
    wait "$app_pid" 2>/dev/null || true
    app_pid=""

    window=$(tail -n +"$((before + 1))" "$log" | head -n "$((after - before))" | awk -v side="$side" '
      function field(name,   i, kv) { for (i = 2; i <= NF; i++) { split($i, kv, "="); if (kv[1] == name) return kv[2] } }
      /^raylab-frame/ {
        n++; s = field("samples") + 0; t = field("t_ms") + 0
        if (n == 1) { s0 = s; t0 = t }
        s1 = s; t1 = t
      }
      END {
        if (t1 <= t0) { print "0 0 0"; exit }
        per_s = (s1 - s0) / ((t1 - t0) / 1e3)
        printf "%.3f %.0f %d\n", per_s, per_s * side * side, n
      }')
    read -r samples_per_s window_paths ui_frames <<<"$window"
    bench=$(awk -v a="$bench_before" -v b="$(bench_paths)" 'BEGIN { print (a + b) / 2 }')
    ratio=$(awk -v w="$window_paths" -v b="$bench" 'BEGIN { printf "%.3f", w / b }')
    printf "measure-window: run %d: window %.2f samples/s = %.2f M paths/s (%d UI frames in %d s);" \
      "$run" "$samples_per_s" "$(awk -v w="$window_paths" 'BEGIN { print w / 1e6 }')" "$ui_frames" "$span"
    printf " bench %.2f M paths/s (mean of before and after); ratio %.3f\n" "$(awk -v b="$bench" 'BEGIN { print b / 1e6 }')" "$ratio"
    # CPU share of each kind of thread over the span (% of one core), busiest first.
    join <(sort <<<"$ticks_before") <(sort <<<"$ticks_after") | awk -v hz="$hz" -v span="$span" '
      { name = $2; sub(/[-:]?[0-9]+$/, "", name); use[name] += ($5 - $3) / hz / span * 100 }
      END { for (n in use) if (use[n] >= 0.5) printf "%s %.0f%%\n", n, use[n] }' |
      sort -k2 -t' ' -rn | paste -sd, - | sed 's/,/, /g; s/^/measure-window:   CPU by thread: /'
    echo "$ratio $window_paths $bench" >>"$summary"
  done
  awk '{ r[NR] = $1; w[NR] = $2; b[NR] = $3 }
    END {
      rmin = rmax = r[1]; wmin = wmax = w[1]; bmin = bmax = b[1]
      for (i = 2; i <= NR; i++) {
        if (r[i] < rmin) rmin = r[i]; if (r[i] > rmax) rmax = r[i]
        if (w[i] < wmin) wmin = w[i]; if (w[i] > wmax) wmax = w[i]
        if (b[i] < bmin) bmin = b[i]; if (b[i] > bmax) bmax = b[i]
      }
      printf "measure-window: ratio window/bench %.3f to %.3f; window %.2f to %.2f M paths/s, bench %.2f to %.2f M paths/s\n", rmin, rmax, wmin / 1e6, wmax / 1e6, bmin / 1e6, bmax / 1e6
    }' "$summary"
  sort -n "$summary" | awk '{ r[NR] = $1 } END { printf "measure-window: median ratio %.3f of %d runs\n", NR % 2 ? r[(NR + 1) / 2] : (r[NR / 2] + r[NR / 2 + 1]) / 2, NR }'
  exit 0
fi

if [ "$mode" = clean ]; then
  side=${1:-512}
  threads=${2:-2}
  runs=${3:-3}
  wanted=${CLEAN_SAMPLES:-16}
  echo "measure-window: path stage, $side², $threads render threads, denoised at $wanted samples;" \
    "$(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: //'), $(nproc) cores," \
    "load $(cut -d' ' -f1-3 /proc/loadavg)"
  for run in $(seq "$runs"); do
    start_app "$(path_stage "$side" "$threads" ', "denoise": true')" "$out/clean-$run.log" \
      "denoised=[1-9]"
    grep -Eq "denoised=[1-9]" "$log" || { echo "measure-window: no denoised frame logged" >&2; exit 1; }
    sleep 1
    before=$(wc -l <"$log")
    # The Light x (or Camera x) slider's handle (its place with the Camera and Light sections
    # open, as they are on the path stage) dragged a little to the right: new jobs as it goes.
    slider_y=572
    [ "${CLEAN_SLIDER:-light}" = camera ] && slider_y=301
    xdotool mousemove --window "$window" 75 "$slider_y"
    sleep 0.3
    xdotool mousedown 1
    sleep 0.1
    for _ in 1 2 3 4; do
      xdotool mousemove_relative -- 5 0
      sleep 0.05
    done
    xdotool mouseup 1
    for _ in $(seq 200); do
      tail -n +"$((before + 1))" "$log" | awk -v w="$wanted" '
        /preview=true/ { changed = 1 }
        changed && match($0, /denoised=[0-9]+/) && substr($0, RSTART + 9, RLENGTH - 9) + 0 >= w { found = 1 }
        END { exit !found }' && break
      sleep 0.1
    done
    xwd -root -display "$display" | /usr/bin/convert xwd:- "$out/clean-$run.png"
    kill "$app_pid"
    wait "$app_pid" 2>/dev/null || true
    app_pid=""
    # The change: the frame before the drag's last preview; clean: the first frame after it
    # showing a denoised image of at least $wanted samples.
    tail -n +"$((before + 1))" "$log" | awk -v w="$wanted" -v run="$run" '
      function field(name,   i, kv) { for (i = 2; i <= NF; i++) { split($i, kv, "="); if (kv[1] == name) return kv[2] } }
      /^raylab-frame/ {
        t = field("t_ms") + 0
        # Each preview starts a job: the last one, the last step of the drag, is timed.
        if (field("preview") == "true" && !done) { changed = 1; t0 = last_t; n = 0 }
        last_t = t
        if (changed) n++
        if (changed && !done && field("denoised") + 0 >= w) {
          done = 1
          printf "measure-window: run %d: change to a denoised image of %d samples: %.0f ms (%d frames)\n", run, field("denoised"), t - t0, n
        }
      }
      END { if (!done) printf "measure-window: run %d: no denoised image of %d samples within 20 s\n", run, w }'
  done
  exit 0
fi

side=${1:-1024}

# The lab's stage on a SIDE² image, 16 samples.
start_app "{\"version\": 1, \"settings\": {\"camera\": {\"width\": $side, \"height\": $side, \"focal_length\": $side}, \"samples_per_pixel\": 16}}" \
  "$out/app.log" "samples=16 target=16 preview=false"
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

#!/usr/bin/env bash
# Smoke test of the real workbench window, on a machine with no display.
#
# Starts the release binary (or the one RAYLAB_BIN names: CI passes the test build's) under
# Xvfb (its own display number, a fresh settings folder), waits
# for the render to reach its sample target, takes a screenshot, presses the Up arrow with
# xdotool (camera forward), waits again, takes another, and checks that
#   - the render area shows the Cornell box (cyan ceiling, purple and yellow walls, green floor,
#     red and blue blocks), before and after, and
#   - the picture changed.
# Screenshots and the app's log go to target/smoke/. Exits non-zero on failure; always stops
# Xvfb and the app.
#
# Needs Xvfb, xdotool, xwd and ImageMagick: scripts/install-display-tools.sh installs them.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
out="$root/target/smoke"
mkdir -p "$out"

for tool in Xvfb xdotool xwd /usr/bin/convert /usr/bin/compare; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "smoke-window: $tool is missing: run scripts/install-display-tools.sh" >&2
    exit 2
  fi
done

if [ -n "${RAYLAB_BIN:-}" ]; then
  bin=$RAYLAB_BIN
else
  echo "smoke-window: cargo build --release"
  cargo build --release --quiet
  bin="${CARGO_TARGET_DIR:-$root/target}/release/raylab"
fi

# shellcheck source=scripts/xvfb-common.sh
source "$root/scripts/xvfb-common.sh"
start_xvfb smoke-window 91 150 "$out"
display=$DISPLAY

# A fresh settings folder: the app starts on the lab's defaults (figure 7, 512², 16 samples).
rm -rf "$out/xdg"
mkdir -p "$out/xdg/data" "$out/xdg/config" "$out/xdg/runtime"
chmod 700 "$out/xdg/runtime"
export XDG_DATA_HOME="$out/xdg/data" XDG_CONFIG_HOME="$out/xdg/config" XDG_RUNTIME_DIR="$out/xdg/runtime"

log="$out/app.log"
RAYLAB_LOG_FRAMES=1 "$bin" >"$log" 2>&1 &
app_pid=$!

window=$(timeout 30 xdotool search --sync --onlyvisible --name '^raylab( |$)' | head -n 1) || {
  echo "smoke-window: no window titled 'raylab' within 30 s; the app's log:" >&2
  tail -n 20 "$log" >&2
  exit 1
}
echo "smoke-window: window $window on $display"

# Waits until, after line $1 of the log, the app logs a frame still rendering (a preview or
# fewer samples than the target) and then one at its sample target.
wait_for_target() {
  local from=$1
  for _ in $(seq 600); do
    if tail -n +"$((from + 1))" "$log" | awk '
      /^raylab-frame/ {
        split($4, s, "="); split($5, t, "="); split($6, p, "=")
        final = (p[2] == "false" && t[2] > 0 && s[2] + 0 >= t[2] + 0)
        if (!final) busy = 1
        else if (busy) { found = 1; exit }
      }
      END { exit !found }'; then
      return 0
    fi
    kill -0 "$app_pid" 2>/dev/null || { echo "smoke-window: the app exited" >&2; tail -n 20 "$log" >&2; exit 1; }
    sleep 0.1
  done
  echo "smoke-window: the render did not reach its target within 60 s" >&2
  exit 1
}

shot() {
  xwd -root -display "$display" | /usr/bin/convert xwd:- "$1"
}

# Counts the Cornell box's colours in the render area (right of the side panel), on a 96×96
# downscale: prints "cyan purple yellow green red blue".
box_colours() {
  local geometry
  geometry=$(xdotool getwindowgeometry --shell "$window")
  local WIDTH HEIGHT X Y
  eval "$(echo "$geometry" | grep -E '^(WIDTH|HEIGHT|X|Y)=')"
  # The side panel is about 330 px wide; the status line about 30 px high.
  local x0=$((X + 360)) y0=$((Y + 10)) w=$((WIDTH - 370)) h=$((HEIGHT - 50))
  /usr/bin/convert "$1" -crop "${w}x${h}+${x0}+${y0}" +repage -scale '96x96!' -depth 8 txt:- |
    awk -F'[(),]' 'NR > 1 {
      r = $3 + 0; g = $4 + 0; b = $5 + 0
      if (r + g + b < 60) next
      if (g > 1.6 * r && b > 1.6 * r && g < 1.4 * b && b < 1.4 * g) cyan++
      else if (r > 1.6 * g && b > 1.6 * g && r < 1.4 * b && b < 1.4 * r) purple++
      else if (r > 1.6 * b && g > 1.6 * b && r < 1.4 * g && g < 1.4 * r) yellow++
      else if (g > 1.6 * r && g > 1.6 * b) green++
      else if (r > 1.6 * g && r > 1.6 * b) red++
      else if (b > 1.6 * r && b > 1.6 * g) blue++
    } END { printf "%d %d %d %d %d %d\n", cyan, purple, yellow, green, red, blue }'
}

check_box() {
  local counts
  read -r -a counts <<<"$(box_colours "$1")"
  echo "smoke-window: $1: cyan ${counts[0]}, purple ${counts[1]}, yellow ${counts[2]}, green ${counts[3]}, red ${counts[4]}, blue ${counts[5]} (of 9216 samples)"
  local names=(cyan purple yellow green red blue)
  for i in 0 1 2 3 4 5; do
    if [ "${counts[$i]}" -lt 40 ]; then
      echo "smoke-window: FAIL: little or no ${names[$i]} in the render area of $1" >&2
      exit 1
    fi
  done
}

wait_for_target 0
shot "$out/before.png"
check_box "$out/before.png"

lines=$(wc -l <"$log")
xdotool windowfocus --sync "$window"
xdotool key Up
wait_for_target "$lines"
shot "$out/after.png"
check_box "$out/after.png"

differing=$(/usr/bin/compare -metric AE "$out/before.png" "$out/after.png" null: 2>&1 || true)
differing=${differing%% *}
echo "smoke-window: $differing pixels differ after pressing Up"
if ! [ "${differing%.*}" -gt 1000 ] 2>/dev/null; then
  echo "smoke-window: FAIL: the picture did not change after pressing Up" >&2
  exit 1
fi

# The UI frame times the app logged (CPU time of each frame, including painting).
awk '/^raylab-frame/ { split($3, a, "="); if (a[2] != "NaN") { n++; s += a[2]; if (a[2] > m) m = a[2] } }
     END { if (n) printf "smoke-window: %d UI frames, mean %.1f ms, max %.1f ms CPU\n", n, s / n, m }' "$log"
echo "smoke-window: OK (screenshots: $out/before.png, $out/after.png)"

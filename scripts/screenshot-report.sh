#!/usr/bin/env bash
# The class report in a real browser: makes a class folder (the class_folder example: every
# mistake of the catalogue, right, anti-aliased and JPEG images, broken files, identical
# images), runs `raylab check FOLDER --csv LIST --report OUT --gradescope`, and has headless
# Chromium open the page from the file system:
#   - a screenshot of the page (FOLDER/page.png), of a student's detail view, shown by its
#     #d-ID fragment with no script (detail.png), of the page filtered to one verdict with no
#     script (filtered.png) and sorted by SSIM by its script (sorted.png), and
#   - the page's DOM after its script ran, which must show the sortable headings it marks.
# Exits non-zero if the report or a screenshot is missing, or the script did not run.
#
# Usage: scripts/screenshot-report.sh [FOLDER] (default target/class-report). RAYLAB_BIN names
# the binary (CI passes the test build's); SIDE the images' side (default 96).
# Needs Chromium: scripts/install-browser.sh installs it.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
work="${1:-$root/target/class-report}"
side="${SIDE:-96}"

browser=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$browser" ]; then
  echo "screenshot-report: chromium is missing: run scripts/install-browser.sh" >&2
  exit 2
fi
if [ -n "${RAYLAB_BIN:-}" ]; then
  bin=$RAYLAB_BIN
  profile=()
else
  echo "screenshot-report: cargo build --release"
  cargo build --release --quiet
  bin="${CARGO_TARGET_DIR:-$root/target}/release/raylab"
  profile=(--release)
fi

rm -rf "$work"
mkdir -p "$work"
cargo run --quiet "${profile[@]}" --example class_folder -- "$work" "$side"
report="$work/report"
"$bin" check "$work/submissions" --csv "$work/list.csv" --report "$report" --gradescope \
  >"$work/check.txt"
tail -n 1 "$work/check.txt"
for f in index.html report.csv report.json; do
  [ -s "$report/$f" ] || { echo "screenshot-report: $report/$f is missing" >&2; exit 1; }
done

profile_dir=$(mktemp -d)
trap 'rm -rf "$profile_dir"' EXIT
chrome() {
  "$browser" --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
    --disable-background-networking --disable-component-update --disable-sync \
    --user-data-dir="$profile_dir" "$@" 2>>"$work/chromium.log"
}
page="file://$report/index.html"
chrome --screenshot="$work/page.png" --window-size=1280,1600 "$page" >/dev/null
# A student whose mistake is named: their detail view.
id=$(grep -B1 -A1 '"file": "inverse-r.png"' "$report/report.json" | grep -o 's[0-9]\{3\}' | head -n 1)
chrome --screenshot="$work/detail.png" --window-size=1280,1000 "$page#d-$id" >/dev/null
# Filtering with no script: the page as it is once "inverse-r" is chosen (its radio button
# checked), a copy beside it so its links still hold.
sed -e 's/ id="show-all" checked>/ id="show-all">/' \
  -e 's/ id="show-inverse-r">/ id="show-inverse-r" checked>/' \
  "$report/index.html" >"$report/filtered.html"
chrome --screenshot="$work/filtered.png" --window-size=1280,1600 "file://$report/filtered.html" \
  >/dev/null
rm "$report/filtered.html"
# Sorting (the script): the page opened sorted by SSIM, least similar first.
chrome --screenshot="$work/sorted.png" --window-size=1280,1600 "$page#sort-ssim" >/dev/null
for shot in page.png detail.png filtered.png sorted.png; do
  if [ "$(stat -c %s "$work/$shot" 2>/dev/null || echo 0)" -lt 10000 ]; then
    echo "screenshot-report: $work/$shot is missing or blank" >&2
    exit 1
  fi
done
sortable=$(chrome --dump-dom "$page" | grep -o 'tabindex="0"' | wc -l)
if [ "$sortable" -lt 4 ]; then
  echo "screenshot-report: the page's script did not run (${sortable} sortable headings)" >&2
  exit 1
fi
echo "screenshot-report: $work/{page,detail,filtered,sorted}.png ($sortable sortable headings)"

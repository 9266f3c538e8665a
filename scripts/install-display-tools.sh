#!/usr/bin/env bash
# Installs what the window smoke test (scripts/smoke-window.sh) needs on a Debian/Ubuntu machine
# with no display: an X server in memory (Xvfb), xdotool (keys and focus), xwd (x11-apps, window
# screenshots), ImageMagick (xwd → PNG, colour checks) and Mesa's software OpenGL (llvmpipe) for
# eframe's glow renderer. Says what it installs; installs nothing that is already there.
set -euo pipefail

packages=()
need() { # need COMMAND-OR-FILE PACKAGE
  if [[ "$1" == /* ]]; then
    [ -e "$1" ] || packages+=("$2")
  else
    command -v "$1" >/dev/null 2>&1 || packages+=("$2")
  fi
}
need Xvfb xvfb
need xdotool xdotool
need xwd x11-apps
need /usr/bin/convert imagemagick
# Mesa: the DRI drivers (llvmpipe), libGL and libEGL. Checked by package, since the libraries'
# paths differ between architectures.
for p in libgl1-mesa-dri libgl1 libegl1; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || packages+=("$p")
done

if [ ${#packages[@]} -eq 0 ]; then
  echo "install-display-tools: everything is already installed"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  SUDO="sudo"
fi
echo "install-display-tools: installing with apt-get: ${packages[*]}"
$SUDO apt-get update
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends "${packages[@]}"
echo "install-display-tools: installed ${packages[*]}"

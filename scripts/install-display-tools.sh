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

# shellcheck source=apt-install.sh
. "$(dirname "$0")/apt-install.sh"
apt_install install-display-tools "${packages[@]}"

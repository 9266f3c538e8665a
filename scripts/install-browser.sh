#!/usr/bin/env bash
# Installs Debian's Chromium, which scripts/screenshot-report.sh runs headless to open the class
# report's page (`raylab check FOLDER --report OUT`) and take a screenshot of it, and the DejaVu
# fonts it draws the page's text with. Says what it installs; installs nothing already there.
set -euo pipefail

packages=()
command -v chromium >/dev/null 2>&1 || packages+=(chromium)
dpkg-query -W -f='${Status}' fonts-dejavu-core 2>/dev/null | grep -q "install ok installed" ||
  packages+=(fonts-dejavu-core)

# shellcheck source=apt-install.sh
. "$(dirname "$0")/apt-install.sh"
apt_install install-browser "${packages[@]}"

#!/usr/bin/env bash
# Installs Debian's Chromium, which scripts/screenshot-report.sh runs headless to open the class
# report's page (`raylab check FOLDER --report OUT`) and take a screenshot of it, and the DejaVu
# fonts it draws the page's text with. Says what it installs; installs nothing already there.
set -euo pipefail

packages=()
command -v chromium >/dev/null 2>&1 || packages+=(chromium)
dpkg-query -W -f='${Status}' fonts-dejavu-core 2>/dev/null | grep -q "install ok installed" ||
  packages+=(fonts-dejavu-core)

if [ ${#packages[@]} -eq 0 ]; then
  echo "install-browser: everything is already installed"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  SUDO="sudo"
fi
echo "install-browser: installing with apt-get: ${packages[*]}"
$SUDO apt-get update
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends "${packages[@]}"
echo "install-browser: installed ${packages[*]}"

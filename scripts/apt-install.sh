# Sourced by the install scripts: `apt_install NAME PACKAGE...` installs the packages named
# (none: says everything is there), with sudo when not root, saying what it does as NAME.
apt_install() {
  local name=$1
  shift
  if [ $# -eq 0 ]; then
    echo "$name: everything is already installed"
    return 0
  fi
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    sudo="sudo"
  fi
  echo "$name: installing with apt-get: $*"
  $sudo apt-get update
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y --no-install-recommends "$@"
  echo "$name: installed $*"
}

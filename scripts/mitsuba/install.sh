#!/usr/bin/env bash
# Installs Mitsuba 3 (pip: mitsuba, drjit; numpy for the scripts) and the LLVM library that its
# llvm_ad_rgb variant needs (Debian: libllvm19). Safe to run again: each step is skipped when done.
# apt-get runs only as root; otherwise the script says what to install.
set -euo pipefail

LIBLLVM=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1
PY=${PYTHON:-python3}

if [ ! -e "$LIBLLVM" ]; then
    if [ "$(id -u)" = 0 ]; then
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libllvm19
    else
        echo "install.sh: $LIBLLVM missing; as root: apt-get install libllvm19" >&2
        exit 1
    fi
fi

if ! "$PY" -c "import mitsuba, drjit, numpy" 2>/dev/null; then
    "$PY" -m pip install --quiet mitsuba numpy
fi

DRJIT_LIBLLVM_PATH=$LIBLLVM "$PY" -c "
import mitsuba as mi
mi.set_variant('llvm_ad_rgb')
print('mitsuba', mi.__version__, 'llvm_ad_rgb ready')"

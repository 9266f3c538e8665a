#!/usr/bin/env bash
# Installs what the fuzz targets (FUZZING.md) need: cargo-fuzz, which drives libFuzzer, and the
# nightly toolchain it builds with (-Z sanitizer flags are nightly-only). Says what it installs;
# installs nothing that is already there, so it is safe to run again.
set -euo pipefail

if rustup toolchain list | grep -q '^nightly'; then
  echo "install-fuzz: the nightly toolchain is already installed"
else
  echo "install-fuzz: installing the nightly toolchain (rustup toolchain install nightly)"
  rustup toolchain install nightly --profile minimal
fi

if cargo fuzz --version >/dev/null 2>&1; then
  echo "install-fuzz: $(cargo fuzz --version) is already installed"
else
  echo "install-fuzz: installing cargo-fuzz (cargo install cargo-fuzz --locked; a few minutes)"
  cargo install cargo-fuzz --locked
fi

#!/usr/bin/env bash
# Installs what luxtally needs to build and test, when it is missing: Debian's Embree 3,
# libclang (for bindgen) and chromium (tests/report_browser.rs opens report.html in it,
# headless). Safe to run again; does nothing when all is there.
set -euo pipefail
missing=()
[ -e /usr/include/embree3/rtcore.h ] || [ -e /usr/include/embree4/rtcore.h ] || missing+=(libembree-dev)
ls /usr/lib/llvm-*/lib/libclang*.so* >/dev/null 2>&1 || ls /usr/lib/x86_64-linux-gnu/libclang*.so* >/dev/null 2>&1 || missing+=(libclang-dev)
command -v pkg-config >/dev/null 2>&1 || missing+=(pkg-config)
command -v cc >/dev/null 2>&1 || missing+=(build-essential)
[ -x /usr/bin/chromium ] || missing+=(chromium)
if [ ${#missing[@]} -gt 0 ]; then
  echo "luxtally setup: installing ${missing[*]}" >&2
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}" >/dev/null
fi
if ! command -v cargo >/dev/null 2>&1; then
  echo "luxtally setup: cargo not found: install Rust (https://rustup.rs), then run this again" >&2
  exit 1
fi

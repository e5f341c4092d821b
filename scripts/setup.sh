#!/usr/bin/env bash
# Installs the Debian packages luxtally needs to build, test and run the README's commands,
# when they are missing: build-essential and pkg-config, libclang-dev (bindgen loads
# libclang), libembree-dev (Embree 3), chromium (tests/report_browser.rs opens report.html
# in it, headless), OpenMPI (openmpi-bin, libopenmpi-dev), and python3-venv and
# python3-dev (scripts/test.sh builds the Python package into a virtual environment:
# Debian 12 refuses system-wide `pip install`; pyo3 links libpython).
#
# What is missing is decided from dpkg's package state (`dpkg-query -W`), never from files
# on disk: a libclang-cpp14 pulled in by another package is not libclang-dev. Only the
# missing packages are installed, after one `apt-get update`; as root directly, else
# through sudo; without either it stops with the apt-get command to run as root.
# Safe to run again: does nothing when everything is installed.
set -euo pipefail

packages=(build-essential pkg-config libclang-dev libembree-dev chromium openmpi-bin libopenmpi-dev
  python3-venv python3-dev)

# True when dpkg reports PACKAGE as installed (status "install ok installed", or
# "hold ok installed"); a removed package with its configuration left is not.
installed() {
  local status
  status=$(dpkg-query -W -f='${Status}' "$1" 2>/dev/null) || return 1
  [ "${status##* }" = installed ]
}

if ! command -v dpkg-query >/dev/null 2>&1; then
  echo "luxtally setup: dpkg-query not found (not Debian?): not checking system packages;" \
    "the build needs Embree 3, libclang, pkg-config and a C compiler" >&2
else
  missing=()
  for p in "${packages[@]}"; do
    installed "$p" || missing+=("$p")
  done
  if [ ${#missing[@]} -gt 0 ]; then
    # Debconf asks no questions; sudo is told so explicitly (it resets the environment).
    export DEBIAN_FRONTEND=noninteractive
    if [ "$(id -u)" -eq 0 ]; then
      as_root=()
    elif command -v sudo >/dev/null 2>&1; then
      as_root=(sudo DEBIAN_FRONTEND=noninteractive)
    else
      echo "luxtally setup: missing ${missing[*]}, and not root and no sudo: as root, run" \
        "\`apt-get update && apt-get install -y ${missing[*]}\`, then run this again" >&2
      exit 1
    fi
    echo "luxtally setup: installing ${missing[*]}" >&2
    "${as_root[@]}" apt-get update -qq
    "${as_root[@]}" apt-get install -y -qq "${missing[@]}" >/dev/null
  fi
fi

if ! command -v cargo >/dev/null 2>&1; then
  echo "luxtally setup: cargo not found: install Rust (https://rustup.rs), then run this again" >&2
  exit 1
fi

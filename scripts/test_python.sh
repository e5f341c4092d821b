#!/usr/bin/env bash
# The Python package's step of scripts/test.sh (docs/python.md): a virtual environment
# under target/py-venv (Debian 12 refuses system-wide pip installs), maturin and pytest
# from the Python registry, the package built into it with the obvhs backend, then its
# lints and the pytest suite (whose parity tests run the release CLI on the same
# scenes). A missing Python toolchain fails here, loudly: never "0 tests".
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
venv="$root/target/py-venv"

if ! command -v python3 >/dev/null 2>&1; then
  echo "luxtally test: python3 not found: run scripts/setup.sh (python3-venv, python3-dev)" >&2
  exit 1
fi
if ! python3 -c 'import venv, ensurepip' >/dev/null 2>&1; then
  echo "luxtally test: python3 has no venv/ensurepip: install python3-venv (scripts/setup.sh)" >&2
  exit 1
fi
if ! python3 -c 'import sysconfig, os, sys; h = sysconfig.get_paths()["include"]; sys.exit(not os.path.exists(os.path.join(h, "Python.h")))'; then
  echo "luxtally test: Python.h not found: install python3-dev (scripts/setup.sh)" >&2
  exit 1
fi
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check \
  "maturin>=1.16,<2" "pytest>=8" numpy

# The CLI the parity tests compare with, with the obvhs backend as the package has it.
cargo build --release --features obvhs --bin luxtally
# One target directory with the engine's build: the dependencies compile once.
export CARGO_TARGET_DIR="$root/target"
(
  cd python
  if cargo clippy --version >/dev/null 2>&1; then
    cargo clippy --release --features obvhs -- -D warnings
  fi
  if cargo fmt --version >/dev/null 2>&1; then
    cargo fmt --check
  fi
  VIRTUAL_ENV="$venv" PATH="$venv/bin:$PATH" maturin develop --release --features obvhs --quiet
)
# -p no:cacheprovider: nothing written into the source tree. pytest exits non-zero on
# a failure and also when it collects no test.
"$venv/bin/python" -m pytest -p no:cacheprovider python/tests

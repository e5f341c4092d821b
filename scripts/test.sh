#!/usr/bin/env bash
# Runs clippy and rustfmt, then every test: with the Embree backend alone, then with the
# obvhs backend as well (backend parity), then the Python package's build and pytest
# suite (scripts/test_python.sh), then the MPI test (feature mpi). Tests are
# built optimised ([profile.test]) so physics tests can use real photon counts.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
# Lints and formatting first: a minute, and they fail fast. A toolchain without clippy or
# rustfmt (they come with rustup's default profile) skips them and says so.
if cargo clippy --version >/dev/null 2>&1; then
  cargo clippy --release --all-targets --features obvhs -- -D warnings
else
  echo "cargo clippy is not installed: lints skipped"
fi
if cargo fmt --version >/dev/null 2>&1; then
  cargo fmt --check
else
  echo "rustfmt is not installed: formatting check skipped"
fi
cargo test --release
cargo test --release --features obvhs
# The Python package (docs/python.md): a venv, maturin, the extension, pytest.
scripts/test_python.sh
# MPI (docs/distributed.md): two ranks bit-identical to one process.
cargo test --release --features mpi --test mpi

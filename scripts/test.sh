#!/usr/bin/env bash
# Runs every test: with the Embree backend alone, then with the obvhs backend as well
# (backend parity). Tests are built optimised ([profile.test]) so physics tests can use
# real photon counts.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cargo test --release
cargo test --release --features obvhs

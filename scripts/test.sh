#!/usr/bin/env bash
# Runs every test: with the Embree backend alone, then with the obvhs backend as well
# (backend parity), then the MPI test (feature mpi). Tests are built optimised ([profile.test]) so physics tests can use
# real photon counts.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cargo test --release
cargo test --release --features obvhs
# MPI (docs/distributed.md): two ranks bit-identical to one process.
cargo test --release --features mpi --test mpi

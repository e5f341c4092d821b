#!/usr/bin/env bash
# Builds luxtally and runs the bundled default scene (scenes/office.toml) into out/office/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cargo run --release -- run scenes/office.toml "$@"

#!/usr/bin/env bash
# A year of daylight on the bundled daylit office (600 cells, Reinhart MF:2 sky, MF:6
# sun bins, Golden CO TMY3) until its sDA interval is within ±2 % of the area: wall
# time, the set-up of the sky matrix, photons, rays and peak memory (BENCHMARKS.md,
# "Annual daylight"). Usage: benches/annual.sh [extra `luxtally annual` flags]
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --features obvhs --quiet
out="${TMPDIR:-/tmp}/luxtally-bench-annual"
rm -rf "$out"
echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
run=(target/release/luxtally annual scenes/daylit_office_annual.toml --out "$out" "$@")
if [ -x /usr/bin/time ]; then
    /usr/bin/time -f "wall %e s, peak RSS %M kB" "${run[@]}"
else
    echo "(no /usr/bin/time, Debian's package \`time\`: no peak memory)"
    time "${run[@]}"
fi
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"

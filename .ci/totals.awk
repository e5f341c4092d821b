# The one closing line of .ci/run: the totals of every test binary and pytest session
# in scripts/test.sh's log (tests/suite/project/ci_totals.rs checks it on sample logs).
#
# Cargo: every binary (the one-binary suite, the few of their own, the doc tests) starts
# with "running N tests" and ends with its "test result:" line. pytest: a session says
# "collected N items" and ends with "=== 3 failed, 50 passed, 1 skipped in 9.1s ===".
# Tests that start but count in no result line (a binary aborted by a signal in one
# test, a pytest session killed) are shown as unreported, never dropped.
/^running [0-9]+ tests?$/ { n += $2 }
/^collected [0-9]+ items?/ { n += $2 }
/^test result:/ {
  for (i = 1; i <= NF; i++) {
    if ($(i+1) ~ /^passed/) p += $i
    if ($(i+1) ~ /^failed/) f += $i
    if ($(i+1) ~ /^ignored/) s += $i
  }
}
/^=+ .* in [0-9.]+s( \([^)]*\))? =+$/ {
  line = $0
  gsub(/^=+ | in [0-9.]+s( \([^)]*\))? =+$/, "", line)
  count = split(line, parts, ", ")
  for (k = 1; k <= count; k++) {
    split(parts[k], w, " ")
    if (w[2] ~ /^(passed|xpassed)$/) p += w[1]
    if (w[2] ~ /^(failed|errors?)$/) f += w[1]
    if (w[2] ~ /^(skipped|xfailed)$/) s += w[1]
  }
}
END {
  printf "totals: %d passed, %d failed, %d skipped", p, f, s
  if (n > p + f + s) printf ", %d unreported (a test binary or pytest session ended without its result)", n - p - f - s
  printf "\n"
}

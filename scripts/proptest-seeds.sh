#!/usr/bin/env bash
# Runs every test target that holds a property test (proptest) once per seed FIRST..=LAST: the
# unit tests of both workspace members (viscobar and the certificate) and the tests/ files.
# `cargo test` draws from the fixed seed of .cargo/config.toml; this explores the others.
# A failing case is reported with its seed and saved by proptest under proptest-regressions/
# (commit that file: its cases are replayed before the seeded ones).
# Usage: bash scripts/proptest-seeds.sh FIRST LAST     e.g. bash scripts/proptest-seeds.sh 1 100
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -ne 2 ] || ! [[ "$1" =~ ^[0-9]+$ && "$2" =~ ^[0-9]+$ ]]; then
  echo "usage: bash scripts/proptest-seeds.sh FIRST LAST (two seeds, u64)" >&2
  exit 2
fi
targets=(--workspace --lib)
for f in tests/*.rs; do
  if grep -q 'proptest!\|proptest::test_runner' "$f"; then
    targets+=(--test "$(basename "$f" .rs)")
  fi
done
log=$(mktemp)
trap 'rm -f "$log"' EXIT
if ! cargo test --release --no-run "${targets[@]}" >"$log" 2>&1; then
  cat "$log" >&2
  exit 1
fi
failed=()
for seed in $(seq "$1" "$2"); do
  if ! PROPTEST_RNG_SEED="$seed" cargo test --release -q "${targets[@]}" >"$log" 2>&1; then
    echo "seed $seed: FAILED"
    grep -E 'panicked|minimal failing input' "$log" | head -n 6
    failed+=("$seed")
  else
    echo "seed $seed: ok"
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "failing seeds: ${failed[*]}" >&2
  exit 1
fi
echo "all seeds $1..=$2 passed"

#!/usr/bin/env bash
# Measures every bar group in one sitting (run it on a quiet machine) and writes the
# generated blocks of README.md and benches/README.md (benches/README.md, "Running").
set -euo pipefail
cd "$(dirname "$0")/.."
cargo bench --features npy --bench step -- --warm-up-time 0.5 --measurement-time 2 "step/(unconstrained|unconstrained-bare|exact-one-end|exact-two-ends)/(100|1000|10000|100000|1000000)$"
cargo bench --features npy --bench step -- --warm-up-time 0.5 --measurement-time 2 "step/(distributed-exact|distributed-exact-dt10dx)/"
cargo bench --features npy --bench step -- --warm-up-time 0.5 --measurement-time 2 "^load/"
cargo bench --features npy --bench scenes -- --warm-up-time 0.5 --measurement-time 3 "^setup/"
cargo bench --features npy --bench scenes -- --warm-up-time 0.3 --measurement-time 2 "^scenes/"
cargo run --release -p viscobar-certificate -- bench-table --update README.md benches/README.md

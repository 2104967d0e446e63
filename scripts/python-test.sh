#!/usr/bin/env bash
# The Python package's tests: a virtual environment in target/venv (made when missing), the
# package built by maturin and installed from ./python, then its pytest suite, which compares
# with the command line's files (target/release/viscobar, built here when out of date).
# Packages come from PyPI: maturin, pytest, numpy, dask[distributed], matplotlib.
set -euo pipefail
cd "$(dirname "$0")/.."

venv=target/venv
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
fi
py="$venv/bin/python"
"$py" -m pip install --quiet --disable-pip-version-check \
  'maturin>=1.9.4,<2' pytest numpy 'dask[distributed]' matplotlib
# maturin is in the environment already (its PEP 517 hook calls it from PATH): no isolated
# build environment to fetch it into.
export PATH="$PWD/$venv/bin:$PATH"
"$py" -m pip install --quiet --disable-pip-version-check --no-build-isolation ./python
cargo build --release --quiet
VISCOBAR_CLI="$PWD/target/release/viscobar" MPLBACKEND=Agg "$py" -m pytest python/tests -q "$@"

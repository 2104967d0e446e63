#!/usr/bin/env bash
# Installs what the build needs beyond the Rust toolchain: cmake, for osqp-sys (the OSQP C
# sources bundled in the `osqp` crate are built with cmake). Idempotent: does nothing when
# `cmake` is already on PATH. Tries Debian's package first (as root, or with sudo when there is
# one), then PyPI's `cmake<4` (cmake 4 needs CMAKE_POLICY_VERSION_MINIMUM, which
# .cargo/config.toml sets anyway).
set -euo pipefail

if command -v cmake >/dev/null 2>&1; then
  exit 0
fi

echo "setup: cmake not found; installing it" >&2

as_root() {
  if [ "$(id -u)" -eq 0 ]; then
    "$@"
  elif command -v sudo >/dev/null 2>&1; then
    sudo -n "$@"
  else
    return 1
  fi
}

if command -v apt-get >/dev/null 2>&1; then
  if as_root apt-get update -qq &&
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends cmake >/dev/null; then
    hash -r
  fi
fi

if ! command -v cmake >/dev/null 2>&1; then
  echo "setup: apt could not install cmake; trying pip" >&2
  py=$(command -v python3 || command -v python || true)
  if [ -z "$py" ]; then
    echo "setup: neither apt nor python is available; install cmake (>= 3.5) by hand" >&2
    exit 1
  fi
  "$py" -m pip install --quiet 'cmake<4'
  hash -r
  # pyenv-style installs may need their shims refreshed before the new script is on PATH.
  if command -v pyenv >/dev/null 2>&1; then
    pyenv rehash || true
  fi
fi

if ! command -v cmake >/dev/null 2>&1; then
  echo "setup: cmake was installed but is not on PATH; add it to PATH and retry" >&2
  exit 1
fi
echo "setup: $(cmake --version | head -n 1)" >&2

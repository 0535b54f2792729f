#!/usr/bin/env bash
# The whole test suite on lavapipe with the Khronos validation layer on (every GPU test
# enables it and fails on any validation error).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/setup.sh
# Mitsuba 3 from PyPI (tests/mitsuba.rs cross-checks the CPU reference against it), in a
# virtual environment under target/ (pinned; reinstalled only when missing).
venv=target/mitsuba-venv
if ! "$venv/bin/python" -c "import mitsuba" >/dev/null 2>&1; then
  if ! python3 -m venv --help >/dev/null 2>&1 || ! python3 -c "import ensurepip" >/dev/null 2>&1; then
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends python3 python3-venv >/dev/null
  fi
  rm -rf "$venv"
  mkdir -p target
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q "mitsuba==3.9.1"
fi
export SPECULA_DEVICE="${SPECULA_DEVICE:-llvmpipe}"
# Not incremental: a fresh clone compiles everything once, and the incremental cache only
# costs time then (the library: 137 s instead of 153 on 2 cores).
export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-0}"
cargo test --locked --all-targets "$@"

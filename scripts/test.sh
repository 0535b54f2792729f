#!/usr/bin/env bash
# The whole test suite on lavapipe with the Khronos validation layer on (every GPU test
# enables it and fails on any validation error).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/setup.sh
export SPECULA_DEVICE="${SPECULA_DEVICE:-llvmpipe}"
cargo test --locked --all-targets "$@"

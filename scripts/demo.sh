#!/usr/bin/env bash
# The main job: renders the bundled demo scene with auto and every method into out/ (PNG + EXR
# per method, Chrome traces) and prints the per-pass timing table (also out/timings.txt).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/setup.sh
cargo build --release --locked
./target/release/specula demo out --size 512x512 "$@"

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
# setup.sh installed Xvfb: the viewer's test must run here, not skip.
export SPECULA_REQUIRE_VIEWER="${SPECULA_REQUIRE_VIEWER:-1}"
# Not incremental: a fresh clone compiles everything once, and the incremental cache only
# costs time then (the library: 137 s instead of 153 on 2 cores).
export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-0}"
if [ $# -gt 0 ]; then
  # A selection (`bash scripts/test.sh --test planner`): cargo runs it as usual.
  exec cargo test --locked --all-targets "$@"
fi
# The whole suite: cargo builds every test binary, then two run at a time. `cargo test`
# runs binaries one after another, and one binary's tests leave a core idle for much of the
# run (the GPU is lavapipe on the same two cores; measured: 1.47 cores busy over the suite).
# The binaries that compare measured frame times between methods run alone, afterwards.
cargo test --locked --all-targets --no-run --message-format=json-render-diagnostics >target/test-binaries.json
mapfile -t binaries < <(grep -E '"profile":\{[^}]*"test":true\}' target/test-binaries.json | grep -o '"executable":"[^"]*"' | sed 's/"executable":"//; s/"$//')
alone=(planner per_object curved budget niches)
# The longest first, so that the two lanes end together.
first=(c_abi c_abi_leaks caustics aa frames tradeoff_cli golden geometry raytrace_conformance showcase distance)
name() { basename "$1" | sed 's/-[0-9a-f]*$//'; }
ordered=() serial=()
for f in "${first[@]}"; do
  for b in "${binaries[@]}"; do [ "$(name "$b")" = "$f" ] && ordered+=("$b"); done
done
for b in "${binaries[@]}"; do
  n=$(name "$b")
  if printf '%s\n' "${alone[@]}" | grep -qx "$n"; then serial+=("$b")
  elif ! printf '%s\n' "${first[@]}" | grep -qx "$n"; then ordered+=("$b"); fi
done
export TEST_LOGS=target/test-logs
rm -rf "$TEST_LOGS" && mkdir -p "$TEST_LOGS"
# One binary: its output to a log, a line when it ends, the whole log if it failed.
run_one() {
  local b=$1 log start
  log=$TEST_LOGS/$(basename "$b").log
  start=$(date +%s)
  if "$b" >"$log" 2>&1; then
    echo "ok     $(basename "$b") ($(($(date +%s) - start)) s): $(grep -h '^test result' "$log" | tail -1)"
  else
    echo "FAILED $(basename "$b") ($(($(date +%s) - start)) s):"
    cat "$log"
    return 1
  fi
}
export -f run_one
status=0
printf '%s\n' "${ordered[@]}" | xargs -P 2 -I{} bash -c 'run_one "$1"' _ {} || status=1
for b in "${serial[@]}"; do run_one "$b" || status=1; done
[ "$status" = 0 ] && echo "every test binary passed (${#binaries[@]})" || echo "some test binary failed: see above"
exit "$status"

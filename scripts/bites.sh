#!/usr/bin/env bash
# Do the tests bite? Applies each consistent physics bug in scripts/bites/*.patch (the same
# mistake in src/optics.rs and its GLSL twin glsl/common/optics.glsl, so every GPU-vs-CPU
# conformance test still agrees with itself), runs the tests, lists the tests that failed,
# and reverts the bug. A bug that no test catches is reported as such and makes the script
# exit 1.
#
#   bash scripts/bites.sh                         # the whole suite per bug
#   bash scripts/bites.sh --test physics_anchors  # only these test targets (cargo test args)
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/setup.sh
export SPECULA_DEVICE="${SPECULA_DEVICE:-llvmpipe}"
if [ $# -eq 0 ]; then set -- --all-targets; fi
if ! git diff --quiet -- src/optics.rs glsl/common/optics.glsl; then
  echo "src/optics.rs or glsl/common/optics.glsl has uncommitted changes: commit or stash them first" >&2
  exit 2
fi
out=target/bites
mkdir -p "$out"
status=0
summary=""
for patch in scripts/bites/*.patch; do
  name=$(basename "$patch" .patch)
  git apply "$patch"
  trap 'git apply -R "'"$patch"'" 2>/dev/null || true' EXIT
  set +e
  cargo test --locked --no-fail-fast "$@" >"$out/$name.log" 2>&1
  set -e
  git apply -R "$patch"
  trap - EXIT
  caught=$(grep -E '^test .* \.\.\. FAILED$' "$out/$name.log" | sed -E 's/^test (.*) \.\.\. FAILED$/\1/' | sort -u || true)
  targets=$(grep -E '^error: test failed, to rerun pass `' "$out/$name.log" | sed -E 's/.*`(.*)`.*/\1/' | sort -u | tr '\n' ' ' || true)
  n=$(printf '%s' "$caught" | grep -c . || true)
  if [ "$n" -eq 0 ]; then
    status=1
    summary+="$name: NOT CAUGHT (log: $out/$name.log)"$'\n'
  else
    summary+="$name: caught by $n test(s) in ${targets:-?}"$'\n'
    summary+=$(printf '%s\n' "$caught" | sed 's/^/    /')$'\n'
  fi
done
printf '%s' "$summary" | tee "$out/summary.txt"
exit $status

#!/usr/bin/env bash
# Planar mirrors by geometry transformation (survey §5), measured with the CLI on the
# mirror scene (assets/mirrors/mirrors.gltf: two facing mirror panels, the corridor):
#   1. the cost of each recursion level: depth 1..8 (mirror_budget 64), GPU frame ms, the
#      views rendered and the mirrored views' share of the frame, PSNR and mean FLIP against
#      the reference at the same depth (their floor is the shared terms: shadow maps against
#      exact shadows, the light's blown-out spot on the ceiling, the sphere's distance map);
#   2. the budget: mirror_budget 0, 1, 2, 4, 8 at depth 16, against planar-mirror with no
#      budget limit (isolating the fallback's error: mirrors beyond the budget show the
#      environment, black in this closed room) and against the depth-16 reference.
# `--method planar-mirror` for the whole scene: the mirror sphere falls back to distance
# maps (its error is in every row alike).
# Usage: scripts/bench-mirrors.sh [OUTDIR] [SIZE]   (needs cargo build --release)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-bench-mirrors}
size=${2:-512x512}
mkdir -p "$out"
. scripts/bench-lib.sh
scene=assets/mirrors/mirrors.gltf
# The frame's stats line (the memory table has a row of the same name, in MiB).
views_of() { awk '/^geometry.mirror_views / {v=$2} END {printf "%d", v}'; }
errors() { $bin compare "$1" "$2" | awk '/^PSNR/ {p=$2} /^mean FLIP/ {f=$3} END {printf "%s dB | %.4f", p, f}'; }
share() { awk '/^geometry.mirror_view( ×[0-9]+)? +[0-9.]+ +[0-9.]+$/ {v+=$(NF-1)} /^frame +[0-9.]+ +[0-9.]+$/ {f=$2} END {if (f > 0) printf "%.0f %%", 100 * v / f; else print "-"}'; }

echo "## Recursion depth, $size, mirror_budget=64: GPU ms per frame"
echo "| depth | views | frame ms | mirrored views' share | PSNR vs reference (same depth) | mean FLIP |"
echo "|---:|---:|---:|---:|---:|---:|"
for d in 1 2 3 4 5 6 7 8; do
  $bin render $scene --method reference --size "$size" -q depth=$d -q spp=1 --out "$out/ref_d$d.exr" > /dev/null
  log=$($bin render $scene --method planar-mirror --size "$size" -q depth=$d -q mirror_budget=64 --warmup 1 --frames 3 --out "$out/pm_d$d.exr")
  echo "| $d | $(views_of <<< "$log") | $(frame_ms <<< "$log") | $(share <<< "$log") | $(errors "$out/pm_d$d.exr" "$out/ref_d$d.exr") |"
done

echo
echo "## mirror_budget at depth 16, $size: GPU ms, error against no budget limit and against the depth-16 reference"
$bin render $scene --method reference --size "$size" -q depth=16 -q spp=1 --out "$out/ref_d16.exr" > /dev/null
$bin render $scene --method planar-mirror --size "$size" -q depth=16 -q mirror_budget=64 --out "$out/pm_b64.exr" > /dev/null
echo "| mirror_budget | views | frame ms | PSNR vs no limit | mean FLIP vs no limit | PSNR vs reference | mean FLIP vs reference |"
echo "|---:|---:|---:|---:|---:|---:|---:|"
for b in 0 1 2 4 8; do
  log=$($bin render $scene --method planar-mirror --size "$size" -q depth=16 -q mirror_budget=$b --warmup 1 --frames 3 --out "$out/pm_b$b.exr")
  echo "| $b | $(views_of <<< "$log") | $(frame_ms <<< "$log") | $(errors "$out/pm_b$b.exr" "$out/pm_b64.exr") | $(errors "$out/pm_b$b.exr" "$out/ref_d16.exr") |"
done

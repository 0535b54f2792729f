#!/usr/bin/env bash
# Caustics (survey §6), measured with the CLI on the demo scene (assets/demo/demo.gltf: a
# glass and a mirror sphere lit by a point light in a closed room, both caustic generators):
#   1. error vs time: photons 32² … 512² × {splat, triangles} (and caustics=off) in
#      `specula tradeoff` against the reference with light-traced caustics (1e6 photons per
#      light and generator), refractor-map for every object: its table, CSV and Pareto plot;
#   2. each caustic pass at photons=512, cube_size=512, and their share of the frame;
#   3. the survey's Figure 39 anchor: the frame at a 64² photon image with and without
#      caustics (2005 GPU: 182 FPS).
# Usage: scripts/bench-caustics.sh [OUTDIR] [SIZE]   (needs cargo build --release)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-bench-caustics}
size=${2:-256x256}
mkdir -p "$out"
. scripts/bench-lib.sh
scene=assets/demo/demo.gltf
caustic_ms() { awk '/^caustics\.[a-z]+ +[0-9.]+ +[0-9.]+$/ {printf "%s %s ms, ", $1, $2; s+=$2} /^frame +[0-9.]+ +[0-9.]+$/ {f=$2} END {printf "all caustics %.1f ms of %.1f ms (%.0f %%)", s, f, 100 * s / f}'; }

echo "## 1. Error vs time ($size, refractor-map, reference spp=4)"
$bin tradeoff $scene --method refractor-map --size "$size" -q spp=4 --frames 3 \
  --sweep caustics=off,splat,triangles --sweep photons=32,64,128,256,512 --out "$out/tradeoff"

echo
echo "## 2. Caustic passes at photons=512, cube_size=512 ($size)"
for c in splat triangles; do
  log=$($bin render $scene --method refractor-map --size "$size" -q caustics=$c -q photons=512 -q cube_size=512 --warmup 1 --frames 3 --out "$out/passes_$c.exr")
  echo "- $c: $(caustic_ms <<< "$log")"
done

echo
echo "## 3. Figure 39 anchor: photons=64 ($size)"
for c in off triangles; do
  log=$($bin render $scene --method refractor-map --size "$size" -q caustics=$c -q photons=64 --warmup 1 --frames 3 --out "$out/fig39_$c.exr")
  echo "- caustics=$c: frame $(frame_ms <<< "$log") ms"
done

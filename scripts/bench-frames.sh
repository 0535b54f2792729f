#!/usr/bin/env bash
# Frames over time and anti-aliasing, measured with the CLI (BENCHMARKS.md, issue 13):
#   1. the static demo scene, per method: frame 1 (every map generated) against the median of
#      frames 2–4 with map_updates=on_change (only what changed: nothing, so camera passes);
#   2. the animated demo (the mirror sphere on its path), mean GPU frame with on_change vs always;
#   3. aa=off|msaa4|ssaa2|ssaa4 at 512² with bvh, distance and envmap (msaa4 with per-sample
#      and per-pixel shading of the specular passes): GPU ms and PSNR / mean FLIP against the
#      16-spp reference;
#   4. what a move reaches (issue 33 item 4): a box slides across builtin:caustic-room (two glass
#      balls focusing a lamp's light, refracted caustic paths) and across the demo (its mirror
#      sphere held still), mean GPU frame with on_change vs always.
# Usage: scripts/bench-frames.sh [OUTDIR] [SECTIONS]   (SECTIONS: e.g. 3, default 1234; needs a
# release build: cargo build --release)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-bench-frames}
sections=${2:-1234}
mkdir -p "$out"
. scripts/bench-lib.sh
scene=assets/demo/demo.gltf

if [[ $sections == *1* ]]; then
echo "## Static demo scene, 256x256: frame 1 vs frames 2-4 (map_updates=on_change), GPU ms"
echo "| method | frame 1 | frames 2+ (median) | ratio |"
echo "|---|---:|---:|---:|"
for m in envmap proxy-sphere proxy-box distance distance-multi refractor-map image-space-refraction bvh; do
  f1=$($bin render $scene --method $m --size 256x256 -q map_updates=on_change --warmup 0 --frames 1 --out "$out/f1.exr" | frame_ms)
  f2=$($bin render $scene --method $m --size 256x256 -q map_updates=on_change --warmup 1 --frames 3 --out "$out/f2.exr" | frame_ms)
  echo "| $m | $f1 | $f2 | $(awk -v a="$f1" -v b="$f2" 'BEGIN { printf "%.1f×", a / b }') |"
done

fi

if [[ $sections == *2* ]]; then
echo
echo "## Animated demo (mirror sphere on its path), 256x256, 12 fps x 4 s: mean GPU ms per frame"
echo "(the mirror sphere is a caustic generator whose light reaches every wall: with caustics every face)"
echo "| method | caustics | on_change | always |"
echo "|---|---|---:|---:|"
for m in envmap distance distance-multi bvh; do
  for c in triangles off; do
    a=$($bin animate $scene --method $m --size 256x256 --fps 12 -q map_updates=on_change -q caustics=$c --out "$out/anim_$m" 2>/dev/null | sed -n 's/.*mean \([0-9.]*\) ms.*/\1/p')
    b=$($bin animate $scene --method $m --size 256x256 --fps 12 -q map_updates=always -q caustics=$c --out "$out/anim_$m" 2>/dev/null | sed -n 's/.*mean \([0-9.]*\) ms.*/\1/p')
    echo "| $m | $c | $a | $b |"
  done
done

fi

if [[ $sections == *3* ]]; then
echo
echo "## Anti-aliasing at 512x512 (depth 4): GPU ms and errors against the 16-spp reference"
$bin render $scene --method reference --size 512x512 -q spp=16 -q depth=4 --out "$out/ref16.exr" > /dev/null
echo "| method | aa | msaa_shading | frame ms | PSNR | mean FLIP |"
echo "|---|---|---|---:|---:|---:|"
for run in "bvh off sample" "bvh msaa4 sample" "bvh ssaa2 sample" "bvh ssaa4 sample" \
           "distance off sample" "distance msaa4 sample" "distance msaa4 pixel" "distance ssaa2 sample" "distance ssaa4 sample" \
           "envmap off sample" "envmap msaa4 sample" "envmap msaa4 pixel" "envmap ssaa4 sample"; do
  read -r m aa sh <<< "$run"
  img="$out/${m}_${aa}_${sh}.exr"
  ms=$($bin render $scene --method "$m" --size 512x512 -q depth=4 -q aa="$aa" -q msaa_shading="$sh" --out "$img" | frame_ms)
  errors=$($bin compare "$img" "$out/ref16.exr")
  psnr=$(awk '/^PSNR/ {print $2}' <<< "$errors")
  flip=$(awk '/^mean FLIP/ {print $3}' <<< "$errors")
  echo "| $m | $aa | $sh | $ms | $psnr dB | $flip |"
done
fi

if [[ $sections == *4* ]]; then
echo
echo "## A box slides (0.2 m/s, 12 fps x 2 s), 256x256: mean GPU ms per frame"
echo "| scene | method | caustics | on_change | always | on_change / always |"
echo "|---|---|---|---:|---:|---:|"
for run in "builtin:caustic-room box refracted" "assets/demo/demo.gltf box/0 both"; do
  read -r s obj paths <<< "$run"
  for m in envmap distance bvh; do
    for c in triangles off; do
      args=(animate "$s" --method $m --size 256x256 --fps 12 --duration 2 --freeze --slide "$obj=0.2,0,0" -q caustics=$c -q caustic_paths=$paths --out "$out/slide_$m")
      a=$($bin "${args[@]}" -q map_updates=on_change 2>/dev/null | sed -n 's/.*mean \([0-9.]*\) ms.*/\1/p')
      b=$($bin "${args[@]}" -q map_updates=always 2>/dev/null | sed -n 's/.*mean \([0-9.]*\) ms.*/\1/p')
      echo "| ${s#*/} | $m | $c | $a | $b | $(awk -v a="$a" -v b="$b" 'BEGIN { printf "%.2f", a / b }') |"
    done
  done
done
fi

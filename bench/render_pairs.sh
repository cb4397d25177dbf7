#!/usr/bin/env bash
# Render every GPU (technique, scene) pair of the demo at 128×96 into DIR, to compare two builds
# image by image (a refactor must leave them identical):
#   bench/render_pairs.sh DIR [BINARY]          # renders DIR/SCENE-TECHNIQUE.exr
#   bench/render_pairs.sh --compare A B [BINARY] # relMSE and RMSE of every image of A against B
set -u
B=${3:-${2:-target/release/lightlab}}
if [ "${1:-}" = "--compare" ]; then
  B=${4:-target/release/lightlab}
  for f in "$2"/*.exr; do
    n=$(basename "$f")
    printf "%-34s %s\n" "$n" "$("$B" compare "$f" "$3/$n" --json 2>/dev/null | tail -1)"
  done
  exit 0
fi
out=$1
B=${2:-target/release/lightlab}
mkdir -p "$out"
common="--width 128 --height 96 --attenuation inverse-square --ssaa 2"
r() {
  s=$1; t=$2; shift 2
  "$B" render --scene "$s" --technique "$t" $common "$@" -o "$out/$s-$t.exr" >"$out/$s-$t.log" 2>&1 \
    || echo "FAIL $s $t (see $out/$s-$t.log)"
}
for s in cornell room shadows bush prt spheres; do
  for t in phong phong-shadow-volumes phong-shadow-maps; do r $s $t; done
done
for s in cornell:32 room:10 shadows:8; do
  n=${s%%:*}; d=${s##*:}
  for t in lightmap lightmap+phong; do r "$n" $t --texels-per-metre "$d" --gather-samples 8; done
done
for t in prt-vertex prt-textured shl shl-compressed shl-normalmapped; do
  r prt $t --texels-per-metre 12 --transfer-samples 32 --bounces 1
done
for s in bush cornell room; do for t in lpv lpv-faithful; do r $s $t; done; done

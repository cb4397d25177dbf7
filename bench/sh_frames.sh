#!/bin/sh
# Frame times of the SH/PRT techniques on `prt` at 1920×1080 (issue 6's table), printed by
# `lightlab bench frame` (GPU passes, and the CPU time of projecting the lights each frame).
# Run on the machine being measured:
#   LIGHTLAB=target/release/lightlab sh bench/sh_frames.sh [FRAMES]
set -u
B=${LIGHTLAB:-lightlab}
N=${1:-30}
bake=$(mktemp -d)
for bands in 4 5; do
    "$B" bake --scene prt --method sh --bands "$bands" --transfer shadowed \
        --transfer-samples 128 --texels-per-metre 16 --out "$bake/sh$bands" >/dev/null 2>&1
done
"$B" bake --scene prt --method sh --bands 4 --transfer shadowed --normal-mapped \
    --transfer-samples 128 --texels-per-metre 16 --out "$bake/nm4" >/dev/null 2>&1
while read -r label args; do
    echo "### $label"
    # shellcheck disable=SC2086
    "$B" bench frame --scene prt --frames "$N" $args --json | tail -n 1
done <<LIST
shl-4 --technique shl --baked $bake/sh4
shl-normalmapped-4 --technique shl-normalmapped --baked $bake/nm4
shl-compressed-4 --technique shl-compressed --baked $bake/sh4
shl-compressed-4-nearest --technique shl-compressed --baked $bake/sh4 --sh-filter nearest
shl-compressed-4-4tap --technique shl-compressed --baked $bake/sh4 --sh-filter 4tap
prt-textured-5 --technique prt-textured --baked $bake/sh5
prt-textured-5-scene --technique prt-textured --baked $bake/sh5 --sh-points scene
prt-vertex-5 --technique prt-vertex --bands 5 --transfer shadowed --transfer-samples 64
LIST
rm -rf "$bake"

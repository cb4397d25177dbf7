#!/bin/sh
# Frame times of every GPU technique on `shadows` at 1920×1080 (issue 4's table), printed by
# `lightlab bench frame`. Run on the machine being measured:
#   LIGHTLAB=target/release/lightlab sh bench/gpu_frames.sh [FRAMES]
# On the H100 device this ran with WGPU_BACKEND=vulkan and the NVIDIA ICD (see docs).
set -u
B=${LIGHTLAB:-lightlab}
N=${1:-30}
bake=$(mktemp -d)
"$B" bake --scene shadows --method path --gather-samples 32 --texels-per-metre 8 \
    --out "$bake/all" >/dev/null 2>&1
"$B" bake --scene shadows --method path --gather-samples 32 --texels-per-metre 8 \
    --light-mode all=indirect-only --out "$bake/ind" >/dev/null 2>&1
while read -r label args; do
    echo "### $label"
    # shellcheck disable=SC2086
    "$B" bench frame --scene shadows --frames "$N" $args --json | tail -n 1
done <<LIST
phong-5 --technique phong
phong-8 --technique phong --lights 8
sv-zfail-5 --technique phong-shadow-volumes
sv-zfail-8 --technique phong-shadow-volumes --lights 8
sv-zpass-8 --technique phong-shadow-volumes --lights 8 --shadow-variant zpass
sv-zfail-8-deferred --technique phong-shadow-volumes --lights 8 --path deferred
sv-zfail-32 --technique phong-shadow-volumes --lights 32
sm-5 --technique phong-shadow-maps
sm-8 --technique phong-shadow-maps --lights 8
sm-8-linear --technique phong-shadow-maps --lights 8 --shadow-variant linear
planar-8 --technique phong-shadow-maps --lights 8 --shadow-variant planar
lightmap --technique lightmap --baked $bake/all
lightmap-bicubic --technique lightmap --baked $bake/all --lightmap-filter bicubic
lightmap+phong-8 --technique lightmap+phong --lights 8 --baked $bake/ind
LIST
rm -rf "$bake"

#!/bin/sh
# Issue 7's table: frame time of `lpv` on `bush` at 1024×1024 against the grid size (8³–128³)
# and the RSM size (128²–2048²), with the volumes' GPU memory, as the WPI report's Tables
# 5.1–5.3. Prints one JSON line per configuration (`lightlab bench frame --json`):
#   LIGHTLAB=target/release/lightlab sh bench/lpv_table.sh [FRAMES] [SIZE] [TECHNIQUE] [EXTRA]
# EXTRA is passed on (e.g. "--lpv-cascades 3"). On the H100 device run it with
# WGPU_BACKEND=vulkan and the NVIDIA ICD (docs/lpv.md).
set -u
B=${LIGHTLAB:-lightlab}
N=${1:-5}
S=${2:-1024}
T=${3:-lpv}
X=${4:-}
for grid in 8 16 32 64 128; do
    for rsm in 128 256 512 1024 2048; do
        # shellcheck disable=SC2086
        "$B" bench frame --scene bush --technique "$T" --frames "$N" --width "$S" --height "$S" \
            --lpv-grid "$grid" --rsm-size "$rsm" $X --json | tail -n 1
    done
done

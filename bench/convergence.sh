#!/usr/bin/env bash
# Two reference renders of a scene with different seeds at increasing spp: their relMSE should
# fall as 1/spp (issue 2's convergence acceptance). Usage: bench/convergence.sh [scene] [size]
set -euo pipefail
scene=${1:-cornell}
size=${2:-256}
cd "$(dirname "$0")/.."
cargo build --release -q -p lightlab
exe=target/release/lightlab
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
prev=""
for spp in 64 256 1024; do
  for seed in 1 2; do
    "$exe" render --scene "$scene" --width "$size" --spp "$spp" --seed "$seed" -o "$tmp/$spp-$seed.exr" 2>/dev/null
  done
  rel=$("$exe" compare "$tmp/$spp-1.exr" "$tmp/$spp-2.exr" --json | tail -1 | python3 -c 'import json,sys; print(json.load(sys.stdin)["relmse"])')
  if [ -n "$prev" ]; then
    ratio=$(python3 -c "print(f'{$prev/$rel:.2f}')")
    echo "$scene ${size}x${size} spp $spp: relMSE between seeds $rel (previous/this = $ratio, expected 4)"
  else
    echo "$scene ${size}x${size} spp $spp: relMSE between seeds $rel"
  fi
  prev=$rel
done

#!/usr/bin/env python3
"""Summarise bench/lpv_table.sh's JSON lines (stdin) as a markdown table: GPU ms per frame
(LPV passes in brackets) and memory, rows = grid, columns = RSM size."""
import json
import sys

rows = {}
for line in sys.stdin:
    line = line.strip()
    if not line.startswith("{"):
        continue
    j = json.loads(line)
    lpv = sum(v for k, v in j["passes_ms"].items() if k.startswith("lpv"))
    rows.setdefault(j["grid"], {})[j["rsm"]] = (j["gpu_ms"] or j["wall_ms"], lpv, j["lpv_bytes"])
rsms = sorted({r for g in rows.values() for r in g})
print("| grid | " + " | ".join(f"RSM {r}²" for r in rsms) + " | memory (RSM 256²) |")
print("|---" * (len(rsms) + 2) + "|")
for g in sorted(rows):
    cells = []
    for r in rsms:
        v = rows[g].get(r)
        cells.append(f"{v[0]:.2f} ({v[1]:.2f})" if v else "")
    mem = rows[g].get(256, next(iter(rows[g].values())))[2] / 2**20
    print(f"| {g}³ | " + " | ".join(cells) + f" | {mem:.1f} MiB |")

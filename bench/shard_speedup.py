#!/usr/bin/env python3
"""Local shards of a light-map bake (issue 27's cost model, docs/scale.md).

Runs the one-machine bake, then N = 1, 2, 4 shards as concurrent local processes (each with
cores/N threads, at least one) and the merge, and prints the wall times, the speed-up, the
per-texel cost and the merge's cost, and a projection for a bake 100 times larger on 64
machines like this one.

    python3 bench/shard_speedup.py [--scene room] [--samples 128] [--density 16]
"""
import argparse, json, os, shutil, subprocess, tempfile, time

p = argparse.ArgumentParser()
p.add_argument("--scene", default="room")
p.add_argument("--samples", type=int, default=128)
p.add_argument("--density", type=float, default=16)
p.add_argument("--lightlab", default=None)
a = p.parse_args()
root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
exe = a.lightlab or next(x for x in (f"{root}/target/release/lightlab",
                                     f"{root}/target/debug/lightlab") if os.path.exists(x))
cores = os.cpu_count() or 1
bake = ["bake", "--scene", a.scene, "--method", "path", "--gather-samples", str(a.samples),
        "--texels-per-metre", str(a.density)]
tmp = tempfile.mkdtemp(prefix="lightlab-shards.")


def run(args, threads=cores):
    env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
    return subprocess.Popen([exe] + args, env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE)


def wait(ps):
    for q in ps:
        _, err = q.communicate()
        if q.returncode:
            raise SystemExit(err.decode())


t = time.time()
wait([run(bake + ["--out", f"{tmp}/whole"])])
whole = time.time() - t
m = json.load(open(f"{tmp}/whole/manifest.json"))["stats"]
texels = m["valid_texels"]
print(f"{a.scene}: {texels} gathered texels, {a.samples} paths each, {cores} cores, {exe}")
print(f"one machine: {whole:.2f} s wall (layout and validity {m['seconds_layout']:.2f} s, "
      f"gathering {m['seconds_solve']:.2f} s)")
per_texel = m["seconds_solve"] * cores / texels
print(f"per-texel cost: {per_texel * 1e3:.3f} core-ms")
merge = None
for n in (1, 2, 4):
    threads = max(1, cores // n)
    t = time.time()
    wait([run(bake + ["--shard", f"{i}/{n}", "--out", f"{tmp}/n{n}-p{i}"], threads)
          for i in range(n)])
    shards = time.time() - t
    t = time.time()
    wait([run(["merge"] + [f"{tmp}/n{n}-p{i}" for i in range(n)] + ["--out", f"{tmp}/m{n}"])])
    merge = time.time() - t
    same = all(open(f"{tmp}/whole/{f}", "rb").read() == open(f"{tmp}/m{n}/{f}", "rb").read()
               for f in os.listdir(f"{tmp}/whole") if f != "manifest.json")
    print(f"{n} local shard(s), {threads} thread(s) each: shards {shards:.2f} s + merge "
          f"{merge:.2f} s = {shards + merge:.2f} s, speed-up {whole / (shards + merge):.2f}x, "
          f"pages equal: {'yes' if same else 'NO'}")
# 100x the texels on 64 machines like this one: each shard lays out and probes the whole
# scene, gathers 1/64 of the texels on all its cores; the merge lays out, probes and repairs.
layout = m["seconds_layout"] * 100
gather = per_texel * texels * 100 / cores
projected = layout + gather / 64 + merge * 100
print(f"projection, a bake 100x larger on 64 such machines: {layout:.0f} s layout and "
      f"validity per shard + {gather / 64:.0f} s gathering + {merge * 100:.0f} s merge = "
      f"{projected / 60:.1f} min, against {(layout + gather) / 60:.1f} min on one")
shutil.rmtree(tmp)

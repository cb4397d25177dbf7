#!/usr/bin/env python3
"""Ray-casting throughput of lightlab against Embree (the `embreex` package) on the same geometry.

For each scene, the built-in scene is exported to glTF, `lightlab bench trace` loads that file,
measures closest-hit Mrays/s (coherent primary rays, incoherent diffuse bounce rays; 1 thread and
all threads) and dumps its triangles and rays; Embree then casts exactly the same rays against
exactly the same triangles, single-threaded (embreex runs one rtcIntersect per ray in one thread,
its per-ray Python-side loop included). Printed: lightlab/Embree per ray kind. Target (issue 2):
>= 0.5x Embree's single-thread throughput on incoherent rays.

Usage: python3 bench/trace_vs_embree.py [--scenes cornell,bush,prt] [--rays N] [--repeat K] [--bvh SETTING] [--json]
Each scene runs K pairs (lightlab, then Embree, alternated; each side best of three inside its
run); the printed ratio is the median of the K pair ratios, [min-max] beside it, and the two
figures shown are those of the median pair. On a shared 2-core machine one pair's ratio moves by
up to 15 %; the median of several is the figure to quote.
Installs embreex and numpy into a private virtual environment (bench/.venv) on first use.
Both sides treat every triangle as opaque (`lightlab bench trace --opaque`); lightlab's figure
with its alpha test (the leaves of `bush`) is printed beside for reference.
"""
import argparse, json, os, subprocess, sys, tempfile, time

from benchlib import ensure_venv, lightlab_exe


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", default="cornell,bush,prt")
    ap.add_argument("--rays", type=int, default=1_000_000)
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--bvh", default="default",
                    help="lightlab's BVH build setting (`lightlab bench trace --bvh`), to compare settings")
    ap.add_argument("--repeat", type=int, default=3,
                    help="pairs of runs per scene (lightlab then Embree); the median ratio is reported")
    ap.add_argument("--inner", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--dir", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.inner:
        return embree_inner(args.dir)
    py = ensure_venv(["embreex", "numpy"])
    exe = lightlab_exe()
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for scene in args.scenes.split(","):
            glb = os.path.join(tmp, f"{scene}.glb")
            subprocess.check_call([exe, "export", "--scene", scene, "-o", glb], stderr=subprocess.DEVNULL)
            d = os.path.join(tmp, scene)
            pairs = []
            for k in range(max(1, args.repeat)):
                # The first run also dumps the rays; later runs time the same rays again.
                cmd = [exe, "bench", "trace", "--scene", glb, "--rays", str(args.rays), "--json", "--opaque", "--bvh", args.bvh]
                if k == 0:
                    cmd += ["--dump", d]
                ours = json.loads(subprocess.check_output(cmd).decode().strip().splitlines()[-1])
                theirs = json.loads(subprocess.check_output([py, __file__, "--inner", "--dir", d]).decode().strip().splitlines()[-1])
                pairs.append((ours, theirs))
            alpha = json.loads(subprocess.check_output([exe, "bench", "trace", "--scene", glb, "--rays", str(args.rays), "--json", "--bvh", args.bvh]).decode().strip().splitlines()[-1])
            med = lambda xs: sorted(xs)[len(xs) // 2]
            r = {"scene": scene, "triangles": pairs[0][0]["triangles"], "pairs": len(pairs),
                 "lightlab_alpha_incoherent_1t": alpha["incoherent_mrays_1t"]}
            for kind in ["coherent", "incoherent"]:
                ratios = [o[f"{kind}_mrays_1t"] / t[kind] for o, t in pairs]
                # The pair whose ratio is the median: its own two figures are printed.
                o, t = sorted(pairs, key=lambda p: p[0][f"{kind}_mrays_1t"] / p[1][kind])[len(pairs) // 2]
                r[f"lightlab_{kind}_1t"] = o[f"{kind}_mrays_1t"]
                r[f"embree_{kind}_1t"] = t[kind]
                r[f"ratio_{kind}_1t"] = med(ratios)
                r[f"ratio_{kind}_1t_range"] = [min(ratios), max(ratios)]
                r[f"lightlab_{kind}_mt"] = med([o[f"{kind}_mrays_mt"] for o, _ in pairs])
            results.append(r)
    print(f"{'scene':<9} {'tris':>8} | {'Mrays/s 1 thread: lightlab / Embree (ratio)':<48} | lightlab all threads")
    for r in results:
        print(f"{r['scene']:<9} {r['triangles']:>8} | coherent {r['lightlab_coherent_1t']:6.2f} / {r['embree_coherent_1t']:6.2f} ({r['ratio_coherent_1t']:.2f}x)"
              f" [{r['ratio_coherent_1t_range'][0]:.2f}-{r['ratio_coherent_1t_range'][1]:.2f}]"
              f"  incoherent {r['lightlab_incoherent_1t']:6.2f} / {r['embree_incoherent_1t']:6.2f} ({r['ratio_incoherent_1t']:.2f}x)"
              f" [{r['ratio_incoherent_1t_range'][0]:.2f}-{r['ratio_incoherent_1t_range'][1]:.2f}]"
              f" | {r['lightlab_coherent_mt']:6.2f} / {r['lightlab_incoherent_mt']:6.2f}"
              f" | with alpha test: incoherent {r['lightlab_alpha_incoherent_1t']:6.2f}")
    if args.json:
        print(json.dumps(results))


def embree_inner(d):
    import numpy as np
    from embreex import rtcore_scene as rtcs
    from embreex.mesh_construction import TriangleMesh

    tris = np.fromfile(os.path.join(d, "triangles.f32"), dtype="<f4").reshape(-1, 3, 3)
    scene = rtcs.EmbreeScene()
    TriangleMesh(scene, tris)
    out = {}
    for kind, name in [("coherent", "primary"), ("incoherent", "secondary")]:
        rays = np.fromfile(os.path.join(d, f"{name}.f32"), dtype="<f4").reshape(-1, 6)
        o = np.ascontiguousarray(rays[:, :3])
        dirs = np.ascontiguousarray(rays[:, 3:])
        scene.run(o[:10000], dirs[:10000], output=1)  # warm-up (also commits the BVH)
        best = float("inf")
        for _ in range(3):
            t = time.perf_counter()
            scene.run(o, dirs, output=1)
            best = min(best, time.perf_counter() - t)
        out[kind] = len(rays) / best / 1e6
    print(json.dumps(out))


if __name__ == "__main__":
    main()

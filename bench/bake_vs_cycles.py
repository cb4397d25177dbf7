#!/usr/bin/env python3
"""Light-map bake time of lightlab against Blender's Cycles baker (PyPI `bpy`) on the same scene.

The built-in scene is exported to glTF; `lightlab bench bake` bakes it with both bakers
(radiosity and path-traced gathering) and reports its light-map texels. Blender then imports the
same .glb, joins its meshes, packs one light-map UV layer (Lightmap Pack) into one image with the
same number of texels as lightlab's pages, and bakes Cycles' DIFFUSE pass (direct + indirect
light, no colour: the irradiance a white receiver sees, which is what lightlab stores) on the CPU
with the same samples per texel, bounce limit and thread count, adaptive sampling and denoising
off. Only the bake calls are timed on both sides (lightlab's time includes its UV layout, texel
rasterisation and repair; Blender's UV packing and scene set-up are not counted). Both bakers
trace only the texels their charts cover, so the time per covered texel is printed too.

Printed: seconds of each baker and the ratio Cycles / lightlab (above 1: lightlab is faster).
Target (issue 5): lightlab faster than Cycles on the CPU.

`--equal-error` compares the path-traced bakers at equal error instead (issue 26: lightlab
>= 5x Cycles). Each side bakes the scene at the sample counts `--levels` and at `--ref-samples`
(its own converged bake, another seed), all with the same layout, and each level's relMSE
against that reference is measured over the texels the reference covers (the metric of
`lightlab compare`), less the reference's own noise. A power law through the levels' errors
(slope −1 for plain Monte Carlo; Cycles' quasi-Monte Carlo falls faster at low counts) gives
the samples that reach `--target`, and a line a + b·s through the levels' bake times gives the
seconds. The ratio of those seconds is printed; the script says when the target lies outside
the levels' errors (extrapolated).

Usage: python3 bench/bake_vs_cycles.py [--scene cornell] [--texels-per-metre 128]
                                        [--samples 128] [--depth 8] [--threads N] [--json]
       python3 bench/bake_vs_cycles.py --equal-error [--levels 32,128] [--ref-samples 1024]
                                        [--target 0.003] [--scene ...] [--depth 8] [--json]
Installs bpy (Blender as a Python module, Python 3.11 only), numpy and OpenEXR into
bench/.venv on first use.
"""
import argparse, json, math, os, subprocess, sys, tempfile, time

from benchlib import ensure_venv, lightlab_exe


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", default="cornell")
    ap.add_argument("--texels-per-metre", type=float, default=128)
    ap.add_argument("--samples", type=int, default=128)
    ap.add_argument("--depth", type=int, default=8)
    ap.add_argument("--threads", type=int, default=os.cpu_count())
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--equal-error", action="store_true",
                    help="time to a relMSE target against each side's own converged bake")
    ap.add_argument("--levels", default="32,128", help="--equal-error: samples per texel measured")
    ap.add_argument("--ref-samples", type=int, default=1024, help="--equal-error: the converged bake")
    ap.add_argument("--target", type=float, default=0.003, help="--equal-error: relMSE to reach")
    ap.add_argument("--inner", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--npy", help=argparse.SUPPRESS)
    ap.add_argument("--glb", help=argparse.SUPPRESS)
    ap.add_argument("--texels", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.inner and args.equal_error:
        return equal_error(args)
    if args.inner:
        return cycles_inner(args)
    if sys.version_info[:2] != (3, 11):
        sys.exit("bpy from PyPI needs Python 3.11; run this script with python3.11")
    py = ensure_venv(["bpy", "numpy", "OpenEXR"])
    exe = lightlab_exe()
    env = dict(os.environ, RAYON_NUM_THREADS=str(args.threads))
    with tempfile.TemporaryDirectory() as tmp:
        glb = os.path.join(tmp, f"{args.scene}.glb")
        subprocess.check_call([exe, "export", "--scene", args.scene, "-o", glb], stderr=subprocess.DEVNULL)
        if args.equal_error:
            out = subprocess.check_output(
                [py, __file__, "--equal-error", "--inner", "--glb", glb, "--npy", tmp,
                 "--scene", args.scene, "--texels-per-metre", str(args.texels_per_metre),
                 "--levels", args.levels, "--ref-samples", str(args.ref_samples),
                 "--target", str(args.target), "--depth", str(args.depth),
                 "--threads", str(args.threads)] + (["--json"] if args.json else []),
                env=dict(env, LIGHTLAB_EXE=exe))
            print(out.decode().rstrip())
            return
        out = subprocess.check_output(
            [exe, "bench", "bake", "--scene", glb, "--json",
             "--texels-per-metre", str(args.texels_per_metre),
             "--gather-samples", str(args.samples), "--gather-depth", str(args.depth)],
            env=env)
        ours = json.loads(out.decode().strip().splitlines()[-1])
        texels = ours["bakers"]["path"]["page_texels"]
        out = subprocess.check_output(
            [py, __file__, "--inner", "--glb", glb, "--texels", str(texels),
             "--samples", str(args.samples), "--depth", str(args.depth),
             "--threads", str(args.threads)], stderr=subprocess.DEVNULL)
        theirs = json.loads(out.decode().strip().splitlines()[-1])
    path_s = ours["bakers"]["path"]["seconds"]
    rad_s = ours["bakers"]["radiosity"]["seconds"]
    r = {
        "scene": args.scene, "threads": args.threads, "samples_per_texel": args.samples,
        "max_depth": args.depth, "lightlab_texels": texels, "cycles_texels": theirs["texels"],
        "lightlab_path_s": path_s, "lightlab_radiosity_s": rad_s, "cycles_s": theirs["seconds"],
        "cycles_mean": theirs["mean"], "cycles_covered_texels": theirs["covered"],
        "lightlab_valid_texels": ours["bakers"]["path"]["valid_texels"],
        # Time per covered texel, both sides (the bakers skip texels outside the charts).
        "ratio_per_texel_path": (theirs["seconds"] / theirs["covered"])
        / (path_s / ours["bakers"]["path"]["valid_texels"]),
        "ratio_cycles_over_path": theirs["seconds"] / path_s,
        "ratio_cycles_over_radiosity": theirs["seconds"] / rad_s,
        "blender": theirs["blender"],
    }
    print(f"{args.scene}: {texels} light-map texels (Cycles {theirs['texels']}), "
          f"{args.samples} samples/texel, depth {args.depth}, {args.threads} threads")
    print(f"  lightlab path gathering {path_s:8.2f} s   Cycles / lightlab = {r['ratio_cycles_over_path']:.2f}x")
    print(f"  lightlab radiosity      {rad_s:8.2f} s   Cycles / lightlab = {r['ratio_cycles_over_radiosity']:.2f}x")
    print(f"  Cycles {theirs['blender']:<17}{theirs['seconds']:8.2f} s")
    print(f"  covered texels: lightlab {r['lightlab_valid_texels']}, Cycles {theirs['covered']}; "
          f"per covered texel Cycles / lightlab path = {r['ratio_per_texel_path']:.2f}x")
    if args.json:
        print(json.dumps(r))


def cycles_setup(glb, texels, samples, depth, threads):
    """Blender's scene from the .glb: one joined object with a packed light-map UV layer and
    a float image of about `texels` texels to bake into; returns (object, image)."""
    import bpy
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=glb)
    meshes = [o for o in bpy.data.objects if o.type == "MESH"]
    bpy.ops.object.select_all(action="DESELECT")
    for o in meshes:
        o.select_set(True)
    bpy.context.view_layer.objects.active = meshes[0]
    if len(meshes) > 1:
        bpy.ops.object.join()
    obj = bpy.context.view_layer.objects.active
    uv = obj.data.uv_layers.new(name="lightmap")
    obj.data.uv_layers.active = uv
    side = max(8, math.ceil(math.sqrt(texels)))
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.uv.lightmap_pack(PREF_CONTEXT="ALL_FACES", PREF_PACK_IN_ONE=True,
                             PREF_BOX_DIV=12, PREF_MARGIN_DIV=0.2)
    bpy.ops.object.mode_set(mode="OBJECT")
    img = bpy.data.images.new("lightmap", side, side, float_buffer=True)
    for mat in obj.data.materials:
        mat.use_nodes = True
        node = mat.node_tree.nodes.new("ShaderNodeTexImage")
        node.image = img
        mat.node_tree.nodes.active = node
    scene = bpy.context.scene
    world = bpy.data.worlds.new("black")
    world.color = (0, 0, 0)
    scene.world = world
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device = "CPU"
    c.samples = samples
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.max_bounces = depth
    c.diffuse_bounces = depth
    c.glossy_bounces = depth
    c.transmission_bounces = depth
    scene.render.threads_mode = "FIXED"
    scene.render.threads = threads
    # No margin: the covered texels (the ones Cycles actually path-traces) are counted below.
    scene.render.bake.margin = 0
    bpy.ops.object.select_all(action="DESELECT")
    obj.select_set(True)
    return obj, img


def cycles_bake(img):
    """Bake Cycles' DIFFUSE pass (direct + indirect, no colour) into `img`; seconds taken."""
    import bpy
    t = time.perf_counter()
    bpy.ops.object.bake(type="DIFFUSE", pass_filter={"DIRECT", "INDIRECT"}, margin=0)
    return time.perf_counter() - t


def cycles_inner(args):
    import bpy
    _, img = cycles_setup(args.glb, args.texels, args.samples, args.depth, args.threads)
    seconds = cycles_bake(img)
    side = img.size[0]
    px = img.pixels[:]
    covered = [px[i] for i in range(0, len(px), 4) if px[i] + px[i + 1] + px[i + 2] > 0.0]
    mean = sum(covered) / max(1, len(covered))
    print(json.dumps({"seconds": seconds, "texels": side * side, "covered": len(covered),
                      "mean": mean, "blender": bpy.app.version_string}))


def relmse(a, ref):
    """`lightlab compare`'s relMSE, (a − b)²/(b² + 0.01) averaged over channels, over the
    texels where the reference is not black."""
    import numpy as np
    mask = ref.sum(axis=-1) > 0.0
    a, b = a[mask].astype(np.float64), ref[mask].astype(np.float64)
    return float(np.mean((a - b) ** 2 / (b * b + 0.01)))


def lightlab_pages(folder):
    """A bake folder's pages (lightmap-K.exr) as one (texels, 3) array."""
    import numpy as np
    import OpenEXR
    pages = []
    for k in range(1000):
        path = os.path.join(folder, f"lightmap-{k}.exr")
        if not os.path.exists(path):
            break
        with OpenEXR.File(path) as f:
            ch = f.channels()
            rgb = ch["RGB"].pixels if "RGB" in ch else np.stack(
                [ch[c].pixels for c in "RGB"], axis=-1)
        pages.append(rgb.reshape(-1, 3))
    return np.concatenate(pages)


def fit(levels, ref_samples, runs, target):
    """runs: {samples: (seconds, texels)}. Each level's relMSE against the reference, less the
    reference's own share (its noise, taken as the top level's error × s_top / S_ref); a power
    law e = k·s^slope through those (least squares in log-log: slope −1 for plain Monte Carlo,
    steeper for quasi-Monte Carlo at low counts); the time line a + b·s; and the samples and
    seconds that reach `target`."""
    ref = runs[ref_samples][1]
    raw = [relmse(runs[s][1], ref) for s in levels]
    floor = raw[-1] * levels[-1] / ref_samples
    err = [e - floor for e in raw]
    xs, ys = [math.log(s) for s in levels], [math.log(e) for e in err]
    n = len(levels)
    mx, my = sum(xs) / n, sum(ys) / n
    slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
    samples = math.exp(mx + (math.log(target) - my) / slope)
    ts = [runs[s][0] for s in levels]
    ms, mt = sum(levels) / n, sum(ts) / n
    b = sum((s - ms) * (t - mt) for s, t in zip(levels, ts)) / sum((s - ms) ** 2 for s in levels)
    a = max(0.0, mt - b * ms)
    return {"relmse": {str(s): e for s, e in zip(levels, raw)},
            "relmse_less_reference": {str(s): e for s, e in zip(levels, err)},
            "slope": slope, "a": a, "b": b,
            "seconds": {str(s): runs[s][0] for s in levels + [ref_samples]},
            "samples_to_target": samples, "seconds_to_target": a + b * samples,
            "interpolated": min(err) <= target <= max(err)}


def equal_error(args):
    """Both bakers at each level and at the reference's samples; the fitted times to reach
    `args.target` (runs inside bench/.venv, which has bpy, numpy and OpenEXR)."""
    import bpy
    import numpy as np
    exe = os.environ["LIGHTLAB_EXE"]
    levels = sorted(int(x) for x in args.levels.split(","))
    assert len(levels) >= 2, "--levels needs two sample counts or more"
    counts = levels + [args.ref_samples]
    ours, stats = {}, None
    for i, s in enumerate(counts):
        folder = os.path.join(args.npy, f"lightlab-{s}")
        out = subprocess.check_output(
            [exe, "bake", "--scene", args.glb, "--method", "path", "--out", folder, "--json",
             "--texels-per-metre", str(args.texels_per_metre), "--gather-samples", str(s),
             "--gather-depth", str(args.depth), "--bake-seed", str(7919 * (i + 1))],
            stderr=subprocess.DEVNULL)
        stats = json.loads(out.decode().strip().splitlines()[-1])
        ours[s] = (stats["seconds_total"], lightlab_pages(folder))
    _, img = cycles_setup(args.glb, stats["page_texels"], counts[0], args.depth, args.threads)
    theirs = {}
    for i, s in enumerate(counts):
        bpy.context.scene.cycles.samples = s
        bpy.context.scene.cycles.seed = 7919 * (i + 1)
        seconds = cycles_bake(img)
        px = np.empty(len(img.pixels), dtype=np.float32)
        img.pixels.foreach_get(px)
        theirs[s] = (seconds, px.reshape(-1, 4)[:, :3].copy())
    fl = fit(levels, args.ref_samples, ours, args.target)
    fc = fit(levels, args.ref_samples, theirs, args.target)
    r = {
        "scene": args.scene, "threads": args.threads, "max_depth": args.depth,
        "texels_per_metre": args.texels_per_metre, "levels": levels,
        "ref_samples": args.ref_samples, "target_relmse": args.target,
        "lightlab": fl, "cycles": fc, "blender": bpy.app.version_string,
        "ratio_at_target": fc["seconds_to_target"] / fl["seconds_to_target"],
    }
    print(f"{args.scene}: path-traced bakes at equal error, {args.texels_per_metre} texels/m, "
          f"depth {args.depth}, {args.threads} threads, levels {levels}, each side against its "
          f"own bake at {args.ref_samples} samples")
    for name, f in (("lightlab", fl), (f"Cycles {r['blender']}", fc)):
        per = ", ".join(f"{s}: {f['relmse'][str(s)]:.5f} in {f['seconds'][str(s)]:.2f} s"
                        for s in levels)
        where = "interpolated" if f["interpolated"] else "EXTRAPOLATED"
        print(f"  {name:<14} relMSE {per}; error ~ spp^{f['slope']:.2f}; time {f['a']:.2f} s + "
              f"{1000 * f['b']:.2f} ms/spp; relMSE {args.target} at {f['samples_to_target']:.0f} "
              f"spp ({where}) in {f['seconds_to_target']:.2f} s")
    print(f"  Cycles / lightlab at equal error: {r['ratio_at_target']:.2f}x")
    if args.json:
        print(json.dumps(r))


if __name__ == "__main__":
    main()

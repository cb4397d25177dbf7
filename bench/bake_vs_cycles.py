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

Usage: python3 bench/bake_vs_cycles.py [--scene cornell] [--texels-per-metre 128]
                                        [--samples 128] [--depth 8] [--threads N] [--json]
Installs bpy (Blender as a Python module, Python 3.11 only) into bench/.venv on first use.
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
    ap.add_argument("--inner", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--glb", help=argparse.SUPPRESS)
    ap.add_argument("--texels", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.inner:
        return cycles_inner(args)
    if sys.version_info[:2] != (3, 11):
        sys.exit("bpy from PyPI needs Python 3.11; run this script with python3.11")
    py = ensure_venv(["bpy"])
    exe = lightlab_exe()
    env = dict(os.environ, RAYON_NUM_THREADS=str(args.threads))
    with tempfile.TemporaryDirectory() as tmp:
        glb = os.path.join(tmp, f"{args.scene}.glb")
        subprocess.check_call([exe, "export", "--scene", args.scene, "-o", glb], stderr=subprocess.DEVNULL)
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


def cycles_inner(args):
    import bpy
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=args.glb)
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
    side = max(8, math.ceil(math.sqrt(args.texels)))
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
    c.samples = args.samples
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.max_bounces = args.depth
    c.diffuse_bounces = args.depth
    c.glossy_bounces = args.depth
    c.transmission_bounces = args.depth
    scene.render.threads_mode = "FIXED"
    scene.render.threads = args.threads
    # No margin: the covered texels (the ones Cycles actually path-traces) are counted below.
    scene.render.bake.margin = 0
    bpy.ops.object.select_all(action="DESELECT")
    obj.select_set(True)
    t = time.perf_counter()
    bpy.ops.object.bake(type="DIFFUSE", pass_filter={"DIRECT", "INDIRECT"}, margin=0)
    seconds = time.perf_counter() - t
    px = img.pixels[:]
    covered = [px[i] for i in range(0, len(px), 4) if px[i] + px[i + 1] + px[i + 2] > 0.0]
    mean = sum(covered) / max(1, len(covered))
    print(json.dumps({"seconds": seconds, "texels": side * side, "covered": len(covered),
                      "mean": mean, "blender": bpy.app.version_string}))


if __name__ == "__main__":
    main()

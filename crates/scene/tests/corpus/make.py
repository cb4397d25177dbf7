#!/usr/bin/env python3
"""Writes the hostile glTF corpus of `tests/hostile.rs` (run from this folder; the files are
committed, so tests need no Python). Each file is a small valid scene with one thing broken;
`valid*.gltf`/`.glb` are the intact seeds of the mutation test."""
import base64, json, struct, zlib, copy

def png(w, h, rgba=None, header_only=False):
    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xffffffff)
    ihdr = struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0)
    if header_only:
        raw = b"\0" + b"\0" * 16
    else:
        rows = b"".join(b"\0" + bytes(rgba or [200, 100, 50, 255]) * w for _ in range(h))
        raw = rows
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")

def data_uri(b, mime="application/octet-stream"):
    return f"data:{mime};base64," + base64.b64encode(b).decode()

# Two triangles (a quad) with normals, UVs, indices.
pos = [(-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1)]
nrm = [(0, 1, 0)] * 4
uv = [(0, 0), (1, 0), (1, 1), (0, 1)]
idx = [0, 2, 1, 0, 3, 2]

def blob(pos=pos, nrm=nrm, uv=uv, idx=idx):
    b = b"".join(struct.pack("<3f", *p) for p in pos)
    b += b"".join(struct.pack("<3f", *n) for n in nrm)
    b += b"".join(struct.pack("<2f", *t) for t in uv)
    b += b"".join(struct.pack("<H", i) for i in idx)
    while len(b) % 4:
        b += b"\0"
    return b

def base(buf=None):
    b = blob() if buf is None else buf
    np, nn = 48, 48
    return {
        "asset": {"version": "2.0", "generator": "lightlab hostile corpus"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "intensity": 20.0, "color": [1, 1, 1], "range": 10.0}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [
            {"mesh": 0, "name": "floor"},
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 2, 0]},
            {"camera": 0, "translation": [0, 1, 4]},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.05}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                                    "indices": 3, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
                                                "metallicFactor": 0.0}}],
        "textures": [{"source": 0}],
        "images": [{"uri": data_uri(png(2, 2), "image/png")}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [-1, 0, -1], "max": [1, 0, 1]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 48},
            {"buffer": 0, "byteOffset": 96, "byteLength": 32},
            {"buffer": 0, "byteOffset": 128, "byteLength": 12},
        ],
        "buffers": [{"byteLength": len(b), "uri": data_uri(b)}],
    }

files = {}
files["valid.gltf"] = base()

def variant(name, f):
    g = copy.deepcopy(base())
    f(g)
    files[name] = g

variant("stride_smaller_than_element.gltf",
        lambda g: g["bufferViews"][0].update(byteStride=4))
variant("stride_not_multiple_of_4.gltf",
        lambda g: g["bufferViews"][0].update(byteStride=14))
variant("indices_past_view.gltf", lambda g: g["accessors"][3].update(count=60))
variant("positions_past_view.gltf", lambda g: g["accessors"][0].update(byteOffset=40))
variant("view_past_buffer.gltf", lambda g: g["bufferViews"][3].update(byteLength=4000))
variant("byte_length_too_large.gltf", lambda g: g["buffers"][0].update(byteLength=4096))
variant("uri_parent.gltf", lambda g: g["buffers"][0].update(uri="../outside.bin"))
variant("uri_absolute.gltf", lambda g: g["buffers"][0].update(uri="/etc/passwd"))
variant("uri_file_scheme.gltf", lambda g: g["buffers"][0].update(uri="file:///etc/passwd"))
variant("uri_bad_percent.gltf", lambda g: g["buffers"][0].update(uri="%FF%FE.bin"))
variant("uri_http.gltf", lambda g: g["buffers"][0].update(uri="http://example.com/a.bin"))
variant("missing_buffer.gltf", lambda g: g["buffers"][0].update(uri="missing.bin"))
variant("missing_image.gltf", lambda g: g["images"][0].update(uri="textures/missing.png"))
variant("image_uri_parent.gltf", lambda g: g["images"][0].update(uri="../../secret.png"))
variant("image_not_png.gltf", lambda g: g["images"][0].update(
    uri=data_uri(b"GIF89a-not-really", "image/png")))
variant("image_truncated.gltf", lambda g: g["images"][0].update(
    uri=data_uri(png(64, 64)[:60], "image/png")))
variant("image_huge_dimensions.gltf", lambda g: g["images"][0].update(
    uri=data_uri(png(200000, 200000, header_only=True), "image/png")))
variant("node_self_cycle.gltf", lambda g: g["nodes"][0].update(children=[0]))
variant("node_cycle.gltf", lambda g: (g["nodes"][0].update(children=[1]),
                                      g["nodes"][1].update(children=[0])))
variant("node_two_parents.gltf", lambda g: (g["nodes"][0].update(children=[2]),
                                            g["nodes"][1].update(children=[2])))
variant("huge_scale.gltf", lambda g: g["nodes"][0].update(scale=[1e30, 1e30, 1e30]))
variant("singular_scale.gltf", lambda g: g["nodes"][0].update(scale=[1, 0, 1]))
variant("negative_light.gltf", lambda g: g["extensions"]["KHR_lights_punctual"]["lights"][0]
        .update(intensity=-5.0))
variant("negative_range.gltf", lambda g: g["extensions"]["KHR_lights_punctual"]["lights"][0]
        .update(range=-1.0))
variant("spot_cone_inverted.gltf", lambda g: g["extensions"]["KHR_lights_punctual"]["lights"][0]
        .update(type="spot", spot={"innerConeAngle": 1.2, "outerConeAngle": 0.3}))
variant("negative_sun_diameter.gltf", lambda g: g["extensions"]["KHR_lights_punctual"]["lights"][0]
        .update(type="directional", extras={"angularDiameter": -0.1}))
variant("camera_zero_fov.gltf", lambda g: g["cameras"][0]["perspective"].update(yfov=0.0))
variant("unknown_required_extension.gltf",
        lambda g: g.update(extensionsRequired=["EXT_made_up"], extensionsUsed=["EXT_made_up"]))
variant("bad_accessor_index.gltf",
        lambda g: g["meshes"][0]["primitives"][0]["attributes"].update(POSITION=99))
variant("sparse_past_view.gltf", lambda g: g["accessors"][0].update(sparse={
    "count": 3, "indices": {"bufferView": 3, "componentType": 5125, "byteOffset": 8},
    "values": {"bufferView": 2}}))
variant("points_mode.gltf", lambda g: g["meshes"][0]["primitives"][0].update(mode=0))
variant("texcoord_set_missing.gltf", lambda g: g["materials"][0]["pbrMetallicRoughness"]
        ["baseColorTexture"].update(texCoord=3))
variant("environment_outside.gltf", lambda g: g["scenes"][0].update(
    extras={"lightlab": {"environment": {"uri": "../../sky.exr", "intensity": 1.0}}}))
variant("environment_huge_intensity.gltf", lambda g: g["scenes"][0].update(
    extras={"lightlab": {"environment": {"uri": "sky.exr", "intensity": 1e38}}}))

# Geometry broken inside the buffer.
nan = float("nan")
files["nan_positions.gltf"] = base(blob(pos=[(nan, 0, 0)] + pos[1:]))
files["zero_normals.gltf"] = base(blob(nrm=[(0, 0, 0)] * 4))
files["index_out_of_range.gltf"] = base(blob(idx=[0, 2, 1, 0, 3, 9]))
files["degenerate_triangle.gltf"] = base(blob(idx=[0, 0, 1, 0, 3, 2]))

# Strips and fans (converted to lists) and a points primitive beside triangles (skipped).
def strip_or_fan(mode, order):
    g = base(blob(idx=order))
    g["accessors"][3]["count"] = len(order)
    g["bufferViews"][3]["byteLength"] = 2 * len(order)
    g["meshes"][0]["primitives"][0]["mode"] = mode
    return g
files["triangle_strip.gltf"] = strip_or_fan(5, [0, 3, 1, 2])
files["triangle_fan.gltf"] = strip_or_fan(6, [0, 3, 2, 1])
g = base()
g["meshes"][0]["primitives"].append({"attributes": {"POSITION": 0}, "mode": 0})
files["points_beside_triangles.gltf"] = g

# Features lightlab does not render yet (transmission): loaded, with one warning each; beside
# features it renders (texture transforms, GPU instancing, vertex colours), without one.
g = base()
g["extensionsUsed"] += ["KHR_materials_volume", "KHR_texture_transform", "EXT_mesh_gpu_instancing", "KHR_materials_transmission"]
g["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = 1
files["unsupported_features.gltf"] = g

# A 3000-deep node chain (deeper than lightlab's 1024 levels).
g = base()
n0 = len(g["nodes"])
g["nodes"][0]["children"] = [n0]
for k in range(3000):
    g["nodes"].append({"children": [n0 + k + 1]} if k < 2999 else {"mesh": 0})
files["deep_chain.gltf"] = g

for name, g in files.items():
    with open(name, "w") as f:
        json.dump(g, f, separators=(",", ":"))

def glb(g, b):
    g = copy.deepcopy(g)
    g["buffers"] = [{"byteLength": len(b)}]
    j = json.dumps(g, separators=(",", ":")).encode()
    while len(j) % 4:
        j += b" "
    body = struct.pack("<I4s", len(j), b"JSON") + j + struct.pack("<I4s", len(b), b"BIN\0") + b
    return b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body

good = glb(base(), blob())
open("valid.glb", "wb").write(good)
open("glb_truncated.glb", "wb").write(good[: len(good) // 2])
bad = bytearray(good); bad[12:16] = struct.pack("<I", 0xFFFFFFF0)
open("glb_json_length_huge.glb", "wb").write(bytes(bad))
bad = bytearray(good); bad[8:12] = struct.pack("<I", 7)
open("glb_total_length_wrong.glb", "wb").write(bytes(bad))
open("glb_header_only.glb", "wb").write(good[:12])
open("not_json.gltf", "wb").write(b"{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [")
open("deep_json.gltf", "wb").write(b"[" * 5000 + b"]" * 5000)

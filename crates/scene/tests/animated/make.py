#!/usr/bin/env python3
"""Writes the animated glTF files of `tests/animation.rs` (run from this folder; the files are
committed, so tests need no Python). Written by hand, not by lightlab's exporter: a node
hierarchy whose parent turns (LINEAR rotation) while its child steps (STEP translation), a
spinner keyed with CUBICSPLINE, a scale channel lightlab ignores, and two broken variants."""
import base64, json, math, struct, copy

def data_uri(b):
    return "data:application/octet-stream;base64," + base64.b64encode(b).decode()

# A unit quad facing +y (positions, normals, indices).
pos = [(-0.5, 0, -0.5), (0.5, 0, -0.5), (0.5, 0, 0.5), (-0.5, 0, 0.5)]
idx = [0, 2, 1, 0, 3, 2]
mesh = b"".join(struct.pack("<3f", *p) for p in pos)
mesh += b"".join(struct.pack("<3f", 0, 1, 0) for _ in pos)
mesh += b"".join(struct.pack("<H", i) for i in idx) + b"\0\0"

def quat_y(a):
    return (0.0, math.sin(a / 2), 0.0, math.cos(a / 2))

# Key data: (name, floats, components, type)
keys = [
    ("rig_times", [0.0, 1.0, 2.0], 1, "SCALAR"),
    ("rig_rot", [c for a in (0, math.pi / 2, math.pi) for c in quat_y(a)], 4, "VEC4"),
    ("rig_scale", [1, 1, 1, 2, 2, 2, 1, 1, 1], 3, "VEC3"),
    ("arm_times", [0.0, 0.5], 1, "SCALAR"),
    ("arm_tr", [1, 0, 0, 2, 0, 0], 3, "VEC3"),
    ("spin_times", [0.0, 2.0], 1, "SCALAR"),
    # Cubic spline: (in-tangent, value, out-tangent) per key.
    ("spin_rot", [0, 0, 0, 0, *quat_y(0), 0, 0, 0, 0, 0, 0, 0, 0, *quat_y(math.pi / 2), 0, 0, 0, 0],
     4, "VEC4"),
]
buf = bytearray(mesh)
views = [
    {"buffer": 0, "byteOffset": 0, "byteLength": 48},
    {"buffer": 0, "byteOffset": 48, "byteLength": 48},
    {"buffer": 0, "byteOffset": 96, "byteLength": 12},
]
accessors = [
    {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
     "min": [-0.5, 0, -0.5], "max": [0.5, 0, 0.5]},
    {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
    {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"},
]
index = {}
for name, data, comps, kind in keys:
    b = b"".join(struct.pack("<f", x) for x in data)
    views.append({"buffer": 0, "byteOffset": len(buf), "byteLength": len(b)})
    buf += b
    a = {"bufferView": len(views) - 1, "componentType": 5126, "count": len(data) // comps,
         "type": kind}
    if kind == "SCALAR":
        a["min"], a["max"] = [min(data)], [max(data)]
    accessors.append(a)
    index[name] = len(accessors) - 1

doc = {
    "asset": {"version": "2.0", "generator": "lightlab animation corpus (hand-written)"},
    "extensionsUsed": ["KHR_lights_punctual"],
    "extensions": {"KHR_lights_punctual": {"lights": [{"type": "directional", "intensity": 2.0}]}},
    "scene": 0,
    "scenes": [{"nodes": [0, 1, 3, 4, 5]}],
    "nodes": [
        {"name": "floor", "mesh": 0, "scale": [8, 1, 8]},
        {"name": "rig", "children": [2], "translation": [0, 1, 0]},
        {"name": "arm", "mesh": 0, "translation": [1, 0, 0]},
        {"name": "spinner", "mesh": 0, "translation": [0, 0.5, 2]},
        {"name": "sun", "rotation": [-0.5, 0, 0, 0.866],
         "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"name": "camera", "camera": 0, "translation": [0, 3, 6], "rotation": [-0.2, 0, 0, 0.98]},
    ],
    "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.05}}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2}]}],
    "animations": [
        {"name": "play",
         "samplers": [
             {"input": index["rig_times"], "output": index["rig_rot"], "interpolation": "LINEAR"},
             {"input": index["rig_times"], "output": index["rig_scale"]},
             {"input": index["arm_times"], "output": index["arm_tr"], "interpolation": "STEP"},
             {"input": index["spin_times"], "output": index["spin_rot"],
              "interpolation": "CUBICSPLINE"},
         ],
         "channels": [
             {"sampler": 0, "target": {"node": 1, "path": "rotation"}},
             {"sampler": 1, "target": {"node": 1, "path": "scale"}},
             {"sampler": 2, "target": {"node": 2, "path": "translation"}},
             {"sampler": 3, "target": {"node": 3, "path": "rotation"}},
         ]},
        {"name": "unused", "samplers": [{"input": index["arm_times"], "output": index["arm_tr"]}],
         "channels": [{"sampler": 0, "target": {"node": 3, "path": "translation"}}]},
    ],
    "accessors": accessors,
    "bufferViews": views,
    "buffers": [{"byteLength": len(buf), "uri": data_uri(bytes(buf))}],
}

def write(name, d):
    open(name, "w").write(json.dumps(d, indent=1))

write("animated.gltf", doc)
# Key times that go backwards.
bad = copy.deepcopy(doc)
bad["animations"][0]["samplers"][0]["input"] = len(bad["accessors"])
bad["accessors"].append({"bufferView": len(bad["bufferViews"]), "componentType": 5126,
                         "count": 3, "type": "SCALAR", "min": [0.0], "max": [2.0]})
b = struct.pack("<3f", 0.0, 2.0, 1.0)
bad["bufferViews"].append({"buffer": 0, "byteOffset": len(buf), "byteLength": len(b)})
raw = bytes(buf) + b
bad["buffers"] = [{"byteLength": len(raw), "uri": data_uri(raw)}]
write("animated_times_backwards.gltf", bad)
# Fewer rotations than key times.
short = copy.deepcopy(doc)
short["animations"][0]["samplers"][2]["input"] = index["rig_times"]  # 3 times, 2 translations
write("animated_short_outputs.gltf", short)

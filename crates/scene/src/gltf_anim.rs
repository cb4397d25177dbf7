//! glTF animations of node transforms, as the scene's rigid [`Animation`].
//!
//! **Import.** The file's first animation (more are named in a warning). Its translation and
//! rotation channels (LINEAR and STEP; CUBICSPLINE reads the key values and interpolates them
//! linearly, with a warning) drive their nodes; an instance moves when a node on its path from
//! the root is driven. Each moving instance gets a [`Track`] keyed at the union of its path's
//! key times: M(t) = world(t) · rest⁻¹, world(t) composed down the path from each node's
//! animated TRS, and resampled at every frame (so that a node turning about another follows
//! its arc, not the chord between keys) and just before each STEP key (so that steps stay
//! steps). Scale channels are ignored with a warning (lightlab's motion is rigid). A glTF
//! animation has no frame rate: `extras.lightlab.fps` (what the exporter writes), else 24.
//!
//! **Export.** Each track's instance node is written as TRS (glTF forbids animating a node
//! that has a matrix), with one translation and one rotation channel keyed at the track's
//! times: world(t) = M(t) · rest, decomposed.

use crate::{Animation, Scene, SceneError, Track};
use glam::{Mat4, Quat, Vec3};
use serde_json::{Value, json};
use std::collections::BTreeMap;

/// Where an imported instance came from: its glTF node, and the transform under that node
/// (a GPU-instancing copy's, else identity).
#[derive(Clone, Copy, Debug)]
pub(crate) struct InstanceSource {
    pub node: usize,
    pub below: Mat4,
}

/// One node's animated channels: key times and values.
#[derive(Default)]
struct NodeKeys {
    translation: Option<(Vec<f32>, Vec<Vec3>, bool)>,
    rotation: Option<(Vec<f32>, Vec<Quat>, bool)>,
}

fn sample_vec3(keys: &(Vec<f32>, Vec<Vec3>, bool), t: f32) -> Vec3 {
    let (times, values, step) = keys;
    let (a, b, f) = bracket(times, t);
    if *step {
        values[a]
    } else {
        values[a].lerp(values[b], f)
    }
}

fn sample_quat(keys: &(Vec<f32>, Vec<Quat>, bool), t: f32) -> Quat {
    let (times, values, step) = keys;
    let (a, b, f) = bracket(times, t);
    if *step {
        values[a]
    } else {
        values[a].slerp(values[b], f).normalize()
    }
}

/// The keys around `t` and the fraction between them (held outside the range).
fn bracket(times: &[f32], t: f32) -> (usize, usize, f32) {
    let n = times.len();
    if t <= times[0] {
        return (0, 0, 0.0);
    }
    if t >= times[n - 1] {
        return (n - 1, n - 1, 0.0);
    }
    let b = times.partition_point(|&k| k <= t);
    (
        b - 1,
        b,
        (t - times[b - 1]) / (times[b] - times[b - 1]).max(1e-12),
    )
}

/// The scene's animation from the document's first animation, and warnings.
pub(crate) fn import(
    path: &std::path::Path,
    doc: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    sources: &[InstanceSource],
    rest: &[Mat4],
) -> Result<(Option<Animation>, Vec<String>), SceneError> {
    let mut warnings = vec![];
    let Some(anim) = doc.animations().next() else {
        return Ok((None, warnings));
    };
    let count = doc.animations().count();
    if count > 1 {
        warnings.push(format!(
            "the file has {count} animations: lightlab plays the first ('{}')",
            anim.name().unwrap_or("unnamed")
        ));
    }
    let keys = read_channels(path, &anim, buffers, &mut warnings)?;
    if keys.is_empty() {
        return Ok((None, warnings));
    }
    let mut parent = vec![None; doc.nodes().len()];
    for n in doc.nodes() {
        for c in n.children() {
            parent[c.index()] = Some(n.index());
        }
    }
    let statics: Vec<Mat4> = doc
        .nodes()
        .map(|n| Mat4::from_cols_array_2d(&n.transform().matrix()))
        .collect();
    let local = |n: usize, t: f32| -> Mat4 {
        let Some(k) = keys.get(&n) else {
            return statics[n];
        };
        let (s, r, tr) = statics[n].to_scale_rotation_translation();
        let tr = k.translation.as_ref().map_or(tr, |x| sample_vec3(x, t));
        let r = k.rotation.as_ref().map_or(r, |x| sample_quat(x, t));
        Mat4::from_scale_rotation_translation(s, r, tr)
    };
    let fps = extras_fps(&anim).unwrap_or(24.0);
    let end = keys
        .values()
        .flat_map(|k| {
            let a = k.translation.iter().filter_map(|x| x.0.last());
            a.chain(k.rotation.iter().filter_map(|x| x.0.last()))
                .copied()
                .collect::<Vec<_>>()
        })
        .fold(0.0f32, f32::max);
    let frames = ((end * fps).round() as u32).max(1);
    let mut tracks = vec![];
    let mut scaled = false;
    for (i, src) in sources.iter().enumerate() {
        let mut path_nodes = vec![src.node];
        while let Some(p) = parent[*path_nodes.last().expect("non-empty")] {
            path_nodes.push(p);
        }
        let driven: Vec<&NodeKeys> = path_nodes.iter().filter_map(|n| keys.get(n)).collect();
        if driven.is_empty() {
            continue;
        }
        let mut times: Vec<f32> = (0..=frames).map(|k| k as f32 / fps).collect();
        for k in &driven {
            let t = k.translation.iter().map(|x| (&x.0, x.2));
            for (ts, step) in t.chain(k.rotation.iter().map(|x| (&x.0, x.2))) {
                times.extend(ts);
                if step {
                    times.extend(ts.iter().skip(1).map(|t| t - 1e-4));
                }
            }
        }
        times.retain(|t| *t >= 0.0);
        times.sort_by(f32::total_cmp);
        times.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
        let inv_rest = rest[i].inverse();
        let mut t = Track {
            instance: i,
            times: vec![],
            translations: vec![],
            rotations: vec![],
        };
        for &time in &times {
            let world = path_nodes
                .iter()
                .rev()
                .fold(Mat4::IDENTITY, |m, &n| m * local(n, time))
                * src.below;
            let (s, r, tr) = (world * inv_rest).to_scale_rotation_translation();
            scaled |= (s - Vec3::ONE).abs().max_element() > 1e-3;
            t.times.push(time);
            t.translations.push(tr);
            t.rotations.push(r.normalize());
        }
        tracks.push(t);
    }
    if scaled {
        warnings.push(
            "animation: instances that change size are moved rigidly (scale is ignored)".into(),
        );
    }
    let a = Animation {
        fps,
        frames,
        tracks,
    };
    a.check(rest.len()).map_err(|problem| SceneError::Content {
        path: path.into(),
        what: format!("animation '{}'", anim.name().unwrap_or("0")),
        problem,
    })?;
    Ok((Some(a), warnings))
}

fn extras_fps(anim: &gltf::Animation) -> Option<f32> {
    let raw = anim.extras().as_ref()?;
    let v: Value = serde_json::from_str(raw.get()).ok()?;
    let fps = v.get("lightlab")?.get("fps")?.as_f64()? as f32;
    (fps.is_finite() && fps > 0.0).then_some(fps)
}

/// The translation and rotation keys of each driven node.
fn read_channels(
    path: &std::path::Path,
    anim: &gltf::Animation,
    buffers: &[gltf::buffer::Data],
    warnings: &mut Vec<String>,
) -> Result<BTreeMap<usize, NodeKeys>, SceneError> {
    use gltf::animation::{Interpolation, util::ReadOutputs};
    let bad = |what: String| SceneError::Content {
        path: path.into(),
        what: format!("animation '{}'", anim.name().unwrap_or("0")),
        problem: what,
    };
    let mut keys: BTreeMap<usize, NodeKeys> = BTreeMap::new();
    let (mut cubic, mut scale) = (false, false);
    for ch in anim.channels() {
        let node = ch.target().node().index();
        let interp = ch.sampler().interpolation();
        let reader = ch.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
        let times: Vec<f32> = reader
            .read_inputs()
            .ok_or_else(|| bad("a channel's key times cannot be read".into()))?
            .collect();
        if times.is_empty()
            || times.iter().any(|t| !t.is_finite())
            || times.windows(2).any(|w| w[1] <= w[0])
        {
            return Err(bad("key times must be finite and increasing".into()));
        }
        let step = interp == Interpolation::Step;
        // Cubic splines store (in-tangent, value, out-tangent) per key.
        let pick = |k: usize| {
            if interp == Interpolation::CubicSpline {
                3 * k + 1
            } else {
                k
            }
        };
        cubic |= interp == Interpolation::CubicSpline;
        let outputs = reader
            .read_outputs()
            .ok_or_else(|| bad("a channel's values cannot be read".into()))?;
        let entry = keys.entry(node).or_default();
        match outputs {
            ReadOutputs::Translations(it) => {
                let all: Vec<Vec3> = it.map(Vec3::from_array).collect();
                let v: Option<Vec<Vec3>> = (0..times.len())
                    .map(|k| all.get(pick(k)).copied())
                    .collect();
                let v = v.ok_or_else(|| bad("fewer translations than key times".into()))?;
                entry.translation = Some((times, v, step));
            }
            ReadOutputs::Rotations(it) => {
                let all: Vec<Quat> = it.into_f32().map(Quat::from_array).collect();
                let v: Option<Vec<Quat>> = (0..times.len())
                    .map(|k| all.get(pick(k)).map(|q| q.normalize()))
                    .collect();
                let v = v.ok_or_else(|| bad("fewer rotations than key times".into()))?;
                entry.rotation = Some((times, v, step));
            }
            ReadOutputs::Scales(_) => scale = true,
            ReadOutputs::MorphTargetWeights(_) => {}
        }
    }
    keys.retain(|_, k| k.translation.is_some() || k.rotation.is_some());
    if cubic {
        warnings.push("animation: cubic-spline keys are interpolated linearly".into());
    }
    if scale {
        warnings.push("animation: scale channels are ignored (lightlab's motion is rigid)".into());
    }
    Ok(keys)
}

/// Adds an accessor of floats: (data, components, glTF type, with min and max) → its index.
pub(crate) type AddFloats<'a> = dyn FnMut(&[f32], usize, &str, bool) -> usize + 'a;

/// Write `scene`'s animation: the driven instance nodes become TRS nodes; returns the
/// `animations` array (None without an animation). `floats(data, comps, type, minmax)` adds an
/// accessor.
pub(crate) fn export(scene: &Scene, nodes: &mut [Value], floats: &mut AddFloats) -> Option<Value> {
    let a = scene.animation.as_ref()?;
    let mut samplers = vec![];
    let mut channels = vec![];
    for tr in &a.tracks {
        let rest = scene.instances[tr.instance].transform;
        let (s0, _, _) = rest.to_scale_rotation_translation();
        let (mut ts, mut rs) = (vec![], vec![]);
        for k in 0..tr.times.len() {
            let m = Mat4::from_rotation_translation(tr.rotations[k], tr.translations[k]) * rest;
            let (_, r, t) = m.to_scale_rotation_translation();
            ts.extend(t.to_array());
            rs.extend(r.normalize().to_array());
        }
        let (_, r0, t0) = rest.to_scale_rotation_translation();
        let node = &mut nodes[tr.instance];
        if let Some(o) = node.as_object_mut() {
            o.remove("matrix");
        }
        node["translation"] = json!(t0.to_array());
        node["rotation"] = json!(r0.normalize().to_array());
        node["scale"] = json!(s0.to_array());
        let input = floats(&tr.times, 1, "SCALAR", true);
        for (path, data, kind) in [("translation", &ts, "VEC3"), ("rotation", &rs, "VEC4")] {
            let output = floats(data, if kind == "VEC3" { 3 } else { 4 }, kind, false);
            samplers.push(json!({ "input": input, "output": output, "interpolation": "LINEAR" }));
            channels.push(json!({ "sampler": samplers.len() - 1,
                "target": { "node": tr.instance, "path": path } }));
        }
    }
    Some(
        json!([{ "name": "lightlab", "samplers": samplers, "channels": channels,
        "extras": { "lightlab": { "fps": a.fps, "frames": a.frames } } }]),
    )
}

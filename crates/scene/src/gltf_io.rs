//! glTF 2.0 import and export (`.gltf` with external or embedded buffers, and `.glb`).
//!
//! Import reads the default scene's node tree (world transforms composed), triangle primitives
//! (POSITION, NORMAL, TANGENT, TEXCOORD_0/1, COLOR_0, indices; strips and fans converted),
//! EXT_mesh_gpu_instancing, metallic–roughness materials with KHR_materials_emissive_strength,
//! KHR_materials_specular, KHR_materials_diffuse_transmission, KHR_materials_transmission,
//! KHR_materials_ior, KHR_materials_volume (its thickness factor only) and
//! KHR_materials_anisotropy (strength and rotation; the texture is not read), textures with
//! KHR_texture_transform, perspective cameras (a node's scale scales znear and zfar) and
//! KHR_lights_punctual.
//!
//! lightlab additions live in `extras` so other tools ignore them harmlessly:
//! - a directional light's `extras.angularDiameter` (radians);
//! - the scene's `extras.lightlab.environment = { uri, intensity }`, an equirectangular EXR/HDR
//!   next to the glTF file (glTF has no ratified equirectangular environment extension);
//! - a decimated mesh's `extras.lightlab.detailSource` = the index of the glTF mesh it was
//!   simplified from (loaded even when no node shows it), for detail baking;
//! - a camera's `extras.lightlab.lens = { model, aperture, focusDistance, thickness, scale }`
//!   (`CameraLens`);
//! - a material's `extras.lightlab.brdf` (a `BrdfModel` name), `conductor`, `sway` and
//!   `lafortune` = [Cx, Cy, Cz].
//!
//! Export writes one binary blob (GLB chunk, or `<stem>.bin` beside a `.gltf`) holding all
//! geometry and the textures as PNG, plus `<stem>.env.exr` when the scene has an environment.
//! The JSON is written by hand with serde_json (rather than the gltf-json builder types) to keep
//! full control of extensions and extras. All files are written atomically.

use crate::model::*;
use crate::{LoadOptions, SceneError};
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use lightlab_core::color::srgb_encode;
use lightlab_core::image::{Image, LdrSettings};
use serde_json::{Value, json};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The extensions lightlab reads; files that *require* any other are rejected.
/// The deepest node hierarchy lightlab loads (real files nest a few dozen levels).
pub const MAX_NODE_DEPTH: usize = 1024;
/// The most triangles a scene may draw, instances counted (the GPU flattens instances, so this
/// bounds its vertex buffers: about 10 GB).
pub const MAX_TRIANGLES: u64 = 100_000_000;

pub const SUPPORTED_EXTENSIONS: [&str; 10] = [
    "KHR_lights_punctual",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_volume",
    "KHR_texture_transform",
    "EXT_mesh_gpu_instancing",
    "KHR_materials_emissive_strength",
    "KHR_materials_specular",
    "KHR_materials_diffuse_transmission",
    "KHR_materials_anisotropy",
];

fn gltf_err(path: &Path, e: impl std::fmt::Display) -> SceneError {
    // The gltf crate's validation errors say "invalid glTF: " themselves.
    let message = e.to_string();
    SceneError::Gltf {
        path: path.into(),
        message: message
            .strip_prefix("invalid glTF: ")
            .unwrap_or(&message)
            .to_string(),
    }
}

/// Import a `.gltf` or `.glb` file and validate it.
pub fn import(path: &Path, opts: LoadOptions) -> Result<Scene, SceneError> {
    let bytes = std::fs::read(path).map_err(|e| SceneError::Io {
        path: path.into(),
        source: e,
    })?;
    import_slice(path, &bytes, opts)
}

/// Import the bytes of a `.gltf` or `.glb` file that lives at `path` (relative URIs resolve
/// beside it; errors name it).
pub fn import_slice(path: &Path, bytes: &[u8], opts: LoadOptions) -> Result<Scene, SceneError> {
    // Check required extensions on the raw JSON first, for a clearer message than the
    // validator's.
    check_required_extensions(path, bytes)?;
    let relaxed = without_required(bytes).map_err(|m| gltf_err(path, m))?;
    let gltf = gltf::Gltf::from_slice(relaxed.as_deref().unwrap_or(bytes))
        .map_err(|e| gltf_err(path, e))?;
    let gltf::Gltf { document, blob } = gltf;
    let inputs = crate::gltf_input::read(path, &document, blob, opts)?;
    let mut scene = Importer {
        path,
        opts,
        doc: &document,
        buffers: &inputs.buffers,
        images: inputs.images.into_iter().map(Some).collect(),
        scene: Scene::default(),
        mesh_map: HashMap::new(),
        sources: vec![],
        tex_map: HashMap::new(),
        skipped: 0,
        instanced_triangles: 0,
        luminaire: None,
    }
    .run()?;
    scene.name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    crate::validate::validate(&mut scene, path, opts)?;
    if scene.cameras.is_empty() {
        // Files without a camera still render: frame the scene.
        scene.cameras.extend(scene.framing_camera());
    }
    Ok(scene)
}

fn check_required_extensions(path: &Path, bytes: &[u8]) -> Result<(), SceneError> {
    let json_bytes: &[u8] = if bytes.starts_with(b"glTF") {
        glb_json(bytes).map_err(|m| gltf_err(path, m))?
    } else {
        bytes
    };
    let v: Value = serde_json::from_slice(json_bytes).map_err(|e| gltf_err(path, e))?;
    check_attribute_indices(path, &v)?;
    check_image_sources(path, &v)?;
    if let Some(req) = v.get("extensionsRequired").and_then(|r| r.as_array()) {
        for e in req.iter().filter_map(|e| e.as_str()) {
            if !SUPPORTED_EXTENSIONS.contains(&e) {
                return Err(SceneError::UnsupportedExtension {
                    path: path.into(),
                    extension: e.into(),
                });
            }
        }
    }
    Ok(())
}

/// The extensions lightlab reads that the gltf crate's validator refuses as *required* (it
/// knows only its own features' extensions).
const REQUIRED_FOR_LIGHTLAB: [&str; 5] = [
    "EXT_mesh_gpu_instancing",
    "KHR_materials_volume",
    "KHR_materials_specular",
    "KHR_materials_diffuse_transmission",
    "KHR_materials_anisotropy",
];

/// The file with [`REQUIRED_FOR_LIGHTLAB`] taken out of `extensionsRequired` (after
/// `check_required_extensions` accepted it), so that the gltf crate parses it; None when there
/// is nothing to take out. A GLB is rebuilt around the new JSON chunk.
fn without_required(bytes: &[u8]) -> Result<Option<Vec<u8>>, String> {
    let glb = bytes.starts_with(b"glTF");
    let json = if glb { glb_json(bytes)? } else { bytes };
    let mut v: Value = serde_json::from_slice(json).map_err(|e| e.to_string())?;
    let Some(req) = v
        .get_mut("extensionsRequired")
        .and_then(|r| r.as_array_mut())
    else {
        return Ok(None);
    };
    let before = req.len();
    req.retain(|e| {
        !e.as_str()
            .is_some_and(|e| REQUIRED_FOR_LIGHTLAB.contains(&e))
    });
    if req.len() == before {
        return Ok(None);
    }
    let mut text = serde_json::to_vec(&v).map_err(|e| e.to_string())?;
    if !glb {
        return Ok(Some(text));
    }
    // Header, the JSON chunk padded with spaces to 4 bytes, then the rest as it was.
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let rest = &bytes[(20 + json.len()).next_multiple_of(4).min(bytes.len())..];
    let total = 12 + 8 + text.len() + rest.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&text);
    out.extend_from_slice(rest);
    Ok(Some(out))
}

/// The JSON chunk of a GLB, after checking the header and chunk lengths (the `gltf` crate
/// subtracts the header size from the stated length before comparing, and overflows on a
/// length under 12).
fn glb_json(bytes: &[u8]) -> Result<&[u8], String> {
    let word = |k: usize| {
        bytes
            .get(k..k + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
            .ok_or_else(|| "truncated GLB header".to_string())
    };
    let (version, total, json_len) = (word(4)?, word(8)?, word(12)?);
    if version != 2 {
        return Err(format!("GLB version {version} (lightlab reads version 2)"));
    }
    if total < 20 || total > bytes.len() {
        return Err(format!(
            "the GLB header says {total} bytes, the file has {}",
            bytes.len()
        ));
    }
    if bytes.get(16..20) != Some(b"JSON") {
        return Err("the first GLB chunk is not JSON".into());
    }
    let json = bytes
        .get(20..20usize.saturating_add(json_len))
        .filter(|_| 20 + json_len <= total)
        .ok_or_else(|| "truncated GLB JSON chunk".to_string())?;
    let bin = (20 + json_len).next_multiple_of(4);
    if bin + 8 <= total {
        let bin_len = word(bin)?;
        if bin.saturating_add(8).saturating_add(bin_len) > total {
            return Err(format!(
                "the GLB's second chunk says {bin_len} bytes, past the end of the file"
            ));
        }
    }
    Ok(json)
}

/// Every image has a `uri`, or a `bufferView` with a `mimeType`, as glTF requires (the `gltf`
/// crate unwraps both).
fn check_image_sources(path: &Path, v: &Value) -> Result<(), SceneError> {
    let images = v.get("images").and_then(Value::as_array);
    for (i, img) in images.into_iter().flatten().enumerate() {
        let ok = match (img.get("uri"), img.get("bufferView")) {
            (Some(u), None) => u.is_string(),
            (None, Some(_)) => img.get("mimeType").is_some_and(Value::is_string),
            _ => false,
        };
        if !ok {
            return Err(gltf_err(
                path,
                format!("image {i} needs a uri, or a bufferView with a mimeType (not both)"),
            ));
        }
    }
    Ok(())
}

/// Every primitive's attribute and index accessors exist: the `gltf` crate's validator indexes
/// the POSITION accessor before checking that it exists, and panics on a file where it does
/// not.
fn check_attribute_indices(path: &Path, v: &Value) -> Result<(), SceneError> {
    let accessors = v
        .get("accessors")
        .and_then(Value::as_array)
        .map_or(0, Vec::len);
    let meshes = v.get("meshes").and_then(Value::as_array);
    for (mi, mesh) in meshes.into_iter().flatten().enumerate() {
        let prims = mesh.get("primitives").and_then(Value::as_array);
        for (pi, prim) in prims.into_iter().flatten().enumerate() {
            let attrs = prim.get("attributes").and_then(Value::as_object);
            let refs = attrs
                .into_iter()
                .flatten()
                .map(|(k, a)| (k.as_str(), a))
                .chain(prim.get("indices").map(|i| ("indices", i)));
            for (name, a) in refs {
                if a.as_u64().is_none_or(|i| i as usize >= accessors) {
                    return Err(gltf_err(
                        path,
                        format!(
                            "mesh {mi} primitive {pi}: {name} names accessor {a}, which does not \
                             exist ({accessors} accessors)"
                        ),
                    ));
                }
            }
        }
    }
    Ok(())
}

/// A node to read: its parent's world transform, its depth, the names above it and the
/// luminaire it belongs to.
type NodeVisit<'a> = (gltf::Node<'a>, Mat4, usize, Vec<String>, Option<String>);

struct Importer<'a> {
    path: &'a Path,
    opts: LoadOptions,
    doc: &'a gltf::Document,
    buffers: &'a [gltf::buffer::Data],
    /// Decoded images, each taken by the first texture that uses it.
    images: Vec<Option<image::DynamicImage>>,
    scene: Scene,
    /// (glTF mesh, primitive) → lightlab mesh.
    mesh_map: HashMap<(usize, usize), usize>,
    /// The glTF node of each instance (what animations drive).
    sources: Vec<crate::gltf_anim::InstanceSource>,
    /// (glTF image, sRGB) → lightlab texture.
    tex_map: HashMap<(usize, bool), usize>,
    /// Primitives skipped (points, lines).
    skipped: usize,
    /// Triangles of the instances so far.
    instanced_triangles: u64,
    /// The luminaire of the node being read (its own `extras.lightlab.luminaire` or one
    /// above it).
    luminaire: Option<String>,
}

/// A camera's glTF object, its lens in `extras.lightlab.lens`.
fn camera_json(c: &Camera) -> Value {
    let mut persp = json!({ "yfov": c.yfov, "znear": c.znear });
    if let Some(f) = c.zfar {
        persp["zfar"] = json!(f);
    }
    let mut cam = json!({ "name": c.name, "type": "perspective", "perspective": persp });
    if let Some(l) = &c.lens {
        let mut lens = json!({ "model": l.model });
        for (key, v) in [
            ("aperture", l.aperture),
            ("focusDistance", l.focus_distance),
            ("thickness", l.thickness),
            ("scale", l.scale),
        ] {
            if let Some(v) = v {
                lens[key] = json!(v);
            }
        }
        cam["extras"] = json!({ "lightlab": { "lens": lens } });
    }
    cam
}

/// A camera's `extras.lightlab.lens` (see `CameraLens`); a prescription path is made
/// relative to the glTF file's folder.
fn camera_lens(cam: &gltf::Camera, path: &Path) -> Result<Option<CameraLens>, SceneError> {
    let Some(v) = extras_json(cam.extras()).and_then(|e| e.get("lightlab")?.get("lens").cloned())
    else {
        return Ok(None);
    };
    let name = cam.name().unwrap_or("camera");
    let bad = |m: String| gltf_err(path, format!("camera '{name}': extras.lightlab.lens {m}"));
    let model = v
        .get("model")
        .and_then(Value::as_str)
        .ok_or_else(|| bad("has no model (pinhole, thin-lens, thick-lens or lens:FILE)".into()))?;
    let number = |key: &str| -> Result<Option<f32>, SceneError> {
        match v.get(key) {
            None => Ok(None),
            Some(x) => x
                .as_f64()
                .filter(|f| f.is_finite())
                .map(|f| Some(f as f32))
                .ok_or_else(|| bad(format!("{key} is not a number"))),
        }
    };
    let model = match model.strip_prefix("lens:") {
        Some(file) if Path::new(file).extension().is_some() => {
            let dir = path.parent().unwrap_or(Path::new("."));
            format!("lens:{}", dir.join(file).display())
        }
        _ => model.to_string(),
    };
    Ok(Some(CameraLens {
        model,
        aperture: number("aperture")?,
        focus_distance: number("focusDistance")?,
        thickness: number("thickness")?,
        scale: number("scale")?,
    }))
}

fn extras_json(extras: &gltf::json::Extras) -> Option<Value> {
    extras
        .as_ref()
        .and_then(|raw| serde_json::from_str(raw.get()).ok())
}

/// A light's photometric profile: `extras.lightlab.ies` names an IES LM-63 or EULUMDAT
/// (`.ldt`) file relative to the glTF's folder.
fn light_profile(
    extras: Option<&Value>,
    path: &Path,
    index: usize,
) -> Result<Option<std::sync::Arc<crate::photometry::Goniometric>>, SceneError> {
    let Some(name) = extras.and_then(|e| e.get("lightlab")?.get("ies")) else {
        return Ok(None);
    };
    let bad = |problem: String| SceneError::Content {
        path: path.into(),
        what: format!("light {index} extras.lightlab.ies"),
        problem,
    };
    let name = name
        .as_str()
        .ok_or_else(|| bad("must be a file name (a string)".into()))?;
    let folder = path.parent().unwrap_or(Path::new("."));
    crate::photometry::read(&folder.join(name))
        .map(|g| Some(std::sync::Arc::new(g)))
        .map_err(|e| bad(e.0))
}

/// The file a goniometric light's profile is exported to, beside the glTF `<stem>.gltf`.
fn profile_uri(stem: &str, light: usize) -> String {
    format!("{stem}.light{light}.ies")
}

/// A texture reference's UV set and KHR_texture_transform (`value` is the extension's
/// object; None = untransformed): its `texCoord` overrides the reference's.
fn uv_transform(value: Option<&Value>, tex_coord: u32) -> Result<(u32, UvTransform), String> {
    let Some(v) = value else {
        return Ok((tex_coord, UvTransform::IDENTITY));
    };
    let floats = |key: &str, default: [f32; 2]| -> Result<[f32; 2], String> {
        match v.get(key) {
            None => Ok(default),
            Some(Value::Array(a)) if a.len() == 2 => {
                let f = |x: &Value| x.as_f64().map(|x| x as f32).filter(|x| x.is_finite());
                match (f(&a[0]), f(&a[1])) {
                    (Some(x), Some(y)) => Ok([x, y]),
                    _ => Err(format!("{key} is not two finite numbers")),
                }
            }
            Some(_) => Err(format!("{key} is not two numbers")),
        }
    };
    let offset = floats("offset", [0.0, 0.0])?;
    let scale = floats("scale", [1.0, 1.0])?;
    let rotation = match v.get("rotation") {
        None => 0.0,
        Some(r) => r
            .as_f64()
            .map(|r| r as f32)
            .filter(|r| r.is_finite())
            .ok_or("rotation is not a finite number")?,
    };
    let set = match v.get("texCoord") {
        None => tex_coord,
        Some(t) => t.as_u64().ok_or("texCoord is not a whole number")? as u32,
    };
    let t = UvTransform::new(Vec2::from(offset), rotation, Vec2::from(scale));
    Ok((set, t))
}

/// Nodes for the groups instances sit under (`Instance::nodes`: names only, identity
/// transforms, so an instance's matrix stays its world transform); returns the scene's roots.
/// Instance nodes come first in `nodes`, one per instance.
fn group_nodes(scene: &Scene, nodes: &mut Vec<Value>) -> Vec<usize> {
    let instances = scene.instances.len();
    let mut groups: HashMap<Vec<String>, usize> = HashMap::new();
    let mut roots = vec![];
    let mut add_child = |nodes: &mut Vec<Value>, parent: Option<usize>, child: usize| match parent {
        Some(p) => {
            if !nodes[p]["children"].is_array() {
                nodes[p]["children"] = json!([]);
            }
            nodes[p]["children"]
                .as_array_mut()
                .expect("an array")
                .push(json!(child));
        }
        None => roots.push(child),
    };
    for (i, inst) in scene.instances.iter().enumerate() {
        let mut parent = None;
        for k in 0..inst.nodes.len() {
            let key = inst.nodes[..=k].to_vec();
            let g = match groups.get(&key) {
                Some(&g) => g,
                None => {
                    nodes.push(json!({ "name": inst.nodes[k] }));
                    let g = nodes.len() - 1;
                    groups.insert(key, g);
                    add_child(nodes, parent, g);
                    g
                }
            };
            parent = Some(g);
        }
        add_child(nodes, parent, i);
    }
    // Cameras and lights (after the instances, before the groups) hang from the root.
    let groups_start = nodes.len() - groups.len();
    let mut out = roots;
    out.extend(instances..groups_start);
    out
}

/// A node's name, or `nodeN` for an unnamed one.
fn node_name(node: &gltf::Node) -> String {
    node.name()
        .map(String::from)
        .unwrap_or_else(|| format!("node{}", node.index()))
}

impl Importer<'_> {
    /// Mesh `extras.lightlab.detailSource` = the index of the glTF mesh it was decimated from;
    /// that mesh (its first primitive) is loaded even when no node shows it.
    fn detail_sources(&mut self, default_material: usize) -> Result<(), SceneError> {
        let mut loaded: Vec<((usize, usize), usize)> =
            self.mesh_map.iter().map(|(k, v)| (*k, *v)).collect();
        loaded.sort();
        for ((mi, _), id) in loaded {
            let Some(gmesh) = self.doc.meshes().nth(mi) else {
                continue;
            };
            let Some(src) = extras_json(gmesh.extras())
                .and_then(|v| v.get("lightlab")?.get("detailSource")?.as_u64())
            else {
                continue;
            };
            let bad = |problem: String| SceneError::Content {
                path: self.path.into(),
                what: format!("mesh {mi}"),
                problem,
            };
            let src_mesh = self
                .doc
                .meshes()
                .nth(src as usize)
                .filter(|_| src as usize != mi)
                .ok_or_else(|| {
                    bad(format!(
                        "extras.lightlab.detailSource {src} is not another mesh"
                    ))
                })?;
            let key = (src_mesh.index(), 0);
            let sid = match self.mesh_map.get(&key) {
                Some(&s) => s,
                None => {
                    let prim = src_mesh
                        .primitives()
                        .next()
                        .ok_or_else(|| bad(format!("detail source mesh {src} has no primitive")))?;
                    let m = self
                        .primitive(&src_mesh, &prim, default_material)?
                        .ok_or_else(|| bad(format!("detail source mesh {src} is not triangles")))?;
                    self.scene.meshes.push(m);
                    let s = self.scene.meshes.len() - 1;
                    self.mesh_map.insert(key, s);
                    s
                }
            };
            self.scene.meshes[id].detail_source = Some(sid);
        }
        Ok(())
    }

    fn run(mut self) -> Result<Scene, SceneError> {
        for m in self.doc.materials() {
            let mat = self.material(&m)?;
            self.scene.materials.push(mat);
        }
        // Primitives without a material get a default one, appended at the end if used.
        let default_material = self.scene.materials.len();
        let gscene = self
            .doc
            .default_scene()
            .or_else(|| self.doc.scenes().next())
            .ok_or_else(|| gltf_err(self.path, "the file contains no scene"))?;
        self.nodes(&gscene, default_material)?;
        let rest: Vec<Mat4> = self.scene.instances.iter().map(|i| i.transform).collect();
        let (animation, warnings) =
            crate::gltf_anim::import(self.path, self.doc, self.buffers, &self.sources, &rest)?;
        self.scene.animation = animation;
        self.scene.warnings.extend(warnings);
        self.ignored_features();
        if self.skipped > 0 {
            self.scene.warnings.push(format!(
                "skipped {} primitive instance(s) of points or lines (lightlab renders triangles)",
                self.skipped
            ));
        }
        self.detail_sources(default_material)?;
        if self
            .scene
            .meshes
            .iter()
            .any(|m| m.material == default_material)
        {
            self.scene.materials.push(Material {
                name: "default".into(),
                ..Default::default()
            });
        }
        if let Some(env) = extras_json(gscene.extras())
            .and_then(|v| v.get("lightlab")?.get("environment").cloned())
        {
            let uri = env
                .get("uri")
                .and_then(|u| u.as_str())
                .ok_or_else(|| gltf_err(self.path, "extras.lightlab.environment has no uri"))?;
            let file = crate::gltf_input::resolve(self.path, uri, self.opts)
                .map_err(|m| gltf_err(self.path, format!("extras.lightlab.environment: {m}")))?;
            let image = Image::read(&file)
                .map_err(|e| gltf_err(self.path, format!("extras.lightlab.environment: {e}")))?;
            let intensity = env.get("intensity").and_then(|v| v.as_f64()).unwrap_or(1.0) as f32;
            self.scene.environment = Some(Environment { image, intensity });
        }
        Ok(self.scene)
    }

    /// One warning per feature of the file that lightlab does not render yet, so that nothing
    /// is dropped in silence.
    fn ignored_features(&mut self) {
        const EXTENSIONS: [(&str, &str); 1] = [(
            "KHR_materials_volume",
            "volumes are ignored (transmissive surfaces are thin interfaces)",
        )];
        let used: Vec<&str> = self.doc.extensions_used().collect();
        for (ext, what) in EXTENSIONS {
            if used.contains(&ext) {
                self.scene.warnings.push(format!("{ext}: {what}"));
            }
        }
        let prims = || {
            self.doc
                .meshes()
                .flat_map(|m| m.primitives().collect::<Vec<_>>())
        };
        if self.doc.materials().any(|m| {
            m.transmission()
                .and_then(|t| t.transmission_texture())
                .is_some()
        }) {
            self.scene.warnings.push(
                "KHR_materials_transmission: transmission textures are ignored (the factor applies)"
                    .into(),
            );
        }
        if self.doc.skins().next().is_some() || prims().any(|p| p.morph_targets().next().is_some())
        {
            self.scene
                .warnings
                .push("skins and morph targets are ignored: meshes render in bind pose".into());
        }
    }

    fn texture(&mut self, tex: gltf::Texture, srgb: bool) -> Result<usize, SceneError> {
        let img_index = tex.source().index();
        if let Some(&t) = self.tex_map.get(&(img_index, srgb)) {
            return Ok(t);
        }
        let name = tex
            .source()
            .name()
            .map(String::from)
            .unwrap_or_else(|| format!("image{img_index}"));
        // The decoded image moves into the texture (no copy for RGBA8); an image used both as
        // colour and as data is the rare second texture, copied from the first.
        let texels = match self.images[img_index].take() {
            Some(img) => {
                let (w, h) = (img.width(), img.height());
                if w == 0 || h == 0 {
                    return Err(SceneError::Content {
                        path: self.path.into(),
                        what: format!("image '{name}'"),
                        problem: "has zero size".into(),
                    });
                }
                // Grey spreads to RGB and grey–alpha keeps its alpha, as glTF reads them.
                let texels = match img {
                    image::DynamicImage::ImageLuma16(_)
                    | image::DynamicImage::ImageLumaA16(_)
                    | image::DynamicImage::ImageRgb16(_)
                    | image::DynamicImage::ImageRgba16(_) => {
                        Texels::Rgba16(img.into_rgba16().into_raw())
                    }
                    _ => Texels::Rgba8(img.into_rgba8().into_raw()),
                };
                (w, h, texels)
            }
            None => {
                let t = self
                    .tex_map
                    .iter()
                    .find(|((i, _), _)| *i == img_index)
                    .map(|(_, &t)| &self.scene.textures[t])
                    .expect("an image taken belongs to a texture");
                (t.width, t.height, t.texels.clone())
            }
        };
        let (width, height, texels) = texels;
        self.scene.textures.push(Texture {
            name,
            width,
            height,
            texels,
            srgb,
        });
        let id = self.scene.textures.len() - 1;
        self.tex_map.insert((img_index, srgb), id);
        Ok(id)
    }

    fn material(&mut self, m: &gltf::Material) -> Result<Material, SceneError> {
        let pbr = m.pbr_metallic_roughness();
        let (doc, path) = (self.doc, self.path);
        let name = m.name().unwrap_or("material").to_string();
        let mut tref = |tex: gltf::Texture,
                        tex_coord: u32,
                        transform: Option<&Value>,
                        srgb: bool|
         -> Result<TextureRef, SceneError> {
            let (uv_set, transform) = uv_transform(transform, tex_coord).map_err(|e| {
                gltf_err(
                    self.path,
                    format!("material '{name}': KHR_texture_transform {e}"),
                )
            })?;
            Ok(TextureRef {
                texture: self.texture(tex, srgb)?,
                uv_set,
                transform,
            })
        };
        const TT: &str = "KHR_texture_transform";
        // The gltf crate parses the extension of a texture info itself (its feature is on so
        // that files requiring it load); a normal texture's stays raw JSON.
        let mut info = |i: Option<gltf::texture::Info>, srgb| {
            i.map(|i| {
                let t = i.texture_transform().map(|t| {
                    let mut v = json!({ "offset": t.offset(), "rotation": t.rotation(),
                        "scale": t.scale() });
                    if let Some(c) = t.tex_coord() {
                        v["texCoord"] = json!(c);
                    }
                    v
                });
                tref(i.texture(), i.tex_coord(), t.as_ref(), srgb)
            })
            .transpose()
        };
        let base_color_texture = info(pbr.base_color_texture(), true)?;
        let metallic_roughness_texture = info(pbr.metallic_roughness_texture(), false)?;
        let emissive_texture = info(m.emissive_texture(), true)?;
        let (normal_texture, normal_scale) = match m.normal_texture() {
            Some(n) => (
                Some(tref(
                    n.texture(),
                    n.tex_coord(),
                    n.extension_value(TT),
                    false,
                )?),
                n.scale(),
            ),
            None => (None, 1.0),
        };
        let dt = m.extension_value("KHR_materials_diffuse_transmission");
        let transmission = dt
            .and_then(|v| v.get("diffuseTransmissionFactor")?.as_f64())
            .unwrap_or(0.0) as f32;
        let transmission_texture = match dt.and_then(|v| v.get("diffuseTransmissionTexture")) {
            None => None,
            Some(info) => {
                let index = info.get("index").and_then(|i| i.as_u64());
                let tex = index.and_then(|i| doc.textures().nth(i as usize));
                let Some(tex) = tex else {
                    return Err(gltf_err(
                        path,
                        format!(
                            "material '{}': diffuseTransmissionTexture has no valid index",
                            m.name().unwrap_or("material")
                        ),
                    ));
                };
                let tex_coord = info.get("texCoord").and_then(|t| t.as_u64()).unwrap_or(0);
                let transform = info.get("extensions").and_then(|e| e.get(TT));
                Some(tref(tex, tex_coord as u32, transform, false)?)
            }
        };
        let aniso = m.extension_value("KHR_materials_anisotropy");
        let aniso_f = |k: &str| {
            aniso
                .and_then(|v| v.get(k)?.as_f64())
                .filter(|x| x.is_finite())
        };
        if aniso.and_then(|v| v.get("anisotropyTexture")).is_some() {
            self.scene.warnings.push(format!(
                "material '{}': KHR_materials_anisotropy's anisotropyTexture is not read (its \
                 strength and rotation are)",
                m.name().unwrap_or("material")
            ));
        }
        let x = material_extras(m, self.path)?;
        Ok(Material {
            name: m.name().unwrap_or("material").into(),
            base_color: Vec4::from_array(pbr.base_color_factor()),
            base_color_texture,
            metallic: pbr.metallic_factor(),
            roughness: pbr.roughness_factor(),
            metallic_roughness_texture,
            specular: m.specular().map(|s| s.specular_factor()).unwrap_or(1.0),
            emissive: Vec3::from_array(m.emissive_factor()),
            emissive_strength: m.emissive_strength().unwrap_or(1.0),
            emissive_texture,
            normal_texture,
            normal_scale,
            alpha_mode: match m.alpha_mode() {
                gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
                gltf::material::AlphaMode::Mask => AlphaMode::Mask {
                    cutoff: m.alpha_cutoff().unwrap_or(0.5),
                },
                gltf::material::AlphaMode::Blend => AlphaMode::Blend,
            },
            double_sided: m.double_sided(),
            transmission,
            transmission_texture,
            sway: x.sway,
            brdf: x.brdf,
            specular_transmission: m
                .transmission()
                .map_or(0.0, |t| t.transmission_factor().clamp(0.0, 1.0)),
            ior: m
                .ior()
                .filter(|n| n.is_finite() && *n >= 1.0)
                .unwrap_or(1.5),
            conductor: x.conductor,
            thickness: m
                .extension_value("KHR_materials_volume")
                .and_then(|v| v.get("thicknessFactor")?.as_f64())
                .filter(|t| t.is_finite() && *t > 0.0)
                .unwrap_or(0.0) as f32,
            anisotropy: aniso_f("anisotropyStrength").unwrap_or(0.0).clamp(0.0, 1.0) as f32,
            anisotropy_rotation: aniso_f("anisotropyRotation").unwrap_or(0.0) as f32,
            lafortune: x.lafortune,
        })
    }

    /// One node's meshes, camera and light under `parent`; returns its world transform.
    fn node(
        &mut self,
        node: &gltf::Node,
        parent: Mat4,
        above: &[String],
        default_material: usize,
    ) -> Result<Mat4, SceneError> {
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        let node_name = node_name(node);
        if let Some(mesh) = node.mesh() {
            // EXT_mesh_gpu_instancing: the mesh is drawn once per instance transform.
            let below = self.gpu_instances(node)?.unwrap_or(vec![Mat4::IDENTITY]);
            let copies: Vec<Mat4> = below.iter().map(|t| world * *t).collect();
            for prim in mesh.primitives() {
                let key = (mesh.index(), prim.index());
                let id = match self.mesh_map.get(&key) {
                    Some(&id) => id,
                    None => {
                        let Some(m) = self.primitive(&mesh, &prim, default_material)? else {
                            self.skipped += copies.len();
                            continue;
                        };
                        self.scene.meshes.push(m);
                        let id = self.scene.meshes.len() - 1;
                        self.mesh_map.insert(key, id);
                        id
                    }
                };
                self.instanced_triangles +=
                    self.scene.meshes[id].triangle_count() as u64 * copies.len() as u64;
                if self.instanced_triangles > MAX_TRIANGLES {
                    return Err(SceneError::Content {
                        path: self.path.into(),
                        what: format!("node {} ('{node_name}')", node.index()),
                        problem: format!(
                            "brings the scene's instanced triangles past {MAX_TRIANGLES}, more \
                             than lightlab renders"
                        ),
                    });
                }
                for (k, &transform) in copies.iter().enumerate() {
                    self.sources.push(crate::gltf_anim::InstanceSource {
                        node: node.index(),
                        below: below[k],
                    });
                    self.scene.instances.push(Instance {
                        name: match copies.len() {
                            1 => node_name.clone(),
                            _ => format!("{node_name}#{k}"),
                        },
                        mesh: id,
                        transform,
                        nodes: above.to_vec(),
                        luminaire: self.luminaire.clone(),
                    });
                }
            }
        }
        // Cameras and lights use the node's rigid part. A camera node's scale scales its clip
        // distances, as inverting the full node transform does in engines (three.js, Bevy):
        // znear and zfar are lengths in the node's space.
        let (scale, rot, pos) = world.to_scale_rotation_translation();
        let rigid = Mat4::from_rotation_translation(rot.normalize(), pos);
        let clip_scale = Some(scale.x * scale.y * scale.z)
            .map(|v| v.abs().cbrt())
            .filter(|s| s.is_finite() && *s > 0.0)
            .unwrap_or(1.0);
        if let Some(cam) = node.camera() {
            match cam.projection() {
                gltf::camera::Projection::Perspective(p) => self.scene.cameras.push(Camera {
                    name: cam.name().map(String::from).unwrap_or(node_name.clone()),
                    transform: rigid,
                    yfov: p.yfov(),
                    znear: p.znear() * clip_scale,
                    zfar: p.zfar().map(|f| f * clip_scale),
                    lens: camera_lens(&cam, self.path)?,
                }),
                gltf::camera::Projection::Orthographic(_) => {
                    // Orthographic cameras are not used by any lightlab technique; skipped.
                }
            }
        }
        if let Some(light) = node.light() {
            use gltf::khr_lights_punctual::Kind;
            let extras = extras_json(light.extras());
            let kind = match light.kind() {
                Kind::Point => LightKind::Point,
                Kind::Spot {
                    inner_cone_angle,
                    outer_cone_angle,
                } => LightKind::Spot {
                    inner_cone: inner_cone_angle,
                    outer_cone: outer_cone_angle,
                },
                Kind::Directional => LightKind::Directional {
                    angular_diameter: extras
                        .as_ref()
                        .and_then(|e| e.get("angularDiameter")?.as_f64())
                        .unwrap_or(0.0) as f32,
                },
            };
            let kind = match light_profile(extras.as_ref(), self.path, light.index())? {
                Some(profile) => {
                    if !matches!(kind, LightKind::Point) {
                        self.scene.warnings.push(format!(
                            "light {}: a photometric profile on a {} light; read as a point light \
                             with the profile",
                            light.index(),
                            if matches!(kind, LightKind::Spot { .. }) {
                                "spot"
                            } else {
                                "directional"
                            }
                        ));
                    }
                    LightKind::Goniometric {
                        profile,
                        c0: rigid.transform_vector3(Vec3::X).normalize(),
                    }
                }
                None => kind,
            };
            self.scene.lights.push(Light {
                name: light.name().map(String::from).unwrap_or(node_name.clone()),
                kind,
                color: Vec3::from_array(light.color()),
                intensity: light.intensity(),
                position: pos,
                direction: rigid.transform_vector3(-Vec3::Z).normalize(),
                range: light.range(),
            });
        }
        Ok(world)
    }

    /// The node's EXT_mesh_gpu_instancing transforms (TRANSLATION, ROTATION, SCALE accessors;
    /// rotations as floats or normalised bytes or shorts); None without the extension.
    fn gpu_instances(&self, node: &gltf::Node) -> Result<Option<Vec<Mat4>>, SceneError> {
        let Some(ext) = node.extension_value("EXT_mesh_gpu_instancing") else {
            return Ok(None);
        };
        let bad = |problem: String| SceneError::Content {
            path: self.path.into(),
            what: format!("node {} EXT_mesh_gpu_instancing", node.index()),
            problem,
        };
        let attributes = ext
            .get("attributes")
            .and_then(Value::as_object)
            .ok_or_else(|| bad("has no attributes".into()))?;
        let read = |name: &str, dims: usize| -> Result<Option<Vec<Vec4>>, SceneError> {
            let Some(index) = attributes.get(name) else {
                return Ok(None);
            };
            let accessor = index
                .as_u64()
                .and_then(|i| self.doc.accessors().nth(i as usize))
                .ok_or_else(|| bad(format!("{name} names no accessor")))?;
            let values = read_vectors(&accessor, dims, self.buffers)
                .ok_or_else(|| bad(format!("{name} is not a readable VEC{dims} accessor")))?;
            if values.iter().any(|v| !v.is_finite()) {
                return Err(bad(format!("{name} has NaN or infinite values")));
            }
            Ok(Some(values))
        };
        let (t, r, s) = (
            read("TRANSLATION", 3)?,
            read("ROTATION", 4)?,
            read("SCALE", 3)?,
        );
        let counts: Vec<usize> = [&t, &r, &s]
            .iter()
            .filter_map(|v| v.as_ref().map(Vec::len))
            .collect();
        let Some(&n) = counts.first() else {
            return Err(bad("has none of TRANSLATION, ROTATION and SCALE".into()));
        };
        if counts.iter().any(|&c| c != n) {
            return Err(bad("its attributes differ in count".into()));
        }
        let at =
            |v: &Option<Vec<Vec4>>, i: usize, default: Vec4| v.as_ref().map_or(default, |v| v[i]);
        Ok(Some(
            (0..n)
                .map(|i| {
                    let q = Quat::from_vec4(at(&r, i, Vec4::W)).normalize();
                    Mat4::from_scale_rotation_translation(
                        at(&s, i, Vec4::ONE).truncate(),
                        if q.is_finite() { q } else { Quat::IDENTITY },
                        at(&t, i, Vec4::ZERO).truncate(),
                    )
                })
                .collect(),
        ))
    }

    /// Every node of the scene, depth first without recursion: a node reached twice (a cycle,
    /// or a node with two parents, both invalid glTF) or deeper than [`MAX_NODE_DEPTH`] is an
    /// error rather than a stack overflow.
    fn nodes(&mut self, scene: &gltf::Scene, default_material: usize) -> Result<(), SceneError> {
        let mut seen = vec![false; self.doc.nodes().len()];
        let mut stack: Vec<NodeVisit> = scene
            .nodes()
            .map(|n| (n, Mat4::IDENTITY, 1, vec![], None))
            .collect();
        stack.reverse();
        while let Some((node, parent, depth, above, luminaire)) = stack.pop() {
            let what = || format!("node {} ('{}')", node.index(), node.name().unwrap_or(""));
            if std::mem::replace(&mut seen[node.index()], true) {
                return Err(SceneError::Content {
                    path: self.path.into(),
                    what: what(),
                    problem: "is reached twice: the node hierarchy has a cycle or a node with \
                              two parents"
                        .into(),
                });
            }
            if depth > MAX_NODE_DEPTH {
                return Err(SceneError::Content {
                    path: self.path.into(),
                    what: what(),
                    problem: format!("lies deeper than {MAX_NODE_DEPTH} levels of nodes"),
                });
            }
            let extras = extras_json(node.extras());
            let lightlab = extras.as_ref().and_then(|e| e.get("lightlab"));
            self.luminaire = lightlab
                .and_then(|l| Some(l.get("luminaire")?.as_str()?.to_string()))
                .or(luminaire);
            if let Some(f) = lightlab.and_then(|l| l.get("luminaireFocus")) {
                self.luminaire_focus(f, what())?;
            }
            let world = self.node(&node, parent, &above, default_material)?;
            let children: Vec<_> = node.children().collect();
            let mut path = above;
            path.push(node_name(&node));
            for child in children.into_iter().rev() {
                stack.push((
                    child,
                    world,
                    depth + 1,
                    path.clone(),
                    self.luminaire.clone(),
                ));
            }
        }
        Ok(())
    }

    /// A node's `extras.lightlab.luminaireFocus`, for the luminaire it belongs to (the first
    /// node's value wins).
    fn luminaire_focus(&mut self, f: &Value, what: String) -> Result<(), SceneError> {
        let bad = |problem: &str| SceneError::Content {
            path: self.path.into(),
            what: what.clone(),
            problem: problem.into(),
        };
        let Some(name) = self.luminaire.clone() else {
            return Err(bad(
                "has extras.lightlab.luminaireFocus but belongs to no luminaire (set \
                 extras.lightlab.luminaire on it or a node above it)",
            ));
        };
        let d = f
            .as_f64()
            .filter(|d| d.is_finite() && *d > 0.0)
            .ok_or_else(|| {
                bad("extras.lightlab.luminaireFocus must be a positive distance in metres")
            })?;
        self.scene.luminaire_focus.entry(name).or_insert(d as f32);
        Ok(())
    }

    /// One primitive as a triangle mesh; None for points and lines (skipped, and counted by
    /// the caller).
    fn primitive(
        &self,
        mesh: &gltf::Mesh,
        prim: &gltf::Primitive,
        default_material: usize,
    ) -> Result<Option<Mesh>, SceneError> {
        let name = match (mesh.name(), mesh.primitives().len()) {
            (Some(n), 1) => n.to_string(),
            (Some(n), _) => format!("{n}.{}", prim.index()),
            (None, _) => format!("mesh{}.{}", mesh.index(), prim.index()),
        };
        let geo = |problem: &str| SceneError::Geometry {
            path: self.path.into(),
            mesh: name.clone(),
            problem: problem.into(),
        };
        use gltf::mesh::Mode;
        match prim.mode() {
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan => {}
            mode if self.opts.strict => {
                return Err(geo(&format!(
                    "primitive mode {mode:?} is not triangles (without --strict such \
                     primitives are skipped with a warning)"
                )));
            }
            _ => return Ok(None),
        }
        let reader = prim.reader(|b| self.buffers.get(b.index()).map(|d| &d.0[..]));
        let positions: Vec<Vec3> = reader
            .read_positions()
            .ok_or_else(|| geo("has no POSITION attribute"))?
            .map(Vec3::from_array)
            .collect();
        let normals = reader
            .read_normals()
            .map(|n| n.map(Vec3::from_array).collect())
            .unwrap_or_default();
        let tangents = reader
            .read_tangents()
            .map(|t| t.map(Vec4::from_array).collect())
            .unwrap_or_default();
        let uv0 = reader
            .read_tex_coords(0)
            .map(|t| t.into_f32().map(Vec2::from_array).collect())
            .unwrap_or_default();
        let uv1 = reader
            .read_tex_coords(1)
            .map(|t| t.into_f32().map(Vec2::from_array).collect());
        let colors = reader
            .read_colors(0)
            .map(|c| c.into_rgba_f32().map(Vec4::from_array).collect())
            .unwrap_or_default();
        let indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None => (0..positions.len() as u32).collect(),
        };
        let indices = triangle_list(prim.mode(), indices);
        Ok(Some(Mesh {
            name,
            positions,
            normals,
            tangents,
            uv0,
            uv1,
            colors,
            indices,
            material: prim.material().index().unwrap_or(default_material),
            detail_source: None,
        }))
    }
}

/// An accessor of `dims` (3 or 4) components as vectors (w = 0 for three): floats, or
/// normalised signed bytes or shorts (as EXT_mesh_gpu_instancing allows for rotations). None
/// for any other type or an unreadable buffer.
fn read_vectors(
    accessor: &gltf::Accessor,
    dims: usize,
    buffers: &[gltf::buffer::Data],
) -> Option<Vec<Vec4>> {
    use gltf::accessor::{DataType, Dimensions, Iter};
    let want = match dims {
        3 => Dimensions::Vec3,
        _ => Dimensions::Vec4,
    };
    if accessor.dimensions() != want {
        return None;
    }
    let get = |b: gltf::Buffer| buffers.get(b.index()).map(|d| &d.0[..]);
    let norm = accessor.normalized();
    match (accessor.data_type(), dims) {
        (DataType::F32, 3) => Some(
            Iter::<[f32; 3]>::new(accessor.clone(), get)?
                .map(|v| Vec3::from_array(v).extend(0.0))
                .collect(),
        ),
        (DataType::F32, _) => Some(
            Iter::<[f32; 4]>::new(accessor.clone(), get)?
                .map(Vec4::from_array)
                .collect(),
        ),
        (DataType::I16, 4) if norm => Some(
            Iter::<[i16; 4]>::new(accessor.clone(), get)?
                .map(|v| Vec4::from_array(v.map(|x| (x as f32 / 32767.0).max(-1.0))))
                .collect(),
        ),
        (DataType::I8, 4) if norm => Some(
            Iter::<[i8; 4]>::new(accessor.clone(), get)?
                .map(|v| Vec4::from_array(v.map(|x| (x as f32 / 127.0).max(-1.0))))
                .collect(),
        ),
        _ => None,
    }
}

/// A texture reference as glTF textureInfo (with its KHR_texture_transform).
fn texture_info(r: &TextureRef) -> Value {
    let mut v = json!({ "index": r.texture, "texCoord": r.uv_set });
    if !r.transform.is_identity() {
        let (offset, rotation, scale) = r.transform.decompose();
        v["extensions"] = json!({ "KHR_texture_transform": {
            "offset": offset.to_array(), "rotation": rotation, "scale": scale.to_array()
        }});
    }
    v
}

fn use_ext_in(used: &mut Vec<&'static str>, e: &'static str) {
    if !used.contains(&e) {
        used.push(e);
    }
}

/// One material as glTF JSON; the extensions it uses are added to `used`.
fn material_json(m: &Material, used: &mut Vec<&'static str>) -> Value {
    let mut pbr = json!({
        "baseColorFactor": m.base_color.to_array(),
        "metallicFactor": m.metallic,
        "roughnessFactor": m.roughness,
    });
    if let Some(r) = &m.base_color_texture {
        pbr["baseColorTexture"] = texture_info(r);
    }
    if let Some(r) = &m.metallic_roughness_texture {
        pbr["metallicRoughnessTexture"] = texture_info(r);
    }
    let mut v =
        json!({ "name": m.name, "pbrMetallicRoughness": pbr, "doubleSided": m.double_sided });
    // glTF requires emissiveFactor ≤ 1: fold any excess into emissive_strength.
    let peak = m.emissive.max_element();
    let (factor, strength) = if peak > 1.0 {
        (m.emissive / peak, m.emissive_strength * peak)
    } else {
        (m.emissive, m.emissive_strength)
    };
    v["emissiveFactor"] = json!(factor.to_array());
    if let Some(r) = &m.emissive_texture {
        v["emissiveTexture"] = texture_info(r);
    }
    if let Some(r) = &m.normal_texture {
        v["normalTexture"] = texture_info(r);
        v["normalTexture"]["scale"] = json!(m.normal_scale);
    }
    match m.alpha_mode {
        AlphaMode::Opaque => {}
        AlphaMode::Mask { cutoff } => {
            v["alphaMode"] = json!("MASK");
            v["alphaCutoff"] = json!(cutoff);
        }
        AlphaMode::Blend => v["alphaMode"] = json!("BLEND"),
    }
    let mut exts = serde_json::Map::new();
    if strength != 1.0 {
        use_ext_in(used, "KHR_materials_emissive_strength");
        exts.insert(
            "KHR_materials_emissive_strength".into(),
            json!({ "emissiveStrength": strength }),
        );
    }
    if m.specular != 1.0 {
        use_ext_in(used, "KHR_materials_specular");
        exts.insert(
            "KHR_materials_specular".into(),
            json!({ "specularFactor": m.specular }),
        );
    }
    if m.specular_transmission != 0.0 {
        use_ext_in(used, "KHR_materials_transmission");
        exts.insert(
            "KHR_materials_transmission".into(),
            json!({ "transmissionFactor": m.specular_transmission }),
        );
    }
    if m.thickness > 0.0 {
        use_ext_in(used, "KHR_materials_volume");
        exts.insert(
            "KHR_materials_volume".into(),
            json!({ "thicknessFactor": m.thickness }),
        );
    }
    if m.ior != 1.5 {
        use_ext_in(used, "KHR_materials_ior");
        exts.insert("KHR_materials_ior".into(), json!({ "ior": m.ior }));
    }
    if m.transmission != 0.0 {
        use_ext_in(used, "KHR_materials_diffuse_transmission");
        let mut dt = json!({ "diffuseTransmissionFactor": m.transmission });
        if let Some(r) = &m.transmission_texture {
            dt["diffuseTransmissionTexture"] = texture_info(r);
        }
        exts.insert("KHR_materials_diffuse_transmission".into(), dt);
    }
    if m.anisotropy != 0.0 || m.anisotropy_rotation != 0.0 {
        use_ext_in(used, "KHR_materials_anisotropy");
        exts.insert(
            "KHR_materials_anisotropy".into(),
            json!({ "anisotropyStrength": m.anisotropy, "anisotropyRotation": m.anisotropy_rotation }),
        );
    }
    if !exts.is_empty() {
        v["extensions"] = Value::Object(exts);
    }
    let mut extras = serde_json::Map::new();
    if m.brdf != BrdfModel::Pbr {
        extras.insert("brdf".into(), json!(m.brdf.name()));
    }
    if m.lafortune != Vec3::new(-1.0, -1.0, 1.0) {
        extras.insert("lafortune".into(), json!(m.lafortune.to_array()));
    }
    if m.sway != 0.0 {
        extras.insert("sway".into(), json!(m.sway));
    }
    if let Some(c) = &m.conductor {
        let v = match c.preset_name() {
            Some(name) => json!(name),
            None => json!({ "eta": c.eta.to_array(), "k": c.k.to_array() }),
        };
        extras.insert("conductor".into(), v);
    }
    if !extras.is_empty() {
        v["extras"] = json!({ "lightlab": extras });
    }
    v
}

/// Three finite numbers as a vector.
fn vec3_of(v: &Value) -> Option<Vec3> {
    let a = v.as_array().filter(|a| a.len() == 3)?;
    let x: Vec<f32> = a
        .iter()
        .filter_map(|x| x.as_f64())
        .map(|x| x as f32)
        .collect();
    (x.len() == 3 && x.iter().all(|x| x.is_finite())).then(|| Vec3::new(x[0], x[1], x[2]))
}

/// A material's `extras.lightlab` settings (wind sway, BRDF model, Lafortune lobe, conductor).
struct MaterialExtras {
    sway: f32,
    brdf: BrdfModel,
    lafortune: Vec3,
    conductor: Option<Conductor>,
}

fn material_extras(m: &gltf::Material, path: &Path) -> Result<MaterialExtras, SceneError> {
    let name = m.name().unwrap_or("material");
    let lightlab = extras_json(m.extras()).and_then(|v| v.get("lightlab").cloned());
    let get = |key: &str| lightlab.as_ref().and_then(|v| v.get(key));
    let sway = get("sway").and_then(|v| v.as_f64()).unwrap_or(0.0) as f32;
    let brdf = match get("brdf").and_then(|v| v.as_str()) {
        None => BrdfModel::Pbr,
        Some(b) => BrdfModel::parse(b).ok_or_else(|| {
            gltf_err(
                path,
                format!(
                    "material '{name}': unknown extras.lightlab.brdf '{b}' (known: {})",
                    BrdfModel::NAMES.join(", ")
                ),
            )
        })?,
    };
    let lafortune = match get("lafortune") {
        None => Vec3::new(-1.0, -1.0, 1.0),
        Some(v) => vec3_of(v).ok_or_else(|| {
            gltf_err(
                path,
                format!(
                    "material '{name}': extras.lightlab.lafortune must be three finite numbers \
                     [Cx, Cy, Cz]"
                ),
            )
        })?,
    };
    let conductor = conductor_extras(m).map_err(|e| {
        gltf_err(
            path,
            format!("material '{name}': extras.lightlab.conductor {e}"),
        )
    })?;
    Ok(MaterialExtras {
        sway,
        brdf,
        lafortune,
        conductor,
    })
}

/// `extras.lightlab.conductor` of a material: a preset name or `{"eta": [r,g,b], "k": [r,g,b]}`
/// (the error completes "extras.lightlab.conductor …").
fn conductor_extras(m: &gltf::Material) -> Result<Option<Conductor>, String> {
    let Some(v) =
        extras_json(m.extras()).and_then(|v| v.get("lightlab")?.get("conductor").cloned())
    else {
        return Ok(None);
    };
    let names = || {
        Conductor::PRESETS
            .iter()
            .map(|(n, _)| *n)
            .collect::<Vec<_>>()
            .join(", ")
    };
    let rgb = |key: &str| -> Result<Vec3, String> {
        let a = v
            .get(key)
            .and_then(|a| a.as_array())
            .filter(|a| a.len() == 3)
            .ok_or_else(|| format!("needs '{key}' as three numbers"))?;
        let mut out = [0f32; 3];
        for (o, x) in out.iter_mut().zip(a) {
            *o = x
                .as_f64()
                .ok_or_else(|| format!("'{key}' holds a non-number"))? as f32;
        }
        Ok(Vec3::from_array(out))
    };
    let c = match &v {
        serde_json::Value::String(name) => Conductor::preset(name)
            .ok_or_else(|| format!("'{name}' is not a known metal (known: {})", names()))?,
        serde_json::Value::Object(_) => Conductor {
            eta: rgb("eta")?,
            k: rgb("k")?,
        },
        _ => {
            return Err(format!(
                "must be a metal's name ({}) or {{\"eta\": [r, g, b], \"k\": [r, g, b]}}",
                names()
            ));
        }
    };
    if !c.is_valid() {
        return Err("needs finite eta > 0 and k >= 0 in every channel".into());
    }
    Ok(Some(c))
}

/// A texture as PNG: 8- and 16-bit texels as stored (an import–export round trip keeps them
/// exactly), float texels encoded to 8 bits (sRGB-encoded for colour textures).
fn texture_png(t: &Texture) -> Result<Vec<u8>, image::ImageError> {
    let (w, h) = (t.width, t.height);
    let img = match &t.texels {
        Texels::Rgba8(v) => image::RgbaImage::from_raw(w, h, v.clone()).map(Into::into),
        Texels::Rgba16(v) => image::ImageBuffer::<image::Rgba<u16>, _>::from_raw(w, h, v.clone())
            .map(image::DynamicImage::ImageRgba16),
        Texels::Rgba32F(v) => {
            let enc = |x: f32| {
                if t.srgb {
                    srgb_encode(x)
                } else {
                    x.clamp(0.0, 1.0)
                }
            };
            let q = |x: f32| (x * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8;
            let rgba = v
                .iter()
                .flat_map(|v| {
                    [
                        q(enc(v.x)),
                        q(enc(v.y)),
                        q(enc(v.z)),
                        q(v.w.clamp(0.0, 1.0)),
                    ]
                })
                .collect();
            image::RgbaImage::from_raw(w, h, rgba).map(Into::into)
        }
    };
    let img: image::DynamicImage = img.ok_or_else(|| {
        image::ImageError::Parameter(image::error::ParameterError::from_kind(
            image::error::ParameterErrorKind::DimensionMismatch,
        ))
    })?;
    let mut png = vec![];
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)?;
    Ok(png)
}

/// The triangles of a primitive as a list: strips and fans converted, with the winding of
/// glTF's definition (strip triangle i: i, i+1, i+2 with odd i swapped; fan: 0, i+1, i+2).
fn triangle_list(mode: gltf::mesh::Mode, idx: Vec<u32>) -> Vec<u32> {
    use gltf::mesh::Mode;
    let n = idx.len().saturating_sub(2);
    match mode {
        Mode::TriangleStrip => (0..n)
            .flat_map(|i| {
                if i % 2 == 0 {
                    [idx[i], idx[i + 1], idx[i + 2]]
                } else {
                    [idx[i + 1], idx[i], idx[i + 2]]
                }
            })
            .collect(),
        Mode::TriangleFan => (0..n)
            .flat_map(|i| [idx[0], idx[i + 1], idx[i + 2]])
            .collect(),
        _ => idx,
    }
}

// ----------------------------------------------------------------------------------------------
// Export

/// What a caller adds to an exported document: PNG images (embedded, each with a texture
/// appended after the scene's own) and `extras` on the instance nodes and the scene. The light-map
/// exporter of `lightlab-bake` uses it to ship its pages with the meshes.
#[derive(Clone, Debug, Default)]
pub struct ExportExtras {
    /// (name, PNG bytes); texture index = scene texture count + position here.
    pub images: Vec<(String, Vec<u8>)>,
    /// `extras` of instance node i (by instance index); None leaves the node without.
    pub instance_extras: Vec<Option<Value>>,
    /// `extras` merged into the scene's.
    pub scene_extras: Option<Value>,
}

/// Write `scene` as `.glb` or `.gltf` (by extension). See the module documentation.
pub fn export(scene: &Scene, path: &Path) -> Result<(), SceneError> {
    export_with(scene, path, &ExportExtras::default())
}

/// [`export`] with caller-supplied images and extras.
pub fn export_with(scene: &Scene, path: &Path, extras: &ExportExtras) -> Result<(), SceneError> {
    let ext = lightlab_core::image::extension(path);
    if ext != "glb" && ext != "gltf" {
        return Err(SceneError::Content {
            path: path.into(),
            what: "output".into(),
            problem: "the file name must end in .glb or .gltf".into(),
        });
    }
    let stem = stem_of(path);
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut w = Writer::default();
    let env_uri = format!("{stem}.env.exr");
    let mut root = w.document(
        scene,
        scene.environment.as_ref().map(|_| env_uri.as_str()),
        path,
        extras,
    )?;
    // Every file is complete before any is renamed into place, the glTF last: a failure
    // leaves no orphan .bin or .env.exr.
    let mut files = vec![];
    if let Some(env) = &scene.environment {
        let p = dir.join(&env_uri);
        let bytes = env.image.encode(&p, LdrSettings::default())?;
        files.push((p, bytes));
    }
    for (i, l) in scene.lights.iter().enumerate() {
        if let LightKind::Goniometric { profile, .. } = &l.kind {
            let text = crate::photometry::ies::write(profile, &l.name);
            files.push((dir.join(profile_uri(&stem, i)), text.into_bytes()));
        }
    }
    while !w.bin.len().is_multiple_of(4) {
        w.bin.push(0);
    }
    root["buffers"] = json!([{ "byteLength": w.bin.len() }]);
    if ext == "glb" {
        let mut json_bytes = serde_json::to_vec(&root).expect("serialisable");
        while !json_bytes.len().is_multiple_of(4) {
            json_bytes.push(b' ');
        }
        let total = 12 + 8 + json_bytes.len() + 8 + w.bin.len();
        if total > u32::MAX as usize {
            return Err(SceneError::Content {
                path: path.into(),
                what: "output".into(),
                problem: format!(
                    "{total} bytes exceed the 4 GiB limit of a .glb; write a .gltf instead"
                ),
            });
        }
        let mut out = Vec::with_capacity(total);
        out.extend(b"glTF");
        out.extend(2u32.to_le_bytes());
        out.extend((total as u32).to_le_bytes());
        out.extend((json_bytes.len() as u32).to_le_bytes());
        out.extend(b"JSON");
        out.extend(&json_bytes);
        out.extend((w.bin.len() as u32).to_le_bytes());
        out.extend(b"BIN\0");
        out.extend(&w.bin);
        files.push((path.to_path_buf(), out));
    } else {
        let bin_uri = format!("{stem}.bin");
        root["buffers"][0]["uri"] = json!(bin_uri);
        files.push((dir.join(&bin_uri), std::mem::take(&mut w.bin)));
        let text = serde_json::to_vec_pretty(&root).expect("serialisable");
        files.push((path.to_path_buf(), text));
    }
    lightlab_core::atomic::write_all_atomic(&files)?;
    Ok(())
}

/// Instance `i`'s node: its mesh, transform, the caller's extras and its luminaire.
fn instance_node(scene: &Scene, i: usize, inst: &Instance, extras: &ExportExtras) -> Value {
    let mut node =
        json!({ "name": inst.name, "mesh": inst.mesh, "matrix": inst.transform.to_cols_array() });
    if let Some(Some(e)) = extras.instance_extras.get(i) {
        node["extras"] = e.clone();
    }
    if let Some(l) = &inst.luminaire {
        if !node["extras"].is_object() {
            node["extras"] = json!({});
        }
        if !node["extras"]["lightlab"].is_object() {
            node["extras"]["lightlab"] = json!({});
        }
        node["extras"]["lightlab"]["luminaire"] = json!(l);
        if let Some(f) = scene.luminaire_focus.get(l) {
            node["extras"]["lightlab"]["luminaireFocus"] = json!(f);
        }
    }
    node
}

/// A punctual light as `KHR_lights_punctual` describes it, and its node (the node's local frame
/// is the light's). `stem`: the exported file's stem, which names goniometric profiles.
fn light_json(l: &Light, i: usize, stem: &str) -> (Value, Value) {
    let mut v = json!({ "name": l.name, "color": l.color.to_array(), "intensity": l.intensity });
    match &l.kind {
        LightKind::Point => v["type"] = json!("point"),
        LightKind::Spot {
            inner_cone,
            outer_cone,
        } => {
            v["type"] = json!("spot");
            v["spot"] = json!({ "innerConeAngle": inner_cone, "outerConeAngle": outer_cone });
        }
        LightKind::Directional { angular_diameter } => {
            v["type"] = json!("directional");
            v["extras"] = json!({ "angularDiameter": angular_diameter });
        }
        LightKind::Goniometric { .. } => {
            v["type"] = json!("point");
            v["extras"] = json!({ "lightlab": { "ies": profile_uri(stem, i) } });
        }
    }
    if let Some(r) = l.range {
        v["range"] = json!(r);
    }
    // The node's local frame is the light's (−Z its direction; +X a goniometric
    // light's C0 plane).
    let rot = Quat::from_mat3(&l.local_frame().transpose());
    let m = Mat4::from_rotation_translation(rot, l.position);
    let node = json!({
        "name": l.name, "matrix": m.to_cols_array(),
        "extensions": { "KHR_lights_punctual": { "light": i } }
    });
    (v, node)
}

/// The file name of `path` without its extension ("scene" when it has none).
fn stem_of(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into())
}

#[derive(Default)]
struct Writer {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Writer {
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut v = json!({ "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len() });
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.bin.extend_from_slice(bytes);
        self.views.push(v);
        self.views.len() - 1
    }

    fn floats(&mut self, data: &[f32], comps: usize, kind: &str, minmax: bool) -> usize {
        self.floats_in(data, comps, kind, minmax, Some(34962))
    }

    /// [`Writer::floats`] in a buffer view without a target (animation keys).
    fn untargeted_floats(&mut self, data: &[f32], comps: usize, kind: &str, minmax: bool) -> usize {
        self.floats_in(data, comps, kind, minmax, None)
    }

    fn floats_in(
        &mut self,
        data: &[f32],
        comps: usize,
        kind: &str,
        minmax: bool,
        target: Option<u32>,
    ) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|f| f.to_le_bytes()).collect();
        let view = self.view(&bytes, target);
        let count = data.len() / comps;
        let mut a =
            json!({ "bufferView": view, "componentType": 5126, "count": count, "type": kind });
        if minmax {
            let mut mn = vec![f32::INFINITY; comps];
            let mut mx = vec![f32::NEG_INFINITY; comps];
            for c in data.chunks_exact(comps) {
                for k in 0..comps {
                    mn[k] = mn[k].min(c[k]);
                    mx[k] = mx[k].max(c[k]);
                }
            }
            a["min"] = json!(mn);
            a["max"] = json!(mx);
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    /// The scene's textures and the caller's images (light-maps) as PNG images in the binary
    /// blob, in that order.
    fn images(
        &mut self,
        scene: &Scene,
        path: &Path,
        extras: &ExportExtras,
    ) -> Result<Vec<Value>, SceneError> {
        let mut images = vec![];
        for t in &scene.textures {
            let png = texture_png(t).map_err(|e| SceneError::Content {
                path: path.into(),
                what: format!("texture '{}'", t.name),
                problem: e.to_string(),
            })?;
            let view = self.view(&png, None);
            images.push(json!({ "name": t.name, "bufferView": view, "mimeType": "image/png" }));
        }
        for (name, png) in &extras.images {
            let view = self.view(png, None);
            images.push(json!({ "name": name, "bufferView": view, "mimeType": "image/png" }));
        }
        Ok(images)
    }

    /// One mesh with its attributes and indices written to the blob.
    fn mesh_json(&mut self, m: &Mesh) -> Value {
        let flat = |v: &[Vec3]| v.iter().flat_map(|p| p.to_array()).collect::<Vec<f32>>();
        let mut attrs = serde_json::Map::new();
        attrs.insert(
            "POSITION".into(),
            json!(self.floats(&flat(&m.positions), 3, "VEC3", true)),
        );
        if !m.normals.is_empty() {
            attrs.insert(
                "NORMAL".into(),
                json!(self.floats(&flat(&m.normals), 3, "VEC3", false)),
            );
        }
        if !m.tangents.is_empty() {
            let t: Vec<f32> = m.tangents.iter().flat_map(|t| t.to_array()).collect();
            attrs.insert("TANGENT".into(), json!(self.floats(&t, 4, "VEC4", false)));
        }
        let uvs = |v: &[Vec2]| v.iter().flat_map(|p| p.to_array()).collect::<Vec<f32>>();
        if !m.uv0.is_empty() {
            attrs.insert(
                "TEXCOORD_0".into(),
                json!(self.floats(&uvs(&m.uv0), 2, "VEC2", false)),
            );
        }
        if let Some(uv1) = &m.uv1 {
            attrs.insert(
                "TEXCOORD_1".into(),
                json!(self.floats(&uvs(uv1), 2, "VEC2", false)),
            );
        }
        if !m.colors.is_empty() {
            let c: Vec<f32> = m.colors.iter().flat_map(|c| c.to_array()).collect();
            attrs.insert("COLOR_0".into(), json!(self.floats(&c, 4, "VEC4", false)));
        }
        let idx: Vec<u8> = m.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&idx, Some(34963));
        self.accessors.push(json!({
            "bufferView": view, "componentType": 5125, "count": m.indices.len(), "type": "SCALAR"
        }));
        let indices = self.accessors.len() - 1;
        let mut mesh = json!({
            "name": m.name,
            "primitives": [{ "attributes": attrs, "indices": indices, "material": m.material, "mode": 4 }]
        });
        if let Some(d) = m.detail_source {
            // glTF mesh i is scene mesh i.
            mesh["extras"] = json!({ "lightlab": { "detailSource": d } });
        }
        mesh
    }

    fn document(
        &mut self,
        scene: &Scene,
        env_uri: Option<&str>,
        path: &Path,
        extras: &ExportExtras,
    ) -> Result<Value, SceneError> {
        let mut used: Vec<&str> = vec![];
        let use_ext = |e: &'static str, used: &mut Vec<&str>| {
            if !used.contains(&e) {
                used.push(e);
            }
        };
        let images = self.images(scene, path, extras)?;
        // Caller images (light-maps) get sampler 1: bilinear, no mip-maps, clamped.
        let textures: Vec<Value> = (0..images.len())
            .map(|i| json!({ "source": i, "sampler": usize::from(i >= scene.textures.len()) }))
            .collect();
        if scene
            .materials
            .iter()
            .flat_map(|m| m.texture_refs())
            .any(|r| !r.transform.is_identity())
        {
            use_ext("KHR_texture_transform", &mut used);
        }
        let materials: Vec<Value> = scene
            .materials
            .iter()
            .map(|m| material_json(m, &mut used))
            .collect();
        let meshes: Vec<Value> = scene.meshes.iter().map(|m| self.mesh_json(m)).collect();
        let mut nodes: Vec<Value> = scene
            .instances
            .iter()
            .enumerate()
            .map(|(i, inst)| instance_node(scene, i, inst, extras))
            .collect();
        let animations = crate::gltf_anim::export(scene, &mut nodes, &mut |d, c, k, m| {
            self.untargeted_floats(d, c, k, m)
        });
        let mut cameras = vec![];
        for (i, c) in scene.cameras.iter().enumerate() {
            cameras.push(camera_json(c));
            nodes.push(
                json!({ "name": c.name, "camera": i, "matrix": c.transform.to_cols_array() }),
            );
        }
        let mut lights = vec![];
        for (i, l) in scene.lights.iter().enumerate() {
            let (light, node) = light_json(l, i, &stem_of(path));
            lights.push(light);
            nodes.push(node);
        }
        if !lights.is_empty() {
            use_ext("KHR_lights_punctual", &mut used);
        }
        let roots = group_nodes(scene, &mut nodes);
        let mut gscene = json!({ "name": scene.name, "nodes": roots });
        if let (Some(uri), Some(env)) = (env_uri, &scene.environment) {
            gscene["extras"] = json!({ "lightlab": { "environment": { "uri": uri, "intensity": env.intensity } } });
        }
        if let Some(Value::Object(add)) = &extras.scene_extras {
            if !gscene["extras"].is_object() {
                gscene["extras"] = json!({});
            }
            for (k, v) in add {
                gscene["extras"][k] = v.clone();
            }
        }
        let mut root = json!({
            "asset": { "version": "2.0", "generator": concat!("lightlab ", env!("CARGO_PKG_VERSION")) },
            "scene": 0,
            "scenes": [gscene],
            "nodes": nodes,
            "meshes": meshes,
            "materials": materials,
            "accessors": self.accessors,
            "bufferViews": self.views,
        });
        if !cameras.is_empty() {
            root["cameras"] = json!(cameras);
        }
        if let Some(a) = animations {
            root["animations"] = a;
        }
        if !images.is_empty() {
            root["images"] = json!(images);
            root["textures"] = json!(textures);
            root["samplers"] = json!([
                { "magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497 },
                { "magFilter": 9729, "minFilter": 9729, "wrapS": 33071, "wrapT": 33071 }
            ]);
        }
        if !lights.is_empty() {
            root["extensions"] = json!({ "KHR_lights_punctual": { "lights": lights } });
        }
        if !used.is_empty() {
            root["extensionsUsed"] = json!(used);
        }
        Ok(root)
    }
}

//! Writing and reading a baked light-map folder.
//!
//! ```text
//! DIR/manifest.json        what was baked, with which settings, the layout and the figures
//! DIR/lightmap-K.exr       page K, linear RGB E/π (32-bit float): the primary output
//! DIR/directional-K.exr   page K's directional ratios (directional bakes; see `gather`)
//! DIR/lightmap-K.png       page K tone-reproduced by Ward Larson's histogram adjustment
//!                          (Fuchs §3.3.5, one histogram over all pages) and gamma 2, as CaLight
//!                          stored its 8-bit light-maps (optional)
//! DIR/scene.glb            the scene with light-map UVs for other engines (optional): one mesh
//!                          per instance whose TEXCOORD_1 is already in page space, the PNG
//!                          pages embedded as images, and on every light-mapped node
//!                          `extras.lightmap = {page, texture, exr, uv_rect: [0,0,1,1], quantity}`
//!                          (the EXR beside the .glb holds the linear values; the embedded PNG
//!                          is the gamma-2 display version). In Bevy: read the node's
//!                          `GltfExtras`, load the EXR as the `Lightmap` image, `uv_rect` full.
//!                          Directional bakes add `directional_exr` (the ratios page).
//! ```
//!
//! The folder is written whole and replaces any earlier bake in one step; its manifest records
//! the size and checksum of every page, and [`read`] verifies them (see [`crate::folder`]).

use crate::layout::{Layout, unwrap_scene};
use crate::{BakeError, BakeSettings, BakeStats, Lightmaps};
use glam::Vec3;
use lightlab_core::color::WardLarson;
use lightlab_core::image::{Image, LdrSettings, write_atomic};
use lightlab_scene::Scene;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::Path;

pub use crate::folder::MANIFEST;
/// 2: the manifest carries the integrity record (bake id, size and CRC-32 of every file).
pub const FORMAT_VERSION: u32 = 2;
pub const FORMAT: &str = "lightlab-lightmaps";

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    pub format: String,
    pub version: u32,
    /// Scene name (a built-in name or the file it was loaded from).
    pub scene: String,
    /// The quantity stored.
    pub quantity: String,
    pub settings: BakeSettings,
    pub layout: Layout,
    pub stats: BakeStats,
    /// Page files, in page order (EXR).
    pub pages: Vec<String>,
    /// Tone-reproduced PNG pages, when written.
    pub png_pages: Vec<String>,
    /// Directional pages (luminance ratios of the three basis directions), when baked.
    #[serde(default)]
    pub directional_pages: Vec<String>,
    /// The glTF export with light-map UVs and pages, when written.
    #[serde(default)]
    pub gltf: Option<String>,
}

fn io(path: &Path, e: impl std::fmt::Display) -> BakeError {
    BakeError::Io(format!("{}: {e}", path.display()))
}

/// What [`write`] writes besides the EXR pages and the manifest.
#[derive(Clone, Copy, Debug, Default)]
pub struct Outputs {
    /// Tone-reproduced PNG pages.
    pub png: bool,
    /// `scene.glb` with light-map UVs and the PNG pages (implies `png`).
    pub gltf: bool,
}

/// Write a bake to `dir`, replacing the bake there as a whole (see [`crate::folder`]).
pub fn write(
    lm: &Lightmaps,
    dir: &Path,
    scene_name: &str,
    outputs: Outputs,
) -> Result<Manifest, BakeError> {
    crate::folder::write(dir, |stage| write_files(lm, stage, scene_name, outputs))
}

/// Every file of a light-map bake into `dir`; returns the manifest (written by the caller).
fn write_files(
    lm: &Lightmaps,
    dir: &Path,
    scene_name: &str,
    outputs: Outputs,
) -> Result<Manifest, BakeError> {
    let png = outputs.png || outputs.gltf;
    let mut pages = vec![];
    for (k, page) in lm.pages.iter().enumerate() {
        let name = format!("lightmap-{k}.exr");
        page.write(&dir.join(&name), LdrSettings::default())
            .map_err(|e| io(&dir.join(&name), e))?;
        pages.push(name);
    }
    let mut directional_pages = vec![];
    for (k, page) in lm.directional.iter().flatten().enumerate() {
        let name = format!("directional-{k}.exr");
        page.write(&dir.join(&name), LdrSettings::default())
            .map_err(|e| io(&dir.join(&name), e))?;
        directional_pages.push(name);
    }
    let mut png_pages = vec![];
    if png {
        let all: Vec<Vec3> = lm
            .pages
            .iter()
            .flat_map(|p| p.data.iter().copied())
            .collect();
        let mapped = WardLarson::default().apply(&all);
        let mut off = 0;
        for (k, page) in lm.pages.iter().enumerate() {
            let n = page.data.len();
            // Gamma 2 (CaLight's sqrt) over the [0, 1] output; written through the PNG writer
            // with clamping and no further tone curve. The PNG writer applies sRGB encoding,
            // so undo it: store sqrt(v) as the display value.
            let img = Image {
                width: page.width,
                height: page.height,
                data: mapped[off..off + n]
                    .iter()
                    .map(|v| {
                        v.max(Vec3::ZERO)
                            .to_array()
                            .map(|c| lightlab_core::color::srgb_decode(c.sqrt()))
                            .into()
                    })
                    .collect(),
            };
            off += n;
            let name = format!("lightmap-{k}.png");
            img.write(
                &dir.join(&name),
                LdrSettings {
                    exposure: 1.0,
                    tone: lightlab_core::color::ToneMap::Clamp,
                },
            )
            .map_err(|e| io(&dir.join(&name), e))?;
            png_pages.push(name);
        }
    }
    let gltf = if outputs.gltf {
        Some(write_gltf(lm, dir, &pages, &png_pages, &directional_pages)?)
    } else {
        None
    };
    Ok(Manifest {
        format: FORMAT.into(),
        version: FORMAT_VERSION,
        scene: scene_name.into(),
        quantity:
            "E/pi: incident irradiance over pi, linear Rec.709 RGB; radiance = albedo × value"
                .into(),
        settings: lm.settings.clone(),
        layout: lm.layout.clone(),
        stats: lm.stats.clone(),
        pages,
        png_pages,
        directional_pages,
        gltf,
    })
}

/// Write `bytes` to `path` atomically (temporary file, then rename).
pub(crate) fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), BakeError> {
    write_atomic(path, |mut f| {
        f.write_all(bytes)
            .map_err(|e| lightlab_core::image::ImageError::Io {
                path: path.into(),
                source: e,
            })
    })
    .map_err(|e| io(path, e))
}

/// The glTF file of a bake.
pub const GLTF: &str = "scene.glb";

/// The scene as glTF with page-space TEXCOORD_1 per instance and the PNG pages embedded.
fn write_gltf(
    lm: &Lightmaps,
    dir: &Path,
    exr_pages: &[String],
    png_pages: &[String],
    directional_pages: &[String],
) -> Result<String, BakeError> {
    use lightlab_scene::gltf_io::{ExportExtras, export_with};
    let mut scene = lm.scene.clone();
    let mut meshes = vec![];
    let mut kept: std::collections::HashMap<usize, usize> = Default::default();
    let mut extras = ExportExtras::default();
    let textures = scene.textures.len();
    for (i, inst) in scene.instances.iter_mut().enumerate() {
        let rect = lm.layout.instances.get(i).copied().flatten();
        let mesh = &lm.scene.meshes[inst.mesh];
        match (rect, &mesh.uv1) {
            (Some(r), Some(uv1)) => {
                let mut m = mesh.clone();
                m.name = format!("{}#{}", mesh.name, inst.name);
                m.uv1 = Some(uv1.iter().map(|&uv| r.page_uv(uv)).collect());
                meshes.push(m);
                inst.mesh = meshes.len() - 1;
                let k = r.page as usize;
                let mut e = serde_json::json!({
                    "lightmap": {
                        "page": k,
                        "texture": textures + k,
                        "exr": exr_pages[k],
                        "uv_rect": [0.0, 0.0, 1.0, 1.0],
                        "quantity": "E/pi (linear in the EXR; the embedded PNG is sqrt of Ward Larson's display value)",
                    }
                });
                if let Some(d) = directional_pages.get(k) {
                    e["lightmap"]["directional_exr"] = d.clone().into();
                }
                extras.instance_extras.push(Some(e));
            }
            _ => {
                let j = *kept.entry(inst.mesh).or_insert_with(|| {
                    meshes.push(mesh.clone());
                    meshes.len() - 1
                });
                inst.mesh = j;
                extras.instance_extras.push(None);
            }
        }
    }
    // Mesh indices changed above; the light-maps already carry the detail of any high-poly
    // source, so the exported meshes name none.
    meshes.iter_mut().for_each(|m| m.detail_source = None);
    scene.meshes = meshes;
    for name in png_pages {
        let p = dir.join(name);
        let bytes = std::fs::read(&p).map_err(|e| io(&p, e))?;
        extras.images.push((name.clone(), bytes));
    }
    extras.scene_extras = Some(serde_json::json!({
        "lightmaps": { "pages": exr_pages, "png_pages": png_pages, "manifest": MANIFEST }
    }));
    let path = dir.join(GLTF);
    export_with(&scene, &path, &extras).map_err(|e| io(&path, e))?;
    Ok(GLTF.to_string())
}

/// Read a baked folder for `scene`: the scene is given the light-map UVs it was baked with
/// (the unwrap is re-run with the recorded settings and must reproduce the recorded layout).
pub fn read(dir: &Path, scene: &Scene) -> Result<Lightmaps, BakeError> {
    let (folder, value) =
        crate::folder::read_manifest(dir, FORMAT, FORMAT_VERSION, "radiosity|path")?;
    let path = folder.manifest.clone();
    let manifest: Manifest = folder.parse(value)?;
    let mut scene = scene.clone();
    let layout = unwrap_scene(&mut scene, &manifest.layout.settings)?;
    if layout.pages != manifest.layout.pages || layout.instances != manifest.layout.instances {
        return Err(BakeError::Scene(format!(
            "the light-maps in {} were baked for a different scene ('{}'): its layout does not \
             match this scene's",
            dir.display(),
            manifest.scene
        )));
    }
    if manifest.pages.len() != layout.pages.len() {
        return Err(io(
            &path,
            format!(
                "lists {} pages, the layout has {}",
                manifest.pages.len(),
                layout.pages.len()
            ),
        ));
    }
    let mut pages = vec![];
    for (k, name) in manifest.pages.iter().enumerate() {
        let p = folder.file(name)?;
        let img = Image::read(&p).map_err(|e| io(&p, e))?;
        let [w, h] = layout.pages[k];
        if img.width != w || img.height != h {
            return Err(io(
                &p,
                format!("is {}×{}, the layout says {w}×{h}", img.width, img.height),
            ));
        }
        pages.push(img);
    }
    let mut directional = vec![];
    for (k, name) in manifest.directional_pages.iter().enumerate() {
        let p = folder.file(name)?;
        let img = Image::read(&p).map_err(|e| io(&p, e))?;
        if Some(&[img.width, img.height]) != layout.pages.get(k) {
            return Err(io(&p, "does not match its light-map page's size"));
        }
        directional.push(img);
    }
    if !directional.is_empty() && directional.len() != pages.len() {
        return Err(io(
            &path,
            "lists a different number of directional pages than pages",
        ));
    }
    Ok(Lightmaps {
        scene,
        layout,
        pages,
        directional: (!directional.is_empty()).then_some(directional),
        settings: manifest.settings,
        stats: manifest.stats,
    })
}

//! Writing and reading a baked light-map folder.
//!
//! ```text
//! DIR/manifest.json        what was baked, with which settings, the layout and the figures
//! DIR/lightmap-K.exr       page K, linear RGB E/π (32-bit float): the primary output
//! DIR/lightmap-K.png       page K tone-reproduced by Ward Larson's histogram adjustment
//!                          (Fuchs §3.3.5, one histogram over all pages) and gamma 2, as CaLight
//!                          stored its 8-bit light-maps (optional)
//! ```
//!
//! Every file is written to a temporary name and renamed, the manifest last, so a folder with
//! a manifest is complete.

use crate::layout::{Layout, unwrap_scene};
use crate::{BakeError, BakeSettings, BakeStats, Lightmaps};
use glam::Vec3;
use lightlab_core::color::WardLarson;
use lightlab_core::image::{Image, LdrSettings, write_atomic};
use lightlab_scene::Scene;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::Path;

pub const MANIFEST: &str = "manifest.json";
pub const FORMAT_VERSION: u32 = 1;

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
}

fn io(path: &Path, e: impl std::fmt::Display) -> BakeError {
    BakeError::Io(format!("{}: {e}", path.display()))
}

/// Write a bake to `dir` (created if missing).
pub fn write(
    lm: &Lightmaps,
    dir: &Path,
    scene_name: &str,
    png: bool,
) -> Result<Manifest, BakeError> {
    std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
    let mut pages = vec![];
    for (k, page) in lm.pages.iter().enumerate() {
        let name = format!("lightmap-{k}.exr");
        page.write(&dir.join(&name), LdrSettings::default())
            .map_err(|e| io(&dir.join(&name), e))?;
        pages.push(name);
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
    let manifest = Manifest {
        format: "lightlab-lightmaps".into(),
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
    };
    let path = dir.join(MANIFEST);
    let json = serde_json::to_string_pretty(&manifest).map_err(|e| io(&path, e))?;
    write_atomic(&path, |mut f| {
        f.write_all(json.as_bytes())
            .map_err(|e| lightlab_core::image::ImageError::Io {
                path: path.clone(),
                source: e,
            })
    })
    .map_err(|e| io(&path, e))?;
    Ok(manifest)
}

/// Read a baked folder for `scene`: the scene is given the light-map UVs it was baked with
/// (the unwrap is re-run with the recorded settings and must reproduce the recorded layout).
pub fn read(dir: &Path, scene: &Scene) -> Result<Lightmaps, BakeError> {
    let path = dir.join(MANIFEST);
    let text = std::fs::read_to_string(&path).map_err(|e| {
        io(
            &path,
            format!("{e} (is this a folder written by `lightlab bake`?)"),
        )
    })?;
    let manifest: Manifest = serde_json::from_str(&text).map_err(|e| io(&path, e))?;
    if manifest.format != "lightlab-lightmaps" || manifest.version != FORMAT_VERSION {
        return Err(io(
            &path,
            format!(
                "unsupported format {} version {} (expected lightlab-lightmaps {FORMAT_VERSION})",
                manifest.format, manifest.version
            ),
        ));
    }
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
    let mut pages = vec![];
    for (k, name) in manifest.pages.iter().enumerate() {
        let p = dir.join(name);
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
    if pages.len() != layout.pages.len() {
        return Err(io(&path, "lists fewer pages than the layout has"));
    }
    Ok(Lightmaps {
        scene,
        layout,
        pages,
        settings: manifest.settings,
        stats: manifest.stats,
    })
}

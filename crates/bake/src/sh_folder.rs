//! SH and per-vertex transfer folders on disk: `bake --method sh|prt` writes them, the SH
//! techniques read them back for a scene (with the k-means copy of `sh_compress` where the
//! folder holds one). Each folder has a `manifest.json` naming its files; pages are EXR.

use crate::prt::{ShLightmaps, TransferSettings, VertexTransfer};
use lightlab_core::sh;
use lightlab_scene::Scene;
use serde::{Deserialize, Serialize};

/// The manifest of a baked SH light-map folder (`manifest.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShManifest {
    pub format: String,
    pub version: u32,
    pub scene: String,
    pub quantity: String,
    pub bands: usize,
    pub transfer: TransferSettings,
    pub layout: crate::layout::Layout,
    /// Per page, its coefficient images: coefficient c is channel c%3 of image c/3.
    pub pages: Vec<Vec<String>>,
    pub seconds: f64,
    /// What the detail projection did (absent: no detail baked).
    #[serde(default)]
    pub detail: Option<crate::detail::DetailStats>,
    /// What CaSHL's shooting did (absent: no shooting).
    #[serde(default)]
    pub shooting: Option<crate::cashl::ShootStats>,
    /// The k-means compressed copy (Fuchs §5.6), when written.
    #[serde(default)]
    pub compressed: Option<crate::sh_compress::CompressedManifest>,
    /// Per page: the baked object-space normal (`normal-K.exr`, signed xyz) and ambient
    /// occlusion (`occlusion-K.exr`) — with a high-poly detail source, its normal and occlusion
    /// maps on the decimated mesh's light-map atlas.
    #[serde(default)]
    pub normal_pages: Vec<String>,
    #[serde(default)]
    pub occlusion_pages: Vec<String>,
}

pub const SH_FORMAT: &str = "lightlab-sh-lightmaps";

fn io_err(path: &std::path::Path, e: impl std::fmt::Display) -> crate::BakeError {
    crate::BakeError::Io(format!("{}: {e}", path.display()))
}

/// Write SH light-maps to `dir`: `sh-K-J.exr` (page K, coefficient image J, 32-bit float) and
/// the manifest, last (a folder with a manifest is complete).
pub fn write_sh(
    sl: &ShLightmaps,
    compressed: Option<&crate::sh_compress::CompressedSh>,
    dir: &std::path::Path,
    scene_name: &str,
    seconds: f64,
) -> Result<ShManifest, crate::BakeError> {
    use lightlab_core::image::LdrSettings;
    std::fs::create_dir_all(dir).map_err(|e| io_err(dir, e))?;
    let mut pages = vec![];
    for (k, imgs) in sl.pages.iter().enumerate() {
        let mut names = vec![];
        for (j, img) in imgs.iter().enumerate() {
            let name = format!("sh-{k}-{j}.exr");
            let p = dir.join(&name);
            img.write(&p, LdrSettings::default())
                .map_err(|e| io_err(&p, e))?;
            names.push(name);
        }
        pages.push(names);
    }
    let mut normal_pages = vec![];
    let mut occlusion_pages = vec![];
    for (k, d) in sl.detail_pages.iter().enumerate() {
        for (img, name, list) in [
            (&d.normal, format!("normal-{k}.exr"), &mut normal_pages),
            (
                &d.occlusion,
                format!("occlusion-{k}.exr"),
                &mut occlusion_pages,
            ),
        ] {
            let p = dir.join(&name);
            img.write(&p, LdrSettings::default())
                .map_err(|e| io_err(&p, e))?;
            list.push(name);
        }
    }
    let m = ShManifest {
        format: SH_FORMAT.into(),
        version: 1,
        scene: scene_name.into(),
        quantity: "diffuse transfer t_i = (1/pi) int V max(n.w,0) Y_i dw: E/pi = sum l_i t_i"
            .into(),
        bands: sl.bands,
        transfer: sl.settings,
        layout: sl.layout.clone(),
        pages,
        seconds,
        detail: sl.detail,
        shooting: sl.shooting,
        normal_pages,
        occlusion_pages,
        compressed: match compressed {
            Some(c) => Some(crate::sh_compress::write_compressed(c, dir)?),
            None => None,
        },
    };
    crate::output::write_manifest(dir, &m)?;
    Ok(m)
}

/// The manifest of a folder baked by `lightlab bake --method {method}`: its path and text.
fn manifest_text(
    dir: &std::path::Path,
    method: &str,
) -> Result<(std::path::PathBuf, String), crate::BakeError> {
    let path = dir.join(crate::output::MANIFEST);
    let text = std::fs::read_to_string(&path).map_err(|e| {
        io_err(
            &path,
            format!("{e} (is this a folder written by `lightlab bake --method {method}`?)"),
        )
    })?;
    Ok((path, text))
}

/// Read an SH light-map folder and its compressed copy, when it has one.
pub fn read_sh_with_compressed(
    dir: &std::path::Path,
    scene: &Scene,
) -> Result<(ShLightmaps, Option<crate::sh_compress::CompressedSh>), crate::BakeError> {
    let (sl, m) = read_sh_and_manifest(dir, scene)?;
    let c = match &m.compressed {
        Some(cm) => Some(crate::sh_compress::read_compressed(cm, dir, &sl)?),
        None => None,
    };
    Ok((sl, c))
}

/// Read an SH light-map folder for `scene` (the unwrap is re-run and must match).
pub fn read_sh(dir: &std::path::Path, scene: &Scene) -> Result<ShLightmaps, crate::BakeError> {
    Ok(read_sh_and_manifest(dir, scene)?.0)
}

fn read_sh_and_manifest(
    dir: &std::path::Path,
    scene: &Scene,
) -> Result<(ShLightmaps, ShManifest), crate::BakeError> {
    let (path, text) = manifest_text(dir, "sh")?;
    let m: ShManifest = serde_json::from_str(&text).map_err(|e| io_err(&path, e))?;
    if m.format != SH_FORMAT || m.version != 1 {
        return Err(io_err(
            &path,
            format!("not an SH light-map folder ({} {})", m.format, m.version),
        ));
    }
    if !(1..=8).contains(&m.bands) {
        return Err(io_err(
            &path,
            format!("says {} SH bands; a bake has 1 to 8", m.bands),
        ));
    }
    let mut scene = scene.clone();
    let layout = crate::layout::unwrap_scene(&mut scene, &m.layout.settings)?;
    if layout.pages != m.layout.pages || layout.instances != m.layout.instances {
        return Err(crate::BakeError::Scene(format!(
            "the SH light-maps in {} were baked for a different scene ('{}')",
            dir.display(),
            m.scene
        )));
    }
    let images = sh::num_coeffs(m.bands).div_ceil(3);
    if m.pages.len() != layout.pages.len() || m.pages.iter().any(|p| p.len() != images) {
        return Err(io_err(
            &path,
            "the page list does not match the layout and band count",
        ));
    }
    let mut pages = vec![];
    for (k, names) in m.pages.iter().enumerate() {
        let mut imgs = vec![];
        for name in names {
            let p = dir.join(name);
            let img = lightlab_core::image::Image::read(&p).map_err(|e| io_err(&p, e))?;
            if [img.width, img.height] != layout.pages[k] {
                return Err(io_err(&p, "does not match its page's size"));
            }
            imgs.push(img);
        }
        pages.push(imgs);
    }
    let sl = ShLightmaps {
        scene,
        layout,
        bands: m.bands,
        pages,
        settings: m.transfer,
        detail: m.detail,
        shooting: m.shooting,
        detail_pages: vec![],
    };
    Ok((sl, m))
}

/// The manifest of a baked per-vertex transfer folder (`lightlab bake --method prt`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VertexManifest {
    pub format: String,
    pub version: u32,
    pub scene: String,
    pub quantity: String,
    pub bands: usize,
    pub transfer: TransferSettings,
    /// Per instance: its name, vertex count and file (`transfer-I.bin`: little-endian f32,
    /// vertex-major, bands² coefficients per vertex, in the mesh's vertex order).
    pub instances: Vec<VertexFile>,
    pub seconds: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VertexFile {
    pub name: String,
    pub vertices: usize,
    pub file: String,
}

pub const VERTEX_FORMAT: &str = "lightlab-vertex-transfer";

/// Write per-vertex transfer to `dir`: one `transfer-I.bin` per instance and the manifest, last.
pub fn write_vertex_transfer(
    vt: &VertexTransfer,
    scene: &Scene,
    settings: &TransferSettings,
    dir: &std::path::Path,
    scene_name: &str,
    seconds: f64,
) -> Result<VertexManifest, crate::BakeError> {
    std::fs::create_dir_all(dir).map_err(|e| io_err(dir, e))?;
    let nc = sh::num_coeffs(vt.bands);
    let mut instances = vec![];
    for (i, (inst, data)) in scene.instances.iter().zip(&vt.instances).enumerate() {
        let file = format!("transfer-{i}.bin");
        let bytes: Vec<u8> = data.iter().flat_map(|v| v.to_le_bytes()).collect();
        crate::output::write_bytes(&dir.join(&file), &bytes)?;
        instances.push(VertexFile {
            name: inst.name.clone(),
            vertices: data.len() / nc,
            file,
        });
    }
    let m = VertexManifest {
        format: VERTEX_FORMAT.into(),
        version: 1,
        scene: scene_name.into(),
        quantity:
            "diffuse transfer per vertex t_i = (1/pi) int V max(n.w,0) Y_i dw: E/pi = sum l_i t_i"
                .into(),
        bands: vt.bands,
        transfer: *settings,
        instances,
        seconds,
    };
    crate::output::write_manifest(dir, &m)?;
    Ok(m)
}

/// Read a per-vertex transfer folder for `scene` (instance names and vertex counts must match).
pub fn read_vertex_transfer(
    dir: &std::path::Path,
    scene: &Scene,
) -> Result<(VertexTransfer, TransferSettings), crate::BakeError> {
    let (path, text) = manifest_text(dir, "prt")?;
    let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| io_err(&path, e))?;
    let format = v
        .get("format")
        .and_then(|f| f.as_str())
        .unwrap_or("no format");
    if format != VERTEX_FORMAT {
        return Err(io_err(
            &path,
            format!(
                "not a per-vertex transfer folder but '{format}' (bake one with `lightlab bake \
                 --method prt`)"
            ),
        ));
    }
    let m: VertexManifest = serde_json::from_value(v).map_err(|e| io_err(&path, e))?;
    if m.version != 1 || !(1..=8).contains(&m.bands) {
        return Err(io_err(
            &path,
            format!(
                "unsupported version {} or band count {}",
                m.version, m.bands
            ),
        ));
    }
    let nc = sh::num_coeffs(m.bands);
    let differs = m.instances.len() != scene.instances.len()
        || m.instances.iter().zip(&scene.instances).any(|(f, inst)| {
            f.name != inst.name || f.vertices != scene.meshes[inst.mesh].positions.len()
        });
    if differs {
        return Err(crate::BakeError::Scene(format!(
            "the per-vertex transfer in {} was baked for a different scene ('{}')",
            dir.display(),
            m.scene
        )));
    }
    let mut instances = vec![];
    for f in &m.instances {
        let p = dir.join(&f.file);
        let bytes = std::fs::read(&p).map_err(|e| io_err(&p, e))?;
        if bytes.len() != f.vertices * nc * 4 {
            return Err(io_err(
                &p,
                format!(
                    "{} bytes, expected {} ({} vertices × {nc} coefficients × 4)",
                    bytes.len(),
                    f.vertices * nc * 4,
                    f.vertices
                ),
            ));
        }
        let v: Vec<f32> = bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        if v.iter().any(|x| !x.is_finite()) {
            return Err(io_err(&p, "holds NaN or infinite coefficients"));
        }
        instances.push(v);
    }
    Ok((
        VertexTransfer {
            bands: m.bands,
            instances,
        },
        m.transfer,
    ))
}

//! SH and per-vertex transfer folders on disk: `bake --method sh|prt` writes them, the SH
//! techniques read them back for a scene (with the k-means copy of `sh_compress` where the
//! folder holds one). Each folder has a `manifest.json` naming its files; pages are EXR. Both
//! are written whole and verified on reading (see [`crate::folder`]).

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
/// 2: the manifest carries the integrity record (see [`crate::folder`]).
pub const SH_VERSION: u32 = 2;

fn io_err(path: &std::path::Path, e: impl std::fmt::Display) -> crate::BakeError {
    crate::BakeError::Io(format!("{}: {e}", path.display()))
}

/// Write SH light-maps to `dir`: `sh-K-J.exr` (page K, coefficient image J, 32-bit float) and
/// the manifest, replacing the bake there as a whole.
pub fn write_sh(
    sl: &ShLightmaps,
    compressed: Option<&crate::sh_compress::CompressedSh>,
    dir: &std::path::Path,
    scene_name: &str,
    seconds: f64,
) -> Result<ShManifest, crate::BakeError> {
    crate::folder::write(dir, |stage| {
        write_sh_files(sl, compressed, stage, scene_name, seconds)
    })
}

fn write_sh_files(
    sl: &ShLightmaps,
    compressed: Option<&crate::sh_compress::CompressedSh>,
    dir: &std::path::Path,
    scene_name: &str,
    seconds: f64,
) -> Result<ShManifest, crate::BakeError> {
    use lightlab_core::image::LdrSettings;
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
    Ok(ShManifest {
        format: SH_FORMAT.into(),
        version: SH_VERSION,
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
    })
}

/// Read an SH light-map folder and its compressed copy, when it has one.
pub fn read_sh_with_compressed(
    dir: &std::path::Path,
    scene: &Scene,
) -> Result<(ShLightmaps, Option<crate::sh_compress::CompressedSh>), crate::BakeError> {
    let (sl, m, folder) = read_sh_and_manifest(dir, scene)?;
    let c = match &m.compressed {
        Some(cm) => Some(crate::sh_compress::read_compressed(cm, &folder, &sl)?),
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
) -> Result<(ShLightmaps, ShManifest, crate::folder::Checked), crate::BakeError> {
    let (folder, value) = crate::folder::read_manifest(dir, SH_FORMAT, SH_VERSION, "sh")?;
    let path = folder.manifest.clone();
    let m: ShManifest = folder.parse(value)?;
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
            let p = folder.file(name)?;
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
    Ok((sl, m, folder))
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
/// 2: the manifest carries the integrity record (see [`crate::folder`]).
pub const VERTEX_VERSION: u32 = 2;

/// Write per-vertex transfer to `dir`: one `transfer-I.bin` per instance and the manifest,
/// replacing the bake there as a whole.
pub fn write_vertex_transfer(
    vt: &VertexTransfer,
    scene: &Scene,
    settings: &TransferSettings,
    dir: &std::path::Path,
    scene_name: &str,
    seconds: f64,
) -> Result<VertexManifest, crate::BakeError> {
    crate::folder::write(dir, |dir| {
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
        Ok(VertexManifest {
            format: VERTEX_FORMAT.into(),
            version: VERTEX_VERSION,
            scene: scene_name.into(),
            quantity:
                "diffuse transfer per vertex t_i = (1/pi) int V max(n.w,0) Y_i dw: E/pi = sum l_i t_i"
                    .into(),
            bands: vt.bands,
            transfer: *settings,
            instances,
            seconds,
        })
    })
}

/// Read a per-vertex transfer folder for `scene` (instance names and vertex counts must match).
pub fn read_vertex_transfer(
    dir: &std::path::Path,
    scene: &Scene,
) -> Result<(VertexTransfer, TransferSettings), crate::BakeError> {
    let (folder, value) = crate::folder::read_manifest(dir, VERTEX_FORMAT, VERTEX_VERSION, "prt")?;
    let path = folder.manifest.clone();
    let m: VertexManifest = folder.parse(value)?;
    if !(1..=8).contains(&m.bands) {
        return Err(io_err(
            &path,
            format!("says {} SH bands; a bake has 1 to 8", m.bands),
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
        let p = folder.file(&f.file)?;
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

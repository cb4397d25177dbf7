//! The SH techniques: `prt-vertex` and `prt-textured` (McKenzie Chapter ch. 4),
//! `prt-hierarchical` (ch. 5: textured PRT's light filtered by the other objects), `shl`,
//! `shl-compressed` and `shl-normalmapped` (Fuchs §5): transfer read from `--baked` or baked
//! now, the scene's lights projected on SH (re-projected every frame by the caller), and the
//! GPU renderer whose ambient term is transfer · light.

use super::{Bakes, Request};
use crate::technique::Technique;
use anyhow::{Result, bail};
use glam::DMat3;
use lightlab_bake::hprt::Hierarchy;
use lightlab_bake::prt::{ShLightmaps, VertexTransfer, bake_sh_lightmaps};
use lightlab_bake::sh_compress::{CompressSettings, CompressedSh, compress};
use lightlab_bake::sh_light::{SamplePoints, ShLighting, ShProjector};
use lightlab_core::sh::Window;
use lightlab_gpu::GpuContext;
use lightlab_gpu::prt::{IndexPage, ShFilter, ShInput, ShTransfer};
use lightlab_gpu::raster::{EnvDiffuse, Renderer};
use lightlab_scene::Scene;

/// Transfer data of an SH technique.
pub enum ShData<'a> {
    Textured(&'a ShLightmaps),
    Compressed(&'a ShLightmaps, CompressedSh),
    Vertex(&'a Scene, &'a VertexTransfer),
}

impl ShData<'_> {
    pub fn bands(&self) -> usize {
        match self {
            ShData::Textured(sl) | ShData::Compressed(sl, _) => sl.bands,
            ShData::Vertex(_, vt) => vt.bands,
        }
    }
    pub fn scene(&self) -> &Scene {
        match self {
            ShData::Textured(sl) | ShData::Compressed(sl, _) => &sl.scene,
            ShData::Vertex(s, _) => s,
        }
    }
}

/// SH light-maps and the compressed copy their folder holds.
pub type StoredSh = (ShLightmaps, Option<CompressedSh>);

/// The transfer of the request: from `--baked`, or computed now; once per folder or settings
/// in `bakes` (one SH light-map bake serves `shl`, `prt-textured` and `shl-compressed`).
pub fn data<'b>(req: &Request<'b>, bakes: &'b mut Bakes) -> Result<ShData<'b>> {
    let mut s = req.args.bake.transfer_settings()?;
    // Fuchs §5.7: only the bake changes; the renderer is shl's.
    s.normal_mapped |= req.technique == Technique::ShlNormalmapped;
    // McKenzie ch. 5: each object's transfer is its self-shadowing; the filters add the rest.
    s.self_only |= req.technique == Technique::PrtHierarchical;
    let scene = req.scene;
    if req.technique == Technique::PrtVertex {
        let key = match &req.args.baked {
            Some(dir) => format!("dir {}", dir.display()),
            None => serde_json::to_string(&s)?,
        };
        if !bakes.vertex.contains_key(&key) {
            let vt = match &req.args.baked {
                Some(dir) => lightlab_bake::sh_folder::read_vertex_transfer(dir, scene)?.0,
                None => {
                    eprintln!(
                        "computing {} per-vertex transfer ({} bands, {:?}, {} directions)",
                        scene.name, s.bands, s.kind, s.samples
                    );
                    // Each moving object of an animated scene against itself only.
                    lightlab_bake::occlusion_groups::vertex_transfer(scene, &s)?
                }
            };
            bakes.vertex.insert(key.clone(), vt);
        }
        return Ok(ShData::Vertex(scene, &bakes.vertex[&key]));
    }
    let tpm = req.args.bake.density(req.scene);
    let key = match &req.args.baked {
        Some(dir) => format!("dir {}", dir.display()),
        None => format!(
            "{} {tpm} {}",
            serde_json::to_string(&s)?,
            req.args.bake.lightmap_uv
        ),
    };
    if !bakes.sh.contains_key(&key) {
        let stored = match &req.args.baked {
            Some(dir) => lightlab_bake::sh_folder::read_sh_with_compressed(dir, scene)?,
            None => {
                eprintln!(
                    "no --baked folder: baking {} SH light-maps now ({} bands, {:?}, {} \
                     directions, {tpm} texels/m)",
                    scene.name, s.bands, s.kind, s.samples
                );
                let layout = req.args.bake.layout(req.scene);
                let sl = bake_sh_lightmaps(scene, &layout, &s, &lightlab_bake::no_progress)?;
                super::lightmap::warn_regenerated(&sl.layout);
                (sl, None)
            }
        };
        bakes.sh.insert(key.clone(), stored);
    }
    let (sl, stored) = &bakes.sh[&key];
    if let Some(dir) = &req.args.baked
        && s.normal_mapped
        && !sl.settings.normal_mapped
    {
        bail!(
            "{} was baked without normal maps; bake it with `lightlab bake --method sh \
             --normal-mapped` for {}",
            dir.display(),
            req.technique
        );
    }
    if let Some(dir) = &req.args.baked
        && s.self_only
        && !sl.settings.self_only
    {
        bail!(
            "{} was baked with every object shadowing every other, and prt-hierarchical's \
             filters would shadow them twice; bake it with `lightlab bake --method sh \
             --occluders object`",
            dir.display()
        );
    }
    if req.technique != Technique::ShlCompressed {
        return Ok(ShData::Textured(sl));
    }
    if let Some(c) = stored {
        eprintln!(
            "using the folder's compressed copy ({} representatives, {:.1}× smaller)",
            c.stats.representatives, c.stats.ratio
        );
        return Ok(ShData::Compressed(sl, c.clone()));
    }
    let c = compress(
        sl,
        &CompressSettings {
            representatives: req.args.sh.sh_representatives,
            ..Default::default()
        },
    )?;
    let st = &c.stats;
    eprintln!(
        "compressed {} transfer vectors to {} representatives in {} iterations ({:.2} s): \
         {:.1}× smaller, rms distance {:.4}",
        st.vectors, st.representatives, st.iterations, st.seconds, st.ratio, st.rms_distance
    );
    Ok(ShData::Compressed(sl, c))
}

/// Upload this frame's SH light.
pub fn set_light(ctx: &GpuContext, r: &mut Renderer, light: &ShLighting) -> Result<()> {
    let (points, coeffs) = light.flattened();
    r.set_sh_light(ctx, &points, &coeffs)?;
    Ok(())
}

/// An SH technique's per-frame light: the projector, the scene as baked (its rest pose) and
/// as posed now, and hierarchical PRT's filters.
pub struct ShState {
    projector: ShProjector,
    pub rest: Scene,
    pub posed: Scene,
    pub hierarchy: Option<Hierarchy>,
}

impl ShState {
    /// This frame's light: projected at the posed scene's sample points, filtered (hierarchical
    /// PRT), and turned into each moved object's baked frame.
    pub fn light(&mut self) -> ShLighting {
        let rotations = self
            .rest
            .animation
            .as_ref()
            .map(|_| rotations(&self.rest, &self.posed));
        match &mut self.hierarchy {
            None => self.projector.project(&self.posed, rotations.as_deref()),
            Some(h) => {
                h.update(&self.posed);
                let world = self.projector.project(&self.posed, None);
                h.relight(&world, rotations.as_deref())
            }
        }
    }
}

/// Each instance's rotation from its rest transform to its posed one.
pub fn rotations(rest: &Scene, posed: &Scene) -> Vec<DMat3> {
    rest.instances
        .iter()
        .zip(&posed.instances)
        .map(|(a, b)| {
            let (_, ra, _) = a.transform.to_scale_rotation_translation();
            let (_, rb, _) = b.transform.to_scale_rotation_translation();
            DMat3::from_quat((rb * ra.inverse()).normalize().as_dquat())
        })
        .collect()
}

/// The GPU renderer of an SH technique lit by the scene's lights of now, and the state that
/// relights it each frame.
pub fn renderer(ctx: &GpuContext, req: &Request, data: &ShData) -> Result<(Renderer, ShState)> {
    let bands = data.bands();
    let hierarchical = req.technique == Technique::PrtHierarchical;
    let prt = matches!(
        req.technique,
        Technique::PrtVertex | Technique::PrtTextured | Technique::PrtHierarchical
    );
    let mut ls = req.args.sh.light_settings(prt, bands)?;
    let hierarchy = if hierarchical {
        anyhow::ensure!(
            ls.points == SamplePoints::PerObject,
            "prt-hierarchical filters the light at each object's sample points: it needs \
             --sh-points object"
        );
        let hs = req.args.sh.hprt.settings(bands, ls.window)?;
        // The hierarchy windows the light as it combines it with the filters.
        ls.window = Window::None;
        let tree = req.args.sh.hprt.tree(data.scene());
        Some(Hierarchy::new(data.scene(), tree, hs))
    } else {
        None
    };
    let a = &req.args.raster;
    let mut s = a.settings(
        req.technique.shadows(a.shadow_variant)?,
        req.width,
        req.height,
        req.camera,
    )?;
    // The transfer carries the diffuse light, the sky's included (the SH source leaves the
    // frame's SH irradiance unused); the environment's specular term for glossy and metal
    // materials still comes from its prefiltered maps, so only an irradiance map is not made.
    s.env_diffuse = EnvDiffuse::Sh;
    // The lights reach the surfaces through the transfer only.
    let mut scene = data.scene().clone();
    let mut state = ShState {
        projector: ShProjector::new(&scene, &ls),
        rest: scene.clone(),
        posed: scene.clone(),
        hierarchy,
    };
    let light = state.light();
    scene.lights.clear();
    let filter = req.args.sh.sh_filter.unwrap_or(ShFilter::Bilinear);
    let index_pages: Vec<IndexPage>;
    let (transfer, rects) = match data {
        ShData::Textured(sl) => (
            ShTransfer::Textured { pages: &sl.pages },
            super::lightmap::layout_rects(&sl.layout),
        ),
        ShData::Compressed(sl, c) => {
            index_pages = c
                .pages
                .iter()
                .map(|p| IndexPage {
                    width: p.width,
                    height: p.height,
                    indices: &p.indices,
                })
                .collect();
            (
                ShTransfer::Compressed {
                    pages: &index_pages,
                    representatives: &c.representatives,
                    filter,
                },
                super::lightmap::layout_rects(&sl.layout),
            )
        }
        ShData::Vertex(_, vt) => (
            ShTransfer::Vertex {
                instances: &vt.instances,
            },
            vec![],
        ),
    };
    let input = ShInput {
        bands,
        transfer,
        rects: &rects,
        per_object: ls.points == SamplePoints::PerObject,
        points: light.points[0].len(),
    };
    let mut r = Renderer::with_sh(ctx, &scene, s, &input)?;
    set_light(ctx, &mut r, &light)?;
    Ok((r, state))
}

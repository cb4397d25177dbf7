//! The SH light-map bake (Fuchs §5, McKenzie Chapter ch. 4) in stages, so that a shard can
//! compute part of the transfer and a merge the rest ([`crate::shard`]):
//! - [`prepare`]: unwrap, rasterise the texels, probe their validity, and set up the detail
//!   sources and the per-vertex bounces that inter-reflected transfer gathers from;
//! - [`page_surface`]: a page's gathered texels as surface points (normal-mapped normals,
//!   projection onto the detail source);
//! - [`page_transfer`]: the transfer and ambient occlusion of a run of those points, texel j
//!   drawing its directions from its index j in the page (so any run gives the same values);
//! - CaSHL shooting between all texels (`cashl`), when asked: one global iteration;
//! - [`finish`]: the coefficient images, normal and occlusion pages, dilated.

use crate::detail::{DetailProjector, DetailStats, SurfacePoint};
use crate::prt::{
    DetailPage, NORMAL_MAP_SAMPLES, ShLightmaps, TransferKind, TransferSettings, VertexTransfer,
};
use glam::Vec3;
use lightlab_core::sampling::Rng;
use lightlab_core::sh;
use lightlab_scene::Scene;
use lightlab_trace::Accel;

/// A bake up to its transfer.
pub(crate) struct Prepared {
    pub scene: Scene,
    pub layout: crate::layout::Layout,
    pub texels: crate::texels::Texels,
    pub valid: Vec<Vec<bool>>,
    accel: Accel,
    detail: Option<(DetailProjector, Scene, Accel)>,
    /// What inter-reflected transfer gathers from (empty otherwise, or when not asked for).
    sources: Vec<VertexTransfer>,
    /// An animated scene's occlusion groups (each moving instance shadows only itself).
    groups: Option<crate::occlusion_groups::Groups>,
}

/// One page's computed texels: their slot indices, surface points, transfer (nc floats each)
/// and ambient occlusion.
pub(crate) type Computed = (Vec<usize>, Vec<SurfacePoint>, Vec<f32>, Vec<f32>);

/// Stage one. `with_sources`: compute the per-vertex bounces (a merge, which computes no
/// transfer, does not need them).
pub(crate) fn prepare(
    scene: &Scene,
    layout: &crate::layout::LayoutSettings,
    s: &TransferSettings,
    with_sources: bool,
    progress: crate::Progress,
) -> Result<Prepared, crate::BakeError> {
    crate::prt::check(s)?;
    let mut scene = scene.clone();
    let layout = crate::layout::unwrap_scene(&mut scene, layout)?;
    let texels = crate::texels::rasterize(&scene, &layout);
    let accel = Accel::new(&scene);
    let valid = crate::texels::probe_validity(&texels, &scene, &accel, 32, 0.25, s.seed);
    if !progress("vertex transfer", 0, 1) {
        return Err(crate::BakeError::Cancelled);
    }
    // With detail, transfer is computed on the source surfaces, against the scene as the
    // source meshes have it (inter-reflection too); texels keep the decimated layout.
    let detail = s
        .detail
        .filter(|_| crate::detail::has_detail(&scene))
        .map(|d| {
            let ds = crate::detail::detail_scene(&scene);
            let da = Accel::new(&ds);
            (DetailProjector::new(&scene, &d), ds, da)
        });
    let mut prep = Prepared {
        scene,
        layout,
        texels,
        valid,
        accel,
        detail,
        sources: vec![],
        groups: None,
    };
    if let Some(of_instance) = crate::occlusion_groups::assign(&prep.scene, s.self_only) {
        if matches!(s.kind, TransferKind::Shooting(_)) {
            return Err(crate::BakeError::Settings(
                "CaSHL shooting bakes one transfer for the whole scene, but this bake gives \
                 objects transfer of their own (an animated scene, or --occluders object): \
                 use --transfer shadowed or interreflected"
                    .into(),
            ));
        }
        let (tscene, _) = prep.transfer_scene();
        prep.groups = Some(crate::occlusion_groups::build(
            tscene,
            of_instance,
            s,
            with_sources,
        )?);
    } else if with_sources && matches!(s.kind, TransferKind::Interreflected { .. }) {
        let (tscene, taccel) = prep.transfer_scene();
        prep.sources = crate::prt::vertex_transfer(tscene, taccel, s)?.1;
    }
    Ok(prep)
}

/// Empty detail-projection figures when the bake projects onto detail sources.
pub(crate) fn detail_stats(prep: &Prepared) -> Option<DetailStats> {
    prep.detail.as_ref().map(|_| DetailStats::default())
}

impl Prepared {
    /// The scene transfer is computed against (the detail sources' when there are any).
    fn transfer_scene(&self) -> (&Scene, &Accel) {
        match &self.detail {
            Some((_, ds, da)) => (ds, da),
            None => (&self.scene, &self.accel),
        }
    }
}

/// The instance of each of page `k`'s texels `idx`.
pub(crate) fn page_instances(prep: &Prepared, k: usize, idx: &[usize]) -> Vec<u32> {
    let page = &prep.texels.pages[k];
    idx.iter()
        .map(|&i| page.samples[i].as_ref().expect("filtered").instance)
        .collect()
}

/// Page `k`'s gathered texels (a sample, valid) in slot order, as surface points; detail
/// projection adds to `stats`.
pub(crate) fn page_surface(
    prep: &Prepared,
    s: &TransferSettings,
    k: usize,
    stats: &mut Option<DetailStats>,
) -> (Vec<usize>, Vec<SurfacePoint>) {
    let page = &prep.texels.pages[k];
    let ok = &prep.valid[k];
    let idx: Vec<usize> = (0..page.samples.len())
        .filter(|&i| page.samples[i].is_some() && ok[i])
        .collect();
    let surface: Vec<(usize, SurfacePoint)> = idx
        .iter()
        .map(|&i| {
            let t = page.samples[i].as_ref().expect("filtered");
            let ns = if s.normal_mapped {
                let mut rng = Rng::new(s.seed ^ 0x6e6d, ((k as u64) << 32) | i as u64);
                crate::texels::normal_mapped_normal(&prep.scene, t, NORMAL_MAP_SAMPLES, &mut rng)
                    .unwrap_or(t.ns)
            } else {
                t.ns
            };
            let sp = SurfacePoint {
                p: t.p,
                ng: t.ng,
                ns,
            };
            (t.instance as usize, sp)
        })
        .collect();
    let surface = match &prep.detail {
        Some((proj, _, _)) => {
            let (pts, st) = proj.project_all(&surface);
            if let Some(acc) = stats.as_mut() {
                acc.merge(&st);
            }
            pts
        }
        None => surface.into_iter().map(|(_, sp)| sp).collect(),
    };
    (idx, surface)
}

/// Transfer and ambient occlusion of `points` (on `instances`), the run of a page's points
/// from index `first`. Shooting starts from the shadowed transfer.
pub(crate) fn page_transfer(
    prep: &Prepared,
    s: &TransferSettings,
    points: &[SurfacePoint],
    instances: &[u32],
    first: u64,
) -> Result<(Vec<f32>, Vec<f32>), crate::BakeError> {
    let direct_s = match s.kind {
        TransferKind::Shooting(_) => TransferSettings {
            kind: TransferKind::Shadowed,
            ..*s
        },
        _ => *s,
    };
    let pts: Vec<(Vec3, Vec3, Vec3)> = points
        .iter()
        .map(|sp| (sp.p + sp.ng * crate::prt::ray_eps(sp.p), sp.ns, sp.ng))
        .collect();
    let Some(groups) = &prep.groups else {
        let (tscene, taccel) = prep.transfer_scene();
        return Ok(crate::prt::transfer_ao_seeded(
            tscene,
            taccel,
            &pts,
            &direct_s,
            &prep.sources,
            &|j| first + j as u64,
        )?);
    };
    // Each group's points against its own geometry; a point keeps its seed (its index).
    let nc = sh::num_coeffs(s.bands);
    let mut tr = vec![0.0f32; pts.len() * nc];
    let mut ao = vec![1.0f32; pts.len()];
    for (g, part) in groups.parts.iter().enumerate() {
        let sel: Vec<usize> = (0..pts.len())
            .filter(|&j| groups.of_instance[instances[j] as usize] == g)
            .collect();
        if sel.is_empty() {
            continue;
        }
        let sub: Vec<_> = sel.iter().map(|&j| pts[j]).collect();
        let (t, a) = crate::prt::transfer_ao_seeded(
            &part.scene,
            &part.accel,
            &sub,
            &direct_s,
            &part.sources,
            &|j| first + sel[j] as u64,
        )?;
        for (q, &j) in sel.iter().enumerate() {
            tr[j * nc..(j + 1) * nc].copy_from_slice(&t[q * nc..(q + 1) * nc]);
            ao[j] = a[q];
        }
    }
    Ok((tr, ao))
}

/// CaSHL: the bounces by shooting between all texels of all pages, in place.
pub(crate) fn shoot(
    prep: &Prepared,
    s: &TransferSettings,
    shoot: &crate::cashl::ShootSettings,
    computed: &mut [Computed],
    progress: crate::Progress,
) -> Result<crate::cashl::ShootStats, crate::BakeError> {
    let nc = sh::num_coeffs(s.bands);
    let mut patches = vec![];
    let mut transfer = vec![];
    for (k, (idx, surface, tr, _)) in computed.iter().enumerate() {
        let page = &prep.texels.pages[k];
        for (j, &i) in idx.iter().enumerate() {
            let t = page.samples[i].as_ref().expect("filtered");
            if t.area <= 0.0 {
                continue;
            }
            patches.push(crate::cashl::ShootPatch {
                p: surface[j].p,
                n: surface[j].ns,
                ng: surface[j].ng,
                area: t.area,
                rho: t.albedo.element_sum() / 3.0,
                page: k as u32,
                x: i as u32 % page.width,
                y: i as u32 / page.width,
                instance: t.instance,
            });
            transfer.extend_from_slice(&tr[j * nc..(j + 1) * nc]);
        }
    }
    let (_, taccel) = prep.transfer_scene();
    let st = crate::cashl::shoot(taccel, &patches, &mut transfer, nc, shoot, &|shots| {
        progress("shooting", shots as usize, 0)
    })?;
    let mut it = transfer.chunks_exact(nc);
    for (k, (idx, _, tr, _)) in computed.iter_mut().enumerate() {
        let page = &prep.texels.pages[k];
        for (j, &i) in idx.iter().enumerate() {
            if page.samples[i].as_ref().is_some_and(|t| t.area > 0.0) {
                tr[j * nc..(j + 1) * nc].copy_from_slice(it.next().expect("one per patch"));
            }
        }
    }
    Ok(st)
}

/// The bake's images from its computed pages: per page the coefficient images (three
/// coefficients each) and the normal and occlusion pages, all dilated over empty texels.
pub(crate) fn finish(
    prep: Prepared,
    s: &TransferSettings,
    computed: &[Computed],
    detail: Option<DetailStats>,
    shooting: Option<crate::cashl::ShootStats>,
) -> ShLightmaps {
    let nc = sh::num_coeffs(s.bands);
    let images = nc.div_ceil(3);
    let mut pages = vec![];
    let mut detail_pages = vec![];
    for (k, (idx, surface, tr, ao)) in computed.iter().enumerate() {
        let page = &prep.texels.pages[k];
        let (w, h) = (page.width, page.height);
        let n = page.samples.len();
        let image = |data| lightlab_core::image::Image {
            width: w,
            height: h,
            data,
        };
        // The baked normal (object space of the texel's instance) and occlusion, dilated.
        let mut nrm = vec![Vec3::ZERO; n];
        let mut occ = vec![Vec3::ZERO; n];
        let mut filled = vec![false; n];
        for (j, &i) in idx.iter().enumerate() {
            let t = page.samples[i].as_ref().expect("filtered");
            let m = glam::Mat3::from_mat4(prep.scene.instances[t.instance as usize].transform);
            nrm[i] = (m.transpose() * surface[j].ns).normalize_or(Vec3::Z);
            occ[i] = Vec3::splat(ao[j].clamp(0.0, 1.0));
            filled[i] = true;
        }
        let mut filled2 = filled.clone();
        crate::repair::dilate(&mut nrm, &mut filled, w, h, 64);
        // Dilation averages: keep the normal map unit length.
        nrm.iter_mut().for_each(|n| *n = n.normalize_or(Vec3::Z));
        crate::repair::dilate(&mut occ, &mut filled2, w, h, 64);
        detail_pages.push(DetailPage {
            normal: image(nrm),
            occlusion: image(occ),
        });
        let mut imgs = vec![];
        for k in 0..images {
            let mut v = vec![Vec3::ZERO; n];
            let mut filled = vec![false; n];
            for (j, &i) in idx.iter().enumerate() {
                let c = &tr[j * nc..(j + 1) * nc];
                v[i] =
                    Vec3::from_array([0, 1, 2].map(|ch| c.get(3 * k + ch).copied().unwrap_or(0.0)));
                filled[i] = true;
            }
            crate::repair::dilate(&mut v, &mut filled, w, h, 64);
            imgs.push(image(v));
        }
        pages.push(imgs);
    }
    ShLightmaps {
        scene: prep.scene,
        layout: prep.layout,
        bands: s.bands,
        pages,
        settings: *s,
        detail,
        shooting,
        detail_pages,
    }
}

/// Bake SH light-maps: unwrap, rasterise texels, probe validity, compute every valid texel's
/// transfer (inter-reflection through per-vertex bounces, or CaSHL shooting), dilate each
/// coefficient image. `progress` is called per stage and page; returning false cancels.
pub fn bake_sh_lightmaps(
    scene: &Scene,
    layout: &crate::layout::LayoutSettings,
    s: &TransferSettings,
    progress: crate::Progress,
) -> Result<ShLightmaps, crate::BakeError> {
    let prep = prepare(scene, layout, s, true, progress)?;
    let total = prep.texels.pages.len();
    let mut stats = detail_stats(&prep);
    let mut computed = vec![];
    for k in 0..total {
        if !progress("texel transfer", k, total) {
            return Err(crate::BakeError::Cancelled);
        }
        let (idx, surface) = page_surface(&prep, s, k, &mut stats);
        let inst = page_instances(&prep, k, &idx);
        let (tr, ao) = page_transfer(&prep, s, &surface, &inst, 0)?;
        computed.push((idx, surface, tr, ao));
    }
    progress("texel transfer", total, total);
    let shooting = match s.kind {
        TransferKind::Shooting(sh) => Some(shoot(&prep, s, &sh, &mut computed, progress)?),
        _ => None,
    };
    progress("texel transfer", total, total);
    Ok(finish(prep, s, &computed, stats, shooting))
}

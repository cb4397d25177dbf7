//! Light-map UVs (TEXCOORD_1) and their pages.
//!
//! A mesh that already has TEXCOORD_1 keeps it untouched: each of its instances gets a page of
//! its own, sized for the requested texel density (how engines that take one light-map per mesh,
//! Bevy among them, use authored UVs). Every other mesh is unwrapped by `uvunwrap` (chart
//! segmentation in a normal cone, planar projection or LSCM, shape packing with padding): the
//! mesh's UVs cover [0, 1] of its own layout and each instance gets a rectangle of a shared page
//! at its own scale, the scheme of Bevy's `Lightmap::uv_rect` and Unity's `lightmapScaleOffset`.
//! The unwrap splits vertices along chart seams; [`unwrap_scene`] rewrites the meshes so.
//!
//! The unwrap is deterministic (uvunwrap without its SIMD direct solver), so the same scene and
//! settings give the same layout on any machine: a baked folder records its settings and
//! [`unwrap_scene`] reproduces the UVs it was baked with.

use crate::BakeError;
use glam::{Mat3, Vec2, Vec3};
use lightlab_scene::{Mesh, Scene};
use serde::{Deserialize, Serialize};

/// Where light-map UVs come from for a mesh that has an authored TEXCOORD_1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum LightmapUv {
    /// The authored set when it passes [`check_authored_uv`], new UVs otherwise (with a note in
    /// [`Layout::regenerated`]).
    #[default]
    Auto,
    /// The authored set, unchecked.
    Authored,
    /// New UVs for every mesh.
    Generate,
}

lightlab_core::named_enum!(LightmapUv, "light-map UV source", {
    Auto => "auto",
    Authored => "authored",
    Generate => "generate",
});

/// How light-map UVs are laid out.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LayoutSettings {
    /// Texel density in texels per metre. Walls must be at least two texels thick for the
    /// back-face invalidation to keep light from leaking under them.
    pub texels_per_metre: f32,
    /// Empty texels around each chart. Bicubic sampling reads two texels beyond a chart's
    /// edge texel, so charts need three to stay apart.
    pub padding: u32,
    /// Largest page side; a scene that needs more gets an error naming the density to lower.
    pub max_page_size: u32,
    /// Authored TEXCOORD_1: checked, kept or replaced.
    #[serde(default)]
    pub lightmap_uv: LightmapUv,
}

impl Default for LayoutSettings {
    fn default() -> Self {
        LayoutSettings {
            texels_per_metre: 32.0,
            padding: 3,
            max_page_size: 4096,
            lightmap_uv: LightmapUv::Auto,
        }
    }
}

/// Where an instance's light-map lives: page coordinates = `offset + uv1 · scale`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct InstanceRect {
    pub page: u32,
    pub offset: [f32; 2],
    pub scale: [f32; 2],
}

impl InstanceRect {
    #[inline]
    pub fn page_uv(&self, uv1: Vec2) -> Vec2 {
        Vec2::from(self.offset) + uv1 * Vec2::from(self.scale)
    }
}

/// The light-map layout of a scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Layout {
    pub settings: LayoutSettings,
    /// (width, height) of each page in texels.
    pub pages: Vec<[u32; 2]>,
    /// One per scene instance (`None` for an instance whose mesh has no triangles).
    pub instances: Vec<Option<InstanceRect>>,
    /// Charts made by the unwrap (0 when every mesh had authored UVs).
    pub charts: u32,
    /// Fraction of page texels covered by surface.
    pub utilization: f32,
    /// Meshes whose authored TEXCOORD_1 was not used, with the reason (print as warnings).
    #[serde(default)]
    pub regenerated: Vec<String>,
}

impl Layout {
    pub fn texel_count(&self) -> u64 {
        self.pages.iter().map(|p| p[0] as u64 * p[1] as u64).sum()
    }

    /// Size of a page in texels.
    pub fn page_size(&self, page: u32) -> Vec2 {
        let [w, h] = self.pages[page as usize];
        Vec2::new(w as f32, h as f32)
    }

    /// The scene's instances that have a light-map, with their meshes' TEXCOORD_1.
    pub fn placed<'a>(&'a self, scene: &'a Scene) -> impl Iterator<Item = Placed<'a>> {
        scene
            .instances
            .iter()
            .enumerate()
            .filter_map(move |(index, instance)| {
                let rect = self.instances[index]?;
                let mesh = &scene.meshes[instance.mesh];
                let uv1 = mesh.uv1.as_deref()?;
                Some(Placed {
                    index,
                    instance,
                    mesh,
                    rect,
                    uv1,
                })
            })
    }
}

/// An instance with a light-map ([`Layout::placed`]).
pub struct Placed<'a> {
    pub index: usize,
    pub instance: &'a lightlab_scene::Instance,
    pub mesh: &'a Mesh,
    pub rect: InstanceRect,
    pub uv1: &'a [Vec2],
}

/// Linear scale of an instance transform (cube root of the volume scale).
fn instance_scale(m: &glam::Mat4) -> f32 {
    let d = Mat3::from_mat4(*m).determinant().abs();
    if d.is_finite() && d > 0.0 {
        d.cbrt()
    } else {
        1.0
    }
}

fn tri_area(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    0.5 * (b - a).cross(c - a).length()
}
/// The world-space area of every instance's triangles [m²].
pub fn surface_area(scene: &Scene) -> f64 {
    scene
        .instances
        .iter()
        .map(|inst| {
            let m = &scene.meshes[inst.mesh];
            m.indices
                .chunks_exact(3)
                .map(|t| {
                    let [a, b, c] = [t[0], t[1], t[2]]
                        .map(|i| inst.transform.transform_point3(m.positions[i as usize]));
                    tri_area(a, b, c) as f64
                })
                .sum::<f64>()
        })
        .sum()
}

/// Whether an authored TEXCOORD_1 can hold light-maps: inside [0, 1], charts that do not
/// overlap (under 1 % of the covered cells of a 256² grid covered twice; cells are counted
/// by their centres strictly inside a triangle, so shared edges do not count), and under 1 %
/// of the surface on triangles with no UV area. Err says what is wrong.
pub fn check_authored_uv(mesh: &lightlab_scene::Mesh) -> Result<(), String> {
    const GRID: usize = 256;
    let Some(uv) = &mesh.uv1 else {
        return Err("is missing".into());
    };
    if uv.len() != mesh.positions.len() {
        return Err("has the wrong length".into());
    }
    if uv
        .iter()
        .any(|u| !u.is_finite() || u.min_element() < -1e-3 || u.max_element() > 1.001)
    {
        return Err("leaves [0, 1]".into());
    }
    let mut cover = vec![0u8; GRID * GRID];
    let (mut world, mut flat) = (0.0f64, 0.0f64);
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| uv[i as usize] * GRID as f32);
        let [pa, pb, pc] = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]);
        let w = tri_area(pa, pb, pc) as f64;
        world += w;
        let det = (b - a).perp_dot(c - a);
        if det.abs() < 1e-9 {
            flat += w;
            continue;
        }
        let lo = a.min(b).min(c).floor().max(Vec2::ZERO);
        let hi = a.max(b).max(c).ceil().min(Vec2::splat(GRID as f32));
        for y in lo.y as usize..hi.y as usize {
            for x in lo.x as usize..hi.x as usize {
                let p = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let l1 = (p - a).perp_dot(c - a) / det;
                let l2 = (b - a).perp_dot(p - a) / det;
                if l1 > 1e-6 && l2 > 1e-6 && 1.0 - l1 - l2 > 1e-6 {
                    let k = &mut cover[y * GRID + x];
                    *k = k.saturating_add(1);
                }
            }
        }
    }
    let covered = cover.iter().filter(|&&k| k > 0).count();
    let twice = cover.iter().filter(|&&k| k > 1).count();
    if covered > 0 && twice as f64 > 0.01 * covered as f64 {
        return Err(format!(
            "overlaps itself ({:.0} % of its area is mapped more than once)",
            100.0 * twice as f64 / covered as f64
        ));
    }
    if world > 0.0 && flat > 0.01 * world {
        return Err(format!(
            "gives {:.0} % of the surface no area",
            100.0 * flat / world
        ));
    }
    Ok(())
}

/// Give every instanced mesh light-map UVs and return the layout. Meshes are rewritten where
/// the unwrap splits vertices along chart seams (all attributes are carried over).
pub fn unwrap_scene(scene: &mut Scene, settings: &LayoutSettings) -> Result<Layout, BakeError> {
    if !(settings.texels_per_metre.is_finite() && settings.texels_per_metre > 0.0) {
        return Err(BakeError::Settings(format!(
            "texel density must be positive, got {}",
            settings.texels_per_metre
        )));
    }
    if settings.max_page_size < 16 || settings.max_page_size > 16384 {
        return Err(BakeError::Settings(format!(
            "page size must be in [16, 16384], got {}",
            settings.max_page_size
        )));
    }
    let mut per_mesh: Vec<Vec<usize>> = vec![vec![]; scene.meshes.len()];
    for (i, inst) in scene.instances.iter().enumerate() {
        per_mesh[inst.mesh].push(i);
    }
    let mut instances = vec![None; scene.instances.len()];
    let mut pages: Vec<[u32; 2]> = vec![];
    let (todo, regenerated) = meshes_to_unwrap(scene, settings, &per_mesh);
    // Refuse a request that cannot fit before the unwrap allocates its raster.
    let area = surface_area(scene);
    let need = area * (settings.texels_per_metre as f64).powi(2);
    let page = settings.max_page_size as f64;
    if need > page * page {
        return Err(BakeError::Settings(format!(
            "the scene's {area:.1} m² need {need:.0} texels at {} per metre, more than one \
             {}² page holds; lower the texel density",
            settings.texels_per_metre, settings.max_page_size
        )));
    }
    let (charts, mut covered) = if todo.is_empty() {
        (0, 0.0)
    } else {
        unwrap_meshes(
            scene,
            settings,
            &todo,
            &per_mesh,
            &mut instances,
            &mut pages,
        )?
    };
    covered += authored_pages(
        scene,
        settings,
        &todo,
        &per_mesh,
        &mut instances,
        &mut pages,
    )?;
    let total: f64 = pages.iter().map(|p| p[0] as f64 * p[1] as f64).sum();
    Ok(Layout {
        settings: *settings,
        pages,
        instances,
        charts,
        utilization: if total > 0.0 {
            (covered / total) as f32
        } else {
            0.0
        },
        regenerated,
    })
}

/// The meshes to unwrap (instanced, with triangles, without usable authored UVs; by
/// `settings.lightmap_uv`) and a line for each mesh whose authored UVs were set aside or kept
/// though unusable.
fn meshes_to_unwrap(
    scene: &Scene,
    settings: &LayoutSettings,
    per_mesh: &[Vec<usize>],
) -> (Vec<usize>, Vec<String>) {
    let mut regenerated = vec![];
    let todo: Vec<usize> = (0..scene.meshes.len())
        .filter(|&m| {
            let mesh = &scene.meshes[m];
            if per_mesh[m].is_empty() || mesh.triangle_count() == 0 {
                return false;
            }
            match (mesh.uv1.is_some(), settings.lightmap_uv) {
                (false, _) | (true, LightmapUv::Generate) => true,
                (true, LightmapUv::Authored) => false,
                (true, LightmapUv::Auto) => match check_authored_uv(mesh) {
                    Ok(()) => false,
                    // Its textures read the authored set: replacing it would break them.
                    Err(why) if scene.materials[mesh.material].reads_uv_set(1) => {
                        regenerated.push(format!(
                            "mesh '{}': authored TEXCOORD_1 {why}, but its textures read it, so \
                             it is kept for light-maps too (expect seams)",
                            mesh.name
                        ));
                        false
                    }
                    Err(why) => {
                        regenerated.push(format!(
                            "mesh '{}': authored TEXCOORD_1 {why}; light-map UVs generated",
                            mesh.name
                        ));
                        true
                    }
                },
            }
        })
        .collect();
    (todo, regenerated)
}

/// Unwrap the meshes `todo` into one atlas: their rects go into `instances`, the atlas's pages
/// onto `pages`. Returns the charts made and the texels covered.
fn unwrap_meshes(
    scene: &mut Scene,
    settings: &LayoutSettings,
    todo: &[usize],
    per_mesh: &[Vec<usize>],
    instances: &mut [Option<InstanceRect>],
    pages: &mut Vec<[u32; 2]>,
) -> Result<(u32, f64), BakeError> {
    let positions: Vec<Vec<[f32; 3]>> = todo
        .iter()
        .map(|&m| {
            scene.meshes[m]
                .positions
                .iter()
                .map(|p| p.to_array())
                .collect()
        })
        .collect();
    let scales: Vec<Vec<f32>> = todo
        .iter()
        .map(|&m| {
            per_mesh[m]
                .iter()
                .map(|&i| instance_scale(&scene.instances[i].transform))
                .collect()
        })
        .collect();
    let inputs: Vec<uvunwrap::MeshInput> = todo
        .iter()
        .enumerate()
        .map(|(k, &m)| uvunwrap::MeshInput {
            instance_scales: &scales[k],
            ..uvunwrap::MeshInput::new(&positions[k], &scene.meshes[m].indices)
        })
        .collect();
    let options = uvunwrap::Options {
        density: uvunwrap::Density::Fixed {
            texels_per_unit: settings.texels_per_metre,
            page_size: None,
        },
        padding: settings.padding,
        max_chart_size: settings.max_page_size - 2 * settings.padding,
        ..Default::default()
    };
    let atlas =
        uvunwrap::generate(&inputs, &options).map_err(|e| BakeError::Unwrap(e.to_string()))?;
    if atlas.width > settings.max_page_size || atlas.height > settings.max_page_size {
        return Err(BakeError::Settings(format!(
            "the light-map page would be {}×{} texels, more than the largest page {}; \
             lower the texel density (now {} per metre)",
            atlas.width, atlas.height, settings.max_page_size, settings.texels_per_metre
        )));
    }
    for _ in 0..atlas.page_count {
        pages.push([atlas.width, atlas.height]);
    }
    let charts = atlas.chart_count;
    let covered = atlas.utilization as f64 * (atlas.width as f64 * atlas.height as f64);
    for (k, &m) in todo.iter().enumerate() {
        let out = &atlas.meshes[k];
        let mesh = &mut scene.meshes[m];
        remap_mesh(mesh, out);
        for (j, &i) in per_mesh[m].iter().enumerate() {
            let r = out.instances[j];
            instances[i] = Some(InstanceRect {
                page: r.page,
                offset: r.min,
                scale: [r.max[0] - r.min[0], r.max[1] - r.min[1]],
            });
        }
    }
    Ok((charts, covered))
}

/// Authored light-map UVs (the meshes not in `todo`): one page per instance, sized for the
/// texel density. Returns the texels covered.
fn authored_pages(
    scene: &Scene,
    settings: &LayoutSettings,
    todo: &[usize],
    per_mesh: &[Vec<usize>],
    instances: &mut [Option<InstanceRect>],
    pages: &mut Vec<[u32; 2]>,
) -> Result<f64, BakeError> {
    let mut covered = 0.0f64;
    for (m, insts) in per_mesh.iter().enumerate() {
        if todo.contains(&m) {
            continue;
        }
        let mesh = &scene.meshes[m];
        let Some(uv1) = &mesh.uv1 else { continue };
        if mesh.triangle_count() == 0 {
            continue;
        }
        if uv1.len() != mesh.positions.len() {
            return Err(BakeError::Scene(format!(
                "mesh '{}' has {} TEXCOORD_1 values for {} vertices",
                mesh.name,
                uv1.len(),
                mesh.positions.len()
            )));
        }
        let uv_area: f32 = mesh
            .indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| uv1[i as usize]);
                0.5 * (b - a).perp_dot(c - a).abs()
            })
            .sum();
        for &i in insts {
            let tf = scene.instances[i].transform;
            let area: f32 = mesh
                .indices
                .chunks_exact(3)
                .map(|t| {
                    let [a, b, c] =
                        [t[0], t[1], t[2]].map(|i| tf.transform_point3(mesh.positions[i as usize]));
                    tri_area(a, b, c)
                })
                .sum();
            let side = ((area / uv_area.max(1e-12)).sqrt() * settings.texels_per_metre).ceil();
            let side = (side as u32).clamp(8, settings.max_page_size);
            covered += (uv_area as f64 * side as f64 * side as f64).min((side * side) as f64);
            instances[i] = Some(InstanceRect {
                page: pages.len() as u32,
                offset: [0.0, 0.0],
                scale: [1.0, 1.0],
            });
            pages.push([side, side]);
        }
    }
    Ok(covered)
}

/// Rebuild a mesh from the unwrap's output vertices (`xref` = source vertex).
fn remap_mesh(mesh: &mut Mesh, out: &uvunwrap::OutputMesh) {
    // Per-vertex attributes follow their source vertex; absent ones stay absent.
    fn pick<T: Copy>(v: &[T], out: &uvunwrap::OutputMesh) -> Vec<T> {
        if v.is_empty() {
            vec![]
        } else {
            out.vertices.iter().map(|o| v[o.xref as usize]).collect()
        }
    }
    mesh.positions = pick(&mesh.positions, out);
    mesh.normals = pick(&mesh.normals, out);
    mesh.tangents = pick(&mesh.tangents, out);
    mesh.uv0 = pick(&mesh.uv0, out);
    mesh.colors = pick(&mesh.colors, out);
    mesh.uv1 = Some(out.vertices.iter().map(|o| Vec2::from(o.uv)).collect());
    mesh.indices = out.indices.clone();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cornell_unwraps_with_one_rect_per_instance_inside_its_page() {
        let mut s = lightlab_scene::builtin::builtin("cornell").unwrap();
        let tris: usize = s.meshes.iter().map(|m| m.triangle_count()).sum();
        let l = unwrap_scene(&mut s, &LayoutSettings::default()).unwrap();
        assert_eq!(l.instances.len(), s.instances.len());
        assert_eq!(
            s.meshes.iter().map(|m| m.triangle_count()).sum::<usize>(),
            tris
        );
        for (inst, r) in s.instances.iter().zip(&l.instances) {
            let r = r.unwrap();
            let [w, h] = l.pages[r.page as usize];
            let mesh = &s.meshes[inst.mesh];
            let uv1 = mesh.uv1.as_ref().unwrap();
            assert_eq!(uv1.len(), mesh.positions.len());
            for &u in uv1 {
                let p = r.page_uv(u) * Vec2::new(w as f32, h as f32);
                // Padding keeps every chart two texels from the page edges.
                assert!(
                    p.min_element() >= 1.99 && p.x <= w as f32 - 1.99 && p.y <= h as f32 - 1.99
                );
            }
        }
        assert!(
            l.utilization > 0.2 && l.utilization <= 1.0,
            "{}",
            l.utilization
        );
    }

    #[test]
    fn authored_uvs_are_checked_kept_or_replaced() {
        let base = lightlab_scene::builtin::builtin("cornell").unwrap();
        // A block of several faces, each of which maps its TEXCOORD_0 onto the whole square.
        let m = (0..base.meshes.len())
            .max_by_key(|&k| base.meshes[k].triangle_count())
            .unwrap();
        assert!(base.instances.iter().any(|i| i.mesh == m));
        // A texture set as TEXCOORD_1 (TEXCOORD_0 fitted into [0, 1]): the faces overlap.
        let uv0 = &base.meshes[m].uv0;
        let (lo, hi) = uv0
            .iter()
            .fold((Vec2::MAX, Vec2::MIN), |(l, h), u| (l.min(*u), h.max(*u)));
        let texture_set: Vec<Vec2> = uv0.iter().map(|u| (*u - lo) / (hi - lo)).collect();
        let mut s = base.clone();
        s.meshes[m].uv1 = Some(texture_set.clone());
        let e = check_authored_uv(&s.meshes[m]).unwrap_err();
        assert!(e.contains("overlaps"), "{e}");
        let l = unwrap_scene(&mut s, &LayoutSettings::default()).unwrap();
        assert!(
            l.regenerated.iter().any(|r| r.contains("generated")),
            "{:?}",
            l.regenerated
        );
        assert_ne!(s.meshes[m].uv1, Some(texture_set.clone()));
        // Good authored UVs pass the check: the generated layout of that same mesh does.
        let mut g = base.clone();
        unwrap_scene(&mut g, &LayoutSettings::default()).unwrap();
        check_authored_uv(&g.meshes[m]).unwrap();
        // Outside [0, 1], or collapsed: refused by the check.
        let mut out = g.meshes[m].clone();
        out.uv1.as_mut().unwrap()[0].x = 1.5;
        assert!(check_authored_uv(&out).unwrap_err().contains("[0, 1]"));
        let mut flat = g.meshes[m].clone();
        flat.uv1 = Some(vec![Vec2::splat(0.5); flat.positions.len()]);
        assert!(check_authored_uv(&flat).unwrap_err().contains("no area"));
        // `generate` replaces even good UVs; `authored` keeps even bad ones.
        let settings = |lightmap_uv| LayoutSettings {
            lightmap_uv,
            ..Default::default()
        };
        let mut a = base.clone();
        a.meshes[m].uv1 = Some(texture_set.clone());
        let l = unwrap_scene(&mut a, &settings(LightmapUv::Authored)).unwrap();
        assert!(l.regenerated.is_empty());
        assert_eq!(a.meshes[m].uv1, Some(texture_set));
        let mut r = g.clone();
        let before = r.meshes[m].uv1.clone();
        unwrap_scene(&mut r, &settings(LightmapUv::Generate)).unwrap();
        assert!(r.meshes[m].uv1.is_some() && r.meshes[m].positions.len() >= before.unwrap().len());
    }

    #[test]
    fn authored_uvs_are_kept_and_bad_settings_are_errors() {
        let mut s = lightlab_scene::builtin::builtin("cornell").unwrap();
        let m = s.instances[0].mesh;
        let uv: Vec<Vec2> = s.meshes[m].uv0.iter().map(|u| *u * 0.9 + 0.05).collect();
        s.meshes[m].uv1 = Some(uv.clone());
        let authored = LayoutSettings {
            lightmap_uv: LightmapUv::Authored,
            ..Default::default()
        };
        let l = unwrap_scene(&mut s, &authored).unwrap();
        assert_eq!(s.meshes[m].uv1.as_ref().unwrap(), &uv);
        let r = l.instances[0].unwrap();
        assert_eq!(r.scale, [1.0, 1.0]);
        assert!(l.pages.len() >= 2);
        let bad = LayoutSettings {
            texels_per_metre: -1.0,
            ..Default::default()
        };
        assert!(matches!(
            unwrap_scene(&mut s, &bad),
            Err(BakeError::Settings(_))
        ));
        let huge = LayoutSettings {
            texels_per_metre: 100000.0,
            max_page_size: 1024,
            ..Default::default()
        };
        let mut s = lightlab_scene::builtin::builtin("cornell").unwrap();
        assert!(matches!(
            unwrap_scene(&mut s, &huge),
            Err(BakeError::Settings(_))
        ));
    }
}

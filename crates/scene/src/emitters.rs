//! Emissive instances as area lights for the rasteriser: each roughly planar emissive instance
//! reduced to a Lambertian rectangle (centre, unit normal, half-edges, radiance).
//!
//! The path tracer samples emissive triangles one by one and needs none of this; the GPU
//! techniques, which light with a fixed list of lights, use it for direct light from lamps
//! that are geometry (cornell's ceiling light), and the light propagation volume for the
//! reflective shadow map of such a lamp.

use crate::Scene;
use glam::Vec3;

/// An emissive instance seen as a Lambertian rectangle of the same area, centre and normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanarEmitter {
    pub instance: usize,
    /// Area-weighted centroid (world space).
    pub centre: Vec3,
    /// Unit normal of the emitting (authored front) side: the area-weighted mean of its
    /// triangles' normals.
    pub normal: Vec3,
    /// Total area (m²).
    pub area: f32,
    /// Emitted radiance: the material's emission, times the area-weighted mean of its emissive
    /// texture over the instance when it has one.
    pub radiance: Vec3,
    /// Half-edges of the rectangle: its corners are centre ± u ± v, and 4·|u|·|v| = area.
    pub half_u: Vec3,
    pub half_v: Vec3,
    pub double_sided: bool,
}

/// A world-space triangle and its area.
type Tri = ([Vec3; 3], f32);

impl Scene {
    /// The emissive instances that are roughly planar (|Σ aᵢnᵢ| ≥ ½·Σ aᵢ), brightest (radiance
    /// luminance × area) first. Others are left out: a Lambertian rectangle would misrepresent
    /// them. So is a luminaire's geometry (`Instance::luminaire`): its emitter sits behind
    /// reflectors, lenses and a housing, and its light reaches the room through its window (a
    /// canned light, or the reference's lamp emitter), not as a bare rectangle.
    pub fn planar_emitters(&self) -> Vec<PlanarEmitter> {
        let mut out = vec![];
        for (ii, inst) in self.instances.iter().enumerate() {
            if inst.luminaire.is_some() {
                continue;
            }
            let Some(mesh) = self.meshes.get(inst.mesh) else {
                continue;
            };
            let Some(mat) = self.materials.get(mesh.material) else {
                continue;
            };
            let mut radiance = mat.emission();
            if radiance.max_element() <= 0.0 {
                continue;
            }
            let world = |i: u32| inst.transform.transform_point3(mesh.positions[i as usize]);
            let tris: Vec<Tri> = mesh
                .indices
                .chunks_exact(3)
                .map(|t| {
                    let p = [world(t[0]), world(t[1]), world(t[2])];
                    (p, 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length())
                })
                .collect();
            let (mut area, mut na, mut ca) = (0.0f32, Vec3::ZERO, Vec3::ZERO);
            for (p, a) in &tris {
                area += a;
                na += 0.5 * (p[1] - p[0]).cross(p[2] - p[0]);
                ca += *a * (p[0] + p[1] + p[2]) / 3.0;
            }
            if area <= 0.0 || !area.is_finite() || na.length() < 0.5 * area {
                continue;
            }
            let normal = na.normalize();
            let centre = ca / area;
            if let Some(r) = mat.emissive_texture
                && let Some(tex) = self.textures.get(r.texture)
            {
                let uvs: Vec<_> = (0..mesh.positions.len())
                    .map(|i| r.uv(&mesh.attrs_of(i)))
                    .collect();
                if let Some(mean) = texture_mean(tex, &uvs, &mesh.indices, &tris) {
                    radiance *= mean;
                }
                if radiance.max_element() <= 0.0 {
                    continue;
                }
            }
            let (half_u, half_v) = bounding_rectangle(&tris, centre, normal, area);
            out.push(PlanarEmitter {
                instance: ii,
                centre,
                normal,
                area,
                radiance,
                half_u,
                half_v,
                double_sided: mat.double_sided,
            });
        }
        let power = |e: &PlanarEmitter| lightlab_core::color::luminance(e.radiance) * e.area;
        out.sort_by(|a, b| power(b).total_cmp(&power(a)));
        out
    }
}

/// The area-weighted mean of `tex` over the triangles (`indices` into `uvs`), from the
/// centroids of an n × n subdivision of each (n² equal parts); None without usable UVs.
fn texture_mean(
    tex: &crate::Texture,
    uvs: &[glam::Vec2],
    indices: &[u32],
    tris: &[Tri],
) -> Option<Vec3> {
    let n = (16.0 / (tris.len() as f32).sqrt()).clamp(1.0, 8.0) as u32;
    let nf = n as f32;
    let (mut sum, mut w) = (Vec3::ZERO, 0.0f32);
    for (t, (_, a)) in indices.chunks_exact(3).zip(tris) {
        let Some(uv) = t
            .iter()
            .map(|&i| uvs.get(i as usize).copied())
            .collect::<Option<Vec<_>>>()
        else {
            continue;
        };
        let at = |b1: f32, b2: f32| {
            let q = uv[0] + (uv[1] - uv[0]) * (b1 / nf) + (uv[2] - uv[0]) * (b2 / nf);
            tex.sample(q).truncate()
        };
        let mut tsum = Vec3::ZERO;
        for i in 0..n {
            for j in 0..n - i {
                let (fi, fj) = (i as f32, j as f32);
                tsum += at(fi + 1.0 / 3.0, fj + 1.0 / 3.0);
                if i + j + 1 < n {
                    tsum += at(fi + 2.0 / 3.0, fj + 2.0 / 3.0);
                }
            }
        }
        sum += *a * tsum / (n * n) as f32;
        w += a;
    }
    (w > 0.0).then(|| sum / w)
}

/// Half-edges of the rectangle standing for planar triangles of total `area` around `centre`:
/// the smallest bounding rectangle over candidate axes (the principal axis of the exact area
/// moments, and the edges of small meshes, one of which is a side of the minimal rectangle of a
/// polygon), scaled to the true area (a rectangle stays itself; a disc becomes the square of
/// its area).
fn bounding_rectangle(tris: &[Tri], centre: Vec3, normal: Vec3, area: f32) -> (Vec3, Vec3) {
    let (t, b) = normal.any_orthonormal_pair();
    let (mut sxx, mut syy, mut sxy) = (0.0f32, 0.0f32, 0.0f32);
    for (p, a) in tris {
        // ∫ x xᵀ dA over a triangle = A/12 · (aaᵀ + bbᵀ + ccᵀ + ssᵀ), s = a + b + c.
        let d = p.map(|q| q - centre);
        let s = d[0] + d[1] + d[2];
        for q in [d[0], d[1], d[2], s] {
            let (x, y) = (q.dot(t), q.dot(b));
            sxx += a / 12.0 * x * x;
            syy += a / 12.0 * y * y;
            sxy += a / 12.0 * x * y;
        }
    }
    let mut angles = vec![0.5 * (2.0 * sxy).atan2(sxx - syy)];
    if tris.len() <= 64 {
        for (p, _) in tris {
            for k in 0..3 {
                let e = p[(k + 1) % 3] - p[k];
                angles.push(e.dot(b).atan2(e.dot(t)));
            }
        }
    }
    let extents = |phi: f32| {
        let ax = t * phi.cos() + b * phi.sin();
        let ay = normal.cross(ax);
        let (mut hx, mut hy) = (0.0f32, 0.0f32);
        for p in tris.iter().flat_map(|(p, _)| p) {
            let d = *p - centre;
            hx = hx.max(d.dot(ax).abs());
            hy = hy.max(d.dot(ay).abs());
        }
        (ax, ay, hx, hy)
    };
    let (ax, ay, hx, hy) = angles
        .iter()
        .map(|&phi| extents(phi))
        .min_by(|a, b| (a.2 * a.3).total_cmp(&(b.2 * b.3)))
        .unwrap_or((t, b, 0.0, 0.0));
    let fit = 4.0 * hx * hy;
    let (hx, hy) = if fit > 0.0 {
        let k = (area / fit).sqrt();
        (hx * k, hy * k)
    } else {
        let s = 0.5 * area.sqrt();
        (s, s)
    };
    (ax * hx, ay * hy)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cornell_lamp_is_its_own_rectangle() {
        let s = crate::builtin::builtin("cornell").unwrap();
        let e = s.planar_emitters();
        assert_eq!(e.len(), 1);
        let e = e[0];
        // 130 mm × 105 mm at y = 548.7 mm, facing down.
        assert!((e.area - 0.130 * 0.105).abs() < 1e-6, "{}", e.area);
        assert!((e.normal - Vec3::NEG_Y).length() < 1e-5);
        assert!((e.centre - Vec3::new(0.278, 0.5487, 0.2795)).length() < 1e-5);
        let (u, v) = (e.half_u.length(), e.half_v.length());
        let (big, small) = (u.max(v), u.min(v));
        assert!((big - 0.065).abs() < 1e-5 && (small - 0.0525).abs() < 1e-5);
        assert!(e.half_u.dot(e.half_v).abs() < 1e-7 && e.half_u.dot(e.normal).abs() < 1e-7);
        assert!((e.radiance - Vec3::new(17.0, 12.0, 4.0)).length() < 1e-4);
    }

    #[test]
    fn an_emissive_texture_scales_the_radiance_by_its_mean() {
        let mut s = crate::builtin::builtin("cornell").unwrap();
        // Left half black, right half (1, 0.5, 0.25) over the lamp's UVs.
        let tex = crate::Texture {
            name: "half".into(),
            width: 2,
            height: 1,
            texels: crate::Texels::Rgba32F(vec![
                glam::Vec4::new(0.0, 0.0, 0.0, 1.0),
                glam::Vec4::new(1.0, 0.5, 0.25, 1.0),
            ]),
            srgb: false,
        };
        s.textures.push(tex);
        let lamp = s.materials.iter().position(|m| m.name == "light").unwrap();
        // The lamp's UVs over the texture's whole period.
        let mesh = s.meshes.iter_mut().find(|m| m.material == lamp).unwrap();
        assert_eq!(mesh.uv0.len(), 4);
        mesh.uv0 = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
            .map(glam::Vec2::from_array)
            .to_vec();
        s.materials[lamp].emissive_texture = Some(crate::TextureRef::new(s.textures.len() - 1, 0));
        let e = s.planar_emitters()[0];
        let want = Vec3::new(17.0, 12.0, 4.0) * Vec3::new(0.5, 0.25, 0.125);
        assert!(
            (e.radiance - want).length() < 0.05 * want.length(),
            "{} vs {want}",
            e.radiance
        );
    }

    #[test]
    fn a_rotated_quad_keeps_its_corners_and_curved_emitters_are_left_out() {
        let mut s = Scene::default();
        let m = s.add_material(crate::Material {
            emissive: Vec3::ONE,
            emissive_strength: 2.0,
            ..Default::default()
        });
        let rot = glam::Mat4::from_rotation_y(0.6) * glam::Mat4::from_rotation_x(1.1);
        let quad = crate::Mesh {
            name: "q".into(),
            positions: vec![
                Vec3::new(-0.3, -0.1, 0.0),
                Vec3::new(0.3, -0.1, 0.0),
                Vec3::new(0.3, 0.1, 0.0),
                Vec3::new(-0.3, 0.1, 0.0),
            ],
            normals: vec![Vec3::Z; 4],
            uv0: vec![glam::Vec2::ZERO; 4],
            indices: vec![0, 1, 2, 0, 2, 3],
            material: m,
            ..Default::default()
        };
        s.add_mesh(quad, glam::Mat4::from_translation(Vec3::ONE) * rot);
        // A closed box emits in every direction: not planar.
        let cube = crate::builtin::geom::aabb_box("c", Vec3::splat(-0.5), Vec3::splat(0.5), m);
        s.add_mesh(cube, glam::Mat4::IDENTITY);
        let e = s.planar_emitters();
        assert_eq!(e.len(), 1, "{e:?}");
        let e = e[0];
        let n = rot.transform_vector3(Vec3::Z);
        assert!((e.normal - n).length() < 1e-5);
        assert!((e.centre - Vec3::ONE).length() < 1e-5);
        assert!((e.area - 0.12).abs() < 1e-6);
        let long = rot.transform_vector3(Vec3::X) * 0.3;
        let along = e.half_u.dot(long).abs().max(e.half_v.dot(long).abs()) / 0.3;
        assert!((along - 0.3).abs() < 1e-4, "{along} {e:?}");
    }
}

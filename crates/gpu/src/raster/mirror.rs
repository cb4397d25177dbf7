//! Planar mirrors (Heidrich 1999 ch. 10 intro, after Diefenbach 1994/96): the scene seen in a
//! flat mirror is the scene drawn from the mirrored eye. Environment maps cannot show it: a
//! large reflector beside other geometry sees that geometry at a parallax no map from one
//! centre holds.
//!
//! Each planar mirror of the scene ([`find`]) gets a child [`Renderer`] of the same scene and
//! settings that draws, every frame, the view from the eye reflected in the mirror's plane
//! (camera transform premultiplied by the reflection, so the winding flips: its pipelines
//! take clockwise front faces), leaves the mirror out, and discards what lies behind the
//! mirror's plane (the frame's clip plane, tested with the alpha test). Its image is
//! pixel-aligned with the main camera's: a point x seen in the mirror at pixel p is the point
//! M·x that the main camera would see at p. The main frame copies it into a layer of the
//! environment term's extras array and the mirror's fragments take Fresnel × that pixel
//! instead of the environment map (`env_planar_mirror` in env.wgsl).
//!
//! Deviation from the seed: Diefenbach marks the reflector in the stencil and draws the
//! mirrored scene into the same frame through it. Here the stencil belongs to each light's
//! shadow volumes (cleared per light), so the mirrored scene is drawn into its own target,
//! restricted to the mirror's screen rectangle (scissor), and read back only at the mirror's
//! own fragments: the same pixels with no resampling, unlike his texture variant. One level
//! of reflection: a mirror seen in another mirror shows the environment map.

use super::Renderer;
use crate::GpuContext;
use glam::{Mat4, Vec3, Vec4};
use lightlab_scene::{Camera, Scene};

/// Materials at most this rough are mirrors (the path tracer's and shader's GGX α = r²
/// reaches their 1e-3 floor at r ≈ 0.03).
pub const MAX_ROUGHNESS: f32 = 0.03;
/// At most this many planar mirrors get their own reflection (the largest first); each
/// costs a frame of the scene.
pub const MAX_MIRRORS: usize = 4;

/// A planar mirror of a scene.
#[derive(Clone, Debug)]
pub struct PlanarMirror {
    pub instance: usize,
    /// (n, d), n·x + d = 0, n along the mirror's front (its triangles' winding).
    pub plane: Vec4,
    /// Its vertices in world space (the screen rectangle's corners).
    pub points: Vec<Vec3>,
    pub area: f32,
    /// Whether its back reflects too.
    pub double_sided: bool,
}

/// Whether a material reflects as a mirror: metallic, smooth, without roughness or normal
/// textures, not transmissive.
fn mirror_material(m: &lightlab_scene::Material) -> bool {
    m.metallic >= 0.9
        && m.roughness <= MAX_ROUGHNESS
        && m.metallic_roughness_texture.is_none()
        && m.specular_transmission <= 0.0
        && m.normal_texture.is_none()
        && m.brdf != lightlab_scene::BrdfModel::Lambert
}

/// The planar mirrors of `scene`: instances of a mirror material whose vertices all lie on one
/// plane (within 1e-4 of their extent), not part of a luminaire; the largest
/// [`MAX_MIRRORS`], largest first.
pub fn find(scene: &Scene) -> Vec<PlanarMirror> {
    let mut found = vec![];
    for (i, inst) in scene.instances.iter().enumerate() {
        let mesh = &scene.meshes[inst.mesh];
        let Some(mat) = scene.materials.get(mesh.material) else {
            continue;
        };
        if inst.luminaire.is_some() || !mirror_material(mat) || mesh.indices.len() < 3 {
            continue;
        }
        // Only the vertices the triangles use: glTF primitives may share a larger accessor.
        let mut used = vec![false; mesh.positions.len()];
        for &i in &mesh.indices {
            if let Some(u) = used.get_mut(i as usize) {
                *u = true;
            }
        }
        let world = |i: u32| inst.transform.transform_point3(mesh.positions[i as usize]);
        let mut area_normal = Vec3::ZERO;
        for t in mesh.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| world(t[k]));
            area_normal += (b - a).cross(c - a);
        }
        let points: Vec<Vec3> = (0..mesh.positions.len() as u32)
            .filter(|&i| used[i as usize])
            .map(world)
            .collect();
        let area = area_normal.length() * 0.5;
        if area <= 1e-8 {
            continue;
        }
        let n = area_normal.normalize();
        let centre = points.iter().sum::<Vec3>() / points.len() as f32;
        let extent = points
            .iter()
            .map(|p| p.distance(centre))
            .fold(0.0f32, f32::max);
        if points
            .iter()
            .any(|p| (*p - centre).dot(n).abs() > 1e-4 * extent.max(1e-3))
        {
            continue;
        }
        found.push(PlanarMirror {
            instance: i,
            plane: n.extend(-n.dot(centre)),
            points,
            area,
            double_sided: mat.double_sided,
        });
    }
    found.sort_by(|a, b| b.area.total_cmp(&a.area));
    found.truncate(MAX_MIRRORS);
    found
}

/// The reflection in plane (n, d): x ↦ x − 2(n·x + d)n.
pub fn reflection(plane: Vec4) -> Mat4 {
    let n = plane.truncate();
    let d = plane.w;
    let c = |axis: Vec3| axis - 2.0 * n.dot(axis) * n;
    Mat4::from_cols(
        c(Vec3::X).extend(0.0),
        c(Vec3::Y).extend(0.0),
        c(Vec3::Z).extend(0.0),
        (-2.0 * d * n).extend(1.0),
    )
}

/// A mirror and the renderer of its reflected view.
pub(super) struct Mirror {
    pub(super) found: PlanarMirror,
    pub(super) child: Box<Renderer>,
    /// Whether the camera sees the mirror's reflecting side (its reflection is drawn).
    pub(super) active: bool,
}

impl Mirror {
    /// Follow the main camera: the child sees from the mirrored eye (through the same lens
    /// view), clips at the plane on the camera's side, and draws only the mirror's screen
    /// rectangle under `view_proj`.
    pub(super) fn follow(
        &mut self,
        ctx: &GpuContext,
        camera: &Camera,
        eye: Vec3,
        lens: Option<(Mat4, Vec3)>,
        view_proj: Mat4,
    ) {
        let p = self.found.plane;
        let side = p.truncate().dot(eye) + p.w;
        self.active = side > 0.0 || (self.found.double_sided && side < 0.0);
        if !self.active {
            return;
        }
        // The side the camera is on is the real scene's.
        let plane = if side > 0.0 { p } else { -p };
        let mut c = camera.clone();
        c.transform = reflection(plane) * camera.transform;
        self.child.frame.clip_plane = plane.to_array();
        self.child.lens = lens;
        self.child.set_camera(ctx, c);
        let (w, h) = self.child.size();
        self.child.clip_rect = screen_rect(&self.found.points, view_proj, w, h);
        self.active = self.child.clip_rect.is_some();
    }
}

impl Renderer {
    /// Draw the reflected view of every mirror the camera sees (each its own submission);
    /// their GPU time goes under "planar mirrors".
    pub(super) fn render_mirrors(&mut self, ctx: &GpuContext, times: &mut super::FrameTimes) {
        if self.mirrors.is_empty() {
            return;
        }
        let mut ms = 0.0;
        for m in self.mirrors.iter_mut().filter(|m| m.active) {
            let t = m.child.render(ctx);
            ms += t.gpu_ms.values().sum::<f64>();
        }
        times.gpu_ms.insert("planar mirrors", ms);
    }

    /// The reflected views into the layers the environment term reads.
    pub(super) fn copy_mirror_images(&self, enc: &mut wgpu::CommandEncoder) {
        for (k, m) in self.mirrors.iter().enumerate().filter(|(_, m)| m.active) {
            let (w, h) = m.child.size();
            enc.copy_texture_to_texture(
                m.child.targets.hdr.as_image_copy(),
                wgpu::TexelCopyTextureInfo {
                    texture: &self.env.extra,
                    mip_level: 0,
                    // Layer 0 holds the split-sum table.
                    origin: wgpu::Origin3d {
                        x: 0,
                        y: 0,
                        z: k as u32 + 1,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: 1,
                },
            );
        }
    }
}

/// The pixel rectangle (x, y, w, h) covering `points` under `view_proj` on a `w`×`h` frame:
/// the whole frame when a point is behind the eye, None when it is empty.
fn screen_rect(points: &[Vec3], view_proj: Mat4, w: u32, h: u32) -> Option<(u32, u32, u32, u32)> {
    let (mut lo, mut hi) = (glam::Vec2::splat(f32::MAX), glam::Vec2::splat(f32::MIN));
    for p in points {
        let q = view_proj * p.extend(1.0);
        if q.w <= 1e-5 {
            return Some((0, 0, w, h));
        }
        let ndc = glam::Vec2::new(q.x, q.y) / q.w;
        lo = lo.min(ndc);
        hi = hi.max(ndc);
    }
    let px = |x: f32, n: u32| ((x * n as f32).max(0.0) as u32).min(n);
    let x0 = px(((lo.x + 1.0) * 0.5).min(1.0), w).saturating_sub(1);
    let x1 = (px((hi.x + 1.0) * 0.5, w) + 1).min(w);
    let y0 = px(((1.0 - hi.y) * 0.5).min(1.0), h).saturating_sub(1);
    let y1 = (px((1.0 - lo.y) * 0.5, h) + 1).min(h);
    (x1 > x0 && y1 > y0).then_some((x0, y0, x1 - x0, y1 - y0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reflection_maps_the_plane_to_itself_and_swaps_its_sides() {
        let plane = Vec3::new(1.0, 2.0, -0.5).normalize().extend(0.7);
        let m = reflection(plane);
        let n = plane.truncate();
        let on = -0.7 * n + Vec3::new(2.0, -1.0, 0.0).cross(n);
        assert!(m.transform_point3(on).distance(on) < 1e-5);
        let x = Vec3::new(0.3, 1.1, -2.0);
        let side = |p: Vec3| n.dot(p) + plane.w;
        assert!((side(m.transform_point3(x)) + side(x)).abs() < 1e-5);
        assert!(m.determinant() < 0.0);
        assert!((m * m).abs_diff_eq(Mat4::IDENTITY, 1e-5));
    }

    #[test]
    fn the_mirror_scene_has_one_planar_mirror_and_spheres_have_none() {
        let s = lightlab_scene::builtin::builtin("mirror").expect("built in");
        let found = find(&s);
        assert_eq!(found.len(), 1);
        assert_eq!(s.instances[found[0].instance].name, "mirror");
        let n = found[0].plane.truncate();
        assert!(n.abs_diff_eq(Vec3::Z, 1e-5), "{n}");
        // A chrome sphere is smooth but not flat; the luminaire's reflector is lamp geometry.
        for name in ["spheres", "luminaire", "cornell"] {
            let s = lightlab_scene::builtin::builtin(name).expect("built in");
            assert!(find(&s).is_empty(), "{name}");
        }
    }

    #[test]
    fn the_screen_rectangle_covers_the_points() {
        let vp = Mat4::IDENTITY;
        let pts = [Vec3::new(-0.5, -0.5, 0.5), Vec3::new(0.5, 0.25, 0.5)];
        let (x, y, w, h) = screen_rect(&pts, vp, 100, 100).expect("on screen");
        assert!(
            x <= 25 && x + w >= 75 && y <= 37 && y + h >= 75,
            "{x} {y} {w} {h}"
        );
        let behind = [Vec3::new(0.0, 0.0, 0.5)];
        let vp_behind = Mat4::from_cols(Vec4::X, Vec4::Y, Vec4::Z, Vec4::new(0.0, 0.0, 0.0, -1.0));
        assert_eq!(
            screen_rect(&behind, vp_behind, 64, 32),
            Some((0, 0, 64, 32))
        );
    }
}

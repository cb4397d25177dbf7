//! Scene lights on the GPU: attenuation (Fuchs 2005 §4.1), light radii for culling and
//! scissoring, and the shadow-map views of each light (spot, point cube faces, cascaded
//! directional).

use crate::uniforms::{GpuLight, ShadowView};
use glam::camera::rh::proj::directx;
use glam::camera::rh::view::look_to_mat4;
use glam::{Mat4, Vec3, Vec4};
use lightlab_scene::{Camera, Light, LightKind};

/// How irradiance falls off with distance.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Attenuation {
    /// Physical 1/d², with the glTF range window `clamp(1 − (d/r)⁴)²` when a range is set: the
    /// path tracer's model, for comparisons with the reference.
    InverseSquare,
    /// Fuchs's atten₁ = min(1, 1/(b·d)); the thesis's b ≈ 0.0005 is per Ca3DE unit (≈ mm), so
    /// b = 0.5 m⁻¹ here. Never reaches 0: no culling radius.
    Fuchs1,
    /// atten₂ = max(1 − d/r, 0).
    Fuchs2,
    /// atten₃ = max(1 − d/r, 0)² (the thesis writes (1 − d/r)², which grows again past r: erratum).
    Fuchs3,
    /// atten₄ = max(1 − (d/r)², 0), the thesis's final choice.
    Fuchs4,
}

lightlab_core::named_enum!(Attenuation, "attenuation", {
    InverseSquare => "inverse-square",
    Fuchs1 => "fuchs1",
    Fuchs2 => "fuchs2",
    Fuchs3 => "fuchs3",
    Fuchs4 => "fuchs4",
});

impl Attenuation {
    fn code(self) -> u32 {
        match self {
            Attenuation::InverseSquare => 0,
            Attenuation::Fuchs1 => 1,
            Attenuation::Fuchs2 => 2,
            Attenuation::Fuchs3 => 3,
            Attenuation::Fuchs4 => 4,
        }
    }

    /// The factor c in E(d) = I·c·atten(d). The thesis's functions are unitless (light colours
    /// in [0,1]); to keep lights of different radii comparable with physical ones, c makes the
    /// flux through spheres of radius d ∈ [0, r], averaged over d, equal the physical 4πI:
    /// c = r / ∫₀ʳ d²·atten(d) dd. For atten₁, c = b² (physical at d = 1/b).
    pub fn scale(self, r: f32) -> f32 {
        let r2 = r * r;
        match self {
            Attenuation::InverseSquare => 1.0,
            Attenuation::Fuchs1 => 0.25,
            Attenuation::Fuchs2 => 12.0 / r2,
            Attenuation::Fuchs3 => 30.0 / r2,
            Attenuation::Fuchs4 => 7.5 / r2,
        }
    }
}

/// Irradiance below which a light without a glTF range is considered out of reach when an
/// attenuation function needs a radius: r = √(I·max(colour) / E_MIN).
pub const E_MIN: f32 = 0.05;

/// The radius r of a light under `atten` (None = unbounded): glTF `range`, else the override,
/// else √(I·max(colour)/[`E_MIN`]) for the Fuchs functions that need one.
pub fn light_radius(light: &Light, atten: Attenuation, radius: Option<f32>) -> Option<f32> {
    if matches!(light.kind, LightKind::Directional { .. }) {
        return None;
    }
    match atten {
        Attenuation::InverseSquare => light.range,
        Attenuation::Fuchs1 => None,
        _ => Some(
            radius
                .or(light.range)
                .unwrap_or_else(|| (light.peak_intensity() / E_MIN).sqrt()),
        ),
    }
}

/// A light as the shaders see it (shadow fields and a goniometric light's profile layer left
/// empty); `r` is its [`light_radius`].
pub fn gpu_light(light: &Light, atten: Attenuation, r: Option<f32>) -> GpuLight {
    let (kind, cos_inner, cos_outer) = match &light.kind {
        LightKind::Point => (0, 1.0, 1.0),
        LightKind::Spot {
            inner_cone,
            outer_cone,
        } => (1, inner_cone.cos(), outer_cone.cos()),
        LightKind::Directional { .. } => (2, 1.0, 1.0),
        LightKind::Goniometric { .. } => (4, 1.0, 1.0),
    };
    // A goniometric light's tilt factor is constant (its orientation is fixed): folded into
    // the intensity; its C0 axis, at right angles to its direction, rides in edge_u.
    let (tilt, c0) = match &light.kind {
        LightKind::Goniometric { profile, .. } => (
            profile.tilt_factor(light.tilt_angle()),
            light.local_frame().row(0),
        ),
        _ => (1.0, Vec3::ZERO),
    };
    GpuLight {
        position: light.position.to_array(),
        kind,
        direction: light.direction.normalize().to_array(),
        range: r.unwrap_or(0.0),
        color: light.color.to_array(),
        intensity: light.intensity * tilt,
        edge_u: c0.to_array(),
        cos_inner,
        cos_outer,
        atten_scale: atten.scale(r.unwrap_or(1.0)),
        attenuation: if kind == 2 { 0 } else { atten.code() },
        ..Default::default()
    }
}

/// A view and projection for rendering a shadow map.
#[derive(Clone, Copy, Debug)]
pub struct ShadowProjection {
    pub view_proj: Mat4,
    pub texel_scale: f32,
    pub ortho: bool,
    pub far: f32,
}

impl ShadowProjection {
    pub fn gpu(&self) -> ShadowView {
        ShadowView {
            view_proj: self.view_proj.to_cols_array_2d(),
            texel_scale: self.texel_scale,
            ortho: self.ortho as u32,
            far: self.far,
            near: if self.ortho { 0.0 } else { SHADOW_NEAR },
        }
    }
}

fn any_up(dir: Vec3) -> Vec3 {
    if dir.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y }
}

/// The eight corners of the box `(lo, hi)`.
pub fn box_corners((lo, hi): (Vec3, Vec3)) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

/// Near plane of perspective shadow views.
pub const SHADOW_NEAR: f32 = 0.05;

/// Far distance of a point or spot light's shadow views: its radius, or the farthest corner of
/// the scene bounds.
pub fn shadow_far(light: &Light, radius: Option<f32>, bounds: (Vec3, Vec3)) -> f32 {
    let far = box_corners(bounds)
        .iter()
        .map(|c| (*c - light.position).length())
        .fold(0.0f32, f32::max);
    let far = far * 1.01 + SHADOW_NEAR;
    radius.map_or(far, |r| r.min(far)).max(SHADOW_NEAR * 2.0)
}

/// A spot light's shadow view: a perspective frustum around the outer cone.
pub fn spot_view(light: &Light, outer_cone: f32, far: f32, size: u32) -> ShadowProjection {
    let fov = (2.0 * outer_cone + 0.05).min(3.0);
    let view = look_to_mat4(light.position, light.direction, any_up(light.direction));
    let proj = directx::perspective(fov, 1.0, SHADOW_NEAR, far);
    ShadowProjection {
        view_proj: proj * view,
        texel_scale: 2.0 * (fov * 0.5).tan() / size as f32,
        ortho: false,
        far,
    }
}

/// The six cube faces of a point light, in the order +X, −X, +Y, −Y, +Z, −Z (the shader picks
/// the face by the major axis). Each face's field of view is widened by two texels so that PCF
/// taps at a face edge stay inside the face.
pub fn point_views(light: &Light, far: f32, size: u32) -> [ShadowProjection; 6] {
    let half = 1.0 + 2.0 / size as f32;
    let fov = 2.0 * half.atan();
    let dirs = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    dirs.map(|d| {
        let view = look_to_mat4(light.position, d, any_up(d));
        let proj = directx::perspective(fov, 1.0, SHADOW_NEAR, far);
        ShadowProjection {
            view_proj: proj * view,
            texel_scale: 2.0 * half / size as f32,
            ortho: false,
            far,
        }
    })
}

/// Cascade ends (view-space distances) by the practical split scheme (Zhang et al. 2006):
/// a blend λ of logarithmic and uniform splits.
pub fn cascade_ends(near: f32, far: f32, count: usize, lambda: f32) -> Vec<f32> {
    (1..=count)
        .map(|i| {
            let f = i as f32 / count as f32;
            let log = near * (far / near).powf(f);
            let uni = near + (far - near) * f;
            lambda * log + (1.0 - lambda) * uni
        })
        .collect()
}

/// The smallest sphere around a frustum slice whose near and far faces, at view distances `a`
/// and `b`, have corners `ra` and `rb` off the view axis: its centre's view distance and its
/// radius. The centre lies on the axis where the near and far corners are equally far, or on
/// the far face when that point lies beyond it. (The corners' centroid, used before, gave
/// spheres 8–10 % wider for the bush's view, and texels as much coarser.)
pub fn slice_sphere(a: f32, b: f32, ra: f32, rb: f32) -> (f32, f32) {
    let z = ((b * b - a * a + rb * rb - ra * ra) / (2.0 * (b - a)).max(1e-6)).clamp(a, b);
    let radius = ((z - a).hypot(ra)).max((b - z).hypot(rb));
    (z, radius)
}

/// Cascaded shadow views of a directional light for a camera: each cascade is an orthographic
/// view of the bounding sphere of its slice of the view frustum (so its size does not change
/// as the camera turns), with the centre snapped to whole texels (no shimmering when the camera
/// moves), and a depth range covering the whole scene (casters outside the frustum count).
pub fn cascade_views(
    direction: Vec3,
    camera: &Camera,
    aspect: f32,
    ends: &[f32],
    near: f32,
    bounds: (Vec3, Vec3),
    size: u32,
) -> Vec<ShadowProjection> {
    let dir = direction.normalize();
    let light_view = look_to_mat4(Vec3::ZERO, dir, any_up(dir));
    let mut zmin = f32::INFINITY;
    let mut zmax = f32::NEG_INFINITY;
    for c in box_corners(bounds) {
        let z = light_view.transform_point3(c).z;
        zmin = zmin.min(z);
        zmax = zmax.max(z);
    }
    let t = (camera.yfov * 0.5).tan();
    // The slice's corners lie at distance r(d) = d·t·√(aspect² + 1) from the view axis.
    let spread = t * (aspect * aspect + 1.0).sqrt();
    let mut start = near;
    ends.iter()
        .map(|&end| {
            let (z, radius) = slice_sphere(start, end, start * spread, end * spread);
            start = end;
            let center = camera.transform.transform_point3(Vec3::new(0.0, 0.0, -z));
            // Round the radius up so it changes in steps, and snap the centre to texels.
            let radius = (radius * 16.0).ceil() / 16.0;
            let texel = 2.0 * radius / size as f32;
            let mut lc = light_view.transform_point3(center);
            lc.x = (lc.x / texel).round() * texel;
            lc.y = (lc.y / texel).round() * texel;
            // Light space looks down −z: visible depths are −z ∈ [−zmax, −zmin].
            let proj = directx::orthographic(
                lc.x - radius,
                lc.x + radius,
                lc.y - radius,
                lc.y + radius,
                -zmax - 0.01,
                -zmin + 0.01,
            );
            ShadowProjection {
                view_proj: proj * light_view,
                texel_scale: texel,
                ortho: true,
                far: 1.0,
            }
        })
        .collect()
}

/// The planar projection that flattens geometry onto the plane P·x = 0 (P = (n, d)) as seen
/// from the homogeneous light position L (w = 1 point, w = 0 direction towards the light):
/// M = (P·L)·I − L·Pᵀ (Blinn 1988; Heidrich 1999 §6.1).
pub fn planar_projection(plane: Vec4, light: Vec4) -> Mat4 {
    let pl = plane.dot(light);
    let m = Mat4::from_diagonal(Vec4::splat(pl));
    // Column j of L·Pᵀ is L·P[j].
    let outer = Mat4::from_cols(
        light * plane.x,
        light * plane.y,
        light * plane.z,
        light * plane.w,
    );
    m - outer
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fuchs_scales_give_the_physical_mean_flux() {
        // ∫₀ʳ d²·c·atten(d) dd = r for every radius-based function (numerically).
        let r = 3.7f32;
        type Curve = fn(f32) -> f32;
        let f: [(Attenuation, Curve); 3] = [
            (Attenuation::Fuchs2, |x| (1.0 - x).max(0.0)),
            (Attenuation::Fuchs3, |x| (1.0 - x).max(0.0).powi(2)),
            (Attenuation::Fuchs4, |x| (1.0 - x * x).max(0.0)),
        ];
        for (a, atten) in f {
            let n = 100_000;
            let h = r / n as f32;
            let integral: f64 = (0..n)
                .map(|i| {
                    let d = (i as f32 + 0.5) * h;
                    (d * d * atten(d / r) * h) as f64
                })
                .sum();
            let mean_flux = integral * a.scale(r) as f64 / r as f64;
            assert!((mean_flux - 1.0).abs() < 1e-4, "{a:?}: {mean_flux}");
        }
    }

    #[test]
    fn planar_projection_lands_on_the_plane_along_the_light_ray() {
        let plane = Vec4::new(0.0, 1.0, 0.0, -0.5); // y = 0.5
        let light = Vec3::new(1.0, 4.0, -2.0);
        let m = planar_projection(plane, light.extend(1.0));
        let p = Vec3::new(0.3, 2.0, 0.7);
        let q = m * p.extend(1.0);
        let q = q.truncate() / q.w;
        assert!((q.y - 0.5).abs() < 1e-5);
        // Collinear with the light.
        assert!((q - light).normalize().dot((p - light).normalize()) > 1.0 - 1e-6);
        // Directional: along the direction.
        let to_light = Vec3::new(0.2, 1.0, 0.1).normalize();
        let m = planar_projection(plane, to_light.extend(0.0));
        let q = m * p.extend(1.0);
        let q = q.truncate() / q.w;
        assert!((q.y - 0.5).abs() < 1e-5);
        assert!((p - q).normalize().dot(to_light) > 1.0 - 1e-6);
    }

    #[test]
    fn slice_spheres_are_the_smallest_that_hold_their_slices() {
        for (a, b, ra, rb) in [
            (0.05, 1.0, 0.03, 0.6),
            (2.2, 4.6, 1.3, 2.8),
            (4.6, 11.3, 2.8, 6.8),
            (1.0, 1.1, 5.0, 5.5),
        ] {
            let (z, r) = slice_sphere(a, b, ra, rb);
            let far = |z: f32| (z - a).hypot(ra).max((b - z).hypot(rb));
            assert!((far(z) - r).abs() < 1e-5 && (a..=b).contains(&z));
            // No other centre on the axis does better (the optimum lies on the axis by symmetry).
            for k in 0..=100 {
                let zk = a + (b - a) * k as f32 / 100.0;
                assert!(far(zk) >= r - 1e-5, "{a} {b}: {zk} gives {} < {r}", far(zk));
            }
            // Never wider than the corners' centroid sphere used before.
            let c = 0.5 * (a + b);
            assert!(r <= far(c) + 1e-6);
        }
    }

    #[test]
    fn cascades_cover_their_slices() {
        let cam = Camera::look_at("c", Vec3::new(0.0, 5.0, 10.0), Vec3::ZERO, Vec3::Y, 0.8);
        let ends = cascade_ends(0.1, 40.0, 4, 0.7);
        assert!(ends.windows(2).all(|w| w[0] < w[1]));
        assert!((ends[3] - 40.0).abs() < 1e-3);
        let bounds = (Vec3::splat(-10.0), Vec3::splat(10.0));
        let views = cascade_views(
            Vec3::new(-0.3, -1.0, -0.2),
            &cam,
            1.5,
            &ends,
            0.1,
            bounds,
            1024,
        );
        // Every corner of every slice projects inside its cascade.
        let t = (0.8f32 * 0.5).tan();
        let mut start = 0.1;
        for (view, &end) in views.iter().zip(&ends) {
            for d in [start, end] {
                for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                    let p = Vec3::new(sx * t * 1.5 * d, sy * t * d, -d);
                    let c = view
                        .view_proj
                        .project_point3(cam.transform.transform_point3(p));
                    assert!(c.x.abs() <= 1.0 && c.y.abs() <= 1.0, "{d}: {c}");
                }
            }
            start = end;
        }
        // A point in the middle of cascade 1's slice projects inside it.
        let d = 0.5 * (ends[0] + ends[1]);
        let p = cam.transform.transform_point3(Vec3::new(0.3, -0.2, -d));
        let c = views[1].view_proj.project_point3(p);
        assert!(
            c.x.abs() < 1.0 && c.y.abs() < 1.0 && (0.0..=1.0).contains(&c.z),
            "{c}"
        );
    }
}

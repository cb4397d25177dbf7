//! The lights a renderer draws, one additive pass each: the scene's punctual lights, then its
//! planar emitters as area lights, each with its shadow views (spot, six cube faces, cascades)
//! or its planar projection, as the GPU's light and view records.

use super::settings::{MAX_AREA_LIGHTS, RasterSettings, ShadowMethod};
use crate::lights::{self, ShadowProjection};
use crate::shadow_volume::LightPos;
use crate::uniforms::GpuLight;
use glam::{Mat4, Vec3, Vec4};
use lightlab_scene::emitters::PlanarEmitter;
use lightlab_scene::{Camera, Light, LightKind, Scene};
use std::collections::BTreeMap;

/// Every light of a frame and its shadow data, index by index.
pub(super) struct LightSet {
    pub lights: Vec<GpuLight>,
    pub light_pos: Vec<LightPos>,
    /// The radius beyond which the light is culled and scissored (None: everywhere).
    pub light_radius: Vec<Option<f32>>,
    pub views: Vec<ShadowProjection>,
    /// The light of every shadow view.
    pub view_light: Vec<usize>,
    /// Per light, its projection onto the planar receiver (planar shadows).
    pub planar: Vec<Option<Mat4>>,
    pub plane: Option<Vec4>,
    /// The goniometric lights' profiles, by layer (`GpuLight::profile`).
    pub profiles: Vec<std::sync::Arc<lightlab_scene::photometry::Goniometric>>,
}

/// How far an area light's point for shadows sits in front of its emitter: 1 % of the
/// emitter's size, so that the emitter (and a ceiling it is mounted on) lies behind it.
fn area_light_offset(e: &PlanarEmitter) -> f32 {
    (0.01 * e.area.sqrt()).max(1e-5)
}

/// The largest up-facing plane of the scene (area-weighted histogram of heights), as (n, d).
fn dominant_floor(scene: &Scene) -> Option<Vec4> {
    let mut heights: BTreeMap<i64, f32> = BTreeMap::new();
    for inst in &scene.instances {
        let m = &scene.meshes[inst.mesh];
        for t in m.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]]
                .map(|i| inst.transform.transform_point3(m.positions[i as usize]));
            let n = (b - a).cross(c - a);
            let area = 0.5 * n.length();
            if area > 0.0 && n.normalize().y > 0.999 {
                *heights.entry((a.y * 1000.0).round() as i64).or_default() += area;
            }
        }
    }
    let (h, _) = heights.into_iter().max_by(|a, b| a.1.total_cmp(&b.1))?;
    Some(Vec4::new(0.0, 1.0, 0.0, -(h as f32) / 1000.0))
}

/// The scene's lights, then (when `area_lights`) its planar emitters: each a point light at
/// the emitter's centre, moved off it along its normal, for the shadows, and a Lambertian
/// rectangle for the shading (kind 3).
fn sources(
    scene: &Scene,
    area_lights: bool,
    sun: Option<&Light>,
) -> Vec<(Light, Option<(PlanarEmitter, f32)>)> {
    let mut sources: Vec<_> = scene.lights.iter().map(|l| (l.clone(), None)).collect();
    if area_lights {
        for e in scene.planar_emitters().into_iter().take(MAX_AREA_LIGHTS) {
            let offset = area_light_offset(&e);
            let l = Light {
                name: format!("emitter {}", e.instance),
                kind: LightKind::Point,
                color: e.radiance,
                intensity: e.area,
                position: e.centre + e.normal * offset,
                direction: e.normal,
                range: None,
            };
            sources.push((l, Some((e, offset))));
        }
    }
    // The environment's sun last: `LightSet::new` marks it diffuse-only.
    sources.extend(sun.map(|l| (l.clone(), None)));
    sources
}

impl LightSet {
    /// The lights of `scene` under `s`; `area_lights` is false for renderers whose bake holds
    /// the emitters' light (light-maps) or that are lit by SH light only.
    pub fn new(
        scene: &Scene,
        s: &RasterSettings,
        camera: &Camera,
        bounds: (Vec3, Vec3),
        area_lights: bool,
        sun: Option<&Light>,
    ) -> LightSet {
        let plane = match s.shadows {
            ShadowMethod::Planar => s.planar_plane.or_else(|| dominant_floor(scene)),
            _ => None,
        };
        let mut set = LightSet {
            lights: vec![],
            light_pos: vec![],
            light_radius: vec![],
            views: vec![],
            view_light: vec![],
            planar: vec![],
            plane,
            profiles: vec![],
        };
        let sources = sources(scene, area_lights, sun);
        let sun_index = sun.map(|_| sources.len() - 1);
        for (li, (l, area)) in sources.iter().enumerate() {
            let radius = match area {
                None => lights::light_radius(l, s.attenuation, s.light_radius),
                // Area lights fall off physically (their exact irradiance): never culled.
                Some(_) => None,
            };
            let mut g = lights::gpu_light(l, s.attenuation, radius);
            g.diffuse_only = (Some(li) == sun_index) as u32;
            if let LightKind::Goniometric { profile, .. } = &l.kind {
                g.profile = set.profiles.len() as u32;
                set.profiles.push(profile.clone());
            }
            if let Some((e, offset)) = area {
                g.kind = 3;
                g.attenuation = 0;
                g.atten_scale = 1.0;
                g.edge_u = e.half_u.to_array();
                g.edge_v = e.half_v.to_array();
                g.area_offset = *offset;
                g.two_sided = e.double_sided as u32;
            }
            if s.shadows.map() {
                set.add_views(li, l, radius, &mut g, s, camera, bounds);
            }
            let (lp, hom) = match l.kind {
                LightKind::Directional { .. } => (
                    LightPos::Directional(l.direction.normalize()),
                    (-l.direction.normalize()).extend(0.0),
                ),
                _ => (LightPos::Point(l.position), l.position.extend(1.0)),
            };
            set.planar.push(
                plane.and_then(|p| (p.dot(hom) > 0.0).then(|| lights::planar_projection(p, hom))),
            );
            set.lights.push(g);
            set.light_pos.push(lp);
            set.light_radius.push(radius);
        }
        let (firsts, _) = crate::canned::first_layers(&s.light_field);
        for (c, first) in s.light_field.iter().zip(firsts) {
            set.add_canned(c, first, s, bounds);
        }
        if set.lights.is_empty() {
            set.lights.push(GpuLight::default());
        }
        set
    }

    /// A canned light's records (`canned.rs`; its slices from layer `first`), sharing one
    /// cube of shadow views at its window's centre.
    fn add_canned(
        &mut self,
        c: &super::CannedLight,
        first: u32,
        s: &RasterSettings,
        bounds: (Vec3, Vec3),
    ) {
        let slab = &*c.slab;
        // The cube sits a little in front of the window, so that nothing at the window casts
        // a shadow over the whole slab.
        let eye = slab.centre + slab.normal() * (1e-3 * slab.half.max_element());
        let point = Light {
            name: "canned light".into(),
            kind: LightKind::Point,
            color: Vec3::ONE,
            intensity: 1.0,
            position: eye,
            direction: slab.normal(),
            range: None,
        };
        let first_view = self.views.len() as u32;
        let li = self.lights.len();
        if s.shadows.map() {
            let far = lights::shadow_far(&point, None, bounds);
            self.views
                .extend(lights::point_views(&point, far, s.shadow_size));
            self.view_light.extend(std::iter::repeat_n(li, 6));
        }
        for mut g in crate::canned::gpu_lights(c, first) {
            if s.shadows.map() {
                g.shadow_first = first_view;
                g.shadow_count = 6;
            }
            g.position = eye.to_array();
            self.lights.push(g);
            self.light_pos.push(LightPos::Point(eye));
            self.light_radius.push(None);
            self.planar.push(None);
        }
    }

    /// Light `li`'s shadow-map views (spot, cube faces or cascades), recorded in `g`.
    #[allow(clippy::too_many_arguments)]
    fn add_views(
        &mut self,
        li: usize,
        l: &Light,
        radius: Option<f32>,
        g: &mut GpuLight,
        s: &RasterSettings,
        camera: &Camera,
        bounds: (Vec3, Vec3),
    ) {
        let first = self.views.len();
        match l.kind {
            LightKind::Spot { outer_cone, .. } => {
                let far = lights::shadow_far(l, radius, bounds);
                self.views
                    .push(lights::spot_view(l, outer_cone, far, s.shadow_size));
            }
            LightKind::Point | LightKind::Goniometric { .. } => {
                let far = lights::shadow_far(l, radius, bounds);
                self.views
                    .extend(lights::point_views(l, far, s.shadow_size));
            }
            LightKind::Directional { .. } => {
                let far_cam = lights::box_corners(bounds)
                    .iter()
                    .map(|c| (*c - camera.position()).length())
                    .fold(1.0f32, f32::max);
                let near = camera.znear.max(0.05);
                let ends = lights::cascade_ends(near, far_cam, s.cascades, 0.7);
                let aspect = s.width as f32 / s.height as f32;
                self.views.extend(lights::cascade_views(
                    l.direction,
                    camera,
                    aspect,
                    &ends,
                    near,
                    bounds,
                    s.shadow_size,
                ));
                let mut ce = [f32::MAX; 4];
                ce[..ends.len()].copy_from_slice(&ends);
                g.cascade_ends = ce;
            }
        }
        g.shadow_first = first as u32;
        g.shadow_count = (self.views.len() - first) as u32;
        self.view_light
            .extend(std::iter::repeat_n(li, self.views.len() - first));
    }
}

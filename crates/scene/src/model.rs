//! The scene model: what a glTF file loads into and what every baker and renderer reads.
//!
//! Units and conventions (docs/ARCHITECTURE.md): right-handed, Y-up, metres. Colours are linear Rec.709.
//! Light intensities follow KHR_lights_punctual numerically (point/spot in candela, directional in
//! lux) but are used as radiometric quantities (W/sr, W/m²) with no luminous-efficacy factor,
//! as most renderers do; emission is `emissive × emissive_strength` in W/(m²·sr).

use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use lightlab_core::image::Image;

/// A complete scene.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub name: String,
    pub meshes: Vec<Mesh>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub instances: Vec<Instance>,
    pub lights: Vec<Light>,
    pub environment: Option<Environment>,
    /// The first camera is the scene's default camera.
    pub cameras: Vec<Camera>,
    /// What loading dropped or changed, one line each (degenerate triangles dropped, primitives
    /// skipped, …); the command line prints them as warnings.
    pub warnings: Vec<String>,
    /// Rigid motion of some instances over time (`--frame K` poses it); None for still scenes.
    pub animation: Option<crate::Animation>,
    /// Where a luminaire is focused (glTF `extras.lightlab.luminaireFocus` on a node of the
    /// luminaire): metres along its axis from its first instance's origin. A slide projector's
    /// screen; its light slab's (s,t) plane lies there (Heidrich Fig 7.3). Luminaires without
    /// an entry get (s,t) at infinity.
    pub luminaire_focus: std::collections::BTreeMap<String, f32>,
}

/// An indexed triangle mesh with one material (a glTF primitive).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    /// xyz tangent and w = handedness (glTF convention); empty when the mesh has none.
    pub tangents: Vec<Vec4>,
    pub uv0: Vec<Vec2>,
    /// Light-map UVs (TEXCOORD_1), when present.
    pub uv1: Option<Vec<Vec2>>,
    /// Vertex colours (COLOR_0, linear RGBA); empty when the mesh has none. They multiply the
    /// base colour, alpha included, as glTF defines.
    pub colors: Vec<Vec4>,
    pub indices: Vec<u32>,
    pub material: usize,
    /// The high-poly mesh (index in the scene's meshes) this one was decimated from: bakers
    /// project its texels onto that surface and take normals and occlusion from it (McKenzie
    /// Chapter 2010 §4.2.4). glTF: mesh `extras.lightlab.detailSource` = the source mesh's name.
    pub detail_source: Option<usize>,
}

impl Mesh {
    /// Both UV sets and the vertex colour at barycentric weights `bw` of the triangle `idx`
    /// (zeros where the mesh has no UV0, white where it has no colours).
    #[inline]
    pub fn uv_at(&self, idx: [usize; 3], bw: [f32; 3]) -> Attrs {
        // `Attrs::weighted` over `attrs_of` the three corners, without the sets the mesh lacks
        // (the path tracer calls this at every hit): the same values, bit for bit.
        let [a, b, c] = idx;
        let lerp = |v: &[Vec2]| {
            let at = |i: usize| v.get(i).copied().unwrap_or_default();
            at(a) * bw[0] + at(b) * bw[1] + at(c) * bw[2]
        };
        let uv0 = lerp(&self.uv0);
        let uv1 = self.uv1.as_deref().map_or(uv0, lerp);
        let color = if self.colors.is_empty() {
            Vec4::splat(bw[0] + bw[1] + bw[2])
        } else {
            let at = |i: usize| self.colors.get(i).copied().unwrap_or(Vec4::ONE);
            at(a) * bw[0] + at(b) * bw[1] + at(c) * bw[2]
        };
        Attrs {
            uv: [uv0, uv1],
            color,
        }
    }

    /// The attributes of vertex `i`.
    #[inline]
    pub fn attrs_of(&self, i: usize) -> Attrs {
        let uv0 = self.uv0.get(i).copied().unwrap_or_default();
        let uv1 = self
            .uv1
            .as_ref()
            .map_or(Some(uv0), |u| u.get(i).copied())
            .unwrap_or_default();
        Attrs {
            uv: [uv0, uv1],
            color: self.colors.get(i).copied().unwrap_or(Vec4::ONE),
        }
    }

    /// The attributes of triangle `t`'s corners.
    #[inline]
    pub fn corners(&self, t: &[u32]) -> [Attrs; 3] {
        [t[0], t[1], t[2]].map(|i| self.attrs_of(i as usize))
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Compute per-vertex normals as the area-weighted average of face normals.
    pub fn compute_normals(&mut self) {
        let mut n = vec![Vec3::ZERO; self.positions.len()];
        for t in self.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| self.positions[i as usize]);
            let f = (b - a).cross(c - a);
            for &i in t {
                n[i as usize] += f;
            }
        }
        self.normals = n.into_iter().map(|v| v.normalize_or(Vec3::Y)).collect();
    }

    /// Compute MikkTSpace tangents from UV0 (glTF's rule for meshes without TANGENT), splitting
    /// vertices whose corners get different tangent frames (UV seams, mirrored UVs). Without
    /// UV0 every vertex gets some tangent orthogonal to its normal. See [`crate::tangents`].
    pub fn compute_tangents(&mut self) {
        crate::tangents::compute(self);
    }
}

/// A placement of a mesh in the world.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    pub name: String,
    pub mesh: usize,
    /// World-from-object transform.
    pub transform: Mat4,
    /// The names of the glTF nodes above the instance's own, root first (empty for the
    /// built-in scenes): the hierarchy hierarchical PRT's trees can follow.
    pub nodes: Vec<String>,
    /// The luminaire this instance belongs to (glTF `extras.lightlab.luminaire` on its node
    /// or a node above it): lamp geometry that a canned light (`bake --method light-field`)
    /// replaces.
    pub luminaire: Option<String>,
}

impl Instance {
    /// The matrix that transforms normals (inverse transpose of the upper 3×3).
    pub fn normal_matrix(&self) -> Mat3 {
        Mat3::from_mat4(self.transform).inverse().transpose()
    }
}

/// How alpha is interpreted (glTF `alphaMode`).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum AlphaMode {
    #[default]
    Opaque,
    /// Alpha-tested: texels with alpha < cutoff are holes.
    Mask { cutoff: f32 },
    /// Blended. The CPU reference treats it as stochastic coverage.
    Blend,
}

/// The interpolated vertex attributes of a surface point: the texture coordinates in both
/// sets, TEXCOORD_0 and TEXCOORD_1 (the second repeats the first where a mesh has none), and
/// the vertex colour (white where a mesh has none). Every texture read picks its set through
/// [`Scene::sample`], so the path tracer, the bakers and the GPU read the same texels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attrs {
    pub uv: [Vec2; 2],
    pub color: Vec4,
}

impl Default for Attrs {
    fn default() -> Self {
        Attrs {
            uv: [Vec2::ZERO; 2],
            color: Vec4::ONE,
        }
    }
}

impl Attrs {
    /// The coordinates of set `set` (0 or 1).
    pub fn set(&self, set: u32) -> Vec2 {
        self.uv[set.min(1) as usize]
    }

    /// The barycentric combination of three corners' attributes.
    #[inline]
    pub fn weighted(c: &[Attrs; 3], bw: [f32; 3]) -> Attrs {
        Attrs {
            uv: [
                c[0].uv[0] * bw[0] + c[1].uv[0] * bw[1] + c[2].uv[0] * bw[2],
                c[0].uv[1] * bw[0] + c[1].uv[1] * bw[1] + c[2].uv[1] * bw[2],
            ],
            color: c[0].color * bw[0] + c[1].color * bw[1] + c[2].color * bw[2],
        }
    }
}

/// A KHR_texture_transform: `uv' = offset + R(rotation) · (scale ∘ uv)`, the matrix T·R·S of
/// the extension, where R turns the UVs counter-clockwise (the image clockwise). Stored as
/// the rows of a 2×3 matrix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform(pub [[f32; 3]; 2]);

impl UvTransform {
    pub const IDENTITY: UvTransform = UvTransform([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);

    /// From the extension's offset, rotation (radians) and scale.
    pub fn new(offset: Vec2, rotation: f32, scale: Vec2) -> UvTransform {
        let (s, c) = rotation.sin_cos();
        UvTransform([
            [c * scale.x, s * scale.y, offset.x],
            [-s * scale.x, c * scale.y, offset.y],
        ])
    }

    pub fn apply(&self, uv: Vec2) -> Vec2 {
        let [a, b] = self.0;
        Vec2::new(
            a[0] * uv.x + a[1] * uv.y + a[2],
            b[0] * uv.x + b[1] * uv.y + b[2],
        )
    }

    pub fn is_identity(&self) -> bool {
        *self == UvTransform::IDENTITY
    }

    /// The offset, rotation and scale that [`UvTransform::new`] turns into this matrix (a
    /// negative x scale comes back as a half turn and a negative y scale).
    pub fn decompose(&self) -> (Vec2, f32, Vec2) {
        let [a, b] = self.0;
        let sx = Vec2::new(a[0], b[0]).length();
        let rotation = (-b[0]).atan2(a[0]);
        let (s, c) = rotation.sin_cos();
        let sy = a[1] * s + b[1] * c;
        (Vec2::new(a[2], b[2]), rotation, Vec2::new(sx, sy))
    }
}

impl Default for UvTransform {
    fn default() -> Self {
        UvTransform::IDENTITY
    }
}

/// A reference to a texture with the UV set it uses and the transform applied to its UVs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    pub texture: usize,
    /// 0 = TEXCOORD_0, 1 = TEXCOORD_1.
    pub uv_set: u32,
    pub transform: UvTransform,
}

impl TextureRef {
    /// Texture `texture` on UV set `uv_set`, untransformed.
    pub fn new(texture: usize, uv_set: u32) -> TextureRef {
        TextureRef {
            texture,
            uv_set,
            transform: UvTransform::IDENTITY,
        }
    }

    /// The texture's coordinates at a surface point.
    pub fn uv(&self, a: &Attrs) -> Vec2 {
        self.transform.apply(a.set(self.uv_set))
    }
}

/// The reflection model a material is shaded with, by the path tracer and the GPU techniques
/// alike (so a real-time method can be compared with the reference of the same model).
///
/// The classical models take their parameters from the glTF material: diffuse reflectance
/// ρd = (1−metallic)·base, specular reflectance ρs = mix(0.04·specular, base, metallic) (the
/// "specular map" is the metallic–roughness texture), and the exponent from the roughness r as
/// n = 2/r⁴ − 2, the usual Beckmann-equivalent exponent for α = r².
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Hash)]
pub enum BrdfModel {
    /// Lambert + GGX/Smith microfacet lobe with Schlick Fresnel (glTF metallic–roughness).
    #[default]
    Pbr,
    /// Lambert only: ρd/π.
    Lambert,
    /// Phong: ρd/π + ρs·(n+2)/(2π)·⟨r,l⟩ⁿ (normalised, reflection vector r).
    Phong,
    /// Blinn-Phong as in Fuchs (2005) eq. 3: ρd/π + ρs·N(n)·⟨n,h⟩ⁿ, N normalised so that the
    /// albedo at normal incidence is exactly ρs (`lightlab_core::brdf::BlinnPhong`).
    BlinnPhong,
    /// Torrance–Sparrow (Heidrich §3.1, §5.1): ρd/π + F·G·D/(4⟨n,l⟩⟨n,v⟩) with Beckmann D
    /// (RMS slope m = roughness²) and separable Smith G (G1(l)·G1(v), the form Heidrich's
    /// factorised tables need); F the material's Fresnel.
    TorranceSparrow,
    /// Cook–Torrance: the same with the V-groove masking of Eq 3.11.
    CookTorrance,
    /// Ward's elliptical Gaussian (α = roughness²): ρd/π + ρs·exp(−(h_t²/α_t² + h_b²/α_b²)/
    /// h_n²)/(4πα_tα_b√(⟨n,l⟩⟨n,v⟩)), anisotropic with [`Material::anisotropy`] (α_t =
    /// mix(α, 1, strength²) along the anisotropy direction, α_b = α, as KHR_materials_anisotropy
    /// widens GGX).
    Ward,
    /// Banks's fibre model (Heidrich §5.2, Eq 5.4 in the two-angle form): fibres along the
    /// anisotropy direction t; ρd/π·√(1−⟨l,t⟩²) + ρs·N(n)·(√(1−⟨l,t⟩²)√(1−⟨v,t⟩²) −
    /// ⟨l,t⟩⟨v,t⟩)ⁿ with the Phong exponent n of the roughness and N(n) the unit-albedo
    /// normalisation of `lightlab_core::brdf::Banks::normalization`. Not reciprocal.
    Banks,
    /// Lafortune's generalised cosine lobe: ρd/π + ρs·(n+2)/(2π)·(C_x l_t v_t + C_y l_b v_b +
    /// C_z l_n v_n)ⁿ in the tangent frame, C = [`Material::lafortune`] (default (−1, −1, 1):
    /// Phong), n the Phong exponent of the roughness.
    Lafortune,
}

lightlab_core::named_enum!(BrdfModel, "BRDF model", {
    Pbr => "pbr",
    Lambert => "lambert",
    Phong => "phong",
    BlinnPhong => "blinn-phong",
    TorranceSparrow => "torrance-sparrow",
    CookTorrance => "cook-torrance",
    Ward => "ward",
    Banks => "banks",
    Lafortune => "lafortune",
});

impl BrdfModel {
    /// Whether the specular lobe is a microfacet (or Ward's Gaussian) lobe of width
    /// roughness², whose environment term reads the GGX-prefiltered maps.
    pub fn microfacet(self) -> bool {
        matches!(
            self,
            BrdfModel::Pbr | BrdfModel::TorranceSparrow | BrdfModel::CookTorrance | BrdfModel::Ward
        )
    }

    /// Whether the model reads the tangent frame (the anisotropy direction).
    pub fn uses_tangent(self) -> bool {
        matches!(
            self,
            BrdfModel::Ward | BrdfModel::Banks | BrdfModel::Lafortune
        )
    }

    /// The Phong/Blinn-Phong exponent of a roughness (clamped to [1, 10⁴]).
    pub fn exponent(roughness: f32) -> f32 {
        lightlab_core::envmap::phong_exponent(roughness)
    }
}

/// A material: glTF metallic–roughness plus the extensions lightlab uses.
///
/// The BRDF is Lambert (`(1−metallic)·base/π`, scaled by 1−F for energy balance when a specular
/// lobe exists) plus a GGX/Smith microfacet lobe with Schlick Fresnel,
/// F0 = mix(0.04·specular, base, metallic). `specular = 0`, `metallic = 0` is pure Lambert.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Linear RGB and alpha.
    pub base_color: Vec4,
    pub base_color_texture: Option<TextureRef>,
    pub metallic: f32,
    pub roughness: f32,
    /// glTF metallicRoughness texture (G = roughness, B = metallic).
    pub metallic_roughness_texture: Option<TextureRef>,
    /// KHR_materials_specular `specularFactor` (scales the dielectric F0 = 0.04).
    pub specular: f32,
    pub emissive: Vec3,
    /// KHR_materials_emissive_strength.
    pub emissive_strength: f32,
    pub emissive_texture: Option<TextureRef>,
    pub normal_texture: Option<TextureRef>,
    pub normal_scale: f32,
    pub alpha_mode: AlphaMode,
    pub double_sided: bool,
    /// KHR_materials_diffuse_transmission `diffuseTransmissionFactor`: the fraction of diffusely
    /// scattered light that leaves through the back side (thin foliage).
    pub transmission: f32,
    /// `diffuseTransmissionTexture`: a translucency map whose alpha scales `transmission`
    /// (linear).
    pub transmission_texture: Option<TextureRef>,
    /// How much the wind moves this material's vertices (glTF `extras.lightlab.sway`; 0 =
    /// rigid; `lightlab_core::wind`).
    pub sway: f32,
    /// The reflection model (glTF `extras.lightlab.brdf`; default the glTF model).
    pub brdf: BrdfModel,
    /// KHR_materials_transmission `transmissionFactor`: the fraction of the base layer that is a
    /// smooth dielectric interface (glass) rather than diffuse; refracted light is tinted by the
    /// base colour. The path tracer refracts through it (Fresnel, total internal reflection);
    /// the GPU looks the refracted direction up in the environment map.
    pub specular_transmission: f32,
    /// KHR_materials_ior: the dielectric's index of refraction (F0 = ((n−1)/(n+1))², 0.04 at
    /// the default 1.5).
    pub ior: f32,
    /// A measured metal (glTF `extras.lightlab.conductor`: a preset name or `{"eta": [r,g,b],
    /// "k": [r,g,b]}`): the metallic part's Fresnel is the exact conductor reflectance of this
    /// complex index, times the base colour (white for the measured metal), instead of Schlick
    /// with F0 = base colour. The path tracer and the GPU's environment term use it exactly;
    /// the GPU's direct light in the deferred path uses Schlick with its normal-incidence value.
    pub conductor: Option<Conductor>,
    /// KHR_materials_volume `thicknessFactor` (metres, in the mesh's space): 0 (glTF's default
    /// without the extension) makes glass thin-walled — a sheet whose transmitted light goes
    /// straight through, reflecting the sheet's Fresnel reflectance; above 0 the mesh bounds a
    /// solid whose surface refracts. Attenuation inside the volume is not modelled.
    pub thickness: f32,
    /// KHR_materials_anisotropy `anisotropyStrength` in [0, 1]: widens the lobe along the
    /// anisotropy direction (Ward: α_t = mix(α, 1, strength²)). The models that read it:
    /// [`BrdfModel::uses_tangent`].
    pub anisotropy: f32,
    /// KHR_materials_anisotropy `anisotropyRotation` (radians): the anisotropy direction is the
    /// tangent turned by this angle towards the bitangent.
    pub anisotropy_rotation: f32,
    /// The Lafortune lobe's (C_x, C_y, C_z) (glTF `extras.lightlab.lafortune`).
    pub lafortune: Vec3,
}

/// A conductor's complex index of refraction η + ik, per RGB channel (relative to air).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    pub eta: Vec3,
    pub k: Vec3,
}

impl Conductor {
    /// Measured metals at about 650, 550 and 450 nm (R, G, B), from the optical constants of
    /// Johnson & Christy (1972: gold, silver, copper) and Rakić (1995, 1998: aluminium,
    /// chromium), as tabulated with the spectral data of common renderers. A single wavelength
    /// per channel, not an average over the channel's band.
    pub const PRESETS: [(&'static str, Conductor); 5] = [
        (
            "gold",
            Conductor {
                eta: Vec3::new(0.143119, 0.374957, 1.44248),
                k: Vec3::new(3.98316, 2.38572, 1.60322),
            },
        ),
        (
            "silver",
            Conductor {
                eta: Vec3::new(0.155265, 0.116723, 0.138342),
                k: Vec3::new(4.82835, 3.12225, 2.14696),
            },
        ),
        (
            "copper",
            Conductor {
                eta: Vec3::new(0.200438, 0.924033, 1.10221),
                k: Vec3::new(3.91295, 2.45285, 2.14219),
            },
        ),
        (
            "aluminium",
            Conductor {
                eta: Vec3::new(1.65746, 0.880369, 0.521229),
                k: Vec3::new(9.22387, 6.26952, 4.837),
            },
        ),
        (
            "chrome",
            Conductor {
                eta: Vec3::new(4.36968, 2.9167, 1.6547),
                k: Vec3::new(5.20643, 4.23136, 3.75495),
            },
        ),
    ];

    /// A preset by name (`gold`, `silver`, `copper`, `aluminium`, `chrome`).
    pub fn preset(name: &str) -> Option<Conductor> {
        Self::PRESETS
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, c)| *c)
    }

    /// The preset's name when this is one.
    pub fn preset_name(&self) -> Option<&'static str> {
        Self::PRESETS
            .iter()
            .find(|(_, c)| c == self)
            .map(|(n, _)| *n)
    }

    /// Exact reflectance per channel at cosine `c` ([`lightlab_core::brdf::fresnel_conductor`]).
    pub fn fresnel(&self, c: f32) -> Vec3 {
        let f = |i: usize| {
            lightlab_core::brdf::fresnel_conductor(c as f64, self.eta[i] as f64, self.k[i] as f64)
                as f32
        };
        Vec3::new(f(0), f(1), f(2))
    }

    /// Whether both indices are finite, η > 0 and k ≥ 0 in every channel.
    pub fn is_valid(&self) -> bool {
        self.eta.is_finite()
            && self.k.is_finite()
            && self.eta.min_element() > 0.0
            && self.k.min_element() >= 0.0
    }
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: String::new(),
            base_color: Vec4::new(0.8, 0.8, 0.8, 1.0),
            base_color_texture: None,
            metallic: 0.0,
            roughness: 1.0,
            metallic_roughness_texture: None,
            specular: 1.0,
            emissive: Vec3::ZERO,
            emissive_strength: 1.0,
            emissive_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            alpha_mode: AlphaMode::Opaque,
            double_sided: false,
            transmission: 0.0,
            transmission_texture: None,
            sway: 0.0,
            brdf: BrdfModel::Pbr,
            specular_transmission: 0.0,
            ior: 1.5,
            conductor: None,
            thickness: 0.0,
            anisotropy: 0.0,
            anisotropy_rotation: 0.0,
            lafortune: Vec3::new(-1.0, -1.0, 1.0),
        }
    }
}

impl Material {
    /// A pure Lambertian material of the given reflectance.
    pub fn diffuse(name: &str, albedo: Vec3) -> Self {
        Material {
            name: name.into(),
            base_color: albedo.extend(1.0),
            specular: 0.0,
            ..Default::default()
        }
    }

    /// The dielectric's reflectance at normal incidence, ((n−1)/(n+1))², times the specular
    /// factor (0.04 · specular at n = 1.5).
    pub fn dielectric_f0(&self) -> f32 {
        let r = (self.ior - 1.0) / (self.ior + 1.0);
        r * r * self.specular
    }

    /// Emitted radiance (before any emissive texture).
    pub fn emission(&self) -> Vec3 {
        self.emissive * self.emissive_strength
    }

    /// Every texture the material reads.
    pub fn texture_refs(&self) -> impl Iterator<Item = TextureRef> {
        [
            self.base_color_texture,
            self.metallic_roughness_texture,
            self.emissive_texture,
            self.normal_texture,
            self.transmission_texture,
        ]
        .into_iter()
        .flatten()
    }

    /// Whether a texture of the material reads UV set `set`.
    pub fn reads_uv_set(&self, set: u32) -> bool {
        self.texture_refs().any(|r| r.uv_set == set)
    }

    pub fn is_emissive(&self) -> bool {
        self.emission().max_element() > 0.0
    }
}

/// A texture: its texels in source precision, read as linear RGBA through [`Texture::texel`].
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    pub name: String,
    pub width: u32,
    pub height: u32,
    /// The texels in their source precision (RGBA, row-major).
    pub texels: Texels,
    /// Whether the source encoding was sRGB (base colour, emissive) or linear (normal, data).
    /// 8- and 16-bit texels are stored encoded and decoded on reading; float texels are linear.
    pub srgb: bool,
}

/// Texel storage in the precision the source had: an 8-bit PNG or JPEG costs 4 bytes a texel,
/// not the 16 of four floats (a 2k-textured model needed 1.7 GB to load).
#[derive(Clone, Debug, PartialEq)]
pub enum Texels {
    Rgba8(Vec<u8>),
    Rgba16(Vec<u16>),
    /// Linear values (built-in scenes, computed maps).
    Rgba32F(Vec<Vec4>),
}

impl Texels {
    /// The number of texels.
    pub fn len(&self) -> usize {
        match self {
            Texels::Rgba8(v) => v.len() / 4,
            Texels::Rgba16(v) => v.len() / 4,
            Texels::Rgba32F(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        match self {
            Texels::Rgba8(v) => v.len(),
            Texels::Rgba16(v) => 2 * v.len(),
            Texels::Rgba32F(v) => 16 * v.len(),
        }
    }
}

/// sRGB-encoded 8-bit value → linear, by table.
fn srgb8_to_linear(v: u8) -> f32 {
    static TABLE: std::sync::OnceLock<[f32; 256]> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        std::array::from_fn(|i| lightlab_core::color::srgb_decode(i as f32 / 255.0))
    })[v as usize]
}

impl Texture {
    /// A texture of linear float texels.
    pub fn linear(name: &str, width: u32, height: u32, data: Vec<Vec4>, srgb: bool) -> Texture {
        Texture {
            name: name.into(),
            width,
            height,
            texels: Texels::Rgba32F(data),
            srgb,
        }
    }

    /// Texel `i` (row-major), linear: sRGB-encoded colour channels decoded, alpha as stored.
    pub fn texel(&self, i: usize) -> Vec4 {
        use lightlab_core::color::srgb_decode;
        match &self.texels {
            Texels::Rgba32F(v) => v[i],
            Texels::Rgba8(v) => {
                let p = &v[4 * i..4 * i + 4];
                let a = p[3] as f32 / 255.0;
                if self.srgb {
                    Vec4::new(
                        srgb8_to_linear(p[0]),
                        srgb8_to_linear(p[1]),
                        srgb8_to_linear(p[2]),
                        a,
                    )
                } else {
                    Vec4::new(p[0] as f32, p[1] as f32, p[2] as f32, p[3] as f32) / 255.0
                }
            }
            Texels::Rgba16(v) => {
                let p = &v[4 * i..4 * i + 4];
                let c = Vec4::new(p[0] as f32, p[1] as f32, p[2] as f32, p[3] as f32) / 65535.0;
                if self.srgb {
                    Vec4::new(srgb_decode(c.x), srgb_decode(c.y), srgb_decode(c.z), c.w)
                } else {
                    c
                }
            }
        }
    }

    /// Every texel, linear (for uploads and filters that work on floats).
    pub fn to_linear(&self) -> Vec<Vec4> {
        (0..self.texels.len()).map(|i| self.texel(i)).collect()
    }

    /// Bilinear lookup with repeat wrapping; `uv` in glTF convention (v down).
    pub fn sample(&self, uv: Vec2) -> Vec4 {
        let (w, h) = (self.width as i64, self.height as i64);
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        if !x.is_finite() || !y.is_finite() {
            return self.texel(0);
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let at = |xi: i64, yi: i64| {
            let xi = xi.rem_euclid(w) as usize;
            let yi = yi.rem_euclid(h) as usize;
            self.texel(yi * w as usize + xi)
        };
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = at(x0, y0).lerp(at(x0 + 1, y0), fx);
        let bottom = at(x0, y0 + 1).lerp(at(x0 + 1, y0 + 1), fx);
        top.lerp(bottom, fy)
    }
}

/// Kinds of punctual light (KHR_lights_punctual), plus the sun's angular size and measured
/// lamps.
#[derive(Clone, Debug, PartialEq)]
pub enum LightKind {
    Point,
    /// Cone angles in radians from the axis, as glTF (inner < outer ≤ π/2).
    Spot {
        inner_cone: f32,
        outer_cone: f32,
    },
    /// A distant light; `angular_diameter` in radians (0 = a delta direction). The sun is
    /// ≈ 0.0093 rad (0.53°).
    Directional {
        angular_diameter: f32,
    },
    /// A point light whose intensity follows a measured distribution (IES LM-63 or EULUMDAT,
    /// [`crate::photometry`]): candela towards each direction is `intensity` × the file's
    /// candela there (so `intensity` 1 is the file's lamp), times the colour. The file's local
    /// frame: −Z is the light's `direction` (nadir), +X is `c0` (the C0 plane; unit, at right
    /// angles to `direction`).
    Goniometric {
        profile: std::sync::Arc<crate::photometry::Goniometric>,
        c0: Vec3,
    },
}

/// A light in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    pub name: String,
    pub kind: LightKind,
    /// Linear RGB colour (multiplied by intensity).
    pub color: Vec3,
    /// Point/spot: radiant intensity (glTF candela); directional: irradiance (glTF lux).
    pub intensity: f32,
    pub position: Vec3,
    /// The direction the light travels (spot axis; for a directional light, from the sun to the
    /// scene). Unit length.
    pub direction: Vec3,
    /// glTF range: the distance beyond which the light is cut off (None = infinite).
    pub range: Option<f32>,
}

impl Light {
    /// The factor on `intensity` towards unit direction `dir_to_point` (from the light): the
    /// spot cone's falloff as KHR_lights_punctual recommends (smooth between outer and inner),
    /// a measured lamp's candela there (× its tilt factor, [`Light::tilt_angle`]); 1 for
    /// point and directional lights.
    pub fn emission(&self, dir_to_point: Vec3) -> f32 {
        match &self.kind {
            LightKind::Spot {
                inner_cone,
                outer_cone,
            } => {
                let cd = self.direction.dot(dir_to_point);
                let (ci, co) = (inner_cone.cos(), outer_cone.cos());
                let scale = 1.0 / (ci - co).max(1e-4);
                let t = ((cd - co) * scale).clamp(0.0, 1.0);
                t * t
            }
            LightKind::Goniometric { profile, .. } => {
                profile.intensity(self.to_local(dir_to_point))
                    * profile.tilt_factor(self.tilt_angle())
            }
            _ => 1.0,
        }
    }

    /// The light's local frame (X = C0, Y, Z = −direction) as rows: `m * d` is `d` in the
    /// photometric file's frame. For lights other than goniometric ones, X is any axis at
    /// right angles to the direction.
    pub fn local_frame(&self) -> Mat3 {
        let z = -self.direction.normalize_or(Vec3::NEG_Z);
        let x = match &self.kind {
            LightKind::Goniometric { c0, .. } => *c0,
            _ => z.any_orthonormal_vector(),
        };
        let x = (x - z * x.dot(z)).normalize_or(z.any_orthonormal_vector());
        Mat3::from_cols(x, z.cross(x), z).transpose()
    }

    /// World direction `d` in the light's local frame ([`Light::local_frame`]).
    pub fn to_local(&self, d: Vec3) -> Vec3 {
        self.local_frame() * d
    }

    /// The lamp's tilt in degrees for an IES `TILT` table: the angle between its nadir (the
    /// light's direction) and straight down, as luminaires are measured hanging nadir-down.
    pub fn tilt_angle(&self) -> f32 {
        (-self.direction.normalize_or(Vec3::NEG_Y).y)
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees()
    }

    /// The largest radiant intensity towards any direction (W/sr; the colour's largest
    /// channel included); for a directional light, its irradiance.
    pub fn peak_intensity(&self) -> f32 {
        let factor = match &self.kind {
            LightKind::Goniometric { profile, .. } => {
                profile.candela.iter().fold(0.0f32, |a, &b| a.max(b))
                    * profile.tilt_factor(self.tilt_angle())
            }
            _ => 1.0,
        };
        self.intensity * self.color.max_element() * factor
    }
}

/// An environment map: an equirectangular (latitude–longitude) radiance image.
///
/// Mapping (shared with `lightlab_core`'s parameterisations): for a world direction d,
/// u = 0.5 + atan2(d.x, −d.z)/(2π), v = acos(d.y)/π; v = 0 is the zenith (+Y), u = 0.5 looks
/// down −Z.
#[derive(Clone, Debug, PartialEq)]
pub struct Environment {
    pub image: Image,
    /// Multiplier on the image.
    pub intensity: f32,
}

impl Environment {
    /// The brightest radiance an environment may have: far above any sky, and far enough
    /// below f32's range that integrals over it (× 4π × sample weights) stay finite.
    pub const MAX_RADIANCE: f32 = 1e30;

    /// Intensity finite and non-negative, and intensity × the brightest pixel within
    /// [`Self::MAX_RADIANCE`] (an intensity of 1e38 on a pixel of 10 overflowed f32 and
    /// filled the images with NaN). The message says what is wrong.
    pub fn check(&self) -> Result<(), String> {
        if !(self.intensity.is_finite() && self.intensity >= 0.0) {
            return Err(format!(
                "intensity {} must be a finite, non-negative number",
                self.intensity
            ));
        }
        let brightest = self
            .image
            .data
            .iter()
            .map(|v| v.max_element())
            .fold(0.0f32, f32::max);
        if (brightest as f64) * (self.intensity as f64) > Self::MAX_RADIANCE as f64 {
            return Err(format!(
                "intensity {} × the brightest pixel {brightest} exceeds {:e}",
                self.intensity,
                Self::MAX_RADIANCE
            ));
        }
        Ok(())
    }

    /// Direction → equirectangular uv in [0,1)² (`lightlab_core::sh_env`'s lat-long convention).
    pub fn dir_to_uv(d: Vec3) -> Vec2 {
        lightlab_core::sh_env::latlong_dir_to_uv(d)
    }

    /// Equirectangular uv → unit direction.
    pub fn uv_to_dir(uv: Vec2) -> Vec3 {
        lightlab_core::sh_env::latlong_uv_to_dir(uv)
    }

    /// Radiance arriving from direction `d` (nearest texel; the map is assumed smooth or
    /// sampled with matching importance).
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        self.radiance_uv(Self::dir_to_uv(d))
    }

    /// Radiance at equirectangular `uv` (nearest texel), for callers that hold the uv already.
    pub fn radiance_uv(&self, uv: Vec2) -> Vec3 {
        let x = ((uv.x * self.image.width as f32) as u32).min(self.image.width - 1);
        let y = ((uv.y * self.image.height as f32) as u32).min(self.image.height - 1);
        self.image.get(x, y) * self.intensity
    }
}

/// A perspective camera (glTF convention: looks down its local −Z, +Y up).
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub name: String,
    /// World-from-camera transform (rigid).
    pub transform: Mat4,
    /// Vertical field of view in radians.
    pub yfov: f32,
    pub znear: f32,
    pub zfar: Option<f32>,
    /// The lens the camera names (glTF `extras.lightlab.lens`); None: the pinhole unless the
    /// command line says otherwise.
    pub lens: Option<CameraLens>,
}

/// A camera's lens as a glTF file names it: `extras.lightlab.lens = { model, aperture,
/// focusDistance, thickness, scale }`, with `model` one of `pinhole`, `thin-lens`,
/// `thick-lens` or `lens:FILE` (a prescription, relative to the glTF file, or a shipped
/// lens's name). Lengths in scene units; absent values take the command line's defaults.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct CameraLens {
    pub model: String,
    pub aperture: Option<f32>,
    pub focus_distance: Option<f32>,
    pub thickness: Option<f32>,
    pub scale: Option<f32>,
}

impl Camera {
    /// A camera at `eye` looking at `target`.
    pub fn look_at(name: &str, eye: Vec3, target: Vec3, up: Vec3, yfov: f32) -> Camera {
        Camera {
            name: name.into(),
            transform: {
                let f = (target - eye).normalize();
                let r = f.cross(up).normalize();
                let u = r.cross(f);
                Mat4::from_cols(
                    r.extend(0.0),
                    u.extend(0.0),
                    (-f).extend(0.0),
                    eye.extend(1.0),
                )
            },
            yfov,
            znear: 0.01,
            zfar: None,
            lens: None,
        }
    }

    pub fn position(&self) -> Vec3 {
        self.transform.w_axis.truncate()
    }

    /// Primary ray direction through normalised film position `ndc` ∈ [−1,1]² (y up), for an
    /// image of aspect ratio width/height.
    pub fn ray_direction(&self, ndc: Vec2, aspect: f32) -> Vec3 {
        let t = (self.yfov * 0.5).tan();
        let local = Vec3::new(ndc.x * t * aspect, ndc.y * t, -1.0);
        self.transform.transform_vector3(local).normalize()
    }
}

impl Scene {
    /// Whether nothing lights the scene: no punctual light, no environment, and no instance
    /// of an emissive material.
    pub fn is_unlit(&self) -> bool {
        self.lights.is_empty()
            && self.environment.is_none()
            && !self
                .instances
                .iter()
                .any(|i| self.materials[self.meshes[i.mesh].material].is_emissive())
    }

    /// Light the scene with daylight `d`: its Preetham sky as the environment (replacing any)
    /// and its sun as a directional light.
    pub fn add_daylight(&mut self, d: &lightlab_core::sky::Daylight) {
        self.environment = Some(Environment {
            image: d.environment(256),
            intensity: 1.0,
        });
        self.add_sun(d);
    }

    /// Daylight `d`'s sun as a directional light named "sun".
    pub fn add_sun(&mut self, d: &lightlab_core::sky::Daylight) {
        use lightlab_core::sky::{SUN_COLOR, SUN_DIAMETER};
        self.lights.push(Light {
            name: "sun".into(),
            kind: LightKind::Directional {
                angular_diameter: SUN_DIAMETER,
            },
            color: SUN_COLOR,
            intensity: d.sun_irradiance,
            position: Vec3::ZERO,
            direction: -d.sun_direction(),
            range: None,
        });
    }

    /// Texture `r` at the surface point with coordinates `uv`, in the set `r` names.
    pub fn sample(&self, r: TextureRef, a: Attrs) -> Vec4 {
        self.textures[r.texture].sample(r.uv(&a))
    }

    /// Shade every material with `model` (the `--brdf` override of the command line).
    pub fn set_brdf(&mut self, model: BrdfModel) {
        for m in &mut self.materials {
            m.brdf = model;
        }
    }

    /// World-space bounds of all instances (min, max); None for an empty scene.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        (0..self.instances.len())
            .filter_map(|i| self.instance_bounds(i))
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }

    /// The scene as `wind` displaces it: every instance's vertices in world space (identity
    /// transforms), moved by `lightlab_core::wind::Wind::sway` with its material's weight;
    /// normals and tangents are carried along unchanged, as the GPU passes do.
    pub fn swayed(&self, wind: &lightlab_core::wind::Wind) -> Scene {
        let mut out = self.clone();
        out.meshes.clear();
        out.instances.clear();
        for inst in &self.instances {
            let src = &self.meshes[inst.mesh];
            let weight = self.materials.get(src.material).map_or(0.0, |m| m.sway);
            let nm = inst.normal_matrix();
            let mut m = src.clone();
            for p in &mut m.positions {
                *p = wind.sway(inst.transform.transform_point3(*p), weight);
            }
            for n in &mut m.normals {
                *n = (nm * *n).normalize_or(*n);
            }
            for t in &mut m.tangents {
                let v = inst
                    .transform
                    .transform_vector3(t.truncate())
                    .normalize_or(Vec3::X);
                *t = v.extend(t.w);
            }
            out.meshes.push(m);
            out.instances.push(Instance {
                name: inst.name.clone(),
                mesh: out.meshes.len() - 1,
                transform: Mat4::IDENTITY,
                nodes: vec![],
                luminaire: None,
            });
        }
        out
    }

    /// World-space bounds of instance `i`; None for an empty mesh.
    pub fn instance_bounds(&self, i: usize) -> Option<(Vec3, Vec3)> {
        let inst = &self.instances[i];
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for p in &self.meshes[inst.mesh].positions {
            let w = inst.transform.transform_point3(*p);
            lo = lo.min(w);
            hi = hi.max(w);
        }
        (lo.x <= hi.x).then_some((lo, hi))
    }

    /// A camera that frames the whole scene from the front-right and above (for files that
    /// bring no camera), with a 45° vertical field of view.
    pub fn framing_camera(&self) -> Option<Camera> {
        let (lo, hi) = self.bounds()?;
        let centre = (lo + hi) * 0.5;
        let radius = ((hi - lo).length() * 0.5).max(1e-3);
        let yfov = 45f32.to_radians();
        let dist = radius / (yfov * 0.5).sin();
        let dir = Vec3::new(0.5, 0.45, 1.0).normalize();
        let mut c = Camera::look_at(
            "lightlab_framing",
            centre + dir * dist,
            centre,
            Vec3::Y,
            yfov,
        );
        c.znear = (dist - radius).max(1e-3) * 0.5;
        Some(c)
    }

    pub fn default_camera(&self) -> Option<&Camera> {
        self.cameras.first()
    }

    pub fn triangle_count(&self) -> usize {
        self.instances
            .iter()
            .map(|i| self.meshes[i.mesh].triangle_count())
            .sum()
    }

    /// Append a mesh and one instance of it; returns the mesh index.
    pub fn add_mesh(&mut self, mesh: Mesh, transform: Mat4) -> usize {
        let id = self.meshes.len();
        self.instances.push(Instance {
            name: mesh.name.clone(),
            mesh: id,
            transform,
            nodes: vec![],
            luminaire: None,
        });
        self.meshes.push(mesh);
        id
    }

    pub fn add_material(&mut self, m: Material) -> usize {
        self.materials.push(m);
        self.materials.len() - 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uv_at_matches_the_weighted_corners() {
        let base = Mesh {
            positions: vec![Vec3::ZERO; 3],
            uv0: vec![
                Vec2::new(0.1, 0.2),
                Vec2::new(0.7, 0.3),
                Vec2::new(0.4, 0.9),
            ],
            ..Default::default()
        };
        let with_sets = Mesh {
            uv1: Some(vec![Vec2::new(0.5, 0.5), Vec2::new(0.2, 0.8)]),
            colors: vec![Vec4::new(0.3, 0.6, 0.9, 1.0); 3],
            ..base.clone()
        };
        for mesh in [base, with_sets] {
            for bw in [[0.2, 0.3, 0.5], [1.0 / 3.0; 3], [0.7, 0.29999, 1e-5]] {
                let want =
                    Attrs::weighted(&[mesh.attrs_of(0), mesh.attrs_of(1), mesh.attrs_of(2)], bw);
                assert_eq!(mesh.uv_at([0, 1, 2], bw), want);
            }
        }
    }

    #[test]
    fn uv_transforms_follow_the_extension_matrix() {
        // T·R·S with the rows (cos, sin; −sin, cos) of the sample implementations (the
        // extension's GLSL, read column-major, has the other sign; its test model's markers
        // follow the implementations).
        let t = UvTransform::new(
            Vec2::new(0.5, 0.25),
            std::f32::consts::FRAC_PI_2,
            Vec2::new(2.0, 1.0),
        );
        let q = t.apply(Vec2::new(1.0, 0.0));
        assert!((q - Vec2::new(0.5, -1.75)).length() < 1e-6, "{q}");
        let q = t.apply(Vec2::new(0.0, 1.0));
        assert!((q - Vec2::new(1.5, 0.25)).length() < 1e-6, "{q}");
        for (o, r, s) in [
            (Vec2::new(0.1, -3.0), 0.7, Vec2::new(1.5, 0.2)),
            (Vec2::ZERO, -2.9, Vec2::new(0.5, -4.0)),
            (Vec2::new(9.0, 1.0), 3.1, Vec2::new(-1.0, 2.0)),
        ] {
            let t = UvTransform::new(o, r, s);
            let (o2, r2, s2) = t.decompose();
            let back = UvTransform::new(o2, r2, s2);
            for (a, b) in t.0.iter().flatten().zip(back.0.iter().flatten()) {
                assert!((a - b).abs() < 1e-5, "{t:?} {back:?}");
            }
        }
        assert!(UvTransform::default().is_identity());
    }

    #[test]
    fn equirect_round_trip_and_axes() {
        for d in [
            Vec3::new(0.3, 0.5, -0.8).normalize(),
            Vec3::new(-0.9, -0.1, 0.2).normalize(),
            Vec3::new(0.0, 0.2, 1.0).normalize(),
        ] {
            let back = Environment::uv_to_dir(Environment::dir_to_uv(d));
            assert!((back - d).length() < 1e-5, "{d} {back}");
        }
        assert!((Environment::dir_to_uv(Vec3::Y).y).abs() < 1e-6);
        let f = Environment::dir_to_uv(-Vec3::Z);
        assert!((f - Vec2::new(0.5, 0.5)).length() < 1e-6);
    }

    #[test]
    fn camera_looks_at_target() {
        let c = Camera::look_at("c", Vec3::new(1.0, 2.0, 3.0), Vec3::ZERO, Vec3::Y, 0.8);
        let d = c.ray_direction(Vec2::ZERO, 1.5);
        assert!((d - (-Vec3::new(1.0, 2.0, 3.0)).normalize()).length() < 1e-5);
        // +ndc.y goes up in the world.
        assert!(c.ray_direction(Vec2::new(0.0, 1.0), 1.0).y > d.y);
    }

    #[test]
    fn tangents_follow_uv_u() {
        let mut m = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Z],
            normals: vec![Vec3::Y; 3],
            uv0: vec![Vec2::ZERO, Vec2::X, Vec2::Y],
            indices: vec![0, 2, 1],
            ..Default::default()
        };
        m.compute_tangents();
        assert!((m.tangents[0].truncate() - Vec3::X).length() < 1e-6);
        // bitangent = w·(n × t) = w·(Y × X) = −w·Z, and it must follow +v = +Z.
        assert_eq!(m.tangents[0].w, -1.0);
    }

    #[test]
    fn spot_falloff() {
        let l = Light {
            name: "s".into(),
            kind: LightKind::Spot {
                inner_cone: 0.2,
                outer_cone: 0.4,
            },
            color: Vec3::ONE,
            intensity: 1.0,
            position: Vec3::ZERO,
            direction: -Vec3::Y,
            range: None,
        };
        assert_eq!(l.emission(-Vec3::Y), 1.0);
        assert_eq!(l.emission(Vec3::X), 0.0);
    }
}

//! The reference BSDF of a scene material: Lambert (with thin diffuse transmission) plus a
//! GGX microfacet lobe.
//!
//! All directions are in the local shading frame, z = shading normal turned towards the viewer
//! (`wo.z > 0`). `wi.z < 0` means transmission through a thin surface.
//!
//! - Diffuse: `kd·base/π`, kd = (1−metallic)·(1−F_schlick(cosθo, 0.04·specular)); a fraction
//!   `transmission` of it leaves through the back side instead of the front. With
//!   `metallic = 0` and `specular = 0` this is exactly Lambert.
//! - Specular: Trowbridge–Reitz (GGX) D with α = roughness², height-correlated Smith G2, Schlick
//!   Fresnel with F0 = mix(0.04·specular, base, metallic) (glTF metallic–roughness). A measured
//!   metal (`Material::conductor`) replaces the metallic part's Schlick term by the exact
//!   conductor reflectance of its complex index times the base colour.
//! - Specular transmission (KHR_materials_transmission, factor t): a fraction t of the BSDF is
//!   a smooth dielectric interface of index `ior` — reflection with the exact Fresnel
//!   reflectance, refraction (tinted by the base colour) otherwise, total internal reflection
//!   included — and the rest, (1−t), the model above. A smooth interface (roughness below
//!   [`ROUGH_INTERFACE`]) is a delta lobe: `eval` and `pdf` hold only the (1−t) part, and
//!   `sample` returns the delta branch with a pdf of [`DELTA_PDF`], so that `f·cos/pdf` is its
//!   weight and multiple importance sampling gives the BSDF sample all the weight. A rough one
//!   (frosted glass) is the GGX microfacet dielectric of Walter et al. 2007 (reflection and
//!   refraction through microfacets of normal h, exact Fresnel at ⟨wo,h⟩), part of `eval` and
//!   `pdf` like any lobe. Neither applies the (η_o/η_i)² radiance scaling across the interface:
//!   it cancels along paths that enter and leave a closed object, which is what scenes hold.
//!   Thin-walled glass (glTF without KHR_materials_volume) is a sheet: straight through,
//!   reflecting 2F/(1+F), always smooth.
//! - Other specular lobes (`Material::brdf`, Heidrich ch. 3): Phong and Blinn-Phong (the
//!   normalised lobes of core, × F0); Torrance–Sparrow (Beckmann D with m = roughness²,
//!   separable Smith G) and Cook–Torrance (Beckmann D, V-groove G), both with the material's
//!   Fresnel like the GGX lobe; Ward's elliptical Gaussian (α = roughness², widened along the
//!   anisotropy direction to mix(α, 1, strength²), × F0); Banks's fibres along the anisotropy
//!   direction (its diffuse term ρd/π·√(1−⟨l,t⟩²) replaces Lambert; specular × F0); Lafortune's
//!   generalised cosine lobe (× F0). The local frame's x is the anisotropy direction
//!   (`render::Surface::frame`).
//! - Sampling: one lobe chosen by its estimated albedo; diffuse by cosine (flipped for
//!   transmission), specular by the distribution of normals D(h)·cosθh. The returned pdf is the
//!   one-sample mixture, as multiple importance sampling needs.

use glam::{Vec2, Vec3, Vec4};
use lightlab_core::brdf::Distribution;
use lightlab_core::brdf::{
    Banks, BlinnPhong, Brdf, Lafortune, LafortuneLobe, Masking, Phong, TorranceSparrow, Ward,
};
use lightlab_core::color::luminance;
use lightlab_core::sampling::cosine_hemisphere;
use lightlab_scene::{BrdfModel, Material, Scene};
use std::f32::consts::PI;

/// The pdf reported for a delta lobe's sample (see the module doc).
pub const DELTA_PDF: f32 = 1e8;

/// The roughness from which a dielectric interface is a microfacet lobe rather than a delta.
pub const ROUGH_INTERFACE: f32 = 0.05;

#[derive(Clone, Copy, Debug)]
pub struct Bsdf {
    /// Weight of the smooth dielectric interface (KHR_materials_transmission).
    pub delta: f32,
    pub ior: f32,
    /// Thin-walled glass (`Material::thickness` 0): a sheet that transmits straight through
    /// and reflects 2F/(1 + F), its two faces' reflections summed; always a delta lobe.
    pub thin: bool,
    /// Whether `wo` lies outside the dielectric (on the surface's authored front side): the
    /// path tracer sets it per hit; refraction goes from 1 to `ior` when true.
    pub entering: bool,
    pub base: Vec3,
    pub kd_scale: f32,
    pub transmission: f32,
    /// Reflectance at normal incidence (the classical models' specular colour, and sampling).
    pub f0: Vec3,
    /// A measured metal: (metallic × base colour, complex index) replacing Schlick's metallic
    /// part, F = (1 − metallic)·Schlick(c, f0d) + metallic·base·F_conductor(c).
    pub conductor: Option<(Vec3, lightlab_scene::Conductor)>,
    pub f0d: f32,
    pub metallic: f32,
    pub alpha: f32,
    pub specular: bool,
    /// Which specular lobe (the material's [`BrdfModel`]).
    pub model: BrdfModel,
    /// Phong / Blinn-Phong exponent.
    pub exponent: f32,
    /// KHR_materials_anisotropy strength (Ward's α along x = mix(α, 1, strength²)).
    pub anisotropy: f32,
    /// The Lafortune lobe's (C_x, C_y, C_z).
    pub lafortune: Vec3,
    p_spec: f32,
}

#[inline]
fn schlick(cos: f32, f0: Vec3) -> Vec3 {
    let m = (1.0 - cos.clamp(0.0, 1.0)).powi(5);
    f0 + (Vec3::ONE - f0) * m
}

impl Bsdf {
    /// Fresnel reflectance of the specular lobe at cosine `c` (with the microfacet normal).
    #[inline]
    pub fn fresnel(&self, c: f32) -> Vec3 {
        Self::fresnel_of(&self.conductor, self.f0, self.f0d, self.metallic, c)
    }

    fn fresnel_of(
        conductor: &Option<(Vec3, lightlab_scene::Conductor)>,
        f0: Vec3,
        f0d: f32,
        metallic: f32,
        c: f32,
    ) -> Vec3 {
        match conductor {
            None => schlick(c, f0),
            Some((metal, m)) => {
                schlick(c, Vec3::splat(f0d)) * (1.0 - metallic) + *metal * m.fresnel(c)
            }
        }
    }

    /// The specular lobe's microfacet distribution: core's GGX (one implementation of D, Λ and
    /// the half-vector sampler for the whole toolkit).
    #[inline]
    fn ggx(&self) -> Distribution {
        Distribution::Ggx {
            alpha: self.alpha as f64,
        }
    }

    /// The reflection lobe's microfacet distribution: GGX for the glTF model, Beckmann of the
    /// same width for Torrance–Sparrow and Cook–Torrance.
    #[inline]
    fn lobe_distribution(&self) -> Distribution {
        match self.model {
            BrdfModel::TorranceSparrow | BrdfModel::CookTorrance => Distribution::Beckmann {
                m: self.alpha as f64,
            },
            _ => self.ggx(),
        }
    }

    /// The reflection lobe's masking–shadowing G(wo, wi, h).
    fn masking(&self, wo: Vec3, wi: Vec3, h: Vec3) -> f32 {
        let masking = match self.model {
            BrdfModel::TorranceSparrow => Masking::Smith,
            BrdfModel::CookTorrance => Masking::VGroove,
            _ => Masking::SmithHeightCorrelated,
        };
        TorranceSparrow {
            ks: 1.0,
            eta: 1.5,
            distribution: self.lobe_distribution(),
            masking,
        }
        .g(wi.as_dvec3(), wo.as_dvec3(), h.as_dvec3()) as f32
    }

    /// The BSDF of `material` at texture coordinate `uv`, seen from local direction `wo`.
    pub fn new(scene: &Scene, material: &Material, uv: lightlab_scene::Attrs, wo_z: f32) -> Bsdf {
        // COLOR_0 multiplies the base colour (white without).
        let mut base = material.base_color * uv.color;
        if let Some(r) = material.base_color_texture {
            base *= scene.sample(r, uv);
        }
        let (mut metallic, mut roughness) = (material.metallic, material.roughness);
        if let Some(r) = material.metallic_roughness_texture {
            let t: Vec4 = scene.sample(r, uv);
            roughness *= t.y;
            metallic *= t.z;
        }
        let base = base.truncate();
        let mut transmission = material.transmission;
        if let Some(r) = material.transmission_texture {
            transmission *= scene.sample(r, uv).w;
        }
        let f0d = material.dielectric_f0();
        let conductor = material.conductor.map(|m| (base * metallic, m));
        let f0 = match &conductor {
            None => Vec3::splat(f0d).lerp(base, metallic),
            Some((metal, m)) => Vec3::splat(f0d * (1.0 - metallic)) + *metal * m.fresnel(1.0),
        };
        let model = material.brdf;
        let specular = model != BrdfModel::Lambert && (metallic > 0.0 || material.specular > 0.0);
        let kd_scale = (1.0 - metallic)
            * if material.specular > 0.0 && model == BrdfModel::Pbr {
                1.0 - schlick(wo_z, Vec3::splat(f0d)).x
            } else {
                1.0
            };
        let alpha = (roughness * roughness).max(1e-3);
        let ws = if !specular {
            0.0
        } else if model == BrdfModel::Pbr {
            luminance(Self::fresnel_of(&conductor, f0, f0d, metallic, wo_z))
        } else {
            luminance(f0)
        };
        let wd = if specular {
            luminance(base) * kd_scale
        } else {
            0.0
        };
        let p_spec = if !specular {
            0.0
        } else if wd <= 0.0 {
            1.0
        } else {
            (ws / (ws + wd)).clamp(0.1, 0.9)
        };
        Bsdf {
            delta: if model == BrdfModel::Pbr {
                material.specular_transmission.clamp(0.0, 1.0) * (1.0 - metallic)
            } else {
                0.0
            },
            ior: material.ior,
            thin: material.thickness <= 0.0,
            entering: true,
            base,
            kd_scale,
            transmission: transmission.clamp(0.0, 1.0),
            f0,
            conductor,
            f0d,
            metallic,
            alpha,
            specular,
            model,
            // Read by the classical lobes only (`classic`); a power function per hit else.
            exponent: if matches!(
                model,
                BrdfModel::Phong | BrdfModel::BlinnPhong | BrdfModel::Banks | BrdfModel::Lafortune
            ) {
                BrdfModel::exponent(roughness)
            } else {
                1.0
            },
            anisotropy: material.anisotropy.clamp(0.0, 1.0),
            lafortune: material.lafortune,
            p_spec,
        }
    }

    /// A Lambertian BSDF of reflectance `albedo` (no transmission, no specular lobe): the
    /// virtual receiver at a light-map texel, whose outgoing radiance with `albedo = 1` is
    /// irradiance/π.
    pub fn lambert(albedo: Vec3) -> Bsdf {
        Bsdf {
            delta: 0.0,
            ior: 1.5,
            thin: false,
            entering: true,
            base: albedo,
            kd_scale: 1.0,
            transmission: 0.0,
            f0: Vec3::ZERO,
            conductor: None,
            f0d: 0.0,
            metallic: 0.0,
            alpha: 1.0,
            specular: false,
            model: BrdfModel::Lambert,
            exponent: 1.0,
            anisotropy: 0.0,
            lafortune: Vec3::new(-1.0, -1.0, 1.0),
            p_spec: 0.0,
        }
    }

    /// The classical lobes of [`BrdfModel::Phong`], [`BrdfModel::BlinnPhong`],
    /// [`BrdfModel::Ward`], [`BrdfModel::Banks`] and [`BrdfModel::Lafortune`], from core
    /// (normalised, unit reflectance; scaled by `f0` as the specular colour). Lafortune takes
    /// Phong's Lewis normalisation (n+2)/(2π), Banks its own ([`Banks::normalization`]).
    fn classic<R>(&self, f: impl FnOnce(&dyn Brdf) -> R) -> Option<R> {
        let n = self.exponent as f64;
        let lewis = (n + 2.0) / (2.0 * std::f64::consts::PI);
        match self.model {
            BrdfModel::Phong => Some(f(&Phong {
                ks: 1.0,
                exponent: n,
                normalized: true,
            })),
            BrdfModel::BlinnPhong => Some(f(&BlinnPhong {
                ks: 1.0,
                exponent: n,
                normalized: true,
            })),
            BrdfModel::Ward => {
                let a = self.alpha as f64;
                let s = self.anisotropy as f64;
                Some(f(&Ward {
                    kd: 0.0,
                    ks: 1.0,
                    alpha_x: a + (1.0 - a) * s * s,
                    alpha_y: a,
                }))
            }
            BrdfModel::Banks => Some(f(&Banks {
                kd: 0.0,
                ks: Banks::normalization(n),
                exponent: n,
            })),
            BrdfModel::Lafortune => Some(f(&Lafortune {
                kd: 0.0,
                lobes: vec![LafortuneLobe {
                    ks: lewis,
                    c: self.lafortune.as_dvec3(),
                    exponent: n,
                }],
            })),
            _ => None,
        }
    }

    /// Whether the dielectric interface is a microfacet lobe (frosted glass), not a delta.
    #[inline]
    fn rough_interface(&self) -> bool {
        self.delta > 0.0 && !self.thin && self.alpha >= ROUGH_INTERFACE * ROUGH_INTERFACE
    }

    /// Whether only the diffuse lobes are present (reflection and thin transmission): the
    /// most common material takes the short paths of [`Self::eval`], [`Self::pdf`] and
    /// [`Self::sample`], which give the general code's results bit for bit.
    #[inline]
    fn diffuse_only(&self) -> bool {
        !self.specular && self.delta == 0.0 && self.model != BrdfModel::Banks
    }

    /// The diffuse lobes' value and density for `wi`.
    #[inline]
    fn diffuse(&self, wi: Vec3) -> (Vec3, f32) {
        let f = self.base * (self.kd_scale / PI);
        if wi.z > 0.0 {
            (
                f * (1.0 - self.transmission),
                (1.0 - self.transmission) * wi.z / PI,
            )
        } else {
            (f * self.transmission, self.transmission * -wi.z / PI)
        }
    }

    /// BSDF value f(wo, wi) (without the cosine; a smooth interface's delta excluded).
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if self.diffuse_only() {
            return self.diffuse(wi).0;
        }
        let mut f = self.eval_smooth(wo, wi) * (1.0 - self.delta);
        if self.rough_interface() {
            f += self.interface_eval(wo, wi) * self.delta;
        }
        f
    }

    /// Indices of refraction on wo's side and on the other.
    #[inline]
    fn indices(&self) -> (f32, f32) {
        if self.entering {
            (1.0, self.ior)
        } else {
            (self.ior, 1.0)
        }
    }

    /// The microfacet normal (h.z > 0) that takes wo to wi by reflection or refraction, with
    /// the Jacobian dω_h/dω_wi; None where no microfacet facing wo does.
    fn interface_h(&self, wo: Vec3, wi: Vec3) -> Option<(Vec3, f32)> {
        let (n_o, n_i) = self.indices();
        if wi.z > 0.0 {
            let h = (wo + wi).normalize_or_zero();
            let c = wo.dot(h);
            (h.z > 0.0 && c > 0.0).then(|| (h, 1.0 / (4.0 * c)))
        } else {
            let v = wo * n_o + wi * n_i;
            let mut h = (-v).normalize_or_zero();
            if h.z < 0.0 {
                h = -h;
            }
            let (co, ci) = (wo.dot(h), wi.dot(h));
            if !(h.z > 0.0 && co > 0.0 && ci < 0.0) {
                return None;
            }
            Some((h, n_i * n_i * -ci / v.length_squared()))
        }
    }

    /// The rough interface's f(wo, wi): F·D·G/(4⟨n,wo⟩⟨n,wi⟩) reflected; refracted
    /// |wi·h||wo·h|/(|wi.z||wo.z|)·η_i²(1−F)·D·G/(η_o(wo·h) + η_i(wi·h))², tinted.
    fn interface_eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        let Some((h, jacobian)) = self.interface_h(wo, wi) else {
            return Vec3::ZERO;
        };
        let (n_o, n_i) = self.indices();
        let ggx = self.ggx();
        let c = wo.dot(h);
        let f = lightlab_core::brdf::fresnel_dielectric(c as f64, (n_i / n_o) as f64) as f32;
        let d = ggx.d(h.z as f64) as f32;
        let g = (1.0 / (1.0 + ggx.lambda(wo.z as f64) + ggx.lambda(wi.z.abs() as f64))) as f32;
        if wi.z > 0.0 {
            Vec3::splat(f * d * g / (4.0 * wo.z * wi.z))
        } else {
            // D·(1−F)·G·|wo·h|·(dω_h/dω_wi)/(|wi.z||wo.z|): Walter's Eq 21 without the radiance
            // scaling (module doc).
            self.base * ((1.0 - f) * d * g * c * jacobian / (wi.z.abs() * wo.z))
        }
    }

    /// Density of the rough interface's sampler: h by D(h)·h.z, reflection with probability
    /// F(wo·h).
    fn interface_pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let Some((h, jacobian)) = self.interface_h(wo, wi) else {
            return 0.0;
        };
        let (n_o, n_i) = self.indices();
        let f =
            lightlab_core::brdf::fresnel_dielectric(wo.dot(h) as f64, (n_i / n_o) as f64) as f32;
        let choice = if wi.z > 0.0 { f } else { 1.0 - f };
        self.ggx().d(h.z as f64) as f32 * h.z * choice * jacobian
    }

    /// Sample the rough interface: a microfacet normal, then reflection or refraction by its
    /// Fresnel reflectance.
    fn interface_sample(&self, wo: Vec3, u_choice: f32, u: Vec2) -> Option<Vec3> {
        let h = self.ggx().sample_h(u.as_dvec2()).as_vec3();
        let c = wo.dot(h);
        if c <= 0.0 {
            return None;
        }
        let (n_o, n_i) = self.indices();
        let f = lightlab_core::brdf::fresnel_dielectric(c as f64, (n_i / n_o) as f64) as f32;
        let wi = if u_choice < f {
            2.0 * c * h - wo
        } else {
            let eta = n_o / n_i;
            let cos_t = (1.0 - eta * eta * (1.0 - c * c)).max(0.0).sqrt();
            (h * (eta * c - cos_t) - wo * eta).normalize()
        };
        // A reflection below the surface or a refraction above it is not a valid sample.
        ((wi.z > 0.0) == (u_choice < f)).then_some(wi)
    }

    fn eval_smooth(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        let mut f = self.diffuse(wi).0;
        if wi.z <= 0.0 {
            return f;
        }
        if self.model == BrdfModel::Banks {
            // Banks's diffuse term: ⟨n', l⟩ = √(1 − ⟨l,t⟩²), the normal in the plane of l and t.
            f *= (1.0 - wi.x * wi.x).max(0.0).sqrt();
        }
        if self.specular && wo.z > 0.0 {
            if let Some(c) = self.classic(|b| b.eval(wi.as_dvec3(), wo.as_dvec3())) {
                return f + self.f0 * c as f32;
            }
            let h = (wo + wi).normalize();
            let d = self.lobe_distribution().d(h.z as f64) as f32;
            let g = self.masking(wo, wi, h);
            let fr = self.fresnel(wo.dot(h));
            f += fr * (d * g / (4.0 * wo.z * wi.z));
        }
        f
    }

    /// Density of [`Self::sample`] choosing `wi` (solid angle).
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if self.diffuse_only() {
            return self.diffuse(wi).1;
        }
        let mut p = self.pdf_smooth(wo, wi) * (1.0 - self.delta);
        if self.rough_interface() {
            p += self.interface_pdf(wo, wi) * self.delta;
        }
        p
    }

    fn pdf_smooth(&self, wo: Vec3, wi: Vec3) -> f32 {
        let pd = self.diffuse(wi).1;
        let ps = if !(self.specular && wi.z > 0.0 && wo.z > 0.0) {
            0.0
        } else if let Some(p) = self.classic(|b| b.pdf(wo.as_dvec3(), wi.as_dvec3())) {
            p as f32
        } else {
            let h = (wo + wi).normalize();
            self.lobe_distribution().d(h.z as f64) as f32 * h.z / (4.0 * wo.dot(h).abs().max(1e-8))
        };
        self.p_spec * ps + (1.0 - self.p_spec) * pd
    }

    /// Sample an incident direction: (wi, f, pdf), or None when the sample is invalid.
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<(Vec3, Vec3, f32)> {
        if self.diffuse_only() {
            let wi = self.diffuse_direction(u_lobe, u);
            let (f, pdf) = self.diffuse(wi);
            return (pdf > 0.0 && pdf.is_finite()).then_some((wi, f, pdf));
        }
        let wi = if u_lobe < self.delta {
            if !self.rough_interface() {
                return self.sample_interface(wo, u_lobe / self.delta);
            }
            self.interface_sample(wo, u_lobe / self.delta, u)?
        } else {
            self.sample_base(wo, (u_lobe - self.delta) / (1.0 - self.delta), u)?
        };
        let pdf = self.pdf(wo, wi);
        if pdf <= 0.0 || !pdf.is_finite() {
            return None;
        }
        Some((wi, self.eval(wo, wi), pdf))
    }

    /// A direction from the (1 − delta) part: the specular lobe or the diffuse one.
    fn sample_base(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<Vec3> {
        Some(if u_lobe < self.p_spec {
            if let Some(wi) = self.classic(|b| b.sample(wo.as_dvec3(), u.as_dvec2())) {
                wi?.as_vec3()
            } else {
                let h = self.lobe_distribution().sample_h(u.as_dvec2()).as_vec3();
                let wi = 2.0 * wo.dot(h) * h - wo;
                if wi.z <= 0.0 {
                    return None;
                }
                wi
            }
        } else {
            // Reuse u_lobe's remaining randomness to choose front or back.
            self.diffuse_direction((u_lobe - self.p_spec) / (1.0 - self.p_spec), u)
        })
    }

    /// A direction from the diffuse lobes: cosine-weighted, through the back where
    /// `u_side < transmission`.
    #[inline]
    fn diffuse_direction(&self, u_side: f32, u: Vec2) -> Vec3 {
        let mut d = cosine_hemisphere(u);
        if u_side < self.transmission {
            d.z = -d.z;
        }
        d
    }

    /// The smooth dielectric interface: reflect with probability F (exact Fresnel), refract
    /// otherwise; the returned f·|cos|/pdf is the branch's weight (1 for reflection, the base
    /// colour for refraction).
    fn sample_interface(&self, wo: Vec3, u: f32) -> Option<(Vec3, Vec3, f32)> {
        // η = n_incident / n_transmitted for the refracted direction.
        let eta = if self.entering {
            1.0 / self.ior
        } else {
            self.ior
        };
        let cos_o = wo.z;
        let f = lightlab_core::brdf::fresnel_dielectric(cos_o as f64, 1.0 / eta as f64) as f32;
        if self.thin {
            // The sheet's reflectance with every internal bounce: F + (1−F)²F/(1 − F²).
            let (wi, weight) = if u < 2.0 * f / (1.0 + f) {
                (Vec3::new(-wo.x, -wo.y, wo.z), Vec3::ONE)
            } else {
                (-wo, self.base)
            };
            return Some((wi, weight * DELTA_PDF / wi.z.abs().max(1e-8), DELTA_PDF));
        }
        let (wi, weight) = if u < f {
            (Vec3::new(-wo.x, -wo.y, wo.z), Vec3::ONE)
        } else {
            let sin2_t = eta * eta * (1.0 - cos_o * cos_o).max(0.0);
            if sin2_t >= 1.0 {
                // Total internal reflection (F = 1 there, so this branch is not reached).
                return None;
            }
            let cos_t = (1.0 - sin2_t).sqrt();
            (Vec3::new(-wo.x * eta, -wo.y * eta, -cos_t), self.base)
        };
        let wi = wi.normalize();
        Some((wi, weight * DELTA_PDF / wi.z.abs().max(1e-8), DELTA_PDF))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lightlab_core::sampling::{Rng, uniform_sphere};

    fn bsdf(m: Material, wo_z: f32) -> Bsdf {
        Bsdf::new(
            &Scene::default(),
            &m,
            lightlab_scene::Attrs::default(),
            wo_z,
        )
    }

    #[test]
    fn lambert_is_exact() {
        let b = bsdf(Material::diffuse("d", Vec3::splat(0.5)), 0.7);
        let wo = Vec3::new(0.0, 0.714, 0.7).normalize();
        let wi = Vec3::new(0.3, 0.1, 0.9).normalize();
        assert!((b.eval(wo, wi) - Vec3::splat(0.5 / PI)).length() < 1e-7);
        assert!((b.pdf(wo, wi) - wi.z / PI).abs() < 1e-7);
    }

    /// Estimate ∫ f cos dwi with the sampler (E[f cos/pdf]) and with uniform sphere sampling:
    /// the two must agree (the sampler's pdf is consistent with its samples) and stay ≤ 1.
    #[test]
    fn sampler_pdf_is_consistent_and_energy_is_bounded() {
        let mats = [
            Material::diffuse("lambert", Vec3::splat(0.8)),
            Material {
                name: "plastic".into(),
                base_color: Vec4::new(0.2, 0.3, 0.8, 1.0),
                roughness: 0.3,
                specular: 1.0,
                ..Default::default()
            },
            Material {
                name: "metal".into(),
                base_color: Vec4::new(0.9, 0.8, 0.5, 1.0),
                roughness: 0.5,
                metallic: 1.0,
                ..Default::default()
            },
            Material {
                name: "blinn-phong".into(),
                base_color: Vec4::new(0.2, 0.3, 0.8, 1.0),
                roughness: 0.4,
                specular: 10.0,
                brdf: BrdfModel::BlinnPhong,
                ..Default::default()
            },
            Material {
                name: "phong".into(),
                base_color: Vec4::new(0.5, 0.3, 0.2, 1.0),
                roughness: 0.5,
                specular: 10.0,
                brdf: BrdfModel::Phong,
                ..Default::default()
            },
            Material {
                name: "leaf".into(),
                base_color: Vec4::new(0.3, 0.7, 0.2, 1.0),
                transmission: 0.4,
                specular: 0.0,
                ..Default::default()
            },
            frosted(0.3, 1.0),
            frosted(0.6, 0.5),
            Material {
                name: "gold".into(),
                base_color: Vec4::ONE,
                roughness: 0.3,
                metallic: 1.0,
                conductor: lightlab_scene::Conductor::preset("gold"),
                ..Default::default()
            },
            Material {
                name: "torrance-sparrow".into(),
                base_color: Vec4::new(0.7, 0.5, 0.3, 1.0),
                roughness: 0.4,
                metallic: 1.0,
                brdf: BrdfModel::TorranceSparrow,
                ..Default::default()
            },
            Material {
                name: "cook-torrance".into(),
                base_color: Vec4::new(0.2, 0.3, 0.8, 1.0),
                roughness: 0.3,
                specular: 1.0,
                brdf: BrdfModel::CookTorrance,
                ..Default::default()
            },
            Material {
                name: "ward".into(),
                base_color: Vec4::new(0.4, 0.4, 0.4, 1.0),
                roughness: 0.5,
                specular: 5.0,
                brdf: BrdfModel::Ward,
                ..Default::default()
            },
            Material {
                name: "ward-anisotropic".into(),
                base_color: Vec4::new(0.8, 0.8, 0.8, 1.0),
                roughness: 0.4,
                metallic: 1.0,
                brdf: BrdfModel::Ward,
                anisotropy: 0.7,
                ..Default::default()
            },
            Material {
                name: "banks".into(),
                base_color: Vec4::new(0.3, 0.3, 0.6, 1.0),
                roughness: 0.3,
                specular: 5.0,
                brdf: BrdfModel::Banks,
                ..Default::default()
            },
            Material {
                name: "lafortune".into(),
                base_color: Vec4::new(0.6, 0.4, 0.3, 1.0),
                roughness: 0.4,
                specular: 5.0,
                brdf: BrdfModel::Lafortune,
                lafortune: Vec3::new(-1.0, -0.8, 0.95),
                ..Default::default()
            },
        ];
        for (m, entering) in mats
            .iter()
            .map(|m| (m, true))
            .chain([(&frosted(0.3, 1.0), false)])
        {
            for wo_z in [0.9f32, 0.5, 0.2] {
                let wo = Vec3::new((1.0 - wo_z * wo_z).sqrt(), 0.0, wo_z);
                let mut b = bsdf(m.clone(), wo_z);
                b.entering = entering;
                let mut rng = Rng::new(11, 0);
                let n = 400_000;
                let (mut s1, mut s2, mut u1, mut u2) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
                for _ in 0..n {
                    let x = match b.sample(wo, rng.next_f32(), rng.next_vec2()) {
                        Some((wi, f, pdf)) => (luminance(f) * wi.z.abs() / pdf) as f64,
                        None => 0.0,
                    };
                    s1 += x;
                    s2 += x * x;
                    let wi = uniform_sphere(rng.next_vec2());
                    let y = (luminance(b.eval(wo, wi)) * wi.z.abs() * 4.0 * PI) as f64;
                    u1 += y;
                    u2 += y * y;
                }
                let nf = n as f64;
                let (es, eu) = (s1 / nf, u1 / nf);
                // Standard error of the difference of the two independent estimators.
                let se = ((s2 / nf - es * es) / nf + (u2 / nf - eu * eu) / nf).sqrt();
                assert!(es <= 1.0 + 1e-3, "{}: albedo {es}", m.name);
                assert!(
                    (es - eu).abs() < 4.0 * se + 1e-4,
                    "{} wo_z={wo_z}: sampled {es} vs uniform {eu} (σ {se})",
                    m.name
                );
            }
        }
    }

    /// Frosted glass: a rough interface of weight `t` over a white diffuse base.
    fn frosted(roughness: f32, t: f32) -> Material {
        Material {
            name: format!("frosted {roughness} {t}"),
            base_color: Vec4::ONE,
            roughness,
            specular_transmission: t,
            ior: 1.5,
            thickness: 1.0,
            ..Default::default()
        }
    }

    /// Pearson's χ² of the rough interface's samples against its pdf, over 16 × 32 bins of
    /// (cos θ, φ) on the whole sphere (reflection and refraction), from outside and inside.
    #[test]
    fn rough_interface_samples_follow_its_pdf() {
        let (nt, np) = (16usize, 32usize);
        for (roughness, entering, wo_z) in
            [(0.3, true, 0.7f32), (0.5, false, 0.9), (0.2, false, 0.5)]
        {
            let mut b = bsdf(frosted(roughness, 1.0), wo_z);
            b.entering = entering;
            let wo = Vec3::new((1.0 - wo_z * wo_z).sqrt(), 0.0, wo_z);
            let bin = |d: Vec3| {
                let t = (((d.z + 1.0) * 0.5 * nt as f32) as usize).min(nt - 1);
                let phi = d.y.atan2(d.x).rem_euclid(std::f32::consts::TAU);
                let p = ((phi / std::f32::consts::TAU * np as f32) as usize).min(np - 1);
                t * np + p
            };
            let n = 500_000;
            let mut observed = vec![0f64; nt * np];
            let mut rng = Rng::new(5, 0);
            for _ in 0..n {
                if let Some((wi, _, _)) = b.sample(wo, rng.next_f32(), rng.next_vec2()) {
                    observed[bin(wi)] += 1.0;
                }
            }
            // Expected counts: the pdf integrated over each bin on a 24 × 24 midpoint grid
            // (equal areas in cos θ × φ).
            let mut expected = vec![0f64; nt * np];
            let sub = 24;
            let cell = 2.0 / (nt * sub) as f64 * std::f64::consts::TAU / (np * sub) as f64;
            for i in 0..nt * sub {
                let z = -1.0 + (i as f64 + 0.5) * 2.0 / (nt * sub) as f64;
                for j in 0..np * sub {
                    let phi = (j as f64 + 0.5) * std::f64::consts::TAU / (np * sub) as f64;
                    let r = (1.0 - z * z).sqrt();
                    let d = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
                    expected[bin(d)] += b.pdf(wo, d) as f64 * cell * n as f64;
                }
            }
            let (mut chi2, mut dof) = (0.0, 0usize);
            let (mut rest_o, mut rest_e) = (0.0, 0.0);
            for (o, e) in observed.iter().zip(&expected) {
                if *e >= 20.0 {
                    chi2 += (o - e).powi(2) / e;
                    dof += 1;
                } else {
                    rest_o += o;
                    rest_e += e;
                }
            }
            // Samples rejected (reflection below the surface, refraction above) leave the
            // pdf's integral under one: both totals must agree.
            let total_e: f64 = expected.iter().sum();
            let total_o: f64 = observed.iter().sum();
            assert!(
                (total_o - total_e).abs() < 0.01 * n as f64,
                "r {roughness} entering {entering}: {total_o} samples, pdf integrates to {total_e}"
            );
            if rest_e > 0.0 {
                chi2 += (rest_o - rest_e).powi(2) / rest_e.max(1.0);
                dof += 1;
            }
            let limit = dof as f64 + 5.0 * (2.0 * dof as f64).sqrt();
            eprintln!(
                "rough interface r {roughness} entering {entering}: χ² {chi2:.0}, {dof} bins"
            );
            assert!(dof > 50, "too few bins: {dof}");
            assert!(
                chi2 < limit,
                "r {roughness} entering {entering}: χ² {chi2} over {dof} bins"
            );
        }
    }

    #[test]
    fn transmission_splits_energy() {
        let b = bsdf(
            Material {
                base_color: Vec4::ONE,
                transmission: 0.25,
                specular: 0.0,
                ..Default::default()
            },
            1.0,
        );
        let f_front = b.eval(Vec3::Z, Vec3::Z);
        let f_back = b.eval(Vec3::Z, -Vec3::Z);
        assert!((f_front.x - 0.75 / PI).abs() < 1e-6);
        assert!((f_back.x - 0.25 / PI).abs() < 1e-6);
    }

    /// The diffuse-only short paths give what the general code gives, bit for bit.
    #[test]
    fn the_diffuse_short_paths_match_the_general_code() {
        let mut rng = Rng::new(9, 0);
        for t in [0.0, 0.3] {
            let m = Material {
                base_color: Vec4::new(0.6, 0.4, 0.2, 1.0),
                transmission: t,
                specular: 0.0,
                ..Default::default()
            };
            let b = bsdf(m, 0.8);
            assert!(b.diffuse_only());
            for _ in 0..1000 {
                let wo = uniform_sphere(rng.next_vec2());
                let wo = Vec3::new(wo.x, wo.y, wo.z.abs());
                let wi = uniform_sphere(rng.next_vec2());
                assert_eq!(b.eval(wo, wi), b.eval_smooth(wo, wi) * (1.0 - b.delta));
                assert_eq!(b.pdf(wo, wi), b.pdf_smooth(wo, wi) * (1.0 - b.delta));
                let (u_lobe, u) = (rng.next_f32(), rng.next_vec2());
                let wi = b.sample_base(wo, u_lobe, u).unwrap();
                let general = (wi, b.eval_smooth(wo, wi), b.pdf_smooth(wo, wi));
                assert_eq!(b.sample(wo, u_lobe, u), Some(general));
            }
        }
    }
}

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
//!   Fresnel with F0 = mix(0.04·specular, base, metallic) (glTF metallic–roughness).
//! - Specular transmission (KHR_materials_transmission, factor t): a fraction t of the BSDF is
//!   a smooth dielectric interface of index `ior` — reflection with the exact Fresnel
//!   reflectance, refraction (tinted by the base colour) otherwise, total internal reflection
//!   included — and the rest, (1−t), the model above. The interface is a delta lobe: `eval` and
//!   `pdf` hold only the (1−t) part, and `sample` returns the delta branch with a pdf of
//!   [`DELTA_PDF`], so that `f·cos/pdf` is its weight and multiple importance sampling gives the
//!   BSDF sample all the weight. Roughness does not blur the interface (no rough BTDF).
//! - Sampling: one lobe chosen by its estimated albedo; diffuse by cosine (flipped for
//!   transmission), specular by the distribution of normals D(h)·cosθh. The returned pdf is the
//!   one-sample mixture, as multiple importance sampling needs.

use glam::{Vec2, Vec3, Vec4};
use lightlab_core::brdf::Distribution;
use lightlab_core::brdf::{BlinnPhong, Brdf, Phong};
use lightlab_core::color::luminance;
use lightlab_core::sampling::cosine_hemisphere;
use lightlab_scene::{BrdfModel, Material, Scene};
use std::f32::consts::PI;

/// The pdf reported for a delta lobe's sample (see the module doc).
pub const DELTA_PDF: f32 = 1e8;

#[derive(Clone, Copy, Debug)]
pub struct Bsdf {
    /// Weight of the smooth dielectric interface (KHR_materials_transmission).
    pub delta: f32,
    pub ior: f32,
    /// Whether `wo` lies outside the dielectric (on the surface's authored front side): the
    /// path tracer sets it per hit; refraction goes from 1 to `ior` when true.
    pub entering: bool,
    pub base: Vec3,
    pub kd_scale: f32,
    pub transmission: f32,
    pub f0: Vec3,
    pub alpha: f32,
    pub specular: bool,
    /// Which specular lobe (the material's [`BrdfModel`]).
    pub model: BrdfModel,
    /// Phong / Blinn-Phong exponent.
    pub exponent: f32,
    p_spec: f32,
}

#[inline]
fn schlick(cos: f32, f0: Vec3) -> Vec3 {
    let m = (1.0 - cos.clamp(0.0, 1.0)).powi(5);
    f0 + (Vec3::ONE - f0) * m
}

impl Bsdf {
    /// The specular lobe's microfacet distribution: core's GGX (one implementation of D, Λ and
    /// the half-vector sampler for the whole toolkit).
    #[inline]
    fn ggx(&self) -> Distribution {
        Distribution::Ggx {
            alpha: self.alpha as f64,
        }
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
        let f0 = Vec3::splat(f0d).lerp(base, metallic);
        let model = material.brdf;
        let specular = model != BrdfModel::Lambert && (metallic > 0.0 || material.specular > 0.0);
        let fd = schlick(wo_z, Vec3::splat(f0d)).x;
        let kd_scale = (1.0 - metallic)
            * if material.specular > 0.0 && model == BrdfModel::Pbr {
                1.0 - fd
            } else {
                1.0
            };
        let alpha = (roughness * roughness).max(1e-3);
        let ws = if !specular {
            0.0
        } else if model == BrdfModel::Pbr {
            luminance(schlick(wo_z, f0))
        } else {
            luminance(f0)
        };
        let wd = luminance(base) * kd_scale;
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
            entering: true,
            base,
            kd_scale,
            transmission: transmission.clamp(0.0, 1.0),
            f0,
            alpha,
            specular,
            model,
            exponent: BrdfModel::exponent(roughness),
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
            entering: true,
            base: albedo,
            kd_scale: 1.0,
            transmission: 0.0,
            f0: Vec3::ZERO,
            alpha: 1.0,
            specular: false,
            model: BrdfModel::Lambert,
            exponent: 1.0,
            p_spec: 0.0,
        }
    }

    /// The classical lobes of [`BrdfModel::Phong`] and [`BrdfModel::BlinnPhong`], from core
    /// (normalised, unit reflectance; scaled by `f0` as the specular colour).
    fn classic<R>(&self, f: impl FnOnce(&dyn Brdf) -> R) -> Option<R> {
        let n = self.exponent as f64;
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
            _ => None,
        }
    }

    /// BSDF value f(wo, wi) (without the cosine; the delta interface excluded).
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        self.eval_smooth(wo, wi) * (1.0 - self.delta)
    }

    fn eval_smooth(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        let diffuse = self.base * (self.kd_scale / PI);
        if wi.z <= 0.0 {
            return diffuse * self.transmission;
        }
        let mut f = diffuse * (1.0 - self.transmission);
        if self.specular && wo.z > 0.0 {
            if let Some(c) = self.classic(|b| b.eval(wi.as_dvec3(), wo.as_dvec3())) {
                return f + self.f0 * c as f32;
            }
            let h = (wo + wi).normalize();
            let ggx = self.ggx();
            let d = ggx.d(h.z as f64) as f32;
            let g = (1.0 / (1.0 + ggx.lambda(wo.z as f64) + ggx.lambda(wi.z as f64))) as f32;
            let fr = schlick(wo.dot(h), self.f0);
            f += fr * (d * g / (4.0 * wo.z * wi.z));
        }
        f
    }

    /// Density of [`Self::sample`] choosing `wi` (solid angle).
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.pdf_smooth(wo, wi) * (1.0 - self.delta)
    }

    fn pdf_smooth(&self, wo: Vec3, wi: Vec3) -> f32 {
        let pd = if wi.z > 0.0 {
            (1.0 - self.transmission) * wi.z / PI
        } else {
            self.transmission * -wi.z / PI
        };
        let ps = if !(self.specular && wi.z > 0.0 && wo.z > 0.0) {
            0.0
        } else if let Some(p) = self.classic(|b| b.pdf(wo.as_dvec3(), wi.as_dvec3())) {
            p as f32
        } else {
            let h = (wo + wi).normalize();
            self.ggx().d(h.z as f64) as f32 * h.z / (4.0 * wo.dot(h).abs().max(1e-8))
        };
        self.p_spec * ps + (1.0 - self.p_spec) * pd
    }

    /// Sample an incident direction: (wi, f, pdf), or None when the sample is invalid.
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<(Vec3, Vec3, f32)> {
        if u_lobe < self.delta {
            return self.sample_interface(wo, u_lobe / self.delta);
        }
        let u_lobe = (u_lobe - self.delta) / (1.0 - self.delta);
        let wi = if u_lobe < self.p_spec {
            if let Some(wi) = self.classic(|b| b.sample(wo.as_dvec3(), u.as_dvec2())) {
                wi?.as_vec3()
            } else {
                let h = self.ggx().sample_h(u.as_dvec2()).as_vec3();
                let wi = 2.0 * wo.dot(h) * h - wo;
                if wi.z <= 0.0 {
                    return None;
                }
                wi
            }
        } else {
            // Reuse u_lobe's remaining randomness to choose front or back.
            let u2 = (u_lobe - self.p_spec) / (1.0 - self.p_spec);
            let mut d = cosine_hemisphere(u);
            if u2 < self.transmission {
                d.z = -d.z;
            }
            d
        };
        let pdf = self.pdf(wo, wi);
        if pdf <= 0.0 || !pdf.is_finite() {
            return None;
        }
        Some((wi, self.eval(wo, wi), pdf))
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
        ];
        for m in mats {
            for wo_z in [0.9f32, 0.5, 0.2] {
                let wo = Vec3::new((1.0 - wo_z * wo_z).sqrt(), 0.0, wo_z);
                let b = bsdf(m.clone(), wo_z);
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
}

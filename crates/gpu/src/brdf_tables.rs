//! Heidrich's lookup-table shading (§5.1, §5.2): reflection models evaluated from 2-D tables
//! the shader reads, instead of their formulas (`--brdf-eval tables`).
//!
//! - Torrance–Sparrow (separable Smith G), factorised as f·cos α = T1(cos θ, cos δ) ·
//!   T2(cos α, cos β) with T1 = F·D (RGB: the material's Fresnel) and T2 = G/(4 cos β), as
//!   `lightlab_core::brdf::FactorizedTs` (θ between l and h, δ between n and h, α and β the
//!   light's and the viewer's angles with n). Deviation: T1's rows are indexed by √(1 − cos δ),
//!   not cos δ. Heidrich's cos δ axis spends one texel of 256 on a lobe of RMS slope 0.06
//!   (cos δ > 0.996): measured on `brdfs` with every surface Torrance–Sparrow, 16-bit tables
//!   on the cos δ axis err by 1.7 % (relative L1) against the formula; √(1 − cos δ) is nearly
//!   δ/√2, uniform in angle near the peak.
//! - Banks: one table over (⟨l,t⟩, ⟨v,t⟩) ∈ [−1, 1]², red the diffuse factor √(1 − ⟨l,t⟩²),
//!   green the normalised specular term (`Banks::table`).
//!
//! Tables are `TABLE_SIZE`² with samples at i/(n − 1), read with four texel loads and a
//! bilinear blend in the shader (`table_read` in common.wgsl), so they read exactly as the CPU
//! model's lookup. Texels are 8-bit unsigned normalised, as Heidrich's, or 16-bit floats, each
//! table scaled into [0, 1] by a bound of its values (`GpuMaterial::tables`): T1 by D's peak
//! 1/(π m²) (F ≤ 1), T2 by 1/(4 · 0.1) (its rows at cos β < 0.1 clamp: the grazing
//! singularity); Banks's entries are ≤ 1 and its normalisation is applied in the shader.
//!
//! A table describes one uniform material, as in the seed: F and the exponent come from the
//! material's factors (a base-colour texture or vertex colours do not reach T1), and the other
//! models keep their formulas. The deferred path shades from the G-buffer, which does not name
//! the material, so it stays analytic.

use lightlab_core::brdf::{Distribution, TableBits, fresnel_conductor};
use lightlab_scene::{BrdfModel, Material, Scene};

/// Samples per axis of every table.
pub const TABLE_SIZE: usize = 256;

/// How the renderers evaluate Torrance–Sparrow and Banks materials.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BrdfEval {
    /// Their formulas, per fragment.
    #[default]
    Analytic,
    /// Heidrich's 2-D tables at this precision.
    Tables(TableBits),
}

/// The largest T2 = G/(4 cos β) stored: its value at cos β = 0.1 with G = 1.
const T2_BOUND: f64 = 2.5;

/// The first table layer of each material with tables (Torrance–Sparrow: T1 and T2; Banks:
/// one), in material order, and the number of layers.
pub fn layers(materials: &[Material]) -> (Vec<Option<u32>>, u32) {
    let mut next = 0;
    let first = materials
        .iter()
        .map(|m| {
            let n = match m.brdf {
                BrdfModel::TorranceSparrow => 2,
                BrdfModel::Banks => 1,
                _ => return None,
            };
            next += n;
            Some(next - n)
        })
        .collect();
    (first, next)
}

/// The material's Beckmann RMS slope and Phong-family exponent as the shaders derive them.
fn slope(m: &Material) -> f64 {
    (m.roughness as f64 * m.roughness as f64).max(1e-3)
}

/// `phong_exponent` of common.wgsl.
fn exponent(m: &Material) -> f64 {
    let a2 = (m.roughness as f64).powi(4).max(1e-6);
    2.0 / a2 - 2.0
}

/// `GpuMaterial::tables`: (scale of layer 0, scale of layer 1 or of Banks's specular, first
/// layer, 1) for a material with tables; zero otherwise.
pub fn gpu_entry(m: &Material, first: Option<u32>) -> [f32; 4] {
    let Some(first) = first else {
        return [0.0; 4];
    };
    match m.brdf {
        BrdfModel::TorranceSparrow => {
            let s = slope(m);
            let d_peak = 1.0 / (std::f64::consts::PI * s * s);
            [d_peak as f32, T2_BOUND as f32, first as f32, 1.0]
        }
        _ => {
            let norm = lightlab_core::brdf::Banks::normalization(exponent(m));
            [1.0, norm as f32, first as f32, 1.0]
        }
    }
}

/// The material's Fresnel reflectance per channel at cosine `c`, as `surface_fresnel` in
/// common.wgsl computes it from the material's factors.
fn fresnel(m: &Material, c: f64) -> [f64; 3] {
    let r = (m.ior as f64 - 1.0) / (m.ior as f64 + 1.0);
    let f0d = r * r * m.specular as f64;
    let metallic = m.metallic as f64;
    let schlick = |f0: f64| f0 + (1.0 - f0) * (1.0 - c).max(0.0).powi(5);
    std::array::from_fn(|i| {
        let base = m.base_color[i] as f64;
        match m.conductor {
            Some(k) => {
                schlick(f0d) * (1.0 - metallic)
                    + base * metallic * fresnel_conductor(c, k.eta[i] as f64, k.k[i] as f64)
            }
            None => schlick(f0d + (base - f0d) * metallic),
        }
    })
}

/// The layers of one material's tables, unscaled (RGBA per texel).
fn material_layers(m: &Material) -> Vec<Vec<[f64; 4]>> {
    let n = TABLE_SIZE;
    let c = |i: usize| i as f64 / (n - 1) as f64;
    let grid = |f: &dyn Fn(usize, usize) -> [f64; 4]| {
        (0..n * n).map(|k| f(k % n, k / n)).collect::<Vec<_>>()
    };
    match m.brdf {
        BrdfModel::TorranceSparrow => {
            let d = Distribution::Beckmann { m: slope(m) };
            let g1 = |x: f64| 1.0 / (1.0 + d.lambda(x));
            // T1's rows: y = √(1 − cos δ) (see the module doc).
            let t1 = grid(&|i, j| {
                let f = fresnel(m, c(i));
                let dd = d.d(1.0 - c(j) * c(j));
                [f[0] * dd, f[1] * dd, f[2] * dd, 0.0]
            });
            let t2 = grid(&|i, j| {
                let v = (g1(c(i)) * g1(c(j)) / (4.0 * c(j).max(c(1)))).min(T2_BOUND);
                [v, 0.0, 0.0, 0.0]
            });
            vec![t1, t2]
        }
        _ => {
            let banks = lightlab_core::brdf::Banks {
                kd: 0.0,
                ks: 1.0,
                exponent: exponent(m),
            };
            let t = grid(&|i, j| {
                let (a, b) = (2.0 * c(i) - 1.0, 2.0 * c(j) - 1.0);
                [(1.0 - a * a).max(0.0).sqrt(), banks.table(a, b), 0.0, 0.0]
            });
            vec![t]
        }
    }
}

/// Every material's table layers, each divided by its scale (`gpu_entry`) and rounded to
/// `bits`, as RGBA f32 texels (at least one layer: a zero one when no material has tables).
pub fn texels(scene: &Scene, bits: TableBits) -> (Vec<[f32; 4]>, u32) {
    let (first, count) = layers(&scene.materials);
    let mut out = vec![];
    for (m, f) in scene.materials.iter().zip(&first) {
        if f.is_none() {
            continue;
        }
        let entry = gpu_entry(m, *f);
        for (k, layer) in material_layers(m).into_iter().enumerate() {
            // Banks: red the diffuse factor, green the lobe before its normalisation (both
            // ≤ 1; the shader multiplies green by the normalisation, `gpu_entry`).
            let scale = match (m.brdf, k) {
                (BrdfModel::Banks, _) => [1.0; 4],
                (_, 0) => [entry[0] as f64; 4],
                _ => [entry[1] as f64; 4],
            };
            out.extend(
                layer
                    .iter()
                    .map(|t| std::array::from_fn(|c| bits.round(t[c] / scale[c]) as f32)),
            );
        }
    }
    if count == 0 {
        out = vec![[0.0; 4]; TABLE_SIZE * TABLE_SIZE];
    }
    (out, count.max(1))
}

/// The tables of `scene`'s materials as a texture array for `eval` (two black 1 × 1 layers when
/// the formulas are used; `resources::array_layers` keeps GL from taking it for a cube map).
pub fn texture(ctx: &crate::GpuContext, scene: &Scene, eval: BrdfEval) -> wgpu::TextureView {
    let (data, layers, size, bits) = match eval {
        BrdfEval::Analytic => (vec![[0.0f32; 4]; 2], 2, 1, TableBits::Sixteen),
        BrdfEval::Tables(bits) => {
            let (mut data, layers) = texels(scene, bits);
            let layers = crate::resources::array_layers(layers);
            data.resize(layers as usize * TABLE_SIZE * TABLE_SIZE, [0.0; 4]);
            (data, layers, TABLE_SIZE as u32, bits)
        }
    };
    let (format, bytes): (_, Vec<u8>) = match bits {
        TableBits::Eight => (
            wgpu::TextureFormat::Rgba8Unorm,
            data.iter()
                .flat_map(|t| t.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8))
                .collect(),
        ),
        TableBits::Sixteen => (
            wgpu::TextureFormat::Rgba16Float,
            bytemuck::cast_slice(
                &data
                    .iter()
                    .flat_map(|t| t.map(half::f16::from_f32))
                    .collect::<Vec<_>>(),
            )
            .to_vec(),
        ),
    };
    let tex = crate::resources::texture(
        &ctx.device,
        "brdf tables",
        size,
        size,
        layers,
        format,
        wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
    );
    let texel = format.block_copy_size(None).unwrap_or(4);
    let layer_bytes = (size * size * texel) as usize;
    for layer in 0..layers {
        crate::resources::write_layer(
            ctx,
            &tex,
            layer,
            &bytes[layer as usize * layer_bytes..][..layer_bytes],
            size * texel,
            [size, size],
        );
    }
    crate::resources::array_view(&tex)
}

#[cfg(test)]
mod tests {
    use super::*;
    use lightlab_core::brdf::{FactorizedTs, Masking, TorranceSparrow};

    /// A dielectric Torrance–Sparrow material's tables: T1 is F·D on the √(1 − cos δ) rows, T2
    /// is core's FactorizedTs's for the same slope, and the scales bound both.
    #[test]
    fn torrance_sparrow_tables_are_the_cores_factorisation() {
        let m = Material {
            brdf: BrdfModel::TorranceSparrow,
            roughness: 0.6,
            metallic: 0.0,
            specular: 1.0,
            ior: 1.5,
            ..Default::default()
        };
        let layers = material_layers(&m);
        let ts = TorranceSparrow {
            ks: 1.0,
            eta: 1.5,
            distribution: Distribution::Beckmann { m: 0.36 },
            masking: Masking::Smith,
        };
        let core = FactorizedTs::new(&ts, TABLE_SIZE);
        // T1 = F·D with the shaders' Schlick F (surface_fresnel) and core's Beckmann D.
        let core_t1 = |ts: &TorranceSparrow, cos_theta: f64, cos_delta: f64| {
            fresnel(&m, cos_theta)[0] * ts.distribution.d(cos_delta)
        };
        let n = TABLE_SIZE;
        for k in (0..n * n).step_by(997) {
            // T1 at (cos θ, y = √(1 − cos δ)): row y holds cos δ = 1 − y².
            let (i, j) = (k % n, k / n);
            let (ct, y) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
            let exact = core_t1(&ts, ct, 1.0 - y * y);
            let a = layers[0][k][0];
            assert!(
                (a - exact).abs() <= 1e-5 * exact + 1e-12,
                "T1 {k}: {a} vs {exact}"
            );
            let (a, b) = (layers[1][k][0], core.t2[k].min(T2_BOUND));
            // (The material's roughness is an f32: its m differs from 0.36 by 3e-8.)
            assert!((a - b).abs() <= 1e-5 * b, "T2 {k}: {a} vs {b}");
        }
        // The scales bound the tables.
        let e = gpu_entry(&m, Some(0));
        assert!(layers[0].iter().all(|t| t[0] <= e[0] as f64 * (1.0 + 1e-6)));
        assert!(layers[1].iter().all(|t| t[0] <= e[1] as f64));
    }

    /// Layers are handed out in material order: two per Torrance–Sparrow, one per Banks.
    #[test]
    fn layers_follow_the_materials() {
        let mat = |brdf| Material {
            brdf,
            ..Default::default()
        };
        let ms = [
            mat(BrdfModel::Banks),
            mat(BrdfModel::Pbr),
            mat(BrdfModel::TorranceSparrow),
            mat(BrdfModel::Banks),
        ];
        assert_eq!(layers(&ms), (vec![Some(0), None, Some(1), Some(3)], 4));
    }
}

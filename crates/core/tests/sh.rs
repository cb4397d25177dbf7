//! Acceptance tests of the spherical-harmonics module against analytic values.

use glam::{DMat3, DQuat, DVec3, Vec3};
use lightlab_core::image::Image;
use lightlab_core::quadrature::DirectionSet;
use lightlab_core::sampling::{Rng, uniform_sphere};
use lightlab_core::sh::{self, Rotation, TripleProduct, Window, index, num_coeffs};
use lightlab_core::sh_env::{self, EnvFormat};
use std::f64::consts::PI;

fn random_dir(rng: &mut Rng) -> DVec3 {
    uniform_sphere(rng.next_vec2()).as_dvec3().normalize()
}

#[test]
fn basis_matches_the_closed_forms_and_sign_convention() {
    let d = DVec3::new(0.3, -0.5, 0.7).normalize();
    let (x, y, z) = (d.x, d.y, d.z);
    let c = sh::eval(3, d);
    let expect = [
        0.282095,
        0.488603 * y,
        0.488603 * z,
        0.488603 * x,
        1.092548 * x * y,
        1.092548 * y * z,
        0.315392 * (3.0 * z * z - 1.0),
        1.092548 * x * z,
        0.546274 * (x * x - y * y),
    ];
    for (i, (a, b)) in c.iter().zip(expect).enumerate() {
        assert!((a - b).abs() < 2e-6, "Y[{i}] = {a}, expected {b}");
    }
}

#[test]
fn orthonormal_to_1e10_up_to_10_bands() {
    let bands = 10;
    let set = DirectionSet::exact_for_degree(2 * (bands - 1));
    let n = num_coeffs(bands);
    let mut gram = vec![0.0; n * n];
    for (d, w) in set.dirs.iter().zip(&set.weights) {
        let y = sh::eval(bands, *d);
        for i in 0..n {
            for j in 0..n {
                gram[i * n + j] += y[i] * y[j] * w;
            }
        }
    }
    let mut worst = 0.0f64;
    for i in 0..n {
        for j in 0..n {
            let e = if i == j { 1.0 } else { 0.0 };
            worst = worst.max((gram[i * n + j] - e).abs());
        }
    }
    eprintln!("orthonormality, 10 bands: max |<Yi,Yj> − δij| = {worst:e}");
    assert!(worst < 1e-10, "{worst}");
}

#[test]
fn f32_evaluation_matches_f64() {
    let mut rng = Rng::new(1, 0);
    let mut out = vec![0.0f32; 100];
    for _ in 0..200 {
        let d = random_dir(&mut rng);
        sh::eval_f32(10, d.x as f32, d.y as f32, d.z as f32, &mut out);
        let r = sh::eval(10, d);
        for (a, b) in out.iter().zip(&r) {
            assert!((*a as f64 - b).abs() < 2e-5 * (1.0 + b.abs()), "{a} vs {b}");
        }
    }
}

#[test]
fn clamped_cosine_zonal_coefficients() {
    let z = sh::clamped_cosine_zonal(5);
    let expect = [0.886227, 1.023327, 0.495416, 0.0, -0.110778];
    eprintln!("clamped cosine zonal: {z:?}");
    for (a, b) in z.iter().zip(expect) {
        assert!((a - b).abs() < 1e-6, "{a} vs {b}");
    }
    // A_l = √(4π/(2l+1))·z_l = π, 2π/3, π/4, 0, −π/24
    let a: Vec<f64> = z
        .iter()
        .enumerate()
        .map(|(l, v)| (4.0 * PI / (2 * l + 1) as f64).sqrt() * v)
        .collect();
    for (x, y) in a
        .iter()
        .zip([PI, 2.0 * PI / 3.0, PI / 4.0, 0.0, -PI / 24.0])
    {
        assert!((x - y).abs() < 1e-12);
    }
}

/// One directional light of unit irradiance: the 9-coefficient irradiance is
/// 0.09375 + 0.5c + 0.46875c² (c = n·ω), exact at c ∈ {−1, 0, 1} and everywhere.
#[test]
fn directional_light_irradiance_is_the_quadratic() {
    let w = DVec3::new(0.2, 0.9, -0.3).normalize();
    let e = sh::irradiance_from_radiance(&sh::project_directional(3, w, 1.0));
    let (t, _) = {
        let t = w.any_orthonormal_vector();
        (t, 0)
    };
    for c in [-1.0f64, -0.5333, 0.0, 0.5, 1.0] {
        let n = w * c + t * (1.0 - c * c).max(0.0).sqrt();
        let got = sh::evaluate(&e, n);
        let expect = 0.09375 + 0.5 * c + 0.46875 * c * c;
        assert!((got - expect).abs() < 1e-12, "c={c}: {got} vs {expect}");
    }
}

#[test]
fn constant_environment_gives_pi_l() {
    let set = DirectionSet::exact_for_degree(8);
    let l = 1.7;
    let e = sh::irradiance_from_radiance(&sh::project(5, &set, |_| l));
    let mut rng = Rng::new(2, 0);
    for _ in 0..20 {
        let got = sh::evaluate(&e, random_dir(&mut rng));
        assert!((got - PI * l).abs() < 1e-12, "{got}");
    }
}

/// Grace Cathedral (Ramamoorthi–Hanrahan's table, five-decimal version): the general
/// convolution reproduces their quadratic form (eq. 12) to the precision of its constants.
#[test]
fn grace_cathedral_irradiance_matches_ramamoorthi_hanrahan() {
    let g: [DVec3; 9] = [
        DVec3::new(0.78908, 0.43710, 0.54161),
        DVec3::new(0.39499, 0.34989, 0.60488),
        DVec3::new(-0.33974, -0.18236, -0.26940),
        DVec3::new(-0.29213, -0.05562, 0.00944),
        DVec3::new(-0.11141, -0.05090, -0.12231),
        DVec3::new(-0.26240, -0.22401, -0.47479),
        DVec3::new(-0.15570, -0.09471, -0.14733),
        DVec3::new(0.56014, 0.21444, 0.13915),
        DVec3::new(0.21205, -0.05432, -0.30374),
    ];
    let e = sh::irradiance_from_radiance(&g);
    let mut rng = Rng::new(3, 0);
    let mut worst = 0.0f64;
    for _ in 0..500 {
        let n = random_dir(&mut rng);
        let a = sh::evaluate_rgb(&e, n);
        let b = sh::irradiance_rh(&g, n);
        worst = worst.max((a - b).abs().max_element());
    }
    eprintln!("Grace Cathedral: max |E_general − E_RH| = {worst:e}");
    assert!(worst < 1e-5, "{worst}");
    // Spot values of the quadratic form at the axes (E at +z and −z).
    let up = sh::irradiance_rh(&g, DVec3::Z);
    assert!(up.x > 0.0 && up.min_element() > 0.0);
}

fn random_rotation(rng: &mut Rng) -> DMat3 {
    let axis = random_dir(rng);
    DMat3::from_quat(DQuat::from_axis_angle(axis, rng.next_f64() * 2.0 * PI))
}

/// Rotating coefficients equals projecting the rotated function: checked pointwise at random
/// directions (g(d) = f(R⁻¹d)) for bands 0–9, and band energy is invariant.
#[test]
fn rotation_is_exact_and_preserves_band_energy() {
    let bands = 10;
    let mut rng = Rng::new(4, 0);
    for _ in 0..5 {
        let f: Vec<f64> = (0..num_coeffs(bands))
            .map(|_| rng.next_f64() * 2.0 - 1.0)
            .collect();
        let r = random_rotation(&mut rng);
        let g = Rotation::new(bands, r).apply(&f);
        for _ in 0..50 {
            let d = random_dir(&mut rng);
            let a = sh::evaluate(&g, d);
            let b = sh::evaluate(&f, r.transpose() * d);
            assert!((a - b).abs() < 1e-9, "{a} vs {b}");
        }
        for l in 0..bands {
            let ef: f64 = f[l * l..(l + 1) * (l + 1)].iter().map(|v| v * v).sum();
            let eg: f64 = g[l * l..(l + 1) * (l + 1)].iter().map(|v| v * v).sum();
            assert!(
                (ef - eg).abs() < 1e-10 * ef.max(1.0),
                "band {l}: {ef} vs {eg}"
            );
        }
    }
    // A rotation by 90° about z maps x → y: the coefficient of Y11 (∝ x) moves to Y1-1 (∝ y).
    let mut c = vec![0.0; 4];
    c[index(1, 1)] = 1.0;
    let rz = DMat3::from_rotation_z(PI / 2.0);
    let rc = Rotation::new(2, rz).apply(&c);
    assert!(
        (rc[index(1, -1)] - 1.0).abs() < 1e-12 && rc[index(1, 1)].abs() < 1e-12,
        "{rc:?}"
    );
}

/// The projected product of two band-limited functions equals numeric integration.
#[test]
fn triple_product_matches_numeric_integration() {
    let bands = 5;
    let tp = TripleProduct::new(bands);
    let mut rng = Rng::new(5, 0);
    let a: Vec<f64> = (0..num_coeffs(bands))
        .map(|_| rng.next_f64() - 0.5)
        .collect();
    let b: Vec<f64> = (0..num_coeffs(bands))
        .map(|_| rng.next_f64() - 0.5)
        .collect();
    let c = tp.product(&a, &b);
    let set = DirectionSet::exact_for_degree(3 * (bands - 1));
    let numeric = sh::project(bands, &set, |d| sh::evaluate(&a, d) * sh::evaluate(&b, d));
    let worst = c
        .iter()
        .zip(&numeric)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    eprintln!(
        "triple product, 5 bands: max error {worst:e}, {} non-zero entries",
        tp.entries.len()
    );
    assert!(worst < 1e-6, "{worst}");
    // The product matrix agrees with the tensor.
    let m = tp.matrix(&a);
    let n = num_coeffs(bands);
    for i in 0..n {
        let v: f64 = (0..n).map(|j| m[i * n + j] * b[j]).sum();
        assert!((v - c[i]).abs() < 1e-12);
    }
    // Γ000 = Y00 = 1/(2√π).
    assert!((tp.entries[0].3 - 0.5 / PI.sqrt()).abs() < 1e-12);
}

#[test]
fn caps_discs_and_skies() {
    // Cap zonal coefficients against a fine 1-D integral of P_l over [cos α, 1].
    let alpha = 0.7f64;
    let z = sh::cap_zonal(6, alpha);
    let (x, w) = lightlab_core::quadrature::gauss_legendre(64);
    for (l, zl) in z.iter().enumerate() {
        let c = alpha.cos();
        let mut integral = 0.0;
        for (xi, wi) in x.iter().zip(&w) {
            let t = c + (1.0 - c) * 0.5 * (xi + 1.0);
            let y = sh::eval(l + 1, DVec3::new((1.0 - t * t).sqrt(), 0.0, t));
            integral += 2.0 * PI * (1.0 - c) * 0.5 * wi * y[index(l, 0)];
        }
        assert!((zl - integral).abs() < 1e-12, "l={l}: {zl} vs {integral}");
    }
    // A uniform sky over the upper hemisphere: irradiance at the zenith is πL exactly, and the
    // 9-coefficient approximation keeps it to within the known truncation error.
    let sky = sh::project_uniform_sky(12, DVec3::Y, 1.0);
    let e = sh::irradiance_from_radiance(&sky);
    let top = sh::evaluate(&e, DVec3::Y);
    assert!((top - PI).abs() < 1e-3, "{top}");
    // Disc of radius α: total power 2π(1 − cos α)·L is carried by the DC term.
    let d = sh::project_disc(4, DVec3::new(0.3, 0.4, 0.5).normalize(), alpha, 2.0);
    assert!((d[0] * 2.0 * PI.sqrt() - 2.0 * 2.0 * PI * (1.0 - alpha.cos())).abs() < 1e-12);
}

#[test]
fn windows_reduce_ringing() {
    for size in [4.0, 6.0] {
        for w in [Window::Hann { size }, Window::Lanczos { size }] {
            assert_eq!(w.weight(0), 1.0);
            assert!(w.weight(size as usize) == 0.0);
            assert!(w.weight(1) < 1.0 && w.weight(1) > w.weight(2));
        }
    }
    // A narrow cap truncated at 6 bands rings (negative lobes); windowing shrinks them.
    let c = sh::project_disc(6, DVec3::Z, 0.3, 1.0);
    let min_along = |c: &[f64]| {
        (0..=180)
            .map(|i| {
                sh::evaluate(
                    c,
                    DVec3::new(
                        (i as f64).to_radians().sin(),
                        0.0,
                        (i as f64).to_radians().cos(),
                    ),
                )
            })
            .fold(f64::INFINITY, f64::min)
    };
    let raw = min_along(&c);
    let mut h = c.clone();
    Window::Hann { size: 6.0 }.apply(&mut h);
    let mut l = c.clone();
    Window::Lanczos { size: 6.0 }.apply(&mut l);
    eprintln!(
        "cap ringing minimum: raw {raw:.4}, Hann {:.4}, Lanczos {:.4}",
        min_along(&h),
        min_along(&l)
    );
    assert!(raw < -0.01);
    assert!(min_along(&h) > raw * 0.5);
    assert!(min_along(&l) > raw);
}

/// Projection of a lat-long map at texel centres agrees with a brute-force projection that
/// supersamples every texel (4×4) with exact sub-texel solid angles, to 1e-4 at 512×256 (the
/// centre-sampling error falls as the texel area: 5e-3 at 64×32).
#[test]
fn env_projection_matches_brute_force() {
    let (w, h) = (512u32, 256u32);
    let img = Image::from_fn(w, h, |x, y| {
        let d = sh_env::latlong_uv_to_dir(glam::Vec2::new(
            (x as f32 + 0.5) / w as f32,
            (y as f32 + 0.5) / h as f32,
        ));
        Vec3::new(1.0 + d.x, 0.5 + 0.5 * d.y * d.y, 2.0 + d.z * d.x)
    });
    let bands = 4;
    let fast = sh_env::project_env(&img, EnvFormat::LatLong, bands);
    let mut brute = vec![DVec3::ZERO; num_coeffs(bands)];
    let s = 4;
    for y in 0..h {
        for sy in 0..s {
            let v0 = (y as f64 + sy as f64 / s as f64) / h as f64;
            let v1 = v0 + 1.0 / (h as f64 * s as f64);
            let omega = 2.0 * PI / (w as f64 * s as f64) * ((PI * v0).cos() - (PI * v1).cos());
            for x in 0..w {
                for sx in 0..s {
                    let u = (x as f64 + (sx as f64 + 0.5) / s as f64) / w as f64;
                    let d = sh_env::latlong_uv_to_dir(glam::Vec2::new(
                        u as f32,
                        ((v0 + v1) * 0.5) as f32,
                    ))
                    .as_dvec3()
                    .normalize();
                    let yv = sh::eval(bands, d);
                    let val = img.get(x, y).as_dvec3() * omega;
                    for (c, b) in brute.iter_mut().zip(&yv) {
                        *c += val * *b;
                    }
                }
            }
        }
    }
    let worst = fast
        .iter()
        .zip(&brute)
        .map(|(a, b)| (*a - *b).abs().max_element())
        .fold(0.0, f64::max);
    eprintln!("env projection (512×256) vs 4×4 supersampled brute force: max |Δc| = {worst:e}");
    assert!(worst < 1e-4, "{worst}");
    // A constant map projects to L00 = 2√π·L exactly (solid angles sum to 4π).
    let c = sh_env::project_env(
        &Image::from_fn(w, h, |_, _| Vec3::ONE),
        EnvFormat::LatLong,
        1,
    );
    assert!((c[0].x - 2.0 * PI.sqrt()).abs() < 1e-9);
    let c = sh_env::project_env(
        &Image::from_fn(256, 256, |_, _| Vec3::ONE),
        EnvFormat::Angular,
        1,
    );
    assert!(
        (c[0].x - 2.0 * PI.sqrt()).abs() < 2e-2,
        "angular map solid angles: {}",
        c[0].x
    );
}

/// A cube strip and a lat-long map of the same smooth sky project to the same coefficients.
#[test]
fn cube_strip_projection_agrees_with_latlong() {
    let sky = |d: DVec3| {
        Vec3::new(
            (1.0 + d.x * 0.5 + d.y * d.y) as f32,
            (0.7 + 0.3 * d.z) as f32,
            0.5,
        )
    };
    let n = 128u32;
    let strip = Image::from_fn(6 * n, n, |x, y| {
        let face = (x / n) as usize;
        let uv = glam::DVec2::new(
            ((x % n) as f64 + 0.5) / n as f64,
            (y as f64 + 0.5) / n as f64,
        );
        sky(lightlab_core::param::Param::Cube
            .uv_to_dir(face, uv)
            .unwrap())
    });
    let ll = Image::from_fn(512, 256, |x, y| {
        let d = sh_env::latlong_uv_to_dir(glam::Vec2::new(
            (x as f32 + 0.5) / 512.0,
            (y as f32 + 0.5) / 256.0,
        ));
        sky(d.as_dvec3())
    });
    assert_eq!(
        EnvFormat::guess(strip.width, strip.height),
        Some(EnvFormat::CubeStrip)
    );
    let a = sh_env::project_env(&strip, EnvFormat::CubeStrip, 3);
    let b = sh_env::project_env(&ll, EnvFormat::LatLong, 3);
    let worst = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (*x - *y).abs().max_element())
        .fold(0.0, f64::max);
    eprintln!("cube strip (6×128²) vs lat-long (512×256): max |Δc| = {worst:e}");
    assert!(worst < 1e-3, "{worst}");
    let c = sh_env::project_env(
        &Image::from_fn(6 * 16, 16, |_, _| Vec3::ONE),
        EnvFormat::CubeStrip,
        1,
    );
    assert!(
        (c[0].x - 2.0 * PI.sqrt()).abs() < 1e-12,
        "cube texel solid angles sum to 4π"
    );
}

/// The normalised Phong lobe integrates to one (z₀ = Y₀₀), and its convolution weights
/// √(4π/(2l+1))·zₗ/z₀·Y... fall off like Ramamoorthi's exp(−l²/2n) for large n.
#[test]
fn phong_lobe_zonal_coefficients() {
    let n = 64.0;
    let z = sh::phong_zonal(6, n);
    assert!((z[0] - 0.5 / PI.sqrt()).abs() < 1e-9, "{}", z[0]);
    for l in 1..6 {
        let a = (4.0 * PI / (2 * l + 1) as f64).sqrt() * z[l] / ((4.0 * PI).sqrt() * z[0]);
        let approx = (-((l * l) as f64) / (2.0 * n)).exp();
        assert!((a - approx).abs() < 0.03, "l={l}: {a} vs {approx}");
    }
}

/// McKenzie §5.1.7's sparse table: the non-zero Γᵢⱼₖ over ordered triples per band count.
#[test]
fn triple_product_nonzero_counts() {
    for (bands, count) in [(2, 10), (3, 83), (4, 353), (5, 1158), (6, 2907)] {
        let tp = TripleProduct::new(bands);
        assert_eq!(tp.ordered.len(), count, "{bands} bands");
    }
    // 238 distinct i ≤ j ≤ k triples at 5 bands, the smallest |Γ| ≈ 0.02564.
    let tp = TripleProduct::new(5);
    assert_eq!(tp.entries.len(), 238);
    let smallest = tp.entries.iter().map(|e| e.3.abs()).fold(1.0, f64::min);
    assert!((smallest - 0.02564).abs() < 1e-4, "{smallest}");
}

/// The unit filter (McKenzie §5.1.5): the basis summed over a jittered 100 × 100 sampler with
/// weight 4π/n is √(4π) in the DC term and ≈ 0 elsewhere; masking a light with it is the
/// light Hann-windowed.
#[test]
fn unit_filter_and_masking_without_occluders() {
    let bands = 5;
    let set = DirectionSet::stratified(100 * 100, 7);
    let unit = sh::project(bands, &set, |_| 1.0);
    assert!((unit[0] - (4.0 * PI).sqrt()).abs() < 1e-3, "{}", unit[0]);
    let worst = unit[1..].iter().map(|v| v.abs()).fold(0.0, f64::max);
    assert!(worst < 6e-3, "{worst}");
    let tp = TripleProduct::new(bands);
    let mut rng = Rng::new(9, 0);
    let light: Vec<DVec3> = (0..num_coeffs(bands))
        .map(|_| DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) - 0.5)
        .collect();
    let mut exact_unit = vec![0.0; num_coeffs(bands)];
    exact_unit[0] = (4.0 * PI).sqrt();
    let window = Window::Hann { size: 5.0 };
    let masked = tp.masked_product(&exact_unit, &light, window);
    let mut expected = light.clone();
    window.apply(&mut expected);
    for (m, e) in masked.iter().zip(&expected) {
        assert!((*m - *e).length() < 1e-12, "{m} vs {e}");
    }
    // The plain product with the unit filter is the identity.
    let plain = tp.product(&exact_unit, &light);
    for (p, l) in plain.iter().zip(&light) {
        assert!((*p - *l).length() < 1e-12);
    }
}

//! The GPU techniques `phong`, `phong-shadow-volumes` and `phong-shadow-maps` for `render`,
//! `demo` and `bench frame`.

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use lightlab_core::image::Image;
use lightlab_gpu::GpuContext;
use lightlab_gpu::lights::Attenuation;
use lightlab_gpu::raster::{
    Ambient, FrameTimes, RasterSettings, RenderPath, Renderer, ShadowMethod,
};
use lightlab_scene::{BrdfModel, Scene};

/// The rasterised techniques.
pub const RASTER_TECHNIQUES: [&str; 3] = ["phong", "phong-shadow-volumes", "phong-shadow-maps"];

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum PathArg {
    Forward,
    Deferred,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum VariantArg {
    /// Shadow volumes: z-fail with capped volumes (robust; the default).
    Zfail,
    /// Shadow volumes: z-pass (wrong when the camera is inside a volume).
    Zpass,
    /// Shadow maps: hardware depth comparison (the default).
    Depth,
    /// Shadow maps: Heidrich's linear-depth comparison.
    Linear,
    /// Projected planar shadows on the largest floor plane (Heidrich §6.1).
    Planar,
}

/// Options of the GPU techniques.
#[derive(Args, Clone, Debug)]
pub struct RasterArgs {
    /// Forward (one scene pass per light) or deferred (G-buffer, one screen pass per light).
    #[arg(long, value_enum, default_value_t = PathArg::Forward)]
    pub path: PathArg,
    /// Attenuation of point and spot lights: inverse-square (physical, as the reference) or
    /// Fuchs's atten₁..₄ (fuchs4 = 1 − (d/r)², the thesis's choice).
    #[arg(long, default_value = "fuchs4")]
    pub attenuation: String,
    /// Radius r of the Fuchs attenuation functions (default: the glTF range, else
    /// √(I/0.05 lx)).
    #[arg(long)]
    pub light_radius: Option<f32>,
    /// Shade every material with this model: pbr, lambert, phong or blinn-phong (default: each
    /// material's own). Applies to the reference techniques too.
    #[arg(long)]
    pub brdf: Option<String>,
    /// Shadow variant: zfail|zpass (shadow volumes), depth|linear|planar (shadow maps).
    #[arg(long, value_enum)]
    pub shadow_variant: Option<VariantArg>,
    /// Ambient term: `env` (the scene's environment as 9 SH coefficients), `none`, or a
    /// constant sky radiance `r,g,b`.
    #[arg(long, default_value = "env")]
    pub ambient: String,
    /// Shadow-map resolution (per layer).
    #[arg(long, default_value_t = 2048)]
    pub shadow_size: u32,
    /// PCF kernel half-width in texels (0 = one bilinear comparison).
    #[arg(long, default_value_t = 1)]
    pub pcf: i32,
    /// Supersampling factor per axis (renders ssaa² samples per pixel).
    #[arg(long, default_value_t = 1)]
    pub ssaa: u32,
}

impl Default for RasterArgs {
    fn default() -> Self {
        RasterArgs {
            path: PathArg::Forward,
            attenuation: "fuchs4".into(),
            light_radius: None,
            brdf: None,
            shadow_variant: None,
            ambient: "env".into(),
            shadow_size: 2048,
            pcf: 1,
            ssaa: 1,
        }
    }
}

/// Apply `--brdf` to the scene (before any technique renders it).
pub fn apply_brdf(scene: &mut Scene, brdf: Option<&str>) -> Result<()> {
    if let Some(name) = brdf {
        let m = BrdfModel::parse(name).with_context(|| {
            format!(
                "unknown --brdf '{name}' (known: {})",
                BrdfModel::NAMES.join(", ")
            )
        })?;
        scene.set_brdf(m);
    }
    Ok(())
}

/// The renderer settings of a technique and its options.
pub fn settings(
    technique: &str,
    a: &RasterArgs,
    width: u32,
    height: u32,
    camera: usize,
) -> Result<RasterSettings> {
    let attenuation = Attenuation::parse(&a.attenuation).with_context(|| {
        format!(
            "unknown --attenuation '{}' (known: {})",
            a.attenuation,
            Attenuation::NAMES.join(", ")
        )
    })?;
    let shadows = match (technique, a.shadow_variant) {
        ("phong", None) => ShadowMethod::None,
        ("phong-shadow-volumes", None | Some(VariantArg::Zfail)) => ShadowMethod::VolumesZFail,
        ("phong-shadow-volumes", Some(VariantArg::Zpass)) => ShadowMethod::VolumesZPass,
        ("phong-shadow-maps", None | Some(VariantArg::Depth)) => ShadowMethod::Map,
        ("phong-shadow-maps", Some(VariantArg::Linear)) => ShadowMethod::MapLinear,
        ("phong-shadow-maps", Some(VariantArg::Planar)) => ShadowMethod::Planar,
        (t, Some(v)) => bail!("--shadow-variant {v:?} does not apply to technique '{t}'"),
        (t, None) => bail!("'{t}' is not a GPU technique"),
    };
    let ambient = match a.ambient.as_str() {
        "env" => Ambient::Environment,
        "none" => Ambient::None,
        s => {
            let v: Vec<f32> = s
                .split(',')
                .map(|x| x.trim().parse::<f32>())
                .collect::<Result<_, _>>()
                .ok()
                .filter(|v: &Vec<f32>| v.len() == 3 && v.iter().all(|x| x.is_finite() && *x >= 0.0))
                .with_context(|| {
                    format!("--ambient must be env, none or r,g,b (non-negative), not '{s}'")
                })?;
            Ambient::Constant(glam::Vec3::new(v[0], v[1], v[2]))
        }
    };
    if !(1..=8).contains(&a.ssaa) {
        bail!("--ssaa must be 1 to 8");
    }
    if let Some(r) = a.light_radius
        && !(r.is_finite() && r > 0.0)
    {
        bail!("--light-radius must be a positive number");
    }
    Ok(RasterSettings {
        width: width * a.ssaa,
        height: height * a.ssaa,
        camera,
        path: match a.path {
            PathArg::Forward => RenderPath::Forward,
            PathArg::Deferred => RenderPath::Deferred,
        },
        shadows,
        attenuation,
        light_radius: a.light_radius,
        ambient,
        shadow_size: a.shadow_size,
        pcf_radius: a.pcf,
        ..Default::default()
    })
}

/// Box-filter an image down by `k` per axis.
pub fn downsample(img: &Image, k: u32) -> Image {
    if k == 1 {
        return img.clone();
    }
    let (w, h) = (img.width / k, img.height / k);
    let mut out = Image::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let mut s = glam::Vec3::ZERO;
            for dy in 0..k {
                for dx in 0..k {
                    s += img.data[((y * k + dy) * img.width + x * k + dx) as usize];
                }
            }
            out.data[(y * w + x) as usize] = s / (k * k) as f32;
        }
    }
    out
}

/// Render one image with a GPU technique; also returns the frame's timings.
pub fn render_raster(
    ctx: &GpuContext,
    scene: &Scene,
    technique: &str,
    a: &RasterArgs,
    width: u32,
    height: u32,
    camera: usize,
) -> Result<(Image, FrameTimes)> {
    let s = settings(technique, a, width, height, camera)?;
    let mut r = Renderer::new(ctx, scene, s)?;
    // The first frame compiles pipelines and uploads; time the second.
    r.render(ctx);
    let times = r.render(ctx);
    let img = r.read_hdr(ctx)?;
    Ok((downsample(&img, a.ssaa), times))
}

/// A GPU context, with the CLI's advice when none exists.
pub fn context() -> Result<GpuContext> {
    let ctx = GpuContext::headless()?;
    eprintln!(
        "GPU: {} ({:?}, {})",
        ctx.info.name, ctx.info.backend, ctx.info.driver
    );
    Ok(ctx)
}

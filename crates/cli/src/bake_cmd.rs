//! `lightlab bake`: light-maps (`--method radiosity|path`), SH light-maps (`sh`, alias
//! `prt-textured`, `shl`) and per-vertex transfer (`prt`), written to a folder with a manifest.

use crate::options::BakeArgs;
use crate::progress::with_progress_bar;
use crate::techniques::lightmap::bake_with_progress;
use anyhow::{Result, bail};
use lightlab_bake::{Method, output};
use lightlab_core::object_field::FieldKind;
use lightlab_scene::Scene;
use std::path::{Path, PathBuf};

/// Whether `method` bakes SH light-maps (textured PRT's data are SH light-maps too).
fn is_sh_method(method: &str) -> bool {
    ["sh", "shl", "prt-textured"].contains(&method)
}

/// The k-means compressed copy of SH light-maps (Fuchs §5.6) with `representatives`, if asked.
fn compressed_copy(
    sl: &lightlab_bake::prt::ShLightmaps,
    representatives: Option<usize>,
) -> Result<Option<lightlab_bake::sh_compress::CompressedSh>> {
    let Some(n) = representatives else {
        return Ok(None);
    };
    let c = lightlab_bake::sh_compress::compress(
        sl,
        &lightlab_bake::sh_compress::CompressSettings {
            representatives: n,
            ..Default::default()
        },
    )?;
    let st = &c.stats;
    eprintln!(
        "compressed {} transfer vectors to {} representatives in {} iterations: {:.1}× smaller, \
         rms distance {:.4}",
        st.vectors, st.representatives, st.iterations, st.ratio, st.rms_distance
    );
    Ok(Some(c))
}

/// `lightlab bake --method radiosity|path`.
pub fn run(scene: &Scene, method: &str, out: &Path, args: &BakeArgs, json: bool) -> Result<()> {
    // Before any work: a bake replaces its folder whole, so it must be new, empty or a bake.
    lightlab_bake::folder::check_destination(out)?;
    // Textured PRT's data are SH light-maps (transfer per light-map texel).
    if is_sh_method(method) {
        return bake_sh(scene, out, args, json);
    }
    if method == "prt" {
        return bake_vertex(scene, out, args, json);
    }
    if method == "prt-hierarchical" {
        bail!(
            "prt-hierarchical is not a bake: its filters are found every frame as objects move. \
             Its data are textured PRT's: bake them with `--method sh` (each moving object of an \
             animated scene gets transfer of its own) and render with `--technique \
             prt-hierarchical --baked DIR`"
        );
    }
    if method == "light-field" {
        return bake_light_field(scene, out, args, json);
    }
    if method == "refraction-field" {
        return bake_object_field(scene, FieldKind::Geometry, out, args, json);
    }
    if method == "radiance-field" {
        return bake_object_field(scene, FieldKind::Radiance, out, args, json);
    }
    let Some(m) = Method::parse(method) else {
        bail!(
            "unknown bake method '{method}' (known: {}, sh, prt-textured, shl, prt, light-field, \
             refraction-field, radiance-field)",
            Method::NAMES.join(", ")
        );
    };
    let settings = args.settings(scene, m)?;
    let lm = bake_with_progress(scene, &settings)?;
    let manifest = output::write(
        &lm,
        out,
        &scene.name,
        output::Outputs {
            png: args.png,
            gltf: args.gltf,
        },
    )?;
    let st = &lm.stats;
    eprintln!(
        "baked {} with {}: {} pages, {} texels ({} valid), {:.2} s; wrote {}",
        scene.name,
        m.name(),
        st.pages,
        st.texels,
        st.valid_texels,
        st.seconds_total,
        out.display()
    );
    if let Some(r) = &st.radiosity {
        eprintln!(
            "radiosity: {} shots, unshot energy left {:.3} %{}",
            r.shots,
            r.unshot_fraction * 100.0,
            if r.hit_shot_limit {
                " (stopped by the shot limit)"
            } else {
                ""
            }
        );
    }
    if json {
        println!("{}", serde_json::to_string(&manifest.stats)?);
    }
    Ok(())
}

/// `lightlab bake --method refraction-field|radiance-field`: a glass object's geometry light
/// field (Heidrich §10.2) or a glossy object's radiance light field (§10.1); the folder holds
/// `field.json`, two EXR atlases per slab and the bake manifest.
fn bake_object_field(
    scene: &Scene,
    kind: FieldKind,
    out: &Path,
    args: &BakeArgs,
    json: bool,
) -> Result<()> {
    let t = std::time::Instant::now();
    let (instance, field) =
        crate::techniques::refraction::bake(scene, kind, &args.field, args.bake_seed)?;
    let seconds = t.elapsed().as_secs_f64();
    let method = match kind {
        FieldKind::Geometry => "refraction-field",
        FieldKind::Radiance => "radiance-field",
    };
    let stats = serde_json::json!({
        "method": method,
        "scene": scene.name,
        "object": scene.instances[instance].name,
        "n_uv": field.n_uv,
        "n_st": field.n_st,
        "spp": (kind == FieldKind::Radiance).then_some(args.field.field_spp),
        "gpu_bytes": field.gpu_bytes(),
        "seconds": seconds,
    });
    let manifest = stats.clone();
    lightlab_bake::folder::write(out, |dir| {
        field
            .write(dir)
            .map_err(|e| lightlab_bake::BakeError::Io(e.to_string()))?;
        Ok(manifest)
    })?;
    eprintln!(
        "baked {}'s '{}' into a 6 × {}² × {}² {method} ({:.1} MB) in {seconds:.1} s; wrote {}",
        scene.name,
        scene.instances[instance].name,
        field.n_uv,
        field.n_st,
        field.gpu_bytes() as f64 / 1e6,
        out.display()
    );
    if json {
        println!("{stats}");
    }
    Ok(())
}

/// `lightlab bake --method light-field`: a luminaire's light slab (Heidrich ch. 7), the lamp's
/// real geometry path-traced from each (u,v) grid point through the (s,t) window; the folder
/// holds `slab.json`, one EXR per grid point and the bake manifest.
fn bake_light_field(scene: &Scene, out: &Path, args: &BakeArgs, json: bool) -> Result<()> {
    let s = &args.slab;
    let t = std::time::Instant::now();
    let name = crate::techniques::canned::chosen(scene, s, false)?.remove(0);
    let slab = crate::techniques::canned::bake(scene, &name, s, args.bake_seed)?;
    let seconds = t.elapsed().as_secs_f64();
    let far = match slab.far {
        lightlab_core::light_slab::Far::Plane(d) => serde_json::json!(d),
        lightlab_core::light_slab::Far::Infinity => serde_json::json!("inf"),
    };
    let stats = serde_json::json!({
        "method": "light-field",
        "scene": scene.name,
        "luminaire": name,
        "n_uv": slab.n_uv,
        "n_st": slab.n_st,
        "far": far,
        "far_half": slab.far_half.to_array(),
        "samples": s.slab_samples,
        "gpu_bytes": slab.gpu_bytes(),
        "seconds": seconds,
    });
    let manifest = stats.clone();
    lightlab_bake::folder::write(out, |dir| {
        slab.write(dir)
            .map_err(|e| lightlab_bake::BakeError::Io(e.to_string()))?;
        Ok(manifest)
    })?;
    eprintln!(
        "baked {}'s luminaire '{name}' into a {}×{}×{}×{} light slab ({:.1} MB on the GPU) in {seconds:.1} s; wrote {}",
        scene.name,
        slab.n_uv[0],
        slab.n_uv[1],
        slab.n_st[0],
        slab.n_st[1],
        slab.gpu_bytes() as f64 / 1e6,
        out.display()
    );
    if json {
        println!("{stats}");
    }
    Ok(())
}

/// `lightlab bake --method prt`: per-vertex transfer (Sloan et al. 2002), one binary file per
/// instance and a manifest; `render --technique prt-vertex --baked DIR` reads it.
fn bake_vertex(scene: &Scene, out: &Path, args: &BakeArgs, json: bool) -> Result<()> {
    use lightlab_bake::occlusion_groups::vertex_transfer;
    use lightlab_bake::sh_folder::write_vertex_transfer;
    let s = args.transfer_settings()?;
    eprintln!(
        "baking {} per-vertex transfer: {} bands, {:?}, {} directions per vertex",
        scene.name, s.bands, s.kind, s.samples
    );
    let t = std::time::Instant::now();
    let vt = vertex_transfer(scene, &s)?;
    let seconds = t.elapsed().as_secs_f64();
    let m = write_vertex_transfer(&vt, scene, &s, out, &scene.name, seconds)?;
    let vertices: usize = m.instances.iter().map(|f| f.vertices).sum();
    eprintln!(
        "baked {} in {seconds:.2} s: {vertices} vertices of {} instances; wrote {}",
        scene.name,
        m.instances.len(),
        out.display()
    );
    if json {
        println!(
            "{}",
            serde_json::json!({
                "scene": scene.name, "method": "prt", "bands": s.bands, "seconds": seconds,
                "vertices": vertices, "samples": s.samples, "transfer": args.transfer,
            })
        );
    }
    Ok(())
}

/// `lightlab bake --method sh`: SH light-maps (per-texel diffuse transfer, Fuchs §5).
fn bake_sh(scene: &Scene, out: &Path, args: &BakeArgs, json: bool) -> Result<()> {
    use lightlab_bake::prt::bake_sh_lightmaps;
    use lightlab_bake::sh_folder::write_sh;
    let s = args.transfer_settings()?;
    let kind = s.kind;
    let layout = args.layout(scene);
    eprintln!(
        "baking {} SH light-maps: {} bands, {:?}, {} directions per texel, {} texels/m",
        scene.name,
        s.bands,
        kind,
        s.samples,
        args.density(scene)
    );
    let t = std::time::Instant::now();
    let sl = with_progress_bar(format!("{} sh", scene.name), |progress| {
        bake_sh_lightmaps(scene, &layout, &s, progress)
    })?;
    crate::techniques::lightmap::warn_regenerated(&sl.layout);
    let seconds = t.elapsed().as_secs_f64();
    if let Some(d) = &sl.detail {
        eprintln!(
            "detail from high-poly sources: {} texels projected (mean offset {:.4} m), {} missed \
             the cage (kept on the decimated surface)",
            d.texels - d.misses,
            d.mean_offset,
            d.misses
        );
    }
    if let Some(st) = &sl.shooting {
        eprintln!(
            "shooting: {} shots over {} texels, unshot transfer left {:.2e}{}",
            st.shots,
            st.patches,
            st.unshot_fraction,
            if st.hit_shot_limit {
                " (stopped at the shot limit)"
            } else {
                ""
            }
        );
    }
    let compressed = compressed_copy(&sl, args.compress)?;
    let m = write_sh(&sl, compressed.as_ref(), out, &scene.name, seconds)?;
    eprintln!(
        "baked {} in {seconds:.2} s: {} pages × {} coefficient images; wrote {}",
        scene.name,
        m.pages.len(),
        m.pages.first().map_or(0, |p| p.len()),
        out.display()
    );
    if json {
        println!(
            "{}",
            serde_json::json!({
                "scene": scene.name, "method": "sh", "bands": s.bands, "seconds": seconds,
                "pages": m.pages.len(), "texels_per_metre": args.density(scene),
                "samples": s.samples, "transfer": args.transfer,
                "normal_mapped": s.normal_mapped, "detail": sl.detail, "shooting": sl.shooting,
            })
        );
    }
    Ok(())
}

/// `lightlab bake --shard I/N`: one shard of a path-gathered light-map bake or of an SH
/// light-map bake, as a part folder.
pub fn run_shard(
    scene: &Scene,
    spec: &str,
    method: &str,
    out: &Path,
    args: &BakeArgs,
    shard: &str,
) -> Result<()> {
    use lightlab_bake::shard::{ShBakeSettings, Shard, bake_part, bake_sh_part, write_part};
    lightlab_bake::folder::check_destination(out)?;
    let shard = Shard::parse(shard)?;
    let prefix = format!("{} shard {shard}", scene.name);
    let part = if is_sh_method(method) {
        let settings = ShBakeSettings {
            layout: args.layout(scene),
            transfer: args.transfer_settings()?,
        };
        let mut p = with_progress_bar(prefix, |progress| {
            bake_sh_part(scene, spec, &settings, shard, progress)
        })?;
        p.manifest.compress = args.compress;
        p
    } else {
        let Some(m) = Method::parse(method) else {
            bail!(
                "--shard splits light-map (path) and SH light-map (sh) bakes; '{method}' cannot \
                 be sharded"
            );
        };
        let settings = args.settings(scene, m)?;
        let mut p = with_progress_bar(prefix, |progress| {
            bake_part(scene, spec, &settings, shard, progress)
        })?;
        p.manifest.png = args.png;
        p.manifest.gltf = args.gltf;
        p
    };
    let m = write_part(&part, out)?;
    eprintln!(
        "baked {} shard {shard}: texel slots {}..{} of {}, {:.2} s; wrote {}",
        scene.name,
        m.start,
        m.end,
        m.slots,
        m.seconds,
        out.display()
    );
    Ok(())
}

/// `lightlab merge PARTS... --out DIR`.
pub fn merge(
    parts: &[PathBuf],
    out: &Path,
    scene: Option<&str>,
    load: &crate::options::LoadArgs,
) -> Result<()> {
    use lightlab_bake::shard::{RENDER_PART_FORMAT, part_format, read_part};
    if part_format(&parts[0])? == RENDER_PART_FORMAT {
        return merge_render(parts, out);
    }
    lightlab_bake::folder::check_destination(out)?;
    let parts = parts
        .iter()
        .map(|p| read_part(p).map(|part| (p.clone(), part)))
        .collect::<Result<Vec<_>, _>>()?;
    let m0 = &parts[0].1.manifest;
    let spec = scene.unwrap_or(&m0.scene);
    let scene = crate::load_scene(spec, load)?;
    if m0.kind == "sh" {
        return merge_sh(&scene, &parts, out);
    }
    let lm = with_progress_bar(format!("{} merge", scene.name), |progress| {
        lightlab_bake::shard::merge(&scene, &parts, progress)
    })?;
    let outputs = output::Outputs {
        png: m0.png,
        gltf: m0.gltf,
    };
    output::write(&lm, out, &scene.name, outputs)?;
    eprintln!(
        "merged {} parts of {} ({} pages, {} valid texels); wrote {}",
        parts.len(),
        scene.name,
        lm.stats.pages,
        lm.stats.valid_texels,
        out.display()
    );
    Ok(())
}

/// `lightlab merge` of a sharded render's parts into the image `out` (.exr or .png).
fn merge_render(parts: &[PathBuf], out: &Path) -> Result<()> {
    use lightlab_bake::shard::{merge_render, read_render_part};
    let ext = lightlab_core::image::extension(out);
    if ext != "exr" && ext != "png" {
        bail!("{}: a merged render must be .exr or .png", out.display());
    }
    let parts = parts
        .iter()
        .map(|p| read_render_part(p).map(|part| (p.clone(), part)))
        .collect::<Result<Vec<_>, _>>()?;
    let img = merge_render(&parts)?;
    let r = &parts[0].1.manifest.render;
    let tone = lightlab_core::color::ToneMap::parse(&r.tonemap)
        .ok_or_else(|| anyhow::anyhow!("unknown tone operator '{}' in the parts", r.tonemap))?;
    img.write(
        out,
        lightlab_core::image::LdrSettings {
            exposure: r.exposure,
            tone,
        },
    )?;
    eprintln!(
        "merged {} parts of a {}×{} {} render; wrote {}",
        parts.len(),
        r.width,
        r.height,
        r.technique,
        out.display()
    );
    Ok(())
}

/// The SH half of `lightlab merge`: the light-maps, and their compressed copy when the bake
/// asked for one, written as `bake --method sh` writes them.
fn merge_sh(
    scene: &Scene,
    parts: &[(PathBuf, lightlab_bake::shard::Part)],
    out: &Path,
) -> Result<()> {
    let (sl, seconds) = with_progress_bar(format!("{} merge", scene.name), |progress| {
        lightlab_bake::shard::merge_sh(scene, parts, progress)
    })?;
    let compressed = compressed_copy(&sl, parts[0].1.manifest.compress)?;
    lightlab_bake::sh_folder::write_sh(&sl, compressed.as_ref(), out, &scene.name, seconds)?;
    eprintln!(
        "merged {} parts of {}'s SH light-maps ({} pages); wrote {}",
        parts.len(),
        scene.name,
        sl.pages.len(),
        out.display()
    );
    Ok(())
}

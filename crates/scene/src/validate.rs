//! Scene checks: every problem becomes a [`SceneError`] naming the file and the mesh.
//!
//! Checked: finite positions/normals/UVs/transforms, index bounds, index count a multiple of
//! three, attribute lengths, degenerate triangles (dropped with a warning in
//! [`Scene::warnings`], an error with [`LoadOptions::strict`](crate::LoadOptions)), material
//! and texture references, light parameters, camera field of view.
//!
//! Meshes without normals get flat-shaded normals (the glTF specification requires exactly
//! this), and meshes without UV0 get zeros unless a material texture needs them (then it is an
//! error).

use crate::{LoadOptions, Scene, SceneError, model::LightKind};
use std::path::Path;

/// The largest world coordinate a scene may have [m]: far beyond any real scene, and far
/// enough below f32's range that bounding boxes, their areas and ray intersections stay finite.
pub const MAX_COORDINATE: f32 = 1e15;

/// A triangle is degenerate when twice its area is at most this fraction of its mesh's
/// bounding-box diagonal squared (1e-12: a 10 m mesh's triangles under ≈ 0.05 mm²).
pub const DEGENERATE_AREA: f32 = 1e-12;

/// Validate (and where allowed, repair) a scene loaded from `path`.
pub fn validate(scene: &mut Scene, path: &Path, opts: LoadOptions) -> Result<(), SceneError> {
    let geo = |mesh: &str, problem: String| SceneError::Geometry {
        path: path.into(),
        mesh: mesh.into(),
        problem,
    };
    let content = |what: String, problem: String| SceneError::Content {
        path: path.into(),
        what,
        problem,
    };
    check_materials(scene, path)?;
    if let Some(a) = &scene.animation {
        a.check(scene.instances.len())
            .map_err(|problem| content("animation".into(), problem))?;
    }
    let nmesh = scene.meshes.len();
    for k in 0..nmesh {
        let name = scene.meshes[k].name.clone();
        let warning = check_mesh(scene, k, opts.strict).map_err(|problem| geo(&name, problem))?;
        scene.warnings.extend(warning);
    }
    check_instances(scene, path)?;
    check_lights(scene, path)?;
    for c in &scene.cameras {
        if !(c.yfov > 0.0 && c.yfov < std::f32::consts::PI && c.transform.is_finite()) {
            return Err(content(
                format!("camera '{}'", c.name),
                "field of view or transform invalid".into(),
            ));
        }
    }
    if let Some(env) = &scene.environment {
        env.check()
            .map_err(|m| content("extras.lightlab.environment".into(), m))?;
    }
    if scene.instances.is_empty() {
        return Err(content(
            "scene".into(),
            "contains no triangle meshes".into(),
        ));
    }
    Ok(())
}

/// Check mesh `k` of `scene` (and repair what may be: missing UVs, normals and tangents,
/// degenerate triangles); the problem, or a warning about what was dropped.
fn check_mesh(scene: &mut Scene, k: usize, strict: bool) -> Result<Option<String>, String> {
    let nmesh = scene.meshes.len();
    let (meshes, materials) = (&mut scene.meshes, &scene.materials);
    let mesh = &mut meshes[k];
    let n = mesh.positions.len();
    if mesh.detail_source.is_some_and(|d| d >= nmesh || d == k) {
        return Err("its detail source is itself or a mesh that does not exist".into());
    }
    if mesh.indices.len() % 3 != 0 {
        return Err(format!(
            "{} indices is not a multiple of 3",
            mesh.indices.len()
        ));
    }
    if mesh.indices.is_empty() {
        return Err("has no triangles".into());
    }
    if let Some(bad) = mesh.indices.iter().find(|&&i| i as usize >= n) {
        return Err(format!("index {bad} out of range ({n} vertices)"));
    }
    if mesh.material >= materials.len() {
        return Err("references a material that does not exist".into());
    }
    if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("vertex {i} has a NaN or infinite position"));
    }
    let uv_needed = materials[mesh.material].reads_uv_set(0);
    if mesh.uv0.is_empty() {
        if uv_needed {
            return Err("has no TEXCOORD_0 but its material is textured".into());
        }
        mesh.uv0 = vec![glam::Vec2::ZERO; n];
    }
    if mesh.uv0.len() != n {
        return Err("TEXCOORD_0 length differs from POSITION".into());
    }
    if mesh.uv0.iter().any(|u| !u.is_finite()) {
        return Err("TEXCOORD_0 has NaN or infinite values".into());
    }
    let uv1_needed = materials[mesh.material].reads_uv_set(1);
    if uv1_needed && mesh.uv1.is_none() {
        return Err("has no TEXCOORD_1 but a texture of its material reads it".into());
    }
    if let Some(uv1) = &mesh.uv1
        && (uv1.len() != n || uv1.iter().any(|u| !u.is_finite()))
    {
        return Err("TEXCOORD_1 is inconsistent or not finite".into());
    }
    if !mesh.colors.is_empty()
        && (mesh.colors.len() != n || mesh.colors.iter().any(|c| !c.is_finite()))
    {
        return Err("COLOR_0 is inconsistent or not finite".into());
    }
    let warning = drop_degenerate(mesh, strict)?;
    if mesh.normals.is_empty() {
        mesh.compute_normals();
    }
    if mesh.normals.len() != n {
        return Err("NORMAL length differs from POSITION".into());
    }
    if mesh.normals.iter().any(|v| !v.is_finite()) {
        return Err("NORMAL has NaN or infinite values".into());
    }
    repair_normals(mesh);
    if mesh.tangents.len() != n || mesh.tangents.iter().any(|t| !t.is_finite()) {
        mesh.compute_tangents();
    }
    Ok(warning)
}

/// Light parameters: finite, non-negative, cones and angles in range.
fn check_lights(scene: &Scene, path: &Path) -> Result<(), SceneError> {
    let content = |what: String, problem: String| SceneError::Content {
        path: path.into(),
        what,
        problem,
    };
    for l in &scene.lights {
        let what = format!("light '{}'", l.name);
        if !l.color.is_finite()
            || l.color.min_element() < 0.0
            || !l.intensity.is_finite()
            || l.intensity < 0.0
            || !l.position.is_finite()
            || !l.direction.is_finite()
        {
            return Err(content(
                what,
                "has NaN, infinite or negative colour, intensity, position or direction".into(),
            ));
        }
        if let Some(r) = l.range
            && !(r.is_finite() && r > 0.0)
        {
            return Err(content(
                what,
                format!("range {r} must be a positive number (or absent: no cut-off)"),
            ));
        }
        if let LightKind::Directional { angular_diameter } = l.kind
            && !(0.0..std::f32::consts::PI).contains(&angular_diameter)
        {
            return Err(content(
                what,
                format!("angular diameter {angular_diameter} must be 0 to π radians"),
            ));
        }
        if let LightKind::Spot {
            inner_cone,
            outer_cone,
        } = l.kind
            && !(0.0..=std::f32::consts::FRAC_PI_2).contains(&outer_cone)
                | !(0.0..=outer_cone).contains(&inner_cone)
        {
            return Err(content(what, "spot cone angles out of range".into()));
        }
        if let LightKind::Goniometric { c0, .. } = &l.kind
            && !(c0.is_finite() && c0.cross(l.direction).length() > 1e-3 * l.direction.length())
        {
            return Err(content(
                what,
                "the C0 axis of its photometric profile must be finite and not along its \
                 direction"
                    .into(),
            ));
        }
    }
    Ok(())
}

/// Textures of consistent size; materials whose textures exist, read set 0 or 1, and whose
/// parameters are finite.
fn check_materials(scene: &Scene, path: &Path) -> Result<(), SceneError> {
    let content = |what: String, problem: String| SceneError::Content {
        path: path.into(),
        what,
        problem,
    };
    let ntex = scene.textures.len();
    for t in &scene.textures {
        if t.width == 0 || t.height == 0 || t.texels.len() != t.width as usize * t.height as usize {
            return Err(content(
                format!("texture '{}'", t.name),
                format!("zero-sized or inconsistent ({}×{})", t.width, t.height),
            ));
        }
    }
    for m in &scene.materials {
        if let Some(r) = m.texture_refs().find(|r| r.uv_set > 1) {
            return Err(content(
                format!("material '{}'", m.name),
                format!(
                    "a texture reads TEXCOORD_{}; lightlab reads TEXCOORD_0 and TEXCOORD_1",
                    r.uv_set
                ),
            ));
        }
        if m.texture_refs().any(|r| r.texture >= ntex) {
            return Err(content(
                format!("material '{}'", m.name),
                "references a texture that does not exist".into(),
            ));
        }
        let scalars = [
            m.metallic,
            m.roughness,
            m.specular,
            m.emissive_strength,
            m.transmission,
            m.sway,
            m.specular_transmission,
            m.ior,
        ];
        if !m.base_color.is_finite()
            || !m.emissive.is_finite()
            || scalars.iter().any(|v| !v.is_finite())
        {
            return Err(content(
                format!("material '{}'", m.name),
                "has NaN or infinite parameters".into(),
            ));
        }
    }
    Ok(())
}

/// Drop the mesh's degenerate triangles: a repeated index, or twice the area at most
/// [`DEGENERATE_AREA`] × its bounding-box diagonal² (relative, so a node's uniform scale does
/// not change the verdict). Returns the warning to give; Err with `strict`, or when nothing
/// would be left.
fn drop_degenerate(mesh: &mut crate::Mesh, strict: bool) -> Result<Option<String>, String> {
    let (lo, hi) = mesh
        .positions
        .iter()
        .fold((glam::Vec3::MAX, glam::Vec3::MIN), |(l, h), p| {
            (l.min(*p), h.max(*p))
        });
    // A mesh beyond the coordinate limit is refused later for that, not judged here.
    let extent = (hi - lo).as_dvec3();
    let floor = if extent.max_element() > MAX_COORDINATE as f64 {
        0.0
    } else {
        DEGENERATE_AREA as f64 * extent.length_squared()
    };
    let positions = &mesh.positions;
    let degenerate = |t: &[u32]| {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| positions[i as usize].as_dvec3());
        t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || (b - a).cross(c - a).length() <= floor
    };
    let count = mesh
        .indices
        .chunks_exact(3)
        .filter(|t| degenerate(t))
        .count();
    if count == 0 {
        return Ok(None);
    }
    let total = mesh.indices.len() / 3;
    if strict {
        return Err(format!(
            "{count} of {total} triangles are degenerate (zero area); without --strict they \
             are dropped with a warning"
        ));
    }
    let kept: Vec<u32> = mesh
        .indices
        .chunks_exact(3)
        .filter(|t| !degenerate(t))
        .flatten()
        .copied()
        .collect();
    if kept.is_empty() {
        return Err("all triangles have zero area".into());
    }
    mesh.indices = kept;
    Ok(Some(format!(
        "mesh '{}': dropped {count} of {total} degenerate (zero-area) triangles",
        mesh.name
    )))
}

/// Normals of unit length: a zero-length normal (which shaded as NaN on the GPU) takes the
/// area-weighted normal of its triangles, and the others are normalised.
fn repair_normals(mesh: &mut crate::Mesh) {
    const SHORT: f32 = 1e-12;
    if mesh.normals.iter().all(|n| n.length_squared() > SHORT) {
        mesh.normals.iter_mut().for_each(|n| *n = n.normalize());
        return;
    }
    let authored = std::mem::take(&mut mesh.normals);
    mesh.compute_normals();
    for (n, a) in mesh.normals.iter_mut().zip(authored) {
        if a.length_squared() > SHORT {
            *n = a.normalize();
        }
    }
}

/// Every instance names a mesh, has a finite non-singular transform, and keeps its mesh within
/// ±[`MAX_COORDINATE`] of the origin.
fn check_instances(scene: &Scene, path: &Path) -> Result<(), SceneError> {
    let content = |what: String, problem: String| SceneError::Content {
        path: path.into(),
        what,
        problem,
    };
    for inst in &scene.instances {
        if inst.mesh >= scene.meshes.len() {
            return Err(content(
                format!("node '{}'", inst.name),
                "references a mesh that does not exist".into(),
            ));
        }
        // In f64: an f32 determinant of a huge scale overflows to infinity and passes.
        let det = inst.transform.as_dmat4().determinant();
        if !inst.transform.is_finite() || !det.is_finite() || det.abs() < 1e-20 {
            return Err(content(
                format!("node '{}'", inst.name),
                "has a NaN, infinite or singular transform".into(),
            ));
        }
        let mesh = &scene.meshes[inst.mesh];
        let far = mesh
            .positions
            .iter()
            .map(|p| inst.transform.transform_point3(*p).abs().max_element())
            .fold(
                0.0f32,
                |a, b| if b.is_nan() { f32::INFINITY } else { a.max(b) },
            );
        if far > MAX_COORDINATE {
            return Err(content(
                format!("node '{}'", inst.name),
                format!(
                    "places mesh '{}' up to {far:.3e} m from the origin; world coordinates must stay \
                 within ±{MAX_COORDINATE:.0e} m (beyond that the ray tracer's arithmetic overflows)",
                    mesh.name
                ),
            ));
        }
    }
    Ok(())
}

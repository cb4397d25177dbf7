//! Procedural mesh builders for the built-in scenes. All meshes are indexed, with normals, UV0 and
//! counter-clockwise front faces (glTF).

use crate::model::Mesh;
use glam::{Vec2, Vec3};
use std::f32::consts::{PI, TAU};

/// A quad p0,p1,p2,p3 (counter-clockwise seen from the front), flat shaded, UVs in metres so that
/// textures and light-map densities are uniform.
pub fn quad(name: &str, p: [Vec3; 4], material: usize) -> Mesh {
    let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
    let u_axis = (p[1] - p[0]).normalize();
    let v_axis = n.cross(u_axis);
    let uv = p.map(|q| Vec2::new((q - p[0]).dot(u_axis), (q - p[0]).dot(v_axis)));
    Mesh {
        name: name.into(),
        positions: p.to_vec(),
        normals: vec![n; 4],
        tangents: vec![],
        uv0: uv.to_vec(),
        uv1: None,
        colors: vec![],
        indices: vec![0, 1, 2, 0, 2, 3],
        material,
        detail_source: None,
    }
}

/// A quad whose front faces the point `toward` (the winding is flipped when needed).
pub fn quad_facing(name: &str, mut p: [Vec3; 4], toward: Vec3, material: usize) -> Mesh {
    let n = (p[1] - p[0]).cross(p[2] - p[0]);
    let c = (p[0] + p[1] + p[2] + p[3]) * 0.25;
    if n.dot(toward - c) < 0.0 {
        p.reverse();
    }
    quad(name, p, material)
}

/// Join meshes into one (same material as the first).
pub fn merge(name: &str, parts: &[Mesh]) -> Mesh {
    let mut m = Mesh {
        name: name.into(),
        material: parts.first().map(|p| p.material).unwrap_or(0),
        ..Default::default()
    };
    for p in parts {
        let base = m.positions.len() as u32;
        m.positions.extend(&p.positions);
        m.normals.extend(&p.normals);
        m.uv0.extend(&p.uv0);
        m.indices.extend(p.indices.iter().map(|i| i + base));
    }
    m
}

/// A closed convex hexahedron from its 8 corners: bottom face b0..b3 and top face t0..t3 in the
/// same order around the vertical axis. Faces are flat and oriented outwards.
pub fn hexahedron(name: &str, bottom: [Vec3; 4], top: [Vec3; 4], material: usize) -> Mesh {
    let centre = (bottom.iter().sum::<Vec3>() + top.iter().sum::<Vec3>()) / 8.0;
    let away = |face: [Vec3; 4]| {
        let c = (face[0] + face[1] + face[2] + face[3]) * 0.25;
        c + (c - centre)
    };
    let mut faces = vec![
        quad_facing("top", top, away(top), material),
        quad_facing("bottom", bottom, away(bottom), material),
    ];
    for i in 0..4 {
        let j = (i + 1) % 4;
        let f = [bottom[i], bottom[j], top[j], top[i]];
        faces.push(quad_facing("side", f, away(f), material));
    }
    merge(name, &faces)
}

/// An axis-aligned closed box between `min` and `max`.
pub fn aabb_box(name: &str, min: Vec3, max: Vec3, material: usize) -> Mesh {
    let b = [
        Vec3::new(min.x, min.y, min.z),
        Vec3::new(max.x, min.y, min.z),
        Vec3::new(max.x, min.y, max.z),
        Vec3::new(min.x, min.y, max.z),
    ];
    let t = b.map(|p| Vec3::new(p.x, max.y, p.z));
    hexahedron(name, b, t, material)
}

/// A closed cylinder along +Y from y = 0 to `height`, with flat caps.
pub fn cylinder(name: &str, radius: f32, height: f32, segments: u32, material: usize) -> Mesh {
    let mut m = Mesh {
        name: name.into(),
        material,
        ..Default::default()
    };
    // Side, with a seam duplicate so UVs wrap.
    for i in 0..=segments {
        let a = i as f32 / segments as f32 * TAU;
        let n = Vec3::new(a.cos(), 0.0, -a.sin());
        for (y, v) in [(0.0, 0.0), (height, height)] {
            m.positions.push(n * radius + Vec3::Y * y);
            m.normals.push(n);
            m.uv0
                .push(Vec2::new(i as f32 / segments as f32 * TAU * radius, v));
        }
    }
    for i in 0..segments {
        let (a, b, c, d) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
        m.indices.extend([a, c, b, b, c, d]);
    }
    // Caps.
    for (y, n) in [(0.0, -Vec3::Y), (height, Vec3::Y)] {
        let centre = m.positions.len() as u32;
        m.positions.push(Vec3::Y * y);
        m.normals.push(n);
        m.uv0.push(Vec2::ZERO);
        for i in 0..segments {
            let a = i as f32 / segments as f32 * TAU;
            let p = Vec3::new(a.cos() * radius, y, -a.sin() * radius);
            m.positions.push(p);
            m.normals.push(n);
            m.uv0.push(Vec2::new(p.x, p.z));
        }
        for i in 0..segments {
            let a = centre + 1 + i;
            let b = centre + 1 + (i + 1) % segments;
            if n.y > 0.0 {
                m.indices.extend([centre, a, b]);
            } else {
                m.indices.extend([centre, b, a]);
            }
        }
    }
    m
}

/// A grid over (u, v) ∈ [0,1]² mapped by `f` to a position; normals computed from the surface.
/// `wrap_u`/`wrap_v` join the seams topologically (shared vertices are still duplicated for UVs).
pub fn parametric(
    name: &str,
    nu: u32,
    nv: u32,
    material: usize,
    uv_scale: Vec2,
    f: impl Fn(f32, f32) -> Vec3,
) -> Mesh {
    let mut m = Mesh {
        name: name.into(),
        material,
        ..Default::default()
    };
    for j in 0..=nv {
        for i in 0..=nu {
            let (u, v) = (i as f32 / nu as f32, j as f32 / nv as f32);
            m.positions.push(f(u, v));
            m.uv0.push(Vec2::new(u, v) * uv_scale);
        }
    }
    let row = nu + 1;
    for j in 0..nv {
        for i in 0..nu {
            let a = j * row + i;
            let (b, c, d) = (a + 1, a + row, a + row + 1);
            m.indices.extend([a, c, b, b, c, d]);
        }
    }
    // Drop triangles that collapse (at poles): they have zero area and no use.
    let pos = &m.positions;
    m.indices = m
        .indices
        .chunks_exact(3)
        .filter(|t| {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| pos[i as usize]);
            (b - a).cross(c - a).length_squared() > 1e-24
        })
        .flatten()
        .copied()
        .collect();
    // Analytic-ish normals from central differences of f, robust at poles and seams.
    let eps = 1e-3;
    m.normals = (0..=nv)
        .flat_map(|j| (0..=nu).map(move |i| (i, j)))
        .map(|(i, j)| {
            let (u, v) = (i as f32 / nu as f32, j as f32 / nv as f32);
            let du = f((u + eps).min(1.0), v) - f((u - eps).max(0.0), v);
            let dv = f(u, (v + eps).min(1.0)) - f(u, (v - eps).max(0.0));
            let n = dv.cross(du);
            if n.length_squared() > 1e-20 {
                n.normalize()
            } else {
                // Degenerate at a pole: use the direction from the surface centroid estimate.
                (f(u, v) - f(0.5, 0.5)).normalize_or(Vec3::Y)
            }
        })
        .collect();
    m
}

/// A UV sphere of radius `r` centred at the origin.
pub fn sphere(name: &str, r: f32, nu: u32, nv: u32, material: usize) -> Mesh {
    let mut m = parametric(
        name,
        nu,
        nv,
        material,
        Vec2::new(TAU * r, PI * r),
        |u, v| {
            let (phi, theta) = (u * TAU, v * PI);
            Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            ) * r
        },
    );
    m.normals = m.positions.iter().map(|p| p.normalize()).collect();
    m
}

/// A torus in the XZ plane: major radius `big`, minor radius `small`.
pub fn torus(name: &str, big: f32, small: f32, nu: u32, nv: u32, material: usize) -> Mesh {
    let mut m = parametric(name, nu, nv, material, Vec2::new(8.0, 2.0), |u, v| {
        let (a, b) = (u * TAU, v * TAU);
        let ring = Vec3::new(a.cos(), 0.0, -a.sin());
        // −Y keeps the winding counter-clockwise seen from outside.
        ring * (big + small * b.cos()) - Vec3::Y * small * b.sin()
    });
    m.normals = m
        .positions
        .iter()
        .map(|p| {
            let ring = Vec3::new(p.x, 0.0, p.z).normalize_or(Vec3::X) * big;
            (*p - ring).normalize()
        })
        .collect();
    m
}

/// A (p, q) torus knot tube with radial ridges: a detailed shape with deep self-occlusion.
/// `ridges` sinusoidal grooves run along the tube, with relative depth `ridge_depth`.
///
/// The tube's cross-section follows a rotation-minimising (parallel-transported) frame, with the
/// closing twist of the loop spread evenly along it, so consecutive rings never jump (a frame
/// built from a fixed helper axis flips where the tangent passes the axis and twists the tube
/// through itself). Normals are the mesh's area-weighted normals.
#[allow(clippy::too_many_arguments)]
pub fn ridged_torus_knot(
    name: &str,
    p: f32,
    q: f32,
    scale: f32,
    tube: f32,
    ridges: f32,
    ridge_depth: f32,
    nu: u32,
    nv: u32,
    material: usize,
) -> Mesh {
    let centre = move |t: f32| {
        let a = t * TAU;
        let r = 2.0 + (q * a).cos();
        Vec3::new(r * (p * a).cos(), -(q * a).sin(), r * (p * a).sin()) * scale * 0.33
    };
    let tangent = |t: f32| (centre(t + 1e-4) - centre(t - 1e-4)).normalize();
    // Parallel transport of a normal along the closed curve.
    let mut frames = Vec::with_capacity(nu as usize + 1);
    let t0 = tangent(0.0);
    let helper = if t0.y.abs() < 0.9 { Vec3::Y } else { Vec3::X };
    let mut n = t0.cross(helper).normalize();
    for i in 0..=nu {
        let t = tangent(i as f32 / nu as f32);
        n = (n - t * t.dot(n)).normalize();
        frames.push((t, n));
    }
    // The transported normal comes back rotated by some angle about the start tangent; unwind
    // that twist linearly along the loop.
    let (t_end, n_end) = frames[nu as usize];
    let n_start = frames[0].1;
    let twist = t_end.cross(n_end).dot(n_start).atan2(n_end.dot(n_start));
    let mut m = Mesh {
        name: name.into(),
        material,
        ..Default::default()
    };
    for (i, &(t, n)) in frames.iter().enumerate() {
        let u = i as f32 / nu as f32;
        let c = centre(u);
        let rot = glam::Quat::from_axis_angle(t, twist * u);
        let n1 = rot * n;
        let n2 = t.cross(n1);
        for j in 0..=nv {
            let v = j as f32 / nv as f32;
            let b = v * TAU;
            let radius = tube * (1.0 + ridge_depth * (ridges * b).sin());
            m.positions.push(c + (n1 * b.cos() + n2 * b.sin()) * radius);
            m.uv0.push(Vec2::new(u * 16.0, v * 2.0));
        }
    }
    let row = nv + 1;
    for i in 0..nu {
        for j in 0..nv {
            let a = i * row + j;
            let (b, c, d) = (a + row, a + 1, a + row + 1);
            // Counter-clockwise seen from outside (checked by the signed-volume test).
            m.indices.extend([a, c, b, b, c, d]);
        }
    }
    m.compute_normals();
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Signed volume by the divergence theorem: positive when faces point outwards.
    fn signed_volume(m: &Mesh) -> f32 {
        m.indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    #[test]
    fn closed_builders_face_outwards_with_the_right_volume() {
        let cases = [
            (
                aabb_box("b", Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0), 0),
                6.0,
                1e-5,
            ),
            (cylinder("c", 0.5, 2.0, 256, 0), PI * 0.25 * 2.0, 1e-3),
            (sphere("s", 1.0, 256, 128, 0), 4.0 / 3.0 * PI, 1e-3),
            (
                torus("t", 1.0, 0.25, 256, 128, 0),
                2.0 * PI * PI * 1.0 * 0.0625,
                1e-3,
            ),
        ];
        for (m, v, tol) in cases {
            let got = signed_volume(&m);
            assert!(
                (got - v).abs() < tol * v.max(1.0) * 10.0,
                "{}: volume {got} vs {v}",
                m.name
            );
        }
        let knot = ridged_torus_knot("k", 2.0, 3.0, 1.0, 0.22, 7.0, 0.0, 400, 24, 0);
        assert!(signed_volume(&knot) > 0.0, "knot faces inwards");
        // Vertex normals agree with the winding (area-weighted), and point away from the tube
        // axis: check against the face normal of each triangle.
        for t in knot.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| knot.positions[i as usize]);
            let f = (b - a).cross(c - a).normalize();
            assert!(knot.normals[t[0] as usize].dot(f) > 0.5);
        }
    }
}

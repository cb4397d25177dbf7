//! Two-plane light slabs (Heidrich 1999 §3.3, ch. 7): the outgoing light field of a lamp as
//! radiance samples over rays through a (u,v) window near the lamp and an (s,t) window that
//! is a parallel plane or at infinity.
//!
//! **Geometry.** The (u,v) window is centred at `centre`, spanned by the unit axes `u_axis`,
//! `v_axis` (`half.x`, `half.y` either side); light leaves it along `n = u_axis × v_axis`.
//! The (s,t) window is the plane `distance` further along `n`, spanned by the same axes
//! (`far_half` either side), or at infinity, where (s,t) are the direction's slopes
//! (d·u/d·n, d·v/d·n) within `far_half`. Both windows are cut into cells whose centres hold
//! the samples (`n_uv` × `n_st`); the radiance of a ray is quadrilinear between the centres
//! (Eq 7.2), held at the windows' edge cells, and zero outside the windows.
//!
//! **Storage** (`write`/`read`): a folder with `slab.json` (the geometry, the resolution, the
//! file names) and one EXR per (u,v) sample, `slice-IU-IV.exr`: the image of that grid point
//! over (s,t), s along the width. Written atomically, like the bake folders.
//!
//! **The reference emitter** ([`SlabEmitter`], §7.2.1): the slab as micro lights, one per
//! pair of a (u,v) cell and an (s,t) cell. From a point x, per axis, the part of each (u,v)
//! cell whose rays through x cross a given (s,t) cell is one interval (the projection is
//! separable because the windows are parallel); the visible micro lights are the products of
//! the two axes' intervals, at most (N_u + N_s)(N_v + N_t). One is chosen with probability
//! proportional to its area × a bound of its radiance × the geometric term at its centre,
//! then a point uniformly within it: an unbiased Monte Carlo estimate of Eq 7.3 that spends
//! its samples where the lamp is bright.

use crate::image::{Image, ImageError};
use glam::{Vec2, Vec3};
use std::path::{Path, PathBuf};

/// Where the (s,t) samples lie.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Far {
    /// A plane `distance` metres along the normal from the (u,v) window.
    Plane(f32),
    /// At infinity: (s,t) are direction slopes.
    Infinity,
}

/// A two-plane light slab.
#[derive(Clone, Debug, PartialEq)]
pub struct LightSlab {
    pub centre: Vec3,
    pub u_axis: Vec3,
    pub v_axis: Vec3,
    /// Half the (u,v) window's size in metres.
    pub half: Vec2,
    pub n_uv: [usize; 2],
    pub far: Far,
    /// Half the (s,t) window: metres on the far plane, or slopes at infinity.
    pub far_half: Vec2,
    pub n_st: [usize; 2],
    /// Radiance, `[((iu · N_v + iv) · N_s + is) · N_t + it]`.
    pub radiance: Vec<Vec3>,
    /// The luminaire this slab was baked from (glTF `extras.lightlab.luminaire`): the one it
    /// replaces when it lights a scene. None: it replaces every luminaire.
    pub luminaire: Option<String>,
}

/// Why a slab was refused.
#[derive(Debug, thiserror::Error)]
pub enum SlabError {
    #[error("{0}")]
    Image(#[from] ImageError),
    #[error("{path}: {problem}")]
    Bad { path: PathBuf, problem: String },
}

impl LightSlab {
    /// An all-black slab of the given geometry and resolution.
    #[allow(clippy::too_many_arguments)]
    pub fn black(
        centre: Vec3,
        u_axis: Vec3,
        v_axis: Vec3,
        half: Vec2,
        n_uv: [usize; 2],
        far: Far,
        far_half: Vec2,
        n_st: [usize; 2],
    ) -> LightSlab {
        LightSlab {
            centre,
            u_axis,
            v_axis,
            half,
            n_uv,
            far,
            far_half,
            n_st,
            radiance: vec![Vec3::ZERO; n_uv[0] * n_uv[1] * n_st[0] * n_st[1]],
            luminaire: None,
        }
    }

    pub fn normal(&self) -> Vec3 {
        self.u_axis.cross(self.v_axis)
    }

    /// The area of one (u,v) cell: the weight of a grid point (§7.2.2).
    pub fn cell_area(&self) -> f32 {
        4.0 * self.half.x * self.half.y / (self.n_uv[0] * self.n_uv[1]) as f32
    }

    /// Memory of the radiance samples as the GPU holds them (RGBA16F), in bytes.
    pub fn gpu_bytes(&self) -> usize {
        self.radiance.len() * 8
    }

    /// The centre of (u,v) cell (iu, iv).
    pub fn uv_point(&self, iu: usize, iv: usize) -> Vec3 {
        let a = (iu as f32 + 0.5) / self.n_uv[0] as f32 * 2.0 - 1.0;
        let b = (iv as f32 + 0.5) / self.n_uv[1] as f32 * 2.0 - 1.0;
        self.centre + self.u_axis * (a * self.half.x) + self.v_axis * (b * self.half.y)
    }

    /// The direction (not normalised) of the ray from `p` on the (u,v) plane through the
    /// (s,t) point of window coordinates `st` ∈ [−1, 1]².
    pub fn ray_direction(&self, p: Vec3, st: Vec2) -> Vec3 {
        let (s, t) = (st.x * self.far_half.x, st.y * self.far_half.y);
        match self.far {
            Far::Infinity => self.normal() + self.u_axis * s + self.v_axis * t,
            Far::Plane(d) => {
                self.centre + self.normal() * d + self.u_axis * s + self.v_axis * t - p
            }
        }
    }

    /// The (s,t) window coordinates (−1…1 inside) of the ray leaving `p` on the (u,v)
    /// plane along `d`; None when it does not leave forwards.
    pub fn st_of(&self, p: Vec3, d: Vec3) -> Option<Vec2> {
        let dn = d.dot(self.normal());
        if dn <= 1e-12 {
            return None;
        }
        let (s, t) = match self.far {
            Far::Infinity => (d.dot(self.u_axis) / dn, d.dot(self.v_axis) / dn),
            Far::Plane(dist) => {
                let q = p + d * (dist / dn) - self.centre;
                (q.dot(self.u_axis), q.dot(self.v_axis))
            }
        };
        Some(Vec2::new(s / self.far_half.x, t / self.far_half.y))
    }

    /// The (u,v) window coordinates (−1…1 inside) of a point on the (u,v) plane.
    pub fn uv_of(&self, p: Vec3) -> Vec2 {
        let q = p - self.centre;
        Vec2::new(
            q.dot(self.u_axis) / self.half.x,
            q.dot(self.v_axis) / self.half.y,
        )
    }

    fn index(&self, iu: usize, iv: usize, is: usize, it: usize) -> usize {
        ((iu * self.n_uv[1] + iv) * self.n_st[0] + is) * self.n_st[1] + it
    }

    /// The sample of (u,v) cell (iu, iv) and (s,t) cell (is, it).
    pub fn sample(&self, iu: usize, iv: usize, is: usize, it: usize) -> Vec3 {
        self.radiance[self.index(iu, iv, is, it)]
    }

    pub fn set(&mut self, iu: usize, iv: usize, is: usize, it: usize, l: Vec3) {
        let i = self.index(iu, iv, is, it);
        self.radiance[i] = l;
    }

    /// Radiance of the ray with window coordinates `uv`, `st` (−1…1 inside): quadrilinear
    /// between cell centres (Eq 7.2), zero outside either window.
    pub fn radiance_at(&self, uv: Vec2, st: Vec2) -> Vec3 {
        let inside = |c: Vec2| c.x.abs() <= 1.0 && c.y.abs() <= 1.0;
        if !inside(uv) || !inside(st) {
            return Vec3::ZERO;
        }
        let axis = |c: f32, n: usize| {
            let f = ((c + 1.0) * 0.5 * n as f32 - 0.5).clamp(0.0, (n - 1) as f32);
            let i = (f.floor() as usize).min(n.saturating_sub(2));
            (i, (i + 1).min(n - 1), f - i as f32)
        };
        let ax = [
            axis(uv.x, self.n_uv[0]),
            axis(uv.y, self.n_uv[1]),
            axis(st.x, self.n_st[0]),
            axis(st.y, self.n_st[1]),
        ];
        let mut sum = Vec3::ZERO;
        for corner in 0..16 {
            let pick = |k: usize| {
                let (i0, i1, f) = ax[k];
                if corner >> (3 - k) & 1 == 1 {
                    (i1, f)
                } else {
                    (i0, 1.0 - f)
                }
            };
            let (a, wa) = pick(0);
            let (b, wb) = pick(1);
            let (c, wc) = pick(2);
            let (d, wd) = pick(3);
            let w = wa * wb * wc * wd;
            if w > 0.0 {
                sum += self.sample(a, b, c, d) * w;
            }
        }
        sum
    }

    /// Radiance leaving `p` on the (u,v) plane along `d`.
    pub fn radiance_along(&self, p: Vec3, d: Vec3) -> Vec3 {
        match self.st_of(p, d) {
            Some(st) => self.radiance_at(self.uv_of(p), st),
            None => Vec3::ZERO,
        }
    }

    /// The (s,t) image of (u,v) sample (iu, iv): width N_s, height N_t.
    pub fn slice(&self, iu: usize, iv: usize) -> Image {
        Image::from_fn(self.n_st[0] as u32, self.n_st[1] as u32, |x, y| {
            self.sample(iu, iv, x as usize, y as usize)
        })
    }

    /// Check the geometry and the sample count.
    pub fn check(&self) -> Result<(), String> {
        let unit = |a: Vec3| (a.length() - 1.0).abs() < 1e-3;
        if !(unit(self.u_axis) && unit(self.v_axis) && self.u_axis.dot(self.v_axis).abs() < 1e-3) {
            return Err("the window's axes must be unit length and at right angles".into());
        }
        if !(self.half.min_element() > 0.0 && self.far_half.min_element() > 0.0) {
            return Err("the windows must have positive sizes".into());
        }
        if let Far::Plane(d) = self.far
            && !(d.is_finite() && d > 0.0)
        {
            return Err(format!("the far plane's distance {d} must be positive"));
        }
        if self.n_uv.contains(&0) || self.n_st.contains(&0) {
            return Err("every resolution must be at least 1".into());
        }
        let n = self.n_uv[0] * self.n_uv[1] * self.n_st[0] * self.n_st[1];
        if self.radiance.len() != n {
            return Err(format!("{} samples for {n} rays", self.radiance.len()));
        }
        if self
            .radiance
            .iter()
            .any(|l| !l.is_finite() || l.min_element() < 0.0)
        {
            return Err("radiance must be finite and not negative".into());
        }
        Ok(())
    }

    fn slice_name(iu: usize, iv: usize) -> String {
        format!("slice-{iu}-{iv}.exr")
    }

    /// Write the folder `dir` (the manifest and one EXR per (u,v) sample), atomically.
    pub fn write(&self, dir: &Path) -> Result<(), SlabError> {
        std::fs::create_dir_all(dir).map_err(|e| SlabError::Bad {
            path: dir.into(),
            problem: e.to_string(),
        })?;
        let mut files = vec![];
        for iu in 0..self.n_uv[0] {
            for iv in 0..self.n_uv[1] {
                let p = dir.join(Self::slice_name(iu, iv));
                let bytes = self.slice(iu, iv).encode(&p, Default::default())?;
                files.push((p, bytes));
            }
        }
        let far = match self.far {
            Far::Plane(d) => serde_json::json!({ "plane": d }),
            Far::Infinity => serde_json::json!("infinity"),
        };
        let manifest = serde_json::json!({
            "format": "lightlab light slab 1",
            "centre": self.centre.to_array(),
            "u_axis": self.u_axis.to_array(),
            "v_axis": self.v_axis.to_array(),
            "half": self.half.to_array(),
            "n_uv": self.n_uv,
            "far": far,
            "far_half": self.far_half.to_array(),
            "n_st": self.n_st,
            "luminaire": self.luminaire,
            "slices": "slice-IU-IV.exr: width N_s, height N_t",
        });
        let text = serde_json::to_vec_pretty(&manifest).expect("serialisable");
        files.push((dir.join("slab.json"), text));
        crate::atomic::write_all_atomic(&files)?;
        Ok(())
    }

    /// Read a folder written by [`LightSlab::write`].
    pub fn read(dir: &Path) -> Result<LightSlab, SlabError> {
        let path = dir.join("slab.json");
        let bad = |problem: String| SlabError::Bad {
            path: path.clone(),
            problem,
        };
        let text = std::fs::read_to_string(&path).map_err(|e| bad(e.to_string()))?;
        let m: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| bad(format!("not JSON: {e}")))?;
        let floats = |k: &str, n: usize| -> Result<Vec<f32>, SlabError> {
            let v = m[k]
                .as_array()
                .filter(|a| a.len() == n)
                .ok_or_else(|| bad(format!("'{k}' must be {n} numbers")))?;
            v.iter()
                .map(|x| x.as_f64().map(|f| f as f32))
                .collect::<Option<Vec<f32>>>()
                .ok_or_else(|| bad(format!("'{k}' must be {n} numbers")))
        };
        let counts = |k: &str| -> Result<[usize; 2], SlabError> {
            let v = floats(k, 2)?;
            if v.iter()
                .any(|c| !(1.0..=4096.0).contains(c) || c.fract() != 0.0)
            {
                return Err(bad(format!("'{k}' must be two whole numbers 1…4096")));
            }
            Ok([v[0] as usize, v[1] as usize])
        };
        let far = match &m["far"] {
            serde_json::Value::String(s) if s == "infinity" => Far::Infinity,
            v => Far::Plane(
                v["plane"]
                    .as_f64()
                    .ok_or_else(|| bad("'far' must be \"infinity\" or {\"plane\": d}".into()))?
                    as f32,
            ),
        };
        let v3 = |k: &str| floats(k, 3).map(|v| Vec3::from_slice(&v));
        let v2 = |k: &str| floats(k, 2).map(|v| Vec2::from_slice(&v));
        let mut slab = LightSlab::black(
            v3("centre")?,
            v3("u_axis")?,
            v3("v_axis")?,
            v2("half")?,
            counts("n_uv")?,
            far,
            v2("far_half")?,
            counts("n_st")?,
        );
        slab.luminaire = match &m["luminaire"] {
            serde_json::Value::Null => None,
            v => Some(
                v.as_str()
                    .ok_or_else(|| bad("'luminaire' must be a name or null".into()))?
                    .to_string(),
            ),
        };
        for iu in 0..slab.n_uv[0] {
            for iv in 0..slab.n_uv[1] {
                let p = dir.join(Self::slice_name(iu, iv));
                let img = Image::read(&p)?;
                if (img.width as usize, img.height as usize) != (slab.n_st[0], slab.n_st[1]) {
                    return Err(SlabError::Bad {
                        path: p,
                        problem: format!(
                            "is {}×{}, the manifest says {}×{}",
                            img.width, img.height, slab.n_st[0], slab.n_st[1]
                        ),
                    });
                }
                for (k, l) in img.data.iter().enumerate() {
                    let (is, it) = (k % slab.n_st[0], k / slab.n_st[0]);
                    slab.set(iu, iv, is, it, *l);
                }
            }
        }
        slab.check().map_err(bad)?;
        Ok(slab)
    }
}

/// One axis's visible pairs from a point: (u cell, s cell, the u interval in metres).
fn axis_pairs(
    x_perp: f32,
    z: f32,
    half: f32,
    n: usize,
    far: Far,
    far_half: f32,
    n_far: usize,
) -> Vec<(usize, usize, f32, f32)> {
    // s(a) = alpha + beta·a for the ray from window coordinate a (metres) through x.
    let (alpha, beta) = match far {
        Far::Infinity => (x_perp / z, -1.0 / z),
        Far::Plane(d) => (x_perp * d / z, 1.0 - d / z),
    };
    let du = 2.0 * half / n as f32;
    let ds = 2.0 * far_half / n_far as f32;
    let mut out = vec![];
    for i in 0..n {
        let (a0, a1) = (-half + i as f32 * du, -half + (i + 1) as f32 * du);
        let (s0, s1) = (alpha + beta * a0, alpha + beta * a1);
        let (lo, hi) = (s0.min(s1), s0.max(s1));
        if hi < -far_half || lo > far_half {
            continue;
        }
        let k0 = (((lo + far_half) / ds).floor().max(0.0) as usize).min(n_far - 1);
        let k1 = (((hi + far_half) / ds).floor().max(0.0) as usize).min(n_far - 1);
        for k in k0..=k1 {
            let (b0, b1) = (-far_half + k as f32 * ds, -far_half + (k + 1) as f32 * ds);
            // The a where s(a) lies in [b0, b1], within [a0, a1].
            let (c0, c1) = if beta.abs() < 1e-12 {
                (a0, a1)
            } else {
                let (p, q) = ((b0 - alpha) / beta, (b1 - alpha) / beta);
                (p.min(q).max(a0), p.max(q).min(a1))
            };
            if c1 > c0 {
                out.push((i, k, c0, c1));
            }
        }
    }
    out
}

/// A slab as an emitter of the path tracer (§7.2.1).
#[derive(Clone, Debug)]
pub struct SlabEmitter {
    pub slab: std::sync::Arc<LightSlab>,
    /// Per sample, the largest radiance (max channel) within one sample of it in every
    /// direction: a bound of the quadrilinear radiance over its cell.
    bound: Vec<f32>,
}

/// A point on the (u,v) window and the radiance it sends towards x, divided by the sampling
/// pdf (per unit area) and × cos θ' / r²: the incident radiance's Monte Carlo weight.
#[derive(Clone, Copy, Debug)]
pub struct SlabSample {
    pub point: Vec3,
    /// Irradiance-like estimate: L · cos θ' / (r² · pdf_area); × the receiver's cos θ and
    /// BRDF gives the reflected radiance.
    pub value: Vec3,
}

impl SlabEmitter {
    pub fn new(slab: std::sync::Arc<LightSlab>) -> SlabEmitter {
        let [nu, nv] = slab.n_uv;
        let [ns, nt] = slab.n_st;
        let mut b: Vec<f32> = slab.radiance.iter().map(|l| l.max_element()).collect();
        let dims = [nu, nv, ns, nt];
        let strides = [nv * ns * nt, ns * nt, nt, 1];
        for axis in 0..4 {
            let prev = b.clone();
            for (i, out) in b.iter_mut().enumerate() {
                let c = i / strides[axis] % dims[axis];
                let mut m = prev[i];
                if c > 0 {
                    m = m.max(prev[i - strides[axis]]);
                }
                if c + 1 < dims[axis] {
                    m = m.max(prev[i + strides[axis]]);
                }
                *out = m;
            }
        }
        SlabEmitter { slab, bound: b }
    }

    /// One sample of the light reaching `x` (random numbers `u_pick`, `u`); None where no
    /// lit micro light is visible from x.
    pub fn sample(&self, x: Vec3, u_pick: f32, u: Vec2) -> Option<SlabSample> {
        let s = &*self.slab;
        let n = s.normal();
        let q = x - s.centre;
        let z = q.dot(n);
        if z <= 1e-6 {
            return None;
        }
        let pu = axis_pairs(
            q.dot(s.u_axis),
            z,
            s.half.x,
            s.n_uv[0],
            s.far,
            s.far_half.x,
            s.n_st[0],
        );
        let pv = axis_pairs(
            q.dot(s.v_axis),
            z,
            s.half.y,
            s.n_uv[1],
            s.far,
            s.far_half.y,
            s.n_st[1],
        );
        if pu.is_empty() || pv.is_empty() {
            return None;
        }
        let mut weights = Vec::with_capacity(pu.len() * pv.len());
        let mut total = 0.0f32;
        for a in &pu {
            for b in &pv {
                let bound = self.bound[s.index(a.0, b.0, a.1, b.1)];
                let w = if bound > 0.0 {
                    let area = (a.3 - a.2) * (b.3 - b.2);
                    let c =
                        s.centre + s.u_axis * (0.5 * (a.2 + a.3)) + s.v_axis * (0.5 * (b.2 + b.3));
                    let r = x - c;
                    let r2 = r.length_squared().max(1e-12);
                    // cos θ' / r² at the centre; + a floor so no visible micro light has
                    // zero probability where its radiance could be non-zero.
                    area * bound * (r.dot(n) / r2.sqrt() / r2 + 1e-3 / r2)
                } else {
                    0.0
                };
                total += w;
                weights.push(w);
            }
        }
        if total <= 0.0 {
            return None;
        }
        let mut target = u_pick * total;
        let mut k = weights.len() - 1;
        for (i, w) in weights.iter().enumerate() {
            if target < *w {
                k = i;
                break;
            }
            target -= w;
        }
        let (a, b) = (pu[k / pv.len()], pv[k % pv.len()]);
        let area = (a.3 - a.2) * (b.3 - b.2);
        let pdf_area = weights[k] / total / area;
        let au = a.2 + (a.3 - a.2) * u.x;
        let bv = b.2 + (b.3 - b.2) * u.y;
        let p = s.centre + s.u_axis * au + s.v_axis * bv;
        let r = x - p;
        let r2 = r.length_squared().max(1e-12);
        let dir = r / r2.sqrt();
        let l = s.radiance_along(p, dir);
        let cos_p = dir.dot(n).max(0.0);
        Some(SlabSample {
            point: p,
            value: l * (cos_p / (r2 * pdf_area)),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    fn slab(far: Far) -> LightSlab {
        let mut s = LightSlab::black(
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::X,
            Vec3::Z,
            Vec2::new(0.1, 0.1),
            [4, 4],
            far,
            Vec2::new(1.5, 1.5),
            [16, 16],
        );
        for (i, l) in s.radiance.iter_mut().enumerate() {
            *l = Vec3::splat(1.0 + (i % 7) as f32 * 0.1);
        }
        s
    }

    #[test]
    fn quadrilinear_radiance_hits_the_samples_at_cell_centres() {
        let s = slab(Far::Infinity);
        let c = |i: usize, n: usize| (i as f32 + 0.5) / n as f32 * 2.0 - 1.0;
        for (iu, iv, is, it) in [(0, 0, 0, 0), (1, 2, 5, 9), (3, 3, 15, 15)] {
            let uv = Vec2::new(c(iu, 4), c(iv, 4));
            let st = Vec2::new(c(is, 16), c(it, 16));
            let got = s.radiance_at(uv, st);
            assert!((got - s.sample(iu, iv, is, it)).abs().max_element() < 1e-5);
        }
        assert_eq!(s.radiance_at(Vec2::new(1.01, 0.0), Vec2::ZERO), Vec3::ZERO);
    }

    #[test]
    fn ray_coordinates_round_trip() {
        for far in [Far::Infinity, Far::Plane(2.0)] {
            let s = slab(far);
            let p = s.uv_point(1, 2);
            let st = Vec2::new(0.3, -0.6);
            let d = s.ray_direction(p, st);
            let back = s.st_of(p, d).unwrap();
            assert!((back - st).length() < 1e-5, "{far:?}: {back}");
            assert!((s.uv_of(p) - Vec2::new(-0.25, 0.25)).length() < 1e-5);
        }
    }

    /// The emitter's estimate of the irradiance from a uniform slab equals the uniform
    /// Lambertian window's (Lambert's formula for a square seen head-on) where every ray
    /// through x reaches the (s,t) window.
    #[test]
    fn the_emitter_integrates_a_uniform_slab_exactly_on_average() {
        for far in [Far::Infinity, Far::Plane(0.5)] {
            let mut s = slab(far);
            s.far_half = Vec2::splat(3.0);
            s.radiance.iter_mut().for_each(|l| *l = Vec3::ONE);
            let e = SlabEmitter::new(Arc::new(s.clone()));
            let x = s.centre + s.normal() * 0.4 + Vec3::X * 0.05;
            let mut rng = crate::sampling::Rng::new(3, 0);
            let n = 40000;
            let mut sum = 0.0f64;
            for _ in 0..n {
                if let Some(smp) = e.sample(x, rng.next_f32(), rng.next_vec2()) {
                    let cos = (smp.point - x).normalize().dot(-s.normal()).max(0.0);
                    sum += (smp.value.x * cos) as f64;
                }
            }
            let got = sum / n as f64;
            // Reference: a fine midpoint rule over the window.
            let m = 400;
            let mut want = 0.0f64;
            for i in 0..m {
                for j in 0..m {
                    let a = -0.1 + (i as f32 + 0.5) * 0.2 / m as f32;
                    let b = -0.1 + (j as f32 + 0.5) * 0.2 / m as f32;
                    let p = s.centre + Vec3::X * a + Vec3::Z * b;
                    let r = x - p;
                    let r2 = r.length_squared();
                    let c = r.dot(s.normal()) / r2.sqrt();
                    want += (c * c / r2) as f64 * (0.2 * 0.2 / (m * m) as f32) as f64;
                }
            }
            assert!((got - want).abs() < 0.01 * want, "{far:?}: {got} vs {want}");
        }
    }

    #[test]
    fn a_folder_round_trips() {
        let mut s = slab(Far::Plane(1.5));
        s.luminaire = Some("projector".into());
        let dir = tempfile::tempdir().unwrap();
        s.write(dir.path()).unwrap();
        let back = LightSlab::read(dir.path()).unwrap();
        assert_eq!(back.luminaire.as_deref(), Some("projector"));
        assert_eq!(back.n_uv, s.n_uv);
        assert_eq!(back.far, s.far);
        for (a, b) in s.radiance.iter().zip(&back.radiance) {
            assert!((*a - *b).abs().max_element() < 1e-6);
        }
        std::fs::remove_file(dir.path().join("slice-1-1.exr")).unwrap();
        let e = LightSlab::read(dir.path()).unwrap_err().to_string();
        assert!(e.contains("slice-1-1.exr"), "{e}");
    }
}

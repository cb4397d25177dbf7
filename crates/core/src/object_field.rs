//! Two-plane light fields around one object (Heidrich 1999 ch. 10), of two kinds:
//! - **geometry light fields** (§10.2, after Cohen 1997): for every ray around a refracting
//!   object, where it leaves the object — the direction in which it looks up the environment —
//!   and how much of its light gets through. Geometry only, so the environment can be swapped
//!   without baking again; the seed stores colour-coded environment texture coordinates and
//!   applies the map with pixel textures, here the field stores the exit direction itself and
//!   the shader renormalises the interpolated direction (the extraction's "modern twist");
//! - **radiance light fields** (§10.1): for every ray around a glossy object, the radiance it
//!   leaves the object with — its indirect part, which tolerates the field's blur, while direct
//!   light is shaded per frame (the seed's split).
//!
//! **Parameterisation.** Six two-plane slabs around the object's box, one per axis a and sign
//! of the ray's a-component: a ray belongs to the slab of its dominant axis (ties to the lower
//! axis), so its slope across the box, (d_u, d_v)/│d_a│, lies in [−1, 1]². (u,v) is where the
//! ray crosses the box's central plane ⊥ a, over the box's half extent plus half its depth
//! along a (every ray that meets the box crosses there); (s,t) is the slope (the second plane
//! at infinity, as a light slab with `Far::Infinity`). Samples are cell-centred; lookups are
//! quadrilinear.
//!
//! **Values** ([`FieldKind`]). Geometry: the exit direction (unit) and the throughput (the
//! product of the Fresnel transmittances 1 − F at the refractions, total internal reflections
//! passing all), following the refracted branch at every interface: the path "with two
//! refractions" for a convex object, more where the ray re-enters; a ray that misses keeps its
//! direction with throughput 1. Radiance: RGB and the coverage (1 where the ray meets the
//! object, 0 where it misses, radiance 0).

use crate::image::{Image, ImageError};
use glam::{Vec2, Vec3, Vec4};
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum FieldError {
    #[error("{0}")]
    Image(#[from] ImageError),
    #[error("{path}: {problem}")]
    Bad { path: PathBuf, problem: String },
}

/// What an [`ObjectField`] holds per ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldKind {
    /// Exit direction and throughput (§10.2).
    Geometry,
    /// Outgoing radiance and coverage (§10.1).
    Radiance,
}

impl FieldKind {
    fn name(self) -> &'static str {
        match self {
            FieldKind::Geometry => "geometry",
            FieldKind::Radiance => "radiance",
        }
    }

    /// The folder's two images per slab: the vector part, then the scalar part.
    fn files(self) -> [&'static str; 2] {
        match self {
            FieldKind::Geometry => ["direction", "throughput"],
            FieldKind::Radiance => ["radiance", "coverage"],
        }
    }
}

/// A light field around one object.
#[derive(Clone, Debug)]
pub struct ObjectField {
    pub kind: FieldKind,
    /// The object's box (world space).
    pub min: Vec3,
    pub max: Vec3,
    /// (u,v) samples per side and (s,t) samples per side of every slab.
    pub n_uv: usize,
    pub n_st: usize,
    /// Per slab (2a + [d_a < 0]), per (iv, iu), per (it, is): exit direction and throughput,
    /// or radiance and coverage.
    pub data: Vec<Vec4>,
}

/// The slab of a ray direction and its axes: (slab, a, u axis, v axis).
pub fn slab_of(d: Vec3) -> (usize, usize, usize, usize) {
    let ad = d.abs();
    let a = if ad.x >= ad.y && ad.x >= ad.z {
        0
    } else if ad.y >= ad.z {
        1
    } else {
        2
    };
    (2 * a + (d[a] < 0.0) as usize, a, (a + 1) % 3, (a + 2) % 3)
}

impl ObjectField {
    /// A radiance field of the given box and resolution, black.
    pub fn black(min: Vec3, max: Vec3, n_uv: usize, n_st: usize) -> ObjectField {
        ObjectField {
            kind: FieldKind::Radiance,
            min,
            max,
            n_uv,
            n_st,
            data: vec![Vec4::ZERO; 6 * n_uv * n_uv * n_st * n_st],
        }
    }

    /// A geometry field of the given box and resolution, every ray passing straight through.
    pub fn straight(min: Vec3, max: Vec3, n_uv: usize, n_st: usize) -> ObjectField {
        let mut f = ObjectField {
            kind: FieldKind::Geometry,
            min,
            max,
            n_uv,
            n_st,
            data: vec![Vec4::ZERO; 6 * n_uv * n_uv * n_st * n_st],
        };
        for slab in 0..6 {
            for iu in 0..n_uv {
                for iv in 0..n_uv {
                    for is in 0..n_st {
                        for it in 0..n_st {
                            let (_, d) = f.ray(slab, [iu, iv, is, it]);
                            let i = f.index(slab, [iu, iv, is, it]);
                            f.data[i] = d.extend(1.0);
                        }
                    }
                }
            }
        }
        f
    }

    /// Index of sample (iu, iv, is, it) of `slab` in `data`.
    pub fn index(&self, slab: usize, [iu, iv, is, it]: [usize; 4]) -> usize {
        (((slab * self.n_uv + iv) * self.n_uv + iu) * self.n_st + it) * self.n_st + is
    }

    fn centre_half(&self) -> (Vec3, Vec3) {
        ((self.min + self.max) * 0.5, (self.max - self.min) * 0.5)
    }

    /// The half extents of the (u,v) plane of axis `a` (u axis, v axis).
    fn uv_half(&self, a: usize, ua: usize, va: usize) -> Vec2 {
        let (_, h) = self.centre_half();
        Vec2::new(h[ua] + h[a], h[va] + h[a])
    }

    /// The slab of ray (o, d) and its (u, v, s, t), each in [−1, 1] for rays that meet the
    /// box.
    pub fn coords(&self, o: Vec3, d: Vec3) -> (usize, Vec4) {
        let (slab, a, ua, va) = slab_of(d);
        let (c, _) = self.centre_half();
        let p = o + d * ((c[a] - o[a]) / d[a]);
        let uv = Vec2::new(p[ua] - c[ua], p[va] - c[va]) / self.uv_half(a, ua, va);
        let st = Vec2::new(d[ua], d[va]) / d[a].abs();
        (slab, Vec4::new(uv.x, uv.y, st.x, st.y))
    }

    /// The ray of sample (iu, iv, is, it) of `slab`: a point on the central plane and the unit
    /// direction.
    pub fn ray(&self, slab: usize, [iu, iv, is, it]: [usize; 4]) -> (Vec3, Vec3) {
        let (a, sign) = (slab / 2, if slab.is_multiple_of(2) { 1.0 } else { -1.0 });
        let (ua, va) = ((a + 1) % 3, (a + 2) % 3);
        let centre = |i: usize, n: usize| (i as f32 + 0.5) / n as f32 * 2.0 - 1.0;
        let (c, _) = self.centre_half();
        let half = self.uv_half(a, ua, va);
        let mut p = c;
        p[ua] += centre(iu, self.n_uv) * half.x;
        p[va] += centre(iv, self.n_uv) * half.y;
        let mut d = Vec3::ZERO;
        d[a] = sign;
        d[ua] = centre(is, self.n_st);
        d[va] = centre(it, self.n_st);
        (p, d.normalize())
    }

    /// Quadrilinear lookup of ray (o, d) in a geometry field: the exit direction
    /// (renormalised) and throughput.
    pub fn lookup(&self, o: Vec3, d: Vec3) -> (Vec3, f32) {
        let sum = self.lookup_raw(o, d);
        (sum.truncate().normalize_or(d), sum.w)
    }

    /// Quadrilinear lookup of ray (o, d), as stored (radiance fields: radiance, coverage).
    pub fn lookup_raw(&self, o: Vec3, d: Vec3) -> Vec4 {
        let (slab, c) = self.coords(o, d);
        let axis = |x: f32, n: usize| {
            let f = ((x * 0.5 + 0.5) * n as f32 - 0.5).clamp(0.0, (n - 1) as f32);
            let i0 = (f.floor() as usize).min(n.saturating_sub(2));
            let i1 = (i0 + 1).min(n - 1);
            (i0, i1, f - i0 as f32)
        };
        let (u0, u1, wu) = axis(c.x, self.n_uv);
        let (v0, v1, wv) = axis(c.y, self.n_uv);
        let (s0, s1, ws) = axis(c.z, self.n_st);
        let (t0, t1, wt) = axis(c.w, self.n_st);
        let mut sum = Vec4::ZERO;
        for (iu, fu) in [(u0, 1.0 - wu), (u1, wu)] {
            for (iv, fv) in [(v0, 1.0 - wv), (v1, wv)] {
                for (is, fs) in [(s0, 1.0 - ws), (s1, ws)] {
                    for (it, ft) in [(t0, 1.0 - wt), (t1, wt)] {
                        sum += self.data[self.index(slab, [iu, iv, is, it])] * (fu * fv * fs * ft);
                    }
                }
            }
        }
        sum
    }

    /// Bytes on the GPU (RGBA 16-bit float).
    pub fn gpu_bytes(&self) -> usize {
        self.data.len() * 8
    }

    /// Slab `slab` as an atlas image: (u,v) tiles of n_st × n_st (s,t) texels, `channel`
    /// 0 the direction (RGB), 1 the throughput (grey).
    fn atlas(&self, slab: usize, channel: usize) -> Image {
        let side = (self.n_uv * self.n_st) as u32;
        Image::from_fn(side, side, |x, y| {
            let (x, y) = (x as usize, y as usize);
            let (iu, is, iv, it) = (x / self.n_st, x % self.n_st, y / self.n_st, y % self.n_st);
            let v = self.data[self.index(slab, [iu, iv, is, it])];
            if channel == 0 {
                v.truncate()
            } else {
                Vec3::splat(v.w)
            }
        })
    }

    /// Write the folder `dir`: `field.json` and per slab K `slab-K-direction.exr` and
    /// `slab-K-throughput.exr` (atlases of (u,v) tiles), atomically.
    pub fn write(&self, dir: &Path) -> Result<(), FieldError> {
        std::fs::create_dir_all(dir).map_err(|e| FieldError::Bad {
            path: dir.into(),
            problem: e.to_string(),
        })?;
        let mut files = vec![];
        let [vector, scalar] = self.kind.files();
        for slab in 0..6 {
            for (channel, name) in [(0, vector), (1, scalar)] {
                let p = dir.join(format!("slab-{slab}-{name}.exr"));
                let bytes = self.atlas(slab, channel).encode(&p, Default::default())?;
                files.push((p, bytes));
            }
        }
        let manifest = serde_json::json!({
            "format": "lightlab object light field 1",
            "kind": self.kind.name(),
            "min": self.min.to_array(),
            "max": self.max.to_array(),
            "n_uv": self.n_uv,
            "n_st": self.n_st,
            "slabs": "slab K = 2·axis + (direction negative); atlas of (u,v) tiles of (s,t) texels",
        });
        files.push((
            dir.join("field.json"),
            serde_json::to_vec_pretty(&manifest).expect("serialisable"),
        ));
        crate::atomic::write_all_atomic(&files)?;
        Ok(())
    }

    /// Read a folder written by [`ObjectField::write`].
    pub fn read(dir: &Path) -> Result<ObjectField, FieldError> {
        let path = dir.join("field.json");
        let bad = |problem: String| FieldError::Bad {
            path: path.clone(),
            problem,
        };
        let text = std::fs::read_to_string(&path).map_err(|e| bad(e.to_string()))?;
        let m: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| bad(format!("not JSON: {e}")))?;
        let v3 = |k: &str| -> Result<Vec3, FieldError> {
            let v: Option<Vec<f32>> = m[k]
                .as_array()
                .filter(|a| a.len() == 3)
                .and_then(|a| a.iter().map(|x| x.as_f64().map(|f| f as f32)).collect());
            v.filter(|v| v.iter().all(|x| x.is_finite()))
                .map(|v| Vec3::from_slice(&v))
                .ok_or_else(|| bad(format!("'{k}' must be 3 finite numbers")))
        };
        let count = |k: &str| -> Result<usize, FieldError> {
            m[k].as_u64()
                .filter(|n| (2..=1024).contains(n))
                .map(|n| n as usize)
                .ok_or_else(|| bad(format!("'{k}' must be a whole number 2…1024")))
        };
        let (min, max) = (v3("min")?, v3("max")?);
        if min.cmpge(max).any() {
            return Err(bad("'min' must be below 'max' on every axis".into()));
        }
        let kind = match m["kind"].as_str() {
            Some("geometry") => FieldKind::Geometry,
            Some("radiance") => FieldKind::Radiance,
            _ => return Err(bad("'kind' must be \"geometry\" or \"radiance\"".into())),
        };
        let mut f = ObjectField::black(min, max, count("n_uv")?, count("n_st")?);
        f.kind = kind;
        let [vector, scalar] = kind.files();
        let side = (f.n_uv * f.n_st) as u32;
        for slab in 0..6 {
            let load = |name: &str| -> Result<Image, FieldError> {
                let p = dir.join(format!("slab-{slab}-{name}.exr"));
                let img = Image::read(&p)?;
                if img.width != side || img.height != side {
                    return Err(FieldError::Bad {
                        path: p,
                        problem: format!("must be {side} × {side} (n_uv · n_st)"),
                    });
                }
                Ok(img)
            };
            let (dirs, through) = (load(vector)?, load(scalar)?);
            for y in 0..side {
                for x in 0..side {
                    let (xu, yu) = (x as usize, y as usize);
                    let (iu, is) = (xu / f.n_st, xu % f.n_st);
                    let (iv, it) = (yu / f.n_st, yu % f.n_st);
                    let (d, w) = (dirs.get(x, y), through.get(x, y).x);
                    if !d.is_finite() || !w.is_finite() || !(0.0..=1.0001).contains(&w) {
                        return Err(bad(format!(
                            "slab {slab}: sample ({iu}, {iv}, {is}, {it}) is not finite with \
                             its {scalar} in [0, 1]"
                        )));
                    }
                    let i = f.index(slab, [iu, iv, is, it]);
                    f.data[i] = d.extend(w);
                }
            }
        }
        Ok(f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field() -> ObjectField {
        ObjectField::straight(Vec3::new(-1.0, -0.5, -0.3), Vec3::new(0.6, 0.5, 0.9), 6, 5)
    }

    #[test]
    fn sample_rays_have_their_own_coordinates() {
        let f = field();
        for slab in 0..6 {
            for k in [[0, 0, 0, 0], [5, 2, 4, 1], [3, 5, 2, 2]] {
                let (p, d) = f.ray(slab, k);
                let (s, c) = f.coords(p - 3.0 * d, d);
                assert_eq!(s, slab, "{k:?}");
                let centre = |i: usize, n: usize| (i as f32 + 0.5) / n as f32 * 2.0 - 1.0;
                let want = Vec4::new(
                    centre(k[0], 6),
                    centre(k[1], 6),
                    centre(k[2], 5),
                    centre(k[3], 5),
                );
                assert!(c.abs_diff_eq(want, 1e-5), "{slab} {k:?}: {c} {want}");
            }
        }
    }

    #[test]
    fn every_ray_through_the_box_is_inside_its_slab() {
        let f = field();
        let mut rng = crate::sampling::Rng::new(3, 0);
        for _ in 0..2000 {
            let p =
                f.min + (f.max - f.min) * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let d = crate::sampling::uniform_sphere(rng.next_vec2());
            let (_, c) = f.coords(p - 5.0 * d, d);
            assert!(c.abs().max_element() <= 1.0 + 1e-4, "{p} {d}: {c}");
        }
    }

    #[test]
    fn a_straight_field_looks_up_the_ray_itself() {
        let f = field();
        let mut rng = crate::sampling::Rng::new(4, 0);
        for _ in 0..500 {
            let p =
                f.min + (f.max - f.min) * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let d = crate::sampling::uniform_sphere(rng.next_vec2());
            let (e, w) = f.lookup(p - 2.0 * d, d);
            // Interpolating neighbouring slopes then renormalising: within the cells' spread.
            assert!(e.dot(d) > 0.97, "{d} {e}");
            assert!((w - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn the_folder_round_trips() {
        let mut f = field();
        for (i, v) in f.data.iter_mut().enumerate() {
            *v = Vec3::new(i as f32 % 7.0 - 3.0, 1.0, 0.5)
                .normalize()
                .extend((i % 5) as f32 / 4.0);
        }
        let dir = tempfile::tempdir().unwrap();
        f.write(dir.path()).unwrap();
        let g = ObjectField::read(dir.path()).unwrap();
        assert_eq!(
            (g.n_uv, g.n_st, g.min, g.max),
            (f.n_uv, f.n_st, f.min, f.max)
        );
        for (a, b) in f.data.iter().zip(&g.data) {
            assert!(a.abs_diff_eq(*b, 2e-3), "{a} {b}");
        }
        std::fs::write(dir.path().join("field.json"), "{\"min\": [0, 0]}").unwrap();
        let e = ObjectField::read(dir.path()).unwrap_err().to_string();
        assert!(e.contains("'min'"), "{e}");
    }
}

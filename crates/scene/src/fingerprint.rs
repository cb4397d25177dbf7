//! A 64-bit fingerprint of a scene's content, so that pieces of one job made on different
//! machines (bake shards, reference tiles) can prove they came from the same scene.
//!
//! FNV-1a over the raw bits of every array (positions, indices, texels, the environment's
//! radiance) and over the `Debug` text of the small parts (materials, lights, cameras,
//! transforms). Written here rather than taken from a crate: it must be stable across builds
//! and platforms (std's `DefaultHasher` promises neither), and FNV-1a is a dozen lines.
//! Names and load warnings are left out: renaming a file does not change its light.

use crate::model::{Scene, Texels};
use std::fmt::Write as _;

/// FNV-1a, 64 bits.
struct Fnv(u64);

impl Fnv {
    fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 ^= x as u64;
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }

    fn floats(&mut self, v: impl IntoIterator<Item = f32>) {
        for f in v {
            self.bytes(&f.to_bits().to_le_bytes());
        }
    }

    fn count(&mut self, n: usize) {
        self.bytes(&(n as u64).to_le_bytes());
    }
}

impl std::fmt::Write for Fnv {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.bytes(s.as_bytes());
        Ok(())
    }
}

impl Scene {
    /// The content fingerprint (see the module doc).
    pub fn fingerprint(&self) -> u64 {
        let mut h = Fnv(0xcbf2_9ce4_8422_2325);
        h.count(self.meshes.len());
        for m in &self.meshes {
            h.count(m.positions.len());
            h.floats(m.positions.iter().flat_map(|p| p.to_array()));
            h.floats(m.normals.iter().flat_map(|p| p.to_array()));
            h.floats(m.tangents.iter().flat_map(|p| p.to_array()));
            h.floats(m.uv0.iter().flat_map(|p| p.to_array()));
            h.count(m.uv1.as_ref().map_or(0, |u| u.len() + 1));
            h.floats(m.uv1.iter().flatten().flat_map(|p| p.to_array()));
            h.floats(m.colors.iter().flat_map(|p| p.to_array()));
            h.count(m.indices.len());
            for i in &m.indices {
                h.bytes(&i.to_le_bytes());
            }
            let _ = write!(h, "{}/{:?}", m.material, m.detail_source);
        }
        let _ = write!(h, "{:?}", self.materials);
        for t in &self.textures {
            let _ = write!(h, "{}x{}/{}", t.width, t.height, t.srgb);
            match &t.texels {
                Texels::Rgba8(v) => h.bytes(v),
                Texels::Rgba16(v) => v.iter().for_each(|x| h.bytes(&x.to_le_bytes())),
                Texels::Rgba32F(v) => h.floats(v.iter().flat_map(|p| p.to_array())),
            }
        }
        for i in &self.instances {
            let _ = write!(h, "{}", i.mesh);
            h.floats(i.transform.to_cols_array());
        }
        let _ = write!(h, "{:?}{:?}", self.lights, self.cameras);
        if let Some(e) = &self.environment {
            let _ = write!(h, "{}x{}/{}", e.image.width, e.image.height, e.intensity);
            h.floats(e.image.data.iter().flat_map(|p| p.to_array()));
        }
        h.0
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_fingerprint_sees_content_not_names() {
        let a = crate::builtin::builtin("shadows").unwrap();
        let mut b = a.clone();
        b.name = "renamed".into();
        assert_eq!(a.fingerprint(), b.fingerprint());
        b.meshes[0].positions[0].x += 1e-6;
        assert_ne!(a.fingerprint(), b.fingerprint());
        let mut c = a.clone();
        c.lights[0].intensity *= 2.0;
        assert_ne!(a.fingerprint(), c.fingerprint());
        assert_ne!(
            a.fingerprint(),
            crate::builtin::builtin("room").unwrap().fingerprint()
        );
    }
}

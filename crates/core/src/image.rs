//! Linear RGB float images and their files.
//!
//! Reading: OpenEXR and Radiance HDR are taken as linear; PNG/JPEG are sRGB-decoded to linear.
//! Writing: `.exr` stores linear f32 RGB; `.png` stores tone-mapped 8-bit sRGB. Every write goes to
//! a temporary file in the destination folder that is renamed over the target only when complete,
//! so a failed or interrupted write never leaves a half-written image.

use crate::color::{ToneMap, srgb_decode, to_srgb8};
use glam::Vec3;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Errors of image reading and writing; every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: cannot decode image: {message}")]
    Decode { path: PathBuf, message: String },
    #[error("{path}: cannot encode image: {message}")]
    Encode { path: PathBuf, message: String },
    #[error(
        "{path}: unsupported image format (expected .exr, .hdr or .png{})",
        if *.for_writing { "" } else { ", .jpg" }
    )]
    UnsupportedFormat { path: PathBuf, for_writing: bool },
    #[error("{path}: image has zero size ({width}×{height})")]
    ZeroSized {
        path: PathBuf,
        width: u32,
        height: u32,
    },
    #[error("{path}: image contains NaN or infinite values")]
    NotFinite { path: PathBuf },
    #[error(
        "{path}: not written: {pixels} pixels of the image are NaN or infinite (lightlab would \
         refuse to read it back)"
    )]
    NotFiniteOutput { path: PathBuf, pixels: usize },
}

impl ImageError {
    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            ImageError::Io { path, .. }
            | ImageError::Decode { path, .. }
            | ImageError::Encode { path, .. }
            | ImageError::UnsupportedFormat { path, .. }
            | ImageError::ZeroSized { path, .. }
            | ImageError::NotFinite { path }
            | ImageError::NotFiniteOutput { path, .. } => path,
        }
    }
}

/// A linear Rec.709 RGB image, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub data: Vec<Vec3>,
}

/// How to turn linear radiance into an 8-bit image.
#[derive(Clone, Copy, Debug)]
pub struct LdrSettings {
    pub exposure: f32,
    pub tone: ToneMap,
}

impl Default for LdrSettings {
    fn default() -> Self {
        LdrSettings {
            exposure: 1.0,
            tone: ToneMap::Filmic,
        }
    }
}

impl Image {
    pub fn new(width: u32, height: u32) -> Self {
        Image {
            width,
            height,
            data: vec![Vec3::ZERO; width as usize * height as usize],
        }
    }

    /// Box-filter down by `k` per axis (supersampling resolve); trailing rows and columns that
    /// do not fill a k×k block are dropped.
    pub fn downsample(&self, k: u32) -> Image {
        if k <= 1 {
            return self.clone();
        }
        let (w, h) = (self.width / k, self.height / k);
        let mut out = Image::new(w, h);
        for y in 0..h {
            for x in 0..w {
                let mut s = Vec3::ZERO;
                for dy in 0..k {
                    for dx in 0..k {
                        s += self.data[((y * k + dy) * self.width + x * k + dx) as usize];
                    }
                }
                out.data[(y * w + x) as usize] = s / (k * k) as f32;
            }
        }
        out
    }

    pub fn from_fn(width: u32, height: u32, mut f: impl FnMut(u32, u32) -> Vec3) -> Self {
        let mut img = Image::new(width, height);
        for y in 0..height {
            for x in 0..width {
                img.data[(y * width + x) as usize] = f(x, y);
            }
        }
        img
    }

    #[inline]
    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.data[(y * self.width + x) as usize]
    }

    #[inline]
    pub fn set(&mut self, x: u32, y: u32, v: Vec3) {
        self.data[(y * self.width + x) as usize] = v;
    }

    /// Mean of all pixels.
    pub fn mean(&self) -> Vec3 {
        let s: glam::DVec3 = self.data.iter().map(|v| v.as_dvec3()).sum();
        (s / self.data.len().max(1) as f64).as_vec3()
    }

    /// Read an image file: EXR/HDR (linear) or PNG/JPEG (sRGB, decoded to linear).
    pub fn read(path: &Path) -> Result<Image, ImageError> {
        let ext = extension(path);
        let linear = match ext.as_str() {
            "exr" | "hdr" => true,
            "png" | "jpg" | "jpeg" => false,
            _ => {
                return Err(ImageError::UnsupportedFormat {
                    path: path.into(),
                    for_writing: false,
                });
            }
        };
        let bytes = std::fs::read(path).map_err(|e| ImageError::Io {
            path: path.into(),
            source: e,
        })?;
        Self::decode(path, &bytes, linear)
    }

    /// Decode the bytes of an image file (format from its content; `path` names it in
    /// errors). `linear`: the values are radiometric (EXR, HDR); otherwise sRGB-decoded.
    pub fn decode(path: &Path, bytes: &[u8], linear: bool) -> Result<Image, ImageError> {
        let decoded = image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| ImageError::Io {
                path: path.into(),
                source: e,
            })?
            .decode()
            .map_err(|e| ImageError::Decode {
                path: path.into(),
                message: e.to_string(),
            })?;
        let (w, h) = (decoded.width(), decoded.height());
        if w == 0 || h == 0 {
            return Err(ImageError::ZeroSized {
                path: path.into(),
                width: w,
                height: h,
            });
        }
        let rgb = decoded.to_rgb32f();
        let data: Vec<Vec3> = rgb
            .pixels()
            .map(|p| {
                let v = Vec3::new(p.0[0], p.0[1], p.0[2]);
                if linear {
                    v
                } else {
                    Vec3::new(srgb_decode(v.x), srgb_decode(v.y), srgb_decode(v.z))
                }
            })
            .collect();
        if data.iter().any(|v| !v.is_finite()) {
            return Err(ImageError::NotFinite { path: path.into() });
        }
        Ok(Image {
            width: w,
            height: h,
            data,
        })
    }

    /// EXR, RGB f32, RLE in 64² tiles written in increasing order: the same pixels give the
    /// same bytes (the `image` crate's encoder writes tiles in the order its threads finish,
    /// so two writes of one image differed, and bake folders could not be compared by
    /// checksum).
    fn encode_exr(&self, out: &mut std::io::Cursor<Vec<u8>>) -> exr::error::UnitResult {
        use exr::prelude::*;
        let (w, h) = (self.width as usize, self.height as usize);
        let encoding = Encoding {
            compression: Compression::RLE,
            blocks: Blocks::Tiles(Vec2(64, 64)),
            line_order: LineOrder::Increasing,
        };
        let data = &self.data;
        let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
            let v = data[p.y() * w + p.x()];
            (v.x, v.y, v.z)
        });
        exr::prelude::Image::from_encoded_channels((w, h), encoding, channels)
            .write()
            .to_buffered(out)
    }

    /// 8-bit sRGB bytes (RGB, row-major) after exposure and tone mapping.
    pub fn to_srgb8(&self, ldr: LdrSettings) -> Vec<u8> {
        self.data
            .iter()
            .flat_map(|&c| to_srgb8(c, ldr.exposure, ldr.tone))
            .collect()
    }

    /// Write by extension: `.exr` (linear f32) or `.png` (tone-mapped sRGB), atomically.
    pub fn write(&self, path: &Path, ldr: LdrSettings) -> Result<(), ImageError> {
        let bytes = self.encode(path, ldr)?;
        write_atomic(path, |mut file| {
            file.write_all(&bytes).map_err(|e| ImageError::Io {
                path: path.into(),
                source: e,
            })
        })
    }

    /// The bytes [`Image::write`] would write to `path` (format by its extension). An image
    /// with NaN or infinite pixels is refused.
    pub fn encode(&self, path: &Path, ldr: LdrSettings) -> Result<Vec<u8>, ImageError> {
        let format = match extension(path).as_str() {
            "exr" => image::ImageFormat::OpenExr,
            "png" => image::ImageFormat::Png,
            _ => {
                return Err(ImageError::UnsupportedFormat {
                    path: path.into(),
                    for_writing: true,
                });
            }
        };
        let pixels = self.data.iter().filter(|v| !v.is_finite()).count();
        if pixels > 0 {
            return Err(ImageError::NotFiniteOutput {
                path: path.into(),
                pixels,
            });
        }
        let encode_err = |e: image::ImageError| ImageError::Encode {
            path: path.into(),
            message: e.to_string(),
        };
        if self.data.len() != self.width as usize * self.height as usize {
            return Err(ImageError::Encode {
                path: path.into(),
                message: format!(
                    "{} pixels do not make a {}×{} image",
                    self.data.len(),
                    self.width,
                    self.height
                ),
            });
        }
        let mut out = std::io::Cursor::new(Vec::new());
        if format == image::ImageFormat::OpenExr {
            self.encode_exr(&mut out).map_err(|e| ImageError::Encode {
                path: path.into(),
                message: e.to_string(),
            })?;
            return Ok(out.into_inner());
        }
        let rgb = image::RgbImage::from_raw(self.width, self.height, self.to_srgb8(ldr))
            .expect("the size was checked above");
        image::DynamicImage::ImageRgb8(rgb)
            .write_to(&mut out, format)
            .map_err(encode_err)?;
        Ok(out.into_inner())
    }
}

/// Lower-case extension of a path ("" when none).
pub fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

pub use crate::atomic::write_atomic;

#[cfg(test)]
mod tests {
    use super::*;

    fn gradient() -> Image {
        Image::from_fn(7, 5, |x, y| Vec3::new(x as f32 * 0.3, y as f32 * 0.1, 2.5))
    }

    #[test]
    fn exr_round_trip_is_exact() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.exr");
        let img = gradient();
        img.write(&p, LdrSettings::default()).unwrap();
        let back = Image::read(&p).unwrap();
        assert_eq!(back, img);
        // No temporary files left behind.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    /// An image with NaN or infinite pixels is not written, to EXR or PNG (lightlab refuses to
    /// read such an EXR back, so writing one made a file no later step could use).
    #[test]
    fn images_with_nan_or_infinite_pixels_are_not_written() {
        let dir = tempfile::tempdir().unwrap();
        for (v, ext) in [(f32::NAN, "exr"), (f32::INFINITY, "png")] {
            let mut img = gradient();
            img.data[3].y = v;
            img.data[7] = Vec3::splat(v);
            let p = dir.path().join(format!("bad.{ext}"));
            let e = img.write(&p, LdrSettings::default()).unwrap_err();
            assert!(
                matches!(e, ImageError::NotFiniteOutput { pixels: 2, .. }),
                "{e}"
            );
            assert!(!p.exists());
        }
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn png_round_trip_within_quantisation() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.png");
        let img = Image::from_fn(4, 4, |x, y| Vec3::splat((x + 4 * y) as f32 / 16.0));
        img.write(
            &p,
            LdrSettings {
                exposure: 1.0,
                tone: ToneMap::Clamp,
            },
        )
        .unwrap();
        let back = Image::read(&p).unwrap();
        for (a, b) in img.data.iter().zip(&back.data) {
            assert!((*a - *b).abs().max_element() < 0.01, "{a} {b}");
        }
    }

    #[test]
    fn bad_files_give_named_errors_and_no_output() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.exr");
        std::fs::write(&p, b"not an exr").unwrap();
        let e = Image::read(&p).unwrap_err();
        assert!(e.to_string().contains("bad.exr"), "{e}");
        let e = Image::read(&dir.path().join("missing.png")).unwrap_err();
        assert!(matches!(e, ImageError::Io { .. }));
        let e = gradient()
            .write(&dir.path().join("x.bmp"), LdrSettings::default())
            .unwrap_err();
        assert!(matches!(e, ImageError::UnsupportedFormat { .. }));
        assert!(!dir.path().join("x.bmp").exists());
        // Writing into a folder that does not exist fails and leaves nothing.
        let e = gradient()
            .write(&dir.path().join("no/such/dir.exr"), LdrSettings::default())
            .unwrap_err();
        assert!(matches!(e, ImageError::Io { .. }));
    }
}

//! What a glTF file refers to, read and checked at the boundary before any of it is used:
//! buffers and images by URI, buffer views and accessors within their buffers.
//!
//! - **URIs** (`data:` or a relative path, percent-decoded) resolve inside the glTF file's
//!   folder. Absolute paths, `file:` URIs and paths that climb out of the folder (`../`, or a
//!   symbolic link pointing elsewhere) are refused unless [`LoadOptions::allow_outside_paths`]
//!   is set; other schemes (`http:` …) are always refused, since lightlab reads no network.
//!   Errors name the URI and the path that was tried.
//! - **Buffer views** lie inside their buffer, with a byte stride of 4 to 252 (a multiple of 4)
//!   when given; **accessors** lie inside their view: offset + stride × (count − 1) + element
//!   size ≤ view length, with the stride no smaller than the element. Sparse accessors' index
//!   and value ranges likewise. The `gltf` crate's reader returns nothing for an accessor that
//!   overruns its view (a mesh was silently drawn unindexed) and panics on a stride smaller
//!   than the element, so these are checked here first.
//! - **Images** are decoded with the `image` crate (PNG, JPEG; its default allocation limit
//!   refuses absurd sizes) rather than by `gltf::import_images`, whose URI decoding panics on
//!   invalid percent escapes and whose errors do not say which file failed.
//!
//! Written here rather than taken from the `gltf` crate's importer for those three reasons.

use crate::{LoadOptions, SceneError};
use gltf::accessor::{DataType, Dimensions};
use std::path::{Component, Path, PathBuf};

/// The buffers and decoded images of a document.
pub struct Inputs {
    pub buffers: Vec<gltf::buffer::Data>,
    pub images: Vec<image::DynamicImage>,
}

fn err(path: &Path, message: impl Into<String>) -> SceneError {
    SceneError::Gltf {
        path: path.into(),
        message: message.into(),
    }
}

/// Read every buffer and image of `doc`, checking views and accessors in between.
pub fn read(
    path: &Path,
    doc: &gltf::Document,
    mut blob: Option<Vec<u8>>,
    opts: LoadOptions,
) -> Result<Inputs, SceneError> {
    let mut buffers = vec![];
    for b in doc.buffers() {
        let what = format!("buffer {}", b.index());
        let mut data = match b.source() {
            gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                err(
                    path,
                    format!("{what} refers to the GLB binary chunk, which is missing"),
                )
            })?,
            gltf::buffer::Source::Uri(uri) => read_uri(path, &what, uri, opts)?,
        };
        if data.len() < b.length() {
            return Err(err(
                path,
                format!(
                    "{what} holds {} bytes, its byteLength says {}",
                    data.len(),
                    b.length()
                ),
            ));
        }
        while data.len() % 4 != 0 {
            data.push(0);
        }
        buffers.push(gltf::buffer::Data(data));
    }
    check_views(path, doc, &buffers)?;
    check_accessors(path, doc)?;
    check_attribute_types(path, doc)?;
    let images = doc
        .images()
        .map(|img| read_image(path, &img, &buffers, opts))
        .collect::<Result<_, _>>()?;
    Ok(Inputs { buffers, images })
}

/// The bytes a URI names (see the module documentation).
pub fn read_uri(
    gltf_path: &Path,
    what: &str,
    uri: &str,
    opts: LoadOptions,
) -> Result<Vec<u8>, SceneError> {
    if let Some(rest) = uri.strip_prefix("data:") {
        return data_uri(rest).map_err(|m| err(gltf_path, format!("{what}: data URI: {m}")));
    }
    let file = resolve(gltf_path, uri, opts).map_err(|m| err(gltf_path, format!("{what}: {m}")))?;
    std::fs::read(&file).map_err(|e| {
        err(
            gltf_path,
            format!(
                "{what}: cannot read '{}' (uri '{uri}'): {e}",
                file.display()
            ),
        )
    })
}

/// The file a non-`data:` URI names, inside the glTF's folder unless allowed.
pub fn resolve(gltf_path: &Path, uri: &str, opts: LoadOptions) -> Result<PathBuf, String> {
    let base = lightlab_core::atomic::parent(gltf_path);
    let scheme = uri.find(':').map(|i| &uri[..i]).filter(|s| {
        s.len() > 1
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || "+.-".contains(c))
    });
    let decoded = percent_decode(uri)
        .ok_or_else(|| format!("uri '{uri}' has an invalid percent escape or is not UTF-8"))?;
    let (relative, outside) = match scheme {
        Some(s) if s.eq_ignore_ascii_case("file") => {
            let p = decoded[5..].trim_start_matches("//").to_string();
            (PathBuf::from(p), true)
        }
        Some(s) => {
            return Err(format!(
                "uri '{uri}': the scheme '{s}:' is not supported (lightlab reads files beside \
                 the glTF and data: URIs, never the network)"
            ));
        }
        None => {
            let p = PathBuf::from(&decoded);
            let outside = p.is_absolute() || p.has_root() || climbs_out(&p);
            (p, outside)
        }
    };
    let file = base.join(&relative);
    let escapes = outside || symlinks_out(&base, &file);
    if escapes && !opts.allow_outside_paths {
        return Err(format!(
            "uri '{uri}' names '{}', outside the glTF file's folder '{}'; pass \
             --allow-outside-paths to read it",
            file.display(),
            base.display()
        ));
    }
    Ok(file)
}

/// Whether a relative path climbs above its start (`a/../../b`).
fn climbs_out(p: &Path) -> bool {
    let mut depth = 0i32;
    for c in p.components() {
        match c {
            Component::ParentDir => depth -= 1,
            Component::Normal(_) => depth += 1,
            Component::CurDir => {}
            Component::RootDir | Component::Prefix(_) => return true,
        }
        if depth < 0 {
            return true;
        }
    }
    false
}

/// Whether `file` exists and, with symbolic links resolved, lies outside `base`.
fn symlinks_out(base: &Path, file: &Path) -> bool {
    match (base.canonicalize(), file.canonicalize()) {
        (Ok(b), Ok(f)) => !f.starts_with(b),
        _ => false,
    }
}

fn percent_decode(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = std::str::from_utf8(b.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// `[<mediatype>][;base64],<data>`.
fn data_uri(rest: &str) -> Result<Vec<u8>, String> {
    use base64::Engine;
    let (header, data) = rest
        .split_once(',')
        .ok_or_else(|| "no ',' before the data".to_string())?;
    if header.ends_with(";base64") {
        let clean: String = data.chars().filter(|c| !c.is_ascii_whitespace()).collect();
        base64::engine::general_purpose::STANDARD
            .decode(clean.trim_end_matches('='))
            .or_else(|_| {
                base64::engine::general_purpose::STANDARD_NO_PAD.decode(clean.trim_end_matches('='))
            })
            .map_err(|e| format!("invalid base64: {e}"))
    } else {
        percent_decode(data)
            .map(String::into_bytes)
            .ok_or_else(|| "invalid percent escape".to_string())
    }
}

fn check_views(
    path: &Path,
    doc: &gltf::Document,
    buffers: &[gltf::buffer::Data],
) -> Result<(), SceneError> {
    for v in doc.views() {
        let what = format!("bufferView {}", v.index());
        let len = buffers[v.buffer().index()].0.len();
        let end = v.offset().checked_add(v.length());
        if end.is_none_or(|e| e > len) {
            return Err(err(
                path,
                format!(
                    "{what}: bytes {}..{} run past buffer {} ({len} bytes)",
                    v.offset(),
                    v.offset() as u128 + v.length() as u128,
                    v.buffer().index()
                ),
            ));
        }
        if let Some(s) = v.stride()
            && (!(4..=252).contains(&s) || s % 4 != 0)
        {
            return Err(err(
                path,
                format!("{what}: byteStride {s} is not a multiple of 4 from 4 to 252"),
            ));
        }
    }
    Ok(())
}

/// The size of one element: components × component size, with the glTF column padding of
/// 1- and 2-byte matrices.
fn element_size(dt: DataType, dims: Dimensions) -> usize {
    let c = dt.size();
    let col = |rows: usize| (rows * c).next_multiple_of(4);
    match dims {
        Dimensions::Mat2 => 2 * col(2),
        Dimensions::Mat3 => 3 * col(3),
        Dimensions::Mat4 => 4 * col(4),
        d => d.multiplicity() * c,
    }
}

/// `offset + stride × (count − 1) + element ≤ view length`, in 128-bit arithmetic.
fn fits(offset: usize, stride: usize, count: usize, element: usize, view: usize) -> bool {
    count == 0
        || offset as u128 + stride as u128 * (count as u128 - 1) + element as u128 <= view as u128
}

fn check_accessors(path: &Path, doc: &gltf::Document) -> Result<(), SceneError> {
    for a in doc.accessors() {
        let what = format!("accessor {}", a.index());
        if a.count() == 0 {
            return Err(err(
                path,
                format!("{what} has count 0 (glTF requires at least 1)"),
            ));
        }
        let elem = element_size(a.data_type(), a.dimensions());
        if let Some(view) = a.view() {
            let stride = view.stride().unwrap_or(elem);
            if stride < elem {
                return Err(err(
                    path,
                    format!(
                        "{what}: bufferView {} has byteStride {stride}, smaller than its \
                         {elem}-byte elements",
                        view.index()
                    ),
                ));
            }
            if !fits(a.offset(), stride, a.count(), elem, view.length()) {
                return Err(err(
                    path,
                    format!(
                        "{what}: {} elements of {elem} bytes (stride {stride}) from byte {} run \
                         past bufferView {} ({} bytes)",
                        a.count(),
                        a.offset(),
                        view.index(),
                        view.length()
                    ),
                ));
            }
        }
        if let Some(s) = a.sparse() {
            let n = s.count();
            if n > a.count() {
                return Err(err(
                    path,
                    format!("{what}: {n} sparse values for {} elements", a.count()),
                ));
            }
            let idx = s.indices();
            let isz = match idx.index_type() {
                gltf::accessor::sparse::IndexType::U8 => 1,
                gltf::accessor::sparse::IndexType::U16 => 2,
                gltf::accessor::sparse::IndexType::U32 => 4,
            };
            let vals = s.values();
            if !fits(idx.offset(), isz, n, isz, idx.view().length())
                || !fits(vals.offset(), elem, n, elem, vals.view().length())
            {
                return Err(err(
                    path,
                    format!("{what}: its sparse indices or values run past their bufferView"),
                ));
            }
        }
    }
    Ok(())
}

/// Each attribute lightlab reads has the type glTF prescribes for it (the `gltf` crate's reader
/// assumes so, and panics on a FLOAT VEC2 POSITION or FLOAT indices).
fn check_attribute_types(path: &Path, doc: &gltf::Document) -> Result<(), SceneError> {
    use DataType as T;
    use Dimensions as D;
    use gltf::Semantic as S;
    for mesh in doc.meshes() {
        for prim in mesh.primitives() {
            let what = format!("mesh {} primitive {}", mesh.index(), prim.index());
            let bad = |name: String, a: &gltf::Accessor| {
                err(
                    path,
                    format!(
                        "{what}: {name} is accessor {} of {:?} {:?}, which glTF does not allow for it",
                        a.index(),
                        a.dimensions(),
                        a.data_type()
                    ),
                )
            };
            for (sem, a) in prim.attributes() {
                let (dt, dims) = (a.data_type(), a.dimensions());
                let ok = match &sem {
                    S::Positions | S::Normals => dims == D::Vec3 && dt == T::F32,
                    S::Tangents => dims == D::Vec4 && dt == T::F32,
                    S::TexCoords(_) => dims == D::Vec2 && matches!(dt, T::F32 | T::U8 | T::U16),
                    S::Colors(_) => {
                        matches!(dims, D::Vec3 | D::Vec4) && matches!(dt, T::F32 | T::U8 | T::U16)
                    }
                    _ => true,
                };
                if !ok {
                    return Err(bad(sem.to_string(), &a));
                }
            }
            if let Some(a) = prim.indices()
                && !(a.dimensions() == D::Scalar
                    && matches!(a.data_type(), T::U8 | T::U16 | T::U32))
            {
                return Err(bad("indices".into(), &a));
            }
        }
    }
    Ok(())
}

fn read_image(
    path: &Path,
    img: &gltf::Image,
    buffers: &[gltf::buffer::Data],
    opts: LoadOptions,
) -> Result<image::DynamicImage, SceneError> {
    let what = format!(
        "image {}{}",
        img.index(),
        img.name().map(|n| format!(" ('{n}')")).unwrap_or_default()
    );
    let (bytes, source): (std::borrow::Cow<[u8]>, String) = match img.source() {
        gltf::image::Source::View { view, .. } => {
            let b = &buffers[view.buffer().index()].0;
            (
                b[view.offset()..view.offset() + view.length()].into(),
                format!("bufferView {}", view.index()),
            )
        }
        gltf::image::Source::Uri { uri, .. } => {
            let shown = if uri.starts_with("data:") {
                "a data: URI".to_string()
            } else {
                format!("'{uri}'")
            };
            (read_uri(path, &what, uri, opts)?.into(), shown)
        }
    };
    let format = image::guess_format(&bytes).map_err(|_| {
        err(
            path,
            format!("{what} from {source}: not a PNG or JPEG image"),
        )
    })?;
    if !matches!(format, image::ImageFormat::Png | image::ImageFormat::Jpeg) {
        return Err(err(
            path,
            format!("{what} from {source}: {format:?} images are not supported (PNG or JPEG)"),
        ));
    }
    image::load_from_memory_with_format(&bytes, format)
        .map_err(|e| err(path, format!("{what} from {source}: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uris_resolve_inside_the_folder_unless_allowed() {
        let dir = tempfile::tempdir().unwrap();
        let gltf = dir.path().join("sub/scene.gltf");
        std::fs::create_dir_all(dir.path().join("sub/tex")).unwrap();
        let strict = LoadOptions::default();
        let allow = LoadOptions {
            allow_outside_paths: true,
            ..Default::default()
        };
        for ok in ["a.bin", "tex/a%20b.png", "./tex/../a.bin", "tex/%C3%A9.png"] {
            let p = resolve(&gltf, ok, strict).unwrap_or_else(|e| panic!("{ok}: {e}"));
            assert!(
                p.starts_with(dir.path().join("sub")),
                "{ok} → {}",
                p.display()
            );
        }
        for out in [
            "../a.bin",
            "tex/../../a.bin",
            "/etc/passwd",
            "file:///etc/passwd",
            "file:/etc/x",
        ] {
            let e = resolve(&gltf, out, strict).unwrap_err();
            assert!(
                e.contains("outside") && e.contains("--allow-outside-paths"),
                "{out}: {e}"
            );
            resolve(&gltf, out, allow).unwrap();
        }
        for bad in ["http://example.com/a.bin", "%FF.bin", "%zz.bin", "%4"] {
            assert!(resolve(&gltf, bad, allow).is_err(), "{bad} was accepted");
        }
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink("/etc", dir.path().join("sub/link")).unwrap();
            assert!(
                resolve(&gltf, "link/passwd", strict)
                    .unwrap_err()
                    .contains("outside")
            );
        }
    }

    #[test]
    fn data_uris_decode() {
        assert_eq!(
            data_uri("application/octet-stream;base64,AAEC").unwrap(),
            vec![0, 1, 2]
        );
        assert_eq!(data_uri(";base64,AAE=").unwrap(), vec![0, 1]);
        assert_eq!(data_uri(";base64,AAE").unwrap(), vec![0, 1]);
        assert_eq!(data_uri(",a%20b").unwrap(), b"a b");
        assert!(data_uri(";base64,!!!!").is_err());
        assert!(data_uri("no comma").is_err());
    }

    #[test]
    fn element_sizes_follow_the_column_padding() {
        assert_eq!(element_size(DataType::F32, Dimensions::Vec3), 12);
        assert_eq!(element_size(DataType::U8, Dimensions::Mat2), 8);
        assert_eq!(element_size(DataType::U8, Dimensions::Mat3), 12);
        assert_eq!(element_size(DataType::I16, Dimensions::Mat3), 24);
        assert_eq!(element_size(DataType::F32, Dimensions::Mat4), 64);
        assert!(fits(0, 12, 3, 12, 36) && !fits(0, 12, 3, 12, 35) && fits(99, 4, 0, 4, 0));
        assert!(!fits(usize::MAX, usize::MAX, usize::MAX, 4, usize::MAX));
    }
}

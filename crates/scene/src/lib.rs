//! # lightlab-scene
//!
//! The scene model ([`model`]), the built-in procedural scenes ([`builtin`]), glTF 2.0 import
//! and export ([`gltf_io`]) and the checks that turn bad input into clear errors ([`validate`]).
//!
//! `load("cornell")` gives a built-in scene; `load("path/file.glb")` loads a glTF file.
#![forbid(unsafe_code)]

pub mod animation;
pub mod builtin;
pub mod emitters;
pub mod fingerprint;
mod gltf_anim;
pub mod gltf_input;
pub mod gltf_io;
pub mod model;
pub mod photometry;
pub mod simplify;
pub mod tangents;
pub mod validate;

pub use animation::{Animation, Track};
pub use model::*;

use std::path::{Path, PathBuf};

/// Errors of scene loading, validation and export. Every variant names the file (or the
/// built-in scene) and the problem.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error(
        "unknown scene '{0}': not a built-in scene (see `lightlab scenes`) and not a .gltf/.glb path"
    )]
    UnknownScene(String),
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: invalid glTF: {message}")]
    Gltf { path: PathBuf, message: String },
    #[error(
        "{path}: required extension {extension} is not supported (lightlab supports: {})",
        gltf_io::SUPPORTED_EXTENSIONS.join(", ")
    )]
    UnsupportedExtension { path: PathBuf, extension: String },
    #[error("{path}: mesh '{mesh}': {problem}")]
    Geometry {
        path: PathBuf,
        mesh: String,
        problem: String,
    },
    #[error("{path}: {what}: {problem}")]
    Content {
        path: PathBuf,
        what: String,
        problem: String,
    },
    /// An image error names its file already (it was printed twice).
    #[error("{0}")]
    Image(lightlab_core::image::ImageError, PathBuf),
}

impl From<lightlab_core::image::ImageError> for SceneError {
    fn from(e: lightlab_core::image::ImageError) -> Self {
        let path = e.path().to_path_buf();
        SceneError::Image(e, path)
    }
}

/// Options of scene loading.
#[derive(Clone, Copy, Debug, Default)]
pub struct LoadOptions {
    /// Refuse a file with anything loading would otherwise drop with a warning: degenerate
    /// triangles, primitives that are not triangles.
    pub strict: bool,
    /// Let buffer, image and environment URIs name files outside the glTF file's folder
    /// (absolute paths, `file:` URIs, `../`); refused by default (see [`gltf_input`]).
    pub allow_outside_paths: bool,
}

/// Load a built-in scene by name, or a `.gltf`/`.glb` file by path, and validate it.
pub fn load(spec: &str, opts: LoadOptions) -> Result<Scene, SceneError> {
    if let Some(s) = builtin::builtin(spec) {
        return Ok(s);
    }
    let path = Path::new(spec);
    let ext = lightlab_core::image::extension(path);
    if ext == "gltf" || ext == "glb" {
        return gltf_io::import(path, opts);
    }
    Err(SceneError::UnknownScene(spec.into()))
}

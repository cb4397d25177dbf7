//! # lightlab-core
//!
//! The GPU-free foundation every other lightlab crate leans on:
//!
//! - [`brdf`]: BRDF models (Lambert, Phong, Blinn-Phong, Lafortune, Torrance–Sparrow, Ward,
//!   Banks) behind one interface, and the factorised Torrance–Sparrow tables;
//! - [`color`]: sRGB transfer, luminance, tone operators for PNG output;
//! - [`sampling`]: a counter-based random number generator (deterministic whatever the thread
//!   count), low-discrepancy sequences, and the direction/area samplers of the path tracer;
//! - [`image`]: a linear RGB float image with EXR/HDR/PNG reading and *atomic* writing
//!   (temporary file, then rename: no half-written output on error);
//! - [`metrics`]: RMSE, relMSE and FLIP between two images;
//! - [`names`]: the spelling of option enums ([`named_enum!`]: parse, print, list);
//! - [`sh`]: real spherical harmonics (the basis convention lives there), projection, rotation,
//!   convolution, windows, triple products; [`sh_env`]: projection of environment maps;
//! - [`quadrature`]: direction sets (exact Gauss and stratified);
//! - [`lpv`]: light propagation volumes on the CPU (Kaplanyan's 6-face scheme with geometry
//!   volume, and the WPI report's 18-neighbour scheme), the reference of the GPU passes;
//! - [`wind`]: the wind sway of foliage shared by every pass and the CPU;
//! - [`envmap`]: prefiltered environment maps (mirror, Phong and GGX lobes) and the GGX
//!   split-sum table, for the GPU's specular environment term;
//! - [`param`]: sphere parameterisations (lat-long, angular, sphere map, octahedral, dual
//!   paraboloid, cube) with per-texel solid angles.
//!
//! Conventions (docs/ARCHITECTURE.md): right-handed, Y-up, metres; linear Rec.709 RGB radiometry.
#![forbid(unsafe_code)]

pub mod atomic;
pub mod brdf;
pub mod color;
pub mod envmap;
pub mod fuzz;
pub mod image;
pub mod lens;
pub mod light_slab;
pub mod lpv;
pub mod metrics;
pub mod names;
pub mod object_field;
pub mod param;
pub mod quadrature;
pub mod sampling;
pub mod sh;
pub mod sh_env;
pub mod sky;
pub mod wind;

pub use glam;

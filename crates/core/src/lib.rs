//! # lightlab-core
//!
//! The GPU-free foundation every other lightlab crate leans on:
//!
//! - [`color`]: sRGB transfer, luminance, tone operators for PNG output;
//! - [`sampling`]: a counter-based random number generator (deterministic whatever the thread
//!   count), low-discrepancy sequences, and the direction/area samplers of the path tracer;
//! - [`image`]: a linear RGB float image with EXR/HDR/PNG reading and *atomic* writing
//!   (temporary file, then rename: no half-written output on error);
//! - [`metrics`]: RMSE, relMSE and FLIP between two images.
//!
//! Conventions (DESIGN.md): right-handed, Y-up, metres; linear Rec.709 RGB radiometry.
#![forbid(unsafe_code)]

pub mod color;
pub mod image;
pub mod metrics;
pub mod sampling;

pub use glam;

//! # lightlab-trace
//!
//! CPU ray casting ([`accel`]) and the reference path tracer ([`render`]) that every real-time
//! technique of lightlab is measured against. `reference` renders all light
//! (`max_depth` bounces), `direct` only direct light (`max_depth = 1`).
#![forbid(unsafe_code)]

pub mod accel;
pub mod bsdf;
pub mod bvh8;
pub mod bvh_settings;
pub mod lights;
pub mod luminaire;
pub mod radiance_field;
pub mod refraction_field;
pub mod render;

pub use accel::Accel;
pub use bvh_settings::BvhSettings;
pub use render::{LightUse, PathTracer, RenderError, RenderSettings, WindowEmitter};

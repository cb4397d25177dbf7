//! GPU-visible structs, defined once on the Rust side (`bytemuck::Pod`, explicit padding) and
//! checked against naga's layout of `shaders/common.wgsl` (see `layout::check_struct` and the
//! test below).

use bytemuck::{Pod, Zeroable};

/// Per-frame constants (WGSL `FrameUniforms`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FrameUniforms {
    pub view_proj: [[f32; 4]; 4],
    pub inv_view_proj: [[f32; 4]; 4],
    pub camera_pos: [f32; 3],
    pub exposure: f32,
    pub viewport: [f32; 2],
    pub light_count: u32,
    pub frame: u32,
}

/// One light (WGSL `GpuLight`). `kind`: 0 point, 1 spot, 2 directional.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuLight {
    pub position: [f32; 3],
    pub kind: u32,
    pub direction: [f32; 3],
    pub range: f32,
    pub color: [f32; 3],
    pub intensity: f32,
    pub cos_inner: f32,
    pub cos_outer: f32,
    pub angular_radius: f32,
    /// Which of Fuchs's attenuation functions (§4.1) the light uses.
    pub attenuation: u32,
}

/// The WGSL source that declares these structs.
pub const COMMON_WGSL: &str = include_str!("shaders/common.wgsl");

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::check_struct;
    use crate::rust_layout;

    #[test]
    fn rust_structs_match_the_wgsl_layout() {
        check_struct(
            COMMON_WGSL,
            "FrameUniforms",
            &rust_layout!(
                FrameUniforms,
                view_proj,
                inv_view_proj,
                camera_pos,
                exposure,
                viewport,
                light_count,
                frame
            ),
        )
        .unwrap();
        check_struct(
            COMMON_WGSL,
            "GpuLight",
            &rust_layout!(
                GpuLight,
                position,
                kind,
                direction,
                range,
                color,
                intensity,
                cos_inner,
                cos_outer,
                angular_radius,
                attenuation
            ),
        )
        .unwrap();
    }
}

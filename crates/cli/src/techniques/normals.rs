//! The `normals` debug technique: the shading normals (after normal maps, turned to the viewer)
//! as colours, n/2 + ½, unlit and without background, to check the geometry, its normals and
//! normal maps as every GPU technique sees them.

use super::Request;
use anyhow::Result;
use lightlab_gpu::GpuContext;
use lightlab_gpu::raster::Renderer;

pub fn renderer(ctx: &GpuContext, req: &Request) -> Result<Renderer> {
    let a = &req.args.raster;
    let shadows = req.technique.shadows(a.shadow_variant)?;
    let mut s = a.settings(shadows, req.width, req.height, req.camera)?;
    s.background = false;
    Ok(Renderer::normals(ctx, req.scene, s)?)
}

//! WGSL validation and layout checks with naga (wgpu's own shader compiler).
//!
//! Every WGSL file is parsed and validated in `cargo test` (no GPU needed), and every Rust struct
//! that is uploaded to the GPU is compared, field by field, with naga's layout of the WGSL struct
//! of the same name: offsets and total size must agree, so a forgotten padding field fails a test
//! instead of corrupting a frame.

use wgpu::naga;

/// The layout of a Rust struct: its size and (field name, offset) pairs.
#[derive(Clone, Debug)]
pub struct RustLayout {
    pub size: usize,
    pub fields: Vec<(&'static str, usize)>,
}

/// `rust_layout!(Type, field, …)`: the [`RustLayout`] of a `#[repr(C)]` struct.
#[macro_export]
macro_rules! rust_layout {
    ($t:ty, $($f:ident),+ $(,)?) => {
        $crate::layout::RustLayout {
            size: ::std::mem::size_of::<$t>(),
            fields: vec![$((stringify!($f), ::std::mem::offset_of!($t, $f))),+],
        }
    };
}

/// WGSL that naga rejects, or a struct whose layout differs from its Rust twin (the message
/// says where).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct LayoutError(pub String);

/// Parse and validate a WGSL module.
pub fn validate_wgsl(source: &str) -> Result<naga::Module, LayoutError> {
    wgsl_module(source).map_err(LayoutError)
}

fn wgsl_module(source: &str) -> Result<naga::Module, String> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| e.emit_to_string(source))?;
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .map_err(|e| format!("{e:?}"))?;
    Ok(module)
}

/// Compare a Rust struct with the WGSL struct `name` declared in `source`.
pub fn check_struct(source: &str, name: &str, rust: &RustLayout) -> Result<(), LayoutError> {
    struct_problem(source, name, rust).map_err(LayoutError)
}

fn struct_problem(source: &str, name: &str, rust: &RustLayout) -> Result<(), String> {
    let module = wgsl_module(source)?;
    let (members, span) = module
        .types
        .iter()
        .find_map(|(_, ty)| match (&ty.name, &ty.inner) {
            (Some(n), naga::TypeInner::Struct { members, span }) if n == name => {
                Some((members.clone(), *span))
            }
            _ => None,
        })
        .ok_or_else(|| format!("no struct {name} in the WGSL source"))?;
    if span as usize != rust.size {
        return Err(format!(
            "{name}: WGSL size {span} ≠ Rust size {}",
            rust.size
        ));
    }
    if members.len() != rust.fields.len() {
        return Err(format!(
            "{name}: WGSL has {} fields, Rust {}",
            members.len(),
            rust.fields.len()
        ));
    }
    for (m, (rname, roff)) in members.iter().zip(&rust.fields) {
        let wname = m.name.as_deref().unwrap_or("?");
        if wname != *rname || m.offset as usize != *roff {
            return Err(format!(
                "{name}.{wname}: WGSL offset {} ≠ Rust {rname} at {roff}",
                m.offset
            ));
        }
    }
    Ok(())
}

/// Every WGSL file of the crate, for validation.
pub fn all_shaders() -> Vec<(String, &'static str)> {
    let rasters = crate::raster::SourceKind::ALL.map(|k| {
        (
            format!("common.wgsl + raster.wgsl + ambient source {k:?}"),
            crate::raster::shader_source(k),
        )
    });
    let others = [
        ("common.wgsl", crate::uniforms::COMMON_WGSL),
        (
            "common.wgsl + prt_relit.wgsl",
            crate::prt::RELIT_SOURCE.as_str(),
        ),
        (
            "common.wgsl + material.wgsl + lpv.wgsl",
            crate::lpv::LPV_SOURCE.as_str(),
        ),
    ];
    others
        .into_iter()
        .map(|(n, s)| (n.to_string(), s))
        .chain(rasters)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_wgsl_file_validates() {
        for (name, src) in all_shaders() {
            validate_wgsl(src).unwrap_or_else(|e| panic!("{name}: {e}"));
        }
    }

    #[test]
    fn a_layout_mismatch_is_reported() {
        #[repr(C)]
        struct Bad {
            a: [f32; 3],
            b: [f32; 3],
        }
        let wgsl =
            "struct Bad { a: vec3<f32>, b: vec3<f32> }\n@group(0) @binding(0) var<uniform> u: Bad;";
        // vec3 aligns to 16 bytes in WGSL: b sits at 16, not 12.
        let e = check_struct(wgsl, "Bad", &rust_layout!(Bad, a, b)).unwrap_err();
        assert!(e.0.contains("Bad"), "{e}");
        assert!(validate_wgsl("fn broken( {").is_err());
    }
}

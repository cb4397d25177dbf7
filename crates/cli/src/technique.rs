//! The technique registry: every technique `render`, `demo`, `bench frame` and `view` know,
//! one line each in [`REGISTRY`], with its family (which decides the renderer the factory in
//! `techniques` builds and the options it reads) and what it is.

use crate::options::{DebugView, TechniqueArgs, VariantArg};
use anyhow::{Result, bail};
use lightlab_gpu::raster::ShadowMethod;

/// A technique of `lightlab render --technique`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Technique {
    Reference,
    Direct,
    Phong,
    PhongShadowVolumes,
    PhongShadowMaps,
    CannedLight,
    LightfieldRefraction,
    LightfieldGlossy,
    Lightmap,
    LightmapPhong,
    PrtVertex,
    PrtTextured,
    PrtHierarchical,
    Shl,
    ShlCompressed,
    ShlNormalmapped,
    Lpv,
    LpvFaithful,
    Normals,
}

/// What builds a technique's image, and so which options it reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Family {
    /// The CPU path tracer (`reference`, `direct`).
    PathTraced,
    /// The GPU's direct light with shadows and the environment's SH ambient.
    Phong,
    /// Light-maps baked on the CPU (`--baked`, or baked first).
    Lightmap,
    /// SH transfer baked on the CPU, lit by the scene's lights projected on SH each frame.
    Sh,
    /// Shadow-mapped direct light plus a light propagation volume, every frame.
    Lpv,
    /// Views of the geometry for debugging, not lighting.
    Debug,
}

impl Family {
    /// How the family's images get the sky's diffuse light (the environment, or a constant
    /// ambient), for the report and `--help` (issue 22).
    pub fn sky_term(self) -> String {
        match self {
            Family::PathTraced => "traced: every sky ray is occluded exactly".into(),
            Family::Phong => format!(
                "SH irradiance occluded through {} shadow-mapped sky directions (--sky-occlusion); \
                 its glossy reflection unoccluded",
                lightlab_gpu::raster::SKY_OCCLUSION_DIRECTIONS
            ),
            Family::Lightmap => "baked into the light-map, occluded and bounced by the bake".into(),
            Family::Sh => "SH transfer: shadowed (and inter-reflected) by the bake".into(),
            Family::Lpv => {
                "SH irradiance occluded as the Phong techniques'; the volume adds the bounces of \
                 the lights and of the sky (lpv: 16 directional views, --lpv-sky-lights; \
                 multiple bounces, --lpv-bounces), from the directions whose first surface lies \
                 beyond its cells (lpv: --no-lpv-near-occlusion), the nearer ones' light \
                 gathered from the sun's RSM (lpv: --lpv-near-field; on leaves in place of \
                 the sun's share of the volume's light); lpv's \
                 glossy reflection occluded by the directions in its lobe, the volume's light \
                 where they are hidden"
                    .into()
            }
            Family::Debug => "none".into(),
        }
    }
}

/// One technique: its name on the command line, its family and a line about it.
pub struct Entry {
    pub technique: Technique,
    pub name: &'static str,
    pub family: Family,
    pub about: &'static str,
}

const fn entry(
    technique: Technique,
    name: &'static str,
    family: Family,
    about: &'static str,
) -> Entry {
    Entry {
        technique,
        name,
        family,
        about,
    }
}

/// Every technique, in the order the demo and the viewer show them.
#[rustfmt::skip]
pub const REGISTRY: &[Entry] = {
    use Family as F;
    use Technique as T;
    &[
        entry(T::Reference, "reference", F::PathTraced, "path-traced ground truth (NEE + MIS)"),
        entry(T::Direct, "direct", F::PathTraced, "the path tracer's direct light only"),
        entry(T::Phong, "phong", F::Phong, "Phong lighting, no shadows (Fuchs §4.1)"),
        entry(T::PhongShadowVolumes, "phong-shadow-volumes", F::Phong, "Phong with stencil shadow volumes (Fuchs §4.4)"),
        entry(T::PhongShadowMaps, "phong-shadow-maps", F::Phong, "Phong with shadow maps (Heidrich ch. 6)"),
        entry(T::CannedLight, "canned-light", F::Phong, "shadow-mapped Phong with the luminaire as a light slab (Heidrich ch. 7)"),
        entry(T::LightfieldRefraction, "lightfield-refraction", F::Phong, "shadow-mapped Phong, glass refracting through its geometry light field (Heidrich §10.2)"),
        entry(T::LightfieldGlossy, "lightfield-glossy", F::Phong, "shadow-mapped Phong, a glossy object's indirect light from its light field (Heidrich §10.1)"),
        entry(T::Lightmap, "lightmap", F::Lightmap, "baked light only (Fuchs §3.4)"),
        entry(T::LightmapPhong, "lightmap+phong", F::Lightmap, "baked indirect light + real-time lights with shadow volumes"),
        entry(T::PrtVertex, "prt-vertex", F::Sh, "per-vertex PRT (McKenzie Chapter ch. 4)"),
        entry(T::PrtTextured, "prt-textured", F::Sh, "textured PRT (McKenzie Chapter ch. 4)"),
        entry(T::PrtHierarchical, "prt-hierarchical", F::Sh, "textured PRT with shadows between moving objects (McKenzie Chapter ch. 5)"),
        entry(T::Shl, "shl", F::Sh, "SH light-maps (Fuchs §5)"),
        entry(T::ShlCompressed, "shl-compressed", F::Sh, "k-means compressed SH light-maps (Fuchs §5.6)"),
        entry(T::ShlNormalmapped, "shl-normalmapped", F::Sh, "normal-mapped SH light-maps (Fuchs §5.7)"),
        entry(T::Lpv, "lpv", F::Lpv, "light propagation volumes (Kaplanyan & Dachsbacher)"),
        entry(T::LpvFaithful, "lpv-faithful", F::Lpv, "light propagation volumes as the WPI report"),
        entry(T::Normals, "normals", F::Debug, "shading normals as colours, n/2 + 1/2 (debug view)"),
    ]
};

/// A `--technique` that is not in the registry.
#[derive(Debug, thiserror::Error)]
#[error("unknown technique '{0}' (known: {known})", known = Technique::names().join(", "))]
pub struct UnknownTechnique(String);

impl std::str::FromStr for Technique {
    type Err = UnknownTechnique;
    fn from_str(s: &str) -> Result<Technique, UnknownTechnique> {
        REGISTRY
            .iter()
            .find(|e| e.name == s)
            .map(|e| e.technique)
            .ok_or_else(|| UnknownTechnique(s.into()))
    }
}

impl std::fmt::Display for Technique {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl Technique {
    fn entry(self) -> &'static Entry {
        REGISTRY
            .iter()
            .find(|e| e.technique == self)
            .expect("every technique has a registry line")
    }
    pub fn name(self) -> &'static str {
        self.entry().name
    }
    pub fn family(self) -> Family {
        self.entry().family
    }
    pub fn is_gpu(self) -> bool {
        self.family() != Family::PathTraced
    }
    /// Every name, in registry order.
    pub fn names() -> Vec<&'static str> {
        REGISTRY.iter().map(|e| e.name).collect()
    }
    /// The GPU techniques, in registry order.
    pub fn gpu() -> impl Iterator<Item = Technique> {
        REGISTRY.iter().map(|e| e.technique).filter(|t| t.is_gpu())
    }
    /// The techniques of a family, in registry order.
    pub fn of(family: Family) -> Vec<Technique> {
        REGISTRY
            .iter()
            .filter(|e| e.family == family)
            .map(|e| e.technique)
            .collect()
    }

    /// The shadow method of the renderer this technique runs on, with `--shadow-variant`.
    pub fn shadows(self, variant: Option<VariantArg>) -> Result<ShadowMethod> {
        use {ShadowMethod as S, Technique as T, VariantArg as V};
        Ok(match (self, variant) {
            (T::Phong, None) => S::None,
            (T::PhongShadowVolumes | T::LightmapPhong, None | Some(V::Zfail)) => S::VolumesZFail,
            (T::PhongShadowVolumes | T::LightmapPhong, Some(V::Zpass)) => S::VolumesZPass,
            (
                T::PhongShadowMaps
                | T::CannedLight
                | T::LightfieldRefraction
                | T::LightfieldGlossy
                | T::Lpv
                | T::LpvFaithful,
                None | Some(V::Depth),
            ) => S::Map,
            (
                T::PhongShadowMaps
                | T::CannedLight
                | T::LightfieldRefraction
                | T::LightfieldGlossy
                | T::Lpv
                | T::LpvFaithful,
                Some(V::Linear),
            ) => S::MapLinear,
            (T::PhongShadowMaps | T::Lpv | T::LpvFaithful, Some(V::Planar)) => S::Planar,
            (T::Lightmap | T::Normals, None) => S::None,
            (t, None) if t.family() == Family::Sh => S::None,
            (t, Some(v)) => bail!("--shadow-variant {v:?} does not apply to technique '{t}'"),
            (t, None) => bail!("'{t}' is not a GPU technique"),
        })
    }

    /// Refuse options this technique would ignore (`bounces`: the reference's `--bounces`,
    /// which the baked techniques read as SH bounces).
    pub fn check_options(self, a: &TechniqueArgs, indirect_only: bool) -> Result<()> {
        let family = self.family();
        if indirect_only && self != Technique::Reference {
            bail!(
                "--indirect-only applies to --technique reference{}",
                if family == Family::Lpv {
                    "; the volume's indirect light alone is --debug-view indirect"
                } else {
                    ""
                }
            );
        }
        if !self.is_gpu() {
            return Ok(());
        }
        if a.bake.bounces.is_some() && matches!(family, Family::Phong | Family::Lpv | Family::Debug)
        {
            bail!("--bounces applies to --technique reference and to baked techniques, not {self}");
        }
        if a.lpv.debug_view != DebugView::Final && family != Family::Lpv {
            bail!("--debug-view applies to the LPV techniques (lpv, lpv-faithful)");
        }
        if a.raster.no_area_lights
            && matches!(family, Family::Lightmap | Family::Sh | Family::Debug)
        {
            bail!(
                "--no-area-lights applies to the Phong and LPV techniques; {self} never lights \
                 with emitters as area lights (its bake holds their light)"
            );
        }
        self.shadows(a.raster.shadow_variant)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_technique_has_one_registry_line_and_parses_back() {
        for e in REGISTRY {
            assert_eq!(e.name.parse::<Technique>().unwrap(), e.technique);
            assert_eq!(
                REGISTRY
                    .iter()
                    .filter(|o| o.technique == e.technique)
                    .count(),
                1
            );
            if e.technique.is_gpu() {
                e.technique.shadows(None).unwrap();
            }
        }
        let err = "magic".parse::<Technique>().unwrap_err().to_string();
        assert!(err.starts_with("unknown technique 'magic' (known: reference, direct"));
    }
}

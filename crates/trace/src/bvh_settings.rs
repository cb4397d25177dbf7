//! How the BVH is built: obvhs's PLOC builder (the only builder the crate offers besides
//! insertion) with its presets, and lightlab's leaf size and collapse cost, for the binary
//! tree; the cost model of its collapse into 8-wide nodes ([`crate::bvh8`]). The default is the
//! setting chosen by incoherent rays' speed on the scenes of `docs/reference-path-tracer.md`;
//! `lightlab bench trace --bvh SETTING` compares others.

use crate::bvh8::WideCosts;
use obvhs::BvhBuildParams;
use obvhs::ploc::PlocSearchDistance;
use std::str::FromStr;

/// A BVH build setting, written `PRESET[:KEY=VALUE,...]`: PRESET is one of obvhs's
/// `very-fast`, `fast`, `medium`, `slow`, `very-slow` (with lightlab's leaves of up to 16
/// triangles and collapse cost 4) or `default`; the keys override one parameter each:
/// `search` (PLOC's pairing distance: 1, 2, 6, 14, 24 or 32), `depth` (below it the distance
/// is 1), `reinsert` (share of nodes tried for reinsertion), `post` (the post-collapse pass,
/// × reinsert), `leaf` (triangles per binary leaf, 1–16), `collapse` (the collapse's
/// traversal cost), `presplit` (true/false); and two of the collapse into 8-wide nodes:
/// `node` and `block`, the costs of a node visit and of a block of eight triangle tests.
#[derive(Clone, Copy, Debug)]
pub struct BvhSettings {
    /// The binary tree's build (obvhs).
    pub params: BvhBuildParams,
    /// The cost model that collapses it into 8-wide nodes.
    pub wide: WideCosts,
}

/// A setting that does not parse.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum BvhSettingsError {
    #[error(
        "unknown BVH preset `{0}` (very-fast, fast, medium, slow, very-slow or default, then \
         optionally :key=value,...)"
    )]
    Preset(String),
    #[error(
        "BVH setting `{0}`: expected key=value (search, depth, reinsert, post, leaf, collapse, presplit, node, block)"
    )]
    Pair(String),
    #[error("BVH setting `{key}`: `{value}` is not {expected}")]
    Value {
        key: String,
        value: String,
        expected: &'static str,
    },
}

impl Default for BvhSettings {
    /// obvhs's `slow` preset with every node tried for reinsertion, before and after the
    /// collapse (`slow:reinsert=1,post=1`), leaves of up to 16 triangles and collapse cost 4.
    /// Of the settings compared with `bench/trace_vs_embree.py --bvh`, it is as fast as
    /// `very-slow` on prt and bush for incoherent rays (within noise, 5 % faster than `slow`)
    /// and as fast as `slow` on cornell, where `very-slow`'s PLOC depth threshold of 1 costs
    /// 14 % (docs/reference-path-tracer.md).
    fn default() -> Self {
        BvhSettings {
            params: BvhBuildParams {
                reinsertion_batch_ratio: 1.0,
                post_collapse_reinsertion_batch_ratio_multiplier: 1.0,
                ..lightlab_preset(BvhBuildParams::slow_build())
            },
            wide: WideCosts::default(),
        }
    }
}

fn lightlab_preset(p: BvhBuildParams) -> BvhBuildParams {
    BvhBuildParams {
        max_prims_per_leaf: 16,
        collapse_traversal_cost: 4.0,
        ..p
    }
}

impl FromStr for BvhSettings {
    type Err = BvhSettingsError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let (preset, rest) = s.split_once(':').unwrap_or((s, ""));
        let mut wide = WideCosts::default();
        let mut params = match preset.trim() {
            "default" => BvhSettings::default().params,
            "very-fast" => lightlab_preset(BvhBuildParams::very_fast_build()),
            "fast" => lightlab_preset(BvhBuildParams::fast_build()),
            "medium" => lightlab_preset(BvhBuildParams::medium_build()),
            "slow" => lightlab_preset(BvhBuildParams::slow_build()),
            "very-slow" => lightlab_preset(BvhBuildParams::very_slow_build()),
            other => return Err(BvhSettingsError::Preset(other.to_string())),
        };
        for pair in rest.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let (key, value) = pair
                .split_once('=')
                .ok_or_else(|| BvhSettingsError::Pair(pair.to_string()))?;
            let bad = |expected| BvhSettingsError::Value {
                key: key.to_string(),
                value: value.to_string(),
                expected,
            };
            let positive = || {
                value
                    .parse::<f32>()
                    .ok()
                    .filter(|v| v.is_finite() && *v > 0.0)
                    .ok_or_else(|| bad("a number > 0"))
            };
            let ratio = || {
                value
                    .parse::<f32>()
                    .ok()
                    .filter(|v| v.is_finite() && *v >= 0.0)
                    .ok_or_else(|| bad("a number ≥ 0"))
            };
            match key {
                "search" => {
                    params.ploc_search_distance = match value {
                        "1" => PlocSearchDistance::Minimum,
                        "2" => PlocSearchDistance::VeryLow,
                        "6" => PlocSearchDistance::Low,
                        "14" => PlocSearchDistance::Medium,
                        "24" => PlocSearchDistance::High,
                        "32" => PlocSearchDistance::VeryHigh,
                        _ => return Err(bad("1, 2, 6, 14, 24 or 32")),
                    }
                }
                "depth" => {
                    params.search_depth_threshold =
                        value.parse().map_err(|_| bad("a whole number"))?
                }
                "reinsert" => params.reinsertion_batch_ratio = ratio()?,
                "post" => params.post_collapse_reinsertion_batch_ratio_multiplier = ratio()?,
                "leaf" => {
                    params.max_prims_per_leaf = value
                        .parse()
                        .ok()
                        .filter(|v| (1..=16).contains(v))
                        .ok_or_else(|| bad("1 to 16"))?
                }
                "collapse" => params.collapse_traversal_cost = ratio()?,
                "presplit" => params.pre_split = value.parse().map_err(|_| bad("true or false"))?,
                "node" => wide.node = positive()?,
                "block" => wide.block = positive()?,
                _ => return Err(BvhSettingsError::Pair(pair.to_string())),
            }
        }
        Ok(BvhSettings { params, wide })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_parse_presets_and_overrides() {
        let d = BvhSettings::default().params;
        let p = "default".parse::<BvhSettings>().unwrap().params;
        assert_eq!(p.reinsertion_batch_ratio, d.reinsertion_batch_ratio);
        let p = "very-slow:leaf=8,collapse=3.5,search=6,presplit=false"
            .parse::<BvhSettings>()
            .unwrap()
            .params;
        assert_eq!(p.max_prims_per_leaf, 8);
        assert_eq!(p.collapse_traversal_cost, 3.5);
        assert!(matches!(p.ploc_search_distance, PlocSearchDistance::Low));
        assert!(!p.pre_split);
        assert_eq!(p.reinsertion_batch_ratio, 1.0);
        let w = "slow:block=0.6,node=2".parse::<BvhSettings>().unwrap().wide;
        assert_eq!((w.node, w.block), (2.0, 0.6));
        assert!(matches!(
            "slow:block=0".parse::<BvhSettings>(),
            Err(BvhSettingsError::Value { .. })
        ));
        let p = "fast".parse::<BvhSettings>().unwrap().params;
        assert_eq!(p.max_prims_per_leaf, 16);
        assert!(matches!(
            "quick".parse::<BvhSettings>(),
            Err(BvhSettingsError::Preset(_))
        ));
        assert!(matches!(
            "slow:leaf".parse::<BvhSettings>(),
            Err(BvhSettingsError::Pair(_))
        ));
        assert!(matches!(
            "slow:leaf=17".parse::<BvhSettings>(),
            Err(BvhSettingsError::Value { .. })
        ));
        assert!(matches!(
            "slow:reinsert=-1".parse::<BvhSettings>(),
            Err(BvhSettingsError::Value { .. })
        ));
        assert!(matches!(
            "slow:search=5".parse::<BvhSettings>(),
            Err(BvhSettingsError::Value { .. })
        ));
    }
}

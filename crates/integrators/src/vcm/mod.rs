//! `vcm` — vertex connection and merging (Georgiev, Křivánek, Davidovič & Slusallek 2012): every
//! iteration traces M light subpaths, then per pixel a camera subpath that connects as `bdpt`
//! does (every s, t) and merges with the light vertices within the iteration's radius, all under
//! one MIS in which merging counts η = M π rᵢ² times (`connect_merge`). Consistent: merging is
//! biased by the kernel, the bias vanishing as rᵢ = r₀ i^((α−1)/2) shrinks. With `merging =
//! false` (`lt render --no-merge`) it is BDPT: the same techniques, weights, random numbers and
//! image as `bdpt` (up to the rounding of the two weight computations).
//!
//! | key | type | default | meaning |
//! |---|---|---|---|
//! | `max_depth` | u32 | scene `[render] max_depth` (8) | longest path in segments, camera ray included |
//! | `rr_depth` | u32 | scene `[render] rr_depth` (5) | Russian roulette from this many segments on |
//! | `mis` | power/balance/none | power | heuristic over all connection and merging techniques |
//! | `light_paths` | u64 | the pixel count | light subpaths per iteration (N_VM) |
//! | `radius_px` | f32 | 2 | initial radius in pixel footprints at the mean primary-hit distance |
//! | `radius_scene` | f32 | — | initial radius as a fraction of the scene's bounding-sphere diameter |
//! | `radius` | f32 | — | initial radius in scene units |
//! | `alpha` | f64 | 0.75 | radius reduction α: rᵢ = r₀ i^((α−1)/2) |
//! | `correlation_aware` | true/false | false | correlation-aware MIS for merging (Grittmann et al. 2021, `lt_core::path::camis`): merging at x_i counts η ρ_i; weights from the full path's densities (slower) |
//! | `merging` | true/false | true | false: connections only (BDPT) |
//! | `vertex_connections` | true/false | true | false: no connections s ≥ 2, t ≥ 2 (next-event estimation and light tracing stay); weights from the full path's densities |

//!
//! This folder holds the VCM family: the engine `vcm`, `bpm` and `eamis` share (`engine`), and
//! the two estimators besides `vcm` built on it (`bpm`, `eamis`).

pub mod bpm;
pub mod eamis;
pub mod engine;

use crate::params::ParamReader;
use crate::vcm::engine::{Run, Techniques, VcmParams};
use crate::{Progressive, ProgressiveRun};
use lt_core::Scene;

pub struct Vcm {
    pub params: VcmParams,
}

impl Vcm {
    pub fn read(scene: &Scene, r: &ParamReader) -> Result<Vcm, String> {
        let techniques = match r.get::<bool>("merging")?.unwrap_or(true) {
            true => Techniques::VCM,
            false => Techniques::CONNECTIONS,
        };
        Ok(Vcm {
            params: VcmParams::read(scene, r, "vcm", techniques)?,
        })
    }
}

impl Progressive for Vcm {
    fn name(&self) -> &'static str {
        "vcm"
    }

    fn start<'a>(&'a self, scene: &'a Scene, seed: u64) -> Box<dyn ProgressiveRun + 'a> {
        Box::new(Run::new(&self.params, scene, seed))
    }
}

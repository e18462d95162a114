//! `bpm` — bidirectional photon mapping (Vorba 2011; Georgiev et al. 2012, §5): the merging half
//! of `vcm`. Every iteration traces M light subpaths, and each camera subpath merges at *every*
//! non-delta vertex with the light vertices within rᵢ, the merges of one path weighed against each
//! other (and against the camera walk hitting a light, the only technique for paths no merge can
//! make) by MIS — unlike `sppm`, which merges only at the first non-delta vertex.
//!
//! | key | type | default | meaning |
//! |---|---|---|---|
//! | `max_depth` | u32 | scene `[render] max_depth` (8) | longest path in segments, camera ray included |
//! | `rr_depth` | u32 | scene `[render] rr_depth` (5) | Russian roulette from this many segments on |
//! | `mis` | power/balance/none | power | heuristic over the merging techniques |
//! | `light_paths` | u64 | the pixel count | light subpaths per iteration (N_VM) |
//! | `radius_px` | f32 | 2 | initial radius in pixel footprints at the mean primary-hit distance |
//! | `radius_scene` | f32 | — | initial radius as a fraction of the scene's bounding-sphere diameter |
//! | `radius` | f32 | — | initial radius in scene units |
//! | `alpha` | f64 | 0.75 | radius reduction α: rᵢ = r₀ i^((α−1)/2) |
//! | `correlation_aware` | true/false | false | correlation-aware MIS for merging (Grittmann et al. 2021, `lt_core::path::camis`): merging at x_i counts η ρ_i; weights from the full path's densities (slower) |

use crate::params::ParamReader;
use crate::vcm::engine::{Run, Techniques, VcmParams};
use crate::{Progressive, ProgressiveRun};
use lt_core::Scene;

pub struct Bpm {
    pub params: VcmParams,
}

impl Bpm {
    pub fn read(scene: &Scene, r: &ParamReader) -> Result<Bpm, String> {
        Ok(Bpm {
            params: VcmParams::read(scene, r, "bpm", Techniques::BPM)?,
        })
    }
}

impl Progressive for Bpm {
    fn name(&self) -> &'static str {
        "bpm"
    }

    fn start<'a>(&'a self, scene: &'a Scene, seed: u64) -> Box<dyn ProgressiveRun + 'a> {
        Box::new(Run::new(&self.params, scene, seed))
    }
}

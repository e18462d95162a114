//! `pb2d` — the beam radiance estimate (Jarosz, Zwicker & Jensen 2008; Jarosz et al. 2011's
//! "point–beam 2-D"), progressive: each pass traces its own volume photons and gathers those
//! within r of every flight of the camera walk through a medium (a long camera beam, T inside
//! the estimate) with the 2-D kernel 1/(πr²), r shrinking as i^((α−1)/2) (`schedule`). Which
//! paths it estimates: `volume_density` (mod.rs); the query and its grid: `beams.rs`.
//!
//! | key | type | default | meaning |
//! |---|---|---|---|
//! | `max_depth` | u32 | scene `[render] max_depth` (8) | longest path in segments, camera ray included |
//! | `rr_depth` | u32 | scene `[render] rr_depth` (5) | Russian roulette from this many segments on |
//! | `photons_per_pass` | u64 | the pixel count | photon (light) paths per pass |
//! | `radius` | f32 | — | initial radius r₁ in scene units |
//! | `radius_scene` | f32 | 0.01 | initial radius as a fraction of the scene's bounding-sphere diameter |
//! | `alpha` | f64 | 2/3 | radius reduction: rᵢ = r₁ i^((α−1)/2) |

use super::{Query, VolumeParams, VolumeRun};
use crate::params::ParamReader;
use crate::{Progressive, ProgressiveRun};
use lt_core::Scene;

pub struct Pb2d {
    pub params: VolumeParams,
}

impl Pb2d {
    pub fn read(scene: &Scene, r: &ParamReader) -> Result<Pb2d, String> {
        Ok(Pb2d {
            params: VolumeParams::read(scene, r, "pb2d", 2)?,
        })
    }
}

impl Progressive for Pb2d {
    fn name(&self) -> &'static str {
        "pb2d"
    }

    fn start<'a>(&'a self, scene: &'a Scene, seed: u64) -> Box<dyn ProgressiveRun + 'a> {
        Box::new(VolumeRun::new(&self.params, Query::Beams, scene, seed))
    }
}

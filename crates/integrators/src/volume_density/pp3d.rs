//! `pp3d` — volumetric photon mapping with photon points queried by points (Jensen & Christensen
//! 1998; Jarosz et al. 2011's "point–point 3-D"), progressive: each pass traces its own volume
//! photons and gathers them at the camera walk's first medium vertex with the 3-D kernel
//! 1/((4/3)πr³), r shrinking as i^((α−1)/3) (`schedule`). Which paths it estimates, and how the
//! camera walk stays `pt` elsewhere: `volume_density` (mod.rs); the query: `points.rs`.
//!
//! | key | type | default | meaning |
//! |---|---|---|---|
//! | `max_depth` | u32 | scene `[render] max_depth` (8) | longest path in segments, camera ray included |
//! | `rr_depth` | u32 | scene `[render] rr_depth` (5) | Russian roulette from this many segments on |
//! | `photons_per_pass` | u64 | the pixel count | photon (light) paths per pass |
//! | `radius` | f32 | — | initial radius r₁ in scene units |
//! | `radius_scene` | f32 | 0.01 | initial radius as a fraction of the scene's bounding-sphere diameter |
//! | `alpha` | f64 | 4/7 | radius reduction: rᵢ = r₁ i^((α−1)/3) |

use super::{Query, VolumeParams, VolumeRun};
use crate::params::ParamReader;
use crate::{Progressive, ProgressiveRun};
use lt_core::Scene;

pub struct Pp3d {
    pub params: VolumeParams,
}

impl Pp3d {
    pub fn read(scene: &Scene, r: &ParamReader) -> Result<Pp3d, String> {
        Ok(Pp3d {
            params: VolumeParams::read(scene, r, "pp3d", 3)?,
        })
    }
}

impl Progressive for Pp3d {
    fn name(&self) -> &'static str {
        "pp3d"
    }

    fn start<'a>(&'a self, scene: &'a Scene, seed: u64) -> Box<dyn ProgressiveRun + 'a> {
        Box::new(VolumeRun::new(&self.params, Query::Points, scene, seed))
    }
}

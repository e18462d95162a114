//! `bp2d` — photon beams × camera points with the 2-D kernel (Jarosz, Nowrouzezahrai, Sadeghi &
//! Jensen 2011's "beam × point 2-D", SmallUPBP's BP2D; not `pb2d`, which gathers photon points
//! along camera beams), progressive: each pass traces its own light subpaths and keeps their
//! flights through media as long photon beams (`photon_beams.rs`, as `bb1d`), gathered at the
//! camera walk's first medium vertex (sampled by free flight, as `pp3d`) with the kernel
//! 1/(πr²) across each beam, r shrinking as i^((α−1)/2) (`schedule`, d = 2). Which paths it
//! estimates: `volume_density` (mod.rs); the query: `point_beam.rs`.
//!
//! | key | type | default | meaning |
//! |---|---|---|---|
//! | `max_depth` | u32 | scene `[render] max_depth` (8) | longest path in segments, camera ray included |
//! | `rr_depth` | u32 | scene `[render] rr_depth` (5) | Russian roulette from this many segments on |
//! | `photons_per_pass` | u64 | the pixel count | photon (light) paths per pass, each giving its flights through media as beams |
//! | `radius` | f32 | — | initial radius r₁ in scene units |
//! | `radius_scene` | f32 | 0.01 | initial radius as a fraction of the scene's bounding-sphere diameter |
//! | `alpha` | f64 | 2/3 | radius reduction: rᵢ = r₁ i^((α−1)/2) |

use super::{Query, VolumeParams, VolumeRun};
use crate::params::ParamReader;
use crate::{Progressive, ProgressiveRun};
use lt_core::Scene;

pub struct Bp2d {
    pub params: VolumeParams,
}

impl Bp2d {
    pub fn read(scene: &Scene, r: &ParamReader) -> Result<Bp2d, String> {
        Ok(Bp2d {
            params: VolumeParams::read(scene, r, "bp2d", 2)?,
        })
    }
}

impl Progressive for Bp2d {
    fn name(&self) -> &'static str {
        "bp2d"
    }

    fn start<'a>(&'a self, scene: &'a Scene, seed: u64) -> Box<dyn ProgressiveRun + 'a> {
        Box::new(VolumeRun::new(&self.params, Query::PointBeams, scene, seed))
    }
}

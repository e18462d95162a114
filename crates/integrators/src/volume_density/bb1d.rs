//! `bb1d` — photon beams × camera beams with the 1-D kernel (Jarosz, Nowrouzezahrai, Sadeghi &
//! Jensen 2011, "A comprehensive theory of volumetric radiance estimation using photon points
//! and beams": the beam × beam 1-D estimate; progressive as Jarosz et al. 2011's progressive
//! photon beams): each pass traces its own light subpaths and keeps their flights through media
//! as *long* photon beams (the whole flight, transmittance inside the estimate:
//! `photon_beams.rs`), gathered along every flight of the camera walk through a medium (a long
//! camera beam, as `pb2d`'s) with the kernel 1/(2r) across both beams and the 1/sin θ of their
//! crossing (`beam_beam.rs`), r shrinking as i^(α−1) (`schedule`, d = 1). Which paths it
//! estimates: `volume_density` (mod.rs).
//!
//! | key | type | default | meaning |
//! |---|---|---|---|
//! | `max_depth` | u32 | scene `[render] max_depth` (8) | longest path in segments, camera ray included |
//! | `rr_depth` | u32 | scene `[render] rr_depth` (5) | Russian roulette from this many segments on |
//! | `photons_per_pass` | u64 | the pixel count | photon (light) paths per pass, each giving its flights through media as beams |
//! | `radius` | f32 | — | initial radius r₁ in scene units |
//! | `radius_scene` | f32 | 0.01 | initial radius as a fraction of the scene's bounding-sphere diameter |
//! | `alpha` | f64 | 4/5 | radius reduction: rᵢ = r₁ i^(α−1) |

use super::{Query, VolumeParams, VolumeRun};
use crate::params::ParamReader;
use crate::{Progressive, ProgressiveRun};
use lt_core::Scene;

pub struct Bb1d {
    pub params: VolumeParams,
}

impl Bb1d {
    pub fn read(scene: &Scene, r: &ParamReader) -> Result<Bb1d, String> {
        Ok(Bb1d {
            params: VolumeParams::read(scene, r, "bb1d", 1)?,
        })
    }
}

impl Progressive for Bb1d {
    fn name(&self) -> &'static str {
        "bb1d"
    }

    fn start<'a>(&'a self, scene: &'a Scene, seed: u64) -> Box<dyn ProgressiveRun + 'a> {
        Box::new(VolumeRun::new(&self.params, Query::BeamBeams, scene, seed))
    }
}

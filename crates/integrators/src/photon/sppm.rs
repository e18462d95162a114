//! `sppm` — stochastic progressive photon mapping (Hachisuka & Jensen 2009): like `ppm`, but
//! every pass traces new camera samples, so each pass has its own visible points (a new jittered
//! position per pixel: antialiasing, and glossy and distributed effects converge) while radii and
//! photon statistics stay per pixel. Memory grows with the pixels and with the photons of one pass
//! (measured: ≈ 355 bytes per pixel + 325 per photon path of a pass), not with all photons traced.
//!
//! | key | type | default | meaning |
//! |---|---|---|---|
//! | `max_depth` | u32 | scene `[render] max_depth` (8) | longest path in segments, camera ray included |
//! | `rr_depth` | u32 | scene `[render] rr_depth` (5) | Russian roulette of photon paths from this many segments on |
//! | `photons_per_pass` | u64 | the pixel count | photon paths per pass |
//! | `radius_px` | f32 | 2 | initial radius in pixel footprints at the visible point |
//! | `radius_scene` | f32 | — | initial radius as a fraction of the scene's bounding-sphere diameter |
//! | `radius` | f32 | — | initial radius in scene units (warned about when far from the pixel footprint) |
//! | `alpha` | f64 | 2/3 | radius reduction α (see `radius`: r²ᵢ ∝ i^(α−1)) |
//! | `radius_update` | global/local/power | global | Knaus & Zwicker's global schedule, Hachisuka's per-pixel update, or vcm's r²ᵢ = r²₁ i^(α−1) |
//! | `kernel` | disk/epanechnikov | disk | density-estimation kernel, normalised over the disk |
//! | `direct` | nee/photons | nee | direct light by next-event estimation or from photons |

use crate::density::progressive::{ProgressiveParams, ProgressiveState};
use crate::density::visible::{trace_visible_point, CameraPrefix};
use crate::film::pixel::pixel_sample;
use crate::params::ParamReader;
use crate::{ProgressLog, Progressive, ProgressiveRun};
use lt_core::sampling::{Domain, Sampler};
use lt_core::Scene;
use lt_estimators::Image;
use rayon::prelude::*;

pub struct Sppm {
    pub params: ProgressiveParams,
}

impl Sppm {
    pub fn read(scene: &Scene, r: &ParamReader) -> Result<Sppm, String> {
        Ok(Sppm {
            params: ProgressiveParams::read(scene, r, "sppm")?,
        })
    }
}

impl Progressive for Sppm {
    fn name(&self) -> &'static str {
        "sppm"
    }

    fn start<'a>(&'a self, scene: &'a Scene, seed: u64) -> Box<dyn ProgressiveRun + 'a> {
        Box::new(SppmRun {
            params: &self.params,
            scene,
            seed,
            prefixes: Vec::new(),
            state: ProgressiveState::new(scene),
        })
    }
}

struct SppmRun<'a> {
    params: &'a ProgressiveParams,
    scene: &'a Scene,
    seed: u64,
    /// This pass's camera samples (kept to reuse the allocation).
    prefixes: Vec<CameraPrefix>,
    state: ProgressiveState,
}

impl ProgressiveRun for SppmRun<'_> {
    fn pass(&mut self, pass: u32) -> u64 {
        let (scene, p, seed) = (self.scene, self.params, self.seed);
        (0..scene.camera.pixel_count())
            .into_par_iter()
            .map(|j| {
                let mut s = Sampler::for_item(Domain::Camera, seed, j as u64, pass as u64);
                let film = pixel_sample(scene, j as u64, &mut s);
                CameraPrefix::weighted(film.map(|f| {
                    let prefix =
                        trace_visible_point(scene, f.raster, &mut s, p.max_depth, p.direct);
                    (prefix, f.weight)
                }))
            })
            .collect_into_vec(&mut self.prefixes);
        self.state.pass(scene, p, seed, pass, &self.prefixes)
    }

    fn estimate(&self) -> Image {
        self.state.estimate(self.params)
    }

    fn log(&self) -> ProgressLog {
        self.state.log.clone()
    }
}

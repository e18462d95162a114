//! `ppm` — progressive photon mapping (Hachisuka, Ogaki & Jensen 2008): one camera pass finds a
//! visible point per pixel (through delta bounces to the first non-delta vertex, at one jittered
//! position in the pixel), then every pass traces a batch of photon paths and pushes each photon
//! into the visible points whose disk holds it (`progressive`); the radii shrink pass by pass, so
//! bias and variance both vanish as passes grow. Memory grows with the visible points (the
//! pixels) and one pass's photons, not with all photons traced.
//!
//! The visible points never move, so a pixel converges to the radiance at its one point: the
//! pixel's own integral only in expectation over runs (antialiasing and glossy blur are what
//! `sppm` adds). Next-event estimation at the fixed point is re-sampled every pass.
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
//! | `visible_seed` | u64 | the run's seed | seed of the one camera pass: runs that share it share their visible points and differ in photons only, so their spread is the variance at fixed points that Knaus & Zwicker's rates describe |

use crate::density::progressive::{ProgressiveParams, ProgressiveState};
use crate::density::visible::{next_event, trace_visible_point, CameraPrefix, Direct};
use crate::film::pixel::pixel_sample;
use crate::params::ParamReader;
use crate::{ProgressLog, Progressive, ProgressiveRun};
use lt_core::sampling::{Domain, Sampler};
use lt_core::Scene;
use lt_estimators::Image;
use rayon::prelude::*;

pub struct Ppm {
    pub params: ProgressiveParams,
    /// Seed of the camera pass, when it is not the run's.
    pub visible_seed: Option<u64>,
}

impl Ppm {
    pub fn read(scene: &Scene, r: &ParamReader) -> Result<Ppm, String> {
        Ok(Ppm {
            params: ProgressiveParams::read(scene, r, "ppm")?,
            visible_seed: r.get::<u64>("visible_seed")?,
        })
    }
}

impl Progressive for Ppm {
    fn name(&self) -> &'static str {
        "ppm"
    }

    fn start<'a>(&'a self, scene: &'a Scene, seed: u64) -> Box<dyn ProgressiveRun + 'a> {
        Box::new(PpmRun {
            params: &self.params,
            scene,
            seed,
            visible_seed: self.visible_seed.unwrap_or(seed),
            fixed: Vec::new(),
            prefixes: Vec::new(),
            state: ProgressiveState::new(scene),
        })
    }
}

struct PpmRun<'a> {
    params: &'a ProgressiveParams,
    scene: &'a Scene,
    seed: u64,
    visible_seed: u64,
    /// The visible points of the camera pass (empty until pass 0).
    fixed: Vec<CameraPrefix>,
    /// This pass's prefixes: the fixed points with this pass's next-event estimate.
    prefixes: Vec<CameraPrefix>,
    state: ProgressiveState,
}

impl ProgressiveRun for PpmRun<'_> {
    fn pass(&mut self, pass: u32) -> u64 {
        let (scene, p, seed) = (self.scene, self.params, self.seed);
        let visible_seed = self.visible_seed;
        if self.fixed.is_empty() {
            // The one camera pass, from the pixels' streams of pass 0.
            self.fixed = (0..scene.camera.pixel_count())
                .into_par_iter()
                .map(|j| {
                    let mut s = Sampler::for_item(Domain::Camera, visible_seed, j as u64, 0);
                    let film = pixel_sample(scene, j as u64, &mut s);
                    CameraPrefix::weighted(film.map(|f| {
                        let prefix =
                            trace_visible_point(scene, f.raster, &mut s, p.max_depth, p.direct);
                        (prefix, f.weight)
                    }))
                })
                .collect();
        }
        // Next-event estimation at the fixed points, afresh each pass (the auxiliary streams).
        self.prefixes = self
            .fixed
            .par_iter()
            .enumerate()
            .map(|(j, pre)| {
                let mut out = *pre;
                if pass > 0 {
                    out.nee = lt_core::Color::ZERO;
                    if let (Some(vp), Direct::Nee) = (&pre.vp, p.direct) {
                        if vp.gp.segments < p.max_depth {
                            let mut s = Sampler::for_item(Domain::Aux, seed, j as u64, pass as u64);
                            let sf = vp.gp.sf;
                            out.nee =
                                vp.gp.beta * next_event(scene, &vp.hit, &sf, vp.gp.wo, &mut s);
                        }
                    }
                }
                out
            })
            .collect();
        self.state.pass(scene, p, seed, pass, &self.prefixes)
    }

    fn estimate(&self) -> Image {
        self.state.estimate(self.params)
    }

    fn log(&self) -> ProgressLog {
        self.state.log.clone()
    }
}

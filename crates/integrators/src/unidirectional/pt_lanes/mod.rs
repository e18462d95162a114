//! `pt` with `lanes=8`: the same estimator as `pt` (`unidirectional::pt`), run eight pixel
//! samples at a time, bounce by bounce, over a structure-of-arrays path state (issue 47, item 3).
//!
//! Each lane is one pixel's camera sample drawing from exactly the stream the scalar `pt` uses
//! for it (`Sampler::for_item(Domain::Camera, seed, pixel, pass)`), and every lane kernel does the
//! same IEEE operations in the same order as the scalar code it mirrors (no FMA, no SIMD
//! approximations of transcendental functions), so the image is the scalar `pt`'s bit for bit —
//! which is the whole test (`tests/pt_lanes.rs`). The scalar `pt` stays the reference.
//!
//! What runs lane-wide and what per lane:
//! - the closest hits of a bounce's rays: the ray core's packet query (`Scene::intersect_packet`,
//!   `geometry/packet.rs`: the flat core tests the 8 rays together, other cores one by one);
//! - lane kernels (`kernels.rs`): the MIS weights of emitter hits and of next-event estimation
//!   (power heuristic), and the radiance and throughput arithmetic that adds them to the estimate;
//! - per lane, through the scalar functions (`driver.rs`): camera rays, shadow rays, light and
//!   BSDF sampling and evaluation, Russian roulette, lights at infinity.
//!
//! A lane whose path ends takes the row's next pixel before the next bounce (`driver::run_row`),
//! so the packet stays full until the row runs out. Measured (results/bench.md, "Lane-parallel
//! `pt`, second cut"): the packet query pays on the flat core; a lane kernel for the
//! parallelogram light's `sample_li` did not (the transposition into lanes cost more than the
//! arithmetic it shared) and was dropped. Nor did the packet occlusion query for the shadow
//! rays (`Scene::resolve_shadow_packet`, which `light_lanes` uses): a bounce's packet has lanes
//! with no shadow ray (emitter hits, retired paths, back-facing light samples), and the flat
//! core's packet loop costs the same for them, so it took 6 % more instructions than the shadow
//! rays one by one (results/bench.md, "packet shadow rays").
//!
//! Participating media are not handled: `lanes=8` on a scene with media is refused in one line
//! (`registry`).

mod driver;
mod kernels;
mod state;

use crate::params::ParamReader;
use crate::pt::{Pt, PtParams};
use crate::{Estimator, Integrator};
use lt_core::Scene;
use lt_estimators::Image;
use rayon::prelude::*;
use state::LANES;
use std::sync::atomic::{AtomicU64, Ordering};

/// `pt`'s constructor (registry): its keys, and `lanes` — 1 (the scalar `pt`, default) or 8
/// (this module). A scene with media is refused in one line under `lanes=8`: the lanes walk
/// surfaces only.
pub fn make(scene: &Scene, r: &ParamReader) -> Result<Estimator, String> {
    let params = PtParams::read(scene, r)?;
    let lanes = r
        .get_with("lanes", |v| match v {
            "1" => Ok(false),
            "8" => Ok(true),
            _ => Err(format!("'{v}' is not a lane width (known: 1, {LANES})")),
        })?
        .unwrap_or(false);
    if !lanes {
        return Ok(Estimator::Unbiased(Box::new(Pt { params })));
    }
    if scene.has_media {
        return Err(format!(
            "pt: lanes={LANES} does not handle participating media yet; the scene has {} media \
             (lanes=1 renders it)",
            scene.media.len()
        ));
    }
    Ok(Estimator::Unbiased(Box::new(PtLanes::new(params))))
}

pub struct PtLanes {
    pub pt: Pt,
}

impl PtLanes {
    pub fn new(params: PtParams) -> PtLanes {
        PtLanes { pt: Pt { params } }
    }
}

impl Integrator for PtLanes {
    fn name(&self) -> &'static str {
        "pt"
    }

    /// `film::pixel::pixel_pass`, with each row's pixels walked `LANES` at a time.
    fn render_pass(&self, scene: &Scene, seed: u64, pass: u32) -> (Image, u64) {
        let w = scene.camera.width as usize;
        let h = scene.camera.height as usize;
        let mut img = Image::new(w, h);
        let invalid = AtomicU64::new(0);
        img.data.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            let first = (y * w) as u64;
            let bad = driver::run_row(&self.pt, scene, (seed, pass), first, row);
            if bad > 0 {
                invalid.fetch_add(bad, Ordering::Relaxed);
            }
        });
        (img, invalid.into_inner())
    }
}

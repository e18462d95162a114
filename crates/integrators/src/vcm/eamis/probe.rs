//! The pilot's recorder: per pixel and candidate configuration the sums the prediction reads
//! (values under every candidate, second moments, merging's bias terms) and the counted work.

use super::{fixed_candidates, LIGHT_RATIOS};
use crate::record::{Completed, Merged, Recorder, Work};
use crate::vcm::engine::pixel_of;
use lt_core::math::Color;
use lt_core::path::camis::Mixture;
use lt_core::path::efficiency::{Counts, Scaling};
use lt_core::Scene;

/// The pilot's pilot configuration: one light subpath per pixel, every technique.
pub(super) const PILOT: Counts = Counts {
    light_ratio: 1.0,
    vertex_connections: true,
    merging: true,
};

/// The global candidates (M, vertex connections), each rendered with merging on (`2g`) or off
/// (`2g + 1`) in a pixel.
pub(super) fn globals() -> Vec<(f64, bool)> {
    LIGHT_RATIOS
        .iter()
        .flat_map(|&r| [(r, true), (r, false)])
        .collect()
}

/// What the pilot gathers: per pixel and candidate the second-moment sums, per pixel the merge
/// work, and the counts of the rest of the work.
pub(super) struct Probe {
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) candidates: Vec<Counts>,
    /// moments[pixel × candidates + c].
    pub(super) moments: Vec<f64>,
    /// moments_unmerged[pixel × globals + g]: the moment of global g without merging from the
    /// pilot's samples that are not merges (`Counts::second_moment_term_without_merges`).
    pub(super) moments_unmerged: Vec<f64>,
    /// The same layout: the pilot's weighted light that candidate c makes no path for (q_c = 0:
    /// a caustic seen in a mirror, without merging), summed over the pilot passes.
    pub(super) missed: Vec<f64>,
    pub(super) merge_queries: Vec<u64>,
    pub(super) merges_found: Vec<u64>,
    pub(super) camera_samples: u64,
    pub(super) shadow_rays_fixed: u64,
    pub(super) vertex_connections: u64,
    pub(super) light_tracing: u64,
    pub(super) light_vertices: u64,
    /// The mixture of the path about to be reported.
    pub(super) pending: Option<Mixture>,
    pub(super) pixel: usize,
    pub(super) film_weight: f64,
    /// direct[pixel × candidates + c]: Σ over the pilot's camera samples of the square of the
    /// value c would have got from it (`Counts::contribution` summed over its samples, so the
    /// correlation between its techniques and between its merges is in it); plus each
    /// light-tracing splat's square × r_c. c draws r_c = M_c/M_pilot times the pilot's light
    /// paths: it makes r_c splats for each of the pilot's, and r_c merges of the same mean for
    /// each, so a merge's value is scaled by r_c, and the squares of those scaled values, the
    /// part of the variance from independent light paths, count 1/r_c times (r_c² from the
    /// scaling, over r_c as many paths): (1/r_c − 1) × their sum is added.
    pub(super) direct: Vec<f64>,
    /// The same layout: Σ over camera samples of that value (its mean's estimate).
    pub(super) direct_sum: Vec<f64>,
    /// Per candidate, the value of the camera sample under way and its merges' squares.
    pub(super) sample_value: Vec<f64>,
    pub(super) sample_merge_sq: Vec<f64>,
    /// bias_diff[pixel × globals + g]: Σ over the pilot's merges of w_c v (1 − 2·[d < r/√2]) ×
    /// `bias_scale`, c the merging candidate of global g: half of merging's bias at r₀, summed
    /// over the pilot passes.
    pub(super) bias_diff: Vec<f64>,
    /// The same layout: Σ of the terms' squares (the differences' sampling variance).
    pub(super) bias_terms_sq: Vec<f64>,
    /// (r₀ / r_pass)² of the pass under way: brings each pass's difference to r₀.
    pub(super) bias_scale: f64,
}

impl Probe {
    pub(super) fn new(scene: &Scene) -> Probe {
        let n = scene.camera.pixel_count();
        let candidates = fixed_candidates();
        let nc = candidates.len();
        let globals = nc / 2;
        Probe {
            width: scene.camera.width,
            height: scene.camera.height,
            moments: vec![0.0; n * candidates.len()],
            moments_unmerged: vec![0.0; n * globals],
            missed: vec![0.0; n * candidates.len()],
            candidates,
            merge_queries: vec![0; n],
            merges_found: vec![0; n],
            camera_samples: 0,
            shadow_rays_fixed: 0,
            vertex_connections: 0,
            light_tracing: 0,
            light_vertices: 0,
            pending: None,
            pixel: 0,
            film_weight: 1.0,
            direct: vec![0.0; n * nc],
            direct_sum: vec![0.0; n * nc],
            sample_value: vec![0.0; nc],
            sample_merge_sq: vec![0.0; nc],
            bias_diff: vec![0.0; n * globals],
            bias_terms_sq: vec![0.0; n * globals],
            bias_scale: 1.0,
        }
    }

    /// Adds the camera sample under way to `direct`.
    pub(super) fn flush(&mut self) {
        let nc = self.candidates.len();
        for (c, counts) in self.candidates.iter().enumerate() {
            let (v, sq) = (self.sample_value[c], self.sample_merge_sq[c]);
            let r = counts.light_ratio / PILOT.light_ratio;
            self.direct[self.pixel * nc + c] += v * v + (1.0 / r - 1.0) * sq;
            self.direct_sum[self.pixel * nc + c] += v;
        }
        self.sample_value.iter_mut().for_each(|v| *v = 0.0);
        self.sample_merge_sq.iter_mut().for_each(|v| *v = 0.0);
    }

    /// The value every candidate gives one pilot sample, into the camera sample under way or,
    /// for a light-tracing splat, straight into `direct` of the pixel it lands in.
    pub(super) fn add_direct(
        &mut self,
        pixel: usize,
        value: f64,
        mixture: &Mixture,
        scaling: Scaling,
    ) {
        let nc = self.candidates.len();
        for (c, counts) in self.candidates.iter().enumerate() {
            let x = counts.contribution(value, mixture, &PILOT, scaling);
            match scaling {
                Scaling::LightTracing => {
                    let r = counts.light_ratio / PILOT.light_ratio;
                    self.direct[pixel * nc + c] += x * x * r;
                }
                Scaling::Merge => {
                    let y = x * counts.light_ratio / PILOT.light_ratio;
                    self.sample_value[c] += y;
                    self.sample_merge_sq[c] += y * y;
                }
                _ => self.sample_value[c] += x,
            }
        }
    }

    pub(super) fn add(
        &mut self,
        pixel: usize,
        weight: f64,
        value: f64,
        mixture: &Mixture,
        merge: bool,
    ) {
        let c = self.candidates.len();
        for (i, counts) in self.candidates.iter().enumerate() {
            let term = counts.second_moment_term(weight, value, mixture, &PILOT);
            if term.is_infinite() {
                self.missed[pixel * c + i] += weight * value;
            } else {
                self.moments[pixel * c + i] += term;
            }
            if !counts.merging {
                // Missed light is counted above, from every sample.
                let term = counts.second_moment_term_without_merges(value, mixture, &PILOT, merge);
                if term.is_finite() {
                    self.moments_unmerged[pixel * (c / 2) + i / 2] += term;
                }
            }
        }
    }
}

fn channel_mean(c: Color) -> f64 {
    (c.x as f64 + c.y as f64 + c.z as f64) / 3.0
}

impl Recorder for Probe {
    const ACTIVE: bool = true;

    fn mixture(&mut self, m: Mixture) {
        self.pending = Some(m);
    }

    fn begin_sample(&mut self, pixel: u64, film_weight: f32) {
        self.flush();
        self.pixel = pixel as usize;
        self.film_weight = film_weight as f64;
    }

    fn completed(&mut self, p: Completed) {
        let Some(m) = self.pending.take() else {
            return;
        };
        let light_tracing = p.s >= 1 && p.camera.len() == 1;
        let value = channel_mean(p.value) * if light_tracing { 1.0 } else { self.film_weight };
        let pixel = pixel_of(p.raster, self.width, self.height);
        self.add(pixel, p.weight, value, &m, false);
        self.add_direct(pixel, value, &m, Scaling::of(p.s, p.camera.len(), false));
    }

    fn merged(&mut self, p: Merged) {
        let Some(m) = self.pending.take() else {
            return;
        };
        let value = channel_mean(p.value) * self.film_weight;
        let pixel = pixel_of(p.raster, self.width, self.height);
        self.merges_found[pixel] += 1;
        self.add(pixel, p.weight, value, &m, true);
        self.add_direct(pixel, value, &m, Scaling::Merge);
        // Merging's bias: + outside r/√2, − inside (kept there twice), per merging candidate.
        let (Some(y), Some(x)) = (p.light.last(), p.camera.last()) else {
            return;
        };
        let radius = p.radius as f64;
        let inner = (y.p - x.p).length_squared() as f64 * 2.0 < radius * radius;
        let sign = if inner { -1.0 } else { 1.0 };
        let g_count = self.candidates.len() / 2;
        for g in 0..g_count {
            let w = self.candidates[2 * g].merge_weight(&m, &PILOT);
            let term = sign * w * value * self.bias_scale;
            self.bias_diff[pixel * g_count + g] += term;
            self.bias_terms_sq[pixel * g_count + g] += term * term;
        }
    }

    fn lap(&mut self, work: Work) {
        match work {
            Work::CameraWalk => self.camera_samples += 1,
            Work::Connection { t: 1, .. } => self.light_tracing += 1,
            Work::Connection { s: 0, .. } => {}
            Work::Connection { s: 1, .. } => self.shadow_rays_fixed += 1,
            Work::Connection { .. } => self.vertex_connections += 1,
            Work::Merge { .. } => self.merge_queries[self.pixel] += 1,
            // eamis runs vcm, which has no volumetric merges.
            Work::LightWalk | Work::VolumeMerge { .. } => {}
        }
    }
}

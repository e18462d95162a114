//! `eamis` — efficiency-aware MIS over VCM's techniques (Grittmann, Yazici, Georgiev & Slusallek,
//! SIGGRAPH 2022): a pilot of `pilot_passes` VCM passes (one light subpath per pixel, every
//! technique) predicts, per pixel, the variance every candidate configuration would have
//! (`Counts::contribution` in `lt_core::path::efficiency`), and counts what each would cost; the
//! rest of the run renders with the configuration of least predicted inefficiency (relative
//! variance × cost):
//!
//! - the light subpath count M ∈ {¼, ½, 1, 2} × the pixel count (global),
//! - vertex connections s ≥ 2, t ≥ 2 on or off (global; next-event estimation and light tracing
//!   always run),
//! - merging on or off **per pixel**: η counts in the pixel a path lands in, 0 where it is off.
//!
//! Every weight comes from the full path's densities (`connect_merge`'s full-path route), so the
//! per-pixel η is exact. The pilot passes are left out of the image once a pass has rendered
//! with the choice (`keep_pilot` keeps them): they are full VCM passes, and on veach-bidir their
//! merging's fireflies and bias made most of eamis's error (results/eamis.md). The choice is a
//! function of the pilot's samples alone and the later passes are independent of them, so the
//! estimator stays consistent, and unbiased wherever merging is off. The pilot runs on one
//! thread (its sums then do not depend on the thread count) and the cost is counted, not timed,
//! so the same seed gives the same choice and the same image bit for bit.
//!
//! **Cost model**: the pilot counts camera samples, next-event shadow rays (one per connectable
//! camera vertex), vertex connections, light vertices, light-tracing joins, merge queries and
//! light vertices found per pixel, and weighs them with unit costs measured once on this machine
//! (`COST_*`, results/eamis.md): a count, not a clock, so the choice is deterministic. Light
//! vertices, light tracing and merges found scale with M. The unit costs are one scene's: even
//! a set fitted to four scenes (with a free scale per scene) predicts their renders' CPU time
//! only within 0.84–1.14×, so configurations predicted within ~1.15× of each other are a
//! toss-up.
//!
//! **The variance, from the pilot's own samples.** Each pilot sample's value under every
//! candidate c is f/q_c (the balance heuristic's, merges counted with c's η); a camera sample's
//! values are summed before squaring, so the correlation between the techniques of one camera
//! path and between the merges around one camera vertex is in the square. Light tracing and
//! merging draw on M_c = r_c M_pilot light paths: light tracing's squares count r_c times; a
//! camera sample's merges are scaled by r_c, and the squares of the scaled values count 1/r_c
//! times (`Probe::direct`). μ² is taken out with the neighbours' samples (`direct_variance`). The paper's independent-sample second moment, ∫ f²/q_c, which
//! this replaced, drops those cross terms (it is Var + Σ_u μ_u²/n_u, not Var + μ²) and made
//! second moment × cost rank by cost where μ² dominates (caustic-sds; results/eamis.md). It is
//! still computed: its ratio to the pilot's measured moment, κ, floors merging's variance
//! (`local_merge_correlation`), where one pass sees too few clumps of merges to trust.
//!
//! **Merging's bias.** Variances alone favour merging where it is biased (Bitterli's
//! veach-bidir: 16× the best fixed configuration's inefficiency). The pilot therefore also
//! estimates each pixel's merging bias at the initial radius r₀ from its own merges: with a disk
//! kernel, the estimate at r/√2 keeps the merges within r/√2 at twice their value, and where the
//! blurred density is smooth the bias grows as r² (Knaus & Zwicker 2011, §4.2), so
//! b(r) = 2 (F(r) − F(r/√2)), each merge adding w_c · v · (1 − 2·[d < r/√2]) under candidate c's
//! own merge weight w_c (`Counts::merge_weight`). Per pixel, b² is estimated as the square of
//! that sum less the sum of its terms' squares (the terms' signs have mean 0 where the photon
//! density is smooth — half the disk's area lies within r/√2 — so their cross terms drop out),
//! then averaged over the pixel's 7 × 7 neighbourhood like the moments and clamped at 0. The
//! average keeps a small cluster's total: where merging leaks light through a thin wall
//! (veach-bidir's lamp shade, 1 % of the pixels and 90 % of vcm's relMSE) the window's mean of
//! differences would shrink it by the window's area. Over a render of
//! P passes (`ProgressiveRun::plan`, else `DEFAULT_HORIZON`) whose radius shrinks as
//! r_i² = r₀² i^(α−1), the image's bias is b₀ s(P), s(P) = (1/P) Σ_{i≤P} i^(α−1), so a merging
//! pixel's per-pass moment becomes κ V + P s(P)² b₀²: the inefficiency of the whole render,
//! relMSE × time, divided by P.
//!
//! **Light a configuration misses, and heavy tails.** A pilot sample whose path no technique of
//! a candidate makes (q_c = 0: a caustic seen in a mirror, without merging) is light that
//! candidate misses in every pass, a bias: it adds P b² to the pixel's moment. Such light seen
//! in one pixel is likely in the pixels around it that one pass did not sample, so every pixel
//! within `MUST_MERGE_REACH` of one merges. Without merging, a pixel's variance gains the
//! independent-sample moment the merges add (`Counts::second_moment_term` less
//! `Counts::second_moment_term_without_merges`): merges are the better witnesses of light the
//! other techniques find rarely, a heavy tail one pass does not show in their own samples
//! (caustic-sds). Not where merging's bias is predicted to outweigh its variance: there a merge
//! witnesses a blurred integrand.
//!
//! **Which pixels matter.** The image's inefficiency is Σ_p V_p / (μ̃_p + 0.01)² × cost, the
//! relative variance (pbrt's relMSE guard; μ̃_p the median of the pilot's estimate over the pixel
//! and its 8 neighbours, `relative_weights`) summed over pixels, each pixel's relative terms
//! averaged over its 7 × 7 window (`relative_window`): the merge mask is the prefix, by variance
//! saved per cost added, that minimises it; the global choice the candidate whose best mask
//! minimises it. The choice and the predicted inefficiency of every candidate (per pixel mean,
//! per pass) go to the JSON record, and the merge mask to `OUT.merge-mask.exr` beside
//! `lt render`'s output (1 where the pixel merges).
//!
//! | key | type | default | meaning |
//! |---|---|---|---|
//! | `max_depth` | u32 | scene `[render] max_depth` (8) | longest path in segments, camera ray included |
//! | `rr_depth` | u32 | scene `[render] rr_depth` (5) | Russian roulette from this many segments on |
//! | `mis` | power/balance/none | balance | heuristic (the prediction is the balance heuristic's) |
//! | `pilot_passes` | u32 | 1 | passes of the pilot (all techniques) before the choice |
//! | `keep_pilot` | true/false | false | the pilot passes' image joins the estimate (else only the passes after the choice count, once there is one) |
//! | `fixed` | m0.25_vc1_merge/m0.25_vc1_nomerge/m0.25_vc0_merge/m0.25_vc0_nomerge/m0.5_vc1_merge/m0.5_vc1_nomerge/m0.5_vc0_merge/m0.5_vc0_nomerge/m1_vc1_merge/m1_vc1_nomerge/m1_vc0_merge/m1_vc0_nomerge/m2_vc1_merge/m2_vc1_nomerge/m2_vc0_merge/m2_vc0_nomerge | — | no pilot: render every pass with one candidate, m(M per pixel)_vc(vertex connections)_(merge or not everywhere): the fixed configurations the choice is measured against |
//! | `radius_px` | f32 | 2 | initial radius in pixel footprints at the mean primary-hit distance |
//! | `radius_scene` | f32 | — | initial radius as a fraction of the scene's bounding-sphere diameter |
//! | `radius` | f32 | — | initial radius in scene units |
//! | `alpha` | f64 | 0.75 | radius reduction α: rᵢ = r₀ i^((α−1)/2) |
//!
//! The light subpath count and vertex connections are the choice's, so they are not keys;
//! correlation-aware weights are not offered (the prediction counts merges from η weights).

use crate::params::ParamReader;
use crate::record::{Completed, Merged, Recorder, Work};
use crate::vcm::engine::{pixel_of, MergeMask, Run, VcmParams};
use crate::{ProgressLog, Progressive, ProgressiveRun};
use lt_core::math::Color;
use lt_core::path::camis::Mixture;
use lt_core::path::efficiency::{Counts, Scaling};
use lt_core::path::Heuristic;
use lt_core::Scene;
use lt_estimators::metrics::REL_MSE_GUARD;
use lt_estimators::Image;
use std::sync::Arc;

/// The render length the bias is weighed over when the caller does not say
/// (`ProgressiveRun::plan`).
pub const DEFAULT_HORIZON: u32 = 16;

/// Light subpaths per pixel the choice ranges over.
pub const LIGHT_RATIOS: [f64; 4] = [0.25, 0.5, 1.0, 2.0];
/// The cost model's unit costs, in units of 200 ns of one core of this machine, from one-thread
/// renders of `cornell-box` at 128 px with each `fixed` candidate (results/eamis.md): a camera
/// sample, and per connectable camera vertex its extension and its next-event shadow ray.
pub const COST_CAMERA: f64 = 0.97;
/// A vertex connection (shadow ray and two BSDF evaluations, full-path weight).
pub const COST_VERTEX_CONNECTION: f64 = 0.45;
/// A light vertex traced and stored, or one joined to the lens (light tracing).
pub const COST_LIGHT: f64 = 1.25;
/// A merge query (the grid lookup).
pub const COST_QUERY: f64 = 0.5;
/// A light vertex found in range (BSDF evaluation and full-path weight).
pub const COST_MERGE: f64 = 1.2;

pub struct Eamis {
    pub params: VcmParams,
    pub pilot_passes: u32,
    /// Whether the pilot passes' own image joins the estimate.
    pub keep_pilot: bool,
    /// A candidate rendered without pilot or choice.
    pub fixed: Option<Counts>,
}

/// The label of a candidate with merging everywhere or nowhere, as the record and `fixed` name it.
pub fn label(c: &Counts) -> String {
    format!(
        "m{}_vc{}_{}",
        c.light_ratio,
        u8::from(c.vertex_connections),
        if c.merging { "merge" } else { "nomerge" }
    )
}

/// Every candidate with merging everywhere or nowhere.
pub fn fixed_candidates() -> Vec<Counts> {
    globals()
        .into_iter()
        .flat_map(|(light_ratio, vertex_connections)| {
            [true, false].map(|merging| Counts {
                light_ratio,
                vertex_connections,
                merging,
            })
        })
        .collect()
}

impl Eamis {
    pub fn read(scene: &Scene, r: &ParamReader) -> Result<Eamis, String> {
        // The pilot's configuration; the choice sets light paths, connections and merging.
        let params = VcmParams::read_base(scene, r, "eamis", Heuristic::Balance)?;
        let pilot_passes = r.get::<u32>("pilot_passes")?.unwrap_or(1);
        if pilot_passes == 0 {
            return Err("eamis: pilot_passes must be at least 1".into());
        }
        let fixed = match r.get::<String>("fixed")? {
            None => None,
            Some(name) => Some(
                fixed_candidates()
                    .into_iter()
                    .find(|c| label(c) == name)
                    .ok_or_else(|| {
                        let known: Vec<String> = fixed_candidates().iter().map(label).collect();
                        format!(
                            "eamis: unknown fixed = '{name}' (known: {})",
                            known.join(", ")
                        )
                    })?,
            ),
        };
        let keep_pilot = r.get::<bool>("keep_pilot")?.unwrap_or(false);
        Ok(Eamis {
            params,
            pilot_passes,
            keep_pilot,
            fixed,
        })
    }
}

impl Progressive for Eamis {
    fn name(&self) -> &'static str {
        "eamis"
    }

    fn start<'a>(&'a self, scene: &'a Scene, seed: u64) -> Box<dyn ProgressiveRun + 'a> {
        let n = scene.camera.pixel_count();
        let all: MergeMask = vec![true; n].into();
        let mut run = EamisRun {
            eamis: self,
            scene,
            seed,
            pilot: Run::new(&self.params, scene, seed).with_merge_mask(all.clone()),
            probe: Probe::new(scene),
            render: None,
            choice: None,
            pilot_cpu: 0.0,
            horizon: DEFAULT_HORIZON,
        };
        if let Some(counts) = self.fixed {
            let mask = if counts.merging {
                all
            } else {
                vec![false; n].into()
            };
            run.start_render(Choice {
                counts,
                merge_mask: mask,
                predicted: f64::NAN,
                fixed: Vec::new(),
                direct_over_independent: f64::NAN,
                merge_correlation: f64::NAN,
                merge_correlation_median: f64::NAN,
                bias_share: f64::NAN,
                must_merge: f64::NAN,
            });
        }
        Box::new(run)
    }
}

/// One configuration the choice ranges over, and what it predicts.
#[derive(Clone, Debug)]
pub struct Choice {
    pub counts: Counts,
    /// Pixels that merge.
    pub merge_mask: MergeMask,
    /// Σ_p relative variance per pass × cost per pass (units of `COST_*`), per pixel.
    pub predicted: f64,
    /// Every global candidate with merging everywhere and nowhere: (label, predicted).
    pub fixed: Vec<(String, f64)>,
    /// The pilot configuration's direct variance over its independent-sample moment, relative
    /// and summed over pixels: how much of that model's moment was variance.
    pub direct_over_independent: f64,
    /// κ, the pilot's measured second moment over its independent-sample one (`merge_correlation`).
    pub merge_correlation: f64,
    /// The median over pixels of κ per pixel (`local_merge_correlation`).
    pub merge_correlation_median: f64,
    /// The share of merging's bias in the pilot configuration's predicted inefficiency over the
    /// horizon (0 … 1).
    pub bias_share: f64,
    /// The share of pixels that must merge (within `MUST_MERGE_REACH` of light only merging
    /// found).
    pub must_merge: f64,
}

struct EamisRun<'a> {
    eamis: &'a Eamis,
    scene: &'a Scene,
    seed: u64,
    pilot: Run<'a>,
    probe: Probe,
    render: Option<Run<'a>>,
    choice: Option<Choice>,
    /// CPU seconds the pilot passes took (the record's; nothing rendered depends on it).
    pilot_cpu: f64,
    /// The passes the caller means to run, over which merging's bias is weighed.
    horizon: u32,
}

impl EamisRun<'_> {
    /// Every further pass renders with `choice`.
    fn start_render(&mut self, choice: Choice) {
        let mut params = self.eamis.params;
        let n = self.scene.camera.pixel_count() as f64;
        params.light_paths = Some(((choice.counts.light_ratio * n).round() as u64).max(1));
        params.vertex_connections = choice.counts.vertex_connections;
        params.merging = choice.merge_mask.iter().any(|&m| m);
        let run = Run::new(&params, self.scene, self.seed);
        self.render = Some(if params.merging {
            run.with_merge_mask(choice.merge_mask.clone())
        } else {
            run
        });
        self.choice = Some(choice);
    }
}

impl ProgressiveRun for EamisRun<'_> {
    fn pass(&mut self, pass: u32) -> u64 {
        if let Some(render) = &mut self.render {
            return render.pass(pass);
        }
        let cpu0 = crate::record::tally::pool_cpu_seconds();
        self.probe.bias_scale = 1.0 / self.eamis.params.radius_scale(pass).powi(2);
        let invalid = self.pilot.recorded_pass(pass, &mut self.probe);
        self.probe.flush();
        self.probe.light_vertices += self.pilot.stored_light_vertices() as u64;
        if self.pilot.sum().1 >= self.eamis.pilot_passes {
            let horizon = Horizon {
                passes: self.horizon.max(self.eamis.pilot_passes),
                alpha: self.eamis.params.alpha,
                pilot_passes: self.eamis.pilot_passes,
            };
            let choice = choose(&self.probe, &self.pilot.estimate(), &horizon);
            self.start_render(choice);
        }
        // The choice is overhead too: it is counted with the pilot.
        self.pilot_cpu += crate::record::tally::pool_cpu_seconds() - cpu0;
        invalid
    }

    fn plan(&mut self, passes: u32) {
        self.horizon = passes;
    }

    fn estimate(&self) -> Image {
        let rendered = self.render.as_ref().is_some_and(|r| r.sum().1 > 0);
        if rendered && !self.eamis.keep_pilot {
            return self.render.as_ref().expect("rendered").estimate();
        }
        let (sum, passes) = self.pilot.sum();
        let mut img = sum.clone();
        let mut total = passes;
        if let Some(render) = &self.render {
            let (s, p) = render.sum();
            for (a, b) in img.data.iter_mut().zip(&s.data) {
                for c in 0..3 {
                    a[c] += b[c];
                }
            }
            total += p;
        }
        let k = 1.0 / total.max(1) as f64;
        img.data
            .iter_mut()
            .for_each(|p| p.iter_mut().for_each(|c| *c *= k));
        img
    }

    fn log(&self) -> ProgressLog {
        let mut log = self.pilot.log();
        if let Some(render) = &self.render {
            let r = render.log();
            log.photon_paths.extend(r.photon_paths);
            log.radius_scale.extend(r.radius_scale);
            log.mean_radius.extend(r.mean_radius);
        }
        if let Some(c) = &self.choice {
            let merging = c.merge_mask.iter().filter(|&&m| m).count();
            let facts = [
                ("eamis_light_ratio", format!("{}", c.counts.light_ratio)),
                (
                    "eamis_vertex_connections",
                    format!("{}", c.counts.vertex_connections),
                ),
                (
                    "eamis_merging_pixels",
                    format!("{:.4}", merging as f64 / c.merge_mask.len().max(1) as f64),
                ),
                ("eamis_predicted", format!("{:.6e}", c.predicted)),
                (
                    "eamis_direct_over_independent",
                    format!("{:.4}", c.direct_over_independent),
                ),
                (
                    "eamis_merge_correlation",
                    format!("{:.4}", c.merge_correlation),
                ),
                (
                    "eamis_merge_correlation_median",
                    format!("{:.4}", c.merge_correlation_median),
                ),
                ("eamis_merge_bias_share", format!("{:.4}", c.bias_share)),
                ("eamis_must_merge_pixels", format!("{:.4}", c.must_merge)),
                ("eamis_horizon_passes", format!("{}", self.horizon)),
                ("eamis_pilot_cpu_seconds", format!("{:.6}", self.pilot_cpu)),
                ("eamis_pilot_passes", format!("{}", self.pilot.sum().1)),
            ];
            log.facts
                .extend(facts.into_iter().map(|(k, v)| (k.to_string(), v)));
            let p = &self.probe;
            let counted = [
                ("camera_samples", p.camera_samples),
                ("nee_rays", p.shadow_rays_fixed),
                ("vertex_connections", p.vertex_connections),
                ("light_tracing_joins", p.light_tracing),
                ("light_vertices", p.light_vertices),
                ("merge_queries", p.merge_queries.iter().sum()),
                ("merges_found", p.merges_found.iter().sum()),
            ];
            for (k, v) in counted {
                log.facts.push((format!("eamis_pilot_{k}"), v.to_string()));
            }
            for (label, p) in &c.fixed {
                log.facts
                    .push((format!("eamis_predicted_{label}"), format!("{p:.6e}")));
            }
            let (w, h) = (self.probe.width, self.probe.height);
            let mut mask = Image::new(w as usize, h as usize);
            for (px, &m) in mask.data.iter_mut().zip(c.merge_mask.iter()) {
                *px = [if m { 1.0 } else { 0.0 }; 3];
            }
            log.images.push(("merge-mask".to_string(), mask));
        }
        log
    }
}

/// The pilot's pilot configuration: one light subpath per pixel, every technique.
const PILOT: Counts = Counts {
    light_ratio: 1.0,
    vertex_connections: true,
    merging: true,
};

/// The global candidates (M, vertex connections), each rendered with merging on (`2g`) or off
/// (`2g + 1`) in a pixel.
fn globals() -> Vec<(f64, bool)> {
    LIGHT_RATIOS
        .iter()
        .flat_map(|&r| [(r, true), (r, false)])
        .collect()
}

/// What the pilot gathers: per pixel and candidate the second-moment sums, per pixel the merge
/// work, and the counts of the rest of the work.
struct Probe {
    width: u32,
    height: u32,
    candidates: Vec<Counts>,
    /// moments[pixel × candidates + c].
    moments: Vec<f64>,
    /// moments_unmerged[pixel × globals + g]: the moment of global g without merging from the
    /// pilot's samples that are not merges (`Counts::second_moment_term_without_merges`).
    moments_unmerged: Vec<f64>,
    /// The same layout: the pilot's weighted light that candidate c makes no path for (q_c = 0:
    /// a caustic seen in a mirror, without merging), summed over the pilot passes.
    missed: Vec<f64>,
    merge_queries: Vec<u64>,
    merges_found: Vec<u64>,
    camera_samples: u64,
    shadow_rays_fixed: u64,
    vertex_connections: u64,
    light_tracing: u64,
    light_vertices: u64,
    /// The mixture of the path about to be reported.
    pending: Option<Mixture>,
    pixel: usize,
    film_weight: f64,
    /// direct[pixel × candidates + c]: Σ over the pilot's camera samples of the square of the
    /// value c would have got from it (`Counts::contribution` summed over its samples, so the
    /// correlation between its techniques and between its merges is in it); plus each
    /// light-tracing splat's square × r_c. c draws r_c = M_c/M_pilot times the pilot's light
    /// paths: it makes r_c splats for each of the pilot's, and r_c merges of the same mean for
    /// each, so a merge's value is scaled by r_c, and the squares of those scaled values, the
    /// part of the variance from independent light paths, count 1/r_c times (r_c² from the
    /// scaling, over r_c as many paths): (1/r_c − 1) × their sum is added.
    direct: Vec<f64>,
    /// The same layout: Σ over camera samples of that value (its mean's estimate).
    direct_sum: Vec<f64>,
    /// Per candidate, the value of the camera sample under way and its merges' squares.
    sample_value: Vec<f64>,
    sample_merge_sq: Vec<f64>,
    /// bias_diff[pixel × globals + g]: Σ over the pilot's merges of w_c v (1 − 2·[d < r/√2]) ×
    /// `bias_scale`, c the merging candidate of global g: half of merging's bias at r₀, summed
    /// over the pilot passes.
    bias_diff: Vec<f64>,
    /// The same layout: Σ of the terms' squares (the differences' sampling variance).
    bias_terms_sq: Vec<f64>,
    /// (r₀ / r_pass)² of the pass under way: brings each pass's difference to r₀.
    bias_scale: f64,
}

impl Probe {
    fn new(scene: &Scene) -> Probe {
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
    fn flush(&mut self) {
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
    fn add_direct(&mut self, pixel: usize, value: f64, mixture: &Mixture, scaling: Scaling) {
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

    fn add(&mut self, pixel: usize, weight: f64, value: f64, mixture: &Mixture, merge: bool) {
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
            Work::LightWalk => {}
        }
    }
}

/// Per pixel and candidate, the variance per pass of the value the candidate would get, from
/// the pilot's own samples (`Probe::direct`): each pixel's square less its value times its 8
/// neighbours' mean, averaged over the pixel's window as relative values (`relative_window`),
/// clamped at 0.
///
/// The independent-sample model, M(c) = ∫ f²/q_c, drops the cross terms between techniques: it
/// is Var + Σ_u μ_u²/n_u, not Var + μ², and on cornell-box it fell below μ² altogether. How the
/// mean is split between techniques changes with the configuration, so second moment × cost
/// ranked configurations by that split and by cost as much as by their variance (caustic-sds,
/// where μ² is most of every candidate's second moment; results/eamis.md). Merges around one
/// camera vertex share its prefix and the techniques of one camera path are correlated: summing
/// a camera sample's values before squaring keeps both.
fn direct_variance(probe: &Probe, per_pass: f64, rel: &[f64]) -> Vec<f64> {
    let (w, h) = (probe.width as usize, probe.height as usize);
    let nc = probe.candidates.len();
    let mean = |p: usize, c: usize| probe.direct_sum[p * nc + c] * per_pass;
    // x_p² − x_p x̄_q, x̄_q the mean of the 8 neighbours' (independent) samples: an estimate of
    // E[x²] − μ_p μ_q that a pixel's single sample cannot give of μ_p²; only the local gradient
    // of μ is left in it, not the window's spread of μ (the lamp's edge on cornell-box).
    let mut raw = vec![0.0; w * h * nc];
    let mut around = vec![0.0; nc];
    for y in 0..h {
        for x in 0..w {
            let p = y * w + x;
            around.fill(0.0);
            let mut count = 0usize;
            for ny in span(y, h, 1) {
                for nx in span(x, w, 1) {
                    let q = ny * w + nx;
                    if q != p {
                        count += 1;
                        around
                            .iter_mut()
                            .enumerate()
                            .for_each(|(c, a)| *a += mean(q, c));
                    }
                }
            }
            let k = 1.0 / count.max(1) as f64;
            for (c, a) in around.iter().enumerate() {
                raw[p * nc + c] = probe.direct[p * nc + c] * per_pass - mean(p, c) * (a * k);
            }
        }
    }
    let mut out = relative_window(&raw, nc, w, h, rel);
    out.iter_mut().for_each(|v| *v = v.max(0.0));
    out
}

/// κ = Σ_p rel_p · measured_p / Σ_p rel_p · predicted_p for the pilot's own configuration
/// (candidate `own`, which merges everywhere): the pilot's second moment as measured (each camera
/// sample's contributions summed before squaring, `Probe::direct`) over the independent-sample
/// model's (`Probe::moments`). Merges around one camera vertex share its prefix, which the model
/// does not see and the measurement does.
fn merge_correlation(probe: &Probe, rel: &[f64], own: usize) -> f64 {
    let nc = probe.candidates.len();
    let (mut measured, mut predicted) = (0.0, 0.0);
    for (p, r) in rel.iter().enumerate() {
        measured += r * probe.direct[p * nc + own];
        predicted += r * probe.moments[p * nc + own];
    }
    if predicted > 0.0 && measured > 0.0 {
        measured / predicted
    } else {
        1.0
    }
}

/// κ per pixel: `merge_correlation`'s ratio over the pixel's (2 `KAPPA_REACH` + 1)²
/// neighbourhood, never below the image's κ (`kappa`). Every merging candidate's variance is
/// multiplied by it. The direct variance already holds the correlation the pilot saw, so this
/// is a guard, not a correction: where one camera sample's merges are strongly correlated, one
/// pilot pass sees few of the clumps that make merging's tail, and its variance is unreliable.
/// Without it, veach-bidir merged 8–17 % of its pixels again, on the glass egg where merging's
/// caustic is heavy-tailed; with it, 1 % (results/eamis.md). The image's κ alone, a ratio of
/// sums, is set by the few pixels a rare pilot sample inflated (veach-bidir: 1.4, where the
/// pixels' own ratios have median 8.8).
fn local_merge_correlation(probe: &Probe, kappa: f64, own: usize) -> Vec<f64> {
    let (w, h) = (probe.width as usize, probe.height as usize);
    let nc = probe.candidates.len();
    // Sums over the pilot passes: the ratio needs no per-pass scale.
    let measured: Vec<f64> = (0..w * h).map(|p| probe.direct[p * nc + own]).collect();
    let predicted: Vec<f64> = (0..w * h).map(|p| probe.moments[p * nc + own]).collect();
    let measured = box_filter(&measured, 1, w, h, KAPPA_REACH);
    let predicted = box_filter(&predicted, 1, w, h, KAPPA_REACH);
    measured
        .iter()
        .zip(&predicted)
        .map(|(&m, &q)| if q > 0.0 { (m / q).max(kappa) } else { kappa })
        .collect()
}

/// The window of the per-pixel κ reaches this many pixels each way: wider than the moments'
/// (`FILTER_REACH`), since κ is a ratio that changes slowly across the image and one pilot pass
/// gives one sample per pixel (veach-bidir, 4 seeds: reach 3 left one seed at 3.9× the relMSE of
/// m2_vc1_nomerge, reach 7 at 1.8×).
pub const KAPPA_REACH: usize = 7;

/// How much lower than merging everywhere or nowhere a per-pixel mask's predicted inefficiency
/// must be for eamis to use it. A one-pass pilot misjudges the pixels at a mask's edge both ways:
/// on caustic-sds it under-predicted heavy-tailed light where it turned merging off (relMSE 317
/// at a margin of 1), on veach-bidir merging's rare fireflies where it turned it on (a mask
/// predicted 1.3× better than merging nowhere measured 5× worse; results/eamis.md).
pub const MASK_MARGIN: f64 = 2.0;

/// The moments' box filter reaches this many pixels each way.
pub const FILTER_REACH: usize = 3;

/// Pixels within this many of one where the pilot found light only merging makes merge too.
pub const MUST_MERGE_REACH: usize = 4;

/// `mask` grown by `reach` pixels in x and y.
fn dilate(mask: &[bool], w: usize, h: usize, reach: usize) -> Vec<bool> {
    let mut out = vec![false; mask.len()];
    for y in 0..h {
        for x in 0..w {
            if !mask[y * w + x] {
                continue;
            }
            for ny in span(y, h, reach) {
                for nx in span(x, w, reach) {
                    out[ny * w + nx] = true;
                }
            }
        }
    }
    out
}

/// Indices within `reach` of `i` on an axis of `len`, clamped at its ends.
fn span(i: usize, len: usize, reach: usize) -> std::ops::Range<usize> {
    i.saturating_sub(reach)..(i + reach + 1).min(len)
}

/// Per-pixel rows of `nc` values averaged over each pixel's (2 `reach` + 1)² neighbourhood
/// (clamped at the film's edges), as two passes of 2 `reach` + 1 taps: along x, then along y.
fn box_filter(values: &[f64], nc: usize, w: usize, h: usize, reach: usize) -> Vec<f64> {
    let along_x = window_sums(values, nc, w, h, reach, true);
    let mut out = window_sums(&along_x, nc, w, h, reach, false);
    for y in 0..h {
        for x in 0..w {
            let count = (span(x, w, reach).len() * span(y, h, reach).len()) as f64;
            out[(y * w + x) * nc..(y * w + x + 1) * nc]
                .iter_mut()
                .for_each(|a| *a /= count);
        }
    }
    out
}

/// Per-pixel rows of `nc` values summed over the 2 `reach` + 1 pixels around each along one
/// axis (x when `along_x`, else y), clamped at the film's edges.
fn window_sums(
    values: &[f64],
    nc: usize,
    w: usize,
    h: usize,
    reach: usize,
    along_x: bool,
) -> Vec<f64> {
    let mut out = vec![0.0; values.len()];
    for y in 0..h {
        for x in 0..w {
            let row = &mut out[(y * w + x) * nc..(y * w + x + 1) * nc];
            let taps = if along_x {
                span(x, w, reach)
            } else {
                span(y, h, reach)
            };
            for t in taps {
                let q = if along_x { y * w + t } else { t * w + x };
                let src = &values[q * nc..(q + 1) * nc];
                row.iter_mut().zip(src).for_each(|(a, b)| *a += b);
            }
        }
    }
    out
}

/// Rows of `nc` per-pixel values averaged over each pixel's (2 `FILTER_REACH` + 1)² window as
/// relative values (each weighed by its own pixel's `rel`), then divided by the pixel's `rel`:
/// times `rel` again, a pixel gets its window's mean relative value. Averaging absolute values
/// instead weighed a bright pixel's μ² as its dark neighbours' (cornell-box: the lamp's edge
/// made the whole prediction; results/eamis.md).
fn relative_window(values: &[f64], nc: usize, w: usize, h: usize, rel: &[f64]) -> Vec<f64> {
    let scaled: Vec<f64> = values
        .iter()
        .enumerate()
        .map(|(i, v)| v * rel[i / nc])
        .collect();
    let mut out = box_filter(&scaled, nc, w, h, FILTER_REACH);
    out.iter_mut()
        .enumerate()
        .for_each(|(i, v)| *v /= rel[i / nc]);
    out
}

/// 1/(μ̃ + 0.01)² per pixel (pbrt's relMSE guard), μ̃ the median of the pilot's estimate over
/// the pixel and its 8 neighbours: one pilot sample per pixel is no estimate of the pixel's
/// value where rare light lands (caustic-sds: a pixel whose one sample found the caustic would
/// weigh its own moment by its firefly and call it small).
fn relative_weights(estimate: &Image, w: usize, h: usize) -> Vec<f64> {
    let mean = |p: usize| {
        let c = estimate.data[p];
        (c[0] + c[1] + c[2]) / 3.0
    };
    (0..w * h)
        .map(|p| {
            let (x, y) = (p % w, p / w);
            let (mut around, mut len) = ([0.0; 9], 0);
            for ny in span(y, h, 1) {
                for nx in span(x, w, 1) {
                    around[len] = mean(ny * w + nx);
                    len += 1;
                }
            }
            let around = &mut around[..len];
            around.sort_by(f64::total_cmp);
            let mu = around[len / 2];
            1.0 / (mu.max(0.0) + REL_MSE_GUARD).powi(2)
        })
        .collect()
}

/// The render the choice is made for: merging's bias weighs in over `passes`.
struct Horizon {
    passes: u32,
    alpha: f64,
    pilot_passes: u32,
}

impl Horizon {
    /// P s(P)², s(P) = (1/P) Σ_{i=1}^{P} i^(α−1): what b₀² adds to a merging pixel's per-pass
    /// moment when relMSE × time is divided by P (the module's doc).
    fn bias_factor(&self) -> f64 {
        let p = self.passes.max(1);
        let s = (1..=p)
            .map(|i| (i as f64).powf(self.alpha - 1.0))
            .sum::<f64>()
            / p as f64;
        p as f64 * s * s
    }
}

/// Per pixel and global candidate g, b₀² of merging at r₀: 4 × (the pilot's mean difference
/// squared less its sampling variance), averaged over the pixel's (2 `FILTER_REACH` + 1)²
/// neighbourhood and clamped at 0. Laid out as `Probe::bias_diff`.
fn merge_bias_squared(probe: &Probe, pilot_passes: u32, rel: &[f64]) -> Vec<f64> {
    let g_count = probe.candidates.len() / 2;
    let (w, h) = (probe.width as usize, probe.height as usize);
    let k = 1.0 / pilot_passes.max(1) as f64;
    let raw: Vec<f64> = probe
        .bias_diff
        .iter()
        .zip(&probe.bias_terms_sq)
        .map(|(d, sq)| 4.0 * ((d * k).powi(2) - sq * k * k))
        .collect();
    let mut out = relative_window(&raw, g_count, w, h, rel);
    out.iter_mut().for_each(|b| *b = b.max(0.0));
    out
}

/// The configuration of least predicted inefficiency from the pilot's `probe` and estimate.
fn choose(probe: &Probe, estimate: &Image, horizon: &Horizon) -> Choice {
    let n = estimate.data.len();
    let nc = probe.candidates.len();
    let (w, h) = (probe.width as usize, probe.height as usize);
    let rel = relative_weights(estimate, w, h);
    let fixed_work = COST_CAMERA * (probe.camera_samples + 2 * probe.shadow_rays_fixed) as f64;
    // Light a candidate makes no path for is a bias no pass removes: over the horizon's P passes
    // it adds P b² to the per-pass moment (b the light missed per pass). One pilot pass is one
    // sample per pixel: each pixel's moments are averaged over its 7 × 7 neighbourhood, which
    // keeps the total a rare path the pilot saw once adds and spreads it to the pixels around.
    // The probe's sums run over every pilot pass; the bias terms below are per pass, so the
    // moments are too.
    let per_pass = 1.0 / horizon.pilot_passes.max(1) as f64;
    // P b² of candidate c in pixel p.
    let missed_bias =
        |p: usize, c: usize| horizon.passes as f64 * (probe.missed[p * nc + c] * per_pass).powi(2);
    let missed: Vec<f64> = (0..n * nc).map(|i| missed_bias(i / nc, i % nc)).collect();
    let missed = relative_window(&missed, nc, w, h, &rel);
    let variance = direct_variance(probe, per_pass, &rel);
    // The independent-sample model's moments, from every pilot sample and (without merging,
    // global g's candidate 2g + 1) from the samples that are not merges: where merging is
    // unbiased, their difference is light the merges witness that the other techniques find
    // rarely — a heavy tail one pilot pass does not show in the techniques' own samples
    // (caustic-sds).
    let per_pass_sums = |v: &[f64], k: usize| {
        let scaled: Vec<f64> = v.iter().map(|m| m * per_pass).collect();
        relative_window(&scaled, k, w, h, &rel)
    };
    let independent = per_pass_sums(&probe.moments, nc);
    let independent_unmerged = per_pass_sums(&probe.moments_unmerged, nc / 2);
    // Light only merging reaches, seen by the pilot in one pixel, is likely in the pixels around
    // it that one pass did not sample (caustic-sds: a mask of the pixels the pilot saw it in
    // merged 7–10 % of the image and was 97× the best fixed configuration's inefficiency): every
    // pixel within `MUST_MERGE_REACH` of one merges, and merging nowhere is not an option.
    let only_merging: Vec<bool> = (0..n)
        .map(|p| (0..nc / 2).any(|g| probe.missed[p * nc + 2 * g + 1] != 0.0))
        .collect();
    let must_merge = dilate(&only_merging, w, h, MUST_MERGE_REACH);
    let any_must = must_merge.iter().any(|&m| m);
    let must_share = must_merge.iter().filter(|&&m| m).count() as f64 / n.max(1) as f64;
    let g_count = nc / 2;
    let bias2 = merge_bias_squared(probe, horizon.pilot_passes, &rel);
    let bias_factor = horizon.bias_factor();
    let pilot_g = globals()
        .iter()
        .position(|&(r, vc)| r == PILOT.light_ratio && vc == PILOT.vertex_connections)
        .unwrap_or(0);
    // The pilot's own candidate: global `pilot_g` with merging.
    let own = 2 * pilot_g;
    // Pixels where merging's predicted bias outweighs its variance: their merges witness a
    // blurred integrand, so they witness nothing for the configurations without merging.
    let bias_dominated: Vec<bool> = (0..n)
        .map(|p| bias_factor * bias2[p * g_count + pilot_g] > variance[p * nc + own])
        .collect();
    let bias_share = {
        let g = pilot_g;
        let bias: f64 = (0..n)
            .map(|p| bias_factor * bias2[p * g_count + g] * rel[p])
            .sum();
        let var: f64 = (0..n).map(|p| variance[p * nc + own] * rel[p]).sum();
        if bias + var > 0.0 {
            bias / (bias + var)
        } else {
            0.0
        }
    };
    let direct_over_independent = {
        let d: f64 = (0..n).map(|p| variance[p * nc + own] * rel[p]).sum();
        let i: f64 = (0..n).map(|p| independent[p * nc + own] * rel[p]).sum();
        d / i
    };
    // Merging's variance is floored by κ per pixel (`local_merge_correlation`), after the
    // comparisons above, which weigh the bias against the variance as the pilot measured it.
    let kappa = merge_correlation(probe, &rel, own);
    let kappa_at = local_merge_correlation(probe, kappa, own);
    let kappa_median = {
        let mut sorted = kappa_at.clone();
        sorted.sort_by(f64::total_cmp);
        sorted.get(sorted.len() / 2).copied().unwrap_or(kappa)
    };
    let mut variance = variance;
    for (p, k) in kappa_at.iter().enumerate() {
        for g in 0..g_count {
            variance[p * nc + 2 * g] *= k;
        }
    }
    // Index of candidate c in pixel p.
    let p_c = |c: usize| move |p: usize| p * nc + c;
    let mut best: Option<Choice> = None;
    let mut fixed = Vec::new();
    for (g, (ratio, vc)) in globals().into_iter().enumerate() {
        let cost0 = fixed_work
            + COST_LIGHT * ratio * (probe.light_vertices + probe.light_tracing) as f64
            + if vc {
                COST_VERTEX_CONNECTION * probe.vertex_connections as f64
            } else {
                0.0
            };
        let (on_c, off_c) = (p_c(2 * g), p_c(2 * g + 1));
        let on = |p: usize| {
            (variance[on_c(p)] + missed[on_c(p)] + bias_factor * bias2[p * g_count + g]) * rel[p]
        };
        let off = |p: usize| {
            let witnessed = if bias_dominated[p] {
                0.0
            } else {
                (independent[off_c(p)] - independent_unmerged[p * g_count + g]).max(0.0)
            };
            (variance[off_c(p)] + missed[off_c(p)] + witnessed) * rel[p]
        };
        let merge_cost = |p: usize| {
            COST_QUERY * probe.merge_queries[p] as f64
                + COST_MERGE * ratio * probe.merges_found[p] as f64
        };
        let all_on: f64 =
            (0..n).map(on).sum::<f64>() * (cost0 + (0..n).map(merge_cost).sum::<f64>());
        let all_off: f64 = (0..n).map(off).sum::<f64>() * cost0;
        fixed.push((label(&probe.candidates[2 * g]), all_on / n as f64));
        fixed.push((label(&probe.candidates[2 * g + 1]), all_off / n as f64));
        let mut v: f64 = (0..n)
            .map(|p| if must_merge[p] { on(p) } else { off(p) })
            .sum();
        let mut c = cost0
            + (0..n)
                .filter(|&p| must_merge[p])
                .map(merge_cost)
                .sum::<f64>();
        // Pixels where merging lowers the moment, by moment saved per cost added.
        let mut gain: Vec<(f64, usize)> = (0..n)
            .filter(|&p| !must_merge[p] && on(p) < off(p))
            .map(|p| ((off(p) - on(p)) / merge_cost(p).max(1e-9), p))
            .collect();
        gain.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let (mut best_j, mut best_len) = (v * c, 0);
        for (i, &(_, p)) in gain.iter().enumerate() {
            v -= off(p) - on(p);
            c += merge_cost(p);
            if v * c < best_j {
                best_j = v * c;
                best_len = i + 1;
            }
        }
        // The per-pixel mask must beat merging everywhere and nowhere by `MASK_MARGIN`: one pilot
        // pass misses rare, heavy-tailed light on either side of the mask's edge.
        let uniform = if any_must {
            all_on
        } else {
            all_on.min(all_off)
        };
        let use_mask = best_j * MASK_MARGIN < uniform;
        let (predicted, everywhere) = if use_mask {
            (best_j / n as f64, false)
        } else {
            (uniform / n as f64, any_must || all_on <= all_off)
        };
        if predicted.is_finite() && best.as_ref().is_none_or(|b| predicted < b.predicted) {
            let mut mask = vec![everywhere; n];
            if use_mask {
                for &(_, p) in &gain[..best_len] {
                    mask[p] = true;
                }
                for (m, &must) in mask.iter_mut().zip(&must_merge) {
                    *m |= must;
                }
            }
            let best_len = mask.iter().filter(|&&m| m).count();
            best = Some(Choice {
                counts: Counts {
                    light_ratio: ratio,
                    vertex_connections: vc,
                    merging: best_len > 0,
                },
                merge_mask: Arc::from(mask),
                predicted,
                fixed: Vec::new(),
                direct_over_independent,
                merge_correlation: kappa,
                merge_correlation_median: kappa_median,
                bias_share,
                must_merge: must_share,
            });
        }
    }
    // Every global candidate ruled out (light no candidate samples, e.g. a path only vertex
    // connections make): the pilot's own configuration, which runs every technique.
    let mut choice = best.unwrap_or_else(|| Choice {
        counts: PILOT,
        merge_mask: Arc::from(vec![true; n]),
        predicted: f64::INFINITY,
        fixed: Vec::new(),
        direct_over_independent,
        merge_correlation: kappa,
        merge_correlation_median: kappa_median,
        bias_share,
        must_merge: must_share,
    });
    choice.fixed = fixed;
    choice
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The separable filter against the window's mean summed directly; the tolerance is f64
    /// rounding of sums taken in another order, not a statistical one.
    #[test]
    fn box_filter_is_the_mean_over_the_clamped_window() {
        let (w, h, nc, reach) = (9, 7, 3, 2);
        let values: Vec<f64> = (0..w * h * nc)
            .map(|i| ((i * 7919) % 101) as f64 - 50.0)
            .collect();
        let got = box_filter(&values, nc, w, h, reach);
        for y in 0..h {
            for x in 0..w {
                for c in 0..nc {
                    let (mut sum, mut count) = (0.0, 0.0);
                    for ny in y.saturating_sub(reach)..(y + reach + 1).min(h) {
                        for nx in x.saturating_sub(reach)..(x + reach + 1).min(w) {
                            sum += values[(ny * w + nx) * nc + c];
                            count += 1.0;
                        }
                    }
                    let want = sum / count;
                    let have = got[(y * w + x) * nc + c];
                    assert!(
                        (have - want).abs() <= 1e-12 * want.abs().max(1.0),
                        "({x}, {y}) channel {c}: {have} against {want}"
                    );
                }
            }
        }
    }

    /// A pixel whose one pilot sample found a firefly keeps the relative weight of the value
    /// around it: the median of its 3 × 3 neighbourhood, not its own estimate.
    #[test]
    fn a_lone_firefly_does_not_set_its_pixels_relative_weight() {
        let (w, h) = (5, 4);
        let mut img = Image::new(w, h);
        img.data.iter_mut().for_each(|p| *p = [0.1; 3]);
        img.data[2 * w + 2] = [1000.0; 3];
        let rel = relative_weights(&img, w, h);
        let want = 1.0 / (0.1 + REL_MSE_GUARD).powi(2);
        for (p, r) in rel.iter().enumerate() {
            assert!(
                (r - want).abs() <= 1e-9 * want,
                "pixel {p}: {r} against {want}"
            );
        }
    }
}

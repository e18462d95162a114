//! `eamis` — efficiency-aware MIS over VCM's techniques (Grittmann, Yazici, Georgiev & Slusallek,
//! SIGGRAPH 2022): a pilot of `pilot_passes` VCM passes (one light subpath per pixel, every
//! technique) predicts, per pixel, the variance and the cost every candidate configuration would
//! have — the light subpath count M ∈ {¼, ½, 1, 2} × the pixel count and vertex connections on or
//! off (global), merging on or off per pixel — and the rest of the run renders with the one of
//! least predicted inefficiency (relative variance × cost, merging's bias over the render's
//! horizon added), every weight from the full path's densities (the VCM engine's full-path route),
//! so the per-pixel η is exact. The pilot runs on one thread and the cost is counted, not timed:
//! the same seed gives the same choice and the same image bit for bit.
//!
//! How the prediction works, and why (the variance from the pilot's own samples, the cost model,
//! merging's bias, light a configuration misses, which pixels matter): results/eamis.md, section
//! "How eamis predicts". `probe` is the pilot's recorder, `choice` the prediction and the choice.
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

pub mod choice;
pub mod probe;

use choice::{choose, Horizon};
use probe::{globals, Probe};

use crate::params::ParamReader;
use crate::vcm::engine::{MergeMask, Run, VcmParams};
use crate::{ProgressLog, Progressive, ProgressiveRun};
use lt_core::path::efficiency::Counts;
use lt_core::path::Heuristic;
use lt_core::Scene;
use lt_estimators::Image;

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

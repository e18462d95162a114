//! Metropolis light transport in primary sample space: `pssmlt` (Kelemen et al. 2002) over `pt`
//! or `bdpt`, and `mmlt` (Hachisuka, Kaplanyan & Dachsbacher 2014) over bdpt's strategies.
//!
//! The chains of a run share state across its passes, so the spread of passes is no error bar:
//! both are `Kind::Consistent`, and `--runs K` gives the independent-run standard error (each run
//! its own bootstrap, so the normalisation's error is in it). A pass advances every chain by
//! its share of N mutations (N = pixel count: one mutation per pixel per pass).
//!
//! Each pass's own luminance image (b̂ times its mean splat) goes to a batch-means accumulator
//! (`lt_estimators::batch_means`): the record gives ESS/P per pixel (P passes) — median and
//! 5 %/95 % quantiles over the pixels with light, `ess_*` facts — and `OUT.ess.exr`. A per-pass
//! error bar is too narrow by √(ESS/P).
//!
//! - `target`: u ↦ F(u), the base integrator's per-path code run on a chain's numbers;
//! - `strategy`: one bdpt strategy (s, t) alone, MMLT's state (walks of s and t vertices);
//! - `chain`: the chains, bootstrap, expected-value splats;
//! - `pssmlt`, `mmlt`: the two integrators (their key tables).

pub mod chain;
pub mod mmlt;
pub mod pssmlt;
pub mod strategy;
pub mod target;

use crate::params::ParamReader;
use crate::{ProgressLog, ProgressiveRun};
use chain::{ChainSet, Mutations};
use lt_core::Scene;
use lt_estimators::{BatchMeans, Ess, Image};
use target::Base;

/// Chain settings both integrators read.
#[derive(Clone, Copy, Debug)]
pub struct ChainParams {
    pub mutations: Mutations,
    /// Bootstrap points (per run; MMLT splits them over path lengths). `None`: the pixel count.
    pub bootstrap: Option<u64>,
    pub chains: u64,
}

impl ChainParams {
    pub fn read(r: &ParamReader) -> Result<ChainParams, String> {
        let p_large = r.get::<f32>("p_large")?.unwrap_or(0.3);
        if !(0.0..=1.0).contains(&p_large) {
            return Err(format!(
                "p_large = {p_large} is not a probability in [0, 1]"
            ));
        }
        let sigma = r.get::<f32>("sigma")?.unwrap_or(0.01);
        if !(sigma > 0.0 && sigma.is_finite()) {
            return Err(format!("sigma = {sigma} must be positive"));
        }
        let bootstrap = r.get::<u64>("bootstrap")?;
        if bootstrap == Some(0) {
            return Err("bootstrap must be at least 1".into());
        }
        let chains = r.get::<u64>("chains")?.unwrap_or(256);
        if chains == 0 {
            return Err("chains must be at least 1".into());
        }
        Ok(ChainParams {
            mutations: Mutations { p_large, sigma },
            bootstrap,
            chains,
        })
    }
}

/// One run: a chain set per restriction (one for PSSMLT, one per path length for MMLT), each
/// given a share of every pass's N mutations (MMLT: ∝ its b̂).
pub struct MetropolisRun<'a> {
    scene: &'a Scene,
    base: &'a Base,
    params: ChainParams,
    sets: Vec<ChainSet>,
    /// Mutations per chain per pass, per set.
    per_chain: Vec<u64>,
    bootstrap_invalid: u64,
    /// Every pass's luminance image, for the per-pixel effective sample size.
    batches: BatchMeans,
}

impl<'a> MetropolisRun<'a> {
    /// Starts the chains of bootstrapped `sets`: a pass's N mutations are shared ∝ b̂ of each
    /// set, over min(`chains`, its share) chains (at least one where b̂ > 0), so a small film or
    /// a dim path length does not pay for idle chains.
    fn new(
        scene: &'a Scene,
        base: &'a Base,
        params: ChainParams,
        mut sets: Vec<ChainSet>,
        bad: u64,
    ) -> Self {
        let n = scene.camera.pixel_count() as f64;
        let total_b: f64 = sets.iter().map(|s| s.b).sum();
        let mut per_chain = Vec::with_capacity(sets.len());
        for set in &mut sets {
            if !(set.b > 0.0 && total_b > 0.0) {
                per_chain.push(0);
                continue;
            }
            let share = (n * set.b / total_b).max(1.0);
            let chains = (params.chains as f64).min(share.round()).max(1.0);
            set.start_chains(base, scene, chains as u64);
            per_chain.push((share / chains).ceil() as u64);
        }
        MetropolisRun {
            scene,
            base,
            params,
            sets,
            per_chain,
            bootstrap_invalid: bad,
            batches: BatchMeans::new(scene.camera.pixel_count()),
        }
    }
}

impl ProgressiveRun for MetropolisRun<'_> {
    fn pass(&mut self, _pass: u32) -> u64 {
        let mut invalid = std::mem::take(&mut self.bootstrap_invalid);
        for (set, &m) in self.sets.iter_mut().zip(&self.per_chain) {
            invalid += set.advance(self.base, self.scene, m, self.params.mutations);
        }
        let mut pass = vec![0.0; self.scene.camera.pixel_count()];
        for (set, &m) in self.sets.iter().zip(&self.per_chain) {
            set.add_pass_luminance(m, &mut pass);
        }
        self.batches.add_pass(&pass);
        invalid
    }

    fn estimate(&self) -> Image {
        let cam = &self.scene.camera;
        let mut img = Image::new(cam.width as usize, cam.height as usize);
        for set in &self.sets {
            set.add_estimate(&mut img);
        }
        img
    }

    fn log(&self) -> ProgressLog {
        let b: f64 = self.sets.iter().map(|s| s.b).sum();
        let b_se = self
            .sets
            .iter()
            .map(|s| s.b_std_error.powi(2))
            .sum::<f64>()
            .sqrt();
        let mutations: u64 = self.sets.iter().map(|s| s.mutations).sum();
        let accepted: u64 = self.sets.iter().map(|s| s.accepted).sum();
        let mut facts = vec![
            ("b".to_string(), format!("{b:.6e}")),
            ("b_std_error".to_string(), format!("{b_se:.6e}")),
            ("mutations".to_string(), mutations.to_string()),
            (
                "acceptance".to_string(),
                format!("{:.4}", accepted as f64 / mutations.max(1) as f64),
            ),
        ];
        if self.sets.len() > 1 {
            for s in &self.sets {
                if let target::Restrict::Length(k) = s.restrict {
                    facts.push((
                        format!("b_k{k}"),
                        format!("{:.6e} ± {:.2e}", s.b, s.b_std_error),
                    ));
                }
            }
        }
        let mut images = Vec::new();
        if let Some(ess) = self.batches.ess() {
            facts.extend(ess_facts(&ess));
            let cam = &self.scene.camera;
            let mut img = Image::new(cam.width as usize, cam.height as usize);
            for (px, r) in img.data.iter_mut().zip(&ess.ratio) {
                *px = [r.unwrap_or(0.0); 3];
            }
            images.push(("ess".to_string(), img));
        }
        ProgressLog {
            facts,
            images,
            ..ProgressLog::default()
        }
    }
}

/// The record's ESS summary: ESS/P (P passes) over the pixels that have one, and the batches.
fn ess_facts(ess: &Ess) -> Vec<(String, String)> {
    let mut facts = vec![(
        "ess_batches".to_string(),
        format!("{} × {} passes", ess.batches, ess.batch_len),
    )];
    if let Some(s) = ess.summary() {
        facts.extend([
            (
                "ess_over_passes_median".to_string(),
                format!("{:.4}", s.median),
            ),
            ("ess_over_passes_q05".to_string(), format!("{:.4}", s.q05)),
            ("ess_over_passes_q95".to_string(), format!("{:.4}", s.q95)),
            ("ess_pixels".to_string(), s.pixels.to_string()),
        ]);
    }
    facts
}

/// The bootstrap size when the key is not set: one point per pixel (one pass's work).
fn bootstrap_size(scene: &Scene, p: &ChainParams) -> u64 {
    p.bootstrap
        .unwrap_or(scene.camera.pixel_count() as u64)
        .max(1)
}

//! One Markov chain in primary sample space and the set of chains that shares a normalisation.
//!
//! A chain's state u is distributed as I(u)/b at stationarity (b = ∫ I du), so for any splat
//! function F, E_π[F(u)/I(u)] = E_u[F]/b: the image is b times the mean of F/I over the chain's
//! states (Kelemen et al. 2002; Veach 1997, §11.3). Each mutation splats the proposal y with
//! weight a/I(y) and the current state x with (1 − a)/I(x), a = min(1, I(y)/I(x)) — the expected
//! value of the accept/reject step (Veach 1997, §11.5.1), whichever way the coin falls.
//!
//! b comes from a bootstrap of B independent uniform points (its mean I, its standard error
//! sd/√B); chains start at bootstrap points resampled ∝ I, so each starts at stationarity and no
//! start-up samples are discarded.

use super::target::{Base, LengthImportance, Restrict, Sample, Scratch};
use lt_core::math::luminance;
use lt_core::primary_space::PrimarySpace;
use lt_core::sampling::{Distribution1D, Sampler};
use lt_core::{Color, Scene};
use rayon::prelude::*;

/// Mutation settings shared by every chain of a run.
#[derive(Clone, Copy, Debug)]
pub struct Mutations {
    /// Probability of a large step (an independent proposal).
    pub p_large: f32,
    /// Standard deviation of a small step per coordinate.
    pub sigma: f32,
}

/// What makes a chain set's streams its own: the run's seed and the set's index (MMLT's path
/// length), so two sets' chains never share a number. The bootstrap points are keyed by
/// `bootstrap_set`: MMLT's lengths share one bootstrap (set 0; lengths are 1 …).
#[derive(Clone, Copy, Debug)]
pub struct Keys {
    pub seed: u64,
    pub set: u64,
    pub bootstrap_set: u64,
}

impl Keys {
    fn bootstrap(self, i: u64) -> u64 {
        (self.bootstrap_set << 48) | i
    }
    fn chain(self, j: u64) -> u64 {
        (self.set << 48) | (1 << 40) | j
    }
    fn start(self) -> u64 {
        (self.set << 48) | (2 << 40)
    }
    /// Bootstrap point i: a large step from iteration 0 on its own stream.
    fn bootstrap_point(self, i: u64, sigma: f32) -> PrimarySpace {
        let mut space = PrimarySpace::new(self.seed, self.bootstrap(i), sigma);
        space.start_iteration(true);
        space
    }
}

struct Chain {
    space: PrimarySpace,
    current: Sample,
}

/// Chains sampling one restriction of the base's contribution, with their normalisation and
/// their accumulated film.
pub struct ChainSet {
    pub restrict: Restrict,
    /// b̂ and its standard error from the bootstrap.
    pub b: f64,
    pub b_std_error: f64,
    keys: Keys,
    sigma: f32,
    /// The bootstrap's I values, until the chains start from them.
    weights: Vec<f32>,
    chains: Vec<Chain>,
    film: Vec<[f64; 3]>,
    /// Luminance of the splats of the latest `advance`, per pixel (its pass's share of the
    /// film, for the batch-means ESS).
    pass_luminance: Vec<f64>,
    /// Mutations done (over all chains) and accepted.
    pub mutations: u64,
    pub accepted: u64,
}

impl ChainSet {
    /// Runs the bootstrap of `bootstrap` uniform points: b̂ and its standard error, no chains
    /// yet (`start_chains`). Returns the set and the invalid values dropped.
    pub fn bootstrap(
        base: &Base,
        scene: &Scene,
        restrict: Restrict,
        bootstrap: u64,
        sigma: f32,
        keys: Keys,
    ) -> (ChainSet, u64) {
        // Evaluated in parallel, collected in index order.
        let weights: Vec<(f64, u64)> = (0..bootstrap)
            .into_par_iter()
            .map_init(
                || (base.scratch(scene), Sample::default()),
                |(scratch, sample), i| {
                    let mut space = keys.bootstrap_point(i, sigma);
                    let bad = base.evaluate(scene, restrict, &mut space, scratch, sample);
                    (sample.importance, bad)
                },
            )
            .collect();
        let invalid: u64 = weights.iter().map(|w| w.1).sum();
        let importance: Vec<f64> = weights.iter().map(|w| w.0).collect();
        let set = ChainSet::from_bootstrap(scene, restrict, &importance, &importance, sigma, keys);
        (set, invalid)
    }

    /// MMLT's bootstrap: `bootstrap` uniform points, each one pair of full walks giving I_k for
    /// every length k = 1 … `base.lengths()` (`Base::evaluate_lengths`), so each b̂_k averages
    /// all the points rather than its 1/lengths share, and b̂_k averages each point's sum over all
    /// strategies (`LengthImportance::all_strategies`), while chains start ∝ the picked
    /// strategy's I_k. Returns the sets (length k's keyed `set: k`) and the invalid values dropped.
    pub fn bootstrap_lengths(
        base: &Base,
        scene: &Scene,
        bootstrap: u64,
        sigma: f32,
        seed: u64,
    ) -> (Vec<ChainSet>, u64) {
        let lengths = base.lengths();
        let shared = Keys {
            seed,
            set: 0,
            bootstrap_set: 0,
        };
        let points: Vec<(Vec<LengthImportance>, u64)> = (0..bootstrap)
            .into_par_iter()
            .map_init(
                || base.scratch(scene),
                |scratch, i| {
                    let mut space = shared.bootstrap_point(i, sigma);
                    let mut importance = Vec::with_capacity(lengths);
                    let bad = base.evaluate_lengths(scene, &mut space, scratch, &mut importance);
                    (importance, bad)
                },
            )
            .collect();
        let invalid = points.iter().map(|p| p.1).sum();
        let sets = (1..=lengths)
            .map(|k| {
                let picked: Vec<f64> = points.iter().map(|p| p.0[k - 1].picked).collect();
                let all: Vec<f64> = points.iter().map(|p| p.0[k - 1].all_strategies).collect();
                let keys = Keys {
                    set: k as u64,
                    ..shared
                };
                ChainSet::from_bootstrap(scene, Restrict::Length(k), &picked, &all, sigma, keys)
            })
            .collect();
        (sets, invalid)
    }

    /// A set from its bootstrap: the chains start ∝ `importance` (each point's I), b̂ is the mean
    /// of `estimates` (I itself, or any estimator of it with the same mean per point), its
    /// standard error sd/√B.
    fn from_bootstrap(
        scene: &Scene,
        restrict: Restrict,
        importance: &[f64],
        estimates: &[f64],
        sigma: f32,
        keys: Keys,
    ) -> ChainSet {
        let n = estimates.len().max(1) as f64;
        let b = estimates.iter().sum::<f64>() / n;
        let var = estimates.iter().map(|w| (w - b).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
        ChainSet {
            restrict,
            b,
            b_std_error: (var / n).sqrt(),
            keys,
            sigma,
            weights: importance.iter().map(|&w| w as f32).collect(),
            chains: Vec::new(),
            film: vec![[0.0; 3]; scene.camera.pixel_count()],
            pass_luminance: vec![0.0; scene.camera.pixel_count()],
            mutations: 0,
            accepted: 0,
        }
    }

    /// Starts `chains` chains from bootstrap points resampled ∝ I (none when b̂ = 0).
    pub fn start_chains(&mut self, base: &Base, scene: &Scene, chains: u64) {
        let pick = Distribution1D::new(&self.weights);
        if !(self.b > 0.0) || pick.is_empty() {
            return;
        }
        let (keys, sigma, restrict) = (self.keys, self.sigma, self.restrict);
        let mut u = Sampler::new(keys.seed, keys.start(), 0);
        let starts: Vec<u64> = (0..chains)
            .map(|_| pick.sample(u.next_f32()).0 as u64)
            .collect();
        self.chains = starts
            .into_par_iter()
            .enumerate()
            .map_init(
                || base.scratch(scene),
                |scratch, (j, i)| {
                    // Replays bootstrap point i exactly, then mutates on the chain's own stream.
                    let mut space = keys.bootstrap_point(i, sigma);
                    let mut current = Sample::default();
                    base.evaluate_start(scene, restrict, &mut space, scratch, &mut current);
                    space.accept();
                    space.reseed(keys.seed, keys.chain(j as u64));
                    Chain { space, current }
                },
            )
            .collect();
        self.weights = Vec::new();
    }

    /// Advances every chain by `per_chain` mutations (in parallel) and adds their splats to the
    /// film in chain order. Returns the invalid values dropped.
    pub fn advance(
        &mut self,
        base: &Base,
        scene: &Scene,
        per_chain: u64,
        mutations: Mutations,
    ) -> u64 {
        let restrict = self.restrict;
        let results: Vec<(Vec<(u32, Color)>, u64, u64)> = self
            .chains
            .par_iter_mut()
            .map(|chain| {
                let mut scratch = base.scratch(scene);
                let mut proposal = Sample::default();
                let mut splats = Vec::new();
                let (mut accepted, mut invalid) = (0, 0);
                for _ in 0..per_chain {
                    let (acc, bad) = chain.mutate(
                        (base, scene, restrict),
                        mutations,
                        (&mut scratch, &mut proposal),
                        &mut splats,
                    );
                    accepted += acc as u64;
                    invalid += bad;
                }
                (splats, accepted, invalid)
            })
            .collect();
        let mut invalid = 0;
        self.pass_luminance.iter_mut().for_each(|v| *v = 0.0);
        for (splats, accepted, bad) in results {
            for (p, c) in splats {
                let px = &mut self.film[p as usize];
                px[0] += c.x as f64;
                px[1] += c.y as f64;
                px[2] += c.z as f64;
                self.pass_luminance[p as usize] += luminance(c) as f64;
            }
            self.accepted += accepted;
            invalid += bad;
        }
        self.mutations += per_chain * self.chains.len() as u64;
        invalid
    }

    /// The set's image so far: b times the mean splat per mutation.
    pub fn add_estimate(&self, image: &mut lt_estimators::Image) {
        if self.mutations == 0 {
            return;
        }
        let scale = self.b / self.mutations as f64;
        for (out, px) in image.data.iter_mut().zip(&self.film) {
            for c in 0..3 {
                out[c] += px[c] * scale;
            }
        }
    }

    /// The latest `advance` as an estimate of the image's luminance on its own: b times its mean
    /// splat per mutation, added to `out` (the passes' mean of these is `add_estimate`'s).
    pub fn add_pass_luminance(&self, per_chain: u64, out: &mut [f64]) {
        let done = per_chain * self.chains.len() as u64;
        if done == 0 {
            return;
        }
        let scale = self.b / done as f64;
        for (o, v) in out.iter_mut().zip(&self.pass_luminance) {
            *o += v * scale;
        }
    }

    pub fn chain_count(&self) -> usize {
        self.chains.len()
    }
}

impl Chain {
    /// One proposal, its expected-value splats, and the accept/reject step. Returns (accepted,
    /// invalid values dropped).
    fn mutate(
        &mut self,
        (base, scene, restrict): (&Base, &Scene, Restrict),
        m: Mutations,
        (scratch, proposal): (&mut Scratch, &mut Sample),
        splats: &mut Vec<(u32, Color)>,
    ) -> (bool, u64) {
        let large = self.space.uniform() < m.p_large;
        self.space.start_iteration(large);
        let invalid = base.evaluate(scene, restrict, &mut self.space, scratch, proposal);
        let (iy, ix) = (proposal.importance, self.current.importance);
        // The current state always has I > 0 (it started at a point of I > 0, and a = 0 keeps it).
        let a = if ix > 0.0 { (iy / ix).min(1.0) } else { 1.0 };
        if iy > 0.0 && a > 0.0 {
            let w = (a / iy) as f32;
            splats.extend(proposal.splats.iter().map(|&(p, c)| (p, c * w)));
        }
        if ix > 0.0 && a < 1.0 {
            let w = ((1.0 - a) / ix) as f32;
            splats.extend(self.current.splats.iter().map(|&(p, c)| (p, c * w)));
        }
        let accept = (self.space.uniform() as f64) < a;
        if accept {
            self.space.accept();
            std::mem::swap(&mut self.current, proposal);
        } else {
            self.space.reject();
        }
        (accept, invalid)
    }
}

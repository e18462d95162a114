//! Primary sample space for Metropolis light transport (Kelemen et al. 2002): a path is a function
//! of an infinite vector of uniform numbers, and a Markov chain mutates that vector instead of the
//! path. Coordinates are created and mutated lazily, as the path asks for them, so a chain pays
//! only for the dimensions its paths use:
//!
//! - a **large step** (probability p_large, chosen by the caller) replaces every coordinate by a
//!   fresh uniform number — an independent proposal;
//! - a **small step** moves a coordinate by a normal offset of standard deviation σ·√n, wrapped
//!   to [0, 1), where n is the number of small steps since the coordinate was last touched (the
//!   sum of the n offsets it missed: a sum of n independent N(0, σ²) is N(0, nσ²));
//! - a coordinate last touched before the latest large step is first redrawn uniformly (the large
//!   step replaced it, lazily).
//!
//! Coordinates are interleaved by stream (index = sample number · STREAMS + stream), so the camera
//! walk, the light walk and the rest each read their own sequence and a change in how many
//! numbers one of them draws does not shift the others (MMLT's camera/light/connection streams).
//!
//! The space is installed on the current thread with [`with_space`]; while it is,
//! `Sampler::for_item` hands out samplers that read its streams (`sampling.rs`), so integrators'
//! per-path code runs on a chain's numbers unchanged.

use rand_pcg::rand_core::Rng;
use rand_pcg::Pcg32;
use std::cell::{Cell, RefCell};

/// Streams of one path: 0 for the Metropolis integrator's own choices (pixel, strategy), then one
/// per `sampling::Domain` (stream = 1 + domain).
pub const STREAMS: usize = 5;

/// One coordinate: its value and the iteration that last set it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Coord {
    value: f32,
    modified: u64,
}

/// The primary sample vector of one Markov chain, with its mutation state.
#[derive(Clone, Debug)]
pub struct PrimarySpace {
    coords: Vec<Coord>,
    /// The iteration under way (0 before the first).
    iteration: u64,
    large_step: bool,
    last_large: u64,
    sigma: f32,
    /// How many numbers each stream has given in this iteration.
    drawn: [u32; STREAMS],
    /// Coordinates changed in this iteration with their values before it, and the previous
    /// `last_large`: what `reject` restores.
    backup: Vec<(usize, Coord)>,
    last_large_before: u64,
    len_before: usize,
    rng: Pcg32,
}

/// What `reject` must give back exactly (for tests).
#[derive(Clone, Debug, PartialEq)]
pub struct Snapshot {
    coords: Vec<Coord>,
    iteration: u64,
    last_large: u64,
}

impl PrimarySpace {
    /// An empty vector whose fresh and mutated values come from the stream `(seed, key)`.
    pub fn new(seed: u64, key: u64, sigma: f32) -> PrimarySpace {
        PrimarySpace {
            coords: Vec::new(),
            iteration: 0,
            large_step: true,
            last_large: 0,
            sigma,
            drawn: [0; STREAMS],
            backup: Vec::new(),
            last_large_before: 0,
            len_before: 0,
            rng: pcg(seed, key),
        }
    }

    /// Switches the stream of fresh and mutated values (a chain started from a bootstrap sample
    /// continues on its own stream, so two chains started from the same sample part).
    pub fn reseed(&mut self, seed: u64, key: u64) {
        self.rng = pcg(seed, key);
    }

    /// Starts the next proposal: a large step or a small one.
    pub fn start_iteration(&mut self, large: bool) {
        self.iteration += 1;
        self.large_step = large;
        self.last_large_before = self.last_large;
        if large {
            self.last_large = self.iteration;
        }
        self.drawn = [0; STREAMS];
        self.backup.clear();
        self.len_before = self.coords.len();
    }

    /// Reads the iteration's coordinates again from the first: a replay of what samplers drew
    /// (MMLT's chain start re-reads a bootstrap point's coordinates for one strategy).
    pub fn rewind_draws(&mut self) {
        self.drawn = [0; STREAMS];
    }

    /// Reads `stream`'s coordinates of this iteration again from its first.
    pub fn rewind_stream(&mut self, stream: usize) {
        self.drawn[stream] = 0;
    }

    /// The proposal becomes the chain's state.
    pub fn accept(&mut self) {
        self.backup.clear();
    }

    /// The proposal is dropped: every coordinate it changed and the iteration count return to
    /// the state before `start_iteration`.
    pub fn reject(&mut self) {
        for &(i, c) in self.backup.iter().rev() {
            if i < self.len_before {
                self.coords[i] = c;
            }
        }
        // Coordinates the proposal created did not exist before it.
        self.coords.truncate(self.len_before);
        self.backup.clear();
        self.last_large = self.last_large_before;
        self.iteration -= 1;
    }

    /// The next number of `stream` in this iteration, mutated on first use.
    pub fn next(&mut self, stream: usize) -> f32 {
        let i = self.drawn[stream] as usize * STREAMS + stream;
        self.drawn[stream] += 1;
        if i >= self.coords.len() {
            // Never-used coordinates: untouched since iteration 0, so redrawn below.
            self.coords.resize(
                i + 1,
                Coord {
                    value: 0.0,
                    modified: 0,
                },
            );
        }
        self.ensure_current(i);
        self.coords[i].value
    }

    /// Brings coordinate `i` to this iteration (lazy mutation), saving its old value first.
    fn ensure_current(&mut self, i: usize) {
        let c = self.coords[i];
        if c.modified == self.iteration {
            return;
        }
        self.backup.push((i, c));
        let mut c = c;
        // Replaced by a large step since it was last set (or never set): uniform at that step.
        if c.modified < self.last_large {
            c.value = uniform(&mut self.rng);
            c.modified = self.last_large;
        }
        if c.modified < self.iteration {
            // Only small steps remain between c.modified and now (the latest large step is at
            // or before c.modified): their offsets add up to one normal of variance n·σ².
            let n = (self.iteration - c.modified) as f64;
            let step = self.sigma as f64 * n.sqrt() * standard_normal(&mut self.rng);
            c.value = wrap(c.value as f64 + step);
        }
        c.modified = self.iteration;
        self.coords[i] = c;
    }

    /// The state `reject` restores (for tests).
    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            coords: self.coords.clone(),
            iteration: self.iteration,
            last_large: self.last_large,
        }
    }

    /// A raw uniform number from the chain's own stream (for the caller's coin flips).
    pub fn uniform(&mut self) -> f32 {
        uniform(&mut self.rng)
    }
}

fn pcg(seed: u64, key: u64) -> Pcg32 {
    crate::keyed_pcg::keyed_pcg(seed, key, u64::MAX - 7)
}

fn uniform(rng: &mut Pcg32) -> f32 {
    crate::keyed_pcg::uniform_f32(rng)
}

/// x wrapped into [0, 1) (never 1 after rounding to f32).
fn wrap(x: f64) -> f32 {
    let w = (x - x.floor()) as f32;
    if w >= 1.0 {
        0.0
    } else {
        w
    }
}

/// A standard normal number by Box–Muller from two uniforms (f64, so the tails are kept).
fn standard_normal(rng: &mut Pcg32) -> f64 {
    let u1 = (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    let u2 = (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    (-2.0 * (1.0 - u1).ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

thread_local! {
    /// Whether a space is installed on this thread: `Sampler::for_item` reads only this flag, so
    /// a render without Metropolis pays one thread-local load per stream it opens.
    static INSTALLED: Cell<bool> = const { Cell::new(false) };
    static SPACE: RefCell<Option<PrimarySpace>> = const { RefCell::new(None) };
}

/// Runs `f` with `space` installed on this thread: every sampler `Sampler::for_item` opens inside
/// reads `space`'s stream for its domain. The space is handed back when `f` returns or panics.
pub fn with_space<T>(space: &mut PrimarySpace, f: impl FnOnce() -> T) -> T {
    struct Uninstall<'a>(&'a mut PrimarySpace);
    impl Drop for Uninstall<'_> {
        fn drop(&mut self) {
            INSTALLED.with(|i| i.set(false));
            if let Some(s) = SPACE.with(|c| c.borrow_mut().take()) {
                *self.0 = s;
            }
        }
    }
    let taken = std::mem::replace(space, PrimarySpace::new(0, 0, 0.0));
    SPACE.with(|c| *c.borrow_mut() = Some(taken));
    INSTALLED.with(|i| i.set(true));
    let _guard = Uninstall(space);
    f()
}

/// Rewinds `stream` of the installed space (`PrimarySpace::rewind_stream`): the next sampler
/// reading it starts again from its first coordinate (MMLT's bootstrap gives every strategy the
/// connection numbers its chain would read).
pub fn rewind_installed(stream: usize) {
    SPACE.with(|c| {
        if let Some(s) = c.borrow_mut().as_mut() {
            s.rewind_stream(stream)
        }
    })
}

/// Whether a space is installed on this thread.
#[inline]
pub fn installed() -> bool {
    INSTALLED.with(|i| i.get())
}

/// The next number of `stream` from the installed space.
#[cold]
#[inline(never)]
pub fn next_installed(stream: usize) -> f32 {
    SPACE.with(|c| {
        c.borrow_mut()
            .as_mut()
            .expect("a primary-space sampler outlived its space")
            .next(stream)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Šidák-corrected two-sided normal quantile for `m` tests at family level 1e-3 (a fixed
    /// seed; the threshold only has to be honest, not tight).
    fn z_sidak(m: usize) -> f64 {
        let a = 1.0 - (1.0 - 1e-3f64).powf(1.0 / m as f64);
        // Inverse of the normal tail by bisection on erfc (no dependency).
        let (mut lo, mut hi) = (0.0f64, 10.0f64);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if erfc(mid / std::f64::consts::SQRT_2) > a {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        hi
    }

    /// erfc by its continued-fraction-free Chebyshev fit (Numerical Recipes' erfcc, |ε| < 1.2e-7).
    fn erfc(x: f64) -> f64 {
        let z = x.abs();
        let t = 1.0 / (1.0 + 0.5 * z);
        let r = t
            * (-z * z - 1.26551223
                + t * (1.00002368
                    + t * (0.37409196
                        + t * (0.09678418
                            + t * (-0.18628806
                                + t * (0.27886807
                                    + t * (-1.13520398
                                        + t * (1.48851587
                                            + t * (-0.82215223 + t * 0.17087277)))))))))
                .exp();
        if x >= 0.0 {
            r
        } else {
            2.0 - r
        }
    }

    /// The wrapped offset of a small step, in [−½, ½).
    fn offset(a: f32, b: f32) -> f64 {
        let d = b as f64 - a as f64;
        d - d.round()
    }

    #[test]
    fn small_steps_are_symmetric_with_the_stated_spread() {
        // Offsets of one small step: mean 0 and the same mass on either side (a symmetric
        // proposal is what makes the acceptance ratio I(y)/I(x)); variance σ² (σ small enough
        // that wrapping cuts nothing measurable).
        let sigma = 0.01f32;
        let mut space = PrimarySpace::new(3, 1, sigma);
        space.start_iteration(true);
        let n = 40_000;
        let mut prev: Vec<f32> = (0..n).map(|_| space.next(0)).collect();
        space.accept();
        let (mut sum, mut sum2, mut positive) = (0.0f64, 0.0f64, 0usize);
        let rounds = 3;
        for _ in 0..rounds {
            space.start_iteration(false);
            for p in prev.iter_mut() {
                let v = space.next(0);
                let d = offset(*p, v);
                sum += d;
                sum2 += d * d;
                positive += (d > 0.0) as usize;
                *p = v;
            }
            space.accept();
        }
        let m = (n * rounds) as f64;
        let s = sigma as f64;
        let z = z_sidak(3);
        let z_mean = (sum / m) / (s / m.sqrt());
        assert!(z_mean.abs() < z, "mean offset z = {z_mean}");
        let z_sign = (positive as f64 - m / 2.0) / (m / 4.0).sqrt();
        assert!(z_sign.abs() < z, "sign balance z = {z_sign}");
        // Var of d² for a normal is 2σ⁴.
        let z_var = (sum2 / m - s * s) / (2.0f64.sqrt() * s * s / m.sqrt());
        assert!(z_var.abs() < z, "variance z = {z_var}");
    }

    #[test]
    fn a_coordinate_skipped_for_n_small_steps_moves_by_sigma_root_n() {
        let sigma = 0.005f32;
        let mut space = PrimarySpace::new(9, 2, sigma);
        space.start_iteration(true);
        let n = 20_000;
        let first: Vec<f32> = (0..n).map(|_| space.next(0)).collect();
        space.accept();
        // Four small steps that use no coordinate, then one that reads them all.
        for _ in 0..4 {
            space.start_iteration(false);
            space.accept();
        }
        space.start_iteration(false);
        let s2 = 5.0 * (sigma as f64).powi(2);
        let m = n as f64;
        let sum2: f64 = first
            .iter()
            .map(|&a| offset(a, space.next(0)).powi(2))
            .sum();
        let z = (sum2 / m - s2) / (2.0f64.sqrt() * s2 / m.sqrt());
        assert!(z.abs() < z_sidak(1), "variance after 5 steps: z = {z}");
    }

    #[test]
    fn large_steps_are_uniform() {
        // Histogram of every coordinate after a large step, against the uniform: each bin's count
        // is binomial, Šidák over the bins.
        let mut space = PrimarySpace::new(5, 7, 0.01);
        let bins = 20;
        let mut counts = vec![0u64; bins];
        let per = 2_000;
        let iters = 25;
        for it in 0..iters {
            let _ = it;
            space.start_iteration(true);
            for k in 0..per {
                let v = space.next(k % STREAMS);
                assert!((0.0..1.0).contains(&v));
                counts[(v * bins as f32) as usize] += 1;
            }
            space.accept();
        }
        let m = (per * iters) as f64;
        let p = 1.0 / bins as f64;
        let z = z_sidak(bins);
        for (b, &c) in counts.iter().enumerate() {
            let zb = (c as f64 - m * p) / (m * p * (1.0 - p)).sqrt();
            assert!(zb.abs() < z, "bin {b}: {c} of {m}, z = {zb}");
        }
    }

    #[test]
    fn reject_restores_the_exact_previous_state() {
        let mut space = PrimarySpace::new(1, 1, 0.02);
        space.start_iteration(true);
        for k in 0..30 {
            space.next(k % STREAMS);
        }
        space.accept();
        space.start_iteration(false);
        for k in 0..10 {
            space.next(k % STREAMS);
        }
        space.accept();
        let before = space.snapshot();
        let values: Vec<f32> = {
            let mut s = space.clone();
            s.start_iteration(false);
            (0..5).map(|_| s.next(0)).collect()
        };
        // A small step touching old and new coordinates, rejected.
        space.start_iteration(false);
        for k in 0..50 {
            space.next(k % STREAMS);
        }
        space.reject();
        assert_eq!(space.snapshot(), before);
        // A large step, rejected: the small steps after it still mutate the old state.
        space.start_iteration(true);
        for k in 0..40 {
            space.next(k % STREAMS);
        }
        space.reject();
        assert_eq!(space.snapshot(), before);
        space.start_iteration(false);
        let after: Vec<f32> = (0..5).map(|_| space.next(0)).collect();
        // Same state, different mutation numbers: each value within a few σ of the old one,
        // not redrawn (a lost `last_large` would make these uniform).
        for (a, b) in values.iter().zip(&after) {
            assert!(offset(*a, *b).abs() < 0.2, "{a} vs {b}");
        }
    }
}

//! The function a Metropolis chain samples: a point u of primary sample space mapped, through an
//! existing integrator's per-path code run on u's numbers, to the splats it adds to the image.
//!
//! With N pixels, u's first two numbers (stream 0) pick a pixel uniformly and the base integrator
//! runs that pixel's work item with every random stream read from u (`primary_space`). F(u) is
//! N times the item's splats, so E_u[F] is one pass of the base integrator: the image.
//! The scalar the chain follows is I(u) = Σ luminance of F(u)'s splats (Kelemen et al. 2002).
//!
//! MMLT (Hachisuka et al. 2014) restricts F to paths of k segments and one strategy (s, t),
//! s + t = k + 1, chosen by u's third number uniformly among the k + 1 bdpt samples (t ≥ 1):
//! F_k(u) = N (k + 1) · w_{s,t} f / p_{s,t}, bdpt's MIS-weighted contribution of that strategy,
//! evaluated alone (`strategy::one_strategy`: walks of exactly s and t vertices, one join), so
//! Σ_k E_u[F_k] is bdpt's image again. MMLT's bootstrap reads every length and every strategy
//! of a point from one pair of full walks (`evaluate_lengths`, `strategy::every_strategy`), the
//! picked strategy's value bit for bit what the chain's evaluation gives. b_k = E_u[I_k(u)] is
//! estimated by the expectation over the strategy number in closed form: E_s[(k + 1) I_{s,k}] =
//! Σ_s I_{s,k}, the point's length-k luminance over all strategies (Rao–Blackwellised over s:
//! same mean, never more variance), while the chains still start from the one picked strategy
//! ∝ I_k(u).

use super::strategy::{every_strategy, one_strategy, Rules, Walks};
use crate::bidirectional::bdpt::{self, Bdpt};
use crate::film::pixel::{pixel_sample, weighted};
use crate::film::splat::{Pass, Splats, Worker};
use crate::record::NoRecord;
use crate::unidirectional::pt::Pt;
use lt_core::math::{luminance, Color};
use lt_core::primary_space::{next_installed, with_space, PrimarySpace};
use lt_core::sampling::{Domain, Sampler};
use lt_core::Scene;

/// The per-path estimator a chain runs on its numbers.
pub enum Base {
    Pt(Pt),
    Bdpt(Bdpt),
}

/// Which part of the base's contribution a chain samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Restrict {
    /// Everything one work item adds (PSSMLT).
    Full,
    /// Paths of `k` segments, one strategy drawn per sample (MMLT; bdpt only).
    Length(usize),
}

/// One evaluated point: F(u) as splats (pixel, value) and I(u).
#[derive(Clone, Debug, Default)]
pub struct Sample {
    pub splats: Vec<(u32, Color)>,
    pub importance: f64,
}

/// Per-thread buffers of an evaluation.
pub struct Scratch {
    bdpt: Option<bdpt::Scratch>,
    /// One strategy's walks (MMLT; bdpt base only).
    walks: Option<Walks>,
    item: Splats,
}

impl Base {
    pub fn scratch(&self, scene: &Scene) -> Scratch {
        let (w, h) = (scene.camera.width, scene.camera.height);
        let (bdpt, walks) = match self {
            Base::Bdpt(b) => (Some(b.scratch()), Some(Walks::new(b.params.max_depth))),
            Base::Pt(_) => (None, None),
        };
        Scratch {
            bdpt,
            walks,
            item: Splats::new(w, h),
        }
    }

    /// MMLT's path lengths: 1 … max_depth (at least one).
    pub fn lengths(&self) -> usize {
        match self {
            Base::Bdpt(b) => b.params.max_depth.max(1) as usize,
            Base::Pt(_) => 1,
        }
    }

    /// F(u) and I(u) for the state `space` holds in its current iteration, into `out`; returns
    /// the number of invalid (NaN, infinite, negative) values dropped.
    pub fn evaluate(
        &self,
        scene: &Scene,
        restrict: Restrict,
        space: &mut PrimarySpace,
        scratch: &mut Scratch,
        out: &mut Sample,
    ) -> u64 {
        scratch.item.clear();
        let n = scene.camera.pixel_count() as u64;
        // MMLT's strategy already carries N (k + 1) (`strategy::Walks::add`).
        let scale = match restrict {
            Restrict::Full => n as f32,
            Restrict::Length(_) => 1.0,
        };
        with_space(space, || {
            let pixel = pick_pixel(n);
            match (self, restrict) {
                (Base::Pt(pt), _) => {
                    // pixel_pass's sample, on the chain's camera stream.
                    let mut s = Sampler::for_item(Domain::Camera, 0, pixel, 0);
                    if let Some(film) = pixel_sample(scene, pixel, &mut s) {
                        let c = pt.radiance(scene, film.raster, &mut s);
                        scratch
                            .item
                            .add_to_pixel(pixel as u32, weighted(c, film.weight));
                    }
                }
                (Base::Bdpt(b), Restrict::Full) => {
                    let mut worker = Worker {
                        splats: &mut scratch.item,
                        scratch: scratch.bdpt.as_mut().expect("bdpt scratch"),
                        rec: &mut NoRecord,
                    };
                    b.item(scene, Pass { seed: 0, pass: 0 }, pixel, &mut worker);
                }
                (Base::Bdpt(b), Restrict::Length(k)) => {
                    let s = pick_strategy(next_installed(0), k);
                    let walks = scratch.walks.as_mut().expect("mmlt walks");
                    let rules = rules(b);
                    one_strategy(
                        scene,
                        rules,
                        pixel,
                        (s, k + 1 - s),
                        walks,
                        &mut scratch.item,
                    );
                }
            }
        });
        out.splats.clear();
        out.importance = 0.0;
        for &(p, c) in scratch.item.entries() {
            let c = c * scale;
            out.importance += luminance(c).max(0.0) as f64;
            out.splats.push((p, c));
        }
        scratch.item.invalid()
    }

    /// A chain's first state, at a bootstrap point `space` holds fresh from its large step: for
    /// MMLT, the point's coordinates are first drawn in the bootstrap's order
    /// (`evaluate_lengths`, whose walks read them first), then read again for the one strategy,
    /// so the state's I is the bootstrap's `picked` it was resampled by.
    pub fn evaluate_start(
        &self,
        scene: &Scene,
        restrict: Restrict,
        space: &mut PrimarySpace,
        scratch: &mut Scratch,
        out: &mut Sample,
    ) {
        if let Restrict::Length(_) = restrict {
            self.evaluate_lengths(scene, space, scratch, &mut Vec::new());
            space.rewind_draws();
        }
        self.evaluate(scene, restrict, space, scratch, out);
    }

    /// I_k(u) for every length k = 1 … `lengths()` from one pair of walks on u, into `importance`
    /// (k − 1 indexed): `picked` is what `evaluate` with `Restrict::Length(k)` gives for the same
    /// u, bit for bit; `all_strategies` is Σ_s of the strategies' I_{s,k}, the expectation of
    /// `picked` over u's strategy number. Returns the invalid values dropped. Only for a bdpt base.
    pub fn evaluate_lengths(
        &self,
        scene: &Scene,
        space: &mut PrimarySpace,
        scratch: &mut Scratch,
        importance: &mut Vec<LengthImportance>,
    ) -> u64 {
        let Base::Bdpt(b) = self else {
            panic!("per-length evaluation needs a bdpt base")
        };
        let lengths = self.lengths();
        importance.clear();
        importance.resize(lengths, LengthImportance::default());
        let n = scene.camera.pixel_count() as u64;
        let mut invalid = 0;
        let walks = scratch.walks.as_mut().expect("mmlt walks");
        with_space(space, || {
            let pixel = pick_pixel(n);
            let v = next_installed(0);
            every_strategy(
                scene,
                rules(b),
                pixel,
                lengths,
                walks,
                &mut scratch.item,
                |k, s, splats| {
                    // Summed as `evaluate` sums one strategy's splats (scale 1): the same bits.
                    let i = splats
                        .entries()
                        .iter()
                        .fold(0.0, |acc, &(_, c)| acc + luminance(c).max(0.0) as f64);
                    let at = &mut importance[k - 1];
                    // I_{s,k} without the (k + 1) of the chain's target.
                    at.all_strategies += i / (k + 1) as f64;
                    if s == pick_strategy(v, k) {
                        at.picked = i;
                    }
                    invalid += splats.invalid();
                },
            );
        });
        invalid
    }
}

/// One bootstrap point's I_k for one length k (`Base::evaluate_lengths`).
#[derive(Clone, Copy, Debug, Default)]
pub struct LengthImportance {
    /// (k + 1) · N · luminance of the strategy u's number picked: the chain's target at u.
    pub picked: f64,
    /// N · luminance summed over all k + 1 strategies: E[`picked`] over the strategy number.
    pub all_strategies: f64,
}

/// MMLT's strategy at length k from u's strategy number v: s = ⌊v (k + 1)⌋, uniform over 0 … k.
fn pick_strategy(v: f32, k: usize) -> usize {
    ((v * (k + 1) as f32) as usize).min(k)
}

fn rules(b: &Bdpt) -> Rules {
    Rules {
        rr_depth: b.params.rr_depth,
        mis: b.params.mis,
    }
}

/// A pixel uniformly from stream 0's next two numbers (48 bits, so every pixel of any film has the
/// same chance to within 2⁻²⁴ of itself; one 24-bit number would favour some pixels by up to
/// N / 2²⁴ when N does not divide 2²⁴).
fn pick_pixel(n: u64) -> u64 {
    let hi = next_installed(0) as f64;
    let lo = next_installed(0) as f64;
    let u = hi + lo * (1.0 / (1u64 << 24) as f64);
    ((u * n as f64) as u64).min(n - 1)
}

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
//! F_k(u) = N (k + 1) · w_{s,t} f / p_{s,t}, bdpt's own MIS-weighted contribution of that strategy
//! (read through the `Recorder` bdpt reports every completed path to), so Σ_k E_u[F_k] is bdpt's
//! image again. One bdpt sample on u holds every F_k(u) at once (the same third number picks
//! each length's strategy), so MMLT's bootstrap reads all lengths from one evaluation
//! (`evaluate_lengths`). It holds every strategy's value too, so b_k = E_u[I_k(u)] is estimated
//! by the expectation over the strategy number in closed form: E_s[(k + 1) I_{s,k}] =
//! Σ_s I_{s,k}, bdpt's own length-k luminance (Rao–Blackwellised over s: same mean, never more
//! variance), while the chains still start from the one picked strategy ∝ I_k(u).

use crate::bidirectional::bdpt::{self, Bdpt};
use crate::film::pixel::{pixel_sample, weighted};
use crate::film::splat::{Pass, Splats, Worker};
use crate::record::{Completed, NoRecord, Recorder};
use crate::unidirectional::pt::Pt;
use lt_core::camera::FilmFilter;
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
    item: Splats,
    /// The kept strategy's splats per path length (one buffer for a single length).
    picked: Vec<Splats>,
    /// Every strategy's splats per path length (MMLT's bootstrap only).
    every: Vec<Splats>,
}

impl Base {
    pub fn scratch(&self, scene: &Scene) -> Scratch {
        let (w, h) = (scene.camera.width, scene.camera.height);
        Scratch {
            bdpt: match self {
                Base::Bdpt(b) => Some(b.scratch()),
                Base::Pt(_) => None,
            },
            item: Splats::new(w, h),
            picked: Vec::new(),
            every: Vec::new(),
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
        scratch.clear_picked(1, scene);
        let n = scene.camera.pixel_count() as u64;
        let mut scale = n as f32;
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
                    scale *= (k + 1) as f32;
                    picked_item(b, scene, pixel, k, false, scratch);
                }
            }
        });
        let taken = match restrict {
            Restrict::Length(_) => &scratch.picked[0],
            Restrict::Full => &scratch.item,
        };
        out.splats.clear();
        out.importance = 0.0;
        for &(p, c) in taken.entries() {
            let c = c * scale;
            out.importance += luminance(c).max(0.0) as f64;
            out.splats.push((p, c));
        }
        scratch.item.invalid() + scratch.picked[0].invalid()
    }

    /// I_k(u) for every length k = 1 … `lengths` from one bdpt sample on u, into `importance`
    /// (k − 1 indexed): `picked` is what `evaluate` with `Restrict::Length(k)` gives for the same
    /// u, bit for bit; `all_strategies` is Σ_s of the strategies' I_{s,k}, the expectation of
    /// `picked` over u's strategy number. Returns the invalid values dropped. Only for a bdpt base.
    pub fn evaluate_lengths(
        &self,
        scene: &Scene,
        lengths: usize,
        space: &mut PrimarySpace,
        scratch: &mut Scratch,
        importance: &mut Vec<LengthImportance>,
    ) -> u64 {
        let Base::Bdpt(b) = self else {
            panic!("per-length evaluation needs a bdpt base")
        };
        scratch.clear_picked(lengths, scene);
        let n = scene.camera.pixel_count() as u64;
        with_space(space, || {
            picked_item(b, scene, pick_pixel(n), 1, true, scratch)
        });
        importance.clear();
        let mut invalid = scratch.item.invalid();
        let total = |splats: &Splats, scale: f32| -> f64 {
            splats.entries().iter().fold(0.0, |acc, &(_, c)| {
                acc + luminance(c * scale).max(0.0) as f64
            })
        };
        for (i, (picked, every)) in scratch.picked.iter().zip(&scratch.every).enumerate() {
            importance.push(LengthImportance {
                picked: total(picked, n as f32 * (i + 2) as f32),
                all_strategies: total(every, n as f32),
            });
            invalid += picked.invalid();
        }
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

impl Scratch {
    /// Empties the item's splats and `lengths` per-length buffers.
    fn clear_picked(&mut self, lengths: usize, scene: &Scene) {
        self.item.clear();
        let (w, h) = (scene.camera.width, scene.camera.height);
        if self.picked.len() < lengths {
            self.picked.resize_with(lengths, || Splats::new(w, h));
        }
        self.picked.truncate(lengths);
        self.picked.iter_mut().for_each(Splats::clear);
        if self.every.len() < lengths {
            self.every.resize_with(lengths, || Splats::new(w, h));
        }
        self.every.truncate(lengths);
        self.every.iter_mut().for_each(Splats::clear);
    }
}

/// Runs bdpt's item for `pixel` on the installed space, keeping for each length k ≥ `first_k`
/// (k − `first_k` indexing `scratch.picked`) the one strategy the space's next stream-0 number
/// picks: s = ⌊v (k + 1)⌋; with `every`, each length's strategies all in `scratch.every` too.
fn picked_item(
    b: &Bdpt,
    scene: &Scene,
    pixel: u64,
    first_k: usize,
    every: bool,
    scratch: &mut Scratch,
) {
    let v = next_installed(0);
    let mut pick = Pick {
        first_k,
        v,
        pixel: pixel as u32,
        film_weight: 1.0,
        film: scene.camera.film(),
        out: &mut scratch.picked,
        every: if every {
            Some(&mut scratch.every)
        } else {
            None
        },
    };
    let mut worker = Worker {
        splats: &mut scratch.item,
        scratch: scratch.bdpt.as_mut().expect("bdpt scratch"),
        rec: &mut pick,
    };
    b.item(scene, Pass { seed: 0, pass: 0 }, pixel, &mut worker);
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

/// Keeps, per path length k, the one strategy (s, t = k + 1 − s) a sample chose, from everything
/// bdpt reports: its weighted value where bdpt would add it (the pixel's own estimate times the
/// film weight for t ≥ 2; through the film filter at the splat position for light tracing, t = 1).
struct Pick<'a> {
    /// The length `out[0]` holds; `out[i]` holds length `first_k + i`.
    first_k: usize,
    /// The strategy number: s = ⌊v (k + 1)⌋ at length k.
    v: f32,
    pixel: u32,
    film_weight: f32,
    film: &'a FilmFilter,
    out: &'a mut [Splats],
    /// Every strategy's value per length, indexed as `out` (MMLT's bootstrap).
    every: Option<&'a mut Vec<Splats>>,
}

impl Recorder for Pick<'_> {
    const ACTIVE: bool = true;

    fn begin_sample(&mut self, _pixel: u64, film_weight: f32) {
        self.film_weight = film_weight;
    }

    fn completed(&mut self, path: Completed) {
        let k = path.light.len() + path.camera.len() - 1;
        let Some(out) = k
            .checked_sub(self.first_k)
            .and_then(|i| self.out.get_mut(i))
        else {
            return;
        };
        if path.weight <= 0.0 {
            return;
        }
        let c = path.value * path.weight as f32;
        let light_traced = k + 1 - path.s < 2;
        let (pixel, film_weight, film) = (self.pixel, self.film_weight, self.film);
        let add = |splats: &mut Splats| {
            if light_traced {
                splats.add_filtered(film, path.raster, c);
            } else {
                splats.add_to_pixel(pixel, weighted(c, film_weight));
            }
        };
        if let Some(every) = self.every.as_deref_mut() {
            add(&mut every[k - self.first_k]);
        }
        let s = ((self.v * (k + 1) as f32) as usize).min(k);
        if path.s == s {
            add(out);
        }
    }
}

//! Light-transport estimators over the shared path-space core. One integrator per file, grouped
//! by family (`unidirectional`, `bidirectional`, `photon`, `vcm`); each opens with a table of its
//! parameters. The machinery they share is in `subpath` (walks, joins, the bidirectional camera
//! loop), `film` (pixel samples, splats), `density` (photon maps, radii), `record` (what
//! integrators report: mis-check, tallies); `registry` maps names to constructors, `render`
//! drives passes.

// The estimators, by family (each file opens with its key table).
pub mod bidirectional;
pub mod metropolis;
pub mod photon;
pub mod unidirectional;
pub mod vcm;

// The machinery they share.
pub mod density;
pub mod film;
// Participating media: pt, pt-bsdf and light through volumes (entered when a scene has media).
pub mod media;
pub mod params;
pub mod record;
pub mod registry;
pub mod render;
pub mod subpath;
pub mod upbp;
// Volumetric density estimation: photon points gathered by points and by camera beams.
pub mod volume_density;

// The paths crates outside this one import (the modules' homes are above).
pub use bidirectional::{bdpt, lvc_bdpt};
pub use density::{radius, visible};
pub use film::{pixel, splat};
pub use record::{tally, tally_run};
pub use subpath::connect;
pub use unidirectional::pt;
pub use vcm::engine as connect_merge;

pub use params::IntegratorParams;
pub use registry::{make_integrator, IntegratorInfo, Radius, INTEGRATORS};
pub use render::{
    render, render_runs, EstimatorRef, PassReport, PassState, RenderOptions, RenderResult,
    RunSummary, RunsResult,
};

use lt_core::Scene;
use lt_estimators::Image;

/// What kind of estimator an integrator is, which decides where its error bars come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Every pass is an independent, identically distributed, unbiased estimate of the image: the
    /// spread of passes gives the standard error.
    Unbiased,
    /// Biased but consistent (photon mapping and its progressive forms): passes share state (a
    /// photon map, shrinking radii), so their spread means nothing. Error bars come only from
    /// independent runs (`render_runs`, `lt render --runs K`).
    Consistent,
}

impl Kind {
    pub fn name(self) -> &'static str {
        match self {
            Kind::Unbiased => "unbiased",
            Kind::Consistent => "consistent",
        }
    }
}

/// An unbiased estimator of the image. Every pass is an independent estimate of the whole image
/// (one sample per pixel for pixel-based estimators), so passes average into the result and their
/// spread gives its standard error.
pub trait Integrator: Send + Sync {
    fn name(&self) -> &'static str;

    /// Pass `pass` of the run seeded by `seed`. Must depend on nothing else (not on threads or
    /// timing), so the same seed gives the same image bit for bit. Returns the image and the number
    /// of samples discarded as invalid (NaN, infinite or negative) — zero for a correct integrator.
    fn render_pass(&self, scene: &Scene, seed: u64, pass: u32) -> (Image, u64);
}

/// A consistent estimator: one run keeps state across its passes (SmallVCM's `RunIteration`,
/// pbrt's SPPM loop), and its estimate after n passes is whatever that state says — not a mean of
/// independent passes.
pub trait Progressive: Send + Sync {
    fn name(&self) -> &'static str;

    /// The state of a fresh run seeded by `seed` (no pass done yet).
    fn start<'a>(&'a self, scene: &'a Scene, seed: u64) -> Box<dyn ProgressiveRun + 'a>;
}

/// One run of a [`Progressive`] estimator.
pub trait ProgressiveRun: Send + Sync {
    /// Does pass `pass`; passes come in order 0, 1, 2, … Like `Integrator::render_pass`, it may
    /// depend on nothing but (scene, seed, pass index) and the state so far. Returns the number
    /// of samples discarded as invalid.
    fn pass(&mut self, pass: u32) -> u64;

    /// Told before pass 0 how many passes the caller means to run (it may stop sooner): a run
    /// whose choices weigh bias against variance (`eamis`) needs the horizon; others ignore it.
    fn plan(&mut self, _passes: u32) {}

    /// The run's estimate of the image after the passes done so far.
    fn estimate(&self) -> Image;

    /// What the run's record should say about its schedule so far (radii, photon counts).
    fn log(&self) -> ProgressLog;
}

/// Per-pass facts of a progressive run, for the JSON record and the studies.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ProgressLog {
    /// Photon (light) paths traced in each pass.
    pub photon_paths: Vec<u64>,
    /// The gather radius of each pass relative to the initial one, r_i / r_0 (1 throughout for a
    /// fixed radius).
    pub radius_scale: Vec<f64>,
    /// The mean gather radius over the pass's visible points, in scene units.
    pub mean_radius: Vec<f64>,
    /// Everything else worth recording, as (key, value) text.
    pub facts: Vec<(String, String)>,
    /// Images worth keeping beside the render, as (name, image): `lt render -o OUT.exr` writes
    /// each as `OUT.<name>.exr` (eamis: the merge mask it chose).
    pub images: Vec<(String, Image)>,
}

/// An integrator as the registry builds it: one of the two kinds.
pub enum Estimator {
    Unbiased(Box<dyn Integrator>),
    Consistent(Box<dyn Progressive>),
}

impl Estimator {
    pub fn name(&self) -> &'static str {
        match self {
            Estimator::Unbiased(i) => i.name(),
            Estimator::Consistent(p) => p.name(),
        }
    }

    pub fn kind(&self) -> Kind {
        match self {
            Estimator::Unbiased(_) => Kind::Unbiased,
            Estimator::Consistent(_) => Kind::Consistent,
        }
    }

    /// The pass interface of an unbiased estimator (benchmarks, per-pass tests).
    pub fn unbiased(&self) -> Option<&dyn Integrator> {
        match self {
            Estimator::Unbiased(i) => Some(i.as_ref()),
            Estimator::Consistent(_) => None,
        }
    }
}

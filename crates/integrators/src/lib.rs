//! Light-transport estimators over the shared path-space core. One integrator per file; each opens
//! with a table of its parameters. `registry` maps names to constructors, `render` drives passes.

pub mod bdpt;
pub mod connect;
pub mod light;
pub mod params;
pub mod pixel;
pub mod pt;
pub mod pt_bsdf;
pub mod record;
pub mod registry;
pub mod render;
pub mod splat;
pub mod walk;

pub use params::IntegratorParams;
pub use registry::{make_integrator, IntegratorInfo, INTEGRATORS};
pub use render::{render, PassReport, RenderOptions, RenderResult};

use lt_core::Scene;
use lt_estimators::Image;

/// An estimator of the image. Every pass is an independent estimate of the whole image (one sample
/// per pixel for pixel-based estimators), so passes average into the result and their spread gives
/// its standard error.
pub trait Integrator: Send + Sync {
    fn name(&self) -> &'static str;

    /// Pass `pass` of the run seeded by `seed`. Must depend on nothing else (not on threads or
    /// timing), so the same seed gives the same image bit for bit. Returns the image and the number
    /// of samples discarded as invalid (NaN, infinite or negative) — zero for a correct integrator.
    fn render_pass(&self, scene: &Scene, seed: u64, pass: u32) -> (Image, u64);
}

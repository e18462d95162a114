//! Path space: the vertices and paths every bidirectional integrator (light tracing, BDPT, photon
//! mapping, VCM) shares, and the from-scratch measurement contribution f(x̄) and technique density
//! p_s(x̄) that tests hold those integrators to. Nothing here knows an integrator.
//!
//! # Conventions
//!
//! - **Order.** A path is x0 … xk with x0 on a light and xk the camera (Veach 1997, ch. 8); k is
//!   the number of segments (Mitsuba's depth). Technique s takes x0 … x_{s−1} from a light
//!   subpath and the t = k+1−s vertices x_s … xk from a camera subpath, s = 0 … k+1:
//!   s = 0 is a camera walk hitting the light, s = 1 next-event estimation (x0 sampled towards x1
//!   by `Light::sample_li`) when k ≥ 2, s = k light tracing (x_{k−1} connected to the camera; on a
//!   one-segment path s = 1 = k is the emitted point x0 connected to the pinhole, not next-event
//!   estimation from the pinhole, which nothing samples), and s = k+1
//!   (a light walk hitting the pinhole) is impossible: p = 0. A light with a delta position (point)
//!   cannot be hit: p_0 = 0.
//! - **Measures.** Densities are per unit area at the vertex they choose (**Invariant**), except
//!   at a light at infinity (solid angle, `p` holding the unit direction towards it; the vertex
//!   after it gets pdf_pos of the bounding disk times |cos|) and at delta positions (point light,
//!   pinhole: the discrete 1). Russian roulette is never part of p_s. Densities and contributions
//!   are f64 so long paths in large scenes do not underflow.
//! - **Delta scattering.** f and p of a delta lobe are stored delta-stripped (lobe value, lobe
//!   probability; see `scatter`), so f/p is the sample weight, and any technique whose connection
//!   edge ends at a delta vertex has p_s = 0. A refraction's Dirac lives in the solid angle of the
//!   direction its walk sampled, so its stripped value depends on the side that sampled it:
//!   `contribution` strips as the camera walk does, `contribution_for(s)` as technique s does,
//!   and every f/p_s pairs the two of technique s (they differ only at refractions on the light
//!   subpath, by η² and a cosine ratio; see `mis` for what this means for the weights).
//! - **Image normalisation.** `Camera::importance` is per pixel, We = N / (A cos⁴θ) with N the
//!   pixel count, while `Camera::pdf_dir` is film-wide, 1 / (A cos³θ). A camera sample whose
//!   raster position is uniform in its pixel has the direction density N · pdf_dir, and a light
//!   path traced once per camera sample (N · spp light paths) estimates pixel j as
//!   (1/(N·spp)) Σ f_j / p_s. So for every technique the per-pixel estimate of one sample is
//!   **f(x̄) / (N · p_s(x̄))**, averaged over spp (`Path::estimate`; a path tracer's throughput
//!   starts at We cos / (N pdf_dir) = 1). With M ≠ N light subpaths per pass, light tracing
//!   averages over M instead: f / (M · p_k), and MIS weighs technique k by n_k/n_s = M/N
//!   (`Densities::light_tracing_ratio`, `mis`). The `path_space` test proves the normalisation by
//!   letting s = 0, 1 and 2 estimate the same pixels of an analytic scene.

pub mod camis;
pub mod correlation;
pub mod densities;
pub mod efficiency;
pub mod merging;
pub mod mis;
#[allow(clippy::module_inception)]
mod path;
pub mod scatter;
pub mod subpath_mis;
pub mod vertex;

pub use correlation::Correlation;
pub use densities::Densities;
pub use merging::{Technique, TechniqueSet};
pub use mis::{balance_weight, oracle_weight, power_weight, Chain, Heuristic};
pub use path::Path;
pub use scatter::{scatter, Scatter};
pub use subpath_mis::{CameraMis, LightMis, SubpathMis};
pub use vertex::{geometry, PathVertex, VertexKind};

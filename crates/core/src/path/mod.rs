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
//! - **Media** (Pauly, Kollig & Keller 2000, the volumetric path integral; Veach's form with
//!   vertices in volumes). A vertex lies on a surface (measure dA) or inside a medium (measure
//!   dV, `VertexKind::Medium`); the path measure is the product of the vertices' measures, so
//!   I = ∫ f(x̄) dμ(x̄) sums over every arrangement of surface and volume vertices. With
//!   dω = |cos θ_y| dA(y) / r² at a surface and dV(y) = r² dr dω at a medium point, the
//!   contribution is
//!   f(x̄) = Le(x0→x1) ∏_{i=0}^{k−1} G(x_i↔x_{i+1}) T(x_i↔x_{i+1}) ∏_{i=1}^{k−1} ρ(x_i) · We,
//!   with ρ = fs at a surface and ρ = σs(x) p(ω_o, ω_i) at a medium point (σs carries the extra
//!   length of dV), G = cos·cos / r² with a cosine only at the ends that have a surface (none at
//!   a medium point, as none at a point light), and T(x↔y) = exp(−∫ σt) along the edge through
//!   every medium and null boundary between (`Scene::edge_transmittance`). T is in f because it is
//!   the physics of the edge, whichever technique made it. A walk's density, by contrast, is how
//!   it chose the vertex: a direction (solid angle) and then a free flight along it — per unit
//!   length where it stopped in a medium (σt T when sampled in proportion to T), the probability
//!   of passing every medium when it reached a surface — so the free-flight density enters p and
//!   not f: a medium vertex stores p_ω · p_ff / r² (`measure::solid_angle_to_volume`), a surface
//!   reached through media p_ω |cos| / r² · P_pass (`PathVertex::medium`,
//!   `surface_through_media`, `Scene::free_flight_density`). A connection or next-event
//!   estimation samples no free flight: its edge has T in f and nothing in p, and is estimated by
//!   `Scene::transmittance_estimate` (unbiased) so that f/p stays unbiased. Because f and p hold
//!   these factors per vertex, `Chain` and every MIS weight read medium vertices unchanged. The
//!   medium of each edge follows from one end and the direction (Mitsuba's per-ray medium:
//!   `scene/media.rs`), so both walks and the oracle agree on it. A scene without media
//!   (`Scene::has_media` false) asks none of this.

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
pub mod volume_merging;

pub use correlation::Correlation;
pub use densities::Densities;
pub use merging::{Technique, TechniqueSet};
pub use mis::{balance_weight, oracle_weight, power_weight, Chain, Heuristic};
pub use path::Path;
pub use scatter::{scatter, Scatter};
pub use subpath_mis::{CameraMis, LightMis, SubpathMis};
pub use vertex::{geometry, PathVertex, VertexKind};
pub use volume_merging::{UpbpMode, VolumeRates, VolumeSet, VolumeTechnique};

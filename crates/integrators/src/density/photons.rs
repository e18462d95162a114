//! Photons, shared by the photon-mapping family and owned by none of them: light subpaths traced
//! in importance mode by `walk::light_subpath` (the bidirectional estimators' own light walk, so
//! photons carry exactly the throughput light tracing splats), with every non-delta surface vertex
//! kept as a photon, and the density-estimation kernels that turn photons into reflected radiance.
//!
//! A photon stores β of its light subpath on arrival (Le cos θ₀ / (p_light p_pos p_dir) times
//! f cos / p_ω per earlier bounce): over N photon paths, β / N is its flux. The radiance a camera
//! vertex x reflects towards ω_o is then estimated (Jensen 1996, eq. 7; Hachisuka et al. 2008)
//! as L ≈ Σ_p K_r(|x − x_p|) f(ω_o, ω_p) (|n_s · ω_p| / |n_g,p · ω_p|) β_p / N, with K_r a kernel
//! normalised over the disk of radius r. The cosine ratio is the shading-normal correction: the
//! photon density is flux per unit of true surface area.

use crate::subpath::walk::{light_subpath, Subpath, WalkLimits};
use lt_core::bsdf::{ShadingFrame, TransportMode};
use lt_core::math::{Color, Vec3, PI};
use lt_core::path::scatter::connectable;
use lt_core::path::VertexKind;
use lt_core::sampling::{Domain, Sampler};
use lt_core::spatial::PointGrid;
use lt_core::Scene;
use rayon::prelude::*;

/// One stored photon (its position lives in a parallel array, which the grid indexes).
#[derive(Clone, Copy, Debug)]
pub struct Photon {
    /// Unit direction towards where the photon came from.
    pub wi: Vec3,
    /// Geometric normal of the surface it landed on (for the side test and the cosine ratio).
    pub ng: Vec3,
    /// β of the light subpath on arrival; over N photon paths its flux is β / N.
    pub beta: Color,
    /// Segments from the light: 1 for a photon that arrived directly from an emitter.
    pub segments: u32,
}

/// The photons of `paths` photon paths, positions and records in the same order.
#[derive(Clone, Debug, Default)]
pub struct PhotonBatch {
    pub positions: Vec<Vec3>,
    pub photons: Vec<Photon>,
    pub paths: u64,
}

/// Which photons a batch keeps.
#[derive(Clone, Copy, Debug)]
pub struct PhotonOptions {
    /// Longest photon path kept, in segments from the light.
    pub max_segments: u32,
    pub rr_depth: u32,
    /// Skip photons that arrived straight from an emitter (direct light is then next-event
    /// estimation's job at the camera vertex).
    pub skip_direct: bool,
}

/// Photon paths per parallel chunk: chunks are traced in parallel and concatenated in order, so
/// a batch is the same for any thread count.
const CHUNK: u64 = 4096;

/// Traces photon paths `first .. first + count` of the light-domain streams of (seed, pass).
pub fn trace_photons(
    scene: &Scene,
    seed: u64,
    pass: u32,
    first: u64,
    count: u64,
    opts: PhotonOptions,
) -> PhotonBatch {
    let limits = WalkLimits {
        max_vertices: opts.max_segments as usize + 1,
        rr_depth: opts.rr_depth,
    };
    let chunks = count.div_ceil(CHUNK);
    let parts: Vec<(Vec<Vec3>, Vec<Photon>)> = (0..chunks)
        .into_par_iter()
        .map_init(
            || Subpath::with_capacity(limits.max_vertices),
            |sub, c| {
                let mut pos = Vec::new();
                let mut out = Vec::new();
                let end = ((c + 1) * CHUNK).min(count);
                for i in c * CHUNK..end {
                    let mut sampler =
                        Sampler::for_item(Domain::Light, seed, first + i, pass as u64);
                    light_subpath(scene, &mut sampler, limits, sub);
                    for (segments, v) in sub.vertices.iter().enumerate().skip(1) {
                        if segments == 1 && opts.skip_direct {
                            continue;
                        }
                        if !matches!(v.kind, VertexKind::Surface { .. }) || !connectable(scene, v) {
                            continue;
                        }
                        pos.push(v.p);
                        out.push(Photon {
                            wi: v.wo,
                            ng: v.ng,
                            beta: v.beta,
                            segments: segments as u32,
                        });
                    }
                }
                (pos, out)
            },
        )
        .collect();
    let total = parts.iter().map(|(p, _)| p.len()).sum();
    let mut batch = PhotonBatch {
        positions: Vec::with_capacity(total),
        photons: Vec::with_capacity(total),
        paths: count,
    };
    for (p, o) in parts {
        batch.positions.extend(p);
        batch.photons.extend(o);
    }
    batch
}

/// Density-estimation kernels, each normalised over the disk of radius r (∫ K = 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// K = 1 / (π r²).
    Disk,
    /// K = 2 (1 − d²/r²) / (π r²) (Silverman 1986, the 2-D Epanechnikov kernel).
    Epanechnikov,
}

impl Kernel {
    pub fn parse(s: &str) -> Result<Kernel, String> {
        match s {
            "disk" => Ok(Kernel::Disk),
            "epanechnikov" => Ok(Kernel::Epanechnikov),
            _ => Err(format!("unknown kernel '{s}' (known: disk, epanechnikov)")),
        }
    }

    /// The kernel's shape at squared distance d2 within r2, relative to the disk kernel: its
    /// value times π r². Zero outside.
    #[inline]
    pub fn shape(self, d2: f32, r2: f32) -> f32 {
        if !(d2 <= r2) {
            return 0.0;
        }
        match self {
            Kernel::Disk => 1.0,
            Kernel::Epanechnikov => 2.0 * (1.0 - d2 / r2),
        }
    }

    /// K_r at squared distance d2.
    #[inline]
    pub fn value(self, d2: f32, r2: f32) -> f32 {
        self.shape(d2, r2) / (PI * r2)
    }
}

/// A camera-path vertex where photons are gathered.
#[derive(Clone, Copy, Debug)]
pub struct GatherPoint {
    pub p: Vec3,
    pub sf: ShadingFrame,
    /// Unit direction towards the camera-path vertex before it.
    pub wo: Vec3,
    pub material: u32,
    /// Camera-path throughput up to the point (1 at the pinhole).
    pub beta: Color,
    /// Segments from the camera, the camera ray included.
    pub segments: u32,
}

impl GatherPoint {
    /// f(ω_o, ω_p) (|n_s·ω_p| / |n_g,p·ω_p|) β_p of one photon, before the kernel and the 1/N.
    /// `None` (the photon is not gathered) when the path would be longer than `max_depth` or the
    /// photon arrived at the other side of a surface that does not transmit (a thin wall lit from
    /// behind stays dark in front; rough glass lit from behind does not).
    #[inline]
    pub fn photon_value(&self, scene: &Scene, ph: &Photon, max_depth: u32) -> Option<Color> {
        if self.segments + ph.segments > max_depth {
            return None;
        }
        let ng = self.sf.ng;
        let material = scene.material(self.material);
        // Light from the far side reaches the camera only through a surface that transmits.
        if ng.dot(ph.wi) * ng.dot(self.wo) <= 0.0 && !material.transmits() {
            return None;
        }
        let cos_g = ph.ng.dot(ph.wi).abs();
        if !(cos_g > 0.0) {
            return None;
        }
        let ev = material.eval(&self.sf, self.wo, ph.wi, TransportMode::Radiance);
        Some(ev.f_cos * ph.beta / cos_g)
    }
}

/// A photon batch indexed for radius and k-nearest queries.
pub struct PhotonMap {
    pub batch: PhotonBatch,
    pub grid: PointGrid,
}

impl PhotonMap {
    /// Indexes `batch` with cells of edge `cell` (about the typical query radius).
    pub fn new(batch: PhotonBatch, cell: f32) -> PhotonMap {
        let grid = PointGrid::build(&batch.positions, cell);
        PhotonMap { batch, grid }
    }

    /// The radiance estimate at `q.gp` from the photons within r, per unit of β_gp.
    pub fn radiance_within(&self, q: &Gather, r: f32) -> Color {
        let r2 = r * r;
        let mut sum = Color::ZERO;
        self.grid
            .for_each_within(&self.batch.positions, q.gp.p, r, |i, d2| {
                sum += self.weighted(q, i, d2, r2);
            });
        sum / (PI * r2 * self.batch.paths as f32)
    }

    /// Photon `i`'s kernel-weighted value at `q.gp` (before 1/(π r² N)), at squared distance `d2`
    /// in a disk of squared radius `r2`.
    #[inline]
    fn weighted(&self, q: &Gather, i: u32, d2: f32, r2: f32) -> Color {
        let w = q.kernel.shape(d2, r2);
        if w == 0.0 {
            return Color::ZERO;
        }
        let ph = &self.batch.photons[i as usize];
        q.gp.photon_value(q.scene, ph, q.max_depth)
            .map_or(Color::ZERO, |v| v * w)
    }

    /// The radiance estimate at `q.gp` from its k nearest photons (within `max_r`), the radius
    /// being the distance to the k-th (Jensen's estimate). `scratch` is reused between calls.
    pub fn radiance_knn(
        &self,
        q: &Gather,
        k: usize,
        max_r: f32,
        scratch: &mut Vec<(u32, f32)>,
    ) -> Color {
        self.grid
            .k_nearest(&self.batch.positions, q.gp.p, k, max_r, scratch);
        let Some(&(_, r2)) = scratch.last() else {
            return Color::ZERO;
        };
        if !(r2 > 0.0) {
            return Color::ZERO;
        }
        let sum = scratch
            .iter()
            .fold(Color::ZERO, |s, &(i, d2)| s + self.weighted(q, i, d2, r2));
        sum / (PI * r2 * self.batch.paths as f32)
    }
}

/// One density-estimation query: the gather point, the kernel, and the longest path a photon may
/// complete there.
pub struct Gather<'a> {
    pub scene: &'a Scene,
    pub gp: &'a GatherPoint,
    pub kernel: Kernel,
    pub max_depth: u32,
}

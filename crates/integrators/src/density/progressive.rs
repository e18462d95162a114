//! Progressive photon mapping's shared machinery, owned by neither `ppm` nor `sppm`: per-pixel
//! statistics that persist across passes, and one pass of photons — trace a batch of photon
//! paths, then let every visible point gather the photons within its own radius (the core's
//! `PointGrid` over the photons) and add their contribution.
//!
//! Determinism: each visible point sums its photons in batch order (found in grid order, then
//! sorted by batch index), so every pixel sums the same terms in the same order for any thread
//! count and any storage order. An earlier version pushed each photon into the visible points
//! around it, which sums the same terms in the same order (the images kept their bits) but read
//! visible points scattered over a pixel-ordered array; gathering walks the pixels in order.
//!
//! The per-pass estimate of pixel j with the global schedule is (Knaus & Zwicker 2011, eq. 7)
//! D_i + Σ_p K_{rᵢ}(x_j − x_p) β_j f β_p / M, averaged over passes (D: emission and next-event
//! estimation). With the local update, Hachisuka et al.'s flux τ ← (τ + Φ) r²_new / r² and the
//! pixel's estimate is D̄ + τ / (N_e π r²), N_e the photon paths traced so far.

use crate::density::photons::{trace_photons, GatherPoint, Kernel, Photon, PhotonOptions};
use crate::density::radius::{global_scale2, power_scale2, read_alpha, InitialRadius, Update};
use crate::density::visible::{CameraPrefix, Direct};
use crate::params::ParamReader;
use crate::ProgressLog;
use lt_core::math::{is_valid_color, Color, Vec3, PI};
use lt_core::spatial::PointGrid;
use lt_core::Scene;
use lt_estimators::Image;
use rayon::prelude::*;

/// The parameters `ppm` and `sppm` share (see their key tables).
#[derive(Clone, Copy, Debug)]
pub struct ProgressiveParams {
    pub max_depth: u32,
    pub rr_depth: u32,
    /// `None`: one photon path per pixel per pass.
    pub photons_per_pass: Option<u64>,
    pub radius: InitialRadius,
    pub alpha: f64,
    pub update: Update,
    pub kernel: Kernel,
    pub direct: Direct,
}

impl ProgressiveParams {
    pub fn read(scene: &Scene, r: &ParamReader, who: &str) -> Result<ProgressiveParams, String> {
        let m = r.get::<u64>("photons_per_pass")?;
        if m == Some(0) {
            return Err(format!("{who}: photons_per_pass must be at least 1"));
        }
        Ok(ProgressiveParams {
            max_depth: r.max_depth(scene)?,
            rr_depth: r.rr_depth(scene)?,
            photons_per_pass: m,
            radius: InitialRadius::read(r, who)?,
            alpha: read_alpha(r, who)?,
            update: r
                .get_with("radius_update", Update::parse)?
                .unwrap_or(Update::Global),
            kernel: r.get_with("kernel", Kernel::parse)?.unwrap_or(Kernel::Disk),
            direct: r.get_with("direct", Direct::parse)?.unwrap_or(Direct::Nee),
        })
    }

    pub fn photon_paths(&self, scene: &Scene) -> u64 {
        self.photons_per_pass
            .unwrap_or(scene.camera.pixel_count() as u64)
    }
}

/// What one pixel keeps across passes.
#[derive(Clone, Copy, Debug, Default)]
struct PixelState {
    /// Σ over passes of emission + next-event estimation.
    direct: [f64; 3],
    /// Global schedule: Σ over passes of the photon estimate.
    photons: [f64; 3],
    /// Local update: r², photon count N and flux τ (Hachisuka et al. 2008). r² = 0: not yet set.
    r2: f64,
    n: f64,
    tau: [f64; 3],
}

/// The state of one progressive run.
pub struct ProgressiveState {
    pixels: Vec<PixelState>,
    width: usize,
    passes: u32,
    photon_paths: u64,
    pub log: ProgressLog,
}

fn add(a: &mut [f64; 3], c: Color) {
    a[0] += c.x as f64;
    a[1] += c.y as f64;
    a[2] += c.z as f64;
}

impl ProgressiveState {
    pub fn new(scene: &Scene) -> ProgressiveState {
        ProgressiveState {
            pixels: vec![PixelState::default(); scene.camera.pixel_count()],
            width: scene.camera.width as usize,
            passes: 0,
            photon_paths: 0,
            log: ProgressLog::default(),
        }
    }

    /// One pass over this pass's camera prefixes (one per pixel, in pixel order). Returns the
    /// number of invalid contributions dropped.
    pub fn pass(
        &mut self,
        scene: &Scene,
        params: &ProgressiveParams,
        seed: u64,
        pass: u32,
        prefixes: &[CameraPrefix],
    ) -> u64 {
        let mut invalid = 0;
        let i = pass + 1; // Knaus & Zwicker count passes from 1
        let scale2 = match params.update {
            Update::Power => power_scale2(i, params.alpha),
            _ => global_scale2(i, params.alpha),
        };
        // The visible points of this pass, their pixels and radii.
        let mut pixel_of = Vec::new();
        let mut positions = Vec::new();
        let mut radii2 = Vec::new();
        let (mut r_sum, mut fp_sum) = (0.0f64, 0.0f64);
        for (j, pre) in prefixes.iter().enumerate() {
            let d = pre.direct();
            if is_valid_color(d) {
                add(&mut self.pixels[j].direct, d);
            } else {
                invalid += 1;
            }
            let Some(vp) = &pre.vp else { continue };
            let r0 = params.radius.at(scene, vp) as f64;
            let r2 = match params.update {
                Update::Global | Update::Power => r0 * r0 * scale2,
                Update::Local => {
                    let px = &mut self.pixels[j];
                    if px.r2 == 0.0 {
                        px.r2 = r0 * r0;
                    }
                    px.r2
                }
            };
            pixel_of.push(j as u32);
            positions.push(vp.gp.p);
            radii2.push(r2 as f32);
            r_sum += r2.sqrt();
            fp_sum += vp.footprint as f64;
        }
        let count = positions.len().max(1) as f64;
        self.log.mean_radius.push(r_sum / count);
        self.log.radius_scale.push(match params.update {
            Update::Global | Update::Power => scale2.sqrt(),
            // Per-point radii: the mean radius against the first pass's (a NaN here would be
            // written as null and refused by the run record).
            Update::Local => (r_sum / count) / self.log.mean_radius[0].max(f64::MIN_POSITIVE),
        });
        if pass == 0 {
            if let Some(w) = params.radius.warning(fp_sum / count) {
                self.log.facts.push(("warning".into(), w));
            }
        }

        let paths = params.photon_paths(scene);
        let opts = PhotonOptions {
            max_segments: params.max_depth.saturating_sub(1),
            rr_depth: params.rr_depth,
            skip_direct: params.direct == Direct::Nee,
        };
        let batch = trace_photons(scene, seed, pass, 0, paths, opts);
        self.photon_paths += paths;
        self.log.photon_paths.push(paths);

        // Gather: each visible point sums the photons within its own radius.
        let r_max = radii2.iter().fold(0.0f32, |m, &r2| m.max(r2)).sqrt();
        let mut gathered = vec![(Color::ZERO, 0u32); positions.len()];
        if r_max > 0.0 && !batch.photons.is_empty() {
            // Cells of 2·r_max: a ball of radius r ≤ r_max meets at most 2 cells per axis.
            let photons = GridPhotons::new(batch.positions, batch.photons, 2.0 * r_max);
            pixel_of
                .par_iter()
                .zip(&positions)
                .zip(&radii2)
                .map_init(Vec::new, |found, ((&j, &q), &r2)| {
                    let gp = &prefixes[j as usize]
                        .vp
                        .as_ref()
                        .expect("indexed points have a visible point")
                        .gp;
                    gather_one(scene, &photons, params, gp, q, r2, found)
                })
                .collect_into_vec(&mut gathered);
        }

        // Per-pixel updates.
        for (k, &j) in pixel_of.iter().enumerate() {
            let px = &mut self.pixels[j as usize];
            let (c, mk) = gathered[k];
            if !is_valid_color(c) {
                invalid += 1;
                continue;
            }
            match params.update {
                Update::Global | Update::Power => {
                    let r2 = radii2[k] as f64;
                    let s = 1.0 / (paths as f64 * PI as f64 * r2);
                    add(&mut px.photons, c * s as f32);
                }
                Update::Local => {
                    let mk = mk as f64;
                    if mk > 0.0 {
                        let shrink = (px.n + params.alpha * mk) / (px.n + mk);
                        for (t, ci) in px.tau.iter_mut().zip([c.x, c.y, c.z]) {
                            *t = (*t + ci as f64) * shrink;
                        }
                        px.r2 *= shrink;
                        px.n += params.alpha * mk;
                    }
                }
            }
        }
        self.passes += 1;
        invalid
    }

    /// The run's image after the passes so far.
    pub fn estimate(&self, params: &ProgressiveParams) -> Image {
        let h = self.pixels.len() / self.width.max(1);
        let mut img = Image::new(self.width, h);
        let n = self.passes.max(1) as f64;
        let ne = self.photon_paths.max(1) as f64;
        for (out, px) in img.data.iter_mut().zip(&self.pixels) {
            for (c, out_c) in out.iter_mut().enumerate() {
                let photons = match params.update {
                    Update::Global | Update::Power => px.photons[c] / n,
                    Update::Local if px.r2 > 0.0 => px.tau[c] / (ne * PI as f64 * px.r2),
                    Update::Local => 0.0,
                };
                *out_c = px.direct[c] / n + photons;
            }
        }
        img
    }
}

/// A pass's photons stored in the grid's bucket order, so that the photons one query meets lie
/// together in memory: stored photon s is the batch's photon `original[s]`, at `positions[s]`.
struct GridPhotons {
    positions: Vec<Vec3>,
    records: Vec<Photon>,
    original: Vec<u32>,
    grid: PointGrid,
}

impl GridPhotons {
    fn new(mut positions: Vec<Vec3>, mut records: Vec<Photon>, cell: f32) -> GridPhotons {
        let (grid, original) = PointGrid::build_reordered(&mut positions, &mut records, cell);
        GridPhotons {
            positions,
            records,
            original,
            grid,
        }
    }
}

/// The visible point `gp` (at `q`, squared radius `r2`)'s photon sum Σ_p K(d²) β f β_p, before
/// the 1/(N π r²), and how many photons it took. Photons are summed in batch order, so the sum
/// does not depend on how they are stored. `found` is scratch.
#[inline]
fn gather_one(
    scene: &Scene,
    photons: &GridPhotons,
    params: &ProgressiveParams,
    gp: &GatherPoint,
    q: Vec3,
    r2: f32,
    found: &mut Vec<(u32, u32, f32)>,
) -> (Color, u32) {
    found.clear();
    photons
        .grid
        .for_each_within_squared(&photons.positions, q, r2, |s, d2| {
            found.push((photons.original[s as usize], s, d2));
        });
    found.sort_unstable_by_key(|&(i, _, _)| i);
    let (mut sum, mut taken) = (Color::ZERO, 0);
    for &(_, s, d2) in found.iter() {
        let w = params.kernel.shape(d2, r2);
        if let Some(v) = gp.photon_value(scene, &photons.records[s as usize], params.max_depth) {
            sum += gp.beta * v * w;
            taken += 1;
        }
    }
    (sum, taken)
}

//! Volumetric density estimation (issue 45): photons stored at the medium vertices of light
//! subpaths, gathered by the camera walk in a medium through a kernel — photon points by a point
//! (`pp3d`, 3-D kernel) or by a camera beam (`pb2d`, 2-D kernel) — or the light subpaths' whole
//! flights through media as photon beams, gathered by a camera beam (`bb1d`, 1-D kernel).
//! Progressive: every pass traces its own photons (or beams), renders one camera sample per pixel
//! with them and a radius shrunk by `schedule` for the kernel's dimension; the image is the mean
//! of the passes.
//!
//! **Which paths each part estimates** (so the whole is the image, nothing counted twice). The
//! camera walk is `pt` through media (`media::pt::radiance_with`, NEE and BSDF sampling under MIS
//! at surfaces, transmittance on every segment) with one change in media:
//! - a path with no medium vertex is `pt`'s (emitter hits and next-event estimation from
//!   surface vertices: their shadow rays and flights pass media without a vertex), unbiased;
//! - a path with one or more medium vertices is split at its *first medium vertex from the
//!   camera*, y: the camera walk samples the prefix up to y (surface vertices and passed
//!   flights), the photons the rest (every light subpath ending at a medium vertex near y,
//!   whatever its vertices), joined by the kernel. `pp3d` samples y by free flight and stops
//!   there (no NEE, no phase sampling at y); `pb2d` integrates y along the whole flight with the
//!   beam estimate and lets the walk go on only when the sampled flight passes (weight T/P), so
//!   prefixes with a medium vertex are never continued; `bb1d` splits as `pb2d` (the camera
//!   walk's flight is the query beam), and integrates the light side's last vertex along its
//!   flight too (a photon beam carries what the points of its flight carry: `photon_beams.rs`);
//!   `bp2d` splits as `pp3d` (the camera's free-flight vertex is the query point) and gathers
//!   the light side's flights as photon beams, as `bb1d`'s.
//!
//! A path of k segments is counted once: t segments from the camera to y, k − t from the light
//! (the photon's `segments`), k ≤ max_depth. Surfaces are never density-estimated here: the
//! photons are only volume photons, so a scene without media stores none and renders `pt`'s
//! estimate.

pub mod bb1d;
pub mod beam_beam;
mod beam_events;
pub mod beams;
pub mod bp2d;
pub mod cell_frame;
pub mod pb2d;
pub mod photon_beams;
pub mod photons;
pub mod point_beam;
pub mod points;
pub mod pp3d;
pub mod schedule;

use crate::film::pixel::pixel_pass;
use crate::media::pt::{radiance_with, MediumEvents};
use crate::params::ParamReader;
use crate::pt::{Pt, PtParams, Techniques};
use crate::{ProgressLog, ProgressiveRun};
use lt_core::path::Heuristic;
use lt_core::Scene;
use lt_estimators::Image;

/// The default initial radius as a fraction of the scene's bounding-sphere diameter.
pub const DEFAULT_RADIUS_SCENE: f32 = 0.01;

/// The keys `pp3d`, `pb2d`, `bb1d` and `bp2d` share (their files' tables document them).
#[derive(Clone, Copy, Debug)]
pub struct VolumeParams {
    pub max_depth: u32,
    pub rr_depth: u32,
    /// Photon (light) paths per pass; `None`: the pixel count.
    pub photons_per_pass: Option<u64>,
    /// r₁ in scene units.
    pub radius: f32,
    pub alpha: f64,
    /// Kernel dimension: 3 for points, 2 for points × beams (either way round), 1 for beams ×
    /// beams.
    pub dimension: u32,
}

impl VolumeParams {
    pub fn read(
        scene: &Scene,
        r: &ParamReader,
        who: &str,
        dimension: u32,
    ) -> Result<VolumeParams, String> {
        let abs = r.get::<f32>("radius")?;
        let rel = r.get::<f32>("radius_scene")?;
        let radius = match (abs, rel) {
            (Some(_), Some(_)) => {
                return Err(format!("{who}: give radius or radius_scene, not both"))
            }
            (Some(a), None) => a,
            (None, f) => f.unwrap_or(DEFAULT_RADIUS_SCENE) * 2.0 * scene.bounding_sphere.1,
        };
        // An empty scene has a zero bounding sphere; any positive radius serves it.
        let radius = if radius == 0.0 && abs.is_none() && rel.is_none() {
            1e-3
        } else {
            radius
        };
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(format!(
                "{who}: the radius must be a positive number, got {radius}"
            ));
        }
        let alpha = r
            .get::<f64>("alpha")?
            .unwrap_or(schedule::balanced_alpha(dimension));
        if !(alpha > 0.0 && alpha <= 1.0) {
            return Err(format!("{who}: alpha must lie in (0, 1], got {alpha}"));
        }
        let photons_per_pass = r.get::<u64>("photons_per_pass")?;
        if photons_per_pass == Some(0) {
            return Err(format!("{who}: photons_per_pass must be at least 1"));
        }
        Ok(VolumeParams {
            max_depth: r.max_depth(scene)?,
            rr_depth: r.rr_depth(scene)?,
            photons_per_pass,
            radius,
            alpha,
            dimension,
        })
    }

    fn photon_paths(&self, scene: &Scene) -> u64 {
        self.photons_per_pass
            .unwrap_or(scene.camera.pixel_count() as u64)
    }

    /// The camera walk's `pt` (power heuristic, both techniques).
    fn pt(&self) -> Pt {
        Pt {
            params: PtParams {
                max_depth: self.max_depth,
                rr_depth: self.rr_depth,
                mis: Heuristic::Power,
                techniques: Techniques::Both,
            },
        }
    }
}

/// Which query the camera walk makes in a medium.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Query {
    /// Photon points at the first medium vertex (`pp3d`).
    Points,
    /// Photon points along the camera beam (`pb2d`).
    Beams,
    /// Photon beams along the camera beam (`bb1d`).
    BeamBeams,
    /// Photon beams at the first medium vertex (`bp2d`).
    PointBeams,
}

/// One run of `pp3d`, `pb2d`, `bb1d` or `bp2d`: the sum of the pass images so far.
pub struct VolumeRun<'a> {
    pub params: &'a VolumeParams,
    pub query: Query,
    pub scene: &'a Scene,
    pub seed: u64,
    sum: Image,
    passes: u32,
    log: ProgressLog,
}

impl<'a> VolumeRun<'a> {
    pub fn new(params: &'a VolumeParams, query: Query, scene: &'a Scene, seed: u64) -> Self {
        let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
        VolumeRun {
            params,
            query,
            scene,
            seed,
            sum: Image::new(w, h),
            passes: 0,
            log: ProgressLog::default(),
        }
    }

    fn render_with(&self, events: &(impl MediumEvents + Sync), pass: u32) -> (Image, u64) {
        let pt = self.params.pt();
        if !self.scene.has_media {
            // Nothing was stored and nothing is queried: the walk is pt's surface walk, so a pass
            // is pt's pass bit for bit (`registry::PT_WITHOUT_MEDIA`). The media walk would give
            // the same distribution from other random numbers (cornell-rough-glass).
            return pixel_pass(self.scene, self.seed, pass, |s, raster| {
                pt.radiance(self.scene, raster, s)
            });
        }
        pixel_pass(self.scene, self.seed, pass, |s, raster| {
            radiance_with(&pt, self.scene, raster, s, events)
        })
    }
}

impl ProgressiveRun for VolumeRun<'_> {
    fn pass(&mut self, pass: u32) -> u64 {
        let (scene, p) = (self.scene, self.params);
        let paths = p.photon_paths(scene);
        let scale = schedule::radius_scale(pass + 1, p.alpha, p.dimension);
        let r = p.radius * scale as f32;
        let (depth, rr) = (p.max_depth, p.rr_depth);
        // (image, invalid samples, what was stored, its bytes each, index bytes)
        let (image, invalid, stored, each, index_bytes) = match self.query {
            Query::Points => {
                let photons = photons::trace(scene, depth, rr, paths, self.seed, pass);
                let q = points::PointQuery::new(scene, &photons, r, depth);
                let (img, bad) = self.render_with(&q, pass);
                // PointGrid: one u32 per photon and per bucket (≈ one per photon).
                let n = photons.points.len();
                (img, bad, n, photons::VolumePhotons::BYTES_PER_PHOTON, 8 * n)
            }
            Query::Beams => {
                let photons = photons::trace(scene, depth, rr, paths, self.seed, pass);
                let q = beams::BeamQuery::new(scene, &photons, r, depth);
                let bytes = q.grid.as_ref().map_or(0, |g| g.bytes());
                let (img, bad) = self.render_with(&q, pass);
                let n = photons.points.len();
                (img, bad, n, photons::VolumePhotons::BYTES_PER_PHOTON, bytes)
            }
            Query::PointBeams | Query::BeamBeams => {
                let kernel = if self.query == Query::PointBeams {
                    photon_beams::BeamKernel::Point2d
                } else {
                    photon_beams::BeamKernel::Line1d
                };
                let pb = photon_beams::PhotonBeams::trace(scene, depth, rr, paths, self.seed, pass);
                let q = photon_beams::BeamQuery::new(scene, &pb, (r, kernel), depth);
                let bytes = q.index.as_ref().map_or(0, |g| g.bytes());
                let (img, bad) = self.render_with(&q, pass);
                let n = pb.beams.len();
                (
                    img,
                    bad,
                    n,
                    photon_beams::PhotonBeams::BYTES_PER_BEAM,
                    bytes,
                )
            }
        };
        for (s, v) in self.sum.data.iter_mut().zip(&image.data) {
            for c in 0..3 {
                s[c] += v[c];
            }
        }
        self.passes += 1;
        self.log.photon_paths.push(paths);
        self.log.radius_scale.push(scale);
        self.log.mean_radius.push(r as f64);
        let what = if matches!(self.query, Query::BeamBeams | Query::PointBeams) {
            "photon beams"
        } else {
            "volume photons"
        };
        self.log.facts.retain(|(k, _)| !k.starts_with("last pass"));
        self.log.facts.push((
            format!("last pass {what}"),
            format!("{stored} ({each} B each, index {index_bytes} B)"),
        ));
        invalid
    }

    fn estimate(&self) -> Image {
        self.sum.mean_of_passes(self.passes)
    }

    fn log(&self) -> ProgressLog {
        self.log.clone()
    }
}

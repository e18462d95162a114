//! `pm` — photon mapping, "store all photons, pull" (Jensen 1996): one photon map of `photons`
//! photon paths is traced when a run starts; then every pass sends one camera sample per pixel
//! through delta bounces to its first non-delta vertex and estimates the reflected radiance there
//! from the photons around it (`photons::PhotonMap`), with a fixed radius or from the k nearest.
//!
//! Biased and only consistent as the photon count grows and the radius shrinks with it: at a
//! fixed radius the bias stays whatever the number of passes. Passes share the photon map, so
//! their spread is no error bar: the registry marks `pm` consistent, and error bars come from
//! independent runs (`lt render --runs K`). Memory grows with the photon count.
//!
//! | key | type | default | meaning |
//! |---|---|---|---|
//! | `max_depth` | u32 | scene `[render] max_depth` (8) | longest path in segments, camera ray included |
//! | `rr_depth` | u32 | scene `[render] rr_depth` (5) | Russian roulette of photon paths from this many segments on |
//! | `photons` | u64 | 4 × the pixel count | photon paths in the map |
//! | `radius_px` | f32 | 2 | gather radius in pixel footprints at the visible point |
//! | `radius_scene` | f32 | — | gather radius as a fraction of the scene's bounding-sphere diameter |
//! | `radius` | f32 | — | gather radius in scene units (warned about when far from the pixel footprint) |
//! | `knn` | u32 | — | gather the k nearest photons instead (radius = distance to the k-th, capped at 8 × the radius above) |
//! | `kernel` | disk/epanechnikov | disk | density-estimation kernel, normalised over the disk |
//! | `direct` | nee/photons | nee | direct light by next-event estimation (first photon hits not stored) or from photons |

use crate::density::photons::{trace_photons, Gather, Kernel, PhotonMap, PhotonOptions};
use crate::density::radius::InitialRadius;
use crate::density::visible::{trace_visible_point, Direct};
use crate::film::pixel::pixel_pass;
use crate::params::ParamReader;
use crate::{ProgressLog, Progressive, ProgressiveRun};
use lt_core::Scene;
use lt_estimators::running::RunningImage;
use lt_estimators::Image;
use std::cell::RefCell;
use std::sync::atomic::{AtomicU64, Ordering};

/// Fixed-point scale of pass 0's radius statistics.
const FIXED: f64 = 4294967296.0;

#[derive(Clone, Copy, Debug)]
pub struct PmParams {
    pub max_depth: u32,
    pub rr_depth: u32,
    /// `None`: 4 × the pixel count.
    pub photons: Option<u64>,
    pub radius: InitialRadius,
    pub knn: Option<u32>,
    pub kernel: Kernel,
    pub direct: Direct,
}

impl PmParams {
    pub fn read(scene: &Scene, r: &ParamReader) -> Result<PmParams, String> {
        let photons = r.get::<u64>("photons")?;
        if photons == Some(0) {
            return Err("pm: photons must be at least 1".into());
        }
        let knn = r.get::<u32>("knn")?;
        if knn == Some(0) {
            return Err("pm: knn must be at least 1".into());
        }
        Ok(PmParams {
            max_depth: r.max_depth(scene)?,
            rr_depth: r.rr_depth(scene)?,
            photons,
            radius: InitialRadius::read(r, "pm")?,
            knn,
            kernel: r.get_with("kernel", Kernel::parse)?.unwrap_or(Kernel::Disk),
            direct: r.get_with("direct", Direct::parse)?.unwrap_or(Direct::Nee),
        })
    }
}

pub struct Pm {
    pub params: PmParams,
}

impl Progressive for Pm {
    fn name(&self) -> &'static str {
        "pm"
    }

    fn start<'a>(&'a self, scene: &'a Scene, seed: u64) -> Box<dyn ProgressiveRun + 'a> {
        let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
        Box::new(PmRun {
            pm: self,
            scene,
            seed,
            map: None,
            acc: RunningImage::new(w, h),
            log: ProgressLog::default(),
        })
    }
}

struct PmRun<'a> {
    pm: &'a Pm,
    scene: &'a Scene,
    seed: u64,
    /// Traced on the first pass (so a run's set-up is timed as part of it).
    map: Option<PhotonMap>,
    acc: RunningImage,
    log: ProgressLog,
}

impl PmRun<'_> {
    fn build_map(&mut self) -> PhotonMap {
        let p = &self.pm.params;
        let scene = self.scene;
        let paths = p.photons.unwrap_or(4 * scene.camera.pixel_count() as u64);
        let opts = PhotonOptions {
            max_segments: p.max_depth.saturating_sub(1),
            rr_depth: p.rr_depth,
            skip_direct: p.direct == Direct::Nee,
        };
        let batch = trace_photons(scene, self.seed, 0, 0, paths, opts);
        // Cells about the radius a query at the scene's centre would use.
        let centre = (scene.bounding_sphere.0 - scene.camera.eye)
            .length()
            .max(1e-6);
        let typical = match p.radius {
            InitialRadius::Pixels(k) => k * scene.camera.pixel_footprint(centre),
            InitialRadius::Scene(f) => f * 2.0 * scene.bounding_sphere.1,
            InitialRadius::Absolute(r) => r,
        };
        self.log.photon_paths.push(paths);
        self.log
            .facts
            .push(("photons_stored".into(), batch.photons.len().to_string()));
        self.log.facts.push(("radius".into(), p.radius.describe()));
        if let Some(k) = p.knn {
            self.log.facts.push(("knn".into(), k.to_string()));
        }
        PhotonMap::new(batch, typical.max(1e-12))
    }
}

impl ProgressiveRun for PmRun<'_> {
    fn pass(&mut self, pass: u32) -> u64 {
        if self.map.is_none() {
            self.map = Some(self.build_map());
        } else {
            self.log.photon_paths.push(0);
        }
        let map = self.map.as_ref().expect("built above");
        let p = &self.pm.params;
        let scene = self.scene;
        // Pass 0 measures the radii and footprints it used: sums in fixed point (2⁻³² scene
        // units), so they are exact and order-independent without a lock per pixel.
        let (r_fixed, fp_fixed, n_vp) = (AtomicU64::new(0), AtomicU64::new(0), AtomicU64::new(0));
        let fixed = |x: f32| (x as f64 * FIXED) as u64;
        let (img, bad) = pixel_pass(scene, self.seed, pass, |sampler, raster| {
            let prefix = trace_visible_point(scene, raster, sampler, p.max_depth, p.direct);
            let Some(vp) = prefix.vp else {
                return prefix.direct();
            };
            let r = p.radius.at(scene, &vp);
            let q = Gather {
                scene,
                gp: &vp.gp,
                kernel: p.kernel,
                max_depth: p.max_depth,
            };
            let l = match p.knn {
                None => map.radiance_within(&q, r),
                Some(k) => {
                    SCRATCH.with(|s| map.radiance_knn(&q, k as usize, 8.0 * r, &mut s.borrow_mut()))
                }
            };
            if pass == 0 {
                r_fixed.fetch_add(fixed(r), Ordering::Relaxed);
                fp_fixed.fetch_add(fixed(vp.footprint), Ordering::Relaxed);
                n_vp.fetch_add(1, Ordering::Relaxed);
            }
            prefix.direct() + vp.gp.beta * l
        });
        self.acc.add(&img);
        let r_sum = r_fixed.into_inner() as f64 / FIXED;
        let fp_sum = fp_fixed.into_inner() as f64 / FIXED;
        if pass == 0 {
            let n = n_vp.into_inner().max(1) as f64;
            self.log.mean_radius.push(r_sum / n);
            if let Some(w) = p.radius.warning(fp_sum / n) {
                self.log.facts.push(("warning".into(), w));
            }
        } else {
            let last = self.log.mean_radius.last().copied().unwrap_or(0.0);
            self.log.mean_radius.push(last);
        }
        self.log.radius_scale.push(1.0);
        bad
    }

    fn estimate(&self) -> Image {
        self.acc.mean()
    }

    fn log(&self) -> ProgressLog {
        self.log.clone()
    }
}

// k-nearest results, one buffer per worker thread.
thread_local! {
    static SCRATCH: RefCell<Vec<(u32, f32)>> = const { RefCell::new(Vec::new()) };
}

//! The keys and techniques of the VCM family (`vcm`, `bpm`, `eamis`) and the initial radius r₀.

use crate::density::radius::InitialRadius;
use crate::params::ParamReader;
use lt_core::math::Vec2;
use lt_core::path::Heuristic;
use lt_core::Scene;

/// The techniques and schedule of a VCM-family estimator.
#[derive(Clone, Copy, Debug)]
pub struct VcmParams {
    pub max_depth: u32,
    pub rr_depth: u32,
    pub mis: Heuristic,
    /// `None`: one light subpath per pixel.
    pub light_paths: Option<u64>,
    pub radius: InitialRadius,
    pub alpha: f64,
    /// Connections s ≥ 1 (bdpt's techniques); s = 0 always runs.
    pub connections: bool,
    pub merging: bool,
    /// Correlation-aware MIS for merging (`lt_core::path::camis`): every weight from the full
    /// path's densities instead of the per-vertex recursion. Off by default.
    pub correlation_aware: bool,
    /// Vertex connections s ≥ 2, t ≥ 2 (with `connections`); off keeps next-event estimation
    /// and light tracing. Off needs full-path weights (`SubpathMis` counts every connection).
    pub vertex_connections: bool,
}

/// SmallVCM's radius reduction.
pub const DEFAULT_ALPHA: f64 = 0.75;

/// Which techniques a VCM-family estimator runs besides light tracing (t = 1) and the camera
/// walk reaching a light (s = 0), which always run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Techniques {
    /// Connections s ≥ 1, t ≥ 2 (bdpt's techniques).
    pub connections: bool,
    /// Merging at camera vertices (photon mapping's technique).
    pub merging: bool,
}

impl Techniques {
    /// `vcm`: connections and merging under one MIS.
    pub const VCM: Techniques = Techniques {
        connections: true,
        merging: true,
    };
    /// `bpm`: merging without connections (Georgiev et al. 2012's bidirectional photon mapping).
    pub const BPM: Techniques = Techniques {
        connections: false,
        merging: true,
    };
    /// `vcm merging=false`: bdpt's techniques under VCM's bookkeeping.
    pub const CONNECTIONS: Techniques = Techniques {
        connections: true,
        merging: false,
    };
}

impl VcmParams {
    /// Reads the keys common to `vcm` and `bpm`.
    pub fn read(
        scene: &Scene,
        r: &ParamReader,
        who: &str,
        techniques: Techniques,
    ) -> Result<VcmParams, String> {
        let base = VcmParams::read_base(scene, r, who, Heuristic::Power)?;
        Ok(VcmParams {
            light_paths: r.light_paths()?,
            connections: techniques.connections,
            merging: techniques.merging,
            correlation_aware: r.get::<bool>("correlation_aware")?.unwrap_or(false),
            // bpm has no connections to turn off.
            vertex_connections: if techniques.connections {
                r.get::<bool>("vertex_connections")?.unwrap_or(true)
            } else {
                true
            },
            ..base
        })
    }

    /// The keys every VCM-family estimator reads — `max_depth`, `rr_depth`, `mis` (default
    /// `mis`), the initial radius and `alpha` — with one light subpath per pixel, every technique
    /// and recursive weights; refuses an orthographic camera.
    pub fn read_base(
        scene: &Scene,
        r: &ParamReader,
        who: &str,
        mis: Heuristic,
    ) -> Result<VcmParams, String> {
        if scene.camera.is_delta_direction() {
            // Its MIS records count light tracing as a technique; with a camera that no
            // connection reaches, that share would be lost.
            return Err(format!(
                "{who} cannot render through an orthographic camera (a delta in direction: no \
                 light-tracing connection reaches it); use pt or bdpt"
            ));
        }
        let alpha = r.get::<f64>("alpha")?.unwrap_or(DEFAULT_ALPHA);
        if !(alpha > 0.0 && alpha <= 1.0) {
            return Err(format!("{who}: alpha must be in (0, 1], got {alpha}"));
        }
        Ok(VcmParams {
            max_depth: r.max_depth(scene)?,
            rr_depth: r.rr_depth(scene)?,
            mis: r.get_with("mis", Heuristic::parse)?.unwrap_or(mis),
            light_paths: None,
            radius: InitialRadius::read(r, who)?,
            alpha,
            connections: true,
            merging: true,
            correlation_aware: false,
            vertex_connections: true,
        })
    }

    /// Whether weights come from the full path's densities (`camis::weigh`) rather than the
    /// per-vertex recursion: the recursion counts every connection and one η for every pixel.
    pub fn full_path_weights(&self) -> bool {
        self.correlation_aware || (self.connections && !self.vertex_connections)
    }

    pub fn light_path_count(&self, scene: &Scene) -> u64 {
        self.light_paths
            .unwrap_or(scene.camera.pixel_count() as u64)
    }

    /// r_i / r_0 of pass `pass` (0-based; iteration i = pass + 1).
    pub fn radius_scale(&self, pass: u32) -> f64 {
        ((pass + 1) as f64).powf((self.alpha - 1.0) / 2.0)
    }
}

/// r₀ in scene units: footprint-relative radii use the footprint at the mean distance of primary
/// hits over a fixed grid of pixel centres (deterministic, and one radius for the whole pass).
pub fn initial_radius(scene: &Scene, radius: InitialRadius) -> f32 {
    match radius {
        InitialRadius::Pixels(k) => {
            let cam = &scene.camera;
            let step = (cam.width.max(cam.height) / 64).max(1);
            let (mut sum, mut n) = (0.0f64, 0u64);
            for y in (0..cam.height).step_by(step as usize) {
                for x in (0..cam.width).step_by(step as usize) {
                    let ray = cam.generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                    if let Some(hit) = scene.intersect(&ray) {
                        sum += ((hit.p - ray.o).dot(cam.forward())) as f64;
                        n += 1;
                    }
                }
            }
            let distance = if n > 0 {
                (sum / n as f64) as f32
            } else {
                scene.bounding_sphere.1
            };
            k * cam.pixel_footprint(distance)
        }
        InitialRadius::Scene(f) => f * 2.0 * scene.bounding_sphere.1,
        InitialRadius::Absolute(r) => r,
    }
}

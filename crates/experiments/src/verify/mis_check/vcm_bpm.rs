//! `lt mis-check --integrator vcm|bpm`: the weights `vcm` and `bpm` applied to the paths they
//! completed, by connection or by merging, against the from-scratch oracle
//! (`Densities::vcm_weight`, which knows every connection technique and merging at every non-delta
//! x_i with density η ∏_{j≤i} l_j ∏_{j≥i} c_j), and the partition of unity of the integrator's own
//! recursion replayed on the oracle's densities (`SubpathMis::replay`) over every technique that
//! can make the path.
//!
//! **Merged paths have two x_i**: the light vertex y_i and the camera vertex z within r of it.
//! The oracle (`Densities::merged`) takes the light side from the path through y_i (a specular
//! x_{i−1} aims the light walk at y_i, not z), the camera side from the path through z, and the
//! two densities joining them from z's BSDF with the light vertex's incoming direction, as
//! Georgiev et al. define a merge. It rebuilds every direction from positions, so the tolerance
//! is derived as for connections (`tolerance::derived_tolerance`), with the vertices of both
//! subpaths moved within their rounding boxes: y_i and z separately, since a merge's weight reads
//! the light vertex's incoming direction through z's BSDF.

use super::quota::QuotaCounts;
pub use super::report::Report;
use super::report::Verdict;
use super::tolerance::{derived_tolerance, relative, weight_error_bound, DEFAULT_SLACK};
use lt_core::path::{
    camis, Correlation, Densities, Heuristic, Path, PathVertex, SubpathMis, Technique, TechniqueSet,
};
use lt_core::Scene;
use lt_integrators::radius::InitialRadius;
use lt_integrators::record::{Completed, Merged, Recorder};
use lt_integrators::registry::{self, Weights};
use lt_integrators::splat::{Pass, Splats, Worker};
use lt_integrators::vcm::engine::{
    initial_radius, pixel_of, Engine, MergeMask, PassInputs, VcmParams,
};

/// What to sample and how to judge it.
#[derive(Clone, Copy, Debug)]
pub struct VcmOptions {
    /// vcm (true) or bpm (false).
    pub connections: bool,
    pub heuristic: Heuristic,
    /// Paths kept per (k, technique).
    pub paths: usize,
    pub max_depth: u32,
    pub rr_depth: u32,
    pub seed: u64,
    pub resolution: u32,
    pub max_passes: u32,
    pub light_paths: Option<u64>,
    /// Multiplier on the derived tolerance of (a) (`tolerance::derived_tolerance`).
    pub slack: f64,
    pub radius: InitialRadius,
    /// Correlation-aware MIS for merging (`lt_core::path::camis`): the integrator's option, and
    /// the oracle's weights with ρ_i; the sum and replay then run `camis::weight` (the
    /// integrator's full-path routine) on the oracle's densities.
    pub correlation_aware: bool,
    /// Vertex connections s ≥ 2, t ≥ 2 (vcm's option; off is one of eamis's choices): off, the
    /// oracle drops those techniques and the replay runs the full-path routine.
    pub vertex_connections: bool,
    /// Merging only in the pixels of a checkerboard (eamis's per-pixel choice, through
    /// `Run::with_merge_mask`'s route): each record's η is its pixel's, 0 off the board.
    pub checkerboard_merging: bool,
}

impl VcmOptions {
    pub fn new(scene: &Scene, connections: bool) -> VcmOptions {
        VcmOptions {
            connections,
            heuristic: Heuristic::Power,
            paths: 1000,
            max_depth: scene.settings.max_depth,
            rr_depth: scene.settings.rr_depth,
            seed: 1,
            resolution: 16,
            max_passes: 2000,
            light_paths: None,
            slack: DEFAULT_SLACK,
            // Large radii (relative to the 16² film's footprint) so merging techniques carry
            // weights far from 0 and 1, where a wrong density shows.
            radius: InitialRadius::Pixels(2.0),
            correlation_aware: false,
            vertex_connections: true,
            checkerboard_merging: false,
        }
    }

    /// Whether the integrator weighs from the full path's densities (`camis::weigh`).
    fn full_path(&self) -> bool {
        self.correlation_aware || !self.vertex_connections || self.checkerboard_merging
    }

    /// The registered integrator whose weights these options check.
    pub fn name(&self) -> &'static str {
        let weights = Weights::ConnectMerge {
            connections: self.connections,
        };
        registry::with_weights(move |w| w == weights)
            .next()
            .expect("both connect-merge variants are registered")
    }

    fn params(&self) -> VcmParams {
        VcmParams {
            max_depth: self.max_depth,
            rr_depth: self.rr_depth,
            mis: self.heuristic,
            light_paths: self.light_paths,
            radius: self.radius,
            alpha: lt_integrators::vcm::engine::DEFAULT_ALPHA,
            connections: self.connections,
            merging: true,
            correlation_aware: self.correlation_aware,
            vertex_connections: self.vertex_connections,
        }
    }
}

/// One recorded path.
#[derive(Clone, Debug)]
pub struct VcmRecord {
    pub technique: Technique,
    pub light: Vec<PathVertex>,
    pub camera: Vec<PathVertex>,
    pub weight: f64,
    /// η of the pass that made it.
    pub eta: f64,
}

impl VcmRecord {
    pub fn k(&self) -> usize {
        match self.technique {
            Technique::Connect(_) => self.light.len() + self.camera.len() - 1,
            Technique::Merge(_) => self.light.len() + self.camera.len() - 2,
        }
    }

    /// The path with x_i at the camera vertex (merges) or as connected.
    pub fn path(&self) -> Path {
        match self.technique {
            Technique::Connect(_) => Path::from_subpaths(&self.light, &self.camera),
            Technique::Merge(i) => Path::from_subpaths(&self.light[..i], &self.camera),
        }
    }

    /// For merges, the path with x_i at the light vertex.
    pub fn light_side_path(&self) -> Option<Path> {
        let Technique::Merge(_) = self.technique else {
            return None;
        };
        let t = self.camera.len();
        Some(Path::from_subpaths(&self.light, &self.camera[..t - 1]))
    }
}

/// Keeps up to `quota` paths per (k, technique).
pub struct VcmCollector {
    pub counts: QuotaCounts<Technique>,
    pub records: Vec<VcmRecord>,
    eta: f64,
    /// The pixels that merge (`VcmOptions::checkerboard_merging`).
    mask: Option<MergeMask>,
    width: u32,
    height: u32,
}

impl VcmCollector {
    /// η of a path landing at `raster`: the pass's, 0 in a pixel that does not merge.
    fn eta_at(&self, raster: lt_core::math::Vec2) -> f64 {
        match &self.mask {
            Some(m) if !m[pixel_of(raster, self.width, self.height)] => 0.0,
            _ => self.eta,
        }
    }

    fn keep(&mut self, k: usize, t: Technique) -> bool {
        self.counts.keep(k, t)
    }

    /// Every length has `quota` paths, whatever their techniques.
    fn full(&self) -> bool {
        let c = &self.counts;
        (1..=c.max_depth()).all(|k| c.of_length(k, |_| true) >= c.quota())
    }
}

impl Recorder for VcmCollector {
    const ACTIVE: bool = true;

    fn completed(&mut self, p: Completed) {
        let k = p.light.len() + p.camera.len() - 1;
        if self.keep(k, Technique::Connect(p.s)) {
            self.records.push(VcmRecord {
                technique: Technique::Connect(p.s),
                light: p.light.to_vec(),
                camera: p.camera.to_vec(),
                weight: p.weight,
                eta: self.eta_at(p.raster),
            });
        }
    }

    fn merged(&mut self, p: Merged) {
        let k = p.light.len() + p.camera.len() - 2;
        if self.keep(k, Technique::Merge(p.i)) {
            self.records.push(VcmRecord {
                technique: Technique::Merge(p.i),
                light: p.light.to_vec(),
                camera: p.camera.to_vec(),
                weight: p.weight,
                eta: self.eta_at(p.raster),
            });
        }
    }
}

/// Sets `scene`'s film to the check's resolution.
pub fn prepare_scene(scene: &mut Scene, opts: &VcmOptions) {
    scene.camera = scene
        .camera
        .with_resolution(opts.resolution, opts.resolution);
}

/// Runs passes of the integrator on `scene` (at the check's resolution) until every length has
/// its paths or `max_passes` ran.
pub fn collect(scene: &Scene, opts: &VcmOptions) -> (VcmCollector, u32) {
    let params = opts.params();
    let mut engine = Engine::new(&params, scene);
    let cam = &scene.camera;
    let board = |i: usize| (i % cam.width as usize + i / cam.width as usize).is_multiple_of(2);
    let mask: Option<MergeMask> = opts
        .checkerboard_merging
        .then(|| (0..cam.pixel_count()).map(board).collect());
    engine.merge_mask = mask.clone();
    let r0 = initial_radius(scene, params.radius);
    let mut c = VcmCollector {
        counts: QuotaCounts::new(opts.paths, opts.max_depth as usize),
        records: Vec::new(),
        eta: 0.0,
        mask,
        width: cam.width,
        height: cam.height,
    };
    let mut scratch = engine.scratch();
    let mut passes = 0;
    while passes < opts.max_passes && !c.full() {
        let setup = engine.setup(r0, passes);
        let lights = engine.trace_light_paths(&setup, opts.seed, passes);
        c.eta = setup.eta;
        let items = (cam.pixel_count() as u64).max(params.light_path_count(scene));
        let mut splats = Splats::new(cam.width, cam.height);
        let inputs = PassInputs {
            setup: &setup,
            lights: &lights,
            pass: Pass {
                seed: opts.seed,
                pass: passes,
            },
        };
        let mut worker = Worker {
            splats: &mut splats,
            scratch: &mut scratch,
            rec: &mut c,
        };
        for i in 0..items {
            engine.item(&inputs, i, &mut worker);
        }
        passes += 1;
    }
    (c, passes)
}

fn densities(scene: &Scene, path: &Path, ratio: f64) -> Densities {
    let mut d = path.densities(scene);
    d.light_tracing_ratio = ratio;
    d
}

/// The correlation-aware MIS inputs of `path` under `opts` (none with the option off): N_VM
/// light subpaths, the footprint at the distance of the primary hit x_{k−1} from x_k.
fn correlation(path: &Path, opts: &VcmOptions, light_paths: f64) -> Option<Correlation> {
    opts.correlation_aware.then(|| {
        let v = &path.vertices;
        let k = v.len() - 1;
        Correlation::new(light_paths, (v[k].p - v[k - 1].p).length() as f64)
    })
}

/// Checks one record; `ratio` = M/N, `light_paths` = M.
pub fn check_record(
    scene: &Scene,
    r: &VcmRecord,
    opts: &VcmOptions,
    (ratio, light_paths): (f64, f64),
) -> Verdict {
    let set = TechniqueSet {
        vertex_connections: opts.connections && opts.vertex_connections,
        ..TechniqueSet::new(opts.connections, r.eta)
    };
    let h = opts.heuristic;
    let path = r.path();
    let corr = correlation(&path, opts, light_paths);
    let corr = corr.as_ref();
    let d = match r.technique {
        Technique::Merge(_) => {
            let mut d = Densities::merged(scene, &r.light, &r.camera);
            d.light_tracing_ratio = ratio;
            d
        }
        Technique::Connect(_) => densities(scene, &path, ratio),
    };
    let oracle = d.vcm_weight_with(set, corr, r.technique, h);
    let mismatch = relative(r.weight, oracle);
    let weight = |d: &Densities| d.vcm_weight_with(set, corr, r.technique, h);
    let bound = match r.technique {
        Technique::Merge(_) => {
            let both: Vec<PathVertex> = r.light.iter().chain(&r.camera).copied().collect();
            let n = r.light.len();
            let merged = |v: &[PathVertex]| {
                let mut d = Densities::merged(scene, &v[..n], &v[n..]);
                d.light_tracing_ratio = ratio;
                d
            };
            weight_error_bound(&both, merged, weight)
        }
        Technique::Connect(_) => weight_error_bound(
            &path.vertices,
            |v| {
                densities(
                    scene,
                    &Path {
                        vertices: v.to_vec(),
                    },
                    ratio,
                )
            },
            weight,
        ),
    };
    let allowed = derived_tolerance(bound, opts.slack);
    let mis = SubpathMis::new(h, set, ratio);
    let techniques = d.vcm_techniques(set);
    let mut sum = 0.0;
    let mut replay_error = 0.0f64;
    for &t in &techniques {
        let w = if opts.full_path() {
            camis::weight(&d.chain(), set, corr, t, h)
        } else {
            mis.replay(&d, t)
        };
        replay_error = replay_error.max((w - d.vcm_weight_with(set, corr, t, h)).abs());
        sum += w;
    }
    Verdict {
        k: path.k(),
        technique: r.technique,
        weight: r.weight,
        oracle,
        mismatch,
        allowed,
        sum_error: if sum.is_nan() {
            f64::INFINITY
        } else {
            sum - 1.0
        },
        replay_error,
        valid: techniques,
    }
}

/// Samples and checks; `scene`'s film is set to the check's resolution first.
pub fn check_scene(scene: &mut Scene, opts: &VcmOptions, name: &str) -> Report {
    prepare_scene(scene, opts);
    let (c, passes) = collect(scene, opts);
    check_records(scene, &c.records, opts, passes, c.counts.too_long, name)
}

/// Checks every record (from `collect`, or altered by hand in tests).
pub fn check_records(
    scene: &Scene,
    records: &[VcmRecord],
    opts: &VcmOptions,
    passes: u32,
    too_long: usize,
    scene_name: &str,
) -> Report {
    let n = scene.camera.pixel_count() as u64;
    let light_paths = opts.light_paths.unwrap_or(n) as f64;
    let ratio = light_paths / n as f64;
    let mut name = opts.name().to_string();
    if opts.correlation_aware {
        name += " correlation_aware";
    }
    let mut report = Report::new(scene_name, name, opts.heuristic, opts.max_depth);
    report.slack = opts.slack;
    report.merging = true;
    report.passes = passes;
    report.too_long = too_long;
    for r in records {
        let v = check_record(scene, r, opts, (ratio, light_paths));
        report.add(&v);
        let (over, sum_fail) = (v.over(), v.sum_fails());
        let shown = report
            .examples
            .iter()
            .filter(|e: &&String| e.contains("Σw−1 FAIL") == sum_fail)
            .count();
        if (over || sum_fail) && shown < 3 {
            report.examples.push(format!(
                "k={} {:?} weight={:.9e} oracle={:.9e} rel={:.3e} allowed={:.3e} Σw−1={:.3e}{} techniques={:?}",
                v.k, v.technique, r.weight, v.oracle, v.mismatch, v.allowed,
                v.sum_error, if sum_fail { " Σw−1 FAIL" } else { "" }, v.valid
            ));
        }
    }
    report.finish()
}

/// The report under the name the tests import (`Report`, shared with `pt_bdpt`).
pub type VcmReport = Report;

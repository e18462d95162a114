//! `lt mis-check --integrator upbp`: the weights `upbp` applied to the paths it completed — by a
//! connection, by a photon point at a camera medium vertex (PP3D), by a photon near a camera
//! beam (PB2D), by a photon beam near a camera beam (BB1D), by a photon beam near a camera
//! medium vertex (BP2D) or by a surface merge (vcm's) — against the from-scratch oracle
//! (`Densities::upbp_weight`, `lt_core::path::volume_merging`: every connection technique, PP3D,
//! PB2D and BB1D at every medium vertex, each density and rate rebuilt from the path's
//! positions), and the partition of unity of the
//! integrator's own routine (`upbp::weights::weight`) replayed on the oracle's densities over
//! every technique that can make the path.
//!
//! A merged path has two x_i (the photon y_i and the camera side's medium vertex or beam query
//! point; for BB1D the photon beam's point y_i), as vcm's merges (`vcm_bpm`); the oracle takes
//! the light side from the photon's path and the camera side from the camera's
//! (`Densities::volume_merged`, `VolumeRates::merged`). The tolerance is derived from the
//! rounding of the vertices as for connections (`tolerance::derived_tolerance`), the rates σ̂
//! and sin θ held at the unperturbed path's.

use super::quota::QuotaCounts;
use super::report::{Report, Verdict};
use super::tolerance::{derived_tolerance, relative, weight_error_bound, DEFAULT_SLACK};
use lt_core::path::volume_merging::VolumeRates;
use lt_core::path::{
    Densities, Heuristic, Path, PathVertex, Technique, UpbpMode, VolumeSet, VolumeTechnique,
};
use lt_core::Scene;
use lt_integrators::params::{IntegratorParams, ParamReader};
use lt_integrators::record::{Completed, Recorder, VolumeMerged};
use lt_integrators::upbp::weights::{weight, VertexRate};
use lt_integrators::upbp::Upbp;
use std::collections::BTreeMap;

/// What to sample and how to judge it.
#[derive(Clone, Debug)]
pub struct UpbpOptions {
    pub heuristic: Heuristic,
    /// Paths kept per (k, technique).
    pub paths: usize,
    pub max_depth: u32,
    pub seed: u64,
    pub resolution: u32,
    pub max_passes: u32,
    pub slack: f64,
    /// `upbp`'s `techniques` (all by default).
    pub techniques: String,
    /// `upbp`'s `radius_scene`: larger than its default so that merges carry weights far from 0
    /// and 1, where a wrong density shows.
    pub radius_scene: f32,
    /// `upbp`'s `beams` (short or long).
    pub beams: String,
    /// `upbp`'s `mode` (full, compatible or previous).
    pub mode: String,
}

impl UpbpOptions {
    pub fn new(scene: &Scene) -> UpbpOptions {
        UpbpOptions {
            heuristic: Heuristic::Power,
            paths: 200,
            max_depth: scene.settings.max_depth,
            seed: 1,
            resolution: 8,
            max_passes: 200,
            slack: DEFAULT_SLACK,
            techniques: "all".into(),
            radius_scene: 0.05,
            beams: "short".into(),
            mode: "full".into(),
        }
    }

    fn integrator(&self, scene: &Scene) -> Result<Upbp, String> {
        let p = IntegratorParams::new()
            .with("max_depth", self.max_depth)
            .with("mis", self.heuristic.name())
            .with("techniques", &self.techniques)
            .with("radius_scene", self.radius_scene)
            .with("beams", &self.beams)
            .with("mode", &self.mode);
        Upbp::read(scene, &ParamReader::new("upbp", &p))
    }
}

/// One recorded path.
#[derive(Clone, Debug)]
pub struct UpbpRecord {
    pub technique: VolumeTechnique,
    pub light: Vec<PathVertex>,
    pub camera: Vec<PathVertex>,
    pub weight: f64,
    /// The pass's techniques and η's.
    pub set: Option<VolumeSet>,
}

impl UpbpRecord {
    pub fn k(&self) -> usize {
        match self.technique {
            VolumeTechnique::Connect(_) => self.light.len() + self.camera.len() - 1,
            _ => self.light.len() + self.camera.len() - 2,
        }
    }

    fn merged(&self) -> bool {
        !matches!(self.technique, VolumeTechnique::Connect(_))
    }
}

/// Keeps up to `quota` paths per (k, technique).
pub struct UpbpCollector {
    pub counts: QuotaCounts<VolumeTechnique>,
    pub records: Vec<UpbpRecord>,
}

/// The report's kind of a technique: connections, or which volumetric estimator.
pub fn kind(t: &VolumeTechnique) -> &'static str {
    match t {
        VolumeTechnique::Connect(_) => "connections",
        VolumeTechnique::Point(_) => "pp3d",
        VolumeTechnique::Beam(_) => "pb2d",
        VolumeTechnique::BeamBeam(_) => "bb1d",
        VolumeTechnique::Surface(_) => "surf",
        VolumeTechnique::BeamPoint(_) => "bp2d",
    }
}

impl UpbpCollector {
    fn keep(&mut self, k: usize, t: VolumeTechnique) -> bool {
        self.counts.keep(k, t)
    }

    /// Every length has its quota of each kind of technique seen so far.
    fn full(&self) -> bool {
        let c = &self.counts;
        let kinds = ["connections", "pp3d", "pb2d", "bb1d", "surf", "bp2d"];
        (1..=c.max_depth()).all(|k| {
            kinds.iter().all(|&name| {
                let n = c.of_length(k, |t| kind(t) == name);
                n == 0 || n >= c.quota()
            })
        }) && !self.records.is_empty()
    }
}

impl Recorder for UpbpCollector {
    const ACTIVE: bool = true;

    fn completed(&mut self, p: Completed) {
        let k = p.light.len() + p.camera.len() - 1;
        let t = VolumeTechnique::Connect(p.s);
        if self.keep(k, t) {
            self.records.push(UpbpRecord {
                technique: t,
                light: p.light.to_vec(),
                camera: p.camera.to_vec(),
                weight: p.weight,
                set: None,
            });
        }
    }

    fn volume_merged(&mut self, p: VolumeMerged) {
        let k = p.light.len() + p.camera.len() - 2;
        let t = p.technique;
        if self.keep(k, t) {
            self.records.push(UpbpRecord {
                technique: t,
                light: p.light.to_vec(),
                camera: p.camera.to_vec(),
                weight: p.weight,
                set: None,
            });
        }
    }
}

/// Runs passes of `upbp` on `scene` (at the check's resolution) until every length has its
/// paths of each kind or `max_passes` ran.
pub fn collect(scene: &Scene, opts: &UpbpOptions) -> Result<(UpbpCollector, u32), String> {
    let upbp = opts.integrator(scene)?;
    let mut c = UpbpCollector {
        counts: QuotaCounts::new(opts.paths, opts.max_depth as usize),
        records: Vec::new(),
    };
    let mut passes = 0;
    while passes < opts.max_passes && !(passes >= 2 && c.full()) {
        let setup = upbp.record_pass(scene, opts.seed, passes, &mut c);
        for r in c.records.iter_mut().filter(|r| r.set.is_none()) {
            r.set = Some(setup.set);
        }
        passes += 1;
    }
    Ok((c, passes))
}

/// The oracle's densities and rates of a record (from scratch).
fn oracle(scene: &Scene, r: &UpbpRecord, ratio: f64) -> (Densities, VolumeRates) {
    let (mut d, rates) = if r.merged() {
        (
            Densities::volume_merged(scene, &r.light, &r.camera),
            VolumeRates::merged(scene, &r.light, &r.camera),
        )
    } else {
        let path = Path::from_subpaths(&r.light, &r.camera);
        (path.densities(scene), VolumeRates::of_path(scene, &path))
    };
    d.light_tracing_ratio = ratio;
    (d, rates)
}

/// The report's name for a technique: PP3D, PB2D and BB1D at x_i as merges at x_i.
fn as_reported(t: VolumeTechnique) -> Technique {
    match t {
        VolumeTechnique::Connect(s) => Technique::Connect(s),
        VolumeTechnique::Point(i)
        | VolumeTechnique::Beam(i)
        | VolumeTechnique::BeamBeam(i)
        | VolumeTechnique::Surface(i)
        | VolumeTechnique::BeamPoint(i) => Technique::Merge(i),
    }
}

/// Checks one record; `ratio` = M/N.
pub fn check_record(scene: &Scene, r: &UpbpRecord, opts: &UpbpOptions, ratio: f64) -> Verdict {
    let set = r.set.expect("every record carries its pass's set");
    let h = opts.heuristic;
    let (d, rates) = oracle(scene, r, ratio);
    let oracle_w = d.upbp_weight(set, &rates, r.technique, h);
    let mismatch = relative(r.weight, oracle_w);
    let both: Vec<PathVertex> = r.light.iter().chain(&r.camera).copied().collect();
    let n = r.light.len();
    let weigh = |d: &Densities| d.upbp_weight(set, &rates, r.technique, h);
    let bound = if r.merged() {
        let densities = |v: &[PathVertex]| {
            let mut d = Densities::volume_merged(scene, &v[..n], &v[n..]);
            d.light_tracing_ratio = ratio;
            d
        };
        weight_error_bound(&both, densities, weigh)
    } else {
        let path = Path::from_subpaths(&r.light, &r.camera);
        let densities = |v: &[PathVertex]| {
            let mut d = Path {
                vertices: v.to_vec(),
            }
            .densities(scene);
            d.light_tracing_ratio = ratio;
            d
        };
        weight_error_bound(&path.vertices, densities, weigh)
    };
    let allowed = derived_tolerance(bound, opts.slack);
    let techniques = d.upbp_techniques(set, &rates);
    let vol: Vec<VertexRate> = (0..rates.medium.len())
        .map(|j| VertexRate {
            medium: rates.medium[j],
            rate: rates.rate[j],
            light_rate: rates.light_side(&set, j),
            sin: rates.sin[j],
        })
        .collect();
    let chain = d.chain();
    let mut sum = 0.0;
    let mut replay_error = 0.0f64;
    for &t in &techniques {
        let w = weight(&chain, &vol, &set, t, h);
        replay_error = replay_error.max((w - d.upbp_weight(set, &rates, t, h)).abs());
        sum += w;
    }
    // Under compatible/previous a path outside class ES*M(S|D|M)*L has no technique: Σw = 0.
    let expected = if techniques.is_empty() && set.mode != UpbpMode::Full {
        0.0
    } else {
        1.0
    };
    let mut valid: Vec<Technique> = techniques.iter().map(|&t| as_reported(t)).collect();
    valid.dedup();
    Verdict {
        k: r.k(),
        technique: as_reported(r.technique),
        weight: r.weight,
        oracle: oracle_w,
        mismatch,
        allowed,
        sum_error: if sum.is_nan() {
            f64::INFINITY
        } else {
            sum - expected
        },
        replay_error,
        valid,
    }
}

/// Sets `scene`'s film to the check's resolution.
pub fn prepare_scene(scene: &mut Scene, opts: &UpbpOptions) {
    scene.camera = scene
        .camera
        .with_resolution(opts.resolution, opts.resolution);
}

/// Samples and checks; `scene`'s film is set to the check's resolution first. Returns the report
/// and a line per kind of technique (connections, pp3d, pb2d, bb1d): paths checked, the largest
/// relative mismatch, the paths failing.
pub fn check_scene(
    scene: &mut Scene,
    opts: &UpbpOptions,
    name: &str,
) -> Result<(Report, String), String> {
    prepare_scene(scene, opts);
    let (c, passes) = collect(scene, opts)?;
    Ok(check_records(
        scene,
        &c.records,
        opts,
        (passes, c.counts.too_long),
        name,
    ))
}

/// Checks every record (from `collect`, or altered by hand in tests); see `check_scene`.
pub fn check_records(
    scene: &Scene,
    records: &[UpbpRecord],
    opts: &UpbpOptions,
    (passes, too_long): (u32, usize),
    name: &str,
) -> (Report, String) {
    let ratio = 1.0;
    let mut report = Report::new(name, "upbp".into(), opts.heuristic, opts.max_depth);
    report.slack = opts.slack;
    report.merging = true;
    report.passes = passes;
    report.too_long = too_long;
    let mut kinds = BTreeMap::new();
    for r in records {
        let v = check_record(scene, r, opts, ratio);
        let e = kinds
            .entry(kind(&r.technique))
            .or_insert((0usize, 0.0f64, 0usize));
        e.0 += 1;
        e.1 = e.1.max(v.mismatch);
        e.2 += (v.over() || v.sum_fails()) as usize;
        report.add(&v);
        let shown = report.examples.len();
        if (v.over() || v.sum_fails()) && shown < 6 {
            report.examples.push(format!(
                "k={} {:?} weight={:.9e} oracle={:.9e} rel={:.3e} allowed={:.3e} Σw−1={:.3e} \
                 replay={:.3e}",
                v.k,
                r.technique,
                r.weight,
                v.oracle,
                v.mismatch,
                v.allowed,
                v.sum_error,
                v.replay_error
            ));
        }
    }
    let mut summary = String::new();
    for (kind, (n, worst, bad)) in kinds {
        summary += &format!(
            "  upbp {kind}: {n} paths checked, largest relative mismatch {worst:.3e}, {bad} failing\n"
        );
    }
    (report.finish(), summary)
}

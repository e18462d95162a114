//! `lt mis-check`: samples paths with an integrator's own code (through its `Recorder` hooks) and
//! holds the MIS weights it applied to the from-scratch oracle of `lt_core::path`.
//!
//! Per recorded path x̄ of k segments made by technique s:
//!
//! - **(a) oracle.** The weight the integrator used against `oracle_weight` over the effective
//!   densities of `Path::densities` (bdpt: every technique 0 … k+1; pt: only 0 = BSDF hit and
//!   1 = NEE, and only 0 for k = 1). The mismatch is relative, |w − w°| / max(w, w°): the
//!   heuristics' weights have bounded log-derivatives (|∂ ln w_s / ∂ ln p_i| ≤ β), so a relative
//!   error ε in the walk's densities moves a weight by at most ~βε relatively, whatever its size;
//!   an absolute measure would hide a wrong density behind a small weight. A weight that is zero
//!   on one side only is a mismatch of 1.
//!
//!   **Tolerance**, per path, derived from what the walks round (`tolerance::derived_tolerance`):
//!   the walks build densities in f32 from the directions they traced, the oracle in f64 from
//!   directions it rebuilds from two f32 positions, so on a short, grazing or glossy segment the
//!   two legitimately differ. The bound sums, over the path's densities, how far each moves when
//!   the vertices move within (twice) their rounding boxes — finite differences of the oracle
//!   itself, so glossy lobes and grazing cosines are amplified exactly as in the walks — times
//!   β = 2, plus the f32 arithmetic of 2(k + 1) stored densities. It replaced a fixed τ = 1e-3
//!   and a max-over-segments condition number, which cried wolf at 10⁵ paths (a k = 6 path in a
//!   corner of 0.8 mm segments, 3.2e-3 off where 2.9e-3 was allowed) while letting a weight off by
//!   9e-4 pass on any path.
//! - **(b) partition of unity.** Σ_s' w_s' = 1 over the techniques, each by the integrator's own
//!   code: for pt `weight + alternatives`; for bdpt `bdpt::mis_weight` replayed for every valid
//!   technique s' on the same path split at s', its vertices' `pdf_fwd`/`pdf_rev` set from the
//!   oracle's densities (as the walks would have set them) and its end evaluations from
//!   `connect::eval_towards`. This exercises bdpt's patching and the chain arithmetic; (a)
//!   exercises the densities the walks filled. Each replayed weight is also compared with the
//!   oracle's (`replay` column).
//!
//! The table (`report::Report`, shared with `vcm_bpm`) has one row per path length k.

pub use super::report::Report;
use super::report::Verdict;
use super::tolerance::{derived_tolerance, relative, weight_error_bound, DEFAULT_SLACK};
use lt_core::bsdf::TransportMode;
use lt_core::math::{Color, Vec2};
use lt_core::path::{oracle_weight, Heuristic, Path, PathVertex, Technique, VertexKind};
use lt_core::sampling::{Domain, Sampler};
use lt_core::Scene;
use lt_integrators::bdpt::{
    mis_weight_in, with_chain_in, Bdpt, BdptParams, BdptWeights, EndEvals, Split,
};
use lt_integrators::connect::eval_towards;
use lt_integrators::lvc_bdpt::{lvc_weight, LvcBdpt, LvcParams};
use lt_integrators::pt::{Pt, PtParams, Techniques};
use lt_integrators::record::{Completed, Recorder};
use lt_integrators::registry::{self, Weights};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Which {
    Pt,
    Bdpt,
    /// lvc-bdpt: bdpt's techniques with connections counted n_conn = N / L̄ times.
    Lvc,
}

impl Which {
    /// The registered integrator whose weights this checker holds (the registry's name, not a
    /// copy of it).
    pub fn name(self) -> &'static str {
        let weights = match self {
            Which::Pt => Weights::PathTracing,
            Which::Bdpt => Weights::Connections,
            Which::Lvc => Weights::VertexCache,
        };
        registry::with_weights(move |w| w == weights)
            .next()
            .expect("every checker's weights are registered")
    }
}

/// What to sample and how to judge it.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    pub integrator: Which,
    pub heuristic: Heuristic,
    /// Paths kept per (k, s); sampling stops once every k ≤ max_depth has at least this many.
    pub paths: usize,
    pub max_depth: u32,
    pub rr_depth: u32,
    pub seed: u64,
    pub resolution: u32,
    pub max_passes: u32,
    pub light_paths: Option<u64>,
    /// lvc-bdpt: cache vertices per camera vertex (N).
    pub connections: u32,
    /// Multiplier on the derived tolerance of (a) (`tolerance::derived_tolerance`).
    pub slack: f64,
}

impl Options {
    /// Defaults for `scene`: bdpt, power, the scene's depths, 16×16, the derived tolerance as is.
    pub fn new(scene: &Scene, integrator: Which) -> Options {
        Options {
            integrator,
            heuristic: Heuristic::Power,
            paths: 1000,
            max_depth: scene.settings.max_depth,
            rr_depth: scene.settings.rr_depth,
            seed: 1,
            resolution: 16,
            max_passes: 2000,
            light_paths: None,
            connections: 1,
            slack: DEFAULT_SLACK,
        }
    }
}

/// One completed path as an integrator reported it (an owned `Completed`).
#[derive(Clone, Debug)]
pub struct Record {
    pub s: usize,
    pub light: Vec<PathVertex>,
    pub camera: Vec<PathVertex>,
    pub weight: f64,
    pub value: Color,
    pub raster: Vec2,
    pub alternatives: Vec<(usize, f64)>,
}

impl Record {
    /// Segments k of the full path.
    pub fn k(&self) -> usize {
        self.light.len() + self.camera.len() - 1
    }

    pub fn path(&self) -> Path {
        Path::from_subpaths(&self.light, &self.camera)
    }
}

/// A `Recorder` keeping up to `quota` paths per (k, s).
pub struct Collector {
    pub quota: usize,
    pub max_depth: usize,
    /// counts[k][s].
    counts: Vec<Vec<usize>>,
    pub records: Vec<Record>,
    /// Paths reported with k beyond max_depth (an integrator bug; checked as an error).
    pub too_long: usize,
}

impl Collector {
    pub fn new(quota: usize, max_depth: usize) -> Collector {
        Collector {
            quota,
            max_depth,
            counts: (0..=max_depth).map(|k| vec![0; k + 2]).collect(),
            records: Vec::new(),
            too_long: 0,
        }
    }

    /// Paths kept of length k (all techniques).
    pub fn of_length(&self, k: usize) -> usize {
        self.counts[k].iter().sum()
    }

    /// Every length 1 … max_depth has at least `quota` paths.
    pub fn full(&self) -> bool {
        (1..=self.max_depth).all(|k| self.of_length(k) >= self.quota)
    }
}

impl Recorder for Collector {
    const ACTIVE: bool = true;

    fn completed(&mut self, p: Completed) {
        let k = p.light.len() + p.camera.len() - 1;
        if k > self.max_depth || p.s > k + 1 {
            self.too_long += 1;
            return;
        }
        if self.counts[k][p.s] >= self.quota {
            return;
        }
        self.counts[k][p.s] += 1;
        self.records.push(Record {
            s: p.s,
            light: p.light.to_vec(),
            camera: p.camera.to_vec(),
            weight: p.weight,
            value: p.value,
            raster: p.raster,
            alternatives: p.alternatives.to_vec(),
        });
    }
}

/// Sets `scene`'s film to the check's resolution (passes run over every pixel).
pub fn prepare_scene(scene: &mut Scene, opts: &Options) {
    scene.camera = scene
        .camera
        .with_resolution(opts.resolution, opts.resolution);
}

/// M/N of the run (bdpt's light-tracing ratio; 1 for pt, which has no light tracing).
pub fn light_tracing_ratio(scene: &Scene, opts: &Options) -> f64 {
    match opts.integrator {
        Which::Pt => 1.0,
        Which::Bdpt | Which::Lvc => {
            let n = scene.camera.pixel_count() as u64;
            opts.light_paths.unwrap_or(n) as f64 / n as f64
        }
    }
}

fn lvc(scene: &Scene, opts: &Options) -> LvcBdpt {
    LvcBdpt::new(
        scene,
        LvcParams {
            max_depth: opts.max_depth,
            rr_depth: opts.rr_depth,
            mis: opts.heuristic,
            light_paths: opts.light_paths,
            connections: opts.connections,
        },
    )
}

/// The oracle's sample count of a connection technique (2 ≤ s ≤ k − 1) relative to a camera
/// sample's: 1 for bdpt; for lvc-bdpt n_conn = N·L/|C| = N / L̄ (derived in `lvc_bdpt`'s module
/// docs), computed here from N and the integrator's measured L̄ (its pilot), not taken from it.
pub fn connection_count(scene: &Scene, opts: &Options) -> f64 {
    match opts.integrator {
        Which::Lvc => {
            let mean = lvc(scene, opts).mean_cached;
            if mean > 0.0 {
                opts.connections as f64 / mean
            } else {
                0.0
            }
        }
        _ => 1.0,
    }
}

/// Runs passes of the integrator on `scene` (already at the check's resolution) until every
/// length has its paths or `max_passes` ran. Returns the collector and the passes run.
pub fn collect(scene: &Scene, opts: &Options) -> (Collector, u32) {
    let mut c = Collector::new(opts.paths, opts.max_depth as usize);
    let mut passes = 0;
    match opts.integrator {
        Which::Bdpt => {
            let bdpt = Bdpt {
                params: BdptParams {
                    max_depth: opts.max_depth,
                    rr_depth: opts.rr_depth,
                    mis: opts.heuristic,
                    light_paths: opts.light_paths,
                    // The weights bdpt applies by default: the recursion, held to the oracle.
                    weights: BdptWeights::Recursive,
                },
            };
            while passes < opts.max_passes && !c.full() {
                bdpt.record_pass(scene, opts.seed, passes, &mut c);
                passes += 1;
            }
        }
        Which::Lvc => {
            let lvc = lvc(scene, opts);
            while passes < opts.max_passes && !c.full() {
                lvc.record_pass(scene, opts.seed, passes, &mut c);
                passes += 1;
            }
        }
        Which::Pt => {
            let pt = Pt {
                params: PtParams {
                    max_depth: opts.max_depth,
                    rr_depth: opts.rr_depth,
                    mis: opts.heuristic,
                    techniques: Techniques::Both,
                },
            };
            let w = scene.camera.width as u64;
            let n = scene.camera.pixel_count() as u64;
            while passes < opts.max_passes && !c.full() {
                for i in 0..n {
                    let mut s = Sampler::for_item(Domain::Camera, opts.seed, i, passes as u64);
                    let raster =
                        Vec2::new((i % w) as f32 + s.next_f32(), (i / w) as f32 + s.next_f32());
                    pt.radiance_recorded(scene, raster, &mut s, &mut c);
                }
                passes += 1;
            }
        }
    }
    (c, passes)
}

fn unit_towards(from: &PathVertex, to: &PathVertex) -> lt_core::Vec3 {
    from.dir_to(to)
}

/// The `delta` flag a walk stores: a delta surface, or a surface the path leaves through a delta
/// lobe beside smooth ones (plastic: the oracle's `connectable` is false there), or a light delta
/// in direction, or a camera delta in direction (orthographic: `PathVertex::camera_at`).
fn is_delta(scene: &Scene, v: &PathVertex, d: &lt_core::path::Densities, i: usize) -> bool {
    match v.kind {
        VertexKind::Surface { material } => {
            scene.material(material).is_delta() || !d.connectable[i]
        }
        VertexKind::Light { light, .. } => scene.lights[light as usize].delta_direction(),
        VertexKind::Camera => scene.camera.is_delta_direction(),
        VertexKind::Medium { .. } => false,
    }
}

/// bdpt's own weight of technique `sp` for `path`, replayed through `bdpt::mis_weight` with the
/// subpath densities a walk would have stored, taken from the oracle's `d`.
fn replay_bdpt(
    scene: &Scene,
    path: &Path,
    d: &lt_core::path::Densities,
    sp: usize,
    h: Heuristic,
    ratio: f64,
    n_conn: f64,
) -> f64 {
    let v = &path.vertices;
    let k = path.k();
    // Light side x0 … x_{sp−1}: as the light walk stored them.
    let mut light: Vec<PathVertex> = (0..sp)
        .map(|i| {
            let mut x = v[i];
            x.pdf_fwd = d.light[i] as f32;
            x.pdf_rev = d.camera[i] as f32;
            x.wo = if i == 0 {
                lt_core::Vec3::ZERO
            } else {
                unit_towards(&v[i], &v[i - 1])
            };
            x.delta = is_delta(scene, &v[i], d, i);
            x
        })
        .collect();
    if sp == 1 && k >= 2 {
        light[0].pdf_fwd = d.nee as f32;
    }
    // Camera side x_k … x_sp, camera first: as the camera walk stored them.
    let camera: Vec<PathVertex> = (sp..=k)
        .rev()
        .map(|i| {
            let mut x = v[i];
            x.pdf_fwd = d.camera[i] as f32;
            x.pdf_rev = d.light[i] as f32;
            x.wo = if i == k {
                lt_core::Vec3::ZERO
            } else {
                unit_towards(&v[i], &v[i + 1])
            };
            x.delta = is_delta(scene, &v[i], d, i);
            x
        })
        .collect();
    let t = k + 1 - sp;
    let light_end = (sp >= 2).then(|| {
        eval_towards(
            scene,
            &light[sp - 1],
            unit_towards(&v[sp - 1], &v[sp]),
            TransportMode::Importance,
        )
    });
    let camera_end = (sp >= 1 && t >= 2).then(|| {
        eval_towards(
            scene,
            &camera[t - 1],
            unit_towards(&v[sp], &v[sp - 1]),
            TransportMode::Radiance,
        )
    });
    let split = Split {
        light: &light,
        camera: &camera,
        light_nee: d.nee,
    };
    let evals = EndEvals {
        light_end: light_end.flatten(),
        camera_end: camera_end.flatten(),
        // The checker holds the path alone: the patched free flights are walked anew.
        flights: None,
    };
    // Through media the join's patched densities take their free flights (`with_chain_in`).
    match (n_conn == 1.0, scene.has_media) {
        (true, false) => mis_weight_in::<false>(scene, split, evals, h, ratio),
        (true, true) => mis_weight_in::<true>(scene, split, evals, h, ratio),
        (false, media) => {
            let lvc = |c: &lt_core::path::Chain, s| lvc_weight(c, s, h, n_conn);
            if media {
                with_chain_in::<true, _>(scene, split, evals, ratio, lvc)
            } else {
                with_chain_in::<false, _>(scene, split, evals, ratio, lvc)
            }
        }
    }
}

/// The effective densities n_s·p_s of the techniques `which` runs (the others zeroed): every
/// s = 0 … k+1 for bdpt and lvc-bdpt; for pt 0 (BSDF hit) and, on paths of two segments or
/// more, 1 (NEE). Connections (2 ≤ s ≤ k − 1) count `n_conn` (`connection_count`).
pub fn effective(d: &lt_core::path::Densities, which: Which, n_conn: f64) -> Vec<f64> {
    let mut eff = d.effective_all();
    let k = d.k();
    for e in eff.iter_mut().take(k).skip(2) {
        *e *= n_conn;
    }
    if which == Which::Pt {
        let keep = if d.k() >= 2 { 1 } else { 0 };
        for e in eff.iter_mut().skip(keep + 1) {
            *e = 0.0;
        }
    }
    eff
}

/// Checks one recorded path (see the module docs).
pub fn check_record(scene: &Scene, r: &Record, opts: &Options, ratio: f64, n_conn: f64) -> Verdict {
    let path = r.path();
    let k = path.k();
    let mut d = path.densities(scene);
    d.light_tracing_ratio = ratio;
    let eff = effective(&d, opts.integrator, n_conn);
    let h = opts.heuristic;
    let valid: Vec<usize> = (0..eff.len())
        .filter(|&s| d.valid(s) && eff[s] > 0.0)
        .collect();
    let oracle = oracle_weight(&eff, r.s, h);
    let mismatch = relative(r.weight, oracle);
    let bound = weight_error_bound(
        &path.vertices,
        |v| {
            let mut d = Path {
                vertices: v.to_vec(),
            }
            .densities(scene);
            d.light_tracing_ratio = ratio;
            d
        },
        |d| oracle_weight(&effective(d, opts.integrator, n_conn), r.s, h),
    );
    let (sum, replay_error) = match opts.integrator {
        Which::Pt => (
            r.weight + r.alternatives.iter().map(|a| a.1).sum::<f64>(),
            0.0,
        ),
        Which::Bdpt | Which::Lvc => {
            let mut sum = 0.0;
            let mut worst = 0.0f64;
            for &sp in &valid {
                let w = replay_bdpt(scene, &path, &d, sp, h, ratio, n_conn);
                worst = worst.max((w - oracle_weight(&eff, sp, h)).abs());
                sum += w;
            }
            (sum, worst)
        }
    };
    let sum_error = if sum.is_nan() {
        f64::INFINITY
    } else {
        sum - 1.0
    };
    Verdict {
        k,
        technique: Technique::Connect(r.s),
        weight: r.weight,
        oracle,
        mismatch,
        allowed: derived_tolerance(bound, opts.slack),
        sum_error,
        replay_error,
        valid: valid.into_iter().map(Technique::Connect).collect(),
    }
}

fn kind_name(scene: &Scene, v: &PathVertex) -> String {
    match v.kind {
        VertexKind::Camera => "camera".into(),
        VertexKind::Light { light, infinite } => {
            let l = &scene.lights[light as usize];
            let what = if l.delta_direction() {
                "directional"
            } else if infinite {
                "infinite"
            } else if l.delta_position() {
                "point"
            } else {
                "area"
            };
            format!("light#{light}({what})")
        }
        VertexKind::Surface { material } => {
            let m = scene.material(material);
            format!(
                "surf#{material}{}",
                if m.is_delta() { "(delta)" } else { "" }
            )
        }
        VertexKind::Medium { medium } => format!("medium#{medium}"),
    }
}

/// Describes a failing path: its vertices, the weights, the densities.
pub fn describe(
    scene: &Scene,
    r: &Record,
    c: &Verdict,
    opts: &Options,
    ratio: f64,
    n_conn: f64,
) -> String {
    let path = r.path();
    let kinds: Vec<String> = path.vertices.iter().map(|v| kind_name(scene, v)).collect();
    let mut d = path.densities(scene);
    d.light_tracing_ratio = ratio;
    let eff = effective(&d, opts.integrator, n_conn);
    let oracle_all: Vec<String> = (0..eff.len())
        .map(|s| format!("{:.6e}", oracle_weight(&eff, s, opts.heuristic)))
        .collect();
    // What the walks stored, in path order (light side: pdf_fwd = l_i, pdf_rev = c_i; camera
    // side: pdf_fwd = c_i, pdf_rev = l_i), beside the segment lengths and end cosines.
    let k = path.k();
    let stored: Vec<String> = (0..=k)
        .map(|i| {
            let v = &path.vertices[i];
            let (l, c) = if i < r.s {
                (v.pdf_fwd, v.pdf_rev)
            } else {
                (v.pdf_rev, v.pdf_fwd)
            };
            format!("x{i}: l={l:e} c={c:e}")
        })
        .collect();
    let segs: Vec<String> = (0..k)
        .map(|i| {
            let (a, b) = (&path.vertices[i], &path.vertices[i + 1]);
            let w = a.dir_to(b);
            let len = if a.is_infinite() || b.is_infinite() {
                f32::INFINITY
            } else {
                (b.p - a.p).length()
            };
            let (ma, mb) = (a.medium_towards(scene, w), b.medium_towards(scene, -w));
            let ff = |x: &PathVertex, y: &PathVertex, m| {
                scene.free_flight_density(x.into(), y.into(), m, y.in_medium())
            };
            format!(
                "{i}-{}: len={len:.3e} cos=({:.3e},{:.3e}) derr={:.1e} p=({},{}) media=({ma:?},{mb:?}) ff=({:e},{:e})",
                i + 1,
                a.ng.dot(w).abs(),
                b.ng.dot(w).abs(),
                lt_core::path::scatter::direction_error(a, b),
                a.p,
                b.p,
                ff(a, b, ma),
                ff(b, a, mb)
            )
        })
        .collect();
    format!(
        "k={} s={} path=[{}] weight={:.9e} oracle={:.9e} rel={:.3e} allowed={:.2e} Σw−1={:.3e} alternatives={:?}\n    \
         eff p_s={:?}\n    oracle w_s=[{}]\n    light={:?}\n    camera={:?} nee={:e}\n    stored {}\n    segments {}",
        c.k,
        r.s,
        kinds.join(" → "),
        r.weight,
        c.oracle,
        c.mismatch,
        c.allowed,
        c.sum_error,
        r.alternatives,
        eff,
        oracle_all.join(", "),
        d.light,
        d.camera,
        d.nee,
        stored.join("; "),
        segs.join("; ")
    )
}

/// Checks every record; `records` may come from `collect` or be built by hand (tests).
pub fn check_records(
    scene: &Scene,
    records: &[Record],
    opts: &Options,
    passes: u32,
    too_long: usize,
    scene_name: &str,
) -> Report {
    let ratio = light_tracing_ratio(scene, opts);
    let n_conn = connection_count(scene, opts);
    let name = opts.integrator.name().to_string();
    let mut report = Report::new(scene_name, name, opts.heuristic, opts.max_depth);
    report.slack = opts.slack;
    report.passes = passes;
    report.too_long = too_long;
    for r in records {
        let c = check_record(scene, r, opts, ratio, n_conn);
        report.add(&c);
        if (c.over() || c.sum_fails()) && report.examples.len() < 5 {
            report
                .examples
                .push(describe(scene, r, &c, opts, ratio, n_conn));
        }
    }
    report.finish()
}

/// Samples and checks; `scene`'s film is set to the check's resolution first.
pub fn check_scene(scene: &mut Scene, opts: &Options, name: &str) -> Report {
    prepare_scene(scene, opts);
    let (c, passes) = collect(scene, opts);
    check_records(scene, &c.records, opts, passes, c.too_long, name)
}

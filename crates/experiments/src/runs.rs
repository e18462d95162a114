//! One unit of cached work: a render described completely by a `RunSpec` (scene, resolution,
//! integrator, parameters, seed, passes, snapshots), executed at most once per code version and
//! scene content into the cache (`crate::cache`). Studies, references and cluster shards are all
//! lists of `RunSpec`s; a study's figures are computed from the entries alone, so a study that was
//! interrupted, or whose renders ran on a cluster, is finished by running it again.
//!
//! An entry holds `snapshot-<P>.exr` (the estimate after P passes, for each snapshot P),
//! `stderr.exr` when the render has an honest standard error, and `record.json` (`RunRecord`).

use crate::cache::{scene_hash, RenderCache};
use crate::image_io::{read_exr, write_exr};
use lt_core::Scene;
use lt_estimators::Image;
use lt_integrators::{make_integrator, render_runs, IntegratorParams, Kind, RenderOptions};
use serde::{Deserialize, Serialize};
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct RunSpec {
    /// The scene file (its content, not its path, enters the key).
    pub scene: PathBuf,
    /// Film size override (width, height); the camera keeps its field of view.
    pub resolution: Option<(u32, u32)>,
    pub integrator: String,
    /// Integrator parameters as key=value pairs, kept sorted by key.
    pub params: Vec<(String, String)>,
    /// The seed of run 0; run k uses seed + k.
    pub seed: u64,
    /// Independent runs; with more than one, the entry holds their mean and standard error and
    /// a single snapshot at `passes`.
    pub runs: u32,
    pub passes: u32,
    /// Pass counts after which the estimate is stored, ascending; always includes `passes`.
    pub snapshots: Vec<u32>,
}

impl RunSpec {
    pub fn new(scene: impl Into<PathBuf>, integrator: &str, seed: u64, passes: u32) -> RunSpec {
        RunSpec {
            scene: scene.into(),
            resolution: None,
            integrator: integrator.to_string(),
            params: Vec::new(),
            seed,
            runs: 1,
            passes,
            snapshots: vec![passes],
        }
    }

    pub fn resolution(mut self, res: Option<(u32, u32)>) -> RunSpec {
        self.resolution = res;
        self
    }

    pub fn param(mut self, key: &str, value: impl ToString) -> RunSpec {
        self.params.retain(|(k, _)| k != key);
        self.params.push((key.to_string(), value.to_string()));
        self.params.sort();
        self
    }

    pub fn runs(mut self, runs: u32) -> RunSpec {
        self.runs = runs;
        self
    }

    /// Snapshots at these pass counts (sorted, deduplicated, `passes` added).
    pub fn snapshots(mut self, at: impl IntoIterator<Item = u32>) -> RunSpec {
        let mut s: Vec<u32> = at
            .into_iter()
            .filter(|&p| p >= 1 && p <= self.passes)
            .collect();
        s.push(self.passes);
        s.sort_unstable();
        s.dedup();
        self.snapshots = s;
        self
    }

    pub fn integrator_params(&self) -> IntegratorParams {
        let mut p = IntegratorParams::new();
        for (k, v) in &self.params {
            p.set(k, v);
        }
        p
    }

    /// The scene as this run renders it (resolution applied).
    pub fn load_scene(&self) -> Result<Scene, String> {
        let mut scene = crate::scene_load::load(&self.scene).map_err(|e| e.to_string())?;
        if let Some((w, h)) = self.resolution {
            if w == 0 || h == 0 {
                return Err(format!("resolution {w}×{h} has no pixels"));
            }
            scene.camera = scene.camera.with_resolution(w, h);
        }
        Ok(scene)
    }

    /// What the cache key is made of: everything but the scene's path.
    pub fn key_material(&self, scene: &Scene) -> Result<serde_json::Value, String> {
        Ok(serde_json::json!({
            "what": "render",
            "scene_hash": scene_hash(&scene.source_files)?,
            "resolution": self.resolution,
            "integrator": self.integrator,
            "params": self.params,
            "seed": self.seed,
            "runs": self.runs,
            "passes": self.passes,
            "snapshots": self.snapshots,
        }))
    }

    /// A short name for progress lines.
    pub fn label(&self) -> String {
        let stem = self
            .scene
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_default();
        let params: Vec<String> = self
            .params
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect();
        format!(
            "{stem} {} {}seed {} × {} passes",
            self.integrator,
            if params.is_empty() {
                String::new()
            } else {
                format!("[{}] ", params.join(" "))
            },
            self.seed,
            self.passes
        )
    }
}

/// Whether the registry lists `integrator` as consistent (error bars from independent runs);
/// false for a name it does not know.
pub fn is_consistent(integrator: &str) -> bool {
    lt_integrators::registry::find(integrator).is_ok_and(|i| i.kind == Kind::Consistent)
}

/// What a finished run records beside its images.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunRecord {
    pub spec: RunSpec,
    pub kind: String,
    /// Wall seconds at each snapshot (cumulative from the start of the run; with several runs,
    /// the seconds of all of them).
    pub seconds: Vec<f64>,
    /// CPU seconds of the render's threads at each snapshot, as `seconds` (empty in records
    /// written before it was kept, and in ones assembled from cluster parts).
    #[serde(default)]
    pub cpu_seconds: Vec<f64>,
    pub passes_done: u32,
    pub invalid_samples: u64,
    /// The mean over pixels and channels of `stderr.exr`, when there is one.
    pub mean_std_error: Option<f64>,
    /// Where the standard error comes from: "spread of passes", "independent runs" or "none".
    pub std_error_source: String,
    /// Per pass, r_i/r_0 and the mean radius, for progressive estimators.
    pub radius_scale: Vec<f64>,
    pub mean_radius: Vec<f64>,
    /// The first run's log facts (Metropolis: b̂, acceptance, batch-means ESS); empty in
    /// records written before they were kept.
    #[serde(default)]
    pub facts: Vec<(String, String)>,
    pub code_version: String,
    pub threads: usize,
}

impl RunRecord {
    /// The threads it rendered with; 0 (one per core) is taken to mean this machine's cores.
    pub fn effective_threads(&self) -> usize {
        match self.threads {
            0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
            t => t,
        }
    }

    /// Whether its integrator is consistent, as the registry says.
    pub fn consistent(&self) -> bool {
        is_consistent(&self.spec.integrator)
    }
}

/// A finished run in the cache.
#[derive(Clone, Debug)]
pub struct RunEntry {
    pub dir: PathBuf,
    pub record: RunRecord,
}

impl RunEntry {
    pub fn open(dir: &Path) -> Result<RunEntry, String> {
        let path = dir.join("record.json");
        let text = std::fs::read_to_string(&path)
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        let record = serde_json::from_str(&text)
            .map_err(|e| format!("{}: not a run record: {e}", path.display()))?;
        Ok(RunEntry {
            dir: dir.to_path_buf(),
            record,
        })
    }

    /// The estimate after `passes` passes (one of the spec's snapshots).
    pub fn snapshot(&self, passes: u32) -> Result<Image, String> {
        read_exr(&self.dir.join(format!("snapshot-{passes}.exr")))
    }

    /// The final estimate.
    pub fn image(&self) -> Result<Image, String> {
        self.snapshot(self.record.spec.passes)
    }

    pub fn std_error(&self) -> Result<Option<Image>, String> {
        let p = self.dir.join("stderr.exr");
        if p.is_file() {
            read_exr(&p).map(Some)
        } else {
            Ok(None)
        }
    }

    /// Where snapshot `passes` is in the record's per-snapshot lists.
    fn snapshot_index(&self, passes: u32) -> Option<usize> {
        self.record.spec.snapshots.iter().position(|&p| p == passes)
    }

    /// Seconds to reach snapshot `passes`.
    pub fn seconds_at(&self, passes: u32) -> Option<f64> {
        self.record
            .seconds
            .get(self.snapshot_index(passes)?)
            .copied()
    }

    /// CPU seconds to reach snapshot `passes`: what equal-time budgets divide. A record without
    /// them counts its wall seconds times its threads (0 threads: this machine's cores), which
    /// is what those threads could have spent at most.
    pub fn cpu_seconds_at(&self, passes: u32) -> Option<f64> {
        let i = self.snapshot_index(passes)?;
        match self.record.cpu_seconds.get(i) {
            Some(&c) => Some(c),
            None => Some(self.record.seconds.get(i)? * self.record.effective_threads() as f64),
        }
    }
}

/// How runs are executed: where the cache is and with how many threads (which changes no image).
#[derive(Clone, Debug)]
pub struct Executor {
    pub cache: RenderCache,
    pub threads: usize,
}

impl Executor {
    /// The finished entry of `spec`, rendering it first if the cache does not have it.
    pub fn run(&self, spec: &RunSpec) -> Result<RunEntry, String> {
        let scene = spec.load_scene()?;
        let material = spec.key_material(&scene)?;
        let dir = self
            .cache
            .get_or_build(&material, |tmp| {
                render_into(spec, &scene, self.threads, tmp)
            })
            .map_err(|e| format!("{}: {e}", spec.label()))?;
        RunEntry::open(&dir)
    }

    /// The entry of `spec` if it is finished, without rendering.
    pub fn lookup(&self, spec: &RunSpec) -> Result<Option<RunEntry>, String> {
        let scene = spec.load_scene()?;
        let key = crate::cache::key_of(&spec.key_material(&scene)?);
        self.cache
            .lookup(&key)
            .map(|d| RunEntry::open(&d))
            .transpose()
    }
}

/// Renders `spec` and writes its entry's files into `dir`.
fn render_into(spec: &RunSpec, scene: &Scene, threads: usize, dir: &Path) -> Result<(), String> {
    if spec.passes == 0 || spec.runs == 0 {
        return Err("a run needs at least one pass and one run".into());
    }
    if spec.runs > 1 && spec.snapshots != [spec.passes] {
        return Err("several runs keep one snapshot, at the last pass".into());
    }
    let params = spec.integrator_params();
    let estimator = make_integrator(&spec.integrator, scene, &params)?;
    let opts = RenderOptions {
        passes: spec.passes,
        time_limit: None,
        seed: spec.seed,
        threads,
    };
    let (mut seconds, mut cpu_seconds) = (Vec::new(), Vec::new());
    let mut write_error = None;
    let result = render_runs(
        scene,
        &estimator,
        &opts,
        spec.runs,
        |_, report| {
            if spec.runs == 1 && spec.snapshots.contains(&report.passes_done) {
                seconds.push(report.elapsed.as_secs_f64());
                cpu_seconds.push(report.cpu.as_secs_f64());
                let path = dir.join(format!("snapshot-{}.exr", report.passes_done));
                if let Err(e) = write_exr(&path, &report.estimate()) {
                    write_error = Some(e);
                    return ControlFlow::Break(());
                }
            }
            ControlFlow::Continue(())
        },
        |_| {},
    )?;
    if let Some(e) = write_error {
        return Err(e);
    }
    let (se, source) = if spec.runs > 1 {
        write_exr(
            &dir.join(format!("snapshot-{}.exr", spec.passes)),
            &result.across_runs.mean(),
        )?;
        seconds = vec![result.elapsed.as_secs_f64()];
        cpu_seconds = vec![result.cpu.as_secs_f64()];
        (Some(result.across_runs.std_error()), "independent runs")
    } else if let Some(p) = &result.per_pass {
        (Some(p.std_error()), "spread of passes")
    } else {
        (None, "none")
    };
    if let Some(se) = &se {
        write_exr(&dir.join("stderr.exr"), se)?;
    }
    let log = result.runs[0].log.as_ref();
    let record = RunRecord {
        spec: spec.clone(),
        kind: match result.kind {
            Kind::Unbiased => "unbiased".into(),
            Kind::Consistent => "consistent".into(),
        },
        seconds,
        cpu_seconds,
        passes_done: result.runs.iter().map(|r| r.passes).sum(),
        invalid_samples: result.invalid_samples,
        mean_std_error: se.as_ref().map(crate::image_io::mean_of),
        std_error_source: source.into(),
        radius_scale: log.map(|l| l.radius_scale.clone()).unwrap_or_default(),
        mean_radius: log.map(|l| l.mean_radius.clone()).unwrap_or_default(),
        facts: log.map(|l| l.facts.clone()).unwrap_or_default(),
        code_version: crate::cache::CODE_VERSION.into(),
        threads,
    };
    let text = serde_json::to_string_pretty(&record).map_err(|e| e.to_string())?;
    crate::image_io::write_atomic(&dir.join("record.json"), text.as_bytes())
}

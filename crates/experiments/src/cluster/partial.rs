//! Exact partial renders: the accumulation of a range of passes of one seed (unbiased
//! estimators), or of a set of independent runs (any estimator), kept in f64 with everything
//! needed to merge it exactly and to refuse merging it with anything it does not belong with.
//!
//! # The `.ltp` file (format version 1)
//!
//! ```text
//! bytes 0..8     magic  "LTPART\0\x01"
//! bytes 8..16    H, the header's length in bytes (u64, little-endian)
//! bytes 16..16+H the header: UTF-8 JSON (`Header`: identity, span, count, checksum, …)
//! then           mean: width·height·3 f64 little-endian, row-major, channels R G B
//! then           M2:   width·height·3 f64 little-endian (sums of squared deviations)
//! ```
//!
//! The header's `payload_blake3` is the BLAKE3 hash of the two arrays, so a truncated or damaged
//! file is refused rather than merged. `count` is the number of passes (span `passes`) or of
//! runs (span `runs`) the mean and M2 are over: with Chan et al.'s pairwise update two parts
//! combine into the accumulator one process would have kept, up to f64 rounding.

use crate::cache::{scene_hash, CODE_VERSION};
use crate::image_io::{mean_of, sibling, write_atomic, write_outputs};
use lt_core::Scene;
use lt_estimators::running::RunningImage;
use lt_estimators::Image;
use lt_integrators::render::render_pass_range;
use lt_integrators::{make_integrator, render_runs, Estimator, IntegratorParams, RenderOptions};
use serde::{Deserialize, Serialize};
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

pub const MAGIC: &[u8; 8] = b"LTPART\0\x01";
pub const FORMAT: &str = "lt-partial";
pub const VERSION: u32 = 1;
/// The file a finished shard's cache entry holds.
pub const ENTRY_FILE: &str = "partial.ltp";

/// Which samples a part holds.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(tag = "mode", rename_all = "snake_case")]
pub enum Span {
    /// Passes `start..end` (counted from 0) of one seed: unbiased estimators only.
    Passes { seed: u64, start: u32, end: u32 },
    /// Independent runs seeded `first_seed .. first_seed + runs`, each of `passes` passes; the
    /// accumulator is over the runs' estimates (as `lt render --runs K`).
    Runs {
        first_seed: u64,
        runs: u32,
        passes: u32,
    },
}

impl Span {
    /// Where the part starts and ends in its sequence (passes, or seeds).
    fn interval(&self) -> (u64, u64) {
        match *self {
            Span::Passes { start, end, .. } => (start as u64, end as u64),
            Span::Runs {
                first_seed, runs, ..
            } => (first_seed, first_seed.saturating_add(runs as u64)),
        }
    }

    pub fn describe(&self) -> String {
        match *self {
            Span::Passes { seed, start, end } => format!("seed {seed}, passes {start}..{end}"),
            Span::Runs {
                first_seed,
                runs,
                passes,
            } => format!(
                "runs of seeds {first_seed}..{} × {passes} passes",
                first_seed.saturating_add(runs as u64)
            ),
        }
    }
}

/// What must be equal for two parts to be parts of one render.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Eq)]
pub struct Identity {
    /// `cache::scene_hash` of the scene's files.
    pub scene_hash: String,
    pub width: u32,
    pub height: u32,
    pub integrator: String,
    /// "unbiased" or "consistent".
    pub kind: String,
    /// Integrator parameters, one per key (the last given wins), sorted by key.
    pub params: Vec<(String, String)>,
    /// The rendering code's version (`cache::CODE_VERSION`).
    pub code_version: String,
}

impl Identity {
    /// The fields in which `self` and `other` differ, as "field (a vs b)".
    pub fn differences(&self, other: &Identity) -> Vec<String> {
        let mut d = Vec::new();
        let mut cmp = |name: &str, a: String, b: String| {
            if a != b {
                d.push(format!("{name} ({a} vs {b})"));
            }
        };
        cmp(
            "scene content",
            self.scene_hash.clone(),
            other.scene_hash.clone(),
        );
        cmp(
            "resolution",
            format!("{}x{}", self.width, self.height),
            format!("{}x{}", other.width, other.height),
        );
        cmp(
            "integrator",
            self.integrator.clone(),
            other.integrator.clone(),
        );
        cmp("kind", self.kind.clone(), other.kind.clone());
        let show = |p: &[(String, String)]| {
            let v: Vec<String> = p.iter().map(|(k, v)| format!("{k}={v}")).collect();
            if v.is_empty() {
                "no parameters".to_string()
            } else {
                v.join(" ")
            }
        };
        cmp("parameters", show(&self.params), show(&other.params));
        cmp(
            "code version",
            self.code_version.clone(),
            other.code_version.clone(),
        );
        d
    }
}

/// The JSON header of a `.ltp` file.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Header {
    pub format: String,
    pub version: u32,
    pub identity: Identity,
    pub span: Span,
    /// Passes (span `passes`) or runs (span `runs`) accumulated.
    pub count: u64,
    /// The scene file as it was given (for people; the hash is what is compared).
    pub scene: String,
    pub invalid_samples: u64,
    pub seconds: f64,
    pub threads: usize,
    pub host: String,
    /// Warnings the integrator raised (deduplicated).
    pub warnings: Vec<String>,
    pub payload_bytes: u64,
    pub payload_blake3: String,
}

/// A partial render in memory.
#[derive(Clone, Debug)]
pub struct Partial {
    pub header: Header,
    pub acc: RunningImage,
}

/// Integrator parameters as an identity holds them: one value per key (the last given), sorted.
pub fn normalize_params(given: &[(String, String)]) -> Vec<(String, String)> {
    let mut out: Vec<(String, String)> = Vec::new();
    for (k, v) in given {
        out.retain(|(k2, _)| k2 != k);
        out.push((k.clone(), v.clone()));
    }
    out.sort();
    out
}

/// Parses `A..B` (passes A to B−1, counted from 0).
pub fn parse_pass_range(text: &str) -> Result<(u32, u32), String> {
    let bad = || format!("--passes expects A..B (passes A to B-1, from 0), got '{text}'");
    let (a, b) = text.split_once("..").ok_or_else(bad)?;
    let a: u32 = a.trim().parse().map_err(|_| bad())?;
    let b: u32 = b.trim().parse().map_err(|_| bad())?;
    if b <= a {
        return Err(format!(
            "--passes {text}: the range is empty (B must exceed A)"
        ));
    }
    Ok((a, b))
}

/// Parses `WxH`.
pub fn parse_resolution(text: &str) -> Result<(u32, u32), String> {
    let bad = || format!("a resolution is WIDTHxHEIGHT, got '{text}'");
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h): (u32, u32) = (
        w.trim().parse().map_err(|_| bad())?,
        h.trim().parse().map_err(|_| bad())?,
    );
    if w == 0 || h == 0 {
        return Err(format!("resolution {text} has no pixels"));
    }
    Ok((w, h))
}

pub fn hostname() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|s| s.trim().to_string())
        .or_else(|_| std::env::var("HOSTNAME"))
        .unwrap_or_else(|_| "unknown".into())
}

/// One partial render, completely described: what a shard of a render plan runs.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct PartialJob {
    pub scene: PathBuf,
    /// Film size override; the camera keeps its field of view.
    pub resolution: Option<(u32, u32)>,
    pub integrator: String,
    /// Normalised (`normalize_params`).
    pub params: Vec<(String, String)>,
    pub span: Span,
}

impl PartialJob {
    pub fn load_scene(&self) -> Result<Scene, String> {
        let mut scene = crate::scene_load::load(&self.scene).map_err(|e| e.to_string())?;
        if let Some((w, h)) = self.resolution {
            if w == 0 || h == 0 {
                return Err(format!("resolution {w}x{h} has no pixels"));
            }
            scene.camera = scene.camera.with_resolution(w, h);
        }
        Ok(scene)
    }

    fn integrator_params(&self) -> IntegratorParams {
        let mut p = IntegratorParams::new();
        for (k, v) in &self.params {
            p.set(k, v);
        }
        p
    }

    fn estimator(&self, scene: &Scene) -> Result<Estimator, String> {
        let est = make_integrator(&self.integrator, scene, &self.integrator_params())?;
        if let (Estimator::Consistent(_), Span::Passes { .. }) = (&est, &self.span) {
            return Err(format!(
                "'{}' is a consistent estimator: its passes share state (photon maps, shrinking \
                 radii), so it cannot be split into pass ranges; split it into independent runs \
                 (--runs K, shards of seeds)",
                self.integrator
            ));
        }
        Ok(est)
    }

    /// The identity of the parts this job makes.
    pub fn identity(&self, scene: &Scene) -> Result<Identity, String> {
        let kind = lt_integrators::registry::find(&self.integrator)?.kind;
        Ok(Identity {
            scene_hash: scene_hash(&scene.source_files)?,
            width: scene.camera.width,
            height: scene.camera.height,
            integrator: self.integrator.clone(),
            kind: kind.name().to_string(),
            params: self.params.clone(),
            code_version: CODE_VERSION.to_string(),
        })
    }

    /// The cache key material of this job's part (the cache adds the code version itself).
    pub fn key_material(&self, scene: &Scene) -> Result<serde_json::Value, String> {
        let id = self.identity(scene)?;
        Ok(serde_json::json!({
            "what": "partial",
            "scene_hash": id.scene_hash,
            "width": id.width,
            "height": id.height,
            "integrator": id.integrator,
            "params": id.params,
            "span": self.span,
        }))
    }

    pub fn validate(&self) -> Result<(), String> {
        match self.span {
            Span::Passes { start, end, .. } if end <= start => {
                Err(format!("the pass range {start}..{end} is empty"))
            }
            Span::Runs { runs: 0, .. } => Err("a part of runs needs at least one run".into()),
            Span::Runs {
                first_seed, runs, ..
            } if first_seed.checked_add(runs as u64).is_none() => {
                Err("the seeds of the runs overflow: use a smaller --seed".into())
            }
            Span::Runs { passes: 0, .. } => Err("a run needs at least one pass".into()),
            _ => Ok(()),
        }
    }

    /// Renders the part. `progress(done, total)` is told after every pass (passes of the range,
    /// or passes of all runs).
    pub fn render(
        &self,
        scene: &Scene,
        threads: usize,
        mut progress: impl FnMut(u64, u64),
    ) -> Result<Partial, String> {
        self.validate()?;
        let identity = self.identity(scene)?;
        let est = self.estimator(scene)?;
        let mut warnings = Vec::new();
        let (acc, invalid, seconds) = match (&self.span, &est) {
            (&Span::Passes { seed, start, end }, Estimator::Unbiased(integ)) => {
                let total = (end - start) as u64;
                let r =
                    render_pass_range(scene, integ.as_ref(), seed, start..end, threads, |d, _| {
                        progress(d as u64, total);
                        ControlFlow::Continue(())
                    })?;
                (r.accumulated, r.invalid_samples, r.elapsed.as_secs_f64())
            }
            (
                &Span::Runs {
                    first_seed,
                    runs,
                    passes,
                },
                _,
            ) => {
                let opts = RenderOptions {
                    passes,
                    time_limit: None,
                    seed: first_seed,
                    threads,
                };
                let total = runs as u64 * passes as u64;
                let r = render_runs(
                    scene,
                    &est,
                    &opts,
                    runs,
                    |k, rep| {
                        progress(k as u64 * passes as u64 + rep.passes_done as u64, total);
                        ControlFlow::Continue(())
                    },
                    |_| {},
                )?;
                for l in r.runs.iter().filter_map(|r| r.log.as_ref()) {
                    for (k, v) in &l.facts {
                        if k == "warning" && !warnings.contains(v) {
                            warnings.push(v.clone());
                        }
                    }
                }
                (r.across_runs, r.invalid_samples, r.elapsed.as_secs_f64())
            }
            (Span::Passes { .. }, Estimator::Consistent(_)) => {
                unreachable!("refused by estimator()")
            }
        };
        let count = acc.count();
        Ok(Partial {
            header: Header {
                format: FORMAT.into(),
                version: VERSION,
                identity,
                span: self.span.clone(),
                count,
                scene: self.scene.display().to_string(),
                invalid_samples: invalid,
                seconds,
                threads,
                host: hostname(),
                warnings,
                payload_bytes: 0,
                payload_blake3: String::new(),
            },
            acc,
        })
    }
}

fn payload(acc: &RunningImage) -> Vec<u8> {
    let (mean, m2) = acc.parts();
    let mut out = Vec::with_capacity((mean.len() + m2.len()) * 24);
    for px in mean.iter().chain(m2) {
        for v in px {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

impl Partial {
    /// The file's bytes (header completed with the payload's size and checksum).
    pub fn to_bytes(&self) -> Result<Vec<u8>, String> {
        let body = payload(&self.acc);
        let mut header = self.header.clone();
        header.payload_bytes = body.len() as u64;
        header.payload_blake3 = blake3::hash(&body).to_hex().to_string();
        let json = serde_json::to_vec_pretty(&header).map_err(|e| e.to_string())?;
        let mut out = Vec::with_capacity(16 + json.len() + body.len());
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&(json.len() as u64).to_le_bytes());
        out.extend_from_slice(&json);
        out.extend_from_slice(&body);
        Ok(out)
    }

    /// Writes the part atomically.
    pub fn write(&self, path: &Path) -> Result<(), String> {
        crate::image_io::write_atomic(path, &self.to_bytes()?)
    }

    pub fn read(path: &Path) -> Result<Partial, String> {
        let bytes =
            std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        Partial::from_bytes(&bytes).map_err(|e| format!("{}: {e}", path.display()))
    }

    pub fn from_bytes(bytes: &[u8]) -> Result<Partial, String> {
        if bytes.len() < 16 || &bytes[..8] != MAGIC {
            return Err(
                "not an lt partial render (no LTPART header; write one with \
                        `lt render … --partial OUT`)"
                    .into(),
            );
        }
        let hlen = u64::from_le_bytes(bytes[8..16].try_into().expect("8 bytes"));
        if hlen > (bytes.len() - 16) as u64 {
            return Err(format!(
                "truncated: the header says it is {hlen} bytes, the file has {} after the magic",
                bytes.len() - 16
            ));
        }
        let hend = 16 + hlen as usize;
        let header: Header =
            serde_json::from_slice(&bytes[16..hend]).map_err(|e| format!("corrupt header: {e}"))?;
        if header.format != FORMAT || header.version != VERSION {
            return Err(format!(
                "format {} version {}: this lt reads {FORMAT} version {VERSION}",
                header.format, header.version
            ));
        }
        let (w, h) = (
            header.identity.width as usize,
            header.identity.height as usize,
        );
        let floats = w
            .checked_mul(h)
            .and_then(|n| n.checked_mul(6))
            .ok_or("corrupt header: impossible resolution")?;
        let body = &bytes[hend..];
        if body.len() != floats * 8 || header.payload_bytes != body.len() as u64 {
            return Err(format!(
                "truncated or padded: a {w}x{h} part holds {} bytes of pixel data, the file has {} \
                 (its header says {})",
                floats * 8,
                body.len(),
                header.payload_bytes
            ));
        }
        if blake3::hash(body).to_hex().as_str() != header.payload_blake3 {
            return Err("corrupt: its pixel data does not match the checksum in its header".into());
        }
        let mut vals = body
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")));
        let mut take = |n: usize| -> Vec<[f64; 3]> {
            (0..n)
                .map(|_| {
                    let r = vals.next().expect("length checked");
                    let g = vals.next().expect("length checked");
                    let b = vals.next().expect("length checked");
                    [r, g, b]
                })
                .collect()
        };
        let mean = take(w * h);
        let m2 = take(w * h);
        let expected = match header.span {
            Span::Passes { start, end, .. } if end > start => (end - start) as u64,
            Span::Runs {
                first_seed, runs, ..
            } if runs > 0 && first_seed.checked_add(runs as u64).is_some() => runs as u64,
            _ => {
                return Err(format!(
                    "corrupt header: impossible span ({})",
                    header.span.describe()
                ))
            }
        };
        if header.count != expected {
            return Err(format!(
                "incomplete: it holds {} of the {expected} {} its span ({}) names",
                header.count,
                if matches!(header.span, Span::Passes { .. }) {
                    "passes"
                } else {
                    "runs"
                },
                header.span.describe()
            ));
        }
        let acc = RunningImage::from_parts(w, h, header.count, mean, m2)
            .map_err(|e| format!("corrupt pixel data: {e}"))?;
        Ok(Partial { header, acc })
    }

    /// The estimate: the mean of the passes or of the runs.
    pub fn mean(&self) -> Image {
        self.acc.mean()
    }
}

/// Parts merged into one accumulator.
#[derive(Clone, Debug)]
pub struct MergedParts {
    pub identity: Identity,
    /// Same mode and fixed fields as the parts; covering the lowest to the highest part.
    pub span: Span,
    pub acc: RunningImage,
    pub scene: String,
    pub parts: usize,
    /// What is missing between the parts (`A..B` of passes or seeds); empty when complete.
    pub missing: Vec<String>,
    pub invalid_samples: u64,
    /// Sum of the parts' render seconds.
    pub seconds: f64,
    pub warnings: Vec<String>,
}

/// Merges parts (each with the file it came from, for messages) in a fixed order — by where each
/// starts — so the result does not depend on the order they are given in. Parts of different
/// scenes, parameters, seeds or code are refused, as are overlapping ranges; gaps (and, for pass
/// ranges, a first part not starting at pass 0) are refused unless `allow_gaps`, and listed in
/// `MergedParts::missing` either way.
pub fn merge(parts: &[(PathBuf, Partial)], allow_gaps: bool) -> Result<MergedParts, String> {
    let Some((first_path, first)) = parts.first() else {
        return Err("no parts to merge".into());
    };
    let id = &first.header.identity;
    for (p, part) in &parts[1..] {
        let diff = id.differences(&part.header.identity);
        if !diff.is_empty() {
            return Err(format!(
                "{} is not a part of the same render as {}: they differ in {}",
                p.display(),
                first_path.display(),
                diff.join(", ")
            ));
        }
        let same_mode = match (&first.header.span, &part.header.span) {
            (Span::Passes { seed: a, .. }, Span::Passes { seed: b, .. }) => {
                if a != b {
                    return Err(format!(
                        "{} holds passes of seed {b}, {} of seed {a}: pass ranges of one render \
                         share its seed (independent seeds are runs: render them with --runs)",
                        p.display(),
                        first_path.display()
                    ));
                }
                true
            }
            (Span::Runs { passes: a, .. }, Span::Runs { passes: b, .. }) => {
                if a != b {
                    return Err(format!(
                        "{} holds runs of {b} passes, {} runs of {a}: runs of different lengths \
                         estimate different images (for a consistent estimator, different biases)",
                        p.display(),
                        first_path.display()
                    ));
                }
                true
            }
            _ => false,
        };
        if !same_mode {
            return Err(format!(
                "{} and {} cannot be merged: one holds a range of passes of one seed, the other \
                 independent runs",
                p.display(),
                first_path.display()
            ));
        }
    }
    let mut order: Vec<usize> = (0..parts.len()).collect();
    order.sort_by_key(|&i| parts[i].1.header.span.interval());
    let unit = match first.header.span {
        Span::Passes { .. } => "passes",
        Span::Runs { .. } => "seeds",
    };
    let mut missing = Vec::new();
    let (lo, _) = parts[order[0]].1.header.span.interval();
    if unit == "passes" && lo > 0 {
        missing.push(format!("passes 0..{lo}"));
    }
    for w in order.windows(2) {
        let (pa, a) = &parts[w[0]];
        let (pb, b) = &parts[w[1]];
        let (a0, a1) = a.header.span.interval();
        let (b0, b1) = b.header.span.interval();
        if b0 < a1 {
            return Err(format!(
                "{} ({unit} {b0}..{b1}) overlaps {} ({unit} {a0}..{a1}): merging them would count \
                 {unit} {b0}..{} twice",
                pb.display(),
                pa.display(),
                a1.min(b1)
            ));
        }
        if b0 > a1 {
            missing.push(format!("{unit} {a1}..{b0}"));
        }
    }
    if !missing.is_empty() && !allow_gaps {
        return Err(format!(
            "the parts do not cover the render: missing {} (merge them anyway with \
             --allow-incomplete)",
            missing.join(", ")
        ));
    }
    let mut acc = RunningImage::new(id.width as usize, id.height as usize);
    let mut warnings: Vec<String> = Vec::new();
    let (mut invalid, mut seconds) = (0, 0.0);
    for &i in &order {
        let part = &parts[i].1;
        acc.merge(&part.acc);
        invalid += part.header.invalid_samples;
        seconds += part.header.seconds;
        for w in &part.header.warnings {
            if !warnings.contains(w) {
                warnings.push(w.clone());
            }
        }
    }
    let (lo, _) = parts[order[0]].1.header.span.interval();
    let (_, hi) = parts[*order.last().expect("nonempty")]
        .1
        .header
        .span
        .interval();
    let span = match first.header.span {
        Span::Passes { seed, .. } => Span::Passes {
            seed,
            start: lo as u32,
            end: hi as u32,
        },
        Span::Runs { passes, .. } => Span::Runs {
            first_seed: lo,
            runs: (hi - lo) as u32,
            passes,
        },
    };
    Ok(MergedParts {
        identity: id.clone(),
        span,
        acc,
        scene: first.header.scene.clone(),
        parts: parts.len(),
        missing,
        invalid_samples: invalid,
        seconds,
        warnings,
    })
}

impl MergedParts {
    /// The merged accumulation as one part (for merging hierarchically).
    pub fn to_partial(&self) -> Partial {
        Partial {
            header: Header {
                format: FORMAT.into(),
                version: VERSION,
                identity: self.identity.clone(),
                span: self.span.clone(),
                count: self.acc.count(),
                scene: self.scene.clone(),
                invalid_samples: self.invalid_samples,
                seconds: self.seconds,
                threads: 0,
                host: hostname(),
                warnings: self.warnings.clone(),
                payload_bytes: 0,
                payload_blake3: String::new(),
            },
            acc: self.acc.clone(),
        }
    }

    /// The standard error and where it comes from, as `lt render` decides: independent runs
    /// when there are two or more, else the spread of an unbiased estimator's passes.
    pub fn std_error(&self) -> (Option<Image>, &'static str) {
        match self.span {
            Span::Runs { .. } if self.acc.count() >= 2 => {
                (Some(self.acc.std_error()), "independent runs")
            }
            Span::Passes { .. } if self.acc.count() >= 2 => {
                (Some(self.acc.std_error()), "spread of passes")
            }
            _ => (
                None,
                "none written: one run of a consistent estimator has no error bar; use more runs",
            ),
        }
    }

    /// Writes what `lt render` writes: OUT.exr, OUT.png, OUT.stderr.exr (when there is an honest
    /// one) and OUT.json, the record saying which parts made it.
    pub fn write_outputs(
        &self,
        out: &Path,
        sources: &[String],
        extra: serde_json::Value,
    ) -> Result<(), String> {
        let mean = self.acc.mean();
        let (se, se_source) = self.std_error();
        write_outputs(out, &mean, se.as_ref())?;
        let mean_se = se.as_ref().map(mean_of);
        let (spp, runs, seed, seeds) = match self.span {
            Span::Passes { seed, start, end } => (end - start, 1, seed, vec![seed]),
            Span::Runs {
                first_seed,
                runs,
                passes,
            } => (
                passes,
                runs,
                first_seed,
                (first_seed..first_seed + runs as u64).collect(),
            ),
        };
        let record = serde_json::json!({
            "scene": self.scene,
            "scene_hash": self.identity.scene_hash,
            "resolution": [self.identity.width, self.identity.height],
            "integrator": self.identity.integrator,
            "kind": self.identity.kind,
            "spp": spp,
            "runs": runs,
            "run_seeds": seeds,
            "seed": seed,
            "params": self.identity.params.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>(),
            "span": self.span,
            "seconds": self.seconds,
            "std_error_source": se_source,
            "mean_std_error": mean_se,
            "invalid_samples": self.invalid_samples,
            "code_version": self.identity.code_version,
            "merged_from": sources,
            "parts": self.parts,
            "missing": self.missing,
            "warnings": self.warnings,
            "merge": "Chan et al.'s pairwise update of (count, mean, M2) in f64, parts in order of their first pass or seed",
            "extra": extra,
        });
        write_atomic(
            &sibling(out, ".json"),
            serde_json::to_string_pretty(&record)
                .map_err(|e| e.to_string())?
                .as_bytes(),
        )
    }
}

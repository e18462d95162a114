//! The seam between plans and the studies: which renders a study needs (`lt plan study`:
//! `study::plan`, each render with the cache it belongs in) and how its outputs are made once
//! they are in the cache (`lt collect`: `study::run_named`, which finds every render).
//!
//! Beside the studies, a tiny built-in one, `smoke` (a few small `pt` renders of the Cornell
//! box; collecting it writes `RESULTS/smoke/summary.json`), exercises plans in the tests without
//! a study's cost.

use crate::cache::Cache;
use crate::runs::{Executor, RunSpec};
use std::path::{Path, PathBuf};

/// Which of a study's caches a render belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// The study's runs: the cache given (default RESULTS/cache).
    Runs,
    /// Long references: RESULTS/references.
    References,
}

/// The cache folder of `role`.
pub fn cache_for(role: Role, runs_cache: &Path, results: &Path) -> PathBuf {
    match role {
        Role::Runs => runs_cache.to_path_buf(),
        Role::References => results.join("references"),
    }
}

fn smoke(scale: &str, scenes: &Path) -> Result<Vec<RunSpec>, String> {
    let (res, passes, seeds) = match scale {
        "test" => ((16, 16), 4, 2),
        "quick" => ((64, 64), 16, 4),
        "full" => ((256, 256), 256, 8),
        other => return Err(format!("unknown scale '{other}' (test, quick, full)")),
    };
    let scene = scenes.join("cornell-box.toml");
    Ok((1..=seeds)
        .map(|seed| {
            RunSpec::new(&scene, "pt", seed, passes)
                .resolution(Some(res))
                .snapshots([passes / 4, passes / 2])
        })
        .collect())
}

/// Every render study `name` needs at `scale`, with the cache it belongs in.
pub fn plan(
    name: &str,
    scale: &str,
    results: &Path,
    scenes: &Path,
    cache: &Path,
) -> Result<Vec<(RunSpec, Role)>, String> {
    if name == "smoke" {
        return Ok(smoke(scale, scenes)?
            .into_iter()
            .map(|s| (s, Role::Runs))
            .collect());
    }
    let ctx = crate::study::Ctx::new(&study_args(name, scale, results, scenes, cache, 0))?;
    let planned = crate::study::plan(name, &ctx.scale, Some(&ctx))?;
    Ok(planned
        .into_iter()
        .map(|(spec, role)| {
            let role = match role {
                crate::study::Role::Runs => Role::Runs,
                crate::study::Role::References => Role::References,
            };
            (spec, role)
        })
        .collect())
}

fn study_args(
    name: &str,
    scale: &str,
    results: &Path,
    scenes: &Path,
    cache: &Path,
    threads: usize,
) -> crate::study::StudyArgs {
    crate::study::StudyArgs {
        name: name.into(),
        full: scale == "full",
        results: results.into(),
        cache: Some(cache.into()),
        scenes: scenes.into(),
        threads,
        quiet: true,
        stop_after: None,
        test_scale: scale == "test",
    }
}

/// Makes study `name`'s outputs under `results` by running it (every render it finds in the
/// cache is not made again); returns a line per study and how many renders were made here.
pub fn collect(
    name: &str,
    scale: &str,
    results: &Path,
    scenes: &Path,
    cache: &Path,
    threads: usize,
) -> Result<(Vec<String>, usize, usize), String> {
    if name == "smoke" {
        return collect_smoke(name, scale, results, scenes, cache, threads);
    }
    let ctx = crate::study::Ctx::new(&study_args(name, scale, results, scenes, cache, threads))?;
    crate::study::run_named(name, &ctx)?;
    let (b1, r1) = ctx.runs.cache.counts();
    let (b2, r2) = ctx.references.cache.counts();
    Ok((Vec::new(), (r1 + r2) as usize, (b1 + b2) as usize))
}

/// Makes study `name`'s outputs under `results`, rendering whatever the cache lacks; returns
/// a line per render and how many were made here.
fn collect_smoke(
    name: &str,
    scale: &str,
    results: &Path,
    scenes: &Path,
    cache: &Path,
    threads: usize,
) -> Result<(Vec<String>, usize, usize), String> {
    let specs: Vec<(RunSpec, Role)> = smoke(scale, scenes)?
        .into_iter()
        .map(|s| (s, Role::Runs))
        .collect();
    let mut rows = Vec::new();
    let mut lines = Vec::new();
    let mut made = 0;
    for (spec, role) in &specs {
        let exec = Executor {
            cache: Cache::new(cache_for(*role, cache, results)),
            threads,
        };
        if exec.lookup(spec)?.is_none() {
            made += 1;
        }
        let entry = exec.run(spec)?;
        let img = entry.image()?;
        let mean = img.data.iter().flatten().sum::<f64>() / (img.data.len() * 3).max(1) as f64;
        lines.push(format!("{}: mean {mean:.6}", spec.label()));
        rows.push(serde_json::json!({
            "run": spec.label(),
            "entry": entry.dir,
            "mean": mean,
            "seconds": entry.record.seconds,
        }));
    }
    let dir = results.join(name);
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let text = serde_json::to_string_pretty(
        &serde_json::json!({ "study": name, "scale": scale, "runs": rows }),
    )
    .map_err(|e| e.to_string())?;
    crate::image_io::write_atomic(&dir.join("summary.json"), text.as_bytes())?;
    Ok((lines.clone(), lines.len() - made, made))
}

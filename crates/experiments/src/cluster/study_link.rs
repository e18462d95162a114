//! The seam between plans and the studies: which renders a study needs (`lt plan study`) and
//! how its outputs are made once they are in the cache (`lt collect`, which runs the study
//! again: every render is then found).
//!
//! Until `study::plan` and `study::run_named` are on main, a built-in study stands in:
//! `smoke`, a handful of small `pt` renders of the Cornell box, and collecting it writes
//! `RESULTS/smoke/summary.json` from the cached entries. This file is the one place to switch.

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
    _results: &Path,
    scenes: &Path,
    _cache: &Path,
) -> Result<Vec<(RunSpec, Role)>, String> {
    match name {
        "smoke" => Ok(smoke(scale, scenes)?
            .into_iter()
            .map(|s| (s, Role::Runs))
            .collect()),
        other => Err(format!(
            "lt plan study: study '{other}' cannot be planned by this build (it knows: smoke)"
        )),
    }
}

/// Makes study `name`'s outputs under `results`, rendering whatever the cache lacks; returns
/// a line per render and how many were made here.
pub fn collect(
    name: &str,
    scale: &str,
    results: &Path,
    scenes: &Path,
    cache: &Path,
    threads: usize,
) -> Result<(Vec<String>, usize), String> {
    let specs = plan(name, scale, results, scenes, cache)?;
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
    Ok((lines, made))
}

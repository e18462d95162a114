//! The seam between plans and the studies: which renders a study needs (`lt plan study`:
//! `study::plan`, each render with the cache it belongs in) and how its outputs are made once
//! they are in the cache (`lt collect`: `study::run_named`, which finds every render). Every
//! study of `study::registry` can be planned, the hidden `smoke` one included.

use crate::runs::RunSpec;
use crate::study::{Role, StudyContext, StudySetup};
use std::path::{Path, PathBuf};

/// The cache folder of `role`.
pub fn cache_for(role: Role, runs_cache: &Path, results: &Path) -> PathBuf {
    role.cache(runs_cache, results)
}

fn setup(scale: &str, results: &Path, scenes: &Path, cache: &Path, threads: usize) -> StudySetup {
    StudySetup {
        scale: scale.into(),
        results: results.into(),
        cache: Some(cache.into()),
        scenes: scenes.into(),
        threads,
        quiet: true,
        stop_after: None,
    }
}

/// Every render study `name` needs at `scale`, with the cache it belongs in.
pub fn plan(
    name: &str,
    scale: &str,
    results: &Path,
    scenes: &Path,
    cache: &Path,
) -> Result<Vec<(RunSpec, Role)>, String> {
    let ctx = StudyContext::new(&setup(scale, results, scenes, cache, 0))?;
    crate::study::plan(name, &ctx.scale, Some(&ctx))
}

/// Makes study `name`'s outputs under `results` by running it (every render it finds in the
/// cache is not made again); returns how many renders were found and how many made here.
pub fn collect(
    name: &str,
    scale: &str,
    results: &Path,
    scenes: &Path,
    cache: &Path,
    threads: usize,
) -> Result<(usize, usize), String> {
    let ctx = StudyContext::new(&setup(scale, results, scenes, cache, threads))?;
    crate::study::run_named(name, &ctx)?;
    let (made, found) = ctx.counts();
    Ok((found as usize, made as usize))
}

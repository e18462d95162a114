//! `lt study NAME`: the bias, variance and consistency studies. Each study is a list of cached
//! renders (`RunSpec`s, see `crate::runs`) and an analysis of their entries that writes CSV,
//! charts (SVG and PNG), a Markdown summary and a manifest under `results/<study>/`, which
//! `lt report` gathers into `results/index.html`.
//!
//! Because every render goes through the cache, a study that was interrupted resumes where it
//! stopped, and a study whose renders ran elsewhere (`lt plan study`, a cluster) is finished by
//! running it again: every render is then found.

pub mod beam_moments;
pub mod context;
pub mod convergence;
pub mod equal_time;
pub mod figures;
pub mod lecture;
pub mod media_figures;
pub mod metrics;
pub mod metropolis;
pub mod output;
pub mod per_length;
pub mod radius_media;
pub mod radius_plane;
pub mod radius_shrinkage;
pub mod reference;
pub mod registry;
pub mod scale;
pub mod smoke;
pub mod techniques;
pub mod unbiased_consistent;

use crate::runs::RunSpec;
pub use context::{StudyContext, StudySetup};
pub use registry::{StudyInfo, STUDIES};
pub use scale::Scale;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Which cache a planned render belongs in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// A study run: the runs cache (default RESULTS/cache).
    Runs,
    /// A reference: RESULTS/references.
    References,
}

impl Role {
    /// The cache folder of this role: the runs cache given, or RESULTS/references.
    pub fn cache(self, runs_cache: &Path, results: &Path) -> PathBuf {
        match self {
            Role::Runs => runs_cache.to_path_buf(),
            Role::References => results.join("references"),
        }
    }
}

/// Every render study `name` needs at `scale` (references included) and the cache each belongs
/// in, for `lt plan study`. The equal-time study's pass counts come from the convergence study's
/// measured timings, so its equal-time renders are planned only with a context whose cache holds
/// those (`ctx` = None plans the rest of it).
pub fn plan(
    name: &str,
    scale: &Scale,
    ctx: Option<&StudyContext>,
) -> Result<Vec<(RunSpec, Role)>, String> {
    let mut specs = Vec::new();
    for study in registry::resolve(name)? {
        specs.extend((study.specs)(scale, ctx)?);
    }
    let mut seen = std::collections::HashSet::new();
    specs.retain(|s| seen.insert(serde_json::to_string(s).unwrap_or_default()));
    Ok(specs
        .into_iter()
        .map(|s| {
            // A reference is what `reference::spec` makes for its scene, at the scale's film
            // and passes or at a study's own (the figures').
            let role = if reference::is_reference(&s) {
                Role::References
            } else {
                Role::Runs
            };
            (s, role)
        })
        .collect())
}

/// Runs study `name` (or all of them, then the report) with the context's cache.
pub fn run_named(name: &str, ctx: &StudyContext) -> Result<(), String> {
    for study in registry::resolve(name)? {
        let (n, t) = (study.name, Instant::now());
        ctx.say(&format!("study {n} ({} scale)", ctx.scale.name));
        (study.run)(ctx)?;
        ctx.say(&format!(
            "study {n}: done in {:.1} s -> {}",
            t.elapsed().as_secs_f64(),
            ctx.study_dir(n).display()
        ));
    }
    Ok(())
}

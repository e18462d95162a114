//! The one table of studies: `lt study NAME`, `lt plan study NAME`, `lt collect` and the report's
//! order all read it. Adding a study is one entry here (and its module).

use super::context::StudyContext;
use super::media_figures;
use super::scale::Scale;
use super::{
    convergence, equal_time, figures, metropolis, per_length, radius_media, radius_plane,
    radius_shrinkage, smoke, techniques, unbiased_consistent,
};
use crate::runs::RunSpec;

/// What the table knows of one study.
pub struct StudyInfo {
    /// The name on the command line and of its folder under the results.
    pub name: &'static str,
    /// Whether `lt study all` runs it and `lt study`'s help lists it; a hidden study (`smoke`)
    /// exists for the tests of plans and is run only by name.
    pub listed: bool,
    /// Every render the study asks for at a scale. The context, when given, holds the caches
    /// (the equal-time study plans its pass counts from the convergence study's timings there;
    /// without it, it plans the renders that need none).
    pub specs: fn(&Scale, Option<&StudyContext>) -> Result<Vec<RunSpec>, String>,
    /// Renders what the cache lacks and writes the study's outputs under `RESULTS/<name>/`.
    pub run: fn(&StudyContext) -> Result<(), String>,
}

/// The studies in the order `lt study all` runs them and the report shows them.
pub const STUDIES: &[StudyInfo] = &[
    // First, so the report opens with the figures after its findings. Not in `all`: its
    // renders take about half a core-hour (results/figures/summary.md). Run it by name.
    StudyInfo {
        name: figures::NAME,
        listed: false,
        specs: figures::specs,
        run: figures::run,
    },
    // The lecture's slides with independent runs (issue 48, item 5), beside the figures. Not in
    // `all`: about 17 core-minutes of renders (results/slides/summary.md). Run it by name.
    StudyInfo {
        name: figures::slides::NAME,
        listed: false,
        specs: figures::slides::specs,
        run: figures::slides::run,
    },
    StudyInfo {
        name: "convergence",
        listed: true,
        specs: |scale, _| Ok(convergence::specs(scale)),
        run: convergence::run,
    },
    StudyInfo {
        name: "unbiased-vs-consistent",
        listed: true,
        specs: |scale, _| Ok(unbiased_consistent::specs(scale)),
        run: unbiased_consistent::run,
    },
    StudyInfo {
        name: "radius-shrinkage",
        listed: true,
        specs: |scale, _| Ok(radius_shrinkage::specs(scale)),
        run: radius_shrinkage::run,
    },
    // Not in `all`: its committed results are at the full scale, and the quick main command must
    // not overwrite them. Run it by name (`lt study radius-shrinkage-plane --scale full`).
    StudyInfo {
        name: radius_plane::NAME,
        listed: false,
        specs: |scale, _| Ok(radius_plane::specs(scale)),
        run: radius_plane::run,
    },
    // Not in `all`, for the same reason: its committed results (results/points-beams.md) are at
    // the committed scale. Run it by name.
    StudyInfo {
        name: radius_media::NAME,
        listed: false,
        specs: |scale, _| Ok(radius_media::specs(scale)),
        run: radius_media::run,
    },
    StudyInfo {
        name: "equal-time",
        listed: true,
        specs: |scale, ctx| match ctx {
            Some(c) => equal_time::specs(c),
            None => Ok(equal_time::fixed_specs(scale)),
        },
        run: equal_time::run,
    },
    StudyInfo {
        name: "per-length",
        listed: true,
        specs: |scale, _| Ok(per_length::specs(scale)),
        run: per_length::run,
    },
    // Not in `all`: its tallied runs and references cost about ten core-minutes at the quick
    // scale (128 px, three scenes), twice what `all` takes. Run it by name.
    StudyInfo {
        name: techniques::NAME,
        listed: false,
        specs: |scale, _| Ok(techniques::specs(scale)),
        run: techniques::run,
    },
    // Not in `all`: about 25 CPU minutes at the quick scale (results/mlt.md). Run it by name.
    StudyInfo {
        name: metropolis::NAME,
        listed: false,
        specs: |scale, _| metropolis::specs(scale),
        run: metropolis::run,
    },
    // Not in `all`: about a core-quarter-hour of renders (results/media-figures/summary.md).
    // Run it by name.
    StudyInfo {
        name: media_figures::NAME,
        listed: false,
        specs: media_figures::specs,
        run: media_figures::run,
    },
    StudyInfo {
        name: "smoke",
        listed: false,
        specs: |scale, _| smoke::specs(scale),
        run: smoke::run,
    },
];

/// The listed studies' names, in table order: what `all` means.
pub fn names() -> impl Iterator<Item = &'static str> {
    STUDIES.iter().filter(|s| s.listed).map(|s| s.name)
}

/// The studies `name` stands for: one, or every listed one for `all`.
pub fn resolve(name: &str) -> Result<Vec<&'static StudyInfo>, String> {
    if name == "all" {
        return Ok(STUDIES.iter().filter(|s| s.listed).collect());
    }
    match STUDIES.iter().find(|s| s.name == name) {
        Some(s) => Ok(vec![s]),
        None => Err(format!(
            "unknown study '{name}': the studies are {} and all",
            names().collect::<Vec<_>>().join(", ")
        )),
    }
}

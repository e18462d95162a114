//! `lt study techniques` (issue 25, item 1): where a bidirectional estimator's time goes and what
//! it buys. Per scene, `bdpt`, `lvc-bdpt` (N = 1) and `vcm` render independent runs with every
//! technique tallied (`lt_integrators::tally`: per (s, t) connection, light-tracing splat, next
//! event, emission hit and merge, the time it took and the mean and second moment of its
//! MIS-weighted per-pixel estimate); the tables give each technique's share of the time, mean,
//! second moment and efficiency 1/(second moment × time), with Student-t intervals over the
//! runs. Beside them, the inefficiency relMSE × time of `bdpt`, `lvc-bdpt` at N ∈ {1, 4, 16} and
//! `vcm`, from independent plain renders against the scene's reference.
//!
//! Each run is one cache entry of its own (key `what: techniques`): the plain render and the
//! tallied one of the same seed, one after the other on one thread, each timed by its CPU clock
//! (wall seconds on a shared machine count other work), with both images — the summary counts
//! how many are equal bit for bit. The study, like every other, is a function of cache entries.
//!
//! `config`: what is run at a scale; `tally`: the tallied runs and the per-technique tables;
//! `plain`: the plain renders on one thread; `inefficiency`: relMSE × time of the compared
//! configurations and eamis's choice; `overhead`: what the tally costs.

mod config;
mod inefficiency;
mod overhead;
mod plain;
mod tally;

pub use config::{size, specs, Config, StudySize, COMPARED, EVERY, NAME, TALLIED};
pub use tally::SumCheck;

use super::output::{pct, stem, StudyOutput};
use super::StudyContext;
use crate::image_io::write_atomic;
use serde_json::{json, Value};
use std::time::Instant;

pub fn run(ctx: &StudyContext) -> Result<(), String> {
    let size = size(&ctx.scale);
    let conf = ctx.scale.confidence;
    let mut out = StudyOutput::new(
        ctx.study_dir(NAME),
        NAME,
        "Per technique: where the time goes and what it buys",
        &size.scale,
    )?;
    let before = ctx.spent();
    let t_start = Instant::now();
    let mut tally_seconds = 0.0;
    describe(&mut out, &size, conf);
    let checks = tally::tables(ctx, &size, &mut out)?;
    let mut bit_equal = (0usize, 0usize);
    inefficiency::inefficiency(ctx, &size, &mut out, &mut tally_seconds, &mut bit_equal)?;
    overhead::overhead(ctx, &size, &mut out)?;
    out.para(&format!(
        "Tallied images against the plain renders of the same seeds: {} of {} bit for bit equal \
         (each cache entry keeps both, `image.exr` and `plain.exr`).",
        bit_equal.0, bit_equal.1
    ));
    out.para(&format!(
        "{} Plain and tallied runs (one thread each, CPU time): {:.1} core-minutes. Study wall \
         time {:.0} s.",
        ctx.compute_note(before),
        tally_seconds / 60.0,
        t_start.elapsed().as_secs_f64()
    ));
    out.finish()?;
    write_checks(ctx, &checks)
}

/// The study's opening paragraph: what is run and what each table's columns mean.
fn describe(out: &mut StudyOutput, size: &StudySize, conf: f64) {
    out.para(&format!(
        "Scenes {}, {} px wide, max_depth as each scene file says; {} independent runs (seeds \
         1 … {}) of {} passes per configuration; intervals are Student-t at {} % over the runs. \
         Per technique — a connection (s, t) with s light and t camera vertices (path length k = \
         s + t − 1; s = 0 emission hits, s = 1 next-event estimation, t = 1 light-tracing \
         splats), or a merge at camera vertex t — the **mean** and **second moment** are those of \
         its MIS-weighted estimate of a pixel in one pass (channel mean, averaged over the \
         image); **share of time** is its part of the pass's CPU time (one thread), measured by \
         the time-stamp counter on one work item in {EVERY}, chosen by hash (lt_integrators::tally \
         says why, and what `other` is); **efficiency** = 1/(second moment × seconds per pass). \
         Second moments of techniques do not add up to the image's (their cross terms are not \
         measured); means do, and the check table shows it.",
        size.scenes
            .iter()
            .map(|s| format!("`{}`", stem(s)))
            .collect::<Vec<_>>()
            .join(", "),
        size.width,
        size.runs,
        size.runs,
        size.passes,
        pct(conf),
    ));
}

/// `checks.json`: the sum checks tests/techniques_study.rs asserts on.
fn write_checks(ctx: &StudyContext, checks: &[SumCheck]) -> Result<(), String> {
    let path = ctx.study_dir(NAME).join("checks.json");
    let j: Vec<Value> = checks
        .iter()
        .map(|c| {
            json!({"scene": c.scene, "integrator": c.integrator, "sum": c.sum.estimate,
                   "sum_lo": c.sum.lo, "sum_hi": c.sum.hi, "image": c.image,
                   "paired_rel": c.paired_rel})
        })
        .collect();
    write_atomic(
        &path,
        serde_json::to_string_pretty(&j)
            .map_err(|e| e.to_string())?
            .as_bytes(),
    )
}

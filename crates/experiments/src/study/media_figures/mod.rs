//! `lt study media-figures` (issue 45, item 4): the media papers' comparisons on our scenes at
//! equal CPU time, each with relMSE and FLIP from independent runs.
//!
//! (a) Jarosz, Nowrouzezahrai, Sadeghi & Jensen 2011: points (`pp3d`) against beams (`pb2d`,
//!     `bb1d`) on `light-shafts`, a thin medium lit through a slit; `upbp` beside them, `pt` the
//!     unbiased baseline (`points_beams`).
//! (b) Křivánek et al. 2014: `upbp` against each estimator alone (`pp3d`, `pb2d`, `bb1d`, `bdpt`,
//!     `pt`) on three scenes, with upbp's per-technique shares of the image (`upbp_each`,
//!     `contributions`).
//! (c) SmallUPBP's candle-style radius study: estimator × initial radius at fixed time on
//!     `smallupbp-isosph` (`radius`).
//!
//! **Equal time** (`cells`): every cell (scene, estimator, parameters) gets the same CPU budget per
//! run. Its pass count is fixed from cached probes, so a rerun finds the same renders: probe 1
//! at `PROBE_PASSES` gives a first count; probe 2 at that count measures the cost per pass
//! where the runs will be (a progressive estimator's passes get cheaper as its radius shrinks,
//! ~20 % for upbp between 4 and 32 passes), and the runs get round(budget / that). Tables state
//! each cell's mean CPU seconds per run, so the equality is shown, not assumed.
//!
//! **Errors** per run against a long bdpt reference (`reference::spec`, through the reference
//! cache), means with Student-t intervals over the runs (`metrics::mean_of_runs`): relMSE
//! corrected for the reference's own noise (`rel_mse_corrected`), and FLIP.

mod cells;
mod contributions;
mod points_beams;
mod radius;
mod upbp_each;

use super::metrics::{mean_of_runs, rel_mse, REL_EPSILON};
use super::reference::Reference;
use super::{Scale, StudyContext};
use crate::runs::RunSpec;
use lt_estimators::{Image, Interval};
use std::path::PathBuf;

pub const NAME: &str = "media-figures";

/// What every figure renders at: film width, independent runs per cell, CPU seconds per run,
/// reference passes (bdpt).
pub struct Budget {
    pub width: u32,
    pub runs: usize,
    pub cpu_seconds: f64,
    pub reference_passes: u32,
}

/// The study's own budget: `committed` (and every scale but `test` and `full`) is sized for
/// about ten core-minutes of renders (results/media-figures/summary.md states what it took);
/// `full` gives each run 4× that time, to see which verdicts depend on the budget (≈ 40
/// core-minutes).
pub fn budget(scale: &Scale) -> Budget {
    if scale.name == "test" {
        Budget {
            width: 12,
            runs: 3,
            cpu_seconds: 0.05,
            reference_passes: 16,
        }
    } else if scale.name == "full" {
        Budget {
            width: 64,
            runs: 8,
            cpu_seconds: 6.0,
            reference_passes: 512,
        }
    } else {
        Budget {
            width: 64,
            runs: 8,
            // 1.5 s, not 2: on the shared machine (load ≈ 13 on 2 cores) a render thread got
            // about a fifth of a core, and 2 s per run would have taken the study past an hour.
            cpu_seconds: 1.5,
            reference_passes: 512,
        }
    }
}

/// The scale the references and films are made at.
fn at(scale: &Scale, b: &Budget) -> Scale {
    Scale {
        width: b.width,
        reference_passes: b.reference_passes,
        ..scale.clone()
    }
}

fn media_scene(scale: &Scale, name: &str) -> PathBuf {
    scale.scene_beside_focus(&format!("media/{name}.xml"))
}

/// relMSE (ε = 0.01) less what the reference's own noise adds to it: E[(I − R̂)²] = E[(I − R)²]
/// + Var R̂ for independent I and R̂, so each pixel's term loses Var R̂ / (R̂² + ε) (the weights
/// are R̂'s, as `rel_mse`'s). Without it, an estimator far better than the reference would be
/// measured at the reference's noise.
pub fn rel_mse_corrected(img: &Image, r: &Reference) -> f64 {
    let mut noise = 0.0;
    for (v, b) in r.variance.data.iter().zip(&r.image.data) {
        for c in 0..3 {
            noise += v[c] / (b[c] * b[c] + REL_EPSILON);
        }
    }
    rel_mse(img, r) - noise / (3 * r.image.data.len()).max(1) as f64
}

/// relMSE and FLIP of each run, their means with intervals, and the images.
pub struct Errors {
    pub rel: Interval,
    pub flip: Interval,
    pub images: Vec<Image>,
}

pub fn errors(
    entries: &[crate::runs::RunEntry],
    r: &Reference,
    confidence: f64,
) -> Result<Errors, String> {
    let images: Vec<Image> = entries
        .iter()
        .map(|e| e.image())
        .collect::<Result<_, _>>()?;
    let rel: Vec<f64> = images.iter().map(|i| rel_mse_corrected(i, r)).collect();
    let flip: Vec<f64> = images
        .iter()
        .map(|i| crate::flip::flip_mean(&r.image, i))
        .collect::<Result<_, _>>()?;
    Ok(Errors {
        rel: mean_of_runs(&rel, confidence),
        flip: mean_of_runs(&flip, confidence),
        images,
    })
}

/// One cell's runs at equal time and their errors.
pub struct Measured {
    pub label: String,
    pub passes: u32,
    /// Mean CPU seconds per run.
    pub cpu: f64,
    pub errors: Errors,
    pub entries: Vec<crate::runs::RunEntry>,
}

pub fn measure(
    ctx: &StudyContext,
    c: &cells::Cell,
    label: &str,
    (b, fs): (&Budget, &Scale),
    r: &Reference,
) -> Result<Measured, String> {
    let (passes, entries) = cells::measure(ctx, c, b, fs)?;
    Ok(Measured {
        label: label.to_string(),
        passes,
        cpu: cells::mean_cpu(&entries),
        errors: errors(&entries, r, ctx.scale.confidence)?,
        entries,
    })
}

/// The columns `row` fills.
pub const COLUMNS: [&str; 9] = [
    "estimator",
    "passes",
    "CPU s",
    "relMSE",
    "relMSE lo",
    "relMSE hi",
    "FLIP",
    "FLIP lo",
    "FLIP hi",
];

pub fn row(m: &Measured) -> Vec<String> {
    let num = super::output::num;
    let (r, f) = (&m.errors.rel, &m.errors.flip);
    vec![
        m.label.clone(),
        m.passes.to_string(),
        num(m.cpu),
        num(r.estimate),
        num(r.lo),
        num(r.hi),
        num(f.estimate),
        num(f.lo),
        num(f.hi),
    ]
}

/// Run 1's image of each cell beside the reference, as JPEG previews under `gallery/<dir>/`.
pub fn gallery(
    out: &mut super::output::StudyOutput,
    (title, caption): (&str, &str),
    dir: &str,
    r: &Reference,
    ms: &[Measured],
) -> Result<(), String> {
    let num = super::output::num;
    let entries: Vec<crate::gallery::Entry> = ms
        .iter()
        .map(|m| crate::gallery::Entry {
            label: &m.label,
            note: format!(
                "{} passes, relMSE {}, FLIP {}",
                m.passes,
                num(m.errors.rel.estimate),
                num(m.errors.flip.estimate)
            ),
            image: &m.errors.images[0],
            stem: format!("gallery/{dir}/{}", m.label.replace([' ', '=', '.'], "-")),
        })
        .collect();
    let g = crate::gallery::write_gallery(
        &out.dir,
        title,
        caption,
        &r.gallery_entry(format!("gallery/{dir}/reference")),
        &entries,
        None,
    )?;
    out.manifest.galleries.push(g);
    Ok(())
}

/// Whether `better` beats `worse` by a wide margin: its interval wholly below the other's and its
/// mean at most half. tests/media_figures.rs applies the same rule to the committed CSVs.
pub fn wide_margin(better: &Interval, worse: &Interval) -> bool {
    better.hi < worse.lo && 2.0 * better.estimate <= worse.estimate
}

/// Every render of the three figures that the cache (when given) makes known: references and
/// probes always, second probes and runs once the probes they depend on are found.
pub fn specs(scale: &Scale, ctx: Option<&StudyContext>) -> Result<Vec<RunSpec>, String> {
    let b = budget(scale);
    let fs = at(scale, &b);
    let mut v = Vec::new();
    let mut scenes: Vec<PathBuf> = Vec::new();
    let mut all_cells = points_beams::cells(scale);
    all_cells.extend(upbp_each::cells(scale));
    all_cells.extend(radius::cells(scale));
    for c in &all_cells {
        if !scenes.contains(&c.scene) {
            scenes.push(c.scene.clone());
        }
        v.extend(cells::planned(c, &b, &fs, ctx)?);
    }
    for s in &scenes {
        v.push(super::reference::spec(&fs, s, None)?);
    }
    let mut seen = std::collections::HashSet::new();
    v.retain(|s| seen.insert(serde_json::to_string(s).unwrap_or_default()));
    Ok(v)
}

pub fn run(ctx: &StudyContext) -> Result<(), String> {
    let scale = &ctx.scale;
    let b = budget(scale);
    let fs = at(scale, &b);
    let mut out = super::output::StudyOutput::new(
        ctx.study_dir(NAME),
        NAME,
        "The media papers' figures at equal time",
        scale,
    )?;
    out.para(&format!(
        "Points, beams and paths compared as their papers did, on our scenes: {} independent runs \
         (seeds 1 … {}) per cell at {} px wide, each run {} CPU s on {} (the pass count \
         from two cached probes, `media_figures` says how; each table gives the cells' measured \
         mean). Errors against a {}-pass bdpt reference of each scene at the same film (seed \
         1 000 000): relMSE (ε = 0.01) less the reference's own noise, and FLIP, as means over \
         the runs with {} % Student-t intervals. The consistent estimators start at the default \
         radius (1 % of the scene's bounding-sphere diameter, α as `lt list` says) unless a \
         figure varies it. The images shown are run 1's.",
        b.runs,
        b.runs,
        b.width,
        super::output::num(b.cpu_seconds),
        match ctx.runs.threads {
            1 => "one thread".to_string(),
            0 => "one thread per core (CPU s summed over them)".to_string(),
            n => format!("{n} threads (CPU s summed over them)"),
        },
        b.reference_passes,
        super::output::pct(scale.confidence)
    ));
    let before = ctx.spent();
    let mut verdicts = Vec::new();
    verdicts.push(points_beams::figure(ctx, &b, &fs, &mut out)?);
    let after_a = ctx.spent();
    verdicts.extend(upbp_each::figure(ctx, &b, &fs, &mut out)?);
    let after_b = ctx.spent();
    verdicts.push(radius::figure(ctx, &b, &fs, &mut out)?);
    out.table(
        "verdicts",
        "Verdicts",
        "One row per claim: whether it holds on our scenes at this budget, and the numbers that \
         decide it (tests/media_figures.rs holds each verdict to the tables).",
        &["figure", "claim", "verdict", "numbers"],
        verdicts,
        true,
    )?;
    out.para(&format!(
        "**Compute.** Figure (a), its reference included: {:.1} core-minutes; (b): {:.1}; (c): \
         {:.1} (a cell shared with an earlier figure is counted there).",
        (after_a.0 - before.0) / 60.0,
        (after_b.0 - after_a.0) / 60.0,
        (ctx.spent().0 - after_b.0) / 60.0
    ));
    out.para(&ctx.compute_note(before));
    out.finish()
}

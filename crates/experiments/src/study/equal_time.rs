//! `lt study equal-time`: the lecture's galleries — every integrator on every scene at equal
//! samples and at equal time, with crops and MSE — and Veach's MIS comparison on `veach-mis`
//! (BSDF sampling only, light sampling only, balance and power heuristics).
//!
//! Equal time is made reproducible: each integrator's cost per pass is measured by the
//! convergence study (its first run), the budget is what `pt` took for the largest N there, and
//! each integrator gets round(budget / its cost per pass) passes (at least 1). The images then
//! depend on those pass counts only, which the table records; the timings behind them vary from
//! machine to machine, as any equal-time comparison does.

use super::convergence::{self, integrators};
use super::metrics::mse;
use super::output::{film, num, stem, StudyOutput};
use super::{Ctx, Scale};
use crate::gallery::{write_gallery, Entry};
use crate::runs::RunSpec;
use std::path::{Path, PathBuf};

pub const NAME: &str = "equal-time";

/// Veach's comparison: (label, pt parameters).
pub const VEACH: [(&str, &[(&str, &str)]); 4] = [
    ("BSDF sampling only", &[("techniques", "bsdf")]),
    ("light sampling only", &[("techniques", "light")]),
    ("MIS, balance heuristic", &[("mis", "balance")]),
    ("MIS, power heuristic", &[("mis", "power")]),
];

fn veach_scene(scale: &Scale) -> Option<PathBuf> {
    let dir = scale.focus_scene.parent()?;
    let p = dir.join("veach-mis.toml");
    p.is_file().then_some(p)
}

fn veach_spec(scale: &Scale, scene: &Path, params: &[(&str, &str)]) -> RunSpec {
    let mut s = RunSpec::new(scene, "pt", 1, scale.max_passes).resolution(film(scale, scene).ok());
    for (k, v) in params {
        s = s.param(k, v);
    }
    s
}

/// The renders that do not depend on timings: equal spp (the convergence study's first runs)
/// and Veach's four.
pub fn fixed_specs(scale: &Scale) -> Vec<RunSpec> {
    let mut v = Vec::new();
    for scene in &scale.scenes {
        v.extend(super::reference::spec(scale, scene, None));
        for i in integrators() {
            v.push(convergence::spec(scale, scene, i, 0));
        }
    }
    if let Some(s) = veach_scene(scale) {
        v.extend(super::reference::spec(scale, &s, None));
        for (_, p) in VEACH {
            v.push(veach_spec(scale, &s, p));
        }
    }
    v
}

/// Pass counts at equal time on `scene`, from the convergence runs' timings (rendered if absent).
fn equal_time_passes(ctx: &Ctx, scene: &PathBuf) -> Result<Vec<(&'static str, u32, f64)>, String> {
    passes_from_timings(ctx, scene, true).map(|v| v.unwrap_or_default())
}

/// (integrator, passes, seconds) of each integrator at equal time.
type EqualPasses = Vec<(&'static str, u32, f64)>;

/// The same from the cache alone: None when a convergence run is not there yet (`render` false).
fn passes_from_timings(
    ctx: &Ctx,
    scene: &PathBuf,
    render: bool,
) -> Result<Option<EqualPasses>, String> {
    let scale = &ctx.scale;
    let mut cost = Vec::new();
    for i in integrators() {
        let spec = convergence::spec(scale, scene, i, 0);
        let e = if render {
            ctx.run(&spec)?
        } else {
            match ctx.runs.lookup(&spec)? {
                Some(e) => e,
                None => return Ok(None),
            }
        };
        let secs = e.seconds_at(scale.max_passes).unwrap_or(f64::NAN);
        cost.push((i, secs / scale.max_passes as f64));
    }
    let budget = cost
        .iter()
        .find(|(i, _)| *i == "pt")
        .map(|(_, c)| c * scale.max_passes as f64)
        .ok_or("pt is not in the registry")?;
    Ok(Some(
        cost.into_iter()
            .map(|(i, c)| {
                let n = (budget / c).round();
                let n = if n.is_finite() {
                    n.clamp(1.0, 1e6) as u32
                } else {
                    1
                };
                (i, n, budget)
            })
            .collect(),
    ))
}

/// Every render of the study whose pass counts the cache's timings fix (see `fixed_specs`);
/// renders nothing itself: a scene whose convergence runs are not finished is left out.
pub fn specs(ctx: &Ctx) -> Result<Vec<RunSpec>, String> {
    let mut v = fixed_specs(&ctx.scale);
    for scene in &ctx.scale.scenes {
        let Some(passes) = passes_from_timings(ctx, scene, false)? else {
            continue;
        };
        for (i, n, _) in passes {
            v.push(RunSpec::new(scene, i, 1, n).resolution(film(&ctx.scale, scene).ok()));
        }
    }
    Ok(v)
}

pub fn run(ctx: &Ctx) -> Result<(), String> {
    let scale = &ctx.scale;
    let mut out = StudyOutput::new(
        ctx.study_dir(NAME),
        NAME,
        "Equal time and equal samples: galleries",
        scale,
    )?;
    out.para(&format!(
        "Every integrator on every scene ({} px wide), seed 1: at equal samples ({} passes) and at \
         equal time (the time `pt` takes for {} passes; each integrator gets that budget divided \
         by its own cost per pass, measured by the convergence study). MSE is against the scene's \
         reference, corrected for the reference's noise; crops are where the estimates differ \
         most from it.",
        scale.width, scale.max_passes, scale.max_passes
    ));
    let mut rows = Vec::new();
    for scene in &scale.scenes {
        let name = stem(scene);
        let reference = ctx.reference(scene, None)?;
        let budget_passes = equal_time_passes(ctx, scene)?;
        for (mode, title) in [("spp", "equal samples"), ("time", "equal time")] {
            let mut images = Vec::new();
            for &(i, n, budget) in &budget_passes {
                let spec = match mode {
                    "spp" => convergence::spec(scale, scene, i, 0),
                    _ => RunSpec::new(scene, i, 1, n).resolution(film(scale, scene).ok()),
                };
                let e = ctx.run(&spec)?;
                let img = e.image()?;
                let m = mse(&img, &reference);
                let passes = spec.passes;
                rows.push(vec![
                    name.clone(),
                    title.to_string(),
                    i.to_string(),
                    passes.to_string(),
                    format!(
                        "{:.3}",
                        e.record.seconds.last().copied().unwrap_or(f64::NAN)
                    ),
                    format!("{budget:.3}"),
                    num(m),
                ]);
                images.push((i, img, format!("{passes} spp, MSE {}", num(m))));
            }
            let stems: Vec<String> = images
                .iter()
                .map(|(i, _, _)| format!("gallery/{name}/{mode}-{i}"))
                .collect();
            let entries: Vec<Entry> = images
                .iter()
                .zip(&stems)
                .map(|((i, img, note), s)| Entry {
                    label: i,
                    note: note.clone(),
                    image: img,
                    stem: s,
                })
                .collect();
            let ref_stem = format!("gallery/{name}/reference");
            let g = write_gallery(
                &out.dir,
                &format!("{name}, {title}"),
                &format!(
                    "Reference: {} × {} passes of {}.",
                    reference.runs, reference.passes, reference.integrator
                ),
                &Entry {
                    label: "reference",
                    note: format!("{} {}", reference.integrator, reference.passes),
                    image: &reference.image,
                    stem: &ref_stem,
                },
                &entries,
                Some((scale.width / 4).max(4)),
            )?;
            out.manifest.galleries.push(g);
        }
    }
    out.table(
        "galleries",
        "Equal samples and equal time",
        "Passes, seconds actually taken, the time budget, and MSE per scene and integrator.",
        &[
            "scene",
            "comparison",
            "integrator",
            "passes",
            "seconds",
            "budget s",
            "MSE",
        ],
        rows,
        true,
    )?;
    if let Some(vs) = veach_scene(scale) {
        let reference = ctx.reference(&vs, None)?;
        let mut vrows = Vec::new();
        let mut imgs = Vec::new();
        for (label, params) in VEACH {
            let e = ctx.run(&veach_spec(scale, &vs, params))?;
            let img = e.image()?;
            let m = mse(&img, &reference);
            vrows.push(vec![
                label.to_string(),
                scale.max_passes.to_string(),
                num(m),
            ]);
            imgs.push((label, img, format!("MSE {}", num(m))));
        }
        let stems: Vec<String> = (0..imgs.len())
            .map(|k| format!("gallery/veach-mis/{k}"))
            .collect();
        let entries: Vec<Entry> = imgs
            .iter()
            .zip(&stems)
            .map(|((l, img, note), s)| Entry {
                label: l,
                note: note.clone(),
                image: img,
                stem: s,
            })
            .collect();
        let g = write_gallery(
            &out.dir,
            "Veach's MIS comparison on veach-mis",
            "pt with one technique or both, at equal samples: BSDF sampling fails on the small \
             lights over the rough plates, light sampling on the large lights over the smooth \
             ones; MIS keeps the better of both.",
            &Entry {
                label: "reference",
                note: reference.integrator.clone(),
                image: &reference.image,
                stem: "gallery/veach-mis/reference",
            },
            &entries,
            Some((scale.width / 4).max(4)),
        )?;
        out.manifest.galleries.push(g);
        out.table(
            "veach-mis",
            "Veach's MIS comparison",
            "MSE of pt by technique and heuristic at equal samples.",
            &["technique", "passes", "MSE"],
            vrows,
            true,
        )?;
    }
    out.finish()
}

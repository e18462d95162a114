//! `lt study figures` (issue 48): the field's headline comparisons at budgets where one sees the
//! winner converge and the loser not, each with relMSE and FLIP from independent runs.
//!
//! 1. Veach's bidirectional room (Veach & Guibas 1995; Veach 1997, ch. 10), Bitterli's
//!    `veach-bidir`: `pt` against `bdpt` at equal CPU time, and bdpt's per-strategy (s, t) images
//!    of the path pyramid, read from `lt render --strategies` output (see `PYRAMID_DIR`).
//! 2. Veach & Guibas 1995's MIS figure on Bitterli's `veach-mis`: pt with BSDF
//!    sampling only, light sampling only, the balance and the power heuristic, at equal samples.
//!
//! Equal time is made reproducible as in `equal_time`: bdpt's runs fix the budget (the mean CPU
//! seconds of its K runs), a pt run at bdpt's pass count measures pt's CPU seconds per pass, and
//! pt gets round(budget / that) passes. The images then depend on that count only, which the
//! table records. Errors are per run against a long bdpt reference; means carry Student-t
//! intervals over the K independent runs (`metrics::mean_of_runs`).

use super::equal_time::VEACH;
use super::metrics::{mean_of_runs, mse, rel_mse};
use super::output::{film, num, pct, stem, StudyOutput};
use super::{Scale, StudyContext};
use crate::gallery::{write_gallery, Entry};
use crate::runs::{RunEntry, RunSpec};
use lt_estimators::{Image, Interval};
use std::path::{Path, PathBuf};

pub const NAME: &str = "figures";

/// Where the pyramid's EXRs are read from, under the results folder: inside the (uncommitted)
/// cache, since the 80 EXRs weigh ~9 MB. Made by the command `pyramid_command` prints.
pub const PYRAMID_DIR: &str = "cache/figures-pyramid";

/// The strategies shown for the lamp-lit ceiling: every (s, t) of length k = 3 (the ceiling lit
/// by the lamp through one diffuse bounce is k = 3: camera → ceiling → lamp shade → lamp), and
/// k = 4 beside it.
const PYRAMID_LENGTHS: [u32; 2] = [3, 4];

/// The figures' budgets: their own at every scale but `test`, since a figure is only worth
/// showing where its winner has converged.
struct Budget {
    width: u32,
    runs: usize,
    bidir_reference_passes: u32,
    bdpt_passes: u32,
    mis_reference_passes: u32,
    mis_passes: u32,
}

fn budget(scale: &Scale) -> Budget {
    if scale.name == "test" {
        Budget {
            width: 16,
            runs: 3,
            bidir_reference_passes: 32,
            bdpt_passes: 2,
            mis_reference_passes: 64,
            mis_passes: 4,
        }
    } else {
        Budget {
            width: 128,
            // 12, not 4: pt's relMSE on veach-bidir is a mean over a few fireflies, and 4 runs
            // (t₃ = 3.18) left its interval reaching below zero (1.44 [−0.44, 3.32]).
            runs: 12,
            bidir_reference_passes: 512,
            bdpt_passes: 32,
            mis_reference_passes: 1024,
            mis_passes: 16,
        }
    }
}

/// The scale the references and films of a figure are made at.
fn at(scale: &Scale, b: &Budget, reference_passes: u32) -> Scale {
    Scale {
        width: b.width,
        reference_passes,
        ..scale.clone()
    }
}

fn bidir_scene(scale: &Scale) -> PathBuf {
    scale.scene_beside_focus("bitterli/veach-bidir/scene.xml")
}

/// Bitterli's only: the study runs with `-D integrator=path` (Bitterli's files need it), which a
/// TOML scene refuses; ours is in the equal-time study's Veach gallery.
fn mis_scenes(scale: &Scale) -> Vec<PathBuf> {
    vec![scale.scene_beside_focus("bitterli/veach-mis/scene.xml")]
}

/// Passes that fit `budget` CPU seconds at `per_pass` seconds each: round(budget / per_pass),
/// at least 1. An error for a cost that is not a positive number (a record without timings).
pub fn equal_time_passes(budget: f64, per_pass: f64) -> Result<u32, String> {
    if !(budget > 0.0 && budget.is_finite() && per_pass > 0.0 && per_pass.is_finite()) {
        return Err(format!(
            "equal time: budget {budget} s and cost {per_pass} s per pass must be positive"
        ));
    }
    Ok((budget / per_pass).round().clamp(1.0, 1e7) as u32)
}

fn run_spec(scene: &Path, res: (u32, u32), integrator: &str, seed: u64, passes: u32) -> RunSpec {
    RunSpec::new(scene, integrator, seed, passes).resolution(Some(res))
}

fn bdpt_specs(scale: &Scale, b: &Budget) -> Result<Vec<RunSpec>, String> {
    let scene = bidir_scene(scale);
    let res = film(&at(scale, b, b.bidir_reference_passes), &scene)?;
    Ok((0..b.runs)
        .map(|r| run_spec(&scene, res, "bdpt", 1 + r as u64, b.bdpt_passes))
        .collect())
}

/// pt at bdpt's pass count, seed 1: its CPU time per pass sets pt's equal-time pass count.
fn pt_probe(scale: &Scale, b: &Budget) -> Result<RunSpec, String> {
    let scene = bidir_scene(scale);
    let res = film(&at(scale, b, b.bidir_reference_passes), &scene)?;
    Ok(run_spec(&scene, res, "pt", 1, b.bdpt_passes))
}

fn cpu(e: &RunEntry) -> f64 {
    e.cpu_seconds_at(e.record.spec.passes).unwrap_or(f64::NAN)
}

/// (budget CPU s, pt passes) from the bdpt runs and the pt probe.
fn pt_passes(bdpt: &[RunEntry], probe: &RunEntry) -> Result<(f64, u32), String> {
    let budget = bdpt.iter().map(cpu).sum::<f64>() / bdpt.len().max(1) as f64;
    let per_pass = cpu(probe) / probe.record.spec.passes as f64;
    Ok((budget, equal_time_passes(budget, per_pass)?))
}

fn pt_specs(scale: &Scale, b: &Budget, passes: u32) -> Result<Vec<RunSpec>, String> {
    let scene = bidir_scene(scale);
    let res = film(&at(scale, b, b.bidir_reference_passes), &scene)?;
    Ok((0..b.runs)
        .map(|r| run_spec(&scene, res, "pt", 1 + r as u64, passes))
        .collect())
}

fn mis_spec(
    scene: &Path,
    res: (u32, u32),
    params: &[(&str, &str)],
    seed: u64,
    passes: u32,
) -> RunSpec {
    let mut s = run_spec(scene, res, "pt", seed, passes);
    for (k, v) in params {
        s = s.param(k, v);
    }
    s
}

fn mis_specs(scale: &Scale, b: &Budget) -> Result<Vec<RunSpec>, String> {
    let fs = at(scale, b, b.mis_reference_passes);
    let mut v = Vec::new();
    for scene in mis_scenes(scale) {
        let res = film(&fs, &scene)?;
        v.extend(super::reference::spec(&fs, &scene, None));
        for (_, p) in VEACH {
            for r in 0..b.runs {
                v.push(mis_spec(&scene, res, p, 1 + r as u64, b.mis_passes));
            }
        }
    }
    Ok(v)
}

/// Every render of the figures; pt's equal-time runs only when the context's cache holds the
/// bdpt runs and the pt probe that fix their pass count (as `equal_time::specs`).
pub fn specs(scale: &Scale, ctx: Option<&StudyContext>) -> Result<Vec<RunSpec>, String> {
    let b = budget(scale);
    let mut v = Vec::new();
    v.extend(super::reference::spec(
        &at(scale, &b, b.bidir_reference_passes),
        &bidir_scene(scale),
        None,
    ));
    let bdpt = bdpt_specs(scale, &b)?;
    let probe = pt_probe(scale, &b)?;
    v.extend(bdpt.iter().cloned());
    v.push(probe.clone());
    if let Some(ctx) = ctx {
        let found: Option<Vec<RunEntry>> = bdpt
            .iter()
            .map(|s| ctx.runs.lookup(s))
            .collect::<Result<Vec<_>, _>>()?
            .into_iter()
            .collect();
        if let (Some(found), Some(p)) = (found, ctx.runs.lookup(&probe)?) {
            let (_, n) = pt_passes(&found, &p)?;
            v.extend(pt_specs(scale, &b, n)?);
        }
    }
    v.extend(mis_specs(scale, &b)?);
    Ok(v)
}

/// relMSE, FLIP and MSE of each run, and their means with intervals.
struct Errors {
    rel: Interval,
    flip: Interval,
    mse: Interval,
}

fn errors(
    entries: &[RunEntry],
    r: &super::reference::Reference,
    confidence: f64,
) -> Result<(Errors, Vec<Image>), String> {
    let images: Vec<Image> = entries
        .iter()
        .map(|e| e.image())
        .collect::<Result<_, _>>()?;
    let rel: Vec<f64> = images.iter().map(|i| rel_mse(i, r)).collect();
    let m: Vec<f64> = images.iter().map(|i| mse(i, r)).collect();
    let flip: Vec<f64> = images
        .iter()
        .map(|i| crate::flip::flip_mean(&r.image, i))
        .collect::<Result<_, _>>()?;
    Ok((
        Errors {
            rel: mean_of_runs(&rel, confidence),
            flip: mean_of_runs(&flip, confidence),
            mse: mean_of_runs(&m, confidence),
        },
        images,
    ))
}

fn cell(i: &Interval) -> [String; 3] {
    [num(i.estimate), num(i.lo), num(i.hi)]
}

pub fn run(ctx: &StudyContext) -> Result<(), String> {
    let scale = &ctx.scale;
    let b = budget(scale);
    let mut out = StudyOutput::new(
        ctx.study_dir(NAME),
        NAME,
        "The field's figures at equal time",
        scale,
    )?;
    out.para(&format!(
        "The papers' headline comparisons at budgets where one sees them: {} independent runs \
         (seeds 1 … {}) per estimator at {} px wide, relMSE (ε = 0.01, against the reference), \
         FLIP and MSE (corrected for the reference's noise) as means over the runs with {} % \
         Student-t intervals. Time is the render threads' CPU time. The images shown are run 1's.",
        b.runs,
        b.runs,
        b.width,
        pct(scale.confidence)
    ));
    let before = ctx.spent();
    bidir_figure(ctx, &b, &mut out)?;
    let after_bidir = ctx.spent();
    pyramid_gallery(ctx, &mut out)?;
    mis_figure(ctx, &b, &mut out)?;
    out.para(&format!(
        "**Compute.** Figure 1 (references included): {:.1} core-minutes; figure 2: {:.1} \
         core-minutes.",
        (after_bidir.0 - before.0) / 60.0,
        (ctx.spent().0 - after_bidir.0) / 60.0
    ));
    out.para(&ctx.compute_note(before));
    out.finish()
}

fn bidir_figure(ctx: &StudyContext, b: &Budget, out: &mut StudyOutput) -> Result<(), String> {
    let scale = &ctx.scale;
    let fs = at(scale, b, b.bidir_reference_passes);
    let scene = bidir_scene(scale);
    let reference = ctx.reference_at(&fs, &scene, None)?;
    let bdpt = ctx.run_all(&bdpt_specs(scale, b)?)?;
    let probe = ctx.run(&pt_probe(scale, b)?)?;
    let (budget_s, n) = pt_passes(&bdpt, &probe)?;
    let pt = ctx.run_all(&pt_specs(scale, b, n)?)?;
    let (eb, ib) = errors(&bdpt, &reference, scale.confidence)?;
    let (ep, ip) = errors(&pt, &reference, scale.confidence)?;
    let mean_cpu = |v: &[RunEntry]| v.iter().map(cpu).sum::<f64>() / v.len().max(1) as f64;
    let mut rows = Vec::new();
    for (name, passes, e, entries) in [("pt", n, &ep, &pt), ("bdpt", b.bdpt_passes, &eb, &bdpt)] {
        let mut row = vec![name.to_string(), passes.to_string(), num(mean_cpu(entries))];
        row.extend(cell(&e.rel));
        row.extend(cell(&e.flip));
        row.extend(cell(&e.mse));
        rows.push(row);
    }
    out.table(
        "bidir",
        "Figure 1: Veach's bidirectional room at equal time",
        &format!(
            "veach-bidir (Bitterli's), pt against bdpt at {} CPU s per run (bdpt's mean over its \
             runs; pt's pass count from its CPU time per pass at {} passes). Reference: {} \
             passes of {}.",
            num(budget_s),
            b.bdpt_passes,
            reference.passes,
            reference.integrator
        ),
        &[
            "integrator",
            "passes",
            "CPU s",
            "relMSE",
            "relMSE lo",
            "relMSE hi",
            "FLIP",
            "FLIP lo",
            "FLIP hi",
            "MSE",
            "MSE lo",
            "MSE hi",
        ],
        rows,
        true,
    )?;
    let ratio = ep.rel.estimate / eb.rel.estimate;
    let flip_ratio = ep.flip.estimate / eb.flip.estimate;
    let rel_apart = eb.rel.hi < ep.rel.lo;
    let flip_apart = eb.flip.hi < ep.flip.lo;
    // pt's error here is a few bright fireflies (caustic paths through the lamp's glass): its
    // relMSE is heavy-tailed, and K runs may not bound its mean even when every image shows it.
    let verdict = match (rel_apart, flip_apart) {
        (true, true) => format!(
            "holds: at equal CPU time pt's relMSE is {}× bdpt's and its FLIP {}× (both intervals \
             apart)",
            num(ratio),
            num(flip_ratio)
        ),
        (false, true) => format!(
            "holds to the eye: at equal CPU time pt's FLIP is {}× bdpt's, the intervals apart; \
             pt's relMSE is {}× bdpt's by its mean, but its interval reaches below bdpt's: pt's \
             error is a few fireflies whose mean {} runs cannot bound",
            num(flip_ratio),
            num(ratio),
            b.runs
        ),
        _ => format!(
            "is not shown at this budget: pt's relMSE is {}× bdpt's and its FLIP {}×, the \
             intervals overlapping",
            num(ratio),
            num(flip_ratio)
        ),
    };
    out.para(&format!(
        "**Verdict (figure 1).** Veach's claim — bidirectional sampling renders the room lit \
         from the lamp's shade far better than path tracing in the same time — {verdict}."
    ));
    let name = stem(&scene);
    let notes = [
        (
            "pt",
            &ip[0],
            format!(
                "{n} spp, relMSE {}, FLIP {}",
                num(ep.rel.estimate),
                num(ep.flip.estimate)
            ),
        ),
        (
            "bdpt",
            &ib[0],
            format!(
                "{} spp, relMSE {}, FLIP {}",
                b.bdpt_passes,
                num(eb.rel.estimate),
                num(eb.flip.estimate)
            ),
        ),
    ];
    let entries: Vec<Entry> = notes
        .iter()
        .map(|(i, img, note)| Entry {
            label: i,
            note: note.clone(),
            image: img,
            stem: format!("gallery/{name}/{i}"),
        })
        .collect();
    let g = write_gallery(
        &out.dir,
        "Figure 1: veach-bidir, pt against bdpt at equal CPU time",
        &format!(
            "Equal CPU time ({} s per run). Reference: {} passes of bdpt.",
            num(budget_s),
            reference.passes
        ),
        &reference.gallery_entry(format!("gallery/{name}/reference")),
        &entries,
        Some((b.width / 4).max(4)),
    )?;
    out.manifest.galleries.push(g);
    Ok(())
}

/// The command that writes the pyramid the study reads.
pub fn pyramid_command(results: &Path) -> String {
    format!(
        "lt -D integrator=path -D resx=128 -D resy=128 render scenes/bitterli/veach-bidir/scene.xml \
         -i bdpt --spp 16 --seed 7 --threads 1 --strategies {} -o /tmp/figpyr-img.exr",
        results.join(PYRAMID_DIR).display()
    )
}

/// bdpt's per-strategy images of veach-bidir (weighted by MIS), lengths `PYRAMID_LENGTHS`, when
/// `lt render --strategies` wrote them under `PYRAMID_DIR`; otherwise a line saying how to.
fn pyramid_gallery(ctx: &StudyContext, out: &mut StudyOutput) -> Result<(), String> {
    let dir = ctx.results.join(PYRAMID_DIR);
    if !dir.is_dir() {
        out.para(&format!(
            "The path pyramid is not shown: `{}` is missing; `{}` writes it.",
            dir.display(),
            pyramid_command(&ctx.results)
        ));
        return Ok(());
    }
    for k in PYRAMID_LENGTHS {
        let mut images = Vec::new();
        let mut sum: Option<Image> = None;
        for s in 0..=k {
            let t = k + 1 - s;
            let path = dir.join(format!("k{k}_s{s}_t{t}.weighted.exr"));
            let img = crate::image_io::read_exr(&path)?;
            sum = Some(match sum {
                None => img.clone(),
                Some(mut acc) => {
                    for (a, p) in acc.data.iter_mut().zip(&img.data) {
                        for c in 0..3 {
                            a[c] += p[c];
                        }
                    }
                    acc
                }
            });
            images.push((format!("s={s}, t={t}"), img));
        }
        let sum = sum.ok_or("empty pyramid row")?;
        let entries: Vec<Entry> = images
            .iter()
            .enumerate()
            .map(|(i, (l, img))| Entry {
                label: l,
                note: "MIS-weighted".into(),
                image: img,
                stem: format!("gallery/pyramid/k{k}-{i}"),
            })
            .collect();
        let g = write_gallery(
            &out.dir,
            &format!("Figure 1b: bdpt's path pyramid on veach-bidir, paths of {k} segments"),
            &format!(
                "Each strategy (s light vertices, t camera vertices, s + t − 1 = {k}) with its MIS \
                 weight; they sum to the image of length-{k} paths (\"reference\" here). \
                 Veach 1997, fig. 10.3. Written by `{}`.",
                pyramid_command(Path::new("results"))
            ),
            &Entry {
                label: "sum",
                note: format!("all paths of {k} segments"),
                image: &sum,
                stem: format!("gallery/pyramid/k{k}-sum"),
            },
            &entries,
            None,
        )?;
        out.manifest.galleries.push(g);
    }
    Ok(())
}

fn mis_figure(ctx: &StudyContext, b: &Budget, out: &mut StudyOutput) -> Result<(), String> {
    let scale = &ctx.scale;
    let fs = at(scale, b, b.mis_reference_passes);
    let mut rows = Vec::new();
    let mut verdicts = Vec::new();
    for scene in mis_scenes(scale) {
        let name = stem(&scene);
        let label = if scene.extension().is_some_and(|e| e == "xml") {
            format!("{name} (Bitterli)")
        } else {
            format!("{name} (ours)")
        };
        let res = film(&fs, &scene)?;
        let reference = ctx.reference_at(&fs, &scene, None)?;
        let mut shown = Vec::new();
        let mut rel = Vec::new();
        for (k, (technique, params)) in VEACH.iter().enumerate() {
            let specs: Vec<RunSpec> = (0..b.runs)
                .map(|r| mis_spec(&scene, res, params, 1 + r as u64, b.mis_passes))
                .collect();
            let entries = ctx.run_all(&specs)?;
            let (e, mut imgs) = errors(&entries, &reference, scale.confidence)?;
            let mut row = vec![
                label.clone(),
                technique.to_string(),
                b.mis_passes.to_string(),
                num(entries.iter().map(cpu).sum::<f64>() / entries.len().max(1) as f64),
            ];
            row.extend(cell(&e.rel));
            row.extend(cell(&e.flip));
            rows.push(row);
            shown.push((
                k,
                *technique,
                imgs.swap_remove(0),
                format!(
                    "relMSE {}, FLIP {}",
                    num(e.rel.estimate),
                    num(e.flip.estimate)
                ),
            ));
            rel.push(e.rel);
        }
        // VEACH's order: bsdf, light, balance, power.
        let best_single = if rel[0].estimate <= rel[1].estimate {
            0
        } else {
            1
        };
        let worst_single = 1 - best_single;
        let power = &rel[3];
        let robust = power.lo <= rel[best_single].hi;
        verdicts.push(format!(
            "on {label} the power heuristic's relMSE is {}× the better single technique's \
             ({}) and {}× the worse one's ({}){}; balance/power = {:.2}",
            num(power.estimate / rel[best_single].estimate),
            VEACH[best_single].0,
            num(power.estimate / rel[worst_single].estimate),
            VEACH[worst_single].0,
            if robust {
                ", within the better one's interval or below it"
            } else {
                ", above the better one's interval"
            },
            rel[2].estimate / power.estimate
        ));
        let entries: Vec<Entry> = shown
            .iter()
            .map(|(k, l, img, note)| Entry {
                label: l,
                note: note.clone(),
                image: img,
                stem: format!("gallery/mis-{name}/{k}"),
            })
            .collect();
        let g = write_gallery(
            &out.dir,
            &format!("Figure 2: Veach's MIS comparison on {label}, equal samples"),
            &format!(
                "pt at {} passes with BSDF sampling only, light sampling only, and both combined \
                 by the balance and the power heuristic. Reference: {} passes of {}.",
                b.mis_passes, reference.passes, reference.integrator
            ),
            &reference.gallery_entry(format!("gallery/mis-{name}/reference")),
            &entries,
            Some((b.width / 4).max(4)),
        )?;
        out.manifest.galleries.push(g);
    }
    out.table(
        "mis",
        "Figure 2: Veach's MIS comparison at equal samples",
        "pt by technique and heuristic, the same passes for each; CPU s is the mean per run.",
        &[
            "scene",
            "technique",
            "passes",
            "CPU s",
            "relMSE",
            "relMSE lo",
            "relMSE hi",
            "FLIP",
            "FLIP lo",
            "FLIP hi",
        ],
        rows,
        true,
    )?;
    out.para(&format!(
        "**Verdict (figure 2).** Veach & Guibas's claim — MIS is never much worse than the \
         better single technique and far better than the worse — holds where the power heuristic's interval reaches the \
         better one's: {}.",
        verdicts.join("; ")
    ));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::equal_time_passes;

    #[test]
    fn equal_time_passes_round_and_refuse_bad_costs() {
        assert_eq!(equal_time_passes(16.0, 0.5), Ok(32));
        assert_eq!(equal_time_passes(1.0, 0.4), Ok(3));
        assert_eq!(equal_time_passes(0.1, 10.0), Ok(1));
        assert!(equal_time_passes(16.0, f64::NAN).is_err());
        assert!(equal_time_passes(16.0, 0.0).is_err());
    }
}

//! `lt study figures` (issue 48): the field's headline comparisons at budgets where one sees the
//! winner converge and the loser not, each with relMSE and FLIP from independent runs.
//!
//! 1. `bidir`: Veach's bidirectional room (Veach & Guibas 1995; Veach 1997, ch. 10), `pt`
//!    against `bdpt` at equal CPU time, and bdpt's per-strategy images of the path pyramid.
//! 2. `mis`: Veach & Guibas 1995's MIS figure on `veach-mis` (Bitterli's and ours).
//! 3. `ppm`: Hachisuka, Ogaki & Jensen 2008 — caustics seen in a mirror (L S D S E), where
//!    only the consistent estimators (`sppm`, `ppm`) converge; `pt`, `bdpt` beside them; and a
//!    point light's caustic seen directly (`cornell-point-caustic`), which bdpt reaches too.
//! 4. `vcm`: Georgiev et al. 2012 — `bdpt`, `ppm` and `vcm` at equal time on three scenes,
//!    with the per-technique contributions the techniques study measured.
//! 5. `slides` (its own study, `lt study slides`): the lecture's slides with independent runs.
//!
//! Equal time is made reproducible and robust to a drifting load (see `EqualTime`): one
//! estimator's pass count fixes the budget, interleaved probes of every estimator at that count
//! give each its mean CPU seconds per pass, and each gets round(budget / that) passes; the runs
//! are interleaved too, and relMSE × CPU s compares arms whose achieved times still differ.
//! The images then depend on those counts only, which the tables record. Errors are per run
//! against a long reference; means carry Student-t intervals over the K independent runs
//! (`metrics::mean_of_runs`) — for the progressive estimators too: each run is one progressive
//! render of its own seed, never a pass of another.

mod bidir;
mod mis;
mod ppm;
pub mod slides;
mod vcm;

pub use bidir::{pyramid_command, PYRAMID_DIR};

use super::metrics::{mean_of_runs, mse, rel_mse};
use super::output::StudyOutput;
use super::output::{film, num, pct};
use super::reference::Reference;
use super::{Scale, StudyContext};
use crate::gallery::Entry;
use crate::manifest::Crop;
use crate::runs::{RunEntry, RunSpec};
use lt_estimators::{Image, Interval};
use std::path::{Path, PathBuf};

pub const NAME: &str = "figures";

/// The figures' budgets: their own at every scale but `test`, since a figure is only worth
/// showing where its winner has converged.
struct Budget {
    width: u32,
    runs: usize,
    bidir_reference_passes: u32,
    bdpt_passes: u32,
    mis_reference_passes: u32,
    mis_passes: u32,
    /// Independent runs per estimator of figures 3 and 4.
    comparison_runs: usize,
    /// Probes per estimator that set figures 3 and 4's pass counts (`EqualTime`).
    probes: usize,
    /// Passes of a consistent reference (over its runs, `reference::spec`): caustic-sds's, in
    /// figures 3 and 4.
    consistent_reference_passes: u32,
    /// Figure 3: sppm's passes per run on each of `ppm::SCENES`, which fix the equal CPU time.
    sppm_passes: [u32; 2],
    /// Figure 4: passes of an unbiased (bdpt) reference, and vcm's passes per run on each of
    /// `vcm::SCENES`, which fix the equal CPU time there.
    vcm_reference_passes: u32,
    vcm_passes: [u32; 3],
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
            comparison_runs: 3,
            probes: 1,
            consistent_reference_passes: 64,
            sppm_passes: [4, 4],
            vcm_reference_passes: 32,
            vcm_passes: [2, 2, 2],
        }
    } else {
        Budget {
            width: 128,
            // 12, not 4: pt's relMSE on veach-bidir is a mean over a few fireflies, and 4 runs
            // (t₃ = 3.18) left its interval reaching below zero (1.44 [−0.44, 3.32]).
            runs: 12,
            bidir_reference_passes: 512,
            // 16, not 32 (≈ 6.6 CPU s per run, not 13): the compute a machine shared by five
            // agents afforded for the rerun of 2026-12-06 evening; pt is still far behind.
            bdpt_passes: 16,
            mis_reference_passes: 1024,
            mis_passes: 16,
            // 8, not 12: figures 3 and 4 have 16 arms between them (t₇ = 2.36 against t₁₁ =
            // 2.20 is the price).
            comparison_runs: 8,
            // 3 rounds of interleaved probes: their mean cost per pass, not one render's.
            probes: 3,
            // 8 vcm runs of 512 passes at radius 1 px: ≈ 2 CPU-min at 128 px.
            consistent_reference_passes: 4096,
            // ≈ 7 CPU s per run at 128 px (caustic-sds, cornell-point-caustic).
            sppm_passes: [480, 240],
            vcm_reference_passes: 512,
            // ≈ 2.5 CPU s per run at 128 px (cornell-box, veach-door, caustic-sds): what a
            // shared 2-core machine (load 12) afforded within the hour the figures had.
            vcm_passes: [16, 20, 80],
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

/// The scale `scene`'s reference is made at: `consistent_reference_passes` where its reference
/// integrator is consistent (`reference::integrator_for`), `unbiased` passes elsewhere.
fn reference_scale(scale: &Scale, b: &Budget, scene: &Path, unbiased: u32) -> Scale {
    let (integrator, _) = super::reference::integrator_for(&super::output::stem(scene));
    if crate::runs::is_consistent(integrator) {
        at(scale, b, b.consistent_reference_passes)
    } else {
        at(scale, b, unbiased)
    }
}

/// A shipped TOML scene by name, beside the focus scene.
fn toml_scene(scale: &Scale, name: &str) -> PathBuf {
    scale.scene_beside_focus(&format!("{name}.toml"))
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

fn cpu(e: &RunEntry) -> f64 {
    e.cpu_seconds_at(e.record.spec.passes).unwrap_or(f64::NAN)
}

fn mean_cpu(v: &[RunEntry]) -> f64 {
    v.iter().map(cpu).sum::<f64>() / v.len().max(1) as f64
}

/// One estimator of an equal-time figure: its registry name, which is also its label in the
/// tables and galleries.
#[derive(Clone, Copy)]
struct Contender(&'static str);

/// First seed of the probes: apart from the runs' seeds 1 … K, so a probe is never a run.
const PROBE_SEED: u64 = 1001;

/// An equal-time comparison on one scene, made robust to a machine whose load drifts (a shared
/// machine's CPU s per pass moved by ±40 % within the hour): every contender, the setter too,
/// is probed `probes` times at `setter_passes`, the probes interleaved (setter, a, b, setter,
/// a, b, …) so a load change hits all alike; each gets its mean CPU s per pass, and `c` gets
/// round(setter_passes × cost(setter) / cost(c)) passes. The K runs are interleaved the same
/// way (run 1 of every contender, then run 2, …), and the tables state the CPU s each arm
/// achieved and relMSE × CPU s, which an unbiased estimator keeps at any budget.
struct EqualTime {
    scene: PathBuf,
    res: (u32, u32),
    runs: usize,
    probes: usize,
    setter: Contender,
    setter_passes: u32,
    others: Vec<Contender>,
}

/// One estimator's runs in an equal-time comparison.
struct Arm {
    contender: Contender,
    passes: u32,
    entries: Vec<RunEntry>,
}

impl EqualTime {
    /// The setter, then `others` in order: the order of the arms and of each interleaved round.
    fn contenders(&self) -> Vec<Contender> {
        std::iter::once(self.setter)
            .chain(self.others.iter().copied())
            .collect()
    }

    /// Every contender's probes, round by round.
    fn probe_specs(&self) -> Vec<RunSpec> {
        let cs = self.contenders();
        (0..self.probes as u64)
            .flat_map(|j| {
                cs.iter().map(move |c| {
                    run_spec(
                        &self.scene,
                        self.res,
                        c.0,
                        PROBE_SEED + j,
                        self.setter_passes,
                    )
                })
            })
            .collect()
    }

    /// (budget CPU s per run, passes of each contender) from the probes (`probe_specs`' order):
    /// the setter's mean cost at its passes, and each contender's passes at that budget.
    fn passes_for(&self, probes: &[RunEntry]) -> Result<(f64, Vec<u32>), String> {
        let n = self.contenders().len();
        let per_pass: Vec<f64> = (0..n)
            .map(|k| {
                let mine: Vec<&RunEntry> = probes.iter().skip(k).step_by(n).collect();
                mine.iter().map(|e| cpu(e)).sum::<f64>()
                    / (mine.len().max(1) as f64 * self.setter_passes as f64)
            })
            .collect();
        let budget = per_pass[0] * self.setter_passes as f64;
        let mut passes = vec![self.setter_passes];
        for &c in &per_pass[1..] {
            passes.push(equal_time_passes(budget, c)?);
        }
        Ok((budget, passes))
    }

    /// The runs, round by round (run r of every contender, then run r + 1), at `passes`.
    fn run_specs(&self, passes: &[u32]) -> Vec<RunSpec> {
        let cs = self.contenders();
        (0..self.runs)
            .flat_map(|r| {
                cs.iter()
                    .zip(passes)
                    .map(move |(c, &n)| run_spec(&self.scene, self.res, c.0, 1 + r as u64, n))
            })
            .collect()
    }

    /// The renders to plan: the probes; the runs only when the context's cache holds every
    /// probe, which fixes their pass counts (as `equal_time::specs`).
    fn planned(&self, ctx: Option<&StudyContext>) -> Result<Vec<RunSpec>, String> {
        let mut v = self.probe_specs();
        let Some(ctx) = ctx else { return Ok(v) };
        let found: Option<Vec<RunEntry>> = v
            .iter()
            .map(|s| ctx.runs.lookup(s))
            .collect::<Result<Vec<_>, _>>()?
            .into_iter()
            .collect();
        if let Some(found) = found {
            let (_, passes) = self.passes_for(&found)?;
            v.extend(self.run_specs(&passes));
        }
        Ok(v)
    }

    /// Every arm, setter first then `others` in order, rendered now where the cache lacks
    /// them; and the budget in CPU seconds per run the probes predicted.
    fn run(&self, ctx: &StudyContext) -> Result<(f64, Vec<Arm>), String> {
        let probes = ctx.run_all(&self.probe_specs())?;
        let (budget, passes) = self.passes_for(&probes)?;
        let runs = ctx.run_all(&self.run_specs(&passes))?;
        let n = passes.len();
        let arms = self
            .contenders()
            .into_iter()
            .zip(passes)
            .enumerate()
            .map(|(k, (contender, passes))| Arm {
                contender,
                passes,
                entries: runs.iter().skip(k).step_by(n).cloned().collect(),
            })
            .collect();
        Ok((budget, arms))
    }
}

/// Per run relMSE × CPU s (the inefficiency: an unbiased estimator's is the same at any
/// budget, so it compares arms whose achieved times differ), and its mean with an interval.
fn inefficiency(rel: &[f64], entries: &[RunEntry], confidence: f64) -> Interval {
    let v: Vec<f64> = rel.iter().zip(entries).map(|(r, e)| r * cpu(e)).collect();
    mean_of_runs(&v, confidence)
}

/// relMSE, FLIP and MSE of each run, and their means with intervals.
struct Errors {
    /// Each run's relMSE, in the runs' order.
    rel_runs: Vec<f64>,
    rel: Interval,
    flip: Interval,
    mse: Interval,
}

fn errors_of_images(images: &[Image], r: &Reference, confidence: f64) -> Result<Errors, String> {
    let rel: Vec<f64> = images.iter().map(|i| rel_mse(i, r)).collect();
    let m: Vec<f64> = images.iter().map(|i| mse(i, r)).collect();
    let flip: Vec<f64> = images
        .iter()
        .map(|i| crate::flip::flip_mean(&r.image, i))
        .collect::<Result<_, _>>()?;
    Ok(Errors {
        rel: mean_of_runs(&rel, confidence),
        rel_runs: rel,
        flip: mean_of_runs(&flip, confidence),
        mse: mean_of_runs(&m, confidence),
    })
}

fn errors(
    entries: &[RunEntry],
    r: &Reference,
    confidence: f64,
) -> Result<(Errors, Vec<Image>), String> {
    let images: Vec<Image> = entries
        .iter()
        .map(|e| e.image())
        .collect::<Result<_, _>>()?;
    Ok((errors_of_images(&images, r, confidence)?, images))
}

/// The `c` rectangle of an image.
fn crop_image(img: &Image, c: Crop) -> Image {
    Image::from_fn(c.w as usize, c.h as usize, |x, y| {
        img.get(c.x as usize + x, c.y as usize + y)
    })
}

/// The reference restricted to the `c` rectangle: its image, its per-pixel variance and their
/// mean (what an MSE on the crop is corrected by).
fn crop_reference(r: &Reference, c: Crop) -> Reference {
    let variance = crop_image(&r.variance, c);
    let n = (3 * variance.data.len()).max(1) as f64;
    let mean_variance = variance.data.iter().flatten().sum::<f64>() / n;
    Reference {
        image: crop_image(&r.image, c),
        variance,
        mean_variance,
        integrator: r.integrator.clone(),
        passes: r.passes,
        runs: r.runs,
        consistent: r.consistent,
        seconds: r.seconds,
    }
}
/// The columns `cell` fills for relMSE, then FLIP: each estimate and its interval's ends.
const ERROR_COLUMNS: [&str; 6] = [
    "relMSE",
    "relMSE lo",
    "relMSE hi",
    "FLIP",
    "FLIP lo",
    "FLIP hi",
];

/// A figure table's columns: `lead`, the error columns, `tail`.
fn columns(lead: &[&'static str], tail: &[&'static str]) -> Vec<&'static str> {
    [lead, &ERROR_COLUMNS[..], tail].concat()
}

/// Gallery entries for (label, image, note) triples, each stored as `gallery/{dir}/{label}`.
pub(super) fn labelled_entries<'a, I: std::borrow::Borrow<Image>>(
    shown: &'a [(&'a str, I, String)],
    dir: &str,
) -> Vec<Entry<'a>> {
    shown
        .iter()
        .map(|(label, image, note)| Entry {
            label,
            note: note.clone(),
            image: image.borrow(),
            stem: format!("gallery/{dir}/{label}"),
        })
        .collect()
}

fn cell(i: &Interval) -> [String; 3] {
    [num(i.estimate), num(i.lo), num(i.hi)]
}

/// Every render of the figures; the equal-time runs only when the context's cache holds the
/// runs and probes that fix their pass counts.
pub fn specs(scale: &Scale, ctx: Option<&StudyContext>) -> Result<Vec<RunSpec>, String> {
    let b = budget(scale);
    let mut v = bidir::specs(scale, &b, ctx)?;
    v.extend(mis::specs(scale, &b)?);
    v.extend(ppm::specs(scale, &b, ctx)?);
    v.extend(vcm::specs(scale, &b, ctx)?);
    Ok(v)
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
    let mut spent = Vec::new();
    let mut mark = ctx.spent();
    let before = mark;
    let mut lap = |ctx: &StudyContext| {
        let now = ctx.spent();
        spent.push((now.0 - mark.0) / 60.0);
        mark = now;
    };
    bidir::figure(ctx, &b, &mut out)?;
    lap(ctx);
    bidir::pyramid_gallery(ctx, &mut out)?;
    mis::figure(ctx, &b, &mut out)?;
    lap(ctx);
    ppm::figure(ctx, &b, &mut out)?;
    lap(ctx);
    vcm::figure(ctx, &b, &mut out)?;
    lap(ctx);
    out.para(&format!(
        "**Compute.** Figure 1 (references included): {:.1} core-minutes; figure 2: {:.1} \
         core-minutes; figure 3: {:.1} core-minutes; figure 4: {:.1} core-minutes.",
        spent[0], spent[1], spent[2], spent[3]
    ));
    out.para(&ctx.compute_note(before));
    out.finish()
}

#[cfg(test)]
mod tests {
    use super::{crop_image, equal_time_passes};
    use crate::manifest::Crop;
    use lt_estimators::Image;

    #[test]
    fn equal_time_passes_round_and_refuse_bad_costs() {
        assert_eq!(equal_time_passes(16.0, 0.5), Ok(32));
        assert_eq!(equal_time_passes(1.0, 0.4), Ok(3));
        assert_eq!(equal_time_passes(0.1, 10.0), Ok(1));
        assert!(equal_time_passes(16.0, f64::NAN).is_err());
        assert!(equal_time_passes(16.0, 0.0).is_err());
    }

    #[test]
    fn crop_takes_the_rectangle() {
        let img = Image::from_fn(5, 4, |x, y| [x as f64, y as f64, 0.0]);
        let c = crop_image(
            &img,
            Crop {
                x: 1,
                y: 2,
                w: 3,
                h: 2,
            },
        );
        assert_eq!((c.width, c.height), (3, 2));
        assert_eq!(c.get(0, 0), [1.0, 2.0, 0.0]);
        assert_eq!(c.get(2, 1), [3.0, 3.0, 0.0]);
    }
}

//! `lt study convergence`: error against samples and against wall time, log-log, for every
//! integrator on every shipped scene; fitted slopes with intervals; the efficiency table.
//!
//! Each (scene, integrator) is K independent runs with snapshots at 1, 2, 4, … passes. The error
//! at N is the mean over runs of each run's error (t interval over the K independent values).
//! A slope is fitted to ln(mean error) against ln N; its interval is the delete-one jackknife
//! over runs, because one run's errors at N and 2N share its first N passes and are not the
//! independent points ordinary least squares assumes. An unbiased estimator's MSE falls as
//! 1/N (slope −1); a consistent one's falls more slowly, and a fixed-radius one's flattens at
//! its bias².

use super::metrics::{log_log_slope, mean_of_runs, mean_over, mse, rel_mse};
use super::output::{film, num, pct, stem, StudyOutput};
use super::reference::Reference;
use super::{Scale, StudyContext};
use crate::plot::{Chart, Series, Style};
use crate::runs::RunSpec;
use lt_estimators::{jackknife, time_to_mse, Interval};
use std::path::PathBuf;

pub const NAME: &str = "convergence";

/// Seeds of study runs: run r of any configuration has seed `1 + r`.
pub fn seed(run: usize) -> u64 {
    1 + run as u64
}

/// The widest 95 % interval a slope may have and still be reported as one: −1 is then told from
/// −2/3 and −1/2 (issue 27). A wider one is reported as "no slope", with why.
pub const SLOPE_WIDTH: f64 = 0.2;

/// The slope of ln MSE against ln N a converging estimator should show at its default
/// parameters: −1 when unbiased; for a progressive one Knaus & Zwicker's −min(α, 2(1−α))
/// (2011, §4.2: bias² falls as N^(−2(1−α)), variance as N^(−α)) at ppm's and sppm's α = 2/3 and
/// bpm's and vcm's 0.75 (their modules' defaults); none for fixed-radius pm, whose MSE levels
/// off at its bias².
pub fn expected_slope(integrator: &str, consistent: bool) -> Option<f64> {
    let kz = |a: f64| -(a.min(2.0 * (1.0 - a)));
    match integrator {
        _ if !consistent => Some(-1.0),
        "ppm" | "sppm" => Some(kz(2.0 / 3.0)),
        "bpm" | "vcm" => Some(kz(lt_integrators::connect_merge::DEFAULT_ALPHA)),
        _ => None,
    }
}

/// What a fitted slope against N may be reported as.
pub enum Verdict {
    /// Narrower than `SLOPE_WIDTH` and told from 0.
    Slope,
    /// Narrow and not told from 0, or above it: the MSE does not fall (a fixed radius's bias²,
    /// light the estimator cannot sample).
    Flat,
    /// No slope, and why.
    NoSlope(String),
}

/// Judges one (scene, integrator)'s slope: a wide interval is not a slope. Why it is wide is
/// told from the runs: one run's MSE far above the others' at the largest N (a heavy tail: rare
/// paths carry the error, and ln of the mean MSE has no stable value over runs), or a curve that
/// bends (the slopes over the first and the second half of the doublings differ, as when bias²
/// and variance trade places).
pub fn verdict(c: &Curves, fit: &Result<lt_estimators::Jackknifed, String>) -> Verdict {
    let j = match fit {
        Ok(j) => j,
        Err(_) => {
            return Verdict::NoSlope(
                "an MSE ≤ 0 after subtracting the reference's noise: error below what the \
                 reference resolves"
                    .into(),
            )
        }
    };
    let width = j.interval.hi - j.interval.lo;
    if width < SLOPE_WIDTH {
        return if j.interval.hi < -0.05 {
            Verdict::Slope
        } else {
            Verdict::Flat
        };
    }
    let last = c.mse.last().cloned().unwrap_or_default();
    let mut sorted = last.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted.get(sorted.len() / 2).copied().unwrap_or(f64::NAN);
    let max = sorted.last().copied().unwrap_or(f64::NAN);
    let all: Vec<usize> = (0..c.runs()).collect();
    let xs: Vec<f64> = c.passes.iter().map(|&p| p as f64).collect();
    let mid = xs.len() / 2;
    let half = |r: std::ops::Range<usize>| log_log_slope(&xs[r.clone()], &c.mse[r], &all).ok();
    let (early, late) = (half(0..mid + 1), half(mid..xs.len()));
    let n_last = c.passes.last().copied().unwrap_or(0);
    let n_mid = c.passes.get(mid).copied().unwrap_or(0);
    let bend = match (early, late) {
        (Some(a), Some(b)) => format!(
            "slope {} over 1 … {n_mid} passes, {} over {n_mid} … {n_last}",
            num(a),
            num(b)
        ),
        _ => "the MSE is ≤ 0 over part of the range".into(),
    };
    let spread = format!(
        "at N = {n_last} the largest of {} runs' MSE is {:.0}× their median",
        c.runs(),
        max / median
    );
    // An unbiased estimator's expected MSE is exactly c/N, so a bent or wide mean curve is a
    // heavy tail over runs; a consistent one's can bend where bias² and variance trade places.
    Verdict::NoSlope(if !c.consistent && max > 4.0 * median {
        format!("heavy-tailed: rare paths carry the error; {spread}; {bend}")
    } else if !c.consistent {
        format!(
            "the mean curve bends ({bend}) while the runs agree at the largest N ({spread}): \
             the line through it swings as runs are left out"
        )
    } else {
        format!("ln MSE is not a line (bias² and variance trade places, or a heavy tail): {bend}; {spread}")
    })
}

/// The figure the report's findings show (file stem inside the study folder).
pub const FINDINGS_FIGURE: &str = "mse-findings";

/// The scene of the findings' figure: the focus scene (the plain box, where every estimator
/// converges), or the first scene when the scale lacks it.
pub fn findings_scene(scale: &Scale) -> PathBuf {
    if scale.scenes.contains(&scale.focus_scene) {
        scale.focus_scene.clone()
    } else {
        scale.scenes.first().cloned().unwrap_or_default()
    }
}

/// MSE against N of unbiased (pt, bdpt) and consistent (pm, ppm, sppm, vcm) estimators on one
/// scene, each named with its slope and interval, or why it has none.
fn findings_figure(scene: &str, curves: &[Curves], conf: f64) -> Chart {
    let shown = ["pt", "bdpt", "pm", "ppm", "sppm", "vcm"];
    let series = curves
        .iter()
        .filter(|c| shown.contains(&c.integrator.as_str()))
        .map(|c| {
            let fit = c.slope(false, conf);
            let label = match (verdict(c, &fit), &fit) {
                (Verdict::Slope, Ok(j)) => format!(
                    "{}: {} [{}, {}]",
                    c.integrator,
                    num(j.estimate),
                    num(j.interval.lo),
                    num(j.interval.hi)
                ),
                (Verdict::Flat, _) => format!("{}: flat", c.integrator),
                _ => format!("{}: no slope", c.integrator),
            };
            Series {
                name: label,
                ..series(c, false, conf)
            }
        })
        .collect();
    Chart {
        title: format!(
            "{scene}: MSE against N, slopes with {} % intervals",
            pct(conf)
        ),
        x_label: "passes (spp)".into(),
        y_label: "MSE".into(),
        log_x: true,
        log_y: true,
        series,
    }
}

pub fn integrators() -> Vec<&'static str> {
    lt_integrators::INTEGRATORS.iter().map(|i| i.name).collect()
}

pub fn spec(scale: &Scale, scene: &PathBuf, integrator: &str, run: usize) -> RunSpec {
    let res = film(scale, scene).ok();
    RunSpec::new(scene, integrator, seed(run), scale.max_passes)
        .resolution(res)
        .snapshots(Scale::doublings(scale.max_passes))
}

pub fn specs(scale: &Scale) -> Vec<RunSpec> {
    let mut v = Vec::new();
    for scene in &scale.scenes {
        if let Ok(r) = super::reference::spec(scale, scene, None) {
            v.push(r);
        }
        for i in integrators() {
            for r in 0..scale.runs {
                v.push(spec(scale, scene, i, r));
            }
        }
    }
    v
}

/// One (scene, integrator): the error curves over its runs.
pub struct Curves {
    pub scene: String,
    pub integrator: String,
    pub consistent: bool,
    pub passes: Vec<u32>,
    /// Mean wall seconds to reach each snapshot.
    pub seconds: Vec<f64>,
    /// Per snapshot, per run.
    pub mse: Vec<Vec<f64>>,
    pub rel_mse: Vec<Vec<f64>>,
    pub flip: Vec<Vec<f64>>,
}

impl Curves {
    pub fn runs(&self) -> usize {
        self.mse.first().map_or(0, |v| v.len())
    }

    pub fn mean_mse(&self, confidence: f64) -> Vec<Interval> {
        self.mse
            .iter()
            .map(|v| mean_of_runs(v, confidence))
            .collect()
    }

    /// Slope of ln MSE against ln x (x = passes or seconds) with its jackknife interval.
    pub fn slope(
        &self,
        against_time: bool,
        confidence: f64,
    ) -> Result<lt_estimators::Jackknifed, String> {
        let xs: Vec<f64> = if against_time {
            self.seconds.clone()
        } else {
            self.passes.iter().map(|&p| p as f64).collect()
        };
        jackknife(self.runs(), confidence, |kept| {
            log_log_slope(&xs, &self.mse, kept)
        })
    }
}

/// Renders (or finds) and measures every run of `integrator` on `scene`.
pub fn curves(ctx: &StudyContext, scene: &PathBuf, integrator: &str) -> Result<Curves, String> {
    let reference = ctx.reference(scene, None)?;
    let specs: Vec<RunSpec> = (0..ctx.scale.runs)
        .map(|r| spec(&ctx.scale, scene, integrator, r))
        .collect();
    let entries = ctx.run_all(&specs)?;
    let passes = specs[0].snapshots.clone();
    let (mut seconds, mut m, mut rel, mut fl) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for &p in &passes {
        let (mut a, mut b, mut c, mut t) = (Vec::new(), Vec::new(), Vec::new(), 0.0);
        for e in &entries {
            let img = e.snapshot(p)?;
            a.push(mse(&img, &reference));
            b.push(rel_mse(&img, &reference));
            c.push(crate::flip::flip_mean(&reference.image, &img)?);
            t += e.seconds_at(p).unwrap_or(f64::NAN);
        }
        m.push(a);
        rel.push(b);
        fl.push(c);
        seconds.push(t / entries.len() as f64);
    }
    Ok(Curves {
        scene: stem(scene),
        integrator: integrator.into(),
        consistent: entries[0].record.consistent(),
        passes,
        seconds,
        mse: m,
        rel_mse: rel,
        flip: fl,
    })
}

fn series(c: &Curves, against_time: bool, conf: f64) -> Series {
    let iv = c.mean_mse(conf);
    let xs: Vec<f64> = if against_time {
        c.seconds.clone()
    } else {
        c.passes.iter().map(|&p| p as f64).collect()
    };
    Series {
        name: c.integrator.clone(),
        points: xs.iter().zip(&iv).map(|(&x, i)| (x, i.estimate)).collect(),
        y_interval: iv.iter().map(|i| (i.lo, i.hi)).collect(),
        style: Style::Measured,
    }
}

pub fn run(ctx: &StudyContext) -> Result<(), String> {
    let scale = &ctx.scale;
    let conf = scale.confidence;
    let mut out = StudyOutput::new(
        ctx.study_dir(NAME),
        NAME,
        "Convergence: error against samples and time",
        scale,
    )?;
    describe(&mut out, scale);
    let before = ctx.spent();
    let mut rows = Rows::default();
    let mut findings_chart = None;
    for scene in &scale.scenes {
        let name = stem(scene);
        rows.references
            .push(reference_row(&name, &*ctx.reference(scene, None)?));
        let mut scene_curves = Vec::new();
        for i in integrators() {
            let c = curves(ctx, scene, i)?;
            rows.all.extend(measurement_rows(&name, &c, conf));
            rows.slopes.push(slope_row(&name, &c, conf));
            scene_curves.push(c);
        }
        if *scene == findings_scene(scale) {
            findings_chart = Some(findings_figure(&name, &scene_curves, conf));
        }
        rows.efficiency
            .extend(efficiency_rows(&name, &scene_curves, conf));
        scene_charts(&mut out, ctx, &name, &scene_curves)?;
    }
    if let Some(chart) = findings_chart {
        out.chart(
            FINDINGS_FIGURE,
            &chart,
            &format!(
                "MSE against N on {}, unbiased and consistent estimators, mean of {} runs with {} % \
                 intervals; each name carries its fitted slope and jackknife interval, or why it \
                 has none (the slopes table).",
                stem(&findings_scene(scale)),
                scale.runs,
                pct(conf)
            ),
        )?;
    }
    write_tables(&mut out, rows)?;
    out.para(&ctx.compute_note(before));
    out.finish()
}

/// The study's opening paragraph: what was run and how errors and slopes are measured.
fn describe(out: &mut StudyOutput, scale: &Scale) {
    let conf = scale.confidence;
    out.para(&format!(
        "Every integrator on every scene of the {} scale at {} px wide, {} independent runs each, \
         snapshots at 1, 2, 4, … {} passes. MSE is the mean over pixels and channels of \
         (I − R)² minus the reference's own mean variance (so it estimates the error against the \
         true image); relMSE divides each term by R² + {}; FLIP is NVIDIA's perceptual error on \
         the tone-mapped images. Points are means over runs with {} % t intervals; slopes are \
         fitted to ln MSE against ln N or ln t, with delete-one jackknife intervals over runs. An \
         unbiased estimator's slope against N is −1.",
        scale.name,
        scale.width,
        scale.runs,
        scale.max_passes,
        super::metrics::REL_EPSILON,
        pct(conf)
    ));
}

/// The rows of the study's tables, gathered scene by scene.
#[derive(Default)]
struct Rows {
    references: Vec<Vec<String>>,
    all: Vec<Vec<String>>,
    slopes: Vec<Vec<String>>,
    efficiency: Vec<Vec<String>>,
}

/// What a scene's errors are measured against.
fn reference_row(name: &str, reference: &Reference) -> Vec<String> {
    vec![
        name.into(),
        reference.integrator.clone(),
        format!("{} × {}", reference.runs, reference.passes),
        num(reference.mean_variance),
        if reference.consistent {
            "consistent"
        } else {
            "unbiased"
        }
        .into(),
        super::reference::integrator_for(name).1.into(),
    ]
}

/// Every snapshot of one integrator's runs: seconds, MSE with its interval, relMSE, FLIP.
fn measurement_rows(name: &str, c: &Curves, conf: f64) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    for (j, &p) in c.passes.iter().enumerate() {
        let all: Vec<usize> = (0..c.runs()).collect();
        let iv = c.mean_mse(conf)[j];
        rows.push(vec![
            name.into(),
            c.integrator.clone(),
            p.to_string(),
            format!("{:.6}", c.seconds[j]),
            format!("{:.6e}", iv.estimate),
            format!("{:.6e}", iv.lo),
            format!("{:.6e}", iv.hi),
            format!("{:.6e}", mean_over(&all, &c.rel_mse[j])),
            format!("{:.6e}", mean_over(&all, &c.flip[j])),
        ]);
    }
    rows
}

/// One integrator's fitted slopes against N and t, its expected slope and the verdict.
fn slope_row(name: &str, c: &Curves, conf: f64) -> Vec<String> {
    let cell = |r: Result<lt_estimators::Jackknifed, String>| match r {
        Ok(j) => (
            num(j.estimate),
            format!("[{}, {}]", num(j.interval.lo), num(j.interval.hi)),
        ),
        Err(_) => (
            "—".into(),
            "undefined (an MSE ≤ 0 after subtracting the reference's noise)".into(),
        ),
    };
    let fit_n = c.slope(false, conf);
    let (mut s_n, ci_n) = cell(fit_n.clone());
    let (s_t, ci_t) = cell(c.slope(true, conf));
    let width = fit_n
        .as_ref()
        .map_or("—".into(), |j| num(j.interval.hi - j.interval.lo));
    let expected = expected_slope(&c.integrator, c.consistent);
    let (inside, said) = match verdict(c, &fit_n) {
        Verdict::Slope => {
            let j = fit_n.as_ref().expect("a slope has a fit");
            let inside = expected.map_or("—", |e| {
                if j.interval.lo <= e && e <= j.interval.hi {
                    "yes"
                } else {
                    "no"
                }
            });
            (inside, "slope".to_string())
        }
        Verdict::Flat => ("—", "flat: the MSE does not fall over these N".into()),
        Verdict::NoSlope(why) => {
            s_n = "no slope".into();
            ("—", format!("no slope: {why}"))
        }
    };
    vec![
        name.into(),
        c.integrator.clone(),
        if c.consistent {
            "consistent"
        } else {
            "unbiased"
        }
        .into(),
        s_n,
        ci_n,
        width,
        expected.map_or("—".into(), num),
        inside.into(),
        said,
        s_t,
        ci_t,
    ]
}

/// Efficiency at the largest N, and time to the scene's target MSE: the median of the
/// integrators' final MSEs, so some reach it inside the measured range and some do not.
fn efficiency_rows(name: &str, scene_curves: &[Curves], conf: f64) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    // Efficiency at the largest N, and time to the scene's target MSE: the median of the
    // integrators' final MSEs, so some reach it inside the measured range and some do not.
    let last = |c: &Curves| c.mean_mse(conf).last().map_or(f64::NAN, |i| i.estimate);
    let mut finals: Vec<f64> = scene_curves.iter().map(last).filter(|v| *v > 0.0).collect();
    finals.sort_by(f64::total_cmp);
    let target = finals.get(finals.len() / 2).copied().unwrap_or(f64::NAN);
    for c in scene_curves {
        let (m, t) = (last(c), *c.seconds.last().unwrap_or(&f64::NAN));
        let curve: Vec<(f64, f64)> = c
            .seconds
            .iter()
            .zip(c.mean_mse(conf))
            .map(|(&t, i)| (t, i.estimate))
            .collect();
        let reach = match (time_to_mse(&curve, target), c.slope(true, conf)) {
            (Some(s), _) => num(s),
            // Outside the measured range: along the fitted power law MSE ∝ t^slope, for
            // unbiased estimators, whose law holds at every N, and only when the slope is
            // told from 0 (an estimator that misses some light has a flat curve).
            (None, Ok(j)) if !c.consistent && j.interval.hi < 0.0 => {
                format!("≈{}", num(t * (target / m).powf(1.0 / j.estimate)))
            }
            (None, _) if m > target => "not reached".into(),
            (None, _) => "below it at N = 1".into(),
        };
        rows.push(vec![
            name.into(),
            c.integrator.clone(),
            num(m),
            format!("{t:.3}"),
            num(lt_estimators::efficiency(m, t)),
            num(target),
            reach,
        ]);
    }
    rows
}

/// A scene's MSE against passes and against wall time, every integrator.
fn scene_charts(
    out: &mut StudyOutput,
    ctx: &StudyContext,
    name: &str,
    scene_curves: &[Curves],
) -> Result<(), String> {
    let (scale, conf) = (&ctx.scale, ctx.scale.confidence);
    let chart = |time: bool| Chart {
        title: format!(
            "{name}: MSE against {}",
            if time {
                "wall time"
            } else {
                "samples per pixel"
            }
        ),
        x_label: if time {
            "seconds".into()
        } else {
            "passes (spp)".into()
        },
        y_label: "MSE".into(),
        log_x: true,
        log_y: true,
        series: scene_curves.iter().map(|c| series(c, time, conf)).collect(),
    };
    out.chart(
        &format!("mse-spp-{name}"),
        &chart(false),
        &format!(
            "MSE against passes on {name}, mean of {} runs with {} % intervals.",
            scale.runs,
            pct(conf)
        ),
    )?;
    out.chart(
            &format!("mse-time-{name}"),
            &chart(true),
            &format!("MSE against wall time on {name} ({} threads; timings vary ±20 % on this kind of machine).", if ctx.runs.threads == 0 { "all".to_string() } else { ctx.runs.threads.to_string() }),
        )?;
    Ok(())
}

fn write_tables(out: &mut StudyOutput, rows: Rows) -> Result<(), String> {
    out.table(
        "references",
        "References",
        "What every error here is measured against (passes are per run).",
        &[
            "scene",
            "integrator",
            "runs × passes",
            "mean variance",
            "kind",
            "why",
        ],
        rows.references,
        true,
    )?;
    out.table(
        "slopes",
        "Fitted slopes",
        "ln MSE against ln N and against ln t, with jackknife intervals over runs. A slope is \
         reported only where its interval is narrower than 0.2 and told from 0 (`verdict`: \
         slope); `expected` is −1 for an unbiased estimator and Knaus & Zwicker's \
         −min(α, 2(1−α)) for a progressive one (ppm, sppm: α = 2/3; bpm, vcm: α = 0.75; an \
         asymptotic rate, which sppm's camera resampling, falling as 1/N, hides at these N), \
         `inside` whether the interval holds it. Where an interval is wider, the row says \
         \"no slope\" and why: one run's MSE far above the others' (heavy tails) or the curve's \
         bend between the first and second half of the doublings.",
        &[
            "scene",
            "integrator",
            "kind",
            "slope vs N",
            "CI vs N",
            "width",
            "expected",
            "inside",
            "verdict",
            "slope vs t",
            "CI vs t",
        ],
        rows.slopes,
        true,
    )?;
    out.table(
        "efficiency",
        "Efficiency",
        "At the largest N: MSE, seconds, efficiency 1/(MSE·t), and the seconds to reach the \
         scene's target MSE (the median of the final MSEs; ≈ marks a time extrapolated along \
         the fitted slope, for unbiased estimators only).",
        &[
            "scene",
            "integrator",
            "MSE",
            "seconds",
            "1/(MSE·t)",
            "target MSE",
            "seconds to target",
        ],
        rows.efficiency,
        true,
    )?;
    out.table(
        "convergence",
        "Every measurement",
        "Per scene, integrator and pass count: mean seconds, MSE with its interval, relMSE, FLIP.",
        &[
            "scene",
            "integrator",
            "passes",
            "seconds",
            "mse",
            "mse_lo",
            "mse_hi",
            "rel_mse",
            "flip",
        ],
        rows.all,
        false,
    )
}

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
use super::{Ctx, Scale};
use crate::plot::{Chart, Series, Style};
use crate::runs::RunSpec;
use lt_estimators::{jackknife, time_to_mse, Interval};
use std::path::PathBuf;

pub const NAME: &str = "convergence";

/// Seeds of study runs: run r of any configuration has seed `1 + r`.
pub fn seed(run: usize) -> u64 {
    1 + run as u64
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
pub fn curves(ctx: &Ctx, scene: &PathBuf, integrator: &str) -> Result<Curves, String> {
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

pub fn run(ctx: &Ctx) -> Result<(), String> {
    let scale = &ctx.scale;
    let conf = scale.confidence;
    let mut out = StudyOutput::new(
        ctx.study_dir(NAME),
        NAME,
        "Convergence: error against samples and time",
        scale,
    )?;
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
    let before = ctx.spent();
    let mut all_rows = Vec::new();
    let mut slope_rows = Vec::new();
    let mut eff_rows = Vec::new();
    let mut ref_rows = Vec::new();
    for scene in &scale.scenes {
        let name = stem(scene);
        let reference = ctx.reference(scene, None)?;
        ref_rows.push(vec![
            name.clone(),
            reference.integrator.clone(),
            format!("{} × {}", reference.runs, reference.passes),
            num(reference.mean_variance),
            if reference.consistent {
                "consistent"
            } else {
                "unbiased"
            }
            .into(),
            super::reference::integrator_for(&name).1.into(),
        ]);
        let mut scene_curves = Vec::new();
        for i in integrators() {
            let c = curves(ctx, scene, i)?;
            for (j, &p) in c.passes.iter().enumerate() {
                let all: Vec<usize> = (0..c.runs()).collect();
                let iv = c.mean_mse(conf)[j];
                all_rows.push(vec![
                    name.clone(),
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
            let (s_n, ci_n) = cell(c.slope(false, conf));
            let (s_t, ci_t) = cell(c.slope(true, conf));
            slope_rows.push(vec![
                name.clone(),
                c.integrator.clone(),
                if c.consistent {
                    "consistent"
                } else {
                    "unbiased"
                }
                .into(),
                s_n,
                ci_n,
                s_t,
                ci_t,
            ]);
            scene_curves.push(c);
        }
        // Efficiency at the largest N, and time to the scene's target MSE: the median of the
        // integrators' final MSEs, so some reach it inside the measured range and some do not.
        let last = |c: &Curves| c.mean_mse(conf).last().map_or(f64::NAN, |i| i.estimate);
        let mut finals: Vec<f64> = scene_curves.iter().map(last).filter(|v| *v > 0.0).collect();
        finals.sort_by(f64::total_cmp);
        let target = finals.get(finals.len() / 2).copied().unwrap_or(f64::NAN);
        for c in &scene_curves {
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
            eff_rows.push(vec![
                name.clone(),
                c.integrator.clone(),
                num(m),
                format!("{t:.3}"),
                num(lt_estimators::efficiency(m, t)),
                num(target),
                reach,
            ]);
        }
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
    }
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
        ref_rows,
        true,
    )?;
    out.table(
        "slopes",
        "Fitted slopes",
        "ln MSE against ln N and against ln t, with jackknife intervals over runs.",
        &[
            "scene",
            "integrator",
            "kind",
            "slope vs N",
            "CI",
            "slope vs t",
            "CI",
        ],
        slope_rows,
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
        eff_rows,
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
        all_rows,
        false,
    )?;
    out.para(&ctx.compute_note(before));
    out.finish()
}

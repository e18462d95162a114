//! `lt study unbiased-vs-consistent`: bias² and variance against N from K independent runs, for
//! unbiased estimators (pt, bdpt: bias² interval includes 0 at every N), fixed-radius photon
//! mapping (pm: a bias plateau that more passes do not lower) and the consistent ones (ppm,
//! sppm, vcm: bias² → 0 as the radius shrinks); and the lecture's 1-D example with its exact
//! bias beside the measured one.
//!
//! At each N, per pixel and channel, bias² = (mean over runs − R̂)² − s²/K (unbiased for the
//! squared bias of one run), averaged over the image, minus the reference's mean variance;
//! variance = the mean per-pixel sample variance over runs. Intervals are delete-one jackknife
//! over runs (`ImageBiasVariance`), since every pixel's terms share the same runs.

use super::output::{film, num, pct, stem, StudyOutput};
use super::{Ctx, Scale};
use crate::plot::{Chart, Series, Style};
use crate::runs::RunSpec;
use lt_estimators::{ImageBiasVariance, Interval};
use std::path::Path;

pub const NAME: &str = "unbiased-vs-consistent";

/// (label, integrator, parameters).
type Config = (
    &'static str,
    &'static str,
    &'static [(&'static str, &'static str)],
);
pub const CONFIGS: [Config; 6] = [
    ("pt", "pt", &[]),
    ("bdpt", "bdpt", &[]),
    (
        "pm (fixed radius)",
        "pm",
        &[("direct", "photons"), ("radius_px", "4")],
    ),
    ("ppm", "ppm", &[]),
    ("sppm", "sppm", &[]),
    ("vcm", "vcm", &[]),
];

/// Runs per configuration.
pub fn runs(scale: &Scale) -> usize {
    scale.bias_runs
}

pub fn config_specs(
    scale: &Scale,
    scene: &Path,
    integrator: &str,
    params: &[(&str, &str)],
    passes: u32,
) -> Vec<RunSpec> {
    let res = film(scale, scene).ok();
    (0..runs(scale))
        .map(|r| {
            let mut s = RunSpec::new(scene, integrator, 1 + r as u64, passes)
                .resolution(res)
                .snapshots(Scale::doublings(passes));
            for (k, v) in params {
                s = s.param(k, v);
            }
            s
        })
        .collect()
}

pub fn specs(scale: &Scale) -> Vec<RunSpec> {
    let mut v: Vec<RunSpec> = super::reference::spec(scale, &scale.bias_scene, None)
        .into_iter()
        .collect();
    for (_, i, p) in CONFIGS {
        v.extend(config_specs(
            scale,
            &scale.bias_scene,
            i,
            p,
            scale.progressive_passes,
        ));
    }
    v
}

/// bias², variance and MSE at each snapshot.
pub struct Decomposition {
    pub label: String,
    pub passes: Vec<u32>,
    pub bias2: Vec<Interval>,
    pub variance: Vec<Interval>,
    pub mse: Vec<Interval>,
}

pub fn decompose(
    ctx: &Ctx,
    scene: &Path,
    label: &str,
    integrator: &str,
    params: &[(&str, &str)],
    passes: u32,
) -> Result<Decomposition, String> {
    let scale = &ctx.scale;
    let reference = ctx.reference(scene, None)?;
    let specs = config_specs(scale, scene, integrator, params, passes);
    let entries = ctx.run_all(&specs)?;
    let snaps = specs[0].snapshots.clone();
    let shift = |i: Interval, by: f64| Interval {
        estimate: i.estimate - by,
        lo: i.lo - by,
        hi: i.hi - by,
    };
    let mut d = Decomposition {
        label: label.into(),
        passes: snaps.clone(),
        bias2: Vec::new(),
        variance: Vec::new(),
        mse: Vec::new(),
    };
    for &p in &snaps {
        let images: Vec<_> = entries
            .iter()
            .map(|e| e.snapshot(p))
            .collect::<Result<_, _>>()?;
        let bv = ImageBiasVariance::from_runs(&images, &reference.image, scale.confidence);
        d.bias2.push(shift(bv.bias2, reference.mean_variance));
        d.variance.push(bv.variance);
        d.mse.push(shift(bv.mse, reference.mean_variance));
    }
    Ok(d)
}

fn series(name: &str, xs: &[u32], iv: &[Interval], style: Style) -> Series {
    Series {
        name: name.into(),
        points: xs
            .iter()
            .zip(iv)
            .map(|(&x, i)| (x as f64, i.estimate))
            .collect(),
        y_interval: iv.iter().map(|i| (i.lo, i.hi)).collect(),
        style,
    }
}

pub fn run(ctx: &Ctx) -> Result<(), String> {
    let scale = &ctx.scale;
    let scene = stem(&scale.bias_scene);
    let mut out = StudyOutput::new(
        ctx.study_dir(NAME),
        NAME,
        "Unbiased against consistent: bias² and variance against N",
        scale,
    )?;
    out.para(&format!(
        "{k} independent runs of each estimator on `{scene}` at {w} px wide, snapshots at 1, 2, 4, \
         … {n} passes. Per pixel and channel, bias² = (mean of the runs − reference)² − s²/K, \
         averaged over the image and corrected for the reference's own noise; variance is the \
         mean per-pixel variance of one run. Intervals ({c} %) are delete-one jackknife over \
         the runs. Unbiased estimators' bias² intervals should include 0; fixed-radius photon \
         mapping keeps a bias no number of passes removes; the progressive estimators' bias² \
         falls as their radius shrinks. Points ≤ 0 are not drawn on the log axes (the CSV has \
         them).",
        k = runs(scale),
        w = scale.width,
        n = scale.progressive_passes,
        c = pct(scale.confidence)
    ));
    let mut rows = Vec::new();
    let mut final_rows = Vec::new();
    let mut decs = Vec::new();
    for (label, integrator, params) in CONFIGS {
        let d = decompose(
            ctx,
            &scale.bias_scene,
            label,
            integrator,
            params,
            scale.progressive_passes,
        )?;
        for (j, &p) in d.passes.iter().enumerate() {
            rows.push(vec![
                label.to_string(),
                p.to_string(),
                format!("{:.6e}", d.bias2[j].estimate),
                format!("{:.6e}", d.bias2[j].lo),
                format!("{:.6e}", d.bias2[j].hi),
                format!("{:.6e}", d.variance[j].estimate),
                format!("{:.6e}", d.variance[j].lo),
                format!("{:.6e}", d.variance[j].hi),
                format!("{:.6e}", d.mse[j].estimate),
            ]);
        }
        let (b, v) = (*d.bias2.last().unwrap(), *d.variance.last().unwrap());
        let b1 = d.bias2[0];
        final_rows.push(vec![
            label.to_string(),
            format!("{} [{}, {}]", num(b1.estimate), num(b1.lo), num(b1.hi)),
            format!("{} [{}, {}]", num(b.estimate), num(b.lo), num(b.hi)),
            if b.contains(0.0) { "yes" } else { "no" }.into(),
            format!("{} [{}, {}]", num(v.estimate), num(v.lo), num(v.hi)),
        ]);
        decs.push(d);
    }
    out.table(
        "final",
        "At N = 1 and at the largest N",
        "bias² with its interval at the first and last snapshot, whether the last includes 0, \
         and the variance of one run at the last.",
        &[
            "estimator",
            "bias² at N = 1",
            "bias² at largest N",
            "includes 0",
            "variance at largest N",
        ],
        final_rows,
        true,
    )?;
    out.table(
        "bias-variance",
        "bias², variance and MSE at every N",
        "With their jackknife intervals.",
        &[
            "estimator",
            "passes",
            "bias2",
            "bias2_lo",
            "bias2_hi",
            "variance",
            "variance_lo",
            "variance_hi",
            "mse",
        ],
        rows,
        false,
    )?;
    let chart = |what: &str, pick: fn(&Decomposition) -> &Vec<Interval>| Chart {
        title: format!("{scene}: {what} against passes"),
        x_label: "passes".into(),
        y_label: what.into(),
        log_x: true,
        log_y: true,
        series: decs
            .iter()
            .map(|d| series(&d.label, &d.passes, pick(d), Style::Measured))
            .collect(),
    };
    out.chart("bias2", &chart("bias²", |d| &d.bias2), "Squared bias against passes: unbiased estimators scatter around 0 (not drawn when ≤ 0); pm's stays level; ppm, sppm and vcm fall.")?;
    out.chart(
        "variance",
        &chart("variance", |d| &d.variance),
        "Variance of one run against passes.",
    )?;

    // The lecture's example.
    let ns = Scale::doublings(64);
    let lecture = super::lecture::measure(&ns, scale.lecture_repetitions, scale.confidence);
    let mut lrows = Vec::new();
    for r in &lecture {
        lrows.push(vec![
            r.n.to_string(),
            num(r.exact_bias),
            format!(
                "{} [{}, {}]",
                num(r.biased.estimate),
                num(r.biased.lo),
                num(r.biased.hi)
            ),
            if r.biased.contains(r.exact_bias) {
                "yes"
            } else {
                "no"
            }
            .into(),
            format!(
                "{} [{}, {}]",
                num(r.unbiased.estimate),
                num(r.unbiased.lo),
                num(r.unbiased.hi)
            ),
            num(r.exact_variance_biased),
            num(r.measured_variance_biased),
        ]);
    }
    out.para(&format!(
        "**The lecture's example.** f(x) = 3x² on [0, 1] (μ = 1, σ² = 0.8), {} repetitions per N: \
         (1/N) Σ f is unbiased; (1/(N+1)) Σ f has bias exactly −μ/(N+1), which vanishes as N \
         grows — biased yet consistent.",
        scale.lecture_repetitions
    ));
    out.table(
        "lecture",
        "(1/N) Σ f against (1/(N+1)) Σ f",
        "Exact and measured bias (t intervals over the repetitions), and the biased estimator's \
         variance N σ²/(N+1)² exact and measured.",
        &[
            "N",
            "exact bias of 1/(N+1)",
            "measured",
            "exact inside",
            "bias of 1/N",
            "variance exact",
            "variance measured",
        ],
        lrows,
        true,
    )?;
    let xs: Vec<f64> = lecture.iter().map(|r| r.n as f64).collect();
    out.chart(
        "lecture",
        &Chart {
            title: "The lecture's example: |bias| of (1/(N+1)) Σ f".into(),
            x_label: "N".into(),
            y_label: "|bias|".into(),
            log_x: true,
            log_y: true,
            series: vec![
                Series {
                    name: "exact μ/(N+1)".into(),
                    points: lecture
                        .iter()
                        .map(|r| (r.n as f64, -r.exact_bias))
                        .collect(),
                    y_interval: Vec::new(),
                    style: Style::Fitted,
                },
                Series {
                    name: "measured".into(),
                    points: xs
                        .iter()
                        .zip(&lecture)
                        .map(|(&x, r)| (x, -r.biased.estimate))
                        .collect(),
                    y_interval: lecture
                        .iter()
                        .map(|r| (-r.biased.hi, -r.biased.lo))
                        .collect(),
                    style: Style::Measured,
                },
            ],
        },
        "Measured bias (t intervals) against the exact −μ/(N+1).",
    )?;
    out.finish()
}

//! `lt study radius-shrinkage`: ppm, sppm and vcm with radius-reduction exponents α ∈ {0.3, 0.5,
//! 2/3, 0.75, 0.9, 1}: bias², variance and MSE against passes with fitted slopes, beside the rates
//! Knaus & Zwicker (2011, "Progressive photon mapping: a probabilistic approach") predict.
//!
//! With r_N² = r_1² N^(α−1) (our global schedule), pass N's variance grows as 1/r_N² and its bias
//! as r_N², so the mean of N passes has
//!   variance ∝ N^(−α),   bias ∝ N^(α−1), bias² ∝ N^(−2(1−α)),   MSE ∝ N^(−min(α, 2(1−α))),
//! best at α = 2/3 (MSE ∝ N^(−2/3)); α = 1 keeps the radius and the bias. These are asymptotic
//! rates: slopes are fitted over the last snapshots only (N ≥ 1/8 of the largest), with
//! delete-one jackknife intervals over the independent runs.

use super::metrics::subset_bias_variance;
use super::output::{num, pct, slope_cells, stem, StudyOutput};
use super::unbiased_consistent::{config_specs, decompose, runs, Decomposition};
use super::{Scale, StudyContext};
use crate::plot::{Chart, Series, Style};
use crate::runs::RunSpec;
use lt_estimators::jackknife;

pub const NAME: &str = "radius-shrinkage";
pub const INTEGRATORS: [&str; 3] = ["ppm", "sppm", "vcm"];

/// vcm keeps its radius in f32: r² then carries up to ~2 ulps of f32 rounding (2 × 2⁻²³); the
/// check allows 8 × 2⁻²⁴ ≈ 4.8e-7 relative.
pub const SCHEDULE_TOLERANCE: f64 = 8.0 / 16_777_216.0;

pub use super::metrics::alpha_text;

/// The parameter value passed to the integrator (the shortest text that reads back as `a`).
fn alpha_param(a: f64) -> String {
    format!("{a}")
}

pub fn specs(scale: &Scale) -> Vec<RunSpec> {
    let mut v: Vec<RunSpec> = super::reference::spec(scale, &scale.focus_scene, None)
        .into_iter()
        .collect();
    for i in INTEGRATORS {
        for &a in &scale.alphas {
            for fixed in [false, true] {
                // Fixed visible points: only an integrator that takes a camera-pass seed.
                if fixed && !takes(i, FIXED_POINTS.0) {
                    continue;
                }
                let p = params(i, a, fixed);
                let p: Vec<(&str, &str)> = p.iter().map(|(k, v)| (*k, v.as_str())).collect();
                v.extend(config_specs(
                    scale,
                    &scale.focus_scene,
                    i,
                    &p,
                    scale.progressive_passes,
                ));
            }
        }
    }
    v
}

/// The parameters of one configuration. ppm and sppm take all light from photons here
/// (`direct=photons`): next-event estimation, re-sampled every pass, would add a variance falling
/// as 1/N whatever α, and Knaus & Zwicker's rates describe the photon estimate alone.
pub fn params(integrator: &str, alpha: f64, fixed_points: bool) -> Vec<(&'static str, String)> {
    let mut p = vec![("alpha", alpha_param(alpha))];
    if takes(integrator, "direct") {
        p.push(("direct", "photons".into()));
    }
    if fixed_points {
        p.push((FIXED_POINTS.0, FIXED_POINTS.1.into()));
    }
    p
}

/// ppm's visible points are drawn once per run, so its spread over runs holds the spread of
/// the points' positions in their pixels, which no pass reduces. Runs that share the camera pass
/// (`visible_seed`) differ in photons only: their spread is the variance at fixed points whose
/// rate Knaus & Zwicker predict.
pub const FIXED_POINTS: (&str, &str) = ("visible_seed", "1");

/// Whether the registry says `integrator` reads `key` (false for an unknown name).
fn takes(integrator: &str, key: &str) -> bool {
    lt_integrators::registry::find(integrator).is_ok_and(|i| i.takes(key))
}

/// r²ᵢ / r²₁ of the schedule the registry gives `integrator` (NaN without one).
fn schedule(integrator: &str, i: u32, alpha: f64) -> f64 {
    lt_integrators::registry::find(integrator)
        .ok()
        .and_then(|info| info.radius.scale2(i, alpha))
        .unwrap_or(f64::NAN)
}

/// Predicted log-log slopes against N: (variance, bias², MSE, r²).
pub fn predicted(alpha: f64) -> (f64, f64, f64, f64) {
    let b2 = -2.0 * (1.0 - alpha);
    (-alpha, b2, -alpha.min(2.0 * (1.0 - alpha)), alpha - 1.0)
}

/// The same rates at the pass counts measured, from Knaus & Zwicker's model with the schedule
/// the integrator follows (s_i = (r_i / r_1)²): the mean of N passes has variance ∝
/// (1/N²) Σ_{i≤N} 1/s_i and bias ∝ (1/N) Σ_{i≤N} s_i. Their log-log slopes over `tail` are what
/// the measured slopes should match at this N; the asymptotic ones above are their limit.
/// Returns (variance slope, bias² slope, MSE slope = the one of the two that dominates, taken as
/// the asymptotic rule min(α, 2(1 − α))).
pub fn predicted_at(integrator: &str, alpha: f64, tail: &[u32]) -> (f64, f64) {
    let s = |i: u32| schedule(integrator, i, alpha);
    let xs: Vec<f64> = tail.iter().map(|&n| (n as f64).ln()).collect();
    let (mut var, mut b2) = (Vec::new(), Vec::new());
    for &n in tail {
        let nf = n as f64;
        var.push(((1..=n).map(|i| 1.0 / s(i)).sum::<f64>() / (nf * nf)).ln());
        b2.push((2.0 * ((1..=n).map(s).sum::<f64>() / nf).ln()).max(f64::MIN));
    }
    let slope = |ys: &[f64]| lt_estimators::fit_line(&xs, ys, 0.95).map_or(f64::NAN, |f| f.slope);
    (slope(&var), slope(&b2))
}

/// The snapshots a slope is fitted over: N ≥ 1/8 of the largest.
pub fn tail_of(passes: &[u32], last: u32) -> Vec<u32> {
    passes.iter().copied().filter(|&n| 8 * n >= last).collect()
}

/// One configuration's measured slopes over the asymptotic snapshots.
pub struct Rates {
    pub integrator: String,
    pub alpha: f64,
    /// (measured slope with its jackknife interval, or why there is none) for variance, bias², MSE.
    pub slopes: [Result<lt_estimators::Jackknifed, String>; 3],
    /// Slope of (r_N/r_1)² against N over the tail, from the run's log (deterministic).
    pub r2_slope: f64,
    /// Largest relative difference of the logged (r_N/r_1)² from Knaus & Zwicker's product.
    pub schedule_error: f64,
    pub passes: Vec<u32>,
    pub r2: Vec<f64>,
}

pub fn rates(
    ctx: &StudyContext,
    integrator: &str,
    alpha: f64,
    fixed_points: bool,
) -> Result<(Rates, Decomposition), String> {
    let scale = &ctx.scale;
    let owned = params(integrator, alpha, fixed_points);
    let params: Vec<(&str, &str)> = owned.iter().map(|(k, v)| (*k, v.as_str())).collect();
    let reference = ctx.reference(&scale.focus_scene, None)?;
    let label = format!(
        "{integrator}{} α={}",
        if fixed_points { " (fixed points)" } else { "" },
        alpha_text(alpha)
    );
    let dec = decompose(
        ctx,
        &scale.focus_scene,
        &label,
        integrator,
        &params,
        scale.progressive_passes,
    )?;
    let specs = config_specs(
        scale,
        &scale.focus_scene,
        integrator,
        &params,
        scale.progressive_passes,
    );
    let entries = ctx.run_all(&specs)?;
    let last = scale.progressive_passes;
    let tail = tail_of(&dec.passes, last);
    let images: Vec<Vec<_>> = tail
        .iter()
        .map(|&n| {
            entries
                .iter()
                .map(|e| e.snapshot(n))
                .collect::<Result<Vec<_>, _>>()
        })
        .collect::<Result<_, _>>()?;
    let xs: Vec<f64> = tail.iter().map(|&n| (n as f64).ln()).collect();
    let slope_of = |which: usize| {
        jackknife(runs(scale), scale.confidence, |kept| {
            let ys: Vec<f64> = images
                .iter()
                .map(|imgs| {
                    let (b2, v) = subset_bias_variance(imgs, kept, &reference);
                    let y = match which {
                        0 => v,
                        1 => b2,
                        _ => b2 + v,
                    };
                    if y > 0.0 {
                        Ok(y.ln())
                    } else {
                        Err(format!(
                            "{} ≤ 0 at some N",
                            ["variance", "bias²", "MSE"][which]
                        ))
                    }
                })
                .collect::<Result<_, String>>()?;
            lt_estimators::fit_line(&xs, &ys, 0.95).map(|f| f.slope)
        })
    };
    let scales = &entries[0].record.radius_scale;
    let r2: Vec<f64> = scales.iter().map(|s| s * s).collect();
    let (lx, ly): (Vec<f64>, Vec<f64>) = r2
        .iter()
        .enumerate()
        .filter(|(i, v)| 8 * (*i as u32 + 1) >= last && **v > 0.0)
        .map(|(i, v)| (((i + 1) as f64).ln(), v.ln()))
        .unzip();
    let r2_slope = lt_estimators::fit_line(&lx, &ly, 0.95).map_or(f64::NAN, |f| f.slope);
    // The schedule each integrator states: ppm's and sppm's global one r_N² = r_1² Π_{j<N}
    // (j + α)/(j + 1) (Knaus & Zwicker's), vcm's r_N² = r_1² N^(α−1) (Georgiev et al.'s).
    let schedule_error = r2
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let n = i as u32 + 1;
            let exact = schedule(integrator, n, alpha);
            ((v - exact) / exact).abs()
        })
        .fold(0.0, f64::max);
    Ok((
        Rates {
            integrator: integrator.into(),
            alpha,
            slopes: [slope_of(0), slope_of(1), slope_of(2)],
            r2_slope,
            schedule_error,
            passes: (1..=r2.len() as u32).collect(),
            r2,
        },
        dec,
    ))
}

pub fn run(ctx: &StudyContext) -> Result<(), String> {
    let scale = &ctx.scale;
    let scene = stem(&scale.focus_scene);
    let mut out = StudyOutput::new(
        ctx.study_dir(NAME),
        NAME,
        "Radius shrinkage: measured rates against Knaus & Zwicker's",
        scale,
    )?;
    describe(&mut out, scale, &scene);
    let mut rows = Vec::new();
    let mut r2_series = Vec::new();
    for integrator in INTEGRATORS {
        let mut decs = Vec::new();
        // ppm: the variance at fixed visible points, the one K&Z describe.
        let mut fixed_decs = Vec::new();
        for &alpha in &scale.alphas {
            let (r, dec) = rates(ctx, integrator, alpha, false)?;
            let fixed = if takes(integrator, FIXED_POINTS.0) {
                Some(rates(ctx, integrator, alpha, true)?)
            } else {
                None
            };
            let at_fixed = fixed.as_ref().map(|(f, _)| f);
            rows.extend(slope_rows(integrator, alpha, &r, &dec, at_fixed, scale));
            rows.push(radius_row(integrator, alpha, &r));
            if let Some((_, fdec)) = fixed {
                r2_series.push(radius_series(alpha, &r));
                fixed_decs.push(fdec);
            }
            decs.push(dec);
        }
        decomposition_charts(&mut out, integrator, &scene, &decs, &fixed_decs)?;
    }
    out.chart(
        "radius",
        &Chart {
            title: "(r_N / r_1)² against passes (ppm's global schedule)".into(),
            x_label: "pass N".into(),
            y_label: "(r_N / r_1)²".into(),
            log_x: true,
            log_y: true,
            series: r2_series,
        },
        "The squared radius of each pass relative to the first: slope α − 1 on log axes.",
    )?;
    out.table(
        "rates",
        "Measured against predicted slopes",
        "Slope of ln(quantity) against ln N over the tail, its jackknife interval, Knaus & \
         Zwicker's asymptotic rate, the rate their model gives at these N with the integrator's \
         own radius schedule (variance ∝ Σ 1/r_i² / N², bias ∝ Σ r_i² / N; for MSE the \
         asymptotic rule), the difference of the measured slope from the latter (± the \
         interval's half-width) and whether the interval contains it.",
        &[
            "integrator",
            "α",
            "quantity",
            "measured",
            "CI",
            "predicted",
            "predicted at these N",
            "difference",
            "inside",
        ],
        rows,
        true,
    )?;
    out.finish()
}

/// The study's opening paragraph: the predicted rates and how they are measured.
fn describe(out: &mut StudyOutput, scale: &Scale, scene: &str) {
    out.para(&format!(
        "ppm, sppm and vcm on `{scene}` ({w} px wide), {k} independent runs of {n} passes for each \
         α. With r_N² ∝ N^(α−1), Knaus & Zwicker predict variance ∝ N^(−α), bias² ∝ N^(−2(1−α)) \
         and MSE ∝ N^(−min(α, 2(1−α))) — fastest at α = 2/3 — and r² ∝ N^(α−1). Slopes are fitted \
         over the snapshots with N ≥ {tail} (the asymptotic tail), with {c} % delete-one \
         jackknife intervals over runs. sppm's variance also has a 1/N part from its new camera \
         samples each pass; it is the smaller one at large N only when α < 1. ppm's visible points \
         are drawn once per run, so its spread over runs also holds where in its pixel each point \
         fell, which no pass reduces: the rate K&Z predict is that of the variance at fixed \
         points, measured from runs that share their camera pass (`visible_seed`). ppm and sppm take \
         all light from photons here (`direct=photons`), since next-event estimation re-sampled \
         every pass adds a 1/N variance whatever α. A bias² too \
         small to tell from 0 at some N has no slope (—). The r² rows check the logged radii \
         against each integrator's schedule: ppm's and sppm's product r_N² = r_1² Π (j + α)/(j + 1), \
         whose slope over a finite tail is near, not at, α − 1, and vcm's r_N² = r_1² N^(α−1).",
        w = scale.width,
        k = runs(scale),
        n = scale.progressive_passes,
        tail = (scale.progressive_passes / 8).max(1),
        c = pct(scale.confidence)
    ));
}

/// One integrator and α: each quantity's measured slope against the asymptotic rate and the rate
/// at these N (`at_fixed`: ppm's runs sharing their visible points, whose variance K&Z describe).
fn slope_rows(
    integrator: &str,
    alpha: f64,
    r: &Rates,
    dec: &Decomposition,
    at_fixed: Option<&Rates>,
    scale: &Scale,
) -> Vec<Vec<String>> {
    let (pv, pb, pm, _) = predicted(alpha);
    let tail = tail_of(&dec.passes, scale.progressive_passes);
    let (fv, fb) = predicted_at(integrator, alpha, &tail);
    // (quantity, asymptotic rate, rate at these N, measured)
    let mut quantities = vec![
        ("variance", pv, fv, r.slopes[0].clone()),
        ("bias²", pb, fb, r.slopes[1].clone()),
        ("MSE", pm, pm, r.slopes[2].clone()),
    ];
    if let Some(f) = at_fixed {
        quantities.insert(1, ("variance at fixed points", pv, fv, f.slopes[0].clone()));
    }
    let mut rows = Vec::new();
    for (name, asymptotic, pred, slope) in &quantities {
        let (m, ci, diff, inside) = slope_cells(slope, *pred);
        rows.push(vec![
            integrator.to_string(),
            alpha_text(alpha),
            name.to_string(),
            m,
            ci,
            num(*asymptotic),
            num(*pred),
            diff,
            inside,
        ]);
    }
    rows
}

/// The radius follows the product schedule exactly; its slope over a finite tail is near α − 1,
/// not equal to it.
fn radius_row(integrator: &str, alpha: f64, r: &Rates) -> Vec<String> {
    let pr = predicted(alpha).3;
    vec![
        integrator.to_string(),
        alpha_text(alpha),
        "r²".into(),
        num(r.r2_slope),
        format!("schedule matched to {:.1e}", r.schedule_error),
        num(pr),
        "—".into(),
        num(r.r2_slope - pr),
        if r.schedule_error < SCHEDULE_TOLERANCE {
            "yes"
        } else {
            "no"
        }
        .into(),
    ]
}

/// (r_N / r_1)² against N of one α, for the radius chart.
fn radius_series(alpha: f64, r: &Rates) -> Series {
    Series {
        name: format!("α = {}", alpha_text(alpha)),
        points: r
            .passes
            .iter()
            .zip(&r.r2)
            .map(|(&n, &v)| (n as f64, v))
            .collect(),
        y_interval: Vec::new(),
        style: Style::Measured,
    }
}

/// variance, bias² and MSE against passes of one integrator, a curve per α.
fn decomposition_charts(
    out: &mut StudyOutput,
    integrator: &str,
    scene: &str,
    decs: &[Decomposition],
    fixed_decs: &[Decomposition],
) -> Result<(), String> {
    for (what, pick) in [
        (
            "variance",
            (|d: &Decomposition| d.variance.clone()) as fn(&_) -> Vec<_>,
        ),
        ("bias²", |d| d.bias2.clone()),
        ("MSE", |d| d.mse.clone()),
    ] {
        let source = if what == "variance" && !fixed_decs.is_empty() {
            fixed_decs
        } else {
            decs
        };
        let series = source
            .iter()
            .map(|d| {
                let iv = pick(d);
                Series {
                    name: d.label.clone(),
                    points: d
                        .passes
                        .iter()
                        .zip(&iv)
                        .map(|(&n, i)| (n as f64, i.estimate))
                        .collect(),
                    y_interval: iv.iter().map(|i| (i.lo, i.hi)).collect(),
                    style: Style::Measured,
                }
            })
            .collect();
        let file = match what {
            "bias²" => "bias2",
            w => w,
        }
        .to_lowercase();
        out.chart(
            &format!("{integrator}-{file}"),
            &Chart {
                title: format!("{integrator} on {scene}: {what} against passes, per α"),
                x_label: "passes".into(),
                y_label: what.into(),
                log_x: true,
                log_y: true,
                series,
            },
            &format!(
                "{integrator}: {what} of one run against passes for each α, jackknife intervals{}.",
                if what == "variance" && !fixed_decs.is_empty() {
                    " (ppm: runs sharing their visible points, the variance at fixed points)"
                } else {
                    ""
                }
            ),
        )?;
    }
    Ok(())
}

//! `lt study unbiased-vs-consistent`: bias² against N from K independent runs where the bias is
//! exact, so that "unbiased" and "biased but consistent" can be told apart by eye and by
//! interval. The scene is `point-plane-pinhole` (a diffuse plane under a point light, seen
//! through a pinhole from straight above): each pixel is a square of the plane, and its value is
//! the square's average of the exact radiance, so the reference has no noise at all. With a
//! large initial radius (r₁ = h/2) the photon estimators' bias at N = 1 is many standard errors
//! from 0; it then falls as their radius shrinks (ppm, sppm: K&Z's schedule; bpm, vcm: rᵢ =
//! r₁ i^((α−1)/2)), stays level for fixed-radius pm, and the unbiased estimators (pt, bdpt,
//! light) hold 0 inside their interval at every N. The families come from the integrator
//! registry (`IntegratorInfo::kind`, `::radius`), not from names.
//!
//! Per pixel, bias² = (mean over runs − exact)² − s²/K (unbiased for the squared bias of one
//! run), averaged over the image; intervals are delete-one jackknife over the runs, and so are
//! the log-log slopes of bias² over the tail. For ppm and sppm (global schedule) and pm the bias
//! at each N is also exact: (1/N) Σᵢ A_p(D_{rᵢ}) − A_p(L), A_p the pixel average and D_r the disc
//! average of L (`radius_plane::DiscAverage`), since a visible point is uniform in its pixel.
//!
//! The lecture's 1-D example follows, with its exact bias beside the measured one.

use super::output::{film, num, pct, StudyOutput};
use super::radius_plane::{bias2_variance, radiance, DiscAverage};
use super::{Scale, StudyContext};
use crate::plot::{Chart, Series, Style};
use crate::runs::RunSpec;
use lt_estimators::{jackknife, ImageBiasVariance, Interval, Jackknifed};
use lt_integrators::registry::{find, Radius};
use lt_integrators::Kind;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

pub const NAME: &str = "unbiased-vs-consistent";

/// The scene's file name, next to the shipped scenes.
pub const SCENE: &str = "point-plane-pinhole.toml";
/// Initial (and pm's fixed) radius: h/2, so the bias at N = 1 is ~15 % of L at the centre.
pub const R1: f64 = 0.5;
/// Radius reduction of every progressive estimator here: K&Z's best, bias² ∝ N^(−2/3).
pub const ALPHA: f64 = 2.0 / 3.0;

/// (label, integrator, extra parameters). `plane_specs` adds the radius, α, the photon count and
/// `direct = photons` (density estimation's bias alone) where the registry says they apply.
type Config = (
    &'static str,
    &'static str,
    &'static [(&'static str, &'static str)],
);
pub const CONFIGS: [Config; 8] = [
    ("pt", "pt", &[]),
    ("bdpt", "bdpt", &[]),
    ("light", "light", &[]),
    ("pm (fixed radius)", "pm", &[]),
    ("ppm", "ppm", &[]),
    ("sppm", "sppm", &[]),
    ("bpm", "bpm", &[]),
    ("vcm", "vcm", &[]),
];

/// (runs, passes, photon or light paths per pass) at a scale: the quick one runs in seconds.
pub fn uc_scale(scale: &Scale) -> (usize, u32, u64) {
    match scale.name {
        "full" => (32, 256, 2000),
        "test" => (16, 16, 1000),
        _ => (8, 16, 500),
    }
}

pub fn scene(scale: &Scale) -> PathBuf {
    scale
        .focus_scene
        .parent()
        .map(|d| d.join(SCENE))
        .unwrap_or_else(|| Path::new("scenes").join(SCENE))
}

/// The K runs of one configuration on the pinhole plane. Parameters follow what the registry
/// says the integrator takes: a radius where it has one, α where it shrinks, its own name for
/// the photon count.
pub fn plane_specs(scale: &Scale, integrator: &str, params: &[(&str, &str)]) -> Vec<RunSpec> {
    let (runs, passes, photons) = uc_scale(scale);
    let info = find(integrator).ok();
    (0..runs)
        .map(|r| {
            let mut s = RunSpec::new(scene(scale), integrator, 1 + r as u64, passes)
                .snapshots(Scale::doublings(passes));
            for (k, v) in params {
                s = s.param(k, v);
            }
            if let Some(info) = info {
                if info.radius != Radius::None {
                    s = s.param("radius", R1);
                }
                // All light from photons, where the integrator offers the choice.
                if info.radius != Radius::None && info.takes("direct") {
                    s = s.param("direct", "photons");
                }
                if info.takes("alpha") {
                    s = s.param("alpha", ALPHA);
                }
                for key in ["photons", "photons_per_pass", "light_paths"] {
                    if info.takes(key) {
                        s = s.param(key, photons);
                    }
                }
            }
            s
        })
        .collect()
}

pub fn specs(scale: &Scale) -> Vec<RunSpec> {
    CONFIGS
        .iter()
        .flat_map(|(_, i, p)| plane_specs(scale, i, p))
        .collect()
}

/// Runs per configuration of the sun-room decomposition `radius_shrinkage` still uses.
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

/// bias², variance and MSE at each snapshot.
pub struct Decomposition {
    pub label: String,
    pub passes: Vec<u32>,
    pub bias2: Vec<Interval>,
    pub variance: Vec<Interval>,
    pub mse: Vec<Interval>,
}

pub fn decompose(
    ctx: &StudyContext,
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

/// The estimator families the plots are drawn by, from the registry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    Unbiased,
    FixedRadius,
    Consistent,
}

impl Family {
    pub fn of(integrator: &str) -> Result<Family, String> {
        let info = find(integrator)?;
        Ok(match (info.kind, info.radius) {
            (Kind::Unbiased, _) | (_, Radius::None) => Family::Unbiased,
            (_, Radius::Fixed) => Family::FixedRadius,
            _ => Family::Consistent,
        })
    }

    pub fn text(self) -> &'static str {
        match self {
            Family::Unbiased => "unbiased",
            Family::FixedRadius => "fixed radius",
            Family::Consistent => "consistent",
        }
    }
}

/// The exact pixel values: the average of L over each pixel's square of the plane (the camera
/// sees [−1, 1]² from straight above; L is symmetric in x, y and their swap, so the image's
/// orientation does not matter). `disc`: the average of the disc average D_r instead.
fn pixel_averages(width: usize, radius: Option<f64>, q: &DiscAverage) -> Vec<f64> {
    let gl: Vec<(f64, f64)> = {
        let (x, w) = lt_core::bsdf::quadrature::gauss_legendre(4);
        x.iter()
            .zip(&w)
            .map(|(x, w)| (0.5 * (x + 1.0), 0.5 * w))
            .collect()
    };
    let step = 2.0 / width as f64;
    (0..width * width)
        .into_par_iter()
        .map(|j| {
            let (x0, y0) = (
                -1.0 + (j % width) as f64 * step,
                -1.0 + (j / width) as f64 * step,
            );
            let mut s = 0.0;
            for &(u, wu) in &gl {
                for &(v, wv) in &gl {
                    let (x, y) = (x0 + u * step, y0 + v * step);
                    s += wu
                        * wv
                        * match radius {
                            None => radiance(x, y),
                            Some(r) => q.at(x, y, r),
                        };
                }
            }
            s
        })
        .collect()
}

/// One estimator's measurement.
pub struct Measured {
    pub label: &'static str,
    pub integrator: &'static str,
    pub family: Family,
    pub passes: Vec<u32>,
    /// bias² at the family-wise (Bonferroni) level, and variance at the plain one.
    pub bias2: Vec<Jackknifed>,
    pub variance: Vec<Jackknifed>,
    pub mse: Vec<Jackknifed>,
    /// MSE slope over the tail with its prediction (−1 unbiased, −min(α, 2(1−α)) consistent, 0
    /// for a fixed radius).
    pub mse_slope: (Result<Jackknifed, String>, f64),
    /// The exact bias² at each snapshot where the radius schedule is deterministic.
    pub exact_bias2: Option<Vec<f64>>,
    /// bias² slope over the tail (shrinking radii only), and its prediction: the exact model's
    /// slope at these N where there is one, else −2(1 − α).
    pub slope: Option<(Result<Jackknifed, String>, f64, f64)>,
    pub tail: Vec<u32>,
    pub seconds: f64,
}

#[allow(clippy::too_many_arguments)]
fn measure(
    ctx: &StudyContext,
    label: &'static str,
    integrator: &'static str,
    params: &[(&str, &str)],
    exact: &[f64],
    exact_d: &dyn Fn(Radius, u32) -> Option<Vec<Vec<f64>>>,
    strict: f64,
) -> Result<Measured, String> {
    let scale = &ctx.scale;
    let specs = plane_specs(scale, integrator, params);
    let entries = ctx.run_all(&specs)?;
    let snaps = specs[0].snapshots.clone();
    let family = Family::of(integrator)?;
    let radius = find(integrator)?.radius;
    let values: Vec<Vec<Vec<f64>>> = snaps
        .iter()
        .map(|&n| {
            entries
                .iter()
                .map(|e| Ok(e.snapshot(n)?.data.iter().map(|p| p[0]).collect()))
                .collect::<Result<_, String>>()
        })
        .collect::<Result<_, String>>()?;
    let runs = entries.len();
    let mut bias2 = Vec::new();
    let mut variance = Vec::new();
    let mut mse = Vec::new();
    for vals in &values {
        mse.push(jackknife(runs, scale.confidence, |kept| {
            let (b, v) = bias2_variance(vals, kept, exact);
            Ok(b + v)
        })?);
        bias2.push(jackknife(runs, strict, |kept| {
            Ok(bias2_variance(vals, kept, exact).0)
        })?);
        variance.push(jackknife(runs, scale.confidence, |kept| {
            Ok(bias2_variance(vals, kept, exact).1)
        })?);
    }
    let last = *snaps.last().unwrap_or(&1);
    // The exact bias² per snapshot: mean over pixels of ((1/N) Σᵢ A_p(D_{rᵢ}) − A_p(L))².
    let exact_bias2 = exact_d(radius, last).map(|per_pass| {
        let np = exact.len() as f64;
        snaps
            .iter()
            .map(|&n| {
                (0..exact.len())
                    .map(|p| {
                        let m = per_pass[..n as usize].iter().map(|d| d[p]).sum::<f64>() / n as f64;
                        (m - exact[p]).powi(2)
                    })
                    .sum::<f64>()
                    / np
            })
            .collect::<Vec<f64>>()
    });
    let tail_idx: Vec<usize> = (0..snaps.len()).filter(|&k| 8 * snaps[k] >= last).collect();
    let xs: Vec<f64> = tail_idx.iter().map(|&k| (snaps[k] as f64).ln()).collect();
    let slope = (family == Family::Consistent).then(|| {
        let measured = jackknife(runs, scale.confidence, |kept| {
            let ys: Vec<f64> = tail_idx
                .iter()
                .map(|&k| bias2_variance(&values[k], kept, exact).0)
                .collect();
            if let Some(y) = ys.iter().find(|y| !(**y > 0.0)) {
                return Err(format!("bias² {y:.3e} ≤ 0 in the tail"));
            }
            let ly: Vec<f64> = ys.iter().map(|y| y.ln()).collect();
            lt_estimators::fit_line(&xs, &ly, 0.95).map(|f| f.slope)
        });
        let asymptotic = -2.0 * (1.0 - ALPHA);
        let at_n = exact_bias2
            .as_ref()
            .and_then(|e| {
                let ly: Vec<f64> = tail_idx.iter().map(|&k| e[k].ln()).collect();
                lt_estimators::fit_line(&xs, &ly, 0.95).ok()
            })
            .map_or(f64::NAN, |f| f.slope);
        (measured, asymptotic, at_n)
    });
    let mse_slope = (
        jackknife(runs, scale.confidence, |kept| {
            let ly: Vec<f64> = tail_idx
                .iter()
                .map(|&k| {
                    let (b, v) = bias2_variance(&values[k], kept, exact);
                    (b + v).max(f64::MIN_POSITIVE).ln()
                })
                .collect();
            lt_estimators::fit_line(&xs, &ly, 0.95).map(|f| f.slope)
        }),
        match family {
            Family::Unbiased => -1.0,
            Family::FixedRadius => 0.0,
            Family::Consistent => -ALPHA.min(2.0 * (1.0 - ALPHA)),
        },
    );
    Ok(Measured {
        mse,
        mse_slope,
        label,
        integrator,
        family,
        tail: tail_idx.iter().map(|&k| snaps[k]).collect(),
        passes: snaps,
        bias2,
        variance,
        exact_bias2,
        slope,
        seconds: entries
            .iter()
            .filter_map(|e| e.record.seconds.last().copied())
            .sum(),
    })
}

fn yes_no(b: bool) -> String {
    if b { "yes" } else { "no" }.into()
}

fn iv(j: &Jackknifed) -> String {
    format!(
        "{} [{}, {}]",
        num(j.estimate),
        num(j.interval.lo),
        num(j.interval.hi)
    )
}

pub fn run(ctx: &StudyContext) -> Result<(), String> {
    let scale = &ctx.scale;
    let setup = Setup::of(scale)?;
    let ms = measure_all(ctx, &setup)?;
    let mut out = StudyOutput::new(
        ctx.study_dir(NAME),
        NAME,
        "Unbiased against consistent: bias² against N with an exact reference",
        scale,
    )?;
    describe(&mut out, &setup, &ms, scale);
    claims_table(&mut out, &ms)?;
    rates_table(&mut out, &ms)?;
    ppm_floor(&mut out, &ms, &setup);
    bias_variance_table(&mut out, &ms)?;
    bias_charts(&mut out, &ms)?;
    mse_and_variance_charts(&mut out, &ms)?;
    super::lecture::write(&mut out, scale)?;
    out.finish()
}

/// The study's size at a scale and its family-wise level.
struct Setup {
    /// Runs per configuration, passes per run, photon or light paths per pass.
    runs: usize,
    passes: u32,
    photons: u64,
    /// The film's side in pixels (the scene's own).
    width: usize,
    /// The "contains 0" and "excludes 0" claims (configs × snapshots) and the Bonferroni level
    /// each is made at.
    claims: usize,
    strict: f64,
}

impl Setup {
    fn of(scale: &Scale) -> Result<Setup, String> {
        let (runs, passes, photons) = uc_scale(scale);
        let width = lt_scene_io::load_scene(&scene(scale))
            .map_err(|e| e.to_string())?
            .camera
            .width as usize;
        // Every "contains 0" and "excludes 0" claim is one of configs × snapshots: Bonferroni.
        let claims = CONFIGS.len() * Scale::doublings(passes).len();
        let strict = 1.0 - (1.0 - scale.confidence) / claims as f64;
        Ok(Setup {
            runs,
            passes,
            photons,
            width,
            claims,
            strict,
        })
    }
}

/// Every configuration measured against the exact pixel values and, where the radius schedule is
/// deterministic, the exact bias.
fn measure_all(ctx: &StudyContext, setup: &Setup) -> Result<Vec<Measured>, String> {
    let (width, passes) = (setup.width, setup.passes);
    let q = DiscAverage::new(16, 32);
    let exact = pixel_averages(width, None, &q);
    // A_p(D_{rᵢ}) for every pass of a deterministic schedule (ppm and sppm share K&Z's; pm's is
    // one radius). bpm and vcm merge under MIS: no exact model here.
    let kz: Vec<Vec<f64>> = (1..=passes)
        .map(|i| {
            let r2 = R1 * R1 * lt_integrators::radius::global_scale2(i, ALPHA);
            pixel_averages(width, Some(r2.sqrt()), &q)
        })
        .collect();
    let fixed = pixel_averages(width, Some(R1), &q);
    let exact_d = |radius: Radius, last: u32| match radius {
        Radius::KnausZwicker => Some(kz[..last as usize].to_vec()),
        Radius::Fixed => Some(vec![fixed.clone(); last as usize]),
        _ => None,
    };
    CONFIGS
        .iter()
        .map(|(l, i, p)| measure(ctx, l, i, p, &exact, &exact_d, setup.strict))
        .collect()
}

/// The study's opening paragraph: what was run and how it is judged.
fn describe(out: &mut StudyOutput, setup: &Setup, ms: &[Measured], scale: &Scale) {
    let Setup {
        runs: k,
        passes,
        photons,
        width,
        claims,
        strict,
    } = *setup;
    let seconds: f64 = ms.iter().map(|m| m.seconds).sum();
    out.para(&format!(
        "{k} independent runs of each estimator on `point-plane-pinhole` ({width}×{width} px: a \
         diffuse plane under a point light seen from straight above; each pixel's exact value is \
         the average of L = 0.5 / (1 + |x|²)^(3/2) over its square, by quadrature — the reference \
         has no noise), snapshots at 1, 2, 4, … {passes} passes of {photons} photon or light \
         paths. The photon estimators start at radius r₁ = {R1} (h/2) and take all light from \
         photons; ppm, sppm, bpm and vcm shrink it with α = 2/3 (bias² ∝ N^(−2/3)), pm keeps it. \
         Families from the integrator registry (kind, radius). Per pixel, bias² = (mean of the \
         runs − exact)² − s²/K, averaged over the image; variance = mean per-pixel variance of \
         one run. bias² intervals are delete-one jackknife over the runs at {st} % each \
         (Bonferroni over the {claims} estimator × N claims, 95 % in all), so \"contains 0 at \
         every N\" is one claim at 95 %; slopes are fitted over N ∈ {{{tail}}} with {c} % \
         jackknife intervals. Render time: {seconds:.0} s as recorded.",
        st = num(strict * 100.0),
        c = pct(scale.confidence),
        tail = ms[0]
            .tail
            .iter()
            .map(|n| n.to_string())
            .collect::<Vec<_>>()
            .join(", "),
    ));
}

/// The claims, one row each: what tests/studies.rs holds the committed CSV to.
fn claims_table(out: &mut StudyOutput, ms: &[Measured]) -> Result<(), String> {
    let mut rows = Vec::new();
    for m in ms {
        let first = &m.bias2[0];
        let lastb = m.bias2.last().unwrap();
        let zero_inside = m.bias2.iter().filter(|j| j.interval.contains(0.0)).count();
        let (claim, holds) = match m.family {
            Family::Unbiased => (
                format!(
                    "bias² contains 0 at every N ({zero_inside} of {})",
                    m.bias2.len()
                ),
                zero_inside == m.bias2.len(),
            ),
            Family::FixedRadius => (
                "bias² excludes 0 at N = 1 and at the largest N".into(),
                first.interval.lo > 0.0 && lastb.interval.lo > 0.0,
            ),
            Family::Consistent => ("bias² excludes 0 at N = 1".into(), first.interval.lo > 0.0),
        };
        rows.push(vec![
            m.label.into(),
            m.family.text().into(),
            claim,
            iv(first),
            iv(lastb),
            yes_no(holds),
        ]);
    }
    out.table(
        "claims",
        "What each estimator's bias² shows",
        "The claim per family, bias² at N = 1 and at the largest N with their family-wise \
         intervals, and whether the claim holds.",
        &[
            "estimator",
            "family",
            "claim",
            "bias² at N = 1",
            "bias² at largest N",
            "holds",
        ],
        rows,
        true,
    )
}

/// The slopes of the shrinking estimators, in the rates format the claims test reads.
fn rates_table(out: &mut StudyOutput, ms: &[Measured]) -> Result<(), String> {
    let mut srows = Vec::new();
    for m in ms {
        let (measured, predicted) = &m.mse_slope;
        let (meas, ci, inside) = match measured {
            Ok(j) => (
                num(j.estimate),
                format!("[{}, {}]", num(j.interval.lo), num(j.interval.hi)),
                yes_no(j.interval.contains(*predicted)),
            ),
            Err(e) => ("—".into(), e.clone(), "—".into()),
        };
        srows.push(vec![
            m.label.into(),
            if m.family == Family::Consistent {
                "2/3".into()
            } else {
                "—".into()
            },
            "MSE".into(),
            meas,
            ci,
            num(*predicted),
            "—".into(),
            inside.clone(),
            inside,
        ]);
    }
    for m in ms {
        let Some((measured, asymptotic, at_n)) = &m.slope else {
            continue;
        };
        let against = if at_n.is_finite() { *at_n } else { *asymptotic };
        let (meas, ci, inside, asym) = match measured {
            Ok(j) => (
                num(j.estimate),
                format!("[{}, {}]", num(j.interval.lo), num(j.interval.hi)),
                yes_no(j.interval.contains(against)),
                yes_no(j.interval.contains(*asymptotic)),
            ),
            Err(e) => ("—".into(), e.clone(), "—".into(), "—".into()),
        };
        srows.push(vec![
            m.label.into(),
            "2/3".into(),
            "bias²".into(),
            meas,
            ci,
            num(*asymptotic),
            num(*at_n),
            inside,
            asym,
        ]);
    }
    out.table(
        "rates",
        "MSE and bias² slopes",
        "Slope of ln MSE (every estimator) and ln bias² (the consistent ones) against ln N over \
         the tail with its jackknife interval; the asymptotic rate (MSE: −1 unbiased, \
         −min(α, 2(1−α)) = −2/3 consistent, 0 for a fixed radius; bias²: −2(1 − α)); the exact model's slope at these N (ppm, sppm: K&Z's schedule; — for bpm and \
         vcm, whose merging is MIS-weighted); whether the interval holds the latter (else the \
         asymptotic one), and the asymptotic one.",
        &[
            "integrator",
            "α",
            "quantity",
            "measured",
            "CI",
            "predicted",
            "predicted at these N",
            "inside",
            "inside asymptotic",
        ],
        srows,
        true,
    )
}

/// ppm's one camera pass per run: its pixel converges to L at one random point of the pixel,
/// so over runs its variance keeps the pixel variance of L, which no pass lowers.
fn ppm_floor(out: &mut StudyOutput, ms: &[Measured], setup: &Setup) {
    let sigma2 = super::radius_plane::camera_variance(setup.width);
    if let Some(ppm) = ms
        .iter()
        .find(|m| find(m.integrator).is_ok_and(|i| i.takes("visible_seed")))
    {
        out.para(&format!(
            "**Why ppm's MSE levels off.** ppm traces its visible points once per run, so each \
             pixel converges to L at one random point of the pixel, not to the pixel's average: \
             over runs its variance keeps the pixel variance of L, σ²_pixel = {} (quadrature), \
             which no pass lowers — ppm's variance at N = {} is {}. Its bias² still falls at the \
             predicted rate (the table); sppm, drawing new points every pass, does not have the \
             floor.",
            num(sigma2),
            setup.passes,
            iv(ppm.variance.last().unwrap()),
        ));
    }
}

/// bias², variance and MSE of every estimator at every N, for the claims test and by hand.
fn bias_variance_table(out: &mut StudyOutput, ms: &[Measured]) -> Result<(), String> {
    let mut rows = Vec::new();
    for m in ms {
        for (j, &p) in m.passes.iter().enumerate() {
            let (b, v) = (&m.bias2[j], &m.variance[j]);
            rows.push(vec![
                m.label.to_string(),
                m.family.text().into(),
                p.to_string(),
                format!("{:.6e}", b.estimate),
                format!("{:.6e}", b.interval.lo),
                format!("{:.6e}", b.interval.hi),
                m.exact_bias2
                    .as_ref()
                    .map_or("—".into(), |e| format!("{:.6e}", e[j])),
                format!("{:.6e}", v.estimate),
                format!("{:.6e}", v.interval.lo),
                format!("{:.6e}", v.interval.hi),
                format!("{:.6e}", m.mse[j].estimate),
                format!("{:.6e}", m.mse[j].interval.lo),
                format!("{:.6e}", m.mse[j].interval.hi),
            ]);
        }
    }
    out.table(
        "bias-variance",
        "bias² and variance at every N",
        "bias² with its family-wise interval and the exact value where the schedule gives one; \
         variance with its 95 % interval.",
        &[
            "estimator",
            "family",
            "passes",
            "bias2",
            "bias2_lo",
            "bias2_hi",
            "exact_bias2",
            "variance",
            "variance_lo",
            "variance_hi",
            "mse",
            "mse_lo",
            "mse_hi",
        ],
        rows,
        false,
    )
}

/// One chart of bias² against N per family, with the exact bias² where there is one.
fn bias_charts(out: &mut StudyOutput, ms: &[Measured]) -> Result<(), String> {
    let measured = |m: &Measured| Series {
        name: m.label.into(),
        points: m
            .passes
            .iter()
            .zip(&m.bias2)
            .map(|(&n, j)| (n as f64, j.estimate))
            .collect(),
        y_interval: m
            .bias2
            .iter()
            .map(|j| (j.interval.lo, j.interval.hi))
            .collect(),
        style: Style::Measured,
    };
    let exact_series = |m: &Measured| {
        m.exact_bias2.as_ref().map(|e| Series {
            name: format!("{}: exact", m.label),
            points: m
                .passes
                .iter()
                .zip(e)
                .map(|(&n, &b)| (n as f64, b))
                .collect(),
            y_interval: Vec::new(),
            style: Style::Fitted,
        })
    };
    for (family, file, log_y, caption) in [
        (
            Family::Unbiased,
            "bias2-unbiased",
            false,
            "Unbiased estimators: bias² against N on a linear axis with family-wise intervals; \
             every interval holds 0.",
        ),
        (
            Family::Consistent,
            "bias2-consistent",
            true,
            "Consistent estimators: bias² against N (log-log) with family-wise intervals, \
             dashed the exact bias² of K&Z's schedule (ppm, sppm); every point at N = 1 excludes \
             0, and the tail falls along N^(−2/3).",
        ),
        (
            Family::FixedRadius,
            "bias2-fixed",
            true,
            "Fixed-radius photon mapping: bias² stays at its exact value (dashed) whatever N.",
        ),
    ] {
        let mut series = Vec::new();
        for m in ms.iter().filter(|m| m.family == family) {
            series.push(measured(m));
            series.extend(exact_series(m));
        }
        out.chart(
            file,
            &Chart {
                title: format!(
                    "point-plane-pinhole: bias² of the {} estimators",
                    family.text()
                ),
                x_label: "passes N".into(),
                y_label: "bias²".into(),
                log_x: true,
                log_y,
                series,
            },
            caption,
        )?;
    }
    Ok(())
}

/// MSE and variance of one run against N, every estimator on one chart each.
fn mse_and_variance_charts(out: &mut StudyOutput, ms: &[Measured]) -> Result<(), String> {
    out.chart(
        "mse",
        &Chart {
            title: "point-plane-pinhole: MSE against passes".into(),
            x_label: "passes N".into(),
            y_label: "MSE".into(),
            log_x: true,
            log_y: true,
            series: ms
                .iter()
                .map(|m| Series {
                    name: match &m.mse_slope.0 {
                        Ok(j) => format!("{} (slope {})", m.label, num(j.estimate)),
                        Err(_) => m.label.into(),
                    },
                    points: m
                        .passes
                        .iter()
                        .zip(&m.mse)
                        .map(|(&n, j)| (n as f64, j.estimate))
                        .collect(),
                    y_interval: m
                        .mse
                        .iter()
                        .map(|j| (j.interval.lo, j.interval.hi))
                        .collect(),
                    style: Style::Measured,
                })
                .collect(),
        },
        "MSE of one run against passes: the unbiased estimators fall as 1/N, the consistent ones \
         as N^(−2/3) (α = 2/3), fixed-radius pm levels off at its bias².",
    )?;
    out.chart(
        "variance",
        &Chart {
            title: "point-plane-pinhole: variance against passes".into(),
            x_label: "passes N".into(),
            y_label: "variance".into(),
            log_x: true,
            log_y: true,
            series: ms
                .iter()
                .map(|m| Series {
                    name: m.label.into(),
                    points: m
                        .passes
                        .iter()
                        .zip(&m.variance)
                        .map(|(&n, j)| (n as f64, j.estimate))
                        .collect(),
                    y_interval: m
                        .variance
                        .iter()
                        .map(|j| (j.interval.lo, j.interval.hi))
                        .collect(),
                    style: Style::Measured,
                })
                .collect(),
        },
        "Variance of one run against passes.",
    )
}

//! Consistency of the progressive photon mappers (`ppm`, `sppm`) on `cornell-box`, from K
//! independent runs — never from the spread of one run's passes.
//!
//! - **Bias shrinks** from 8 to 64 to 128 passes (to 256 before: z 5.3–9.1 at 128 against 3.48). Per 8×8 block and channel, relative to a long
//!   `pt` reference r: S(N) = Σ [(x̄_b(N) − r_b)² − s²_b(N)/K] / r_b² − Σ se²_ref,b / r_b², the
//!   unbiased estimate of Σ bias²/r² (the run mean's variance s²/K and the reference's own
//!   variance are both subtracted, so neither noise floors it). The reference term is the same at
//!   every N, so the decrease Δ = S(N₁) − S(N₂) does not contain it; Δ's standard error is a
//!   delete-one jackknife over runs (the same runs give every N, so S(N₁) and S(N₂) are
//!   correlated) plus the reference's cross term 4 Σ (d₁ − d₂)² se²_ref / r⁴.
//!   The initial radius is 8 pixel footprints so that the bias at 8 passes stands well above the
//!   noise of K runs; at the default 2 the bias after 64 passes is already near this test's noise.
//! - **Variance falls as N^−α.** The median over pixels of the variance across runs (no
//!   reference involved) against N on log-log axes has a slope within its confidence interval of
//!   −α, for α = 2/3 and α = 0.4 (so the test tells the rates apart). With `direct = photons`
//!   all the variance is the photons' (next-event estimation would add a 1/N part); the median
//!   pixel lies in a smooth region. N from 32 on: the printed slopes of successive octaves show
//!   the rate is asymptotic there. The interval is a delete-one jackknife over runs.
//!   `ppm`'s visible points are fixed per run, so the variance of where in its pixel each one
//!   fell never decays: its variance across runs has a floor, which the test shows instead
//!   (that floor is what `sppm` removes).

use lt_core::Scene;
use lt_estimators::agreement::sidak_threshold;
use lt_estimators::bias_variance::t_quantile;
use lt_estimators::blocks::{block_means, BlockEstimate};
use lt_estimators::fit::fit_log_log;
use lt_estimators::running::RunningStat;
use lt_estimators::Image;
use lt_integrators::IntegratorParams;
use lt_tests::{
    bias2_decrease, bias2_without_reference, inverse_variance_weights, reference_noise,
    render_blocks, shipped_scene,
};

const BLOCK: usize = 8;
const RUNS: u64 = 16;

fn scene() -> Scene {
    shipped_scene("cornell-box", Some((32, 32)))
}

/// `RUNS` independent runs on `scene()`, each run's estimate kept after every pass count in
/// `checkpoints`: result[c][k] is run k at checkpoint c.
fn runs_at(
    integrator: &str,
    params: &IntegratorParams,
    checkpoints: &[u32],
    seed: u64,
) -> Vec<Vec<Image>> {
    lt_tests::runs_at(&scene(), integrator, params, checkpoints, RUNS, seed)
}

/// Pass counts at which `sppm_photon_runs` keeps its runs' estimates. To 256, not 512 as before:
/// half the cost; the variance slopes (fitted from 64) still tell α = 2/3 from 0.4 (rates 0.27
/// apart) by several of their jackknife errors.
const SPPM_PASSES: [u32; 4] = [32, 64, 128, 256];

/// `RUNS` runs of sppm with `direct = photons` and radius exponent `alpha`, kept at
/// `SPPM_PASSES`: made once per test binary and shared by the variance-rate test and, at
/// α = 2/3, the ppm floor test (both read only variances across runs; 16 × 512 passes saved).
fn sppm_photon_runs(alpha: f64, seed: u64) -> std::sync::Arc<Vec<Vec<Image>>> {
    lt_tests::shared(
        &format!("consistency sppm direct=photons α={alpha} seed {seed}"),
        || {
            let params = IntegratorParams::new()
                .with("direct", "photons")
                .with("alpha", alpha);
            runs_at("sppm", &params, &SPPM_PASSES, seed)
        },
    )
}

/// The long unbiased reference, per block.
fn reference() -> BlockEstimate {
    let (_, blocks) = render_blocks(&scene(), "pt", IntegratorParams::default(), 4096, 1, BLOCK);
    blocks.estimate()
}

#[test]
fn bias_of_progressive_photon_mapping_shrinks_with_passes() {
    let reference = reference();
    let checkpoints = [8, 64, 128];
    // 2 integrators × 2 steps, one-sided.
    let z = sidak_threshold(2e-3, 4);
    let mut failures = Vec::new();
    for (integrator, seed) in [("sppm", 1000), ("ppm", 2000)] {
        let params = IntegratorParams::new().with("radius_px", 8);
        let runs = runs_at(integrator, &params, &checkpoints, seed);
        let blocks: Vec<Vec<Image>> = runs
            .iter()
            .map(|rs| rs.iter().map(|r| block_means(r, BLOCK)).collect())
            .collect();
        let w = inverse_variance_weights(blocks.last().unwrap(), &reference);
        let noise = reference_noise(&reference, &w);
        let s: Vec<f64> = blocks
            .iter()
            .map(|b| bias2_without_reference(b, &reference, &w, |_| true) - noise)
            .collect();
        let shown: Vec<String> = s.iter().map(|x| format!("{x:.4e}")).collect();
        println!(
            "{integrator}: Σ w bias² at N = {checkpoints:?}: {} (reference noise {noise:.2e} subtracted)",
            shown.join(", ")
        );
        for step in 0..2 {
            let (d, se) = bias2_decrease(&blocks[step], &blocks[step + 1], &reference, &w);
            let line = format!(
                "{integrator}: S({}) − S({}) = {d:.4e} ± {se:.2e} (z {:.1}, needs > {z:.2})",
                checkpoints[step],
                checkpoints[step + 1],
                d / se
            );
            println!("{line}");
            if !(d > z * se) {
                failures.push(line);
            }
        }
    }
    assert!(
        failures.is_empty(),
        "bias did not shrink:\n{}",
        failures.join("\n")
    );
}

/// Median over pixels (green) of the across-run variance, over the runs `keep` selects.
fn median_variance(runs: &[Image], keep: impl Fn(usize) -> bool) -> f64 {
    let px = runs[0].data.len();
    let mut v: Vec<f64> = (0..px)
        .map(|p| {
            RunningStat::from_slice(
                &runs
                    .iter()
                    .enumerate()
                    .filter(|(k, _)| keep(*k))
                    .map(|(_, r)| r.data[p][1])
                    .collect::<Vec<_>>(),
            )
            .sample_variance()
        })
        .collect();
    v.sort_by(f64::total_cmp);
    v[px / 2]
}

/// The log-log slope of median variance against N, over the runs `keep` selects.
fn variance_slope(runs: &[Vec<Image>], ns: &[u32], keep: impl Fn(usize) -> bool + Copy) -> f64 {
    let xs: Vec<f64> = ns.iter().map(|&n| n as f64).collect();
    let ys: Vec<f64> = runs.iter().map(|r| median_variance(r, keep)).collect();
    fit_log_log(&xs, &ys, 0.95).unwrap().slope
}

#[test]
fn variance_of_sppm_falls_as_n_to_the_minus_alpha() {
    // The fit starts at 64: at α = 0.4 the octave 32 → 64 is still pre-asymptotic (−0.51 against
    // −0.47 and −0.45 after it), so a fit from 32 leans on it (−0.473 ± 0.027, z −2.7).
    let ns = &SPPM_PASSES[1..];
    let z = sidak_threshold(1e-3, 2);
    let mut failures = Vec::new();
    for (alpha, seed) in [(2.0 / 3.0, 3000), (0.4, 4000)] {
        let all_runs = sppm_photon_runs(alpha, seed);
        let runs = &all_runs[1..];
        let k = runs[0].len();
        let slope = variance_slope(&runs, &ns, |_| true);
        let loo: Vec<f64> = (0..k)
            .map(|j| variance_slope(&runs, &ns, |i| i != j))
            .collect();
        let mean = loo.iter().sum::<f64>() / k as f64;
        let se = ((k as f64 - 1.0) / k as f64
            * loo.iter().map(|x| (x - mean).powi(2)).sum::<f64>())
        .sqrt();
        let vars: Vec<f64> = runs.iter().map(|r| median_variance(r, |_| true)).collect();
        let octaves: Vec<String> = vars
            .windows(2)
            .map(|w| format!("{:.3}", (w[1] / w[0]).log2()))
            .collect();
        let t = t_quantile(0.95, (k - 1) as f64);
        let line = format!(
            "sppm α = {alpha:.3}: slope {slope:.3} ± {se:.3} (95 % ±{:.3}), −α = {:.3}, z {:.2} (bound {z:.2}); per octave {}",
            t * se,
            -alpha,
            (slope + alpha) / se,
            octaves.join(" ")
        );
        println!("{line}");
        if !((slope + alpha).abs() < z * se) {
            failures.push(line);
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn ppm_variance_has_the_floor_of_its_fixed_visible_points() {
    // sppm and ppm with the same settings: after 256 passes ppm's variance across runs still
    // holds the spread of where its one visible point per pixel fell, which sppm averages away.
    // sppm's runs are the variance test's at α = 2/3 (sppm's default), taken at 32 and 256.
    let ns = [32, 256];
    let params = IntegratorParams::new().with("direct", "photons");
    let ppm = runs_at("ppm", &params, &ns, 5000);
    let sppm = sppm_photon_runs(2.0 / 3.0, 3000);
    let at = |n: u32| SPPM_PASSES.iter().position(|&m| m == n).unwrap();
    let sppm = [sppm[at(ns[0])].clone(), sppm[at(ns[1])].clone()];
    let decay =
        |r: &[Vec<Image>]| median_variance(&r[0], |_| true) / median_variance(&r[1], |_| true);
    let (dp, ds) = (decay(&ppm), decay(&sppm));
    println!("median variance falls from 32 to 256 passes by ×{dp:.2} (ppm) and ×{ds:.2} (sppm); 8^α = {:.2}", 8f64.powf(2.0 / 3.0));
    // With K = 16 runs ln s² has spread ≈ sqrt(2/15) ≈ 0.37 per point, so a ratio of two
    // medians is known to well within a factor 1.5; the floor makes ppm's far smaller.
    assert!(
        dp < ds / 1.5,
        "ppm's variance fell as fast as sppm's (×{dp:.2} vs ×{ds:.2})"
    );
}

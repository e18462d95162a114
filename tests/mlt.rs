//! Metropolis light transport (`pssmlt`, `mmlt`) against bdpt, and the honesty of its error bars.
//!
//! 1. **Agreement.** On shipped scenes with an area light, a point light behind a specular ball
//!    (caustics: specular chains and a delta light), `pssmlt` over
//!    bdpt, `pssmlt` over pt and `mmlt` agree with bdpt per 8×8 block: `CONSISTENT_RUNS`
//!    independent runs of each Metropolis estimator (each with its own bootstrap, so the
//!    normalisation's error is inside the spread) against bdpt's passes, Student-t and Šidák over
//!    every block × channel × comparison (`agreement_t`).
//! 2. **Chain starts.** MMLT's chains start at bootstrap points resampled ∝ the picked
//!    strategy's I_k, which draws from a chain's target only if the chain, evaluating its one
//!    strategy alone, gets that same I_k at the point: checked bit for bit per point and length.
//! 3. **Coverage.** A Markov chain's passes are correlated, so the spread of passes understates
//!    a run's error; independent runs do not. On a tiny film, per (pixel, run): the interval of
//!    run r from its own passes (t quantile, P − 1 degrees of freedom) and from the other runs'
//!    spread (leave-one-out, t with R − 2), each widened by bdpt's reference error, against bdpt's
//!    reference. The per-run coverage fractions are independent across runs, so their mean has a
//!    standard error: the independent-run coverage must be within z of its nominal 95 %, and the
//!    per-pass coverage z below it. The gap is the chain's correlation: each run's batch-means
//!    ESS (its record's `ess` image, `lt_estimators::batch_means`) says how much too narrow its
//!    per-pass intervals are, and b̂'s bootstrap error (fixed within a run) adds to the miss:
//!    the coverage they predict must not fall below the observed one (batch means at 8 passes
//!    per batch can only understate the correlation), and ESS's share of it must be significant
//!    (against ESS/P = 1), both paired over runs.

use lt_core::primary_space::PrimarySpace;
use lt_estimators::agreement::{agreement_t, sidak_threshold};
use lt_estimators::running::RunningImage;
use lt_estimators::{naive_interval_coverage, Image};
use lt_integrators::metropolis::mmlt::Mmlt;
use lt_integrators::metropolis::target::{Restrict, Sample};
use lt_integrators::params::ParamReader;
use lt_integrators::{make_integrator, render, IntegratorParams, RenderOptions};
use lt_tests::{render_blocks, shipped_scene};
use std::ops::ControlFlow;

const ALPHA: f64 = 1e-3;

/// (integrator, its `--set` keys) compared with bdpt.
fn metropolis() -> Vec<(&'static str, IntegratorParams)> {
    vec![
        ("pssmlt", IntegratorParams::new().with("bootstrap", 4096)),
        (
            "pssmlt",
            IntegratorParams::new()
                .with("base", "pt")
                .with("bootstrap", 4096),
        ),
        ("mmlt", IntegratorParams::new().with("bootstrap", 4096)),
    ]
}

// Two scenes keep the test inside its CI share (~60 CPU s); rough glass cost a third more and
// added no path kind the point-light caustic scene lacks to Metropolis' mutations.
const SCENES: [&str; 2] = ["cornell-box", "cornell-point-caustic"];

#[test]
fn metropolis_agrees_with_bdpt_on_shipped_scenes() {
    let configs = metropolis();
    let comparisons = SCENES.len() * configs.len();
    let per = -(((-ALPHA).ln_1p()) / comparisons as f64).exp_m1();
    let mut failures = Vec::new();
    for name in SCENES {
        let scene = shipped_scene(name, Some((16, 16)));
        let (_, reference) = render_blocks(&scene, "bdpt", IntegratorParams::new(), 512, 1, 8);
        for (integrator, params) in &configs {
            let (r, blocks) = render_blocks(&scene, integrator, params.clone(), 64, 100, 8);
            assert_eq!(
                r.invalid_samples, 0,
                "{integrator} on {name}: invalid samples"
            );
            let a = agreement_t(&blocks, &reference, per);
            let (m, b) = (blocks.estimate(), reference.estimate());
            let total = |e: &lt_estimators::blocks::BlockEstimate| -> f64 {
                e.mean.iter().map(|p| p[0] + p[1] + p[2]).sum()
            };
            let line = format!(
                "{integrator} {:?} on {name}: max |z| {:.2} (threshold {:.2}), image ratio {:.4}",
                params.pairs(),
                a.max_abs_z,
                a.threshold,
                total(&m) / total(&b)
            );
            println!("{line}");
            if !a.passed() {
                failures.push(line);
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn mmlt_chain_starts_hold_their_bootstrap_value() {
    for name in SCENES {
        let scene = shipped_scene(name, Some((16, 16)));
        let params = IntegratorParams::new();
        let mmlt = Mmlt::read(&scene, &ParamReader::new("mmlt", &params)).unwrap();
        let base = &mmlt.base;
        let mut scratch = base.scratch(&scene);
        // A bootstrap point: a fresh large step on its own stream (`chain::Keys`).
        let point = |i: u64| {
            let mut space = PrimarySpace::new(7, i, 0.01);
            space.start_iteration(true);
            space
        };
        let (mut importance, mut sample, mut lit) = (Vec::new(), Sample::default(), 0);
        for i in 0..256 {
            base.evaluate_lengths(&scene, &mut point(i), &mut scratch, &mut importance);
            for (k, at) in (1..).zip(&importance) {
                let mut space = point(i);
                base.evaluate_start(
                    &scene,
                    Restrict::Length(k),
                    &mut space,
                    &mut scratch,
                    &mut sample,
                );
                assert_eq!(
                    sample.importance.to_bits(),
                    at.picked.to_bits(),
                    "{name}, point {i}, length {k}: a chain starts at I {} where the bootstrap \
                     resampled it by {}",
                    sample.importance,
                    at.picked
                );
                lit += (at.picked > 0.0) as usize;
            }
        }
        // Enough lit states that the check saw every kind of strategy.
        assert!(lit >= 64, "{name}: only {lit} lit (point, length) pairs");
    }
}

/// Student-t two-sided 95 % quantile with `dof` degrees of freedom (Cornish–Fisher series from
/// the normal quantile; within 1e-3 for dof ≥ 5).
fn t95(dof: f64) -> f64 {
    let z: f64 = 1.959964;
    let g1 = (z.powi(3) + z) / 4.0;
    let g2 = (5.0 * z.powi(5) + 16.0 * z.powi(3) + 3.0 * z) / 96.0;
    let g3 = (3.0 * z.powi(7) + 19.0 * z.powi(5) + 17.0 * z.powi(3) - 15.0 * z) / 384.0;
    z + g1 / dof + g2 / dof.powi(2) + g3 / dof.powi(3)
}

#[test]
fn independent_runs_cover_and_per_pass_error_bars_do_not() {
    let scene = shipped_scene("cornell-box", Some((8, 8)));
    let n = 64usize;
    // bdpt's reference, its own per-pixel standard error kept.
    let bdpt = make_integrator("bdpt", &scene, &IntegratorParams::new()).unwrap();
    let opts = |passes, seed| RenderOptions {
        passes,
        time_limit: None,
        seed,
        threads: 0,
    };
    let reference = render(&scene, &bdpt, &opts(4096, 1), |_| ControlFlow::Continue(())).unwrap();
    let ref_se = reference.per_pass.as_ref().unwrap().std_error();
    let ref_mean = reference.estimate;

    let mlt = make_integrator("pssmlt", &scene, &IntegratorParams::new()).unwrap();
    let (runs, passes) = (16usize, 64u32);
    // Per run: its estimate and the spread of its passes (pass image i = i·E_i − (i−1)·E_{i−1},
    // as b̂ is fixed within a run and every pass does the same number of mutations).
    let mut estimates: Vec<Image> = Vec::new();
    let mut pass_se: Vec<Image> = Vec::new();
    // Per run: ESS/P per pixel from the run's own batch means (its record's `ess` image).
    let mut ess: Vec<Image> = Vec::new();
    // Per run: b̂'s relative standard error (its bootstrap's; fixed within a run, so neither the
    // passes nor their batches see it) and the batches its ESS used.
    let mut b_rel: Vec<f64> = Vec::new();
    let mut batches = String::new();
    for r in 0..runs {
        let mut prev = Image::new(8, 8);
        let mut spread = RunningImage::new(8, 8);
        let result = render(&scene, &mlt, &opts(passes, 200 + r as u64), |rep| {
            let e = rep.estimate();
            let i = rep.passes_done as f64;
            let mut p = Image::new(8, 8);
            for k in 0..n {
                for c in 0..3 {
                    p.data[k][c] = i * e.data[k][c] - (i - 1.0) * prev.data[k][c];
                }
            }
            spread.add(&p);
            prev = e;
            ControlFlow::Continue(())
        })
        .unwrap();
        assert_eq!(result.invalid_samples, 0);
        let log = result.log.expect("a consistent run has a log");
        let fact = |key: &str| -> String {
            log.facts
                .iter()
                .find(|(k, _)| k == key)
                .map(|(_, v)| v.clone())
                .unwrap_or_else(|| panic!("no {key} in the record"))
        };
        let num = |key: &str| -> f64 { fact(key).parse().unwrap() };
        b_rel.push(num("b_std_error") / num("b"));
        batches = fact("ess_batches");
        let (_, ratio) = log
            .images
            .into_iter()
            .find(|(name, _)| name == "ess")
            .expect("an ESS image after 64 passes");
        ess.push(ratio);
        estimates.push(result.estimate);
        pass_se.push(spread.std_error());
    }
    let (t_pass, t_runs) = (t95(passes as f64 - 1.0), t95(runs as f64 - 2.0));
    let mut cover_pass = vec![0.0f64; runs];
    let mut cover_runs = vec![0.0f64; runs];
    // What ESS and b̂ predict for the per-pass intervals: run r's pixel k is off by its naive
    // error over √(ESS/P) (luminance's ESS applied to green; a pixel with none taken as
    // independent), by b̂'s relative error times the pixel, and by the reference's error.
    let mut predicted = vec![0.0f64; runs];
    // The same with ESS/P = 1: what b̂ and the reference alone would predict.
    let mut predicted_independent = vec![0.0f64; runs];
    for r in 0..runs {
        for k in 0..n {
            // Channel 1 (green) alone: the three channels of a pixel share their paths.
            let c = 1;
            let x = estimates[r].data[k][c];
            let truth = ref_mean.data[k][c];
            let rse2 = ref_se.data[k][c].powi(2);
            let se_p = (pass_se[r].data[k][c].powi(2) + rse2).sqrt();
            cover_pass[r] += ((x - truth).abs() <= t_pass * se_p) as u8 as f64 / n as f64;
            let rho = ess[r].data[k][0];
            let rho = if rho > 0.0 { rho } else { 1.0 };
            let other = (rse2 + (truth * b_rel[r]).powi(2)).sqrt();
            let p = naive_interval_coverage(t_pass, pass_se[r].data[k][c], rho, se_p, other);
            predicted[r] += p / n as f64;
            let p1 = naive_interval_coverage(t_pass, pass_se[r].data[k][c], 1.0, se_p, other);
            predicted_independent[r] += p1 / n as f64;
            // Leave-one-out spread of the other runs: independent of run r.
            let others: Vec<f64> = (0..runs)
                .filter(|&q| q != r)
                .map(|q| estimates[q].data[k][c])
                .collect();
            let m = others.iter().sum::<f64>() / others.len() as f64;
            let var =
                others.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (others.len() - 1) as f64;
            let se_r = (var + rse2).sqrt();
            cover_runs[r] += ((x - truth).abs() <= t_runs * se_r) as u8 as f64 / n as f64;
        }
    }
    let stats = |v: &[f64]| {
        let m = v.iter().sum::<f64>() / v.len() as f64;
        let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64;
        (m, (var / v.len() as f64).sqrt())
    };
    let (cp, sp) = stats(&cover_pass);
    let (cr, sr) = stats(&cover_runs);
    // Paired over runs: observed minus ESS-predicted per-pass coverage.
    let diff: Vec<f64> = (0..runs).map(|r| cover_pass[r] - predicted[r]).collect();
    let (cd, sd) = stats(&diff);
    let mut lit: Vec<f64> = ess
        .iter()
        .flat_map(|e| e.data.iter().map(|p| p[0]))
        .filter(|&v| v > 0.0)
        .collect();
    lit.sort_by(f64::total_cmp);
    let median_ess = lit.get(lit.len() / 2).copied().unwrap_or(f64::NAN);
    // Four checks: Šidák over them.
    let z = sidak_threshold(ALPHA, 4);
    println!(
        "pssmlt on cornell-box 8×8, {runs} runs × {passes} passes: coverage of nominal 95 % \
         intervals from passes {:.1} % ± {:.1} %, from independent runs {:.1} % ± {:.1} % \
         (threshold z {z:.2})",
        100.0 * cp,
        100.0 * sp,
        100.0 * cr,
        100.0 * sr
    );
    println!(
        "batch-means ESS/P median {median_ess:.3} ({batches} per run) with b̂'s relative error \
         (mean {:.3}) predicts per-pass coverage {:.1} %; observed − predicted {:.1} % ± {:.1} %",
        b_rel.iter().sum::<f64>() / runs as f64,
        100.0 * (cp - cd),
        100.0 * cd,
        100.0 * sd
    );
    // Batch means with batches of 8 passes can only understate the correlation (its finite-batch
    // bias; ESS/P falls to 0.288 and 0.257 with 256 and 1,024 passes, batches of 16 and 32), so
    // the prediction may sit above the observed coverage but not below it.
    assert!(
        cd / sd.max(1e-12) < z,
        "ESS predicts per-pass coverage {:.1} %, below the observed {:.1} % (difference {:.1} % ± {:.1} %)",
        100.0 * (cp - cd),
        100.0 * cp,
        100.0 * cd,
        100.0 * sd
    );
    // ESS's share: with ESS/P = 1 (b̂ and the reference alone) the prediction must be
    // significantly higher.
    let share: Vec<f64> = (0..runs)
        .map(|r| predicted_independent[r] - predicted[r])
        .collect();
    let (ce, se_e) = stats(&share);
    println!(
        "without ESS (b̂'s and the reference's errors alone) the prediction is {:.1} %: ESS lowers \
         it by {:.1} % ± {:.1} %",
        100.0 * (cp - cd + ce),
        100.0 * ce,
        100.0 * se_e
    );
    assert!(
        ce / se_e.max(1e-12) > z,
        "ESS lowers the predicted per-pass coverage by only {:.1} % ± {:.1} %",
        100.0 * ce,
        100.0 * se_e
    );
    let z_runs = (cr - 0.95) / sr.max(1e-12);
    assert!(
        z_runs.abs() < z,
        "independent-run intervals cover {:.1} % ± {:.1} %, not 95 % (z = {z_runs:.2})",
        100.0 * cr,
        100.0 * sr
    );
    let z_gap = (cr - cp) / (sp * sp + sr * sr).sqrt().max(1e-12);
    assert!(
        z_gap > z,
        "per-pass intervals cover {:.1} %, not significantly below the runs' {:.1} % (z = {z_gap:.2})",
        100.0 * cp,
        100.0 * cr
    );
    // The runs must have had something to cover: a lit image.
    assert!(ref_mean.data.iter().any(|p| p[1] > 0.0));
}

/// Issue 46 item 5 in full: every Metropolis configuration against bdpt on every shipped scene it
/// accepts, as `metropolis_agrees_with_bdpt_on_shipped_scenes` does on two (Šidák over all
/// comparisons here). Minutes of CPU, so not in CI: `cargo test --release --test checks
/// mlt::metropolis_agrees_with_bdpt_on_every_shipped_scene -- --ignored --nocapture`
/// (results/mlt.md has its table).
#[test]
#[ignore]
fn metropolis_agrees_with_bdpt_on_every_shipped_scene() {
    let configs = metropolis();
    let names = lt_tests::shipped_scene_names();
    let accepted = |scene: &lt_core::Scene, integrator: &str, params: &IntegratorParams| {
        make_integrator(integrator, scene, params).err()
    };
    let mut pairs = Vec::new();
    for name in &names {
        let scene = shipped_scene(name, Some((16, 16)));
        for (integrator, params) in &configs {
            match accepted(&scene, integrator, params) {
                None => pairs.push((name.clone(), *integrator, params.clone())),
                Some(why) => println!("{integrator} on {name}: refused ({why})"),
            }
        }
    }
    let per = -(((-ALPHA).ln_1p()) / pairs.len() as f64).exp_m1();
    let mut failures = Vec::new();
    let mut last: Option<(String, lt_estimators::blocks::RunningBlocks)> = None;
    for (name, integrator, params) in pairs {
        let scene = shipped_scene(&name, Some((16, 16)));
        if last.as_ref().is_none_or(|(n, _)| *n != name) {
            let (_, reference) = render_blocks(&scene, "bdpt", IntegratorParams::new(), 512, 1, 8);
            last = Some((name.clone(), reference));
        }
        let reference = &last.as_ref().unwrap().1;
        let (r, blocks) = render_blocks(&scene, integrator, params.clone(), 64, 100, 8);
        let a = agreement_t(&blocks, reference, per);
        let line = format!(
            "| {name} | {integrator} {:?} | {:.2} | {:.2} | {} |",
            params.pairs(),
            a.max_abs_z,
            a.threshold,
            r.invalid_samples
        );
        println!("{line}");
        if !a.passed() || r.invalid_samples > 0 {
            failures.push(line);
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

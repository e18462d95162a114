//! `render_runs` (`lt render --runs K`): for an unbiased estimator the standard error across K
//! independent runs and the one from the spread of all K·P passes estimate the same quantity, so
//! their per-pixel ratio averages to one. Pixels have their own random streams, so the ratios of
//! different pixels are independent and the mean ratio's standard error comes from their spread.
//! A wrong across-run figure (a missing 1/√K, runs that share a seed, correlated runs) moves the
//! mean ratio by a factor of order K, far outside the bound.

use lt_estimators::agreement::sidak_threshold;
use lt_estimators::running::RunningStat;
use lt_integrators::{make_integrator, render_runs, IntegratorParams, RenderOptions};
use lt_tests::shipped_scene;
use std::ops::ControlFlow;

#[test]
fn unbiased_error_across_runs_agrees_with_the_per_pass_error() {
    let scene = shipped_scene("cornell-box", Some((24, 24)));
    let integ =
        make_integrator("pt", &scene, &IntegratorParams::new().with("max_depth", 3)).unwrap();
    let opts = RenderOptions {
        passes: 16,
        time_limit: None,
        seed: 5,
        threads: 0,
    };
    let runs = 16;
    let r = render_runs(
        &scene,
        &integ,
        &opts,
        runs,
        |_, _| ControlFlow::Continue(()),
        |_| {},
    )
    .unwrap();
    assert_eq!(r.runs.len(), runs as usize);
    let seeds: Vec<u64> = r.runs.iter().map(|s| s.seed).collect();
    assert_eq!(seeds, (5..5 + runs as u64).collect::<Vec<_>>());
    let across = r.across_runs.std_error();
    let per_pass = r.per_pass.as_ref().unwrap().std_error();
    assert_eq!(r.per_pass.as_ref().unwrap().count(), (runs * 16) as u64);
    // One channel per pixel: the three channels of a pixel share its paths.
    let mut ratio = RunningStat::new();
    for (a, p) in across.data.iter().zip(&per_pass.data) {
        if p[1] > 0.0 {
            ratio.add((a[1] / p[1]).powi(2));
        }
    }
    assert!(ratio.count() > 400, "too few lit pixels: {}", ratio.count());
    let z = (ratio.mean() - 1.0) / ratio.std_error();
    let bound = sidak_threshold(1e-3, 1);
    println!(
        "mean (se_runs / se_passes)² = {:.4} ± {:.4} over {} pixels, z = {z:.2} (bound {bound:.2})",
        ratio.mean(),
        ratio.std_error(),
        ratio.count()
    );
    assert!(z.abs() < bound, "z = {z}");
}

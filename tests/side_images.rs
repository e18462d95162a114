//! Side images a progressive run records for `lt render` to write beside its output
//! (`ProgressLog::images`): eamis's merge mask. With a fixed configuration the mask is known
//! without the pilot (every pixel merges, or none does); with a pilot it holds only 0 and 1, at
//! the film's size, in the share of pixels the record says merge.

use lt_integrators::{make_integrator, render, IntegratorParams, RenderOptions};
use lt_tests::shipped_scene;
use std::ops::ControlFlow;

/// The merge mask and the `eamis_merging_pixels` fact of one eamis render of cornell-box at
/// 24 × 16 pixels, 3 passes.
fn mask_and_share(params: IntegratorParams) -> (lt_estimators::Image, f64) {
    let scene = shipped_scene("cornell-box", Some((24, 16)));
    let integ = make_integrator("eamis", &scene, &params).unwrap();
    let opts = RenderOptions {
        passes: 3,
        time_limit: None,
        seed: 4,
        threads: 1,
    };
    let r = render(&scene, &integ, &opts, |_| ControlFlow::Continue(())).unwrap();
    let log = r.log.expect("a progressive run has a log");
    let share = log
        .facts
        .iter()
        .find(|(k, _)| k == "eamis_merging_pixels")
        .map(|(_, v)| v.parse::<f64>().unwrap())
        .expect("the record says how many pixels merge");
    let (_, mask) = log
        .images
        .into_iter()
        .find(|(name, _)| name == "merge-mask")
        .expect("eamis records its merge mask");
    assert_eq!((mask.width, mask.height), (24, 16));
    (mask, share)
}

#[test]
fn eamis_merge_mask_is_the_mask_it_rendered_with() {
    for (fixed, want) in [("m1_vc1_merge", 1.0), ("m1_vc1_nomerge", 0.0)] {
        let (mask, share) = mask_and_share(IntegratorParams::new().with("fixed", fixed));
        assert_eq!(share, want, "{fixed}");
        assert!(
            mask.data.iter().flatten().all(|&v| v == want),
            "{fixed}: every pixel of the mask should be {want}"
        );
    }
    let (mask, share) = mask_and_share(IntegratorParams::new());
    let values: Vec<f64> = mask.data.iter().map(|p| p[0]).collect();
    assert!(mask.data.iter().all(|p| p[0] == p[1] && p[1] == p[2]));
    assert!(values.iter().all(|&v| v == 0.0 || v == 1.0), "{values:?}");
    let ones = values.iter().sum::<f64>() / values.len() as f64;
    // The record prints the share to 4 decimals.
    assert!(
        (ones - share).abs() <= 0.5e-4,
        "mask {ones}, record {share}"
    );
}

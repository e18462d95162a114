//! `pt` with `lanes=8` (`unidirectional::pt_lanes`, eight paths walked together) gives the scalar
//! `pt`'s image bit for bit: same seed, every shipped TOML scene and Bitterli's veach-bidir, at
//! one and two threads, and under each MIS heuristic and technique set. The lanes draw each
//! pixel's own stream and their kernels repeat the scalar operations in order, so equality is
//! exact — any reordered operation or misplaced draw shows as a differing pixel. A
//! scene with media is refused under `lanes=8` in one line.

use lt_integrators::{make_integrator, render, IntegratorParams, RenderOptions};
use lt_tests::{scenes_dir, shipped_media_scene_names, shipped_scene, shipped_scene_names};
use std::ops::ControlFlow;

/// 13 columns: one full batch of 8 lanes and a partial one of 5 per row.
const RESOLUTION: (u32, u32) = (13, 9);
const PASSES: u32 = 2;

/// The image's bits and its invalid-sample count.
fn bits(scene: &lt_core::Scene, params: &IntegratorParams, threads: usize) -> (Vec<u64>, u64) {
    let integ = make_integrator("pt", scene, params).unwrap_or_else(|e| panic!("{e}"));
    let opts = RenderOptions {
        passes: PASSES,
        time_limit: None,
        seed: 11,
        threads,
    };
    let r = render(scene, &integ, &opts, |_| ControlFlow::Continue(())).unwrap();
    let px = r
        .estimate
        .data
        .iter()
        .flatten()
        .map(|v| v.to_bits())
        .collect();
    (px, r.invalid_samples)
}

/// The first differing pixel of `pt` and `pt lanes=8` on `name` under `extra`, if any.
fn same_image(name: &str, scene: &lt_core::Scene, extra: &[(&str, &str)]) {
    let mut scalar = IntegratorParams::new();
    for (k, v) in extra {
        scalar.set(k, v);
    }
    let lanes = scalar.clone().with("lanes", 8);
    let reference = bits(scene, &scalar, 1);
    assert!(
        reference.0.iter().any(|&b| b != 0),
        "{name}: black reference"
    );
    for threads in [1, 2] {
        let got = bits(scene, &lanes, threads);
        let first = reference.0.iter().zip(&got.0).position(|(a, b)| a != b);
        assert!(
            first.is_none() && reference.1 == got.1,
            "{name} {extra:?}, {threads} thread(s): lanes=8 differs from pt at value {first:?} \
             (invalid samples {} vs {})",
            reference.1,
            got.1
        );
    }
}

/// Bitterli's scene `name` with lt's `path` integrator for its `$integrator`.
fn bitterli(name: &str) -> lt_core::Scene {
    let path = scenes_dir().join("bitterli").join(name).join("scene.xml");
    let opts = lt_scene_io::LoadOptions {
        defines: vec![("integrator".into(), "path".into())],
        ..Default::default()
    };
    let (mut scene, _) =
        lt_scene_io::load_scene_with(&path, &opts).unwrap_or_else(|e| panic!("{e}"));
    scene.camera = scene.camera.with_resolution(RESOLUTION.0, RESOLUTION.1);
    scene
}

#[test]
fn lanes_give_the_scalar_pt_image_bit_for_bit_on_every_shipped_scene() {
    let names = shipped_scene_names();
    for name in &names {
        same_image(name, &shipped_scene(name, Some(RESOLUTION)), &[]);
    }
    same_image("bitterli/veach-bidir", &bitterli("veach-bidir"), &[]);
}

#[test]
fn lanes_give_the_scalar_pt_image_bit_for_bit_under_every_weighting() {
    for extra in [
        [("mis", "balance"), ("max_depth", "4")],
        [("techniques", "light"), ("rr_depth", "2")],
        [("techniques", "bsdf"), ("mis", "power")],
    ] {
        for name in ["veach-mis", "cornell-env"] {
            same_image(name, &shipped_scene(name, Some(RESOLUTION)), &extra);
        }
    }
}

#[test]
fn lanes_refuse_a_media_scene_in_one_line() {
    let name = &shipped_media_scene_names()[0];
    let scene = shipped_scene(name, Some((4, 4)));
    let params = IntegratorParams::new().with("lanes", 8);
    let err = make_integrator("pt", &scene, &params)
        .err()
        .expect("a refusal");
    assert!(
        err.contains("media") && !err.contains('\n'),
        "{name}: {err}"
    );
}

//! `light` with `lanes=8` (`unidirectional::light_lanes`, eight light subpaths walked together)
//! gives the scalar `light`'s image bit for bit: same seed, every shipped TOML scene and Bitterli's
//! veach-bidir, at one and two threads. Each lane draws its subpath's own stream and the splats are
//! recorded in the scalar order into the same chunks, so equality is exact — a reordered splat, a
//! misplaced draw or a wrong shadow ray shows as a differing pixel. A scene with media is refused
//! under `lanes=8` in one line.

use lt_integrators::{make_integrator, render, IntegratorParams, RenderOptions};
use lt_tests::{scenes_dir, shipped_media_scene_names, shipped_scene, shipped_scene_names};
use std::ops::ControlFlow;

const RESOLUTION: (u32, u32) = (13, 9);
const PASSES: u32 = 2;
/// Two splat chunks of 1024 subpaths, the second ending in a partial batch of 5 lanes.
const LIGHT_PATHS: u32 = 1024 + 8 * 3 + 5;

/// The image's bits and its invalid-splat count; `None` where `light` refuses the scene (an
/// orthographic camera).
fn bits(
    scene: &lt_core::Scene,
    params: &IntegratorParams,
    threads: usize,
) -> Option<(Vec<u64>, u64)> {
    let integ = make_integrator("light", scene, params).ok()?;
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
    Some((px, r.invalid_samples))
}

/// Asserts that `light` and `light lanes=8` agree on `name` (or both refuse it); true when they
/// rendered something other than black (light tracing cannot see some scenes: a caustic seen
/// only through a delta surface).
fn same_image(name: &str, scene: &lt_core::Scene) -> bool {
    let scalar = IntegratorParams::new().with("light_paths", LIGHT_PATHS);
    let lanes = scalar.clone().with("lanes", 8);
    let Some(reference) = bits(scene, &scalar, 1) else {
        assert!(
            bits(scene, &lanes, 1).is_none(),
            "{name}: only lanes=8 renders"
        );
        return false;
    };
    for threads in [1, 2] {
        let got = bits(scene, &lanes, threads).expect("lanes=8 renders what light renders");
        let first = reference.0.iter().zip(&got.0).position(|(a, b)| a != b);
        assert!(
            first.is_none() && reference.1 == got.1,
            "{name}, {threads} thread(s): lanes=8 differs from light at value {first:?} \
             (invalid splats {} vs {})",
            reference.1,
            got.1
        );
    }
    reference.0.iter().any(|&b| b != 0)
}

#[test]
fn light_lanes_give_the_scalar_light_image_bit_for_bit_on_every_shipped_scene() {
    let names = shipped_scene_names();
    let rendered = names
        .iter()
        .filter(|name| same_image(name, &shipped_scene(name, Some(RESOLUTION))))
        .count();
    // Only a few scenes (an orthographic camera, a caustic behind glass) may be refused or black.
    assert!(rendered + 3 >= names.len(), "{rendered} of {}", names.len());
    let path = scenes_dir().join("bitterli/veach-bidir/scene.xml");
    let opts = lt_scene_io::LoadOptions {
        defines: vec![("integrator".into(), "path".into())],
        ..Default::default()
    };
    let (mut scene, _) =
        lt_scene_io::load_scene_with(&path, &opts).unwrap_or_else(|e| panic!("{e}"));
    scene.camera = scene.camera.with_resolution(RESOLUTION.0, RESOLUTION.1);
    assert!(same_image("bitterli/veach-bidir", &scene));
}

#[test]
fn light_lanes_refuse_a_media_scene_in_one_line() {
    let name = &shipped_media_scene_names()[0];
    let scene = shipped_scene(name, Some((4, 4)));
    let params = IntegratorParams::new().with("lanes", 8);
    let err = make_integrator("light", &scene, &params)
        .err()
        .expect("a refusal");
    assert!(
        err.contains("media") && !err.contains('\n'),
        "{name}: {err}"
    );
}

//! Moving the whole scene far from the origin must not change the image: f32 coordinates near 1e4
//! keep only ~1e-3 absolute precision, so every error bound, ray offset and shadow-ray end point
//! has to scale with the coordinates rather than with the scene's extent. Each integrator renders
//! the Cornell box at the origin and translated by 1e3 and 1e4 on every axis; every 8×8 block must
//! agree within Šidák-corrected standard errors.

use lt_core::Vec3;
use lt_estimators::agreement::agreement_t;
use lt_integrators::{make_integrator, IntegratorParams};
use lt_tests::{render_blocks, shipped_scene};

/// Integrators whose light transport is checked here, as soon as they are registered.
// bdpt rebuilds MIS densities from vertex positions; it holds at 1e4 because `SceneBuilder::build`
// recentres the scene (`Scene::origin`), so the offset costs only the rounding of the input vertices
// (at 1e4 that grows the light by 0.17 %, which every integrator sees alike).
const CHECKED: [&str; 3] = ["pt", "light", "bdpt"];

fn passes(name: &str) -> u32 {
    match name {
        "pt" => 256,
        _ => 128,
    }
}

#[test]
fn translated_cornell_box_renders_the_same() {
    let scene = shipped_scene("cornell-box", Some((64, 64)));
    // Picked up by name as soon as they are registered (the table's row type is not relied on).
    let names: Vec<&str> = CHECKED
        .into_iter()
        .filter(|n| make_integrator(n, &scene, &IntegratorParams::default()).is_ok())
        .collect();
    assert!(names.contains(&"pt"), "pt is not registered");
    let mut failures = Vec::new();
    for name in names {
        let n = passes(name);
        let (r0, base) = render_blocks(&scene, name, IntegratorParams::default(), n, 21, 8);
        assert_eq!(
            r0.invalid_samples, 0,
            "{name}: invalid samples at the origin"
        );
        for offset in [1e3f32, 1e4] {
            let moved = scene.translated(Vec3::splat(offset));
            let (r, blocks) = render_blocks(&moved, name, IntegratorParams::default(), n, 22, 8);
            assert_eq!(
                r.invalid_samples, 0,
                "{name}: invalid samples at {offset:e}"
            );
            let (m0, m1) = (mean(&base), mean(&blocks));
            let result = agreement_t(&base, &blocks, 1e-3);
            eprintln!(
                "{name} at {offset:e}: image mean ratio {:.5}, {result}",
                m1 / m0
            );
            if !result.passed() {
                failures.push(format!("{name} translated by {offset:e}: {result}"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Mean over blocks and channels (for the diagnostic ratio printed above).
fn mean(b: &lt_estimators::blocks::RunningBlocks) -> f64 {
    let e = b.estimate();
    e.mean.iter().flatten().sum::<f64>() / (3 * e.regions()) as f64
}

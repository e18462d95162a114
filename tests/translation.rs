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
    let scene = shipped_scene("cornell-box", Some((32, 32)));
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
            let what = format!("{name} translated by {offset:e}");
            failures.extend(moved_agrees(&base, &moved, name, n, 22, &what));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Renders the moved scene and holds its blocks against `base` (the scene where it was),
/// within Šidák-corrected standard errors; the failure's description when they disagree.
fn moved_agrees(
    base: &lt_estimators::blocks::RunningBlocks,
    moved: &lt_core::Scene,
    name: &str,
    passes: u32,
    seed: u64,
    what: &str,
) -> Option<String> {
    let (r, blocks) = render_blocks(moved, name, IntegratorParams::default(), passes, seed, 8);
    assert_eq!(r.invalid_samples, 0, "{what}: invalid samples");
    let result = agreement_t(base, &blocks, 1e-3);
    eprintln!(
        "{what}: image mean ratio {:.5}, {result}",
        mean(&blocks) / mean(base)
    );
    (!result.passed()).then(|| format!("{what}: {result}"))
}

/// Mean over blocks and channels (for the diagnostic ratio printed above).
fn mean(b: &lt_estimators::blocks::RunningBlocks) -> f64 {
    let e = b.estimate();
    e.mean.iter().flatten().sum::<f64>() / (3 * e.regions()) as f64
}

/// The same scene *file* placed far from the origin: the XML Cornell box with every shape's and
/// the sensor's `to_world` followed by a translation of `offset` on every axis. The loader
/// composes and applies transforms in f64 and subtracts the scene's origin before its one
/// rounding to f32, so the geometry it builds is the geometry at the origin, merely moved; a
/// loader that rounded world coordinates first moves vertices by up to half an f32 spacing
/// (≈ 5e-4 at 1e4, ≈ 3e-2 at 1e6) and the light grows or shrinks with them.
fn cornell_file_at(offset: f64, dir: &std::path::Path) -> lt_core::Scene {
    let src = lt_tests::scenes_dir().join("xml/cornell-box.xml");
    let text = std::fs::read_to_string(&src).unwrap().replace(
        r#"<default name="res" value="256"/>"#,
        r#"<default name="res" value="32"/>"#,
    );
    let o = format!("{offset:?}");
    // The sensor's look-at moves by hand; every shape's to_world gains a translate.
    let (sensor, shapes) = text.split_at(text.find("</sensor>").unwrap());
    let sensor = sensor.replace(
        r#"<lookat origin="0, 0, 3.9" target="0, 0, 0" up="0, 1, 0"/>"#,
        &format!(
            r#"<lookat origin="{o}, {o}, {:?}" target="{o}, {o}, {o}" up="0, 1, 0"/>"#,
            offset + 3.9
        ),
    );
    let shapes = shapes.replace(
        "</transform>",
        &format!(r#"<translate value="{o}, {o}, {o}"/></transform>"#),
    );
    let moved = sensor + &shapes;
    assert!(
        offset == 0.0 || moved.matches("<translate value").count() >= 8,
        "{moved}"
    );
    let path = dir.join(format!("cornell-{offset:e}.xml"));
    std::fs::write(&path, moved).unwrap();
    let (scene, _) =
        lt_scene_io::load_scene_with(&path, &Default::default()).unwrap_or_else(|e| panic!("{e}"));
    scene
}

#[test]
fn cornell_box_file_translated_far_away_renders_the_same() {
    let dir = std::env::temp_dir().join(format!("lt-translation-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let base_scene = cornell_file_at(0.0, &dir);
    assert_eq!(base_scene.origin, Vec3::ZERO);
    let mut failures = Vec::new();
    for name in CHECKED {
        let n = passes(name);
        let (_, base) = render_blocks(&base_scene, name, IntegratorParams::default(), n, 31, 8);
        for offset in [1e4, 1e6] {
            let moved = cornell_file_at(offset, &dir);
            assert_ne!(
                moved.origin,
                Vec3::ZERO,
                "the loader recentres at {offset:e}"
            );
            let what = format!("file translated by {offset:e}, {name}");
            failures.extend(moved_agrees(&base, &moved, name, n, 32, &what));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

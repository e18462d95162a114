//! Every registered integrator (`lt_integrators::INTEGRATORS`, so a new one is covered with no new
//! test code) renders every shipped scene without NaN, infinite or negative pixels and without
//! invalid samples, and gives the same image bit for bit with one thread or two. On the media
//! scenes (`scenes/media/`) the integrators of `registry::HANDLES_MEDIA` render and every other
//! one is held to its one-line refusal.

use lt_core::Scene;
use lt_integrators::{make_integrator, render, IntegratorParams, RenderOptions, INTEGRATORS};
use lt_tests::{
    assert_same_image_as_pt, handles_media, is_pt_without_media, media_refusal,
    shipped_media_scene_names, shipped_scene, shipped_scene_names,
};
use std::ops::ControlFlow;

/// Why an integrator's image of a scene may legitimately be black at this test's sample count.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Black {
    /// Zero is the exact expected value: the image must be black.
    Exact,
    /// Lit paths exist but are so rare that a black image is the likely outcome: either is fine.
    Likely,
}

/// (integrator, scene, kind, reason) where a black image is right. Only the "not black" check is
/// lifted; finiteness, non-negativity and zero invalid samples still hold everywhere.
const BLACK: &[(&str, &str, Black, &str)] = &[
    (
        "pt-bsdf",
        "point-plane",
        Black::Exact,
        "its only light is a point light, which BSDF sampling never hits",
    ),
    (
        "pt-bsdf",
        "point-plane-pinhole",
        Black::Exact,
        "its only light is a point light, which BSDF sampling never hits",
    ),
    (
        "pt-bsdf",
        "cornell-point-caustic",
        Black::Exact,
        "its only light is a point light, which BSDF sampling never hits",
    ),
    (
        "pt-bsdf",
        "sun-room",
        Black::Likely,
        "its only light is the sun (6.87e-5 sr) through a window: a BSDF-sampled direction \
         hits it on ~1e-5 of the bounces that see the window, none in 48²×16 samples",
    ),
    (
        "pt-bsdf",
        "cornell-directional",
        Black::Exact,
        "its only light is a directional light, a single direction no BSDF sample hits",
    ),
    (
        "pt-bsdf",
        "smallvcm-spheres-sun",
        Black::Exact,
        "its only light is a directional light, a single direction no BSDF sample hits",
    ),
    (
        "pt-bsdf",
        "smallvcm-spheres-point",
        Black::Exact,
        "its only light is a point light, which BSDF sampling never hits",
    ),
    (
        "pt-bsdf",
        "cornell-spot",
        Black::Exact,
        "its only lights, a spot and a projector, are deltas in position, which BSDF sampling \
         never hits",
    ),
    (
        "pt-bsdf",
        "media/hg-spot",
        Black::Exact,
        "its only light is a spot light, a delta in position no BSDF or phase sample hits",
    ),
    (
        "light",
        "caustic-sds",
        Black::Exact,
        "the camera sees only the mirror, a delta surface: a light vertex joined to the pinhole \
         would have to be on it",
    ),
];

/// Integrators that refuse a shipped scene, with the words their error must contain: what
/// they cannot do is said at load, not rendered wrong.
const REFUSES: [(&str, &str, &str); 4] = [
    ("light", "point-plane", "orthographic"),
    ("vcm", "point-plane", "orthographic"),
    ("bpm", "point-plane", "orthographic"),
    ("eamis", "point-plane", "orthographic"),
];

fn black(integrator: &str, scene: &str) -> Option<(Black, &'static str)> {
    BLACK
        .iter()
        .find(|(i, s, _, _)| *i == integrator && *s == scene)
        .map(|(_, _, k, why)| (*k, *why))
}

#[test]
fn every_integrator_gives_finite_non_negative_pixels_on_every_shipped_scene() {
    let names = shipped_scene_names();
    assert!(
        names.len() >= 7,
        "expected the seven shipped scenes, found {names:?}"
    );
    // Each scene loaded once, every integrator run on it.
    for name in &names {
        let scene = shipped_scene(name, Some((32, 32)));
        for info in INTEGRATORS {
            if let Some((_, _, words)) = REFUSES
                .iter()
                .find(|(i, s, _)| *i == info.name && s == name)
            {
                let refusal = make_integrator(info.name, &scene, &IntegratorParams::default())
                    .err()
                    .unwrap_or_else(|| panic!("{} on {name}: expected a refusal", info.name));
                assert!(
                    refusal.contains(words),
                    "{} on {name}: {refusal}",
                    info.name
                );
                continue;
            }
            if is_pt_without_media(info.name) {
                assert_same_image_as_pt(&scene, name, info.name);
                continue;
            }
            // upbp has no photons without media (bdpt's connections under its weights): 4
            // passes check its code at a quarter of bdpt's cost here.
            let passes = if info.name == "upbp" { 4 } else { 16 };
            finite_non_negative_and_lit(&scene, name, info.name, passes);
        }
    }
}

/// `integrator` renders `passes` passes of `scene` (named `name`) with no invalid sample, no NaN,
/// infinite or negative pixel, and lit unless `BLACK` says otherwise.
///
/// One run of `passes` passes for every integrator, consistent ones included: this is the loop's
/// fixed per-case budget, so an estimator added to the registry costs the same as any other.
/// (`lt_tests::render_blocks` would give a consistent estimator `CONSISTENT_RUNS` runs for error
/// bars, which these checks do not use: 8× the paths of an unbiased one, 6 of the 11 integrators.)
fn finite_non_negative_and_lit(scene: &Scene, name: &str, integrator: &str, passes: u32) {
    let integ = make_integrator(integrator, scene, &IntegratorParams::default())
        .unwrap_or_else(|e| panic!("{integrator} on {name}: {e}"));
    let opts = RenderOptions {
        passes,
        time_limit: None,
        seed: 3,
        threads: 0,
    };
    let result = render(scene, &integ, &opts, |_| ControlFlow::Continue(())).unwrap();
    let who = format!("{integrator} on {name}");
    assert_eq!(
        result.invalid_samples, 0,
        "{who}: integrator produced invalid samples"
    );
    let mean = &result.estimate;
    assert!(
        mean.data
            .iter()
            .flatten()
            .all(|v| v.is_finite() && *v >= 0.0),
        "{who}: invalid pixel"
    );
    let lit = mean.data.iter().flatten().any(|v| *v > 0.0);
    match black(integrator, name) {
        None => assert!(lit, "{who}: image is black"),
        Some((Black::Exact, why)) => {
            assert!(!lit, "{who}: expected black ({why}), found light")
        }
        Some((Black::Likely, why)) => println!("{who}: black allowed ({why}); lit: {lit}"),
    }
}

/// The media scenes at 24², 8 passes: every integrator of `HANDLES_MEDIA` as above, every other
/// one refuses in one line (checked, and said, never skipped silently).
#[test]
fn media_integrators_give_finite_non_negative_pixels_on_every_media_scene() {
    let names = shipped_media_scene_names();
    assert!(
        names.len() >= 5,
        "expected the five media scenes, found {names:?}"
    );
    for name in &names {
        let scene = shipped_scene(name, Some((24, 24)));
        assert!(scene.has_media, "{name}: a media scene without media");
        for info in INTEGRATORS {
            if handles_media(info.name) {
                finite_non_negative_and_lit(&scene, name, info.name, 8);
            } else {
                let refusal = media_refusal(info.name, &scene, name);
                println!("{} on {name}: refused ({refusal})", info.name);
            }
        }
    }
}

#[test]
fn same_seed_gives_identical_images_for_one_and_two_threads() {
    for info in INTEGRATORS {
        for name in [
            "cornell-box",
            "veach-mis",
            "cornell-glass-light",
            "cornell-rough-glass",
        ] {
            let scene = shipped_scene(name, Some((32, 32)));
            same_bits_at_one_and_two_threads(&scene, name, info.name, 4);
        }
    }
}

/// Every integrator of `HANDLES_MEDIA` on every media scene (24², 2 passes); the others refuse
/// them (`media_integrators_give_finite_non_negative_pixels_on_every_media_scene` checks how).
#[test]
fn same_seed_gives_identical_images_for_one_and_two_threads_on_media_scenes() {
    for name in &shipped_media_scene_names() {
        let scene = shipped_scene(name, Some((24, 24)));
        for info in INTEGRATORS.iter().filter(|i| handles_media(i.name)) {
            same_bits_at_one_and_two_threads(&scene, name, info.name, 2);
        }
    }
}

/// `integrator`'s image of `scene` after `passes` passes is the same bit for bit at 1 and 2
/// threads, and another seed changes it.
fn same_bits_at_one_and_two_threads(scene: &Scene, name: &str, integrator: &str, passes: u32) {
    let who = format!("{integrator} on {name}");
    let integ = make_integrator(integrator, scene, &IntegratorParams::default()).unwrap();
    let run = |threads, seed| {
        let opts = RenderOptions {
            passes,
            time_limit: None,
            seed,
            threads,
        };
        render(scene, &integ, &opts, |_| ControlFlow::Continue(()))
            .unwrap()
            .estimate
    };
    let one = run(1, 99);
    let two = run(2, 99);
    let same = one
        .data
        .iter()
        .flatten()
        .zip(two.data.iter().flatten())
        .all(|(a, b)| a.to_bits() == b.to_bits());
    assert!(same, "{who}: images differ between 1 and 2 threads");
    // A black image (`BLACK`) is black under every seed.
    if black(integrator, name).is_none() {
        assert_ne!(one, run(2, 100), "{who}: the seed must matter");
    }
}

//! Mitsuba 3's render-test suite as a peer's test suite (`lt mitsuba-suite`), on
//! `../shared/mitsuba-render-tests` (relative to the repository root): every scene loads or names
//! its refusal (a token render), every scene that passes today keeps passing at 256 spp
//! (`EXPECTED_PASSING`: add a scene when your work makes it pass), and the participating-media
//! scenes pass with every estimator the suite judges on media (`MEDIA_SCENES`). Without the
//! folder the test says it skipped; `LT_REQUIRE_MITSUBA_SUITE=1` (CI) makes that a failure.

use lt_experiments::verify::mitsuba_suite::cases::MEDIA_ESTIMATORS;
use lt_experiments::verify::mitsuba_suite::{run_suite, run_suite_pairs, table, Budget, Outcome};
use std::path::PathBuf;
use std::time::Duration;

/// (scene, estimator) pairs that pass today at the pinned budget (32 passes × 8 spp), each with
/// at least 99.85 % of its pixel values passing there (the line is 99.75 %). `pt` on every
/// pinned scene; `bdpt` where its feature (projectors, instances, normal maps, mesh attributes,
/// texture interpolation, a point light) is not already held per path length to `pt`
/// (tests/agreement.rs: bump maps, conductors, textures, principled, env, spot, directional and
/// orthographic Cornell boxes) and by material to Mitsuba (tests/material_grid.rs): 14 more bdpt
/// pairs pass (`lt mitsuba-suite`, results/) but would cost CI ≈ 100 CPU s to repeat here. Left out though they
/// pass: infinite_mirrors (99.77 %, too close to the line), roughdielectric (needs 2048 spp: its
/// NEE through α = 0.02 glass is heavy-tailed), various_emitters (512 × 64 with light tracing: 6 s
/// per estimator buys 24–48 spp in 3–6 passes on a loaded machine, whose spread underestimates
/// the splats' error — 97.9 %; at 256 spp it passes, 100 % bdpt / 99.94 % light), various_shapes
/// (6 s buys 16–32 spp on a loaded machine: 99.61 % pt, 97.70 % bdpt; at 464 / 224 spp it passes,
/// 100.00 % / 99.99 %).
const EXPECTED_PASSING: &[(&str, &str)] = &[
    ("floating_sphere/test_directional_direct", "pt"),
    ("orthographic_sensor/test_orthographic_path", "pt"),
    ("spot_light/test_spot_direct", "pt"),
    ("projector/test_projector_constant_direct", "pt"),
    ("projector/test_projector_constant_direct", "bdpt"),
    ("projector/test_projector_textured_direct", "pt"),
    ("projector/test_projector_textured_direct", "bdpt"),
    ("bsdf_spheres/test_bumpmap_path", "pt"),
    ("bsdf_spheres/test_normalmap_path", "pt"),
    ("bsdf_spheres/test_normalmap_path", "bdpt"),
    (
        "bsdf_spheres/test_normalmap_identity_roughconductor_path",
        "pt",
    ),
    ("bsdf_spheres/test_textured_diffuse_path", "pt"),
    ("bsdf_spheres/test_roughplastic_linear_path", "pt"),
    ("bsdf_spheres/test_roughplastic_nonlinear_path", "pt"),
    ("instancing/test_instancing_path", "pt"),
    ("instancing/test_instancing_path", "bdpt"),
    ("texture_interp/test_texture_interp_direct", "pt"),
    ("texture_interp/test_texture_interp_direct", "bdpt"),
    ("bsdf_spheres/test_arealight_path", "pt"),
    ("bsdf_spheres/test_constant_path", "pt"),
    ("bsdf_spheres/test_envmap_path", "pt"),
    ("bsdf_spheres/test_pointlight_path", "pt"),
    ("bsdf_spheres/test_pointlight_path", "bdpt"),
    ("mesh_attributes/test_mesh_attributes_3_face_direct", "pt"),
    ("mesh_attributes/test_mesh_attributes_3_face_direct", "bdpt"),
    ("mesh_attributes/test_mesh_attributes_3_vertex_direct", "pt"),
    (
        "mesh_attributes/test_mesh_attributes_3_vertex_direct",
        "bdpt",
    ),
    ("mesh_attributes/test_mesh_attributes_1_face_direct", "pt"),
    ("mesh_attributes/test_mesh_attributes_1_face_direct", "bdpt"),
    ("bsdf_spheres/test_texturedprincipled1_path", "pt"),
    ("bsdf_spheres/test_texturedprincipled2_path", "pt"),
    ("bsdf_spheres/test_texturedprincipledthin_path", "pt"),
];

/// The participating-media scenes (Mitsuba's `volpath` and `volpathmis` references): each must
/// pass with every estimator of `cases::MEDIA_ESTIMATORS` (the one list: adding `bdpt` there
/// judges it here too) but for `MEDIA_EXEMPT`; where the suite does not judge `light` (the
/// camera sees a delta lobe: `mitsuba_suite::not_judged`) it must say why.
const MEDIA_SCENES: &[&str] = &[
    "participating_media/test_hetero_sigmat_albedo_volpath",
    "participating_media/test_hetero_sigmat_volpath",
    "participating_media/test_hetero_spectral_sigmat_no_scattering_volpath",
    "participating_media/test_hetero_spectral_sigmat_volpathmis",
    "participating_media/test_homo_area_light_volpath",
    "participating_media/test_homo_dielectric_envmap_volpath",
    "participating_media/test_homo_emitter_inside_medium_volpath",
    "participating_media/test_homo_null_envmap_volpath",
    "participating_media/test_homo_obj_inside_medium_volpath",
    "participating_media/test_homo_roughdielectric_spot_volpath",
    "participating_media/test_homo_spectral_sigmat_volpathmis",
    "participating_media/test_surf_area_light_volpath",
];

/// (scene, estimator, why) not rendered in CI: unbiased (image means agree) but heavy-tailed at
/// the CI budget of 256 spp, so the passes' spread underestimates the per-pixel error and the
/// per-pixel rule fails on a fraction of pixels, all on the dark side; what each does at a larger
/// budget is in results/mitsuba-suite-media.md.
const MEDIA_EXEMPT: &[(&str, &str, &str)] = &[
    (
        "participating_media/test_homo_area_light_volpath",
        "pt",
        "the floor in the sphere's shadow sees the small area light through the medium only: \
         99.59 % at 256 spp (the line is 99.75 %), every failing value below the reference",
    ),
    (
        "participating_media/test_homo_dielectric_envmap_volpath",
        "pt",
        "caustics of the museum envmap through the water: 99.10 % at 256 spp (passes at 2048: \
         99.90 %, since delta lobes follow the shading frame across the geometric plane)",
    ),
    (
        "participating_media/test_homo_dielectric_envmap_volpath",
        "bdpt",
        "as pt: 99.15 % at 256 spp, 99.97 % at 2048",
    ),
    (
        "participating_media/test_homo_roughdielectric_spot_volpath",
        "bdpt",
        "as pt: the spot through rough glass, 99.45 % at 256 spp (max |z| 10.0)",
    ),
    (
        "participating_media/test_homo_area_light_volpath",
        "bdpt",
        "99.75 % at 256 spp, on the line: too close for CI",
    ),
    (
        "participating_media/test_hetero_spectral_sigmat_volpathmis",
        "bdpt",
        "passes, 99.83 % at 256 spp, under the 99.85 % this test pins",
    ),
    (
        "participating_media/test_surf_area_light_volpath",
        "bdpt",
        "passes, 99.84 % at 256 spp, under the 99.85 % this test pins",
    ),
    (
        "participating_media/test_hetero_spectral_sigmat_no_scattering_volpath",
        "pt",
        "passes, 99.81 % at 256 spp, too close to the line for CI (albedo 0: a path's free \
         flight either passes or ends)",
    ),
    (
        "participating_media/test_homo_roughdielectric_spot_volpath",
        "pt",
        "a spot light through rough glass (α = 0.3) reaches the floor by BTDF paths only",
    ),
    (
        "participating_media/test_homo_roughdielectric_spot_volpath",
        "light",
        "light paths into the medium through rough glass, joined to the camera through it",
    ),
    (
        "participating_media/test_hetero_sigmat_albedo_volpath",
        "light",
        ENVMAP_LIGHT,
    ),
    (
        "participating_media/test_hetero_sigmat_volpath",
        "light",
        ENVMAP_LIGHT,
    ),
    (
        "participating_media/test_hetero_spectral_sigmat_no_scattering_volpath",
        "light",
        ENVMAP_LIGHT,
    ),
    (
        "participating_media/test_hetero_spectral_sigmat_volpathmis",
        "light",
        ENVMAP_LIGHT,
    ),
    (
        "participating_media/test_homo_null_envmap_volpath",
        "light",
        ENVMAP_LIGHT,
    ),
    (
        "participating_media/test_homo_spectral_sigmat_volpathmis",
        "light",
        ENVMAP_LIGHT,
    ),
];

/// Why light tracing is exempt on the envmap-lit media scenes.
const ENVMAP_LIGHT: &str =
    "light traced from the museum envmap: 1.4 % of its light subpaths first \
     hit a point the camera sees, so at 256 spp a pixel holds a few splats and the passes' spread \
     underestimates its error (pixels at 0 where the reference reads 0.07; image means \
     ×0.99–1.00). Five of the six pass at 8192 spp (no_scattering: 99.73 %), 25–34 CPU s each";

/// bdpt runs here on the seven media scenes it passes with ≥ 99.85 % at 256 spp: 4–15 CPU s
/// each, 61 in all (results/mitsuba-suite-media.md).
fn media_exempt(scene: &str, estimator: &str) -> bool {
    MEDIA_EXEMPT
        .iter()
        .any(|&(s, e, _)| s == scene && e == estimator)
}

#[test]
fn mitsuba_render_suite_keeps_passing() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/mitsuba-render-tests");
    if !dir.join("tests/scenes").is_dir() {
        assert!(
            std::env::var("LT_REQUIRE_MITSUBA_SUITE").as_deref() != Ok("1"),
            "LT_REQUIRE_MITSUBA_SUITE=1 but {} is missing",
            dir.display()
        );
        eprintln!("skipped: no Mitsuba render-test suite at {}", dir.display());
        return;
    }
    // Every scene loads or is refused with a reason: checked on a token render (2 passes of one
    // sample) to keep CI short.
    let token = Budget {
        passes: 2,
        spp_per_pass: 1,
        time_per_estimator: Duration::from_secs(1),
        threads: 0,
        seed: 0,
        diagnostics: None,
    };
    let rows = run_suite(&dir, &token).unwrap();
    let md = table::markdown(&rows, &token, "cargo test --test checks mitsuba_suite");
    assert!(rows.len() >= 29, "{} scenes", rows.len());
    for r in &rows {
        assert!(
            md.contains(&format!("| {} |", r.name)),
            "{} missing from the table",
            r.name
        );
        if let Some(reason) = &r.refusal {
            assert!(
                !reason.trim().is_empty(),
                "{} refused without a reason",
                r.name
            );
            assert!(r.outcomes.is_empty());
        }
    }
    // The pinned scenes at 256 spp in 32 independent passes, whatever the machine's load: the
    // time limit is a safety net. At 6 s a machine at load 8–15 cut bdpt to 176 spp on
    // normalmap_identity_roughconductor, where it failed; an idle 2-core machine renders every
    // pinned pair's 256 spp within 6 s (63 of 63 at 256 spp, 99 s for this whole test), so CI
    // pays the same.
    let budget = Budget {
        passes: 32,
        spp_per_pass: 8,
        time_per_estimator: Duration::from_secs(120),
        threads: 0,
        seed: 0,
        diagnostics: None,
    };
    let rows = run_suite_pairs(&dir, &budget, |scene, estimator| {
        EXPECTED_PASSING.contains(&(scene, estimator))
    })
    .unwrap();
    println!(
        "{}",
        table::markdown(&rows, &budget, "cargo test --test checks mitsuba_suite")
    );
    let mut regressions = Vec::new();
    for &(scene, estimator) in EXPECTED_PASSING {
        let row = rows.iter().find(|r| r.name == scene);
        let passes = row.is_some_and(|r| {
            r.outcomes
                .iter()
                .any(|(e, o)| *e == estimator && o.passes())
        });
        if !passes {
            regressions.push(format!(
                "{scene} with {estimator}: {:?}",
                row.map(|r| (&r.refusal, &r.outcomes))
            ));
        }
    }
    // The media scenes, each with every media estimator not exempt, at the same fixed 256 spp
    // (seed 0 at any thread count gives the same image, so the judgement is the one
    // results/mitsuba-suite-media.md records, every pinned value ≥ 99.85 % there).

    let rows = run_suite_pairs(&dir, &budget, |scene, estimator| {
        MEDIA_SCENES.contains(&scene) && !media_exempt(scene, estimator)
    })
    .unwrap();
    println!(
        "{}",
        table::markdown(&rows, &budget, "cargo test --test checks mitsuba_suite")
    );
    for &scene in MEDIA_SCENES {
        if MEDIA_ESTIMATORS.iter().all(|e| media_exempt(scene, e)) {
            continue;
        }
        let Some(row) = rows.iter().find(|r| r.name == scene) else {
            regressions.push(format!("{scene}: missing (refused or renamed?)"));
            continue;
        };
        for &estimator in MEDIA_ESTIMATORS {
            if media_exempt(scene, estimator) {
                continue;
            }
            match row.outcomes.iter().find(|(e, _)| *e == estimator) {
                Some((_, o)) if o.passes() => {}
                Some((_, Outcome::NotJudged(why))) if !why.is_empty() => {}
                other => regressions.push(format!("{scene} with {estimator}: {other:?}")),
            }
        }
    }
    assert!(
        regressions.is_empty(),
        "scenes that passed no longer do:\n{}",
        regressions.join("\n")
    );
}

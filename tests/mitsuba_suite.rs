//! Mitsuba 3's render-test suite as a peer's test suite (`lt mitsuba-suite`), on
//! `../shared/mitsuba-render-tests` (relative to the repository root) at a small budget: the
//! table is produced, every refused scene names its reason, and every scene that passes today
//! keeps passing (`EXPECTED_PASSING`: add a scene when your work makes it pass). Without the
//! folder the test says it skipped; `LT_REQUIRE_MITSUBA_SUITE=1` (CI) makes that a failure.

use lt_experiments::verify::mitsuba_suite::{run_suite, table, Budget};
use std::path::PathBuf;
use std::time::Duration;

/// (scene, estimator) pairs that pass today.
const EXPECTED_PASSING: &[(&str, &str)] = &[
    ("floating_sphere/test_directional_direct", "pt"),
    ("floating_sphere/test_directional_direct", "bdpt"),
    ("orthographic_sensor/test_orthographic_path", "pt"),
    ("orthographic_sensor/test_orthographic_path", "bdpt"),
    // instancing passes too (99.9 % at 256 spp) but at this budget by 99.76 %, too close to the
    // 99.75 % line to pin without a larger budget; texture_interp likewise (99.94 % at 256 spp,
    // 99.61 % at 64: a few texel-edge pixels of high contrast).
];

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
    // Small: 64 spp in 16 passes, at most 2 s per estimator (CI time; the committed table is
    // rendered at the command's defaults).
    let budget = Budget {
        passes: 16,
        spp_per_pass: 4,
        time_per_estimator: Duration::from_secs(2),
        threads: 0,
        seed: 0,
    };
    let rows = run_suite(&dir, &budget).unwrap();
    let md = table::markdown(&rows, &budget, "cargo test --test mitsuba_suite");
    println!("{md}");
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
    assert!(
        regressions.is_empty(),
        "scenes that passed no longer do:\n{}",
        regressions.join("\n")
    );
}

//! `lt study techniques` at the test scale: it writes its files, its tallied images are the plain
//! renders bit for bit, and per integrator the techniques' means add up to the image mean —
//! within their interval over runs, and within rounding run by run (a technique the tally
//! missed, or counted twice, shows as its own share of the mean).

use lt_experiments::cache::Cache;
use lt_experiments::manifest::Manifest;
use lt_experiments::study::{self, Ctx, Scale};

#[test]
fn the_techniques_study_writes_its_files_and_its_techniques_add_up() {
    let dir = std::env::temp_dir().join(format!("lt-techniques-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let scale = Scale::named("test", &lt_tests::scenes_dir()).unwrap();
    let ctx = Ctx::with(
        scale,
        Cache::new(dir.join("cache")),
        Cache::new(dir.join("references")),
        dir.clone(),
        0,
        true,
        None,
    );
    study::run_named("techniques", &ctx).unwrap();
    let d = dir.join("techniques");
    let m = Manifest::read(&d).unwrap();
    assert!(d.join(&m.summary).is_file());
    for t in &m.tables {
        assert!(d.join(&t.csv).is_file(), "{}", t.csv);
    }
    assert!(m.tables.iter().any(|t| t.csv == "inefficiency.csv"));
    assert!(m
        .tables
        .iter()
        .any(|t| t.csv == "cornell-box-techniques.csv"));
    for f in &m.figures {
        for file in [&f.svg, &f.png] {
            assert!(
                std::fs::metadata(d.join(file)).is_ok_and(|m| m.len() > 0),
                "{file}"
            );
        }
    }
    let summary = std::fs::read_to_string(d.join("summary.md")).unwrap();
    assert!(
        summary.contains("20 of 20 bit for bit equal"),
        "tallied images differ from the plain renders"
    );
    let checks: Vec<serde_json::Value> =
        serde_json::from_str(&std::fs::read_to_string(d.join("checks.json")).unwrap()).unwrap();
    assert_eq!(checks.len(), 3, "bdpt, lvc-bdpt, vcm");
    for c in &checks {
        let f = |k: &str| c[k].as_f64().unwrap();
        let who = format!("{} {}", c["scene"], c["integrator"]);
        assert!(
            f("sum_lo") <= f("image") && f("image") <= f("sum_hi"),
            "{who}: image mean {} outside the techniques' [{}, {}]",
            f("image"),
            f("sum_lo"),
            f("sum_hi")
        );
        assert!(
            f("paired_rel") < 1e-5,
            "{who}: Σ means off by {}",
            f("paired_rel")
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

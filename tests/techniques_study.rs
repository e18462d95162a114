//! `lt study techniques` at the test scale: it writes its files, its tallied images are the plain
//! renders bit for bit, and per integrator the techniques' means add up to the image mean —
//! within their interval over runs, and within rounding run by run (a technique the tally
//! missed, or counted twice, shows as its own share of the mean).

use lt_experiments::cache::RenderCache;
use lt_experiments::manifest::Manifest;
use lt_experiments::study::{self, Scale, StudyContext};

#[test]
fn the_techniques_study_writes_its_files_and_its_techniques_add_up() {
    let dir = std::env::temp_dir().join(format!("lt-techniques-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let scale = Scale::named("test", &lt_tests::scenes_dir()).unwrap();
    let ctx = StudyContext::with(
        scale,
        RenderCache::new(dir.join("cache")),
        RenderCache::new(dir.join("references")),
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
    // Every tallied run (bdpt, lvc-bdpt, vcm and vcm correlation-aware at the test scale's 4
    // runs, plus the compared ones tally_run covers) equals its plain render.
    let (equal, total) = summary
        .split(" bit for bit equal")
        .next()
        .and_then(|head| {
            let words: Vec<&str> = head.split_whitespace().collect();
            let n = words.len();
            (n >= 3 && words[n - 2] == "of").then(|| {
                (
                    words[n - 3].parse::<u32>().ok(),
                    words[n - 1].parse::<u32>().ok(),
                )
            })
        })
        .and_then(|(a, b)| Some((a?, b?)))
        .expect("the summary counts the bit-equal images");
    assert!(
        equal == total && total >= 20,
        "tallied images differ from the plain renders: {equal} of {total} equal"
    );
    assert!(
        summary.contains("Efficiency-aware MIS against the fixed configurations"),
        "the efficiency-aware table is missing"
    );
    let rows = lt_experiments::report::findings::csv(&d.join("check.csv")).unwrap();
    assert_eq!(rows.len(), 3, "bdpt, lvc-bdpt, vcm");
    let parse = |t: &str| t.trim().parse::<f64>().unwrap_or(f64::NAN);
    for r in &rows {
        let who = format!("{} {}", r["scene"], r["integrator"]);
        // "estimate [lo, hi]" (3 significant digits, as printed).
        let sum = &r["Σ technique means"];
        let inner = sum.split('[').nth(1).unwrap().trim_end_matches(']');
        let mut it = inner.split(',').map(parse);
        let (lo, hi) = (it.next().unwrap(), it.next().unwrap());
        let image = parse(&r["image mean"]);
        assert!(
            lo <= image && image <= hi,
            "{who}: image mean {image} outside the techniques' [{lo}, {hi}]"
        );
        let paired = parse(&r["max |Σ − image| / image"]);
        assert!(paired < 1e-5, "{who}: Σ means off by {paired} within a run");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

//! Every study at the tiny test scale, asserted on its outputs: the files exist, unbiased
//! estimators' MSE slopes contain −1, fixed-radius photon mapping's bias² interval excludes 0
//! while pt's and bdpt's include it, PPM's variance slope contains −α, the lecture's exact bias
//! lies in its measured interval; and an interrupted `all` resumes without redoing finished
//! renders.
//!
//! The test scale's intervals are at 99.9 %: about 50 intervals are checked here, so the chance
//! that any one misses by luck is ≈ 5 % (Šidák), which the fixed seeds then pin either way.

use lt_experiments::cache::RenderCache;
use lt_experiments::study::{self, Scale, StudyContext};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

fn scenes() -> PathBuf {
    lt_tests::scenes_dir()
}

fn ctx(results: &Path, stop_after: Option<u64>) -> StudyContext {
    let scale = Scale::named("test", &scenes()).unwrap();
    StudyContext::with(
        scale,
        RenderCache::new(results.join("cache")),
        RenderCache::new(results.join("references")),
        results.to_path_buf(),
        0,
        true,
        stop_after,
    )
}

/// One full test-scale run of every study, made once for all tests here: its folder and the
/// number of renders it made.
fn full_run() -> &'static (PathBuf, u64) {
    static RUN: OnceLock<(PathBuf, u64)> = OnceLock::new();
    RUN.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("lt-studies-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let c = ctx(&dir, None);
        study::run_named("all", &c).unwrap();
        (dir, c.counts().0)
    })
}

fn results() -> &'static PathBuf {
    &full_run().0
}

/// A CSV as rows of column → value (the report's reader, which the findings use).
fn csv(path: &Path) -> Vec<HashMap<String, String>> {
    lt_experiments::report::findings::csv(path).unwrap_or_else(|e| panic!("{e}"))
}

/// "[lo, hi]" → (lo, hi).
fn interval(text: &str) -> (f64, f64) {
    let t = text.trim().trim_start_matches('[').trim_end_matches(']');
    let mut it = t
        .split(',')
        .map(|v| v.trim().parse::<f64>().unwrap_or(f64::NAN));
    (it.next().unwrap(), it.next().unwrap())
}

#[test]
fn every_study_writes_its_files() {
    let dir = results();
    for s in study::registry::names() {
        let d = dir.join(s);
        let m = lt_experiments::manifest::Manifest::read(&d).unwrap();
        assert!(d.join(&m.summary).is_file(), "{s}: summary");
        assert!(!m.tables.is_empty(), "{s}: no tables");
        for t in &m.tables {
            assert!(d.join(&t.csv).is_file(), "{s}: {}", t.csv);
        }
        for f in &m.figures {
            for file in [&f.svg, &f.png] {
                let len = std::fs::metadata(d.join(file))
                    .map(|m| m.len())
                    .unwrap_or(0);
                assert!(len > 0, "{s}: {file} missing or empty");
            }
        }
        for g in &m.galleries {
            for i in std::iter::once(&g.reference).chain(&g.items) {
                assert!(d.join(&i.image).is_file(), "{s}: {}", i.image);
            }
        }
    }
    assert!(
        !lt_experiments::manifest::Manifest::read(&dir.join("equal-time"))
            .unwrap()
            .galleries
            .is_empty()
    );
}

#[test]
fn unbiased_estimators_converge_at_slope_minus_one() {
    let rows = csv(&results().join("convergence/slopes.csv"));
    let mut checked = 0;
    for r in rows
        .iter()
        .filter(|r| r["scene"] == "cornell-box" && r["kind"] == "unbiased")
    {
        let (lo, hi) = interval(&r["CI vs N"]);
        assert!(
            lo <= -1.0 && -1.0 <= hi,
            "{} on cornell-box: MSE slope {} with interval [{lo}, {hi}] excludes −1",
            r["integrator"],
            r["slope vs N"]
        );
        // Containing −1 means something only if the interval also tells the slope from 0.
        assert!(
            hi < 0.0,
            "{}: interval [{lo}, {hi}] does not tell convergence from none",
            r["integrator"]
        );
        checked += 1;
    }
    // Every unbiased integrator of the registry has its row (lvc-bdpt joined without a new line).
    let unbiased = lt_integrators::INTEGRATORS
        .iter()
        .filter(|i| i.kind == lt_integrators::Kind::Unbiased)
        .count();
    assert_eq!(checked, unbiased, "one row per unbiased integrator");
}

#[test]
fn fixed_radius_pm_is_biased_and_pt_is_not() {
    // At the test scale (16 runs of 16 passes) the unbiased claims hold and pm's bias² estimate
    // stands above 0; that it excludes 0 is asserted on the committed full scale
    // (`committed_unbiased_consistent_and_findings_hold_within_their_intervals`).
    let rows = csv(&results().join("unbiased-vs-consistent/claims.csv"));
    let get = |label: &str| {
        rows.iter()
            .find(|r| r["estimator"] == label)
            .unwrap_or_else(|| panic!("no row {label}"))
    };
    for unbiased in ["pt", "bdpt", "light"] {
        assert_eq!(
            get(unbiased)["holds"],
            "yes",
            "{unbiased}: {:?}",
            get(unbiased)
        );
    }
    let pm = get("pm (fixed radius)");
    for column in ["bias² at N = 1", "bias² at largest N"] {
        let estimate: f64 = pm[column].split(' ').next().unwrap().parse().unwrap();
        assert!(estimate > 0.0, "pm {column}: {pm:?}");
    }
    // The lecture's example: the exact bias lies in every measured interval.
    for r in csv(&results().join("unbiased-vs-consistent/lecture.csv")) {
        assert_eq!(r["exact inside"], "yes", "lecture N = {}: {:?}", r["N"], r);
    }
}

#[test]
fn ppm_variance_falls_as_n_to_the_minus_alpha() {
    let rows = csv(&results().join("radius-shrinkage/rates.csv"));
    let mut checked = 0;
    for r in rows
        .iter()
        .filter(|r| r["integrator"] == "ppm" && r["quantity"] == "variance at fixed points")
    {
        let (lo, hi) = interval(&r["CI"]);
        let predicted: f64 = r["predicted at these N"].parse().unwrap();
        assert!(
            lo <= predicted && predicted <= hi,
            "ppm α = {}: variance slope {} in [{lo}, {hi}], predicted {predicted}",
            r["α"],
            r["measured"]
        );
        checked += 1;
    }
    assert_eq!(checked, 3);
    for r in rows.iter().filter(|r| r["quantity"] == "r²") {
        assert_eq!(r["inside"], "yes", "{:?}", r);
    }
}

/// Interrupt `all` after some renders, rerun it, and count: the rerun makes exactly the renders
/// the first run did not finish.
#[test]
fn an_interrupted_run_resumes_without_redoing_finished_renders() {
    // One study (convergence, the one with the most renders at the test scale) rather than
    // `all`: the resume logic is the cache's and the same for every study, and `all` already
    // runs once for the other tests of this file.
    let dir = std::env::temp_dir().join(format!("lt-studies-resume-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let first = ctx(&dir, Some(40));
    let err = study::run_named("convergence", &first).unwrap_err();
    assert!(err.contains("stopped after 40"), "{err}");
    assert_eq!(first.counts().0, 40);
    let second = ctx(&dir, None);
    study::run_named("convergence", &second).unwrap();
    let (made, found) = second.counts();
    let third = ctx(&dir, None);
    study::run_named("convergence", &third).unwrap();
    let (remade, total) = third.counts();
    eprintln!("resume: the study has {total} renders; interrupted after 40, the rerun made {made} and found {found}");
    assert_eq!(remade, 0, "a finished run redoes nothing");
    assert_eq!(
        made + 40,
        total,
        "the rerun makes exactly what the first run did not finish"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The committed report's claims hold against its own numbers: in each committed `rates.csv`
/// (`radius-shrinkage` and `radius-shrinkage-plane`) every row whose `inside` says "yes" or "no"
/// has the rate it compares with (K&Z's at these N where given, else the asymptotic one) inside,
/// or outside, its own interval as claimed; so does `inside asymptotic` with the asymptotic rate
/// where the table has that column. Reads the committed CSVs only, so it is fast.
#[test]
fn committed_radius_shrinkage_claims_hold_within_their_intervals() {
    let root = lt_tests::scenes_dir().parent().unwrap().to_path_buf();
    for study in [
        "radius-shrinkage",
        "radius-shrinkage-plane",
        "radius-shrinkage-media",
        "unbiased-vs-consistent",
    ] {
        let path = root.join(format!("results/{study}/rates.csv"));
        let checked = check_claims(&path);
        assert!(checked > 0, "{}: no claims found", path.display());
    }
    media_study_holds_its_exact_predictions(&root.join("results/radius-shrinkage-media"));
    // The plane study's exact check, as committed: every measured bias² and variance holds the
    // exact model's value, and bias² at N = 1 is told from 0 (a bias is measured, not noise).
    // (At the test scale, 16 runs, bias² at N = 1 is only ~4 standard errors: that part is
    // asserted here, on the committed scale.)
    let path = root.join("results/radius-shrinkage-plane/exact.csv");
    let rows = csv(&path);
    assert!(!rows.is_empty(), "{}: empty", path.display());
    for r in &rows {
        let (lo, hi) = interval(&r["CI"]);
        let exact: f64 = r["exact"].parse().unwrap();
        assert_eq!(
            lo <= exact && exact <= hi,
            r["inside"] == "yes",
            "{}: claim does not match its interval: {r:?}",
            path.display()
        );
        assert_eq!(r["inside"], "yes", "{}: {r:?}", path.display());
        if r["N"] == "1" && r["quantity"] == "bias²" {
            assert!(
                lo > 0.0,
                "{}: bias² at N = 1 includes 0: {r:?}",
                path.display()
            );
        }
    }
}

/// The committed radius-shrinkage-media study (issue 45 item 3): pp3d's, pb2d's and bb1d's
/// bias², variance and MSE slopes inside their exact predictions at these N at four α each
/// (`rates.csv`; a bias² the runs cannot resolve is marked so), and at every N the measured bias² and variance hold their exact values within
/// t · s.e. (`per-n.csv`; the jackknife over the committed 16 runs: Student t with 15 dof, Šidák
/// over every comparison at a 1 % false-alarm rate), so each kernel's level is held, not only its
/// slope. A pb2d kernel normalisation × 1.05 fails both (results/points-beams.md).
fn media_study_holds_its_exact_predictions(dir: &Path) {
    let rates = csv(&dir.join("rates.csv"));
    for e in ["pp3d", "pb2d", "bb1d"] {
        let mine: Vec<_> = rates.iter().filter(|r| r["integrator"] == e).collect();
        let alphas: std::collections::BTreeSet<&str> =
            mine.iter().map(|r| r["α"].as_str()).collect();
        assert!(alphas.len() >= 4, "{e}: only {} values of α", alphas.len());
        for r in mine {
            // `unresolved`: a bias² below the runs' noise at the last N (the study decides it
            // from its exact curves); its values are held N by N below.
            let unresolved = r["quantity"] == "bias²" && r["inside"] == "unresolved";
            assert!(
                r["inside"] == "yes" || unresolved,
                "{}: {r:?}",
                dir.display()
            );
        }
    }
    let per_n = csv(&dir.join("per-n.csv"));
    let comparisons = 2 * per_n.len();
    let per_test = lt_core::testing::sidak(0.01, comparisons);
    let t = lt_estimators::bias_variance::t_quantile(1.0 - per_test, 15.0);
    let num = |r: &HashMap<String, String>, k: &str| -> f64 {
        r[k].parse().unwrap_or_else(|e| panic!("{k}: {e}: {r:?}"))
    };
    for r in &per_n {
        for (q, se, exact) in [
            ("bias²", "± bias²", "exact bias²"),
            ("variance", "± variance", "exact variance"),
        ] {
            let (m, s, x) = (num(r, q), num(r, se), num(r, exact));
            assert!(
                (m - x).abs() <= t * s,
                "{}: {} α {} N {}: {q} {m} ± {s}, exact {x} (t {t})",
                dir.display(),
                r["integrator"],
                r["α"],
                r["N"]
            );
        }
    }
}

/// The committed unbiased-vs-consistent study and the report's findings, against their own
/// intervals: each family claim recomputed from bias-variance.csv (unbiased: 0 inside at every N;
/// consistent: bias² at N = 1 above 0; fixed radius: above 0 at the first and last N) and held
/// to what claims.csv says, and each must hold; the exact bias² inside its interval wherever the
/// table gives one; and the rates the findings quote inside their intervals (pt, bdpt, light: MSE
/// slope −1; sppm, vcm: −2/3; ppm's bias² slope: the exact one at these N; the plane study's α =
/// 2/3 MSE slopes: −2/3). Planting a number outside its interval in any of these CSVs fails it.
#[test]
fn committed_unbiased_consistent_and_findings_hold_within_their_intervals() {
    let root = lt_tests::scenes_dir().parent().unwrap().to_path_buf();
    let dir = root.join("results/unbiased-vs-consistent");
    let rows = csv(&dir.join("bias-variance.csv"));
    let claims = csv(&dir.join("claims.csv"));
    assert!(!claims.is_empty() && !rows.is_empty());
    let num = |r: &HashMap<String, String>, k: &str| -> f64 {
        r[k].parse().unwrap_or_else(|e| panic!("{k}: {e}: {r:?}"))
    };
    for c in &claims {
        let mine: Vec<&HashMap<String, String>> = rows
            .iter()
            .filter(|r| r["estimator"] == c["estimator"])
            .collect();
        assert!(!mine.is_empty(), "no rows for {}", c["estimator"]);
        let above = |r: &HashMap<String, String>| num(r, "bias2_lo") > 0.0;
        let holds = match c["family"].as_str() {
            "unbiased" => mine
                .iter()
                .all(|r| num(r, "bias2_lo") <= 0.0 && 0.0 <= num(r, "bias2_hi")),
            "consistent" => above(mine[0]),
            "fixed radius" => above(mine[0]) && above(mine[mine.len() - 1]),
            f => panic!("unknown family {f}"),
        };
        assert_eq!(
            holds,
            c["holds"] == "yes",
            "claim does not match its intervals: {c:?}"
        );
        assert!(holds, "the report claims it: {c:?}");
    }
    for r in &rows {
        if let Ok(e) = r["exact_bias2"].parse::<f64>() {
            assert!(
                num(r, "bias2_lo") <= e && e <= num(r, "bias2_hi"),
                "exact bias² outside its interval: {r:?}"
            );
        }
    }
    // The numbers the findings quote, each inside its own interval as the report says.
    let rates = csv(&dir.join("rates.csv"));
    let plane = csv(&root.join("results/radius-shrinkage-plane/rates.csv"));
    let held = |table: &[HashMap<String, String>], who: &str, alpha: &str, q: &str, rate: f64| {
        let r = table
            .iter()
            .find(|r| r["integrator"] == who && r["α"] == alpha && r["quantity"] == q)
            .unwrap_or_else(|| panic!("no row {who} {alpha} {q}"));
        let (lo, hi) = interval(&r["CI"]);
        assert!(
            lo <= rate && rate <= hi,
            "findings: {who} α = {alpha} {q} slope [{lo}, {hi}] does not hold {rate}"
        );
    };
    for who in ["pt", "bdpt", "light"] {
        held(&rates, who, "—", "MSE", -1.0);
    }
    for who in ["sppm", "vcm"] {
        held(&rates, who, "2/3", "MSE", -2.0 / 3.0);
    }
    let ppm_b2 = rates
        .iter()
        .find(|r| r["integrator"] == "ppm" && r["quantity"] == "bias²")
        .unwrap();
    held(
        &rates,
        "ppm",
        "2/3",
        "bias²",
        ppm_b2["predicted at these N"].parse().unwrap(),
    );
    for who in ["ppm", "sppm (photon part)", "vcm (merging)"] {
        held(&plane, who, "2/3", "MSE", -2.0 / 3.0);
    }
    // The findings section is built from these CSVs (the fourth from convergence/slopes.csv, the
    // fifth from media-figures/verdicts.csv).
    let f = lt_experiments::report::findings::findings(&root.join("results")).unwrap();
    assert_eq!(f.len(), 5);
}

/// The committed convergence slopes (results/convergence/slopes.csv) against their own
/// intervals: a row reported as a slope has an interval narrower than 0.2 (recomputed from its
/// bounds, and its width column agrees) that excludes 0, and its `inside` says truly whether the
/// interval holds the expected rate; a row whose interval is 0.2 or wider is never reported as a
/// slope but as "no slope" with a reason. Every unbiased slope the findings quote on cornell-box
/// holds −1. Reads the committed CSV only, so it is fast.
#[test]
fn committed_convergence_slopes_hold_within_their_intervals() {
    let root = lt_tests::scenes_dir().parent().unwrap().to_path_buf();
    let path = root.join("results/convergence/slopes.csv");
    let rows = csv(&path);
    assert!(!rows.is_empty(), "{}: empty", path.display());
    let mut slopes = 0;
    for r in &rows {
        let ci = r["CI vs N"].as_str();
        let verdict = r["verdict"].as_str();
        if !ci.starts_with('[') {
            assert!(
                verdict.starts_with("no slope: "),
                "{}: {r:?}",
                path.display()
            );
            continue;
        }
        let (lo, hi) = interval(ci);
        let width = hi - lo;
        // The CSV prints 3 significant digits: a width this near 0.2 is decided by digits it
        // lacks, so either verdict stands.
        let borderline = (width - 0.2).abs() < 2e-3;
        if verdict == "slope" {
            assert!(width < 0.2 || borderline, "wide slope: {r:?}");
            let stated: f64 = r["width"].parse().unwrap();
            assert!((stated - width).abs() < 2e-3, "width column: {r:?}");
            assert!(hi < 0.0, "a slope not told from 0: {r:?}");
            let slope: f64 = r["slope vs N"].parse().unwrap();
            assert!(
                lo <= slope && slope <= hi,
                "slope outside its interval: {r:?}"
            );
            if let Ok(e) = r["expected"].parse::<f64>() {
                let near = |b: f64| (e - b).abs() <= 5e-4;
                if !(near(lo) || near(hi)) {
                    let inside = lo <= e && e <= hi;
                    assert_eq!(inside, r["inside"] == "yes", "inside claim: {r:?}");
                }
            } else {
                assert_eq!(r["inside"], "—", "{r:?}");
            }
            slopes += 1;
        } else if width >= 0.2 && !borderline {
            assert!(verdict.starts_with("no slope: "), "{r:?}");
            assert_eq!(
                r["slope vs N"], "no slope",
                "a wide interval shown as a slope: {r:?}"
            );
        }
    }
    assert!(slopes > 0, "{}: no slopes", path.display());
    // What the findings quote: the unbiased estimators on the plain box converge as 1/N.
    for who in ["pt", "bdpt"] {
        let r = rows
            .iter()
            .find(|r| r["scene"] == "cornell-box" && r["integrator"] == who)
            .unwrap_or_else(|| panic!("no cornell-box {who}"));
        assert_eq!(r["verdict"], "slope", "{r:?}");
        assert_eq!(r["inside"], "yes", "{r:?}");
    }
}

/// Checks every yes/no claim of a rates table against its own interval; returns how many.
fn check_claims(path: &Path) -> usize {
    let rows = csv(path);
    let mut checked = 0;
    for r in &rows {
        // r² rows state a schedule match, not an interval: nothing to recompute here.
        if !r["CI"].starts_with('[') {
            continue;
        }
        let (lo, hi) = interval(&r["CI"]);
        let at_n = r["predicted at these N"].parse::<f64>();
        let asymptotic = r["predicted"].parse::<f64>();
        let mut claims = vec![("inside", at_n.clone().or(asymptotic.clone()))];
        if r.contains_key("inside asymptotic") {
            claims.push(("inside asymptotic", asymptotic));
        }
        // The media study keeps K&Z's model at these N beside its exact prediction.
        if r.contains_key("inside K&Z at these N") {
            claims.push(("inside K&Z at these N", r["K&Z at these N"].parse::<f64>()));
        }
        for (column, predicted) in claims {
            let claim = r[column].as_str();
            if claim != "yes" && claim != "no" {
                continue;
            }
            let predicted = predicted.unwrap_or_else(|e| panic!("{}: {e}: {r:?}", path.display()));
            // The table prints 3 decimals: a rate that equal to a printed bound is decided by
            // digits the CSV does not hold, so either claim stands.
            let near = |b: f64| (predicted - b).abs() <= 5e-4 * b.abs().max(1.0);
            if near(lo) || near(hi) {
                continue;
            }
            let inside = lo <= predicted && predicted <= hi;
            assert_eq!(
                inside,
                claim == "yes",
                "{}: {} α = {} {}: claims {column} = {claim}, but {predicted} vs [{lo}, {hi}]",
                path.display(),
                r["integrator"],
                r["α"],
                r["quantity"]
            );
            checked += 1;
        }
    }
    checked
}

/// The plane study at the test scale: the measured bias² and variance agree with the exact model
/// (disc averages by quadrature) at every α and N — normalisation, radius schedule, kernel and the
/// recomputed visible points all at once — and every slope claim its table makes holds.
#[test]
fn plane_study_matches_its_exact_model() {
    let dir = std::env::temp_dir().join(format!("lt-studies-plane-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let c = ctx(&dir, None);
    study::run_named(study::radius_plane::NAME, &c).unwrap();
    let d = dir.join(study::radius_plane::NAME);
    let rows = csv(&d.join("exact.csv"));
    assert_eq!(
        rows.len(),
        2 * 5 * 7 * 2,
        "(ppm, vcm's merging) × 5 α × 7 snapshots × (bias², variance)"
    );
    for r in &rows {
        assert_eq!(r["inside"], "yes", "{r:?}");
    }
    assert!(check_claims(&d.join("rates.csv")) > 0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The committed figures (results/figures/, `lt study figures`): every mean lies in its own
/// interval, and each verdict the summary states is the one its CSV's intervals give — figure 1
/// "holds" exactly when bdpt's relMSE and FLIP intervals lie below pt's and "holds to the eye"
/// when only its FLIP interval does; figure 2 calls the power
/// heuristic "within the better one's interval or below it" exactly on the scenes where its
/// relMSE interval reaches down to the better single technique's. Reads committed files only.
#[test]
fn committed_figures_verdicts_follow_their_intervals() {
    let root = lt_tests::scenes_dir().parent().unwrap().to_path_buf();
    let dir = root.join("results/figures");
    let summary = std::fs::read_to_string(dir.join("summary.md")).unwrap();
    let get = |r: &HashMap<String, String>, c: &str| -> f64 {
        r[c].parse().unwrap_or_else(|e| panic!("{c}: {e}: {r:?}"))
    };
    let bidir = csv(&dir.join("bidir.csv"));
    let mis = csv(&dir.join("mis.csv"));
    for r in bidir.iter().chain(&mis) {
        for m in ["relMSE", "FLIP"] {
            let (v, lo, hi) = (
                get(r, m),
                get(r, &format!("{m} lo")),
                get(r, &format!("{m} hi")),
            );
            assert!(lo <= v && v <= hi, "{m} outside its interval: {r:?}");
        }
    }
    let row = |who: &str| bidir.iter().find(|r| r["integrator"] == who).unwrap();
    let (pt, bdpt) = (row("pt"), row("bdpt"));
    let rel_apart = get(bdpt, "relMSE hi") < get(pt, "relMSE lo");
    let flip_apart = get(bdpt, "FLIP hi") < get(pt, "FLIP lo");
    let holds = summary.contains("— holds: at equal CPU");
    let to_the_eye = summary.contains("— holds to the eye: at equal CPU");
    assert_eq!(holds, rel_apart && flip_apart, "figure 1's verdict");
    assert_eq!(to_the_eye, flip_apart && !rel_apart, "figure 1's verdict");
    let mut robust = 0;
    let mut scenes: Vec<&str> = mis.iter().map(|r| r["scene"].as_str()).collect();
    scenes.dedup();
    for s in &scenes {
        let t = |name: &str| {
            mis.iter()
                .find(|r| r["scene"] == *s && r["technique"] == name)
                .unwrap_or_else(|| panic!("{s}: no {name}"))
        };
        let (bsdf, light) = (t("BSDF sampling only"), t("light sampling only"));
        let better = if get(bsdf, "relMSE") <= get(light, "relMSE") {
            bsdf
        } else {
            light
        };
        if get(t("MIS, power heuristic"), "relMSE lo") <= get(better, "relMSE hi") {
            robust += 1;
        }
    }
    assert_eq!(
        scenes.len(),
        2,
        "figure 2's scenes: Bitterli's veach-mis and ours"
    );
    assert_eq!(
        summary
            .matches(", within the better one's interval or below it")
            .count(),
        robust,
        "figure 2's verdicts"
    );
    figure_3_verdict_follows_its_intervals(&dir, &summary);
    figure_4_verdicts_follow_their_intervals(&dir, &summary);
}

fn cell(r: &HashMap<String, String>, c: &str) -> f64 {
    r[c].parse().unwrap_or_else(|e| panic!("{c}: {e}: {r:?}"))
}

/// Every (m, m lo, m hi) of `rows` holds its mean inside its interval.
fn means_inside(rows: &[HashMap<String, String>], measures: &[&str]) {
    for r in rows {
        for m in measures {
            let (v, lo, hi) = (
                cell(r, m),
                cell(r, &format!("{m} lo")),
                cell(r, &format!("{m} hi")),
            );
            assert!(lo <= v && v <= hi, "{m} outside its interval: {r:?}");
        }
    }
}

/// Figure 3 (ppm.csv), per scene: the summary says "holds" exactly when, on the caustic crop,
/// the better consistent estimator's relMSE and FLIP intervals both lie below the better
/// unbiased one's, "holds to the eye" when only FLIP's do, "is not shown" otherwise.
fn figure_3_verdict_follows_its_intervals(dir: &std::path::Path, summary: &str) {
    let rows = csv(&dir.join("ppm.csv"));
    means_inside(&rows, &["relMSE", "FLIP", "caustic relMSE", "caustic FLIP"]);
    let mut scenes: Vec<&str> = rows.iter().map(|r| r["scene"].as_str()).collect();
    scenes.dedup();
    assert_eq!(
        scenes,
        ["caustic-sds", "cornell-point-caustic"],
        "figure 3's scenes"
    );
    let said_of = |verdict: &str| {
        // The verdict's phrase as the summary writes it for this scene.
        let mut n = 0;
        for s in &scenes {
            let head = format!("**Verdict (figure 3, {s}).**");
            let text = summary
                .split("\n\n")
                .find(|p| p.starts_with(&head))
                .unwrap_or_else(|| panic!("figure 3's verdict on {s} is missing"));
            n += usize::from(text.contains(&format!("converge — {verdict}")));
        }
        n
    };
    let mut expect = [0usize; 3];
    for s in &scenes {
        let best = |kind: &str| {
            rows.iter()
                .filter(|r| r["scene"] == *s && r["kind"] == kind)
                .min_by(|a, b| cell(a, "caustic relMSE").total_cmp(&cell(b, "caustic relMSE")))
                .unwrap_or_else(|| panic!("figure 3 has no {kind} estimator on {s}"))
        };
        let (c, u) = (best("consistent"), best("unbiased"));
        let below = |m: &str| cell(c, &format!("{m} hi")) < cell(u, &format!("{m} lo"));
        let (rel, flip) = (below("caustic relMSE"), below("caustic FLIP"));
        expect[if rel && flip {
            0
        } else if flip {
            1
        } else {
            2
        }] += 1;
    }
    let found = [
        said_of("holds: on the caustic"),
        said_of("holds to the eye"),
        said_of("is not shown at this budget"),
    ];
    assert_eq!(
        found, expect,
        "figure 3's verdicts (holds, to the eye, not shown)"
    );
}

/// Figure 4 (vcm.csv): per scene, vcm is "as good as the better" of bdpt and ppm when its
/// relMSE × CPU s interval reaches the better one's, "near the better" when it reaches below
/// the geometric mean of the two, "not near" otherwise; the summary's phrases and count follow.
fn figure_4_verdicts_follow_their_intervals(dir: &std::path::Path, summary: &str) {
    let rows = csv(&dir.join("vcm.csv"));
    let time_normalised = "relMSE × CPU s";
    means_inside(&rows, &["relMSE", "FLIP", time_normalised]);
    let mut scenes: Vec<&str> = rows.iter().map(|r| r["scene"].as_str()).collect();
    scenes.dedup();
    assert_eq!(scenes.len(), 3, "figure 4's scenes");
    let mut counts = [0usize; 3];
    for s in &scenes {
        let rel = |i: &str| {
            let r = rows
                .iter()
                .find(|r| r["scene"] == *s && r["integrator"] == i)
                .unwrap_or_else(|| panic!("{s}: no {i}"));
            (
                cell(r, time_normalised),
                cell(r, &format!("{time_normalised} lo")),
                cell(r, &format!("{time_normalised} hi")),
            )
        };
        let (b, p, v) = (rel("bdpt"), rel("ppm"), rel("vcm"));
        let (better, worse) = if b.0 <= p.0 { (b, p) } else { (p, b) };
        let k = if v.1 <= better.2 {
            0
        } else if v.1 <= (better.0 * worse.0).sqrt() {
            1
        } else {
            2
        };
        counts[k] += 1;
    }
    let phrases = [
        ", as good as the better",
        ", near the better (below the geometric mean)",
        ", not near the better",
    ];
    for (p, n) in phrases.iter().zip(counts) {
        assert_eq!(summary.matches(p).count(), n, "figure 4's verdicts: {p}");
    }
    assert!(
        summary.contains(&format!("holds on {} of 3 scenes", counts[0] + counts[1])),
        "figure 4's count"
    );
}

/// The committed slides (results/slides/, `lt study slides`): every mean lies in its interval,
/// and each verdict says "holds" exactly when its relMSE intervals lie apart in the claim's
/// direction (`figures::slides::verdicts`), "is not shown" otherwise.
#[test]
fn committed_slides_verdicts_follow_their_intervals() {
    let root = lt_tests::scenes_dir().parent().unwrap().to_path_buf();
    let dir = root.join("results/slides");
    let summary = std::fs::read_to_string(dir.join("summary.md")).unwrap();
    let rows = csv(&dir.join("slides.csv"));
    means_inside(&rows, &["relMSE", "FLIP"]);
    let rel = |set: &str, scene: &str, i: &str, n: &str| {
        let r = rows
            .iter()
            .find(|r| {
                r["set"] == set && r["scene"] == scene && r["integrator"] == i && r["passes"] == n
            })
            .unwrap_or_else(|| panic!("no slide {set} {scene} {i} {n}"));
        (cell(r, "relMSE lo"), cell(r, "relMSE hi"))
    };
    // (a below b): a's interval lies below b's.
    let below = |a: (f64, f64), b: (f64, f64)| a.1 < b.0;
    let counts = |set: &str, scene: &str| -> Vec<String> {
        let mut v: Vec<String> = rows
            .iter()
            .filter(|r| r["set"] == set && r["scene"] == scene)
            .map(|r| r["passes"].clone())
            .collect();
        v.dedup();
        v.sort_by_key(|n| n.parse::<u32>().unwrap());
        v.dedup();
        v
    };
    let seed = counts("seed", "cornell-box");
    let top = counts("sppm", "caustic-sds").pop().unwrap();
    let pt: Vec<_> = ["cornell-box", "cornell-small-light", "cornell-glass-light"]
        .iter()
        .map(|s| rel("seed", s, "pt", &seed[0]))
        .collect();
    let bdpt_wins = |scene: &str| {
        seed.iter()
            .all(|n| below(rel("seed", scene, "bdpt", n), rel("seed", scene, "pt", n)))
    };
    let expected = [
        (
            "pt's difficulty",
            below(pt[0], pt[1]) && below(pt[1], pt[2]),
        ),
        ("cornell-glass-light", bdpt_wins("cornell-glass-light")),
        ("veach-door", bdpt_wins("veach-door")),
        (
            "caustic-sds",
            below(
                rel("sppm", "caustic-sds", "sppm", &top),
                rel("sppm", "caustic-sds", "bdpt", &top),
            ),
        ),
        (
            "cornell-box",
            below(
                rel("sppm", "cornell-box", "bdpt", &top),
                rel("sppm", "cornell-box", "sppm", &top),
            ),
        ),
    ];
    for (title, holds) in expected {
        let head = format!("**Verdict (slides, {title}).**");
        let text = summary
            .split("\n\n")
            .find(|p| p.starts_with(&head))
            .unwrap_or_else(|| panic!("the slides' verdict on {title} is missing"));
        assert_eq!(
            text.contains("— holds:"),
            holds,
            "slides' verdict on {title}"
        );
        assert_eq!(
            text.contains("— is not shown:"),
            !holds,
            "slides' verdict on {title}"
        );
    }
}

//! `lt mis-check` as a test: on every shipped scene, pt's and bdpt's MIS weights (power and
//! balance) agree with the from-scratch oracle of `lt_core::path`, and the weights each integrator's
//! own code gives a path's techniques sum to one. Plus proof that the check can fail.

use lt_core::path::Heuristic;
use lt_experiments::verify::mis_check::pt_bdpt::{
    check_records, check_scene, collect, prepare_scene, Options, Report, Which,
};
use lt_tests::{shipped_scene, shipped_scene_names};

/// Paths per (length, technique): small, so the whole file runs in seconds.
const PATHS: usize = 150;

fn options(scene: &lt_core::Scene, which: Which, h: Heuristic) -> Options {
    let mut o = Options::new(scene, which);
    o.heuristic = h;
    o.paths = PATHS;
    o.max_passes = 300;
    o.seed = 7;
    o
}

fn check_all(which: Which, h: Heuristic) {
    let names = shipped_scene_names();
    assert!(
        names.len() >= 10,
        "expected the shipped scenes, found {names:?}"
    );
    let mut failed = Vec::new();
    for name in &names {
        let mut scene = shipped_scene(name, None);
        let opts = options(&scene, which, h);
        let report = check_scene(&mut scene, &opts, name);
        assert!(report.checked() > 0, "{name}: no paths recorded\n{report}");
        if !report.passed() {
            failed.push(format!("{report}"));
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

#[test]
fn bdpt_power_weights_match_the_oracle_on_every_shipped_scene() {
    check_all(Which::Bdpt, Heuristic::Power);
}

#[test]
fn bdpt_balance_weights_match_the_oracle_on_every_shipped_scene() {
    check_all(Which::Bdpt, Heuristic::Balance);
}

#[test]
fn pt_power_weights_match_the_oracle_on_every_shipped_scene() {
    check_all(Which::Pt, Heuristic::Power);
}

#[test]
fn pt_balance_weights_match_the_oracle_on_every_shipped_scene() {
    check_all(Which::Pt, Heuristic::Balance);
}

/// Records of cornell-box by `which`, with the options that made them.
fn cornell_records(
    which: Which,
) -> (
    lt_core::Scene,
    Options,
    Vec<lt_experiments::verify::mis_check::pt_bdpt::Record>,
) {
    let mut scene = shipped_scene("cornell-box", None);
    let mut opts = options(&scene, which, Heuristic::Power);
    opts.paths = 50;
    opts.max_depth = 4;
    prepare_scene(&mut scene, &opts);
    let (c, _) = collect(&scene, &opts);
    (scene, opts, c.records)
}

fn check(
    scene: &lt_core::Scene,
    opts: &Options,
    records: &[lt_experiments::verify::mis_check::pt_bdpt::Record],
) -> Report {
    check_records(scene, records, opts, 0, 0, "cornell-box")
}

/// The tolerance check (a) derives for one record.
fn tolerance_of(
    scene: &lt_core::Scene,
    opts: &Options,
    r: &lt_experiments::verify::mis_check::pt_bdpt::Record,
) -> f64 {
    let report = check(scene, opts, std::slice::from_ref(r));
    report
        .rows
        .iter()
        .flat_map(|row| row.allowed.iter().copied())
        .fold(0.0, f64::max)
}

/// Plants a relative error `by` in the weight of the first path whose weight is neither 0 nor 1
/// and whose derived tolerance is below `by / margin`, and asserts that (a) fails it alone.
fn planted_weight_error_fails(which: Which, by: f64, margin: f64) {
    let (scene, opts, mut records) = cornell_records(which);
    assert!(check(&scene, &opts, &records).passed());
    let i = records
        .iter()
        .position(|r| {
            r.weight > 1e-3 && r.weight < 0.999 && tolerance_of(&scene, &opts, r) < by / margin
        })
        .unwrap_or_else(|| {
            panic!("{which:?}: no path with 0 < w < 1 and tolerance < {by}/{margin}")
        });
    records[i].weight *= 1.0 + by;
    let report = check(&scene, &opts, &records);
    assert!(!report.passed(), "{report}");
    assert_eq!(report.failures(), 1, "{report}");
    let row = report.rows.iter().find(|r| r.k == records[i].k()).unwrap();
    assert_eq!(row.over, 1, "{report}");
    // bdpt's (b) replays its own code on the oracle's densities, which the perturbation does
    // not touch; pt's (b) sums the recorded weights, so it fails as well.
    let sum_fail = if which == Which::Pt { 1 } else { 0 };
    assert_eq!(row.sum_fail, sum_fail, "{report}");
}

#[test]
fn a_perturbed_weight_fails_check_a() {
    for which in [Which::Bdpt, Which::Pt] {
        planted_weight_error_fails(which, 1e-2, 10.0);
    }
}

#[test]
fn a_weight_off_by_3e4_fails_where_the_derived_tolerance_is_tighter() {
    // The fixed τ = 1e-3 this tolerance replaced let such an error pass on every path.
    for which in [Which::Bdpt, Which::Pt] {
        planted_weight_error_fails(which, 3e-4, 2.0);
    }
}

#[test]
fn a_perturbed_alternative_fails_check_b() {
    let (scene, opts, mut records) = cornell_records(Which::Pt);
    let i = records
        .iter()
        .position(|r| r.alternatives.iter().any(|a| a.1 > 1e-3))
        .expect("a pt path both techniques can make");
    records[i].alternatives[0].1 += 1e-4;
    let report = check(&scene, &opts, &records);
    assert!(!report.passed(), "{report}");
    let row = report.rows.iter().find(|r| r.k == records[i].k()).unwrap();
    assert_eq!((row.sum_fail, row.over), (1, 0), "{report}");
}

#[test]
fn weights_judged_under_the_other_heuristic_fail() {
    for which in [Which::Bdpt, Which::Pt] {
        let (scene, mut opts, records) = cornell_records(which);
        opts.heuristic = Heuristic::Balance;
        let report = check(&scene, &opts, &records);
        assert!(!report.passed(), "{report}");
        // bdpt's replay uses the heuristic it is told, so (b) still holds; (a) does not.
        assert!(report.rows.iter().all(|r| r.sum_fail == 0), "{report}");
        assert!(report.rows.iter().any(|r| r.over > 0), "{report}");
    }
}

#[test]
fn a_wrong_light_tracing_ratio_fails() {
    // bdpt run with M = 4N light paths, judged as if M = N: light tracing's weight is off.
    let mut scene = shipped_scene("cornell-box", None);
    let mut opts = options(&scene, Which::Bdpt, Heuristic::Power);
    opts.paths = 50;
    opts.max_depth = 3;
    opts.light_paths = Some(4 * 16 * 16);
    prepare_scene(&mut scene, &opts);
    let (c, _) = collect(&scene, &opts);
    assert!(check(&scene, &opts, &c.records).passed());
    opts.light_paths = None;
    let report = check(&scene, &opts, &c.records);
    assert!(!report.passed(), "{report}");
}

/// lvc-bdpt's options: N = `connections` cache vertices per camera vertex.
fn lvc_options(scene: &lt_core::Scene, h: Heuristic, connections: u32) -> Options {
    let mut o = options(scene, Which::Lvc, h);
    o.connections = connections;
    o
}

fn check_all_lvc(h: Heuristic, connections: u32) {
    let mut failed = Vec::new();
    for name in &shipped_scene_names() {
        let mut scene = shipped_scene(name, None);
        let opts = lvc_options(&scene, h, connections);
        let report = check_scene(&mut scene, &opts, name);
        assert!(report.checked() > 0, "{name}: no paths recorded\n{report}");
        if !report.passed() {
            failed.push(format!("{report}"));
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

#[test]
fn lvc_power_weights_match_the_oracle_on_every_shipped_scene() {
    check_all_lvc(Heuristic::Power, 4);
}

#[test]
fn lvc_balance_weights_match_the_oracle_on_every_shipped_scene() {
    check_all_lvc(Heuristic::Balance, 1);
}

#[test]
fn an_lvc_connection_count_without_n_fails() {
    // lvc-bdpt run with N = 4 connections, judged with n_conn = 1 / L̄ (N left out of the
    // count): every path some connection could make has the wrong weight.
    let mut scene = shipped_scene("cornell-box", None);
    let mut opts = lvc_options(&scene, Heuristic::Power, 4);
    opts.paths = 50;
    opts.max_depth = 4;
    prepare_scene(&mut scene, &opts);
    let (c, _) = collect(&scene, &opts);
    assert!(check(&scene, &opts, &c.records).passed());
    opts.connections = 1;
    let report = check(&scene, &opts, &c.records);
    assert!(!report.passed(), "{report}");
    // Paths of three segments or more have a connection technique; shorter ones none.
    assert!(
        report.rows.iter().all(|r| r.k >= 3 || r.over == 0),
        "{report}"
    );
    assert!(
        report.rows.iter().any(|r| r.k >= 3 && r.over > 0),
        "{report}"
    );
}

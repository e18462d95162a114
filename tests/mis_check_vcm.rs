//! `lt mis-check --integrator vcm|bpm` as a test: on every shipped scene the weights vcm and bpm
//! applied, by connection and by merging, agree with the from-scratch oracle
//! (`Densities::vcm_weight`, merges through `Densities::merged`), and their recursion replayed on
//! the oracle's densities sums to one over every connection and merging technique of each path.
//! Plus proof that the check can fail.

use lt_core::path::{Heuristic, Technique};
use lt_experiments::verify::mis_check::vcm_bpm::{
    check_records, check_scene, collect, prepare_scene, VcmOptions, VcmRecord, VcmReport,
};
use lt_tests::{shipped_scene, shipped_scene_names};

/// Paths per (length, technique) on each scene, and the passes allowed to fill them (as in
/// mis_check.rs: every class is still checked; 60 and 60 passes cost CI twice as much).
const PATHS: usize = 30;
const MAX_PASSES: u32 = 30;

/// The check's options, with correlation-aware MIS for merging (`lt_core::path::camis`) on or off.
fn options_with(
    scene: &lt_core::Scene,
    connections: bool,
    h: Heuristic,
    correlation_aware: bool,
) -> VcmOptions {
    let mut o = VcmOptions::new(scene, connections);
    o.correlation_aware = correlation_aware;
    o.heuristic = h;
    o.paths = PATHS;
    o.max_passes = MAX_PASSES;
    o.seed = 7;
    o
}

fn check_all(connections: bool, h: Heuristic) {
    check_all_with(connections, h, false);
}

fn check_all_with(connections: bool, h: Heuristic, correlation_aware: bool) {
    check_all_configured(connections, h, |o| o.correlation_aware = correlation_aware);
}

fn check_all_configured(connections: bool, h: Heuristic, configure: impl Fn(&mut VcmOptions)) {
    let mut failed = Vec::new();
    let (mut paths, mut merges) = (0, 0);
    for name in &shipped_scene_names() {
        let mut scene = shipped_scene(name, None);
        let mut opts = options_with(&scene, connections, h, false);
        configure(&mut opts);
        let report = check_scene(&mut scene, &opts, name);
        assert!(report.checked() > 0, "{name}: no paths recorded\n{report}");
        paths += report.checked();
        merges += report.merges();
        if !report.passed() {
            failed.push(format!("{report}"));
        }
    }
    eprintln!("{paths} paths checked, {merges} of them merged");
    assert!(
        merges > 1000,
        "too few merged paths to mean anything: {merges}"
    );
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

#[test]
fn vcm_power_weights_match_the_oracle_on_every_shipped_scene() {
    check_all(true, Heuristic::Power);
}

#[test]
fn vcm_balance_weights_match_the_oracle_on_every_shipped_scene() {
    check_all(true, Heuristic::Balance);
}

#[test]
fn bpm_power_weights_match_the_oracle_on_every_shipped_scene() {
    check_all(false, Heuristic::Power);
}

/// Correlation-aware MIS (`correlation_aware=true`): the same loop, the oracle's merges counted
/// η ρ_i times, and the integrators' full-path routine (`camis::weight`) summed over every
/// technique of each path.
#[test]
fn vcm_correlation_aware_power_weights_match_the_oracle_on_every_shipped_scene() {
    check_all_with(true, Heuristic::Power, true);
}

#[test]
fn vcm_correlation_aware_balance_weights_match_the_oracle_on_every_shipped_scene() {
    check_all_with(true, Heuristic::Balance, true);
}

#[test]
fn bpm_correlation_aware_power_weights_match_the_oracle_on_every_shipped_scene() {
    check_all_with(false, Heuristic::Power, true);
}

/// The counts efficiency-aware MIS (`eamis`) may choose, through vcm's full-path route: no
/// vertex connections, and merging only in a checkerboard of pixels — each path's η is its
/// pixel's (0 off the board), in the integrator's weights and in the oracle's. A planted error,
/// the mask ignored in the weights, failed 2155 of 18,500 paths on cornell-box (`lt mis-check
/// --integrator vcm --no-vertex-connections --checkerboard-merging --mis balance`).
#[test]
fn vcm_efficiency_aware_counts_match_the_oracle_on_every_shipped_scene() {
    check_all_configured(true, Heuristic::Balance, |o| {
        o.vertex_connections = false;
        o.checkerboard_merging = true;
    });
}

/// Records of cornell-box by vcm (or bpm), with the options that made them.
fn cornell_records(connections: bool) -> (lt_core::Scene, VcmOptions, Vec<VcmRecord>) {
    cornell_records_with(connections, false)
}

fn cornell_records_with(
    connections: bool,
    correlation_aware: bool,
) -> (lt_core::Scene, VcmOptions, Vec<VcmRecord>) {
    let mut scene = shipped_scene("cornell-box", None);
    let mut opts = options_with(&scene, connections, Heuristic::Power, correlation_aware);
    opts.paths = 30;
    opts.max_depth = 4;
    prepare_scene(&mut scene, &opts);
    let (c, _) = collect(&scene, &opts);
    (scene, opts, c.records)
}

fn check(scene: &lt_core::Scene, opts: &VcmOptions, records: &[VcmRecord]) -> VcmReport {
    check_records(scene, records, opts, 0, 0, "cornell-box")
}

fn is_merge(r: &VcmRecord) -> bool {
    matches!(r.technique, Technique::Merge(_))
}

#[test]
fn a_perturbed_merge_weight_fails() {
    for connections in [true, false] {
        let (scene, opts, mut records) = cornell_records(connections);
        assert!(check(&scene, &opts, &records).passed());
        let i = records
            .iter()
            .position(|r| is_merge(r) && r.weight > 1e-3 && r.weight < 0.999)
            .expect("a merged path with a weight strictly between 0 and 1");
        records[i].weight *= 1.01;
        let report = check(&scene, &opts, &records);
        assert_eq!(report.failures(), 1, "{report}");
    }
}

#[test]
fn a_wrong_merging_count_fails() {
    // η = N_VM π r² judged as twice (or without merging, η = 0) what the pass used: every
    // weight of a path that merging could also make is off.
    for scale in [2.0, 0.0] {
        let (scene, opts, mut records) = cornell_records(true);
        for r in &mut records {
            r.eta *= scale;
        }
        let report = check(&scene, &opts, &records);
        let merged_wrong = report.rows.iter().map(|r| r.over).sum::<usize>();
        assert!(merged_wrong > records.len() / 4, "η × {scale}: {report}");
    }
}

#[test]
fn connections_judged_as_bpm_fail() {
    // vcm's weights judged as if it only merged (bpm): the connection techniques' share is missing.
    let (scene, mut opts, records) = cornell_records(true);
    opts.connections = false;
    let report = check(&scene, &opts, &records);
    assert!(!report.passed(), "{report}");
}

#[test]
fn correlation_aware_weights_judged_as_independent_fail() {
    // vcm's and bpm's correlation-aware weights judged by the classic oracle (every merge η, no
    // ρ_i), and the classic weights by the correlation-aware one: the discount must show.
    for connections in [true, false] {
        for on in [true, false] {
            let (scene, mut opts, records) = cornell_records_with(connections, on);
            assert!(check(&scene, &opts, &records).passed());
            opts.correlation_aware = !on;
            let report = check(&scene, &opts, &records);
            let wrong = report.rows.iter().map(|r| r.over).sum::<usize>();
            assert!(
                wrong > records.len() / 20,
                "connections {connections}, judged with correlation {}: {wrong} of {}\n{report}",
                !on,
                records.len()
            );
        }
    }
}

//! `lt mis-check --integrator upbp` as a test: on every shipped media scene and on two surface
//! scenes, upbp's weights (connections, surface merges, PP3D, PB2D, BB1D and BP2D under one MIS;
//! power and balance) agree with the from-scratch oracle (`lt_core::path::volume_merging`) and
//! its own routine's weights over a path's techniques sum to one; with long photon beams
//! (`beams=long`) on two media scenes. Plus proof that the check fails on a merge density off by
//! 1 % (PB2D's, BB1D's, BP2D's, the surface merges'), on a technique missing from the sum, and on
//! long beams weighed as short ones.

use lt_core::path::{Heuristic, UpbpMode};
use lt_experiments::verify::mis_check::upbp::{
    check_records, check_scene, collect, prepare_scene, UpbpOptions, UpbpRecord,
};
use lt_tests::{shipped_media_scene_names, shipped_scene};

/// Paths per (length, technique), up to 5 segments, few passes: every oracle density through
/// media walks its segments, so the quota is small; a 1 % density error fails nearly every
/// merged path of a class (below: 195 of 195 BB1D paths at 20 per class), so 12 per class keep
/// the check's power with BB1D's class added at the same cost as three classes at 20.
fn options(scene: &lt_core::Scene, h: Heuristic) -> UpbpOptions {
    let mut o = UpbpOptions::new(scene);
    o.heuristic = h;
    o.paths = 12;
    o.max_depth = 5;
    o.max_passes = 6;
    o.seed = 7;
    o
}

#[test]
fn upbp_weights_match_the_oracle_on_every_media_scene() {
    let names = shipped_media_scene_names();
    assert!(
        names.len() >= 5,
        "expected the media scenes, found {names:?}"
    );
    weights_match_the_oracle(names.iter().map(String::as_str));
}

/// Records of hg-spot (a spot light in a medium ball: every kind of technique is common).
fn hg_spot_records() -> (lt_core::Scene, UpbpOptions, Vec<UpbpRecord>, (u32, usize)) {
    let mut scene = shipped_scene("media/hg-spot", None);
    let opts = options(&scene, Heuristic::Power);
    prepare_scene(&mut scene, &opts);
    let (c, passes) = collect(&scene, &opts).unwrap();
    (scene, opts, c.records, (passes, c.counts.too_long))
}

#[test]
fn a_planted_merge_density_error_fails() {
    let (scene, opts, records, counts) = hg_spot_records();
    let (report, _) = check_records(&scene, &records, &opts, counts, "hg-spot");
    assert!(report.passed(), "{report}");
    // PB2D's density ×1.01 in the oracle's sum against the integrator's.
    let mut beam = records.clone();
    for r in &mut beam {
        let set = r.set.as_mut().unwrap();
        set.beams_eta *= 1.01;
    }
    let (report, summary) = check_records(&scene, &beam, &opts, counts, "hg-spot");
    println!("PB2D ×1.01:\n{summary}");
    assert!(
        report.failures() > report.checked() / 4,
        "{report}{summary}"
    );
    // BB1D's density ×1.01 likewise.
    let mut beam_beam = records.clone();
    for r in &mut beam_beam {
        r.set.as_mut().unwrap().beam_beams_eta *= 1.01;
    }
    let (report, summary) = check_records(&scene, &beam_beam, &opts, counts, "hg-spot");
    println!("BB1D ×1.01:\n{summary}");
    assert!(
        report.failures() > report.checked() / 4,
        "{report}{summary}"
    );
    // BP2D's density ×1.01 likewise.
    let mut beam_point = records.clone();
    for r in &mut beam_point {
        r.set.as_mut().unwrap().beam_points_eta *= 1.01;
    }
    let (report, summary) = check_records(&scene, &beam_point, &opts, counts, "hg-spot");
    println!("BP2D ×1.01:\n{summary}");
    assert!(
        report.failures() > report.checked() / 4,
        "{report}{summary}"
    );
    // PP3D missing from the oracle's sum: the integrator's weights counted it.
    let mut missing = records;
    for r in &mut missing {
        r.set.as_mut().unwrap().points_eta = 0.0;
    }
    let (report, summary) = check_records(&scene, &missing, &opts, counts, "hg-spot");
    println!("PP3D missing:\n{summary}");
    assert!(
        report.failures() > report.checked() / 4,
        "{report}{summary}"
    );
}

/// Long photon beams (`beams=long`: BB1D's and BP2D's σ̂ᴸ the light flight's whole scattering
/// density) on hg-spot (one homogeneous medium) and grid-smoke (a heterogeneous one, where the
/// pieces' densities differ), both heuristics; and the check failing when the oracle weighs the
/// long beams' paths as short beams' (σ̂ᴸ the pass-probability ratio).
#[test]
fn upbp_long_beams_match_the_oracle_and_short_weights_fail() {
    let mut failed = Vec::new();
    for h in [Heuristic::Power, Heuristic::Balance] {
        for name in ["media/hg-spot", "media/grid-smoke"] {
            let mut scene = shipped_scene(name, None);
            let mut opts = options(&scene, h);
            opts.beams = "long".into();
            prepare_scene(&mut scene, &opts);
            let (c, passes) = collect(&scene, &opts).unwrap();
            let counts = (passes, c.counts.too_long);
            let (report, summary) = check_records(&scene, &c.records, &opts, counts, name);
            println!("{name} {h:?} long beams:\n{summary}");
            assert!(report.merges() > 0, "{name}: no merged paths\n{report}");
            if !report.passed() {
                failed.push(format!("{report}{summary}"));
            }
            if h == Heuristic::Power && name == "media/hg-spot" {
                let mut short = c.records;
                for r in &mut short {
                    r.set.as_mut().unwrap().long_beams = false;
                }
                let (report, summary) = check_records(&scene, &short, &opts, counts, name);
                println!("long beams weighed as short:\n{summary}");
                assert!(
                    report.failures() > report.checked() / 4,
                    "{report}{summary}"
                );
            }
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

/// SmallUPBP's modes on hg-spot (power): `compatible` (class ES*M(S|D|M)*L, full weights) and
/// `previous` (that class, only the techniques meeting at its first medium vertex) against the
/// oracle, which holds what each mode claims (Σw = 1 over the techniques it counts on the class,
/// 0 outside); and the check failing when each mode's records are weighed as the other's.
#[test]
fn upbp_compatible_and_previous_modes_match_the_oracle_and_swapped_fail() {
    let swapped = |mode: UpbpMode| match mode {
        UpbpMode::Previous => UpbpMode::Compatible,
        _ => UpbpMode::Previous,
    };
    for (name, mode) in [
        ("compatible", UpbpMode::Compatible),
        ("previous", UpbpMode::Previous),
    ] {
        let mut scene = shipped_scene("media/hg-spot", None);
        let mut opts = options(&scene, Heuristic::Power);
        opts.mode = name.into();
        prepare_scene(&mut scene, &opts);
        let (c, passes) = collect(&scene, &opts).unwrap();
        let counts = (passes, c.counts.too_long);
        assert!(c.records.iter().all(|r| r.set.unwrap().mode == mode));
        let (report, summary) = check_records(&scene, &c.records, &opts, counts, "hg-spot");
        println!("mode {name}:\n{summary}");
        assert!(report.merges() > 0 && report.passed(), "{report}{summary}");
        let mut planted = c.records;
        for r in &mut planted {
            r.set.as_mut().unwrap().mode = swapped(mode);
        }
        let (report, summary) = check_records(&scene, &planted, &opts, counts, "hg-spot");
        println!("mode {name} weighed as {:?}:\n{summary}", swapped(mode));
        assert!(
            report.failures() > report.checked() / 4,
            "{report}{summary}"
        );
    }
}

/// Without media upbp is vcm's technique set (connections and surface merges): its weights on
/// cornell-box (diffuse) and caustic-sds (specular chains) against the oracle, both heuristics,
/// and the check failing on cornell-box with the surface merges' density ×1.01 in the oracle.
#[test]
fn upbp_surface_merges_match_the_oracle_and_a_planted_error_fails() {
    weights_match_the_oracle(["cornell-box", "caustic-sds"]);
    let mut scene = shipped_scene("cornell-box", None);
    let opts = options(&scene, Heuristic::Power);
    prepare_scene(&mut scene, &opts);
    let (c, passes) = collect(&scene, &opts).unwrap();
    let counts = (passes, c.counts.too_long);
    let mut planted = c.records;
    for r in &mut planted {
        r.set.as_mut().unwrap().surface_eta *= 1.01;
    }
    let (report, summary) = check_records(&scene, &planted, &opts, counts, "cornell-box");
    println!("surface merges ×1.01:\n{summary}");
    assert!(
        report.failures() > report.checked() / 4,
        "{report}{summary}"
    );
}

/// Every applied weight of upbp on each named shipped scene against the oracle, both
/// heuristics; each scene must have merged paths among those checked.
fn weights_match_the_oracle<'a>(names: impl IntoIterator<Item = &'a str> + Clone) {
    let mut failed = Vec::new();
    for h in [Heuristic::Power, Heuristic::Balance] {
        for name in names.clone() {
            let mut scene = shipped_scene(name, None);
            let opts = options(&scene, h);
            let (report, summary) = check_scene(&mut scene, &opts, name).unwrap();
            println!("{name} {h:?}:\n{summary}");
            assert!(report.merges() > 0, "{name}: no merged paths\n{report}");
            if !report.passed() {
                failed.push(format!("{report}{summary}"));
            }
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

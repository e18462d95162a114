//! Exact partial renders and their merge (issue 14), in process.
//!
//! - The part of passes 0..N is bit for bit the accumulator `render` keeps, at 1 and 2 threads.
//! - Shards of uneven pass ranges, merged by Chan et al.'s update, equal the one-process
//!   accumulator within f64 rounding. The bound, per pixel and channel over N passes of largest
//!   magnitude x_max and largest deviation d_max from the mean: |Δmean| ≤ 8·N·ε·x_max and
//!   |ΔM2| ≤ 8·N·ε·x_max·d_max (Welford's own error bound, doubled as both sides err; the same
//!   bound `running.rs` holds its merge to). It is not bit-exact: Welford's and Chan's updates
//!   round differently. It is deterministic: parts given in any order merge to the same bits.
//! - Consistent estimators shard by runs: parts of runs merge into the mean and standard error
//!   across runs that `render_runs` (`--runs K`) gives.
//! - Parts of other scenes, parameters, seeds, run lengths, overlapping or missing ranges, and
//!   damaged files are refused with a message naming the file and the problem.

use lt_estimators::running::RunningImage;
use lt_estimators::Image;
use lt_experiments::cluster::partial::{merge, Partial, PartialJob, Span};
use lt_integrators::{make_integrator, render, render_runs, IntegratorParams, RenderOptions};
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

const RES: (u32, u32) = (16, 12);

fn scene_path(name: &str) -> PathBuf {
    lt_tests::scenes_dir().join(format!("{name}.toml"))
}

fn job(scene: &str, integrator: &str, params: &[(&str, &str)], span: Span) -> PartialJob {
    PartialJob {
        scene: scene_path(scene),
        resolution: Some(RES),
        integrator: integrator.into(),
        params: params
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
        span,
    }
}

fn passes(seed: u64, start: u32, end: u32) -> Span {
    Span::Passes { seed, start, end }
}

fn part(j: &PartialJob, threads: usize) -> Partial {
    let scene = j.load_scene().unwrap();
    j.render(&scene, threads, |_, _| {}).unwrap()
}

fn named(parts: Vec<Partial>) -> Vec<(PathBuf, Partial)> {
    parts
        .into_iter()
        .enumerate()
        .map(|(i, p)| (PathBuf::from(format!("part-{i}.ltp")), p))
        .collect()
}

/// `render`'s accumulator of passes 0..n, and every pass image.
fn one_process(j: &PartialJob, n: u32, threads: usize) -> (RunningImage, Vec<Image>) {
    let scene = j.load_scene().unwrap();
    let integ = make_integrator(&j.integrator, &scene, &IntegratorParams::new()).unwrap();
    let mut images = Vec::new();
    let opts = RenderOptions {
        passes: n,
        time_limit: None,
        seed: 1,
        threads,
    };
    let r = render(&scene, &integ, &opts, |rep| {
        images.push(rep.pass_image().unwrap().clone());
        ControlFlow::Continue(())
    })
    .unwrap();
    (r.per_pass.unwrap(), images)
}

#[test]
fn pass_range_from_zero_is_bitwise_the_render() {
    let j = job("cornell-box", "pt", &[], passes(1, 0, 12));
    let (reference, _) = one_process(&j, 12, 2);
    for threads in [1, 2] {
        let p = part(&j, threads);
        assert_eq!(p.acc, reference, "{threads} threads");
        assert_eq!(p.header.count, 12);
    }
    // The file round trip keeps every bit.
    let p = part(&j, 2);
    let back = Partial::from_bytes(&p.to_bytes().unwrap()).unwrap();
    assert_eq!(back.acc, p.acc);
    assert_eq!(back.header.identity, p.header.identity);
}

#[test]
fn merged_shards_equal_one_process_within_rounding() {
    let n = 24;
    let (reference, images) = one_process(&job("cornell-box", "pt", &[], passes(1, 0, n)), n, 2);
    let ranges = [(0, 5), (5, 6), (6, 17), (17, 24)];
    let parts: Vec<Partial> = ranges
        .iter()
        .map(|&(a, b)| part(&job("cornell-box", "pt", &[], passes(1, a, b)), 2))
        .collect();
    let mut shuffled = parts.clone();
    shuffled.swap(0, 3);
    shuffled.swap(1, 2);
    let merged = merge(&named(parts), false).unwrap();
    let merged2 = merge(&named(shuffled), false).unwrap();
    assert_eq!(merged.acc, merged2.acc, "the merge order is fixed");
    assert_eq!(merged.acc.count(), n as u64);
    assert_eq!(merged.span, passes(1, 0, n));
    let (mm, mm2) = merged.acc.parts();
    let (rm, rm2) = reference.parts();
    let eps = f64::EPSILON;
    let (mut worst_mean, mut worst_m2, mut differing) = (0.0f64, 0.0f64, 0usize);
    for i in 0..mm.len() {
        for c in 0..3 {
            let xs: Vec<f64> = images.iter().map(|img| img.data[i][c]).collect();
            let xmax = xs.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            let dmax = xs.iter().fold(0.0f64, |m, x| m.max((x - rm[i][c]).abs()));
            let (dm, dm2) = ((mm[i][c] - rm[i][c]).abs(), (mm2[i][c] - rm2[i][c]).abs());
            differing += usize::from(dm != 0.0 || dm2 != 0.0);
            let bound_m = 8.0 * n as f64 * eps * xmax;
            let bound_m2 = 8.0 * n as f64 * eps * xmax * dmax;
            assert!(
                dm <= bound_m,
                "pixel {i} channel {c}: mean off by {dm:e} > {bound_m:e}"
            );
            assert!(
                dm2 <= bound_m2,
                "pixel {i} channel {c}: M2 off by {dm2:e} > {bound_m2:e}"
            );
            if xmax > 0.0 {
                worst_mean = worst_mean.max(dm / (n as f64 * eps * xmax));
            }
            if xmax * dmax > 0.0 {
                worst_m2 = worst_m2.max(dm2 / (n as f64 * eps * xmax * dmax));
            }
        }
    }
    eprintln!(
        "merge of {} shards vs one process, {n} passes at {}x{}: {differing} of {} values differ; \
         largest |Δmean| = {worst_mean:.3} N·ε·x_max, |ΔM2| = {worst_m2:.3} N·ε·x_max·d_max \
         (bound 8 of each)",
        ranges.len(),
        RES.0,
        RES.1,
        mm.len() * 3
    );
    // Not vacuous: the rounding differences exist (Chan is not Welford), and are far below the
    // bound.
    assert!(differing > 0);
    assert!(worst_mean < 2.0 && worst_m2 < 2.0);
}

#[test]
fn consistent_estimators_merge_by_runs_into_the_runs_statistics() {
    let j = |first_seed, runs| {
        job(
            "cornell-box",
            "sppm",
            &[],
            Span::Runs {
                first_seed,
                runs,
                passes: 3,
            },
        )
    };
    let scene = j(1, 4).load_scene().unwrap();
    let integ = make_integrator("sppm", &scene, &IntegratorParams::new()).unwrap();
    let opts = RenderOptions {
        passes: 3,
        time_limit: None,
        seed: 1,
        threads: 2,
    };
    let all = render_runs(
        &scene,
        &integ,
        &opts,
        4,
        |_, _| ControlFlow::Continue(()),
        |_| {},
    )
    .unwrap();
    let parts = vec![part(&j(3, 2), 2), part(&j(1, 1), 2), part(&j(2, 1), 2)];
    let merged = merge(&named(parts), false).unwrap();
    assert_eq!(
        merged.span,
        Span::Runs {
            first_seed: 1,
            runs: 4,
            passes: 3
        }
    );
    let (se, source) = merged.std_error();
    assert_eq!(source, "independent runs");
    let (a, b) = (merged.acc.mean(), all.across_runs.mean());
    let (sa, sb) = (se.unwrap(), all.across_runs.std_error());
    for i in 0..a.data.len() {
        for c in 0..3 {
            let scale = b.data[i][c].abs().max(1e-300);
            assert!((a.data[i][c] - b.data[i][c]).abs() <= 1e-12 * scale);
            let s = sb.data[i][c];
            assert!(
                (sa.data[i][c] - s).abs() <= 1e-9 * s.max(1e-300),
                "{} vs {s}",
                sa.data[i][c]
            );
        }
    }
    // A pass range of a consistent estimator is refused: its passes share state.
    let e = job("cornell-box", "sppm", &[], passes(1, 0, 2));
    let err = e
        .render(&e.load_scene().unwrap(), 1, |_, _| {})
        .unwrap_err();
    assert!(err.contains("consistent") && err.contains("runs"), "{err}");
    // Runs of different lengths are refused.
    let mut other = part(&j(5, 1), 1);
    other.header.span = Span::Runs {
        first_seed: 5,
        runs: 1,
        passes: 4,
    };
    let err = merge(&named(vec![part(&j(1, 1), 1), other]), false).unwrap_err();
    assert!(err.contains("runs of different lengths"), "{err}");
}

fn merge_err(parts: Vec<Partial>) -> String {
    merge(&named(parts), false).unwrap_err()
}

#[test]
fn mismatched_or_incomplete_parts_are_refused() {
    let a = part(&job("cornell-box", "pt", &[], passes(1, 0, 2)), 2);
    let b = part(&job("cornell-box", "pt", &[], passes(1, 2, 4)), 2);
    assert!(merge(&named(vec![b.clone(), a.clone()]), false).is_ok());

    let other_scene = part(&job("cornell-small-light", "pt", &[], passes(1, 2, 4)), 2);
    let e = merge_err(vec![a.clone(), other_scene]);
    assert!(
        e.contains("part-1.ltp") && e.contains("scene content"),
        "{e}"
    );

    let other_params = part(
        &job("cornell-box", "pt", &[("max_depth", "3")], passes(1, 2, 4)),
        2,
    );
    let e = merge_err(vec![a.clone(), other_params]);
    assert!(e.contains("parameters") && e.contains("max_depth=3"), "{e}");

    let other_integrator = part(&job("cornell-box", "pt-bsdf", &[], passes(1, 2, 4)), 2);
    let e = merge_err(vec![a.clone(), other_integrator]);
    assert!(e.contains("integrator (pt vs pt-bsdf)"), "{e}");

    let other_seed = part(&job("cornell-box", "pt", &[], passes(2, 2, 4)), 2);
    let e = merge_err(vec![a.clone(), other_seed]);
    assert!(e.contains("seed 2") && e.contains("seed 1"), "{e}");

    let mut other_res = job("cornell-box", "pt", &[], passes(1, 2, 4));
    other_res.resolution = Some((8, 8));
    let e = merge_err(vec![a.clone(), part(&other_res, 2)]);
    assert!(e.contains("resolution (16x12 vs 8x8)"), "{e}");

    let mut other_code = b.clone();
    other_code.header.identity.code_version = "0000".into();
    let e = merge_err(vec![a.clone(), other_code]);
    assert!(e.contains("code version"), "{e}");

    let overlap = part(&job("cornell-box", "pt", &[], passes(1, 1, 3)), 2);
    let e = merge_err(vec![a.clone(), overlap]);
    assert!(e.contains("overlaps") && e.contains("twice"), "{e}");

    let late = part(&job("cornell-box", "pt", &[], passes(1, 3, 4)), 2);
    let e = merge_err(vec![a.clone(), late.clone()]);
    assert!(e.contains("missing passes 2..3"), "{e}");
    let e = merge_err(vec![b.clone()]);
    assert!(e.contains("missing passes 0..2"), "{e}");
    let m = merge(&named(vec![a.clone(), late]), true).unwrap();
    assert_eq!(m.missing, ["passes 2..3"]);
    assert_eq!(m.acc.count(), 3);

    let runs = part(
        &job(
            "cornell-box",
            "pt",
            &[],
            Span::Runs {
                first_seed: 1,
                runs: 1,
                passes: 2,
            },
        ),
        2,
    );
    let e = merge_err(vec![a.clone(), runs]);
    assert!(e.contains("independent runs"), "{e}");
}

#[test]
fn damaged_files_are_refused_naming_the_file() {
    let dir = std::env::temp_dir().join(format!("lt-partial-merge-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = part(&job("cornell-box", "pt", &[], passes(1, 0, 2)), 2);
    let good = dir.join("good.ltp");
    p.write(&good).unwrap();
    assert_eq!(Partial::read(&good).unwrap().acc, p.acc);
    let bytes = std::fs::read(&good).unwrap();
    let check = |name: &str, data: &[u8], says: &str| {
        let path: &Path = &dir.join(name);
        std::fs::write(path, data).unwrap();
        let e = Partial::read(path).unwrap_err();
        assert!(e.contains(name) && e.contains(says), "{name}: {e}");
    };
    let mut flipped = bytes.clone();
    let at = bytes.len() - 100;
    flipped[at] ^= 0x10;
    check("flipped.ltp", &flipped, "checksum");
    check("short.ltp", &bytes[..bytes.len() - 8], "truncated");
    check("header.ltp", &bytes[..40], "truncated");
    check("other.ltp", b"P6 not a partial at all", "not an lt partial");
    let key = b"\"count\": 2";
    let at = bytes.windows(key.len()).position(|w| w == key).unwrap();
    let mut edited = bytes.clone();
    edited[at + key.len() - 1] = b'3';
    check("count.ltp", &edited, "incomplete");
}

//! bdpt's path pyramid (`lt render -i bdpt --strategies DIR`): the strategy images are a
//! partition of the bdpt image (exactly, up to the stated rounding), each unweighted strategy
//! alone estimates its length's image (against pt per block), and the files are written.

use lt_core::Scene;
use lt_estimators::agreement::agreement_t;
use lt_estimators::{Image, RunningBlocks};
use lt_experiments::verify::strategies::{
    make_bdpt, pyramid_pass, render_pyramid, strategies, strategy_index, write_pyramid, PyramidMeta,
};
use lt_integrators::{make_integrator, IntegratorParams, RenderOptions};
use lt_scene_io::load_scene;
use std::ops::ControlFlow;
use std::path::PathBuf;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn cornell(size: u32) -> Scene {
    let mut scene = load_scene(&repo().join("scenes/cornell-box.toml")).unwrap();
    scene.camera = scene.camera.with_resolution(size, size);
    scene
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lt-strategies-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn depth(d: u32) -> IntegratorParams {
    IntegratorParams::new().with("max_depth", d)
}

/// Largest violation of |main − Σ| ≤ tol · Σ over pixels and channels, as a multiple of the bound
/// (≤ 1 passes), where Σ sums the strategy images `include` selects, each `times` times.
fn worst_ratio(main: &Image, parts: &[(&Image, f64)], tol: f64) -> f64 {
    let mut worst: f64 = 0.0;
    for p in 0..main.data.len() {
        for c in 0..3 {
            let sum: f64 = parts.iter().map(|(img, m)| img.data[p][c] * m).sum();
            let err = (main.data[p][c] - sum).abs();
            let bound = tol * sum.abs() + 1e-300;
            worst = worst.max(err / bound);
        }
    }
    worst
}

/// Bound on |main − Σ strategies| relative to Σ (all terms are ≥ 0). bdpt forms each weighted
/// term in f32 (the f64 weight rounded to f32, then one product: ≤ 2 ulps; a t = 1 splat scales
/// value · (w · 1/M) where the recorder has (value / M) · w: ≤ 3 ulps) and sums a pixel's t ≥ 2
/// terms in f32 before splatting (≤ n ulps for n terms, n ≤ (L+1)(L+2)/2 = 15 at L = 4); the
/// images sum in f64. So |Δ| ≤ (15 + 3) · 2⁻²⁴ · Σ; we allow 32 · 2⁻²⁴ ≈ 1.9e-6.
const TOL: f64 = 32.0 / (1u64 << 24) as f64;

#[test]
fn strategy_images_partition_the_bdpt_image_exactly() {
    let scene = cornell(32);
    for max_depth in 1..=4u32 {
        let l = max_depth as usize;
        let bdpt = make_bdpt(&scene, &depth(max_depth)).unwrap();
        let plain = make_integrator("bdpt", &scene, &depth(max_depth)).unwrap();
        for pass in 0..3 {
            let p = pyramid_pass(&bdpt, &scene, 7, pass, l);
            assert_eq!((p.invalid, p.main_invalid), (0, 0));
            // The main image is bdpt's own, bit for bit (same items, same chunks).
            let (reference, _) = plain.unbiased().unwrap().render_pass(&scene, 7, pass);
            assert!(
                p.main
                    .data
                    .iter()
                    .flatten()
                    .zip(reference.data.iter().flatten())
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "max_depth {max_depth} pass {pass}: pyramid main image differs from bdpt's"
            );
            // Lengths 1 … max_depth − 1 plus the length max_depth layer = bdpt at max_depth.
            // With the lower lengths already held to their own runs (max_depth − 1, …), this
            // pins the sum over s of the length-k weighted images to bdpt's length-k part.
            let all: Vec<(&Image, f64)> = p.weighted.iter().map(|i| (i, 1.0)).collect();
            let r = worst_ratio(&p.main, &all, TOL);
            assert!(
                r <= 1.0,
                "max_depth {max_depth} pass {pass}: off by {r}× the bound"
            );
            // The check can fail: dropping or double counting any strategy of length max_depth
            // that contributed breaks it.
            for s in 0..=l {
                let i = strategy_index(l, s);
                let total: f64 = p.weighted[i].data.iter().flatten().sum();
                if total == 0.0 {
                    continue;
                }
                for m in [0.0, 2.0] {
                    let parts: Vec<(&Image, f64)> = p
                        .weighted
                        .iter()
                        .enumerate()
                        .map(|(j, img)| (img, if j == i { m } else { 1.0 }))
                        .collect();
                    assert!(
                        worst_ratio(&p.main, &parts, TOL) > 1.0,
                        "k {l} s {s} × {m} passes the check"
                    );
                }
            }
        }
        // Every strategy of the longest length contributes on cornell-box (nothing is lost
        // silently): all s = 0 … k over a pass.
        let p = pyramid_pass(&bdpt, &scene, 7, 0, l);
        for s in 0..=l {
            let total: f64 = p.weighted[strategy_index(l, s)].data.iter().flatten().sum();
            assert!(
                total > 0.0,
                "max_depth {max_depth}: strategy s = {s} is empty"
            );
        }
    }
}

#[test]
fn lengths_beyond_max_depth_are_empty_and_images_ignore_threads() {
    let scene = cornell(32);
    let bdpt = make_bdpt(&scene, &depth(3)).unwrap();
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| pyramid_pass(&bdpt, &scene, 3, 1, 5))
    };
    let (a, b) = (run(1), run(4));
    assert_eq!(a.main, b.main);
    assert_eq!(a.weighted, b.weighted);
    assert_eq!(a.unweighted, b.unweighted);
    for (i, st) in strategies(5).iter().enumerate() {
        let total: f64 = a.unweighted[i].data.iter().flatten().sum();
        assert_eq!(total > 0.0, st.k <= 3, "{st:?}: total {total}");
    }
    let all: Vec<(&Image, f64)> = a.weighted.iter().map(|i| (i, 1.0)).collect();
    assert!(worst_ratio(&a.main, &all, TOL) <= 1.0);
}

/// Per pass: pt at max_depth 2 minus pt at max_depth 1 (the same camera rays, so the difference
/// is pt's estimate of the length-2 image; its passes are independent).
fn pt_length_two(scene: &Scene, passes: u32, block: usize) -> RunningBlocks {
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let pt2 = make_integrator("pt", scene, &depth(2)).unwrap();
    let pt1 = make_integrator("pt", scene, &depth(1)).unwrap();
    let mut blocks = RunningBlocks::new(w, h, block);
    for pass in 0..passes {
        let (mut a, bad_a) = pt2.unbiased().unwrap().render_pass(scene, 21, pass);
        let (b, bad_b) = pt1.unbiased().unwrap().render_pass(scene, 21, pass);
        assert_eq!(bad_a + bad_b, 0);
        for (x, y) in a.data.iter_mut().zip(&b.data) {
            for c in 0..3 {
                x[c] -= y[c];
            }
        }
        blocks.add(&a);
    }
    blocks
}

#[test]
fn each_length_two_strategy_alone_agrees_with_pt() {
    let scene = cornell(32);
    let (w, h, block) = (32, 32, 8);
    let passes = 1024;
    let reference = pt_length_two(&scene, passes, block);
    let bdpt = make_bdpt(&scene, &depth(2)).unwrap();
    let mut per_s: Vec<RunningBlocks> = (0..3).map(|_| RunningBlocks::new(w, h, block)).collect();
    for pass in 0..passes {
        let p = pyramid_pass(&bdpt, &scene, 5, pass, 2);
        assert_eq!(p.invalid, 0);
        for (s, b) in per_s.iter_mut().enumerate() {
            b.add(&p.unweighted[strategy_index(2, s)]);
        }
    }
    for (s, b) in per_s.iter().enumerate() {
        let result = agreement_t(b, &reference, 1e-3);
        assert!(
            result.passed(),
            "k = 2, s = {s}, t = {}: unweighted vs pt(2) − pt(1): {result}",
            3 - s
        );
    }
}

#[test]
fn pyramid_files_are_written() {
    let scene = cornell(32);
    let opts = RenderOptions {
        passes: 4,
        time_limit: None,
        seed: 1,
        threads: 2,
    };
    let (result, pyr) =
        render_pyramid(&scene, &depth(4), &opts, 3, |_| ControlFlow::Continue(())).unwrap();
    assert_eq!((result.passes, pyr.passes()), (4, 4));
    let dir = temp_dir("files");
    let meta = PyramidMeta {
        scene: "cornell-box".into(),
        seed: 1,
        max_depth: 4,
    };
    write_pyramid(&dir, &pyr, &meta).unwrap();
    let readme = std::fs::read_to_string(dir.join("README.md")).unwrap();
    for st in strategies(3) {
        for suffix in [
            "weighted.exr",
            "unweighted.exr",
            "weighted.stderr.exr",
            "unweighted.stderr.exr",
        ] {
            let f = dir.join(format!("{}.{suffix}", st.stem()));
            let img = lt_experiments::image_io::read_exr(&f).unwrap();
            assert_eq!((img.width, img.height), (32, 32), "{}", f.display());
        }
        assert!(readme.contains(&format!("{}.weighted.exr", st.stem())));
    }
    let png = image::open(dir.join("pyramid.png")).unwrap();
    assert!(png.width() >= 4 * 128 && png.height() >= 3 * 128);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("strategies.json")).unwrap())
            .unwrap();
    assert_eq!(json["strategies"].as_array().unwrap().len(), 9);
    assert_eq!(json["passes"], 4);
    // Means of the lengths ≤ 3 stay below bdpt's (max_depth 4 adds length 4).
    let main = json["main_mean"][0].as_f64().unwrap();
    let sum: f64 = json["lengths"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["weighted_mean_sum"][0].as_f64().unwrap())
        .sum();
    assert!(sum > 0.5 * main && sum < main, "{sum} vs {main}");
}

#[test]
fn cli_writes_pyramid_and_refuses_other_integrators() {
    let lt = || std::process::Command::new(env!("CARGO_BIN_EXE_lt"));
    let dir = temp_dir("cli");
    let scene = repo().join("scenes/cornell-box.toml");
    let out = lt()
        .args([
            "render",
            "-i",
            "pt",
            "--spp",
            "1",
            "--quiet",
            "--strategies",
        ])
        .arg(dir.join("pyr-pt"))
        .arg("-o")
        .arg(dir.join("pt.exr"))
        .arg(&scene)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--strategies") && err.contains("bdpt"),
        "{err}"
    );
    assert!(!dir.join("pt.exr").exists() && !dir.join("pyr-pt").exists());

    let status = lt()
        .args([
            "render",
            "-i",
            "bdpt",
            "--spp",
            "2",
            "--max-depth",
            "3",
            "--quiet",
        ])
        .args(["--strategy-length", "2", "--strategies"])
        .arg(dir.join("pyr"))
        .arg("-o")
        .arg(dir.join("b.exr"))
        .arg(&scene)
        .status()
        .unwrap();
    assert!(status.success());
    for f in [
        "b.exr",
        "pyr/k2_s1_t2.weighted.exr",
        "pyr/k1_s0_t2.unweighted.stderr.exr",
        "pyr/pyramid.png",
        "pyr/README.md",
        "pyr/strategies.json",
    ] {
        assert!(dir.join(f).exists(), "{f} missing");
    }
    assert!(!dir.join("pyr/k3_s0_t4.weighted.exr").exists());
}

//! Per-technique tallies (`lt_integrators::record::tally`): a tallied render is the plain render bit for
//! bit, at any thread count, and its techniques' means add up to the image's mean.

use lt_core::Scene;
use lt_integrators::record::tally::RunTally;
use lt_integrators::record::tally_run::{tally_run, Tallied};
use lt_integrators::record::{VolumeFamily, Work};
use lt_integrators::{make_integrator, render, IntegratorParams, RenderOptions};
use lt_scene_io::load_scene;
use std::ops::ControlFlow;
use std::path::PathBuf;

fn scene(name: &str, width: u32) -> Scene {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../scenes/{name}.toml"));
    let mut s = load_scene(&p).unwrap();
    s.camera = s.camera.with_resolution(width, width);
    s
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

/// Σ of the techniques' means, relative to the image mean.
fn sum_error(t: &RunTally) -> f64 {
    let sum: f64 = t.techniques.values().map(|f| f.mean).sum();
    (sum - t.image_mean).abs() / t.image_mean.abs().max(1e-30)
}

#[test]
fn a_tallied_render_is_the_plain_render_bit_for_bit() {
    let cases: [(&str, &[(&str, &str)]); 4] = [
        ("bdpt", &[]),
        ("lvc-bdpt", &[("connections", "3")]),
        ("vcm", &[]),
        ("bpm", &[]),
    ];
    for scene_name in ["cornell-box", "caustic-sds"] {
        let scene = scene(scene_name, 24);
        for (name, kv) in cases {
            let mut params = IntegratorParams::new();
            for (k, v) in kv {
                params.set(k, v);
            }
            let est = make_integrator(name, &scene, &params).unwrap();
            let opts = RenderOptions {
                passes: 3,
                time_limit: None,
                seed: 7,
                threads: 2,
            };
            let plain = render(&scene, &est, &opts, |_| ControlFlow::Continue(())).unwrap();
            let t = Tallied::make(name, &scene, &params).unwrap();
            for threads in [1, 2] {
                let (img, tally) = pool(threads).install(|| tally_run(&scene, &t, 7, 3, 4));
                assert!(
                    img.data
                        .iter()
                        .zip(&plain.estimate.data)
                        .all(|(a, b)| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())),
                    "{scene_name} {name}: the tallied image differs ({threads} threads)"
                );
                assert_eq!(tally.passes, 3);
                // The techniques' f64 sums of the f32 contributions the image adds up in f32.
                assert!(
                    sum_error(&tally) < 1e-4,
                    "{scene_name} {name}: techniques sum to {} of the image mean {}",
                    1.0 + sum_error(&tally),
                    tally.image_mean
                );
                assert!(tally.techniques.values().all(|f| f.second_moment >= 0.0));
                let timed: f64 = tally.techniques.values().map(|f| f.seconds).sum();
                assert!(
                    timed > 0.0 && timed <= tally.seconds * 2.0,
                    "{name}: {timed} s of {} s",
                    tally.seconds
                );
            }
            let keys: Vec<Work> = t_keys(&scene, &t);
            assert!(keys.contains(&Work::CameraWalk) && keys.contains(&Work::LightWalk));
            assert_eq!(
                keys.iter().any(|w| matches!(w, Work::Merge { .. })),
                matches!(name, "vcm" | "bpm"),
                "{name}: merges"
            );
        }
    }
}

fn t_keys(scene: &Scene, t: &Tallied) -> Vec<Work> {
    let (_, tally) = pool(1).install(|| tally_run(scene, t, 1, 1, 1));
    tally.techniques.keys().copied().collect()
}

/// upbp with every technique on a media scene: the tallied image is the plain one bit for bit at
/// 1 and 2 threads, every volumetric family is heard (in contributions and in time) at the
/// camera vertex counts its geometry allows, and the techniques' means add up to the image's.
#[test]
fn upbp_tallies_its_volumetric_families() {
    let scene = lt_tests::shipped_scene("media/hg-spot", Some((12, 12)));
    let params = IntegratorParams::new()
        .with("techniques", "all")
        .with("photons_per_pass", 64);
    let est = make_integrator("upbp", &scene, &params).unwrap();
    let opts = RenderOptions {
        passes: 2,
        time_limit: None,
        seed: 11,
        threads: 2,
    };
    let plain = render(&scene, &est, &opts, |_| ControlFlow::Continue(())).unwrap();
    let t = Tallied::make("upbp", &scene, &params).unwrap();
    for threads in [1, 2] {
        let (img, tally) = pool(threads).install(|| tally_run(&scene, &t, 11, 2, 1));
        assert!(
            img.data
                .iter()
                .zip(&plain.estimate.data)
                .all(|(a, b)| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())),
            "upbp: the tallied image differs ({threads} threads)"
        );
        assert!(
            sum_error(&tally) < 1e-4,
            "upbp: techniques sum to {} of the image mean {}",
            1.0 + sum_error(&tally),
            tally.image_mean
        );
        for family in VolumeFamily::ALL {
            let heard: Vec<_> = tally
                .techniques
                .iter()
                .filter(|(w, _)| matches!(w, Work::VolumeMerge { family: f, .. } if *f == family))
                .collect();
            assert!(
                heard.iter().any(|(_, f)| f.mean > 0.0)
                    && heard.iter().any(|(_, f)| f.seconds > 0.0),
                "upbp: {} adds nothing to the image or is never timed ({threads} threads)",
                family.name()
            );
            // PP3D and BP2D gather at a camera medium vertex (t ≥ 2), PB2D and BB1D on the
            // segment into it (its query point is the camera side's t-th vertex, t ≥ 2).
            assert!(
                heard
                    .iter()
                    .all(|(w, _)| matches!(w, Work::VolumeMerge { t, .. } if *t >= 2)),
                "upbp: {} at t < 2",
                family.name()
            );
        }
    }
}

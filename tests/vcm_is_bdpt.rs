//! `vcm` without merging is BDPT: with the same heuristic, light-path count and seed it takes
//! the same paths in the same order, gives each the weight `bdpt` gives it (by a different
//! computation: a recursion over per-vertex records against bdpt's patched density chain), and
//! renders the same image — on every shipped scene, with M = N and M ≠ N light paths.

use lt_core::path::Heuristic;
use lt_integrators::bdpt::{Bdpt, BdptParams, BdptWeights};
use lt_integrators::connect_merge::{initial_radius, Engine, PassInputs, VcmParams};
use lt_integrators::radius::InitialRadius;
use lt_integrators::record::{Completed, Recorder};
use lt_integrators::splat::{Pass, Splats, Worker};
use lt_integrators::{make_integrator, Estimator, Integrator, IntegratorParams};
use lt_tests::{shipped_scene, shipped_scene_names};

/// (s, k, raster, weight) of every path in completion order.
#[derive(Default)]
struct Weights(Vec<(usize, usize, [f32; 2], f64)>);

impl Recorder for Weights {
    const ACTIVE: bool = true;
    fn completed(&mut self, p: Completed) {
        let k = p.light.len() + p.camera.len() - 1;
        self.0.push((p.s, k, [p.raster.x, p.raster.y], p.weight));
    }
}

fn params(
    scene: &lt_core::Scene,
    light_paths: Option<u64>,
    mis: Heuristic,
) -> (BdptParams, VcmParams) {
    let b = BdptParams {
        max_depth: scene.settings.max_depth,
        rr_depth: scene.settings.rr_depth,
        mis,
        light_paths,
        // bdpt's chain: vcm's recursion is held to the other computation.
        weights: BdptWeights::Chain,
    };
    let v = VcmParams {
        max_depth: b.max_depth,
        rr_depth: b.rr_depth,
        mis,
        light_paths,
        radius: InitialRadius::Pixels(2.0),
        alpha: 0.75,
        connections: true,
        merging: false,
        correlation_aware: false,
        vertex_connections: true,
    };
    (b, v)
}

#[test]
fn vcm_without_merging_gives_every_path_bdpts_weight() {
    let (mut paths, mut worst) = (0usize, 0.0f64);
    for name in shipped_scene_names() {
        let scene = shipped_scene(&name, Some((12, 12)));
        for (light_paths, mis) in [(None, Heuristic::Power), (Some(36), Heuristic::Balance)] {
            let (bp, vp) = params(&scene, light_paths, mis);
            let mut want = Weights::default();
            Bdpt { params: bp }.record_pass(&scene, 5, 3, &mut want);
            let engine = Engine::new(&vp, &scene);
            let setup = engine.setup(initial_radius(&scene, vp.radius), 3);
            let lights = engine.trace_light_paths(&setup, 5, 3);
            let mut got = Weights::default();
            let mut scratch = engine.scratch();
            let mut splats = Splats::new(12, 12);
            let items = 144u64.max(vp.light_path_count(&scene));
            let inputs = PassInputs {
                setup: &setup,
                lights: &lights,
                pass: Pass { seed: 5, pass: 3 },
            };
            let mut worker = Worker {
                splats: &mut splats,
                scratch: &mut scratch,
                rec: &mut got,
            };
            for i in 0..items {
                engine.item(&inputs, i, &mut worker);
            }
            assert_eq!(
                got.0.len(),
                want.0.len(),
                "{name} {light_paths:?}: path counts differ"
            );
            for (g, w) in got.0.iter().zip(&want.0) {
                assert_eq!((g.0, g.1, g.2), (w.0, w.1, w.2), "{name}: a different path");
                let rel = (g.3 - w.3).abs() / w.3.abs().max(1e-300);
                // Both are f64 arithmetic on the same f32 densities: only rounding differs.
                assert!(
                    rel < 1e-9 || (g.3 - w.3).abs() < 1e-15,
                    "{name} s {} k {}: vcm {} bdpt {}",
                    g.0,
                    g.1,
                    g.3,
                    w.3
                );
                worst = worst.max(if w.3 > 0.0 { rel } else { 0.0 });
            }
            paths += got.0.len();
        }
    }
    eprintln!("{paths} paths, worst relative weight difference {worst:.2e}");
    assert!(paths > 10_000);
}

#[test]
fn vcm_without_merging_renders_bdpts_image() {
    let mut worst = 0.0f64;
    for name in shipped_scene_names() {
        let scene = shipped_scene(&name, Some((24, 24)));
        let p = IntegratorParams::new();
        if scene.camera.is_delta_direction() {
            // vcm refuses a camera no light-tracing connection reaches (point-plane's).
            let refusal = make_integrator("vcm", &scene, &p).err();
            assert!(
                refusal.is_some_and(|e| e.contains("orthographic")),
                "{name}: vcm should refuse an orthographic camera"
            );
            continue;
        }
        let Estimator::Unbiased(bdpt) = make_integrator("bdpt", &scene, &p).unwrap() else {
            panic!("bdpt is unbiased")
        };
        let Estimator::Consistent(vcm) = make_integrator(
            "vcm",
            &scene,
            &IntegratorParams::new().with("merging", false),
        )
        .unwrap() else {
            panic!("vcm is consistent")
        };
        let (want, _) = bdpt.render_pass(&scene, 9, 0);
        let mut run = vcm.start(&scene, 9);
        run.pass(0);
        let got = run.estimate();
        // A pixel sums O(10²) f32 contributions whose weights may round differently in the last
        // bit: the images agree to a few hundred ulps of the pixel's magnitude.
        for (g, w) in got.data.iter().zip(&want.data) {
            for c in 0..3 {
                let d = (g[c] - w[c]).abs();
                let rel = d / w[c].abs().max(1e-30);
                assert!(
                    d <= 512.0 * f32::EPSILON as f64 * w[c].abs().max(1e-6),
                    "{name}: pixel {} vs {}",
                    g[c],
                    w[c]
                );
                if w[c] > 1e-6 {
                    worst = worst.max(rel);
                }
            }
        }
        let _: &dyn Integrator = bdpt.as_ref();
    }
    eprintln!("worst relative pixel difference {worst:.2e}");
}

//! The ray cores at the level of images. The flat core (`lt_core::geometry::flat`) and the wide
//! BVH (`geometry::wide`): every registered integrator on every shipped scene gives the same image
//! bit for bit whether rays are tested one primitive at a time (`flat-scalar`, the reference), in
//! the flat core's vectorised loops at every width the CPU runs (`LT_FLAT_ISA`), or through the
//! wide BVH. Embree (`geometry::embree`), whose traversal may name
//! another primitive at a tie: every unbiased integrator on every shipped scene and Bitterli's three agrees
//! with the BVH's render within its own standard errors. The ray-level tests are in
//! `geometry::accel`; these show nothing downstream of a hit depends on the core.
//!
//! Its own test binary: it switches the process-wide ray core, which would race the other tests
//! (and its two tests take turns through `CORE_LOCK`).

use lt_core::geometry::flat::Isa;
use lt_core::geometry::{set_ray_core, RayCore};
use lt_core::Scene;
use lt_estimators::agreement::agreement_t;
use lt_integrators::{make_integrator, render, IntegratorParams, Kind, RenderOptions, INTEGRATORS};
use lt_tests::{render_blocks, scenes_dir, shipped_scene, shipped_scene_names};
use std::ops::ControlFlow;
use std::sync::Mutex;

/// The process-wide ray core is one setting: one test at a time may hold it.
static CORE_LOCK: Mutex<()> = Mutex::new(());

/// Every integrator's image of every shipped scene (24², 2 passes, seed 5), as bits.
fn images() -> Vec<(String, Vec<u64>)> {
    let mut out = Vec::new();
    for name in shipped_scene_names() {
        let scene = shipped_scene(&name, Some((24, 24)));
        for info in INTEGRATORS {
            let integ = match make_integrator(info.name, &scene, &IntegratorParams::default()) {
                Ok(integ) => integ,
                // An orthographic camera is refused by the estimators that splat to it
                // (robustness.rs holds each refusal by name).
                Err(_) if scene.camera.is_delta_direction() => continue,
                Err(e) => panic!("{} on {name}: {e}", info.name),
            };
            let opts = RenderOptions {
                passes: 2,
                time_limit: None,
                seed: 5,
                threads: 2,
            };
            let image = render(&scene, &integ, &opts, |_| ControlFlow::Continue(()))
                .unwrap()
                .estimate;
            let bits = image.data.iter().flatten().map(|v| v.to_bits()).collect();
            out.push((
                format!("{} on {name} ({})", info.name, scene.ray_core()),
                bits,
            ));
        }
    }
    out
}

#[test]
fn vectorised_flat_and_wide_cores_render_the_scalar_references_images_bit_for_bit() {
    let _core = CORE_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    set_ray_core(RayCore::FlatScalar);
    let reference = images();
    assert!(reference.iter().all(|(who, _)| who.contains("flat-scalar")));
    set_ray_core(RayCore::Flat);
    for isa in Isa::available() {
        // SAFETY (edition 2021: safe): this binary runs this one test, on one thread.
        std::env::set_var("LT_FLAT_ISA", isa.name());
        let wide = images();
        for ((who, bits), (_, expected)) in wide.iter().zip(&reference) {
            assert!(
                who.contains(isa.name()),
                "{who}: expected the {isa:?} loops"
            );
            assert!(bits == expected, "{who}: differs from the scalar reference");
        }
    }
    std::env::remove_var("LT_FLAT_ISA");
    // The wide BVH at the width the CPU picks (every width is held to the reference at ray level
    // in `geometry::accel`).
    set_ray_core(RayCore::Wide);
    for ((who, bits), (_, expected)) in images().iter().zip(&reference) {
        assert!(who.contains("wide"), "{who}: expected the wide core");
        assert!(bits == expected, "{who}: differs from the scalar reference");
    }
    set_ray_core(RayCore::Auto);
}

/// Shipped scenes at 24² and Bitterli's three (`-D integrator=path`) at 32², each loaded under the
/// process-wide ray core `core`.
fn scenes_under(core: RayCore) -> Vec<(String, Scene)> {
    set_ray_core(core);
    let mut v: Vec<(String, Scene)> = shipped_scene_names()
        .into_iter()
        .map(|n| {
            let s = shipped_scene(&n, Some((24, 24)));
            (n, s)
        })
        .collect();
    for name in ["cornell-box", "veach-bidir", "veach-mis"] {
        let path = scenes_dir().join("bitterli").join(name).join("scene.xml");
        let opts = lt_scene_io::LoadOptions {
            defines: vec![("integrator".into(), "path".into())],
            ..Default::default()
        };
        let (mut scene, _) =
            lt_scene_io::load_scene_with(&path, &opts).unwrap_or_else(|e| panic!("{e}"));
        scene.camera = scene.camera.with_resolution(32, 32);
        v.push((format!("bitterli/{name}"), scene));
    }
    v
}

/// Every unbiased integrator on every shipped scene and Bitterli's three renders with Embree what
/// it renders with the BVH: independent seeds, 8 passes (consistent estimators: independent runs),
/// 4 × 4-pixel blocks, Welch t per block and channel, Šidák over blocks and channels and over
/// every (scene, integrator) pair at 1 % in all. Skipped (said) where the build has no Embree;
/// `LT_REQUIRE_EMBREE=1` (CI, which installs it) makes that a failure.
#[test]
fn embree_core_renders_what_the_bvh_renders() {
    let _core = CORE_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    if !RayCore::Embree.available() {
        assert!(
            std::env::var("LT_REQUIRE_EMBREE").is_err(),
            "LT_REQUIRE_EMBREE is set but this build has no Embree (libembree-dev not found)"
        );
        eprintln!("skipped: this build has no Embree (install libembree-dev and rebuild)");
        return;
    }
    let bvh = scenes_under(RayCore::Bvh);
    let embree = scenes_under(RayCore::Embree);
    set_ray_core(RayCore::Auto);
    let mut pairs = Vec::new();
    for ((name, a), (_, b)) in bvh.iter().zip(&embree) {
        assert_eq!(b.ray_core(), "embree", "{name}");
        for info in INTEGRATORS {
            let Ok(integ) = make_integrator(info.name, a, &IntegratorParams::default()) else {
                // An orthographic camera is refused by the estimators that splat to it
                // (robustness.rs holds each refusal by name).
                continue;
            };
            // The unbiased estimators only: they cast every kind of ray there is (camera and
            // light walks, shadow rays, connections, splats to the lens), through the same walk
            // code the consistent ones use (photons are light walks), and a consistent estimator
            // would need 8 independent runs here (8× the passes) to say the same thing.
            if integ.kind() != Kind::Unbiased {
                continue;
            }
            pairs.push((name.clone(), info.name, a, b));
        }
    }
    let per_pair = 1.0 - 0.99f64.powf(1.0 / pairs.len() as f64);
    let mut failures = Vec::new();
    for (name, integrator, a, b) in &pairs {
        let params = IntegratorParams::default;
        let (_, blocks_a) = render_blocks(a, integrator, params(), 8, 5, 4);
        let (_, blocks_b) = render_blocks(b, integrator, params(), 8, 1005, 4);
        let ag = agreement_t(&blocks_b, &blocks_a, per_pair);
        if !ag.passed() {
            failures.push(format!(
                "{integrator} on {name}: max |z| {:.2} > {:.2}",
                ag.max_abs_z, ag.threshold
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} pairs disagree:\n{}",
        failures.len(),
        pairs.len(),
        failures.join("\n")
    );
}

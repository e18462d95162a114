//! The flat ray core (`lt_core::geometry::flat`) at the level of images: every registered
//! integrator on every shipped scene gives the same image bit for bit whether rays are tested one
//! primitive at a time (`flat-scalar`, the reference) or in the vectorised loops at every width the
//! CPU runs (`LT_FLAT_ISA`). The ray-level test is in `geometry::accel`; this one shows nothing
//! downstream of a hit (hit records, shading, splatting, merging) depends on the width.
//!
//! Its own test binary: it switches the process-wide ray core, which would race the other tests.

use lt_core::geometry::flat::Isa;
use lt_core::geometry::{set_ray_core, RayCore};
use lt_integrators::{make_integrator, render, IntegratorParams, RenderOptions, INTEGRATORS};
use lt_tests::{shipped_scene, shipped_scene_names};
use std::ops::ControlFlow;

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
fn vectorised_flat_core_renders_the_scalar_references_images_bit_for_bit() {
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
}

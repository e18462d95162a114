//! White furnace: inside a closed enclosure whose walls have albedo ρ and emit Le everywhere,
//! radiance is Le · (1 + ρ + ρ² + …) = Le / (1 − ρ) in every direction. Both path tracers must
//! reproduce it within 4 standard errors (Šidák-corrected over the channels), for an analytic
//! sphere and for a triangle-mesh cube, at small and at extreme scene scales.

use lt_core::bsdf::{Diffuse, Material};
use lt_core::camera::{Camera, FovAxis};
use lt_core::scene::{RenderSettings, SceneBuilder, ShapeGeometry, TriangleMesh};
use lt_core::{Color, Scene, Vec3};
use lt_estimators::agreement::agreement_with_reference_t;
use lt_integrators::IntegratorParams;
use lt_tests::render_blocks;

const RHO: f32 = 0.6;
const LE: f32 = 0.5;

fn furnace(sphere: bool, scale: f32) -> Scene {
    let camera = Camera::look_at(
        Vec3::new(0.1, 0.2, 0.05) * scale,
        Vec3::new(0.5, 0.1, -0.3) * scale,
        Vec3::Y,
        70.0,
        FovAxis::X,
        16,
        16,
    )
    .unwrap();
    // Deep paths: the truncation error ρ^64 ≈ 6e-15 is far below any standard error here.
    let settings = RenderSettings {
        max_depth: 64,
        rr_depth: 5,
        spp: 1,
    };
    let mut b = SceneBuilder::new(camera, settings);
    let m = b.add_material(Material::Diffuse(Diffuse {
        albedo: Color::splat(RHO),
    }));
    let geometry = if sphere {
        ShapeGeometry::Sphere {
            center: Vec3::ZERO,
            radius: scale,
        }
    } else {
        ShapeGeometry::Mesh(
            TriangleMesh::unit_cube()
                .transformed(&lt_core::math::Mat4::from_scale(Vec3::splat(scale))),
        )
    };
    // Normals flipped to face inwards: that is the side that emits and is seen.
    b.add_shape(geometry, m, Some(Color::splat(LE)), true);
    b.build()
}

fn check(integrator: &str, sphere: bool, scale: f32) {
    let scene = furnace(sphere, scale);
    let (result, blocks) =
        render_blocks(&scene, integrator, IntegratorParams::default(), 64, 7, 16);
    assert_eq!(result.invalid_samples, 0);
    let expected = (LE / (1.0 - RHO)) as f64;
    let a = agreement_with_reference_t(&blocks, &[[expected; 3]], 1e-3);
    let blocks = blocks.estimate();
    assert!(
        a.passed(),
        "{integrator} sphere={sphere} scale={scale}: mean {:?} vs {expected}: {a}",
        blocks.mean[0]
    );
    // Non-trivial: the estimate has a real spread, so the test could detect a bias of a few %.
    assert!(
        blocks.std_error[0][0] > 0.0 && blocks.std_error[0][0] < 0.02 * expected,
        "stderr {:?}",
        blocks.std_error[0]
    );
}

#[test]
fn pt_sphere_furnace() {
    check("pt", true, 1.0);
}

#[test]
fn pt_bsdf_sphere_furnace() {
    check("pt-bsdf", true, 1.0);
}

#[test]
fn pt_cube_furnace() {
    check("pt", false, 1.0);
}

#[test]
fn pt_bsdf_cube_furnace() {
    check("pt-bsdf", false, 1.0);
}

#[test]
fn pt_furnace_is_scale_invariant() {
    for scale in [1e-3, 1e6] {
        check("pt", true, scale);
        check("pt", false, scale);
    }
}

//! The integrators that walk participating media (`registry::HANDLES_MEDIA`: `pt`, `pt-bsdf`,
//! `light`, `bdpt`; scenes built in code: the scene files cannot describe media yet). A white
//! furnace inside a null-bounded medium of albedo 1 under a uniform environment of radiance 1 must
//! return 1; the estimators agree with `pt` per block within Šidák-corrected standard errors on a
//! medium sphere under an area light (null boundary, inside glass, and a heterogeneous grid for
//! bdpt); no NaN or negative pixel; the same bits at 1 and 2 threads.

use lt_core::bsdf::{Dielectric, Diffuse, Material, Null};
use lt_core::camera::{Camera, FovAxis};
use lt_core::light::LightDesc;
use lt_core::math::Mat4;
use lt_core::medium::{GridMedium, GridVolume, Homogeneous, Medium, PhaseFunction};
use lt_core::medium::{Volume, VolumeGrid, WrapMode};
use lt_core::scene::{MediumInterface, RenderSettings, SceneBuilder, ShapeGeometry, TriangleMesh};
use lt_core::{Color, Scene, Vec3};
use lt_estimators::agreement::{agreement_t, agreement_with_reference_t};
use lt_integrators::{make_integrator, render, IntegratorParams, RenderOptions};
use lt_tests::render_blocks;
use std::ops::ControlFlow;

const ALPHA: f64 = 1e-3;

pub(crate) fn homogeneous(sigma_t: Color, albedo: f32, phase: PhaseFunction) -> Medium {
    Medium::Homogeneous(Homogeneous::new(sigma_t, Color::splat(albedo), 1.0, phase).unwrap())
}

/// The camera inside a null sphere of radius 1 filled with `medium`, a uniform environment of
/// radiance 1 outside: with albedo 1 nothing is absorbed, so every pixel is 1. Light tracing
/// reaches the unit sphere from the scene's bounding disk rarely, hence its many passes; the
/// spread bound (5 %) keeps each case able to see a bias of a few per cent.
pub(crate) fn furnace(medium: Medium) -> Scene {
    let camera = Camera::look_at(
        Vec3::new(0.1, 0.05, 0.0),
        Vec3::new(0.2, -0.1, -1.0),
        Vec3::Y,
        70.0,
        FovAxis::X,
        8,
        8,
    )
    .unwrap();
    // Deep paths: at σt ≤ 2 over a unit sphere a path of 512 scatterings never happens.
    let settings = RenderSettings {
        max_depth: 512,
        rr_depth: 5,
        spp: 1,
    };
    let mut b = SceneBuilder::new(camera, settings);
    let m = b.add_medium(medium);
    let null = b.add_material(Material::Null(Null));
    let sphere = ShapeGeometry::Sphere {
        center: Vec3::ZERO,
        radius: 1.0,
    };
    b.add_shape(sphere, null, None, false);
    b.set_last_shape_media(MediumInterface {
        interior: Some(m),
        exterior: None,
    });
    b.set_camera_medium(Some(m));
    b.add_light(LightDesc::Environment {
        radiance: Color::ONE,
    });
    b.build()
}

fn check_furnace(integrator: &str, medium: Medium, passes: u32) {
    let scene = furnace(medium);
    let (r, blocks) = render_blocks(
        &scene,
        integrator,
        IntegratorParams::default(),
        passes,
        3,
        8,
    );
    assert_eq!(r.invalid_samples, 0, "{integrator}: invalid samples");
    let a = agreement_with_reference_t(&blocks, &[[1.0; 3]], ALPHA);
    let e = blocks.estimate();
    let summary = format!(
        "{integrator} furnace: {:.5} {:.5} {:.5} ± {:.5}: {a}",
        e.mean[0][0], e.mean[0][1], e.mean[0][2], e.std_error[0][0]
    );
    println!("{summary}");
    assert!(a.passed(), "{summary}");
    assert!(
        e.std_error[0][0] > 0.0 && e.std_error[0][0] < 0.05,
        "{summary}: spread"
    );
}

/// Without `light`: its 65,536 passes here were half of this file's cost, and the HG furnace
/// below keeps light tracing with the camera inside a chromatic medium; its isotropic splats are
/// held to a furnace by tests/furnace.rs (the isotropic medium cube, seen from outside).
#[test]
fn furnace_isotropic_chromatic() {
    let m = || homogeneous(Color::new(0.5, 1.0, 2.0), 1.0, PhaseFunction::Isotropic);
    for (integrator, passes) in FURNACE_PASSES {
        if integrator == "light" {
            println!("light: not in the isotropic furnace (see this test's doc)");
            continue;
        }
        check_furnace(integrator, m(), passes);
    }
}

/// Passes per integrator of the furnaces (light tracing reaches the unit sphere rarely, and its
/// splats from medium vertices around the eye are heavy-tailed: at 16,384 passes the HG furnace
/// came out at 0.895 ± 0.031 in red, |z| 3.42 of 3.59; at 65,536 it holds).
const FURNACE_PASSES: [(&str, u32); 4] =
    [("pt", 64), ("pt-bsdf", 64), ("light", 65536), ("bdpt", 64)];

/// Media integrators whose kernels this file's furnaces cannot hold (name, reason), reported.
const FURNACE_EXCLUDED: &[(&str, &str)] = &[
    (
        "pp3d",
        "its 3-D kernel straddles the sphere's boundary (bias) and 8 runs of 16 passes leave \
              1.5–10 % standard error; see tests/furnace.rs MEDIUM_FURNACE_EXCLUDED",
    ),
    ("pb2d", "as pp3d, with the 2-D kernel"),
    (
        "bb1d",
        "as pp3d, with the 1-D kernel across photon and camera beams",
    ),
    ("bp2d", "as pp3d, with the 2-D kernel across photon beams"),
    (
        "upbp",
        "as pp3d and pb2d, whose kernels it runs beside bdpt's connections",
    ),
];

#[test]
fn every_media_integrator_has_a_furnace() {
    for name in lt_integrators::registry::HANDLES_MEDIA {
        if let Some((_, why)) = FURNACE_EXCLUDED.iter().find(|(n, _)| n == name) {
            println!("{name}: no furnace here ({why})");
            continue;
        }
        assert!(
            FURNACE_PASSES.iter().any(|(n, _)| n == name),
            "{name} walks media but no furnace runs it"
        );
    }
}

#[test]
fn furnace_hg_forward() {
    let hg = PhaseFunction::henyey_greenstein(0.7).unwrap();
    let m = || homogeneous(Color::new(1.5, 1.0, 0.7), 1.0, hg);
    for (integrator, passes) in FURNACE_PASSES {
        check_furnace(integrator, m(), passes);
    }
}

/// A parallelogram centred at `c` spanned by the half-edges `u`, `v`; its normal is u × v.
fn quad(c: Vec3, u: Vec3, v: Vec3) -> ShapeGeometry {
    let n = u.cross(v).normalize();
    let m = Mat4::from_cols(u.extend(0.0), v.extend(0.0), n.extend(0.0), c.extend(1.0));
    ShapeGeometry::Mesh(TriangleMesh::unit_rectangle().transformed(&m))
}

/// A medium sphere (chromatic σt, albedo 0.8, HG g = 0.5) on a diffuse floor under a square area
/// light, behind a `null` boundary or inside glass (IOR 1.33); the camera in vacuum.
pub(crate) fn medium_sphere(glass: bool) -> Scene {
    let hg = PhaseFunction::henyey_greenstein(0.5).unwrap();
    medium_sphere_with(glass, homogeneous(Color::new(2.0, 1.2, 0.6), 0.8, hg))
}

/// The sphere's centre and radius.
const SPHERE: (Vec3, f32) = (Vec3::new(0.0, -0.2, 0.0), 0.8);

/// The medium sphere filled with a heterogeneous grid instead: σt on 4³ samples between 0.3 and
/// 3.3 (chromatic, three channels), albedo 0.8, HG g = −0.3, over the sphere's bounding box.
pub(crate) fn grid_sphere() -> Scene {
    let n = 4;
    let mut data = Vec::with_capacity(n * n * n * 3);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let f = ((i * 7 + j * 3 + k * 5) % 11) as f32 / 10.0;
                data.extend([0.3 + 3.0 * f, 0.3 + 2.0 * (1.0 - f), 1.0 + f]);
            }
        }
    }
    let grid = VolumeGrid::new([n, n, n], 3, data, [Vec3::ZERO, Vec3::ONE]).unwrap();
    let (c, r) = SPHERE;
    let to_world =
        Mat4::from_translation(c - Vec3::splat(r)) * Mat4::from_scale(Vec3::splat(2.0 * r));
    let vol = GridVolume::new(std::sync::Arc::new(grid), to_world, false, WrapMode::Clamp).unwrap();
    let hg = PhaseFunction::henyey_greenstein(-0.3).unwrap();
    let albedo = Volume::constant(Color::splat(0.8));
    let m = GridMedium::new(Volume::Grid(vol), 1.0, albedo, hg).unwrap();
    medium_sphere_with(false, Medium::Grid(Box::new(m)))
}

fn medium_sphere_with(glass: bool, medium: Medium) -> Scene {
    let camera = Camera::look_at(
        Vec3::new(0.0, 0.6, 4.0),
        Vec3::new(0.0, -0.3, 0.0),
        Vec3::Y,
        45.0,
        FovAxis::X,
        24,
        24,
    )
    .unwrap();
    let settings = RenderSettings {
        max_depth: 12,
        rr_depth: 5,
        spp: 1,
    };
    let mut b = SceneBuilder::new(camera, settings);
    let m = b.add_medium(medium);
    let floor = b.add_material(Material::Diffuse(Diffuse {
        albedo: Color::splat(0.6),
    }));
    let black = b.add_material(Material::Diffuse(Diffuse {
        albedo: Color::ZERO,
    }));
    let boundary = if glass {
        b.add_material(Material::Dielectric(Dielectric { ior: 1.33 }))
    } else {
        b.add_material(Material::Null(Null))
    };
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    b.add_shape(quad(-y, 2.0 * z, 2.0 * x), floor, None, false);
    b.add_shape(
        quad(Vec3::new(0.3, 1.5, 0.2), 0.5 * x, 0.5 * z),
        black,
        Some(Color::splat(6.0)),
        false,
    );
    let sphere = ShapeGeometry::Sphere {
        center: SPHERE.0,
        radius: SPHERE.1,
    };
    b.add_shape(sphere, boundary, None, false);
    b.set_last_shape_media(MediumInterface {
        interior: Some(m),
        exterior: None,
    });
    b.build()
}

fn agree(scene: &Scene, a: (&str, u32), b: (&str, u32)) {
    let p = IntegratorParams::default;
    let (ra, ba) = render_blocks(scene, a.0, p(), a.1, 21, 8);
    let (rb, bb) = render_blocks(scene, b.0, p(), b.1, 22, 8);
    assert_eq!(
        ra.invalid_samples + rb.invalid_samples,
        0,
        "invalid samples"
    );
    for (name, r) in [(a.0, &ra), (b.0, &rb)] {
        let bad = r
            .estimate
            .data
            .iter()
            .filter(|c| !c.iter().all(|&v| v >= 0.0))
            .count();
        assert_eq!(bad, 0, "{name}: {bad} NaN or negative pixels");
    }
    let result = agreement_t(&ba, &bb, ALPHA);
    println!("{} vs {}: {result}", a.0, b.0);
    assert!(result.passed(), "{} vs {}: {result}", a.0, b.0);
}

/// Passes per integrator when held to `pt` on the medium sphere, in the order the registry lists
/// `HANDLES_MEDIA`; `None`: the integrator cannot see the scene (light tracing through glass,
/// which the camera sees only through the delta refraction).
fn agreement_passes(name: &str, glass: bool) -> Option<u32> {
    match name {
        "pt" => None,
        "pt-bsdf" => Some(512),
        "light" if glass => None,
        "light" => Some(128),
        "bdpt" => Some(32),
        // Their kernels need ~10⁴ photon paths per pass to be judged by runs' spread: held to pt
        // on every shipped media scene by agreement.rs and tests/points_beams.rs instead.
        "pp3d" | "pb2d" | "bb1d" | "bp2d" => None,
        // Consistent as they are: held to pt on every shipped media scene by agreement.rs
        // (runs' spread), its weights by tests/mis_check_upbp.rs.
        "upbp" => None,
        _ => panic!("{name} walks media: give it agreement passes here"),
    }
}

#[test]
fn media_integrators_agree_with_pt_on_a_null_bounded_medium() {
    let scene = medium_sphere(false);
    for name in lt_integrators::registry::HANDLES_MEDIA {
        if let Some(passes) = agreement_passes(name, false) {
            agree(&scene, ("pt", 64), (name, passes));
        }
    }
}

#[test]
fn media_integrators_agree_with_pt_on_a_medium_inside_glass() {
    let scene = medium_sphere(true);
    for name in lt_integrators::registry::HANDLES_MEDIA {
        if let Some(passes) = agreement_passes(name, true) {
            agree(&scene, ("pt", 64), (name, passes));
        }
    }
}

#[test]
fn bdpt_agrees_with_pt_on_a_heterogeneous_grid() {
    // Ratio tracking on every connection and the grid's free-flight densities in the weights.
    let scene = grid_sphere();
    agree(&scene, ("pt", 64), ("bdpt", 32));
}

#[test]
fn media_walks_are_deterministic_across_thread_counts() {
    for (scene, name) in [medium_sphere(false), grid_sphere()].iter().flat_map(|s| {
        lt_integrators::registry::HANDLES_MEDIA
            .iter()
            .map(move |n| (s, *n))
    }) {
        let integ = make_integrator(name, &scene, &IntegratorParams::default()).unwrap();
        let image = |threads| {
            let opts = RenderOptions {
                passes: 2,
                time_limit: None,
                seed: 5,
                threads,
            };
            render(&scene, &integ, &opts, |_| ControlFlow::Continue(()))
                .unwrap()
                .estimate
        };
        let (one, two) = (image(1), image(2));
        let same = one
            .data
            .iter()
            .zip(&two.data)
            .all(|(a, b)| (0..3).all(|c| a[c].to_bits() == b[c].to_bits()));
        assert!(same, "{name}: images differ between 1 and 2 threads");
    }
}

#[test]
fn integrators_without_media_refuse_a_scene_with_media() {
    let scene = medium_sphere(false);
    for info in lt_integrators::INTEGRATORS {
        let made = make_integrator(info.name, &scene, &IntegratorParams::default());
        if lt_integrators::registry::HANDLES_MEDIA.contains(&info.name) {
            assert!(made.is_ok(), "{} refused a media scene", info.name);
            continue;
        }
        let Err(e) = made else {
            panic!("{} accepted a scene with media", info.name);
        };
        let want = format!(
            "integrator {} does not handle participating media yet; the scene has 1 media",
            info.name
        );
        assert_eq!(e, want);
    }
}

/// A floor (diffuse 0.6) under a square area light, for Mitsuba's two walk rules below: a
/// fog-filled null sphere around everything (`fog_around`: the camera and the light declared in
/// it, the floor too when `floor_named`) or a small one out of view (so that the media walks run);
/// `pane`, a thin dielectric of IOR 1 (R' = 0: every sample passes straight through) between the
/// light and the floor.
fn floor_scene(floor_named: bool, pane: bool, fog_around: bool) -> Scene {
    let camera = Camera::look_at(
        Vec3::new(0.0, 0.8, 2.0),
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::Y,
        50.0,
        FovAxis::X,
        16,
        16,
    )
    .unwrap();
    let settings = RenderSettings {
        max_depth: 2,
        rr_depth: 5,
        spp: 1,
    };
    let mut b = SceneBuilder::new(camera, settings);
    let fog = b.add_medium(homogeneous(
        Color::new(0.6, 0.4, 0.2),
        0.0,
        PhaseFunction::Isotropic,
    ));
    let floor = b.add_material(Material::Diffuse(Diffuse {
        albedo: Color::splat(0.6),
    }));
    let black = b.add_material(Material::Diffuse(Diffuse {
        albedo: Color::ZERO,
    }));
    let null = b.add_material(Material::Null(Null));
    let in_fog = MediumInterface {
        interior: Some(fog),
        exterior: Some(fog),
    };
    let (x, z) = (Vec3::X, Vec3::Z);
    b.add_shape(quad(Vec3::ZERO, 3.0 * z, 3.0 * x), floor, None, false);
    if floor_named {
        b.set_last_shape_media(in_fog);
    }
    b.add_shape(
        quad(Vec3::new(0.0, 2.0, 0.0), 0.5 * x, 0.5 * z),
        black,
        Some(Color::splat(5.0)),
        false,
    );
    if fog_around {
        // The light emits into the fog (`Scene::light_medium_towards` reads its declared exterior).
        b.set_last_shape_media(in_fog);
    }
    if pane {
        let glass = b.add_material(Material::ThinDielectric(lt_core::bsdf::ThinDielectric {
            ior: 1.0,
            ..Default::default()
        }));
        b.add_shape(
            quad(Vec3::new(0.0, 1.5, 0.0), 3.0 * z, 3.0 * x),
            glass,
            None,
            false,
        );
    }
    // Around everything (radius 10, the camera inside it) or out of view.
    let (center, radius) = if fog_around {
        (Vec3::ZERO, 10.0)
    } else {
        (Vec3::new(0.0, 0.0, 30.0), 0.1)
    };
    b.add_shape(ShapeGeometry::Sphere { center, radius }, null, None, false);
    b.set_last_shape_media(MediumInterface {
        interior: Some(fog),
        exterior: None,
    });
    if fog_around {
        b.set_camera_medium(Some(fog));
    }
    b.build()
}

fn image_bits(scene: &Scene, integrator: &str) -> Vec<[u64; 3]> {
    let integ = make_integrator(integrator, scene, &IntegratorParams::default()).unwrap();
    let opts = RenderOptions {
        passes: 4,
        time_limit: None,
        seed: 9,
        threads: 0,
    };
    let image = render(scene, &integ, &opts, |_| ControlFlow::Continue(()))
        .unwrap()
        .estimate;
    image.data.iter().map(|p| p.map(f64::to_bits)).collect()
}

/// Mitsuba's rule: a shape that declares no media is no medium transition — a path leaving it
/// stays in the fog it arrived in (`Scene::medium_after`). So a floor inside fog that names no
/// media renders the same bits as one naming the fog on both sides. Before the rule, the walk
/// left it into vacuum: shadow rays and camera joins from the floor were not attenuated (the
/// suite's obj_inside_medium: max |z| 25).
#[test]
fn a_shape_without_media_keeps_the_fog_it_sits_in() {
    let silent = floor_scene(false, false, true);
    let named = floor_scene(true, false, true);
    for integrator in ["pt", "light"] {
        assert!(
            image_bits(&silent, integrator) == image_bits(&named, integrator),
            "{integrator}: a floor in fog that names no media renders differently from one \
             naming the fog"
        );
    }
}

/// Mitsuba's `volpath` counts a thin dielectric's straight pass-through as a null event, not a
/// bounce (its `BSDFFlags::Null` lobe): with max_depth 2 (direct light only) a pane of IOR 1
/// between the light and the floor changes nothing — pt-bsdf reaches the light through it,
/// light tracing joins the floor to the camera.
/// Before, the pane took the one bounce and the floor went black.
#[test]
fn a_thin_dielectrics_pass_through_is_no_bounce() {
    let open = floor_scene(false, false, false);
    let paned = floor_scene(false, true, false);
    // pt-bsdf: pt's media walk without next-event estimation, whose shadow rays would pass the
    // pane anyway (a planted count of the pane as a bounce moved pt by 0.6 % only).
    agree_scenes(&paned, &open, ("pt-bsdf", 256), ("pt", 64));
    agree_scenes(&paned, &open, ("light", 64), ("light", 64));
}

/// `agree` between two scenes of the same camera.
fn agree_scenes(sa: &Scene, sb: &Scene, a: (&str, u32), b: (&str, u32)) {
    let p = IntegratorParams::default;
    let (ra, ba) = render_blocks(sa, a.0, p(), a.1, 23, 4);
    let (rb, bb) = render_blocks(sb, b.0, p(), b.1, 24, 4);
    assert_eq!(ra.invalid_samples + rb.invalid_samples, 0);
    let result = agreement_t(&ba, &bb, ALPHA);
    println!("{} (pane) vs {} (open): {result}", a.0, b.0);
    assert!(
        result.passed(),
        "{} (pane) vs {} (open): {result}",
        a.0,
        b.0
    );
}

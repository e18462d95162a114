//! A directional light (a delta in direction) on a lone diffuse plane, against the closed form:
//! a Lambertian plane of albedo ρ under directional lights of irradiance E_i at angles θ_i from
//! its normal has radiance L = ρ/π Σ E_i cos θ_i everywhere, and nothing else lights it (a plane
//! cannot see itself). Every registered integrator (`lt_integrators::INTEGRATORS`, so a new one
//! is covered with no new test code), and the photon family also with direct light from photons
//! (`direct=photons`: a kernel estimate of a uniform photon density, unbiased away from the
//! plane's edges, which the camera does not see), must reproduce it per 8×8 block within
//! Šidák-corrected standard errors — except `pt-bsdf`, which must be exactly black (no BSDF
//! sample hits a single direction). With one light and a light-selection pmf of 1, next-event
//! estimation at a plane point is deterministic: an estimator whose blocks then have no spread
//! must equal the closed form to rounding. Two lights of unequal power make the pmfs 0.62/0.38.

use lt_core::bsdf::{Diffuse, Material};
use lt_core::camera::{Camera, FovAxis};
use lt_core::math::PI;
use lt_core::scene::{LightDesc, RenderSettings, SceneBuilder, ShapeGeometry, TriangleMesh};
use lt_core::{Color, Scene, Vec2, Vec3};
use lt_estimators::agreement::agreement_with_reference_t;
use lt_integrators::{IntegratorParams, Kind, INTEGRATORS};
use lt_tests::{assert_same_image_as_pt, is_pt_without_media, render_blocks};

/// Family-wise false-alarm rate of one configuration's block tests.
const ALPHA: f64 = 1e-3;
const BLOCK: usize = 8;
const HALF: f32 = 1.5;
/// Passes of an unbiased estimator, and of each of the independent runs of a consistent one;
/// light tracing, which spreads 256 light paths a pass over the whole plane, takes 4× as many.
const PASSES: u32 = 256;

fn albedo() -> Color {
    Color::new(0.8, 0.5, 0.3)
}

/// (direction towards the light, irradiance) of each directional light of a case.
type Lights = &'static [([f32; 3], [f32; 3])];

/// One light 60° off the normal (cos θ = 1/2).
const ONE: Lights = &[([0.692_820_3, 0.5, 0.519_615_2], [2.0, 1.5, 1.0])];
/// That light and a dimmer one 24° off the normal from the other side.
const TWO: Lights = &[
    ([0.692_820_3, 0.5, 0.519_615_2], [2.0, 1.5, 1.0]),
    ([-0.3, 0.9, 0.2], [0.5, 1.0, 1.5]),
];

/// Integrators that must render these scenes black: (name, reason).
const BLACK: &[(&str, &str)] = &[(
    "pt-bsdf",
    "BSDF sampling alone never hits the single direction of a directional light",
)];

/// Configurations that fail because of an integrator bug, kept asserted (each must still fail,
/// so a fix is noticed and the entry removed): (name, label, the bug).
// Empty: vcm gave about twice the radiance (ratio 1.96) while its subpath records gated
// technique 1 (next-event estimation) on x0 being connectable, which a directional light is not.
const KNOWN_FAILURES: &[(&str, &str, &str)] = &[];

/// Configurations this test's budget cannot hold to 2 % (name, reason): reported, not rendered.
// Empty: mmlt sat here at 4.5 % standard error (11 runs) while each length's b̂_k came from one
// random strategy times k + 1; with b̂_k the sum over all strategies of the same bootstrap points
// it is at 0.8 % (one light) and 1.7 % (two).
const IMPRECISE: &[(&str, &str)] = &[];

/// The square [-HALF, HALF]² at y = 0 (normal +y), seen obliquely from above; the camera sees
/// only its middle.
fn plane(lights: Lights) -> Scene {
    let camera = Camera::look_at(
        Vec3::new(0.0, 1.6, 1.0),
        Vec3::ZERO,
        Vec3::Y,
        35.0,
        FovAxis::X,
        16,
        16,
    )
    .unwrap();
    let settings = RenderSettings {
        max_depth: 8,
        rr_depth: 5,
        spp: 1,
    };
    let mut b = SceneBuilder::new(camera, settings);
    let m = b.add_material(Material::Diffuse(Diffuse { albedo: albedo() }));
    let to_floor = lt_core::math::Mat4::from_rotation_x(-PI / 2.0)
        * lt_core::math::Mat4::from_scale(Vec3::splat(HALF));
    b.add_shape(
        ShapeGeometry::Mesh(TriangleMesh::unit_rectangle().transformed(&to_floor)),
        m,
        None,
        false,
    );
    for &(d, e) in lights {
        b.add_light(LightDesc::Directional {
            direction: Vec3::from_array(d).normalize(),
            irradiance: Color::from_array(e),
        });
    }
    b.build()
}

/// L = ρ/π Σ E_i cos θ_i, per channel.
fn exact(lights: Lights) -> [f64; 3] {
    let mut l = [0.0f64; 3];
    for &(d, e) in lights {
        let cos = Vec3::from_array(d).normalize().y as f64;
        for c in 0..3 {
            l[c] += albedo()[c] as f64 / std::f64::consts::PI * e[c] as f64 * cos;
        }
    }
    l
}

/// Every pixel sees the plane at least `margin` inside its edges (so a photon kernel there is
/// unbiased), checked at the corners of every pixel.
fn assert_camera_sees_only_the_middle(scene: &Scene, margin: f32) {
    let cam = &scene.camera;
    for j in 0..=cam.height {
        for i in 0..=cam.width {
            let ray = cam.generate_ray(Vec2::new(i as f32, j as f32));
            let hit = scene.intersect(&ray).expect("every ray hits the plane");
            let p = hit.p + scene.origin;
            assert!(
                p.x.abs() < HALF - margin && p.z.abs() < HALF - margin && hit.ng.y > 0.99,
                "pixel corner ({i}, {j}) sees {p}"
            );
        }
    }
}

/// The configurations (name, label, parameters, passes): every registered integrator with its
/// defaults, and (if `with_direct_photons`) each one that takes `direct` also with
/// `direct=photons` (`pm` then with 512× its default photon count: its one photon map per run is
/// the whole of its spread across runs).
fn configs(with_direct_photons: bool) -> Vec<(&'static str, String, IntegratorParams, u32)> {
    let mut out = Vec::new();
    for info in INTEGRATORS {
        let passes = match info.name {
            "light" => 4 * PASSES,
            // No medium: bdpt's connections under upbp's weights, in CONSISTENT_RUNS runs;
            // PASSES / 8 per run is bdpt's cost.
            "upbp" => PASSES / 8,
            _ => PASSES,
        };
        out.push((
            info.name,
            String::new(),
            IntegratorParams::default(),
            passes,
        ));
        if with_direct_photons
            && info.kind == Kind::Consistent
            && info.source.contains("| `direct` |")
        {
            let mut p = IntegratorParams::new().with("direct", "photons");
            let mut label = " direct=photons".to_string();
            if info.source.contains("| `photons` |") {
                p = p.with("photons", 512 * 256);
                label += " photons=131072";
            }
            out.push((info.name, label, p, passes));
        }
    }
    out
}

/// Renders one configuration on one case; `Err` says how it failed.
fn run(
    case: &str,
    lights: Lights,
    name: &str,
    label: &str,
    p: IntegratorParams,
    passes: u32,
) -> Result<String, String> {
    let scene = plane(lights);
    let who = format!("{case}: {name}{label}");
    if is_pt_without_media(name) {
        assert_same_image_as_pt(&scene, &who, name);
        return Ok(format!("{who}: pt's image bit for bit (PT_WITHOUT_MEDIA)"));
    }
    let (rendered, blocks) = render_blocks(&scene, name, p, passes, 11, BLOCK);
    if rendered.invalid_samples != 0 {
        return Err(format!(
            "{who}: {} invalid samples",
            rendered.invalid_samples
        ));
    }
    let e = blocks.estimate();
    if let Some((_, why)) = BLACK.iter().find(|(n, _)| *n == name) {
        let lit = rendered.estimate.data.iter().flatten().any(|v| *v != 0.0);
        return if lit {
            Err(format!("{who}: expected black ({why}), found light"))
        } else {
            Ok(format!("{who}: black ({why})"))
        };
    }
    let expected = exact(lights);
    let reference = vec![expected; e.regions()];
    let (mean, se) = (e.mean[0], e.std_error[0]);
    let ratio = [0, 1, 2].map(|c| mean[c] / expected[c]);
    let deterministic = e.std_error.iter().flatten().all(|&s| s == 0.0);
    if deterministic {
        // Next-event estimation with one light: every sample is ρ/π E cos θ, up to rounding.
        let worst = e
            .mean
            .iter()
            .flat_map(|m| (0..3).map(move |c| (m[c] / expected[c] - 1.0).abs()))
            .fold(0.0f64, f64::max);
        let summary = format!("{who}: no spread; worst relative error {worst:.2e}");
        return if worst <= 1e-5 {
            Ok(summary)
        } else {
            Err(summary)
        };
    }
    let a = agreement_with_reference_t(&blocks, &reference, ALPHA);
    let summary =
        format!("{who}: block 0 {mean:.5?} ± {se:.5?} (ratio {ratio:.4?}) vs {expected:.5?}: {a}");
    if !a.passed() {
        return Err(summary);
    }
    // Non-trivial: the blocks have a real spread, small enough to see a bias of a few per cent.
    let worst_rel_se = (0..e.regions())
        .flat_map(|i| (0..3).map(move |c| (i, c)))
        .map(|(i, c)| e.std_error[i][c] / expected[c])
        .fold(0.0f64, f64::max);
    if !(worst_rel_se < 0.02) {
        return Err(format!(
            "{summary}; relative standard error {worst_rel_se:.3} not below 2 %"
        ));
    }
    Ok(summary)
}

fn check_case(case: &str, lights: Lights) {
    let scene = plane(lights);
    assert_camera_sees_only_the_middle(&scene, 0.3);
    if lights.len() == 2 {
        let pmf = scene.light_sampler.pmf(0);
        assert!((0.55..0.7).contains(&pmf), "pmf {pmf}");
    }
    let mut failures = Vec::new();
    // `direct=photons` under two lights only: photons leave a directional light by the same
    // code for one light or two, and two also draw the light by its pmf (0.62 / 0.38); the
    // photon configurations are most of this file's cost (8 runs each).
    for (name, label, p, passes) in configs(lights.len() == 2) {
        if let Some((_, why)) = IMPRECISE.iter().find(|(n, _)| *n == name) {
            println!("{case}: {name}{label}: not run ({why})");
            continue;
        }
        let known = KNOWN_FAILURES
            .iter()
            .find(|(n, l, _)| *n == name && *l == label)
            .map(|(_, _, why)| *why);
        match (run(case, lights, name, &label, p, passes), known) {
            (Ok(s), None) => println!("{s}"),
            (Err(e), None) => {
                println!("{e}  FAILED");
                failures.push(e);
            }
            (Err(e), Some(why)) => println!("{e}  KNOWN FAILURE ({why})"),
            (Ok(s), Some(why)) => failures.push(format!(
                "{s}: listed in KNOWN_FAILURES ({why}) but now passes: remove it"
            )),
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

#[test]
fn every_integrator_renders_a_plane_under_a_directional_light() {
    check_case("one directional light", ONE);
}

#[test]
fn every_integrator_renders_a_plane_under_two_directional_lights() {
    check_case("two directional lights", TWO);
}

//! Photons against closed-form answers.
//!
//! 1. The flux photons carry is the lights' power. Over N photon paths a photon's flux is β / N
//!    (`photons::Photon::beta`), so the flux landing on a surface is Σ β / N over the photons
//!    stored on it. Every surface here is black (albedo 0), so a photon path ends at its first hit
//!    and leaves at most one photon, with `segments == 1`: the per-path values are independent and
//!    their spread is the estimate's standard error. Finite lights sit in a closed black box, which
//!    catches all they emit: Φ_area = π Le A (one-sided Lambertian emitter, docs/scene-format.md),
//!    Φ_point = 4π I. Lights at infinity emit through the disk of radius R (the scene's bounding
//!    sphere) perpendicular to each direction, so a black sphere of radius r catches
//!    L π r² per unit solid angle of emission — 4π² r² L for a constant environment, Ω π r² L for
//!    the sun (its radiance is L inside a cone of Ω sr, `light/sun.rs`) — and a black quad of area A
//!    catches E A, with E = π L per side for the environment and E = L (n·a) π sin²θmax for the sun
//!    on the side facing it (a cone of half-angle θmax around a, wholly above the quad's horizon).
//!    A directional light of irradiance E (a delta in direction) sends E through every unit of the
//!    disk's area: the sphere catches E π r², the quad E A (n·a) on the side facing it.
//!    The luminance of the emitted flux is also held to `Light::power`, what light selection uses.
//! 2. A thin wall lit from behind stays black in front, for every registered integrator, with
//!    photons gathered for direct light where an integrator offers it.

use lt_core::bsdf::{Diffuse, Material};
use lt_core::camera::{Camera, FovAxis};
use lt_core::math::{luminance, Color, Mat4, Vec3, PI};
use lt_core::scene::{LightDesc, RenderSettings, SceneBuilder, ShapeGeometry, TriangleMesh};
use lt_core::Scene;
use lt_estimators::agreement::sidak_threshold;
use lt_integrators::density::photons::{trace_photons, Photon, PhotonOptions};
use lt_integrators::params::documented_keys;
use lt_integrators::{make_integrator, render, IntegratorParams, RenderOptions, INTEGRATORS};
use std::ops::ControlFlow;

/// Photon paths per flux case: the relative standard error of a catcher hit with probability p is
/// √((1 − p) / (p N)) ≈ 1e-3, small enough to see the sun's cosine integral (1.6 % at Ω = 0.2).
const N: u64 = 1 << 20;

/// Family-wise false-alarm rate of all the z-tests of one test function.
const ALPHA: f64 = 1e-3;

fn camera() -> Camera {
    Camera::look_at(
        Vec3::new(0.1, 0.2, 1.5),
        Vec3::ZERO,
        Vec3::Y,
        40.0,
        FovAxis::X,
        8,
        8,
    )
    .unwrap()
}

fn black(b: &mut SceneBuilder) -> u32 {
    b.add_material(Material::Diffuse(Diffuse {
        albedo: Color::ZERO,
    }))
}

/// The closed black box [-2, 2]³ around a finite light.
fn boxed(add_light: impl FnOnce(&mut SceneBuilder, u32)) -> Scene {
    let mut b = SceneBuilder::new(camera(), RenderSettings::default());
    let m = black(&mut b);
    let cube = TriangleMesh::unit_cube().transformed(&Mat4::from_scale(Vec3::splat(2.0)));
    b.add_shape(ShapeGeometry::Mesh(cube), m, None, false);
    add_light(&mut b, m);
    b.build()
}

/// A lone black catcher under a light at infinity.
fn caught(catcher: ShapeGeometry, light: LightDesc) -> Scene {
    let mut b = SceneBuilder::new(camera(), RenderSettings::default());
    let m = black(&mut b);
    b.add_shape(catcher, m, None, false);
    b.add_light(light);
    b.build()
}

/// Mean and standard error of the flux landing on the photons `keep` accepts, per channel
/// (R, G, B, luminance), from the N per-path values (zero for paths that left no such photon).
struct Flux {
    mean: [f64; 4],
    se: [f64; 4],
    /// Photons kept.
    kept: u64,
}

fn channels(c: Color) -> [f64; 4] {
    [c.x as f64, c.y as f64, c.z as f64, luminance(c) as f64]
}

fn landing_flux(scene: &Scene, seed: u64, keep: impl Fn(&Photon) -> bool) -> Flux {
    let opts = PhotonOptions {
        max_segments: 8,
        rr_depth: 8,
        skip_direct: false,
    };
    let batch = trace_photons(scene, seed, 0, 0, N, opts);
    assert_eq!(batch.paths, N);
    // Black surfaces: every path ends at its first hit, so it left at most one photon and the
    // photons are the per-path values.
    assert!(
        batch.photons.iter().all(|p| p.segments == 1),
        "a photon path continued past a black surface"
    );
    assert!(batch.photons.len() as u64 <= N);
    let kept: Vec<[f64; 4]> = batch
        .photons
        .iter()
        .filter(|p| keep(p))
        .map(|p| channels(p.beta))
        .collect();
    let n = N as f64;
    let mut mean = [0.0; 4];
    for v in &kept {
        for k in 0..4 {
            mean[k] += v[k] / n;
        }
    }
    // Two passes (mean first), so a constant per-path value gives a spread of zero rather than
    // the cancellation error of Σx² − N x̄².
    let mut se = [0.0; 4];
    for k in 0..4 {
        let hits: f64 = kept.iter().map(|v| (v[k] - mean[k]).powi(2)).sum();
        let misses = (n - kept.len() as f64) * mean[k] * mean[k];
        se[k] = ((hits + misses) / (n - 1.0) / n).sqrt();
    }
    Flux {
        mean,
        se,
        kept: kept.len() as u64,
    }
}

/// One flux case: what was measured and what it should be.
struct Case {
    name: &'static str,
    flux: Flux,
    /// Expected flux per channel (R, G, B).
    expected: Color,
    /// `Light::power` scaled to this catcher, which the flux's luminance must match, when the
    /// catcher's flux is a known fraction of the light's whole emission.
    power: Option<f64>,
    /// A closed box around a finite light: every photon path must land.
    closed: bool,
}

/// Rounding allowance of a flux whose per-path value is constant by construction (an area light's
/// β = Le A π, a point light's 4π I, Le/pdf with the cosine cancelled): its spread is zero up to
/// f32 rounding, so the z-test alone would test rounding. β is a product and quotient of at most
/// ~32 rounded f32 values (the area's cross product and length, 1/A, the cosine and its density,
/// the light's pdfs), each a relative error of at most u: |Δβ/β| ≤ γ(32) (pbrt's γ_n).
fn rounding(expected: f64) -> f64 {
    lt_core::math::gamma(32) as f64 * expected.abs()
}

fn flux_cases() -> Vec<Case> {
    let mut cases = Vec::new();
    let up = |p: &Photon| p.wi.dot(p.ng) > 0.0;
    let down = |p: &Photon| p.wi.dot(p.ng) < 0.0;

    // Area lights, one-sided: Φ = π Le A.
    let le = Color::new(1.0, 0.6, 0.3);
    // A unit square (side 1, A = 1), rotated off the axes.
    let rot = Mat4::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.7);
    let quad =
        TriangleMesh::unit_rectangle().transformed(&(rot * Mat4::from_scale(Vec3::splat(0.5))));
    let s = boxed(|b, m| b.add_shape(ShapeGeometry::Mesh(quad), m, Some(le), false));
    cases.push(Case {
        name: "area quad",
        flux: landing_flux(&s, 1, |_| true),
        expected: le * PI,
        power: Some(s.lights[0].power(s.bounding_sphere) as f64),
        closed: true,
    });
    // A sphere, A = 4π r².
    let r = 0.3f32;
    let s = boxed(|b, m| {
        b.add_shape(
            ShapeGeometry::Sphere {
                center: Vec3::new(0.2, -0.1, 0.3),
                radius: r,
            },
            m,
            Some(le),
            false,
        )
    });
    cases.push(Case {
        name: "area sphere",
        flux: landing_flux(&s, 2, |_| true),
        expected: le * PI * (4.0 * PI * r * r),
        power: Some(s.lights[0].power(s.bounding_sphere) as f64),
        closed: true,
    });
    // A tetrahedron O, a x, b y, c z with outward windings: four triangles, no two forming a
    // parallelogram, so the emitter picks a triangle by area. A = (ab + ac + bc)/2 + the slanted
    // face ½ √(a²b² + a²c² + b²c²).
    let (ta, tb, tc) = (0.8f32, 0.6f32, 0.5f32);
    let tetra = TriangleMesh {
        positions: vec![
            Vec3::ZERO,
            Vec3::new(ta, 0.0, 0.0),
            Vec3::new(0.0, tb, 0.0),
            Vec3::new(0.0, 0.0, tc),
        ],
        normals: None,
        uvs: None,
        indices: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        attributes: Vec::new(),
    };
    let (a, b, c) = (ta as f64, tb as f64, tc as f64);
    let area = (a * b + a * c + b * c) / 2.0
        + 0.5 * (a * a * b * b + a * a * c * c + b * b * c * c).sqrt();
    let s = boxed(|bl, m| bl.add_shape(ShapeGeometry::Mesh(tetra), m, Some(le), false));
    cases.push(Case {
        name: "area tetrahedron",
        flux: landing_flux(&s, 3, |_| true),
        expected: le * PI * area as f32,
        power: Some(s.lights[0].power(s.bounding_sphere) as f64),
        closed: true,
    });

    // Point light: Φ = 4π I.
    let intensity = Color::new(2.0, 1.0, 0.5);
    let s = boxed(|b, _| {
        b.add_light(LightDesc::Point {
            position: Vec3::new(0.3, -0.2, 0.1),
            intensity,
        })
    });
    cases.push(Case {
        name: "point",
        flux: landing_flux(&s, 4, |_| true),
        expected: intensity * (4.0 * PI),
        power: Some(s.lights[0].power(s.bounding_sphere) as f64),
        closed: true,
    });

    // Lights at infinity. A black unit sphere (bounding sphere R = √3, the half-diagonal of its
    // box) catches L π r² per unit solid angle of emission: the fraction (r/R)² of the power.
    let env = Color::new(0.5, 1.0, 2.0);
    let sphere = ShapeGeometry::Sphere {
        center: Vec3::ZERO,
        radius: 1.0,
    };
    let catch_fraction =
        |s: &Scene| 1.0 / (s.bounding_sphere.1 as f64 * s.bounding_sphere.1 as f64);
    let s = caught(sphere.clone(), LightDesc::Environment { radiance: env });
    cases.push(Case {
        name: "environment on a sphere",
        flux: landing_flux(&s, 5, |_| true),
        expected: env * (4.0 * PI * PI),
        power: Some(s.lights[0].power(s.bounding_sphere) as f64 * catch_fraction(&s)),
        closed: false,
    });
    // The square [-1, 1]² (A = 4, normal +z) sees each hemisphere of the environment on one side.
    let plane = || ShapeGeometry::Mesh(TriangleMesh::unit_rectangle());
    let s = caught(plane(), LightDesc::Environment { radiance: env });
    cases.push(Case {
        name: "environment on a quad, top",
        flux: landing_flux(&s, 6, up),
        expected: env * (PI * 4.0),
        power: None,
        closed: false,
    });
    cases.push(Case {
        name: "environment on a quad, bottom",
        flux: landing_flux(&s, 6, down),
        expected: env * (PI * 4.0),
        power: None,
        closed: false,
    });

    // The sun, with a cone wide enough (Ω = 0.2 sr, θmax ≈ 14.5°) that the cosine integral
    // π sin²θmax = π h (2 − h), h = 1 − cos θmax = Ω / 2π, differs from Ω by 1.6 %.
    let sun_l = Color::new(3.0, 2.0, 1.0);
    let omega = 0.2f32;
    let axis = Vec3::new(0.3, 0.2, 1.0).normalize();
    let sun = LightDesc::Sun {
        direction: axis,
        solid_angle: omega,
        radiance: sun_l,
    };
    let s = caught(sphere, sun.clone());
    cases.push(Case {
        name: "sun on a sphere",
        flux: landing_flux(&s, 7, |_| true),
        expected: sun_l * (omega * PI),
        power: Some(s.lights[0].power(s.bounding_sphere) as f64 * catch_fraction(&s)),
        closed: false,
    });
    let s = caught(plane(), sun);
    let h = omega as f64 / (2.0 * std::f64::consts::PI);
    let cosine_integral = axis.z as f64 * std::f64::consts::PI * h * (2.0 - h);
    cases.push(Case {
        name: "sun on a quad, facing it",
        flux: landing_flux(&s, 8, up),
        expected: sun_l * (4.0 * cosine_integral) as f32,
        power: None,
        closed: false,
    });
    // The cone (axis 19.7° off the normal, half-angle 14.5°) lies above the quad's horizon: no
    // sunlight reaches the underside, exactly.
    let under = landing_flux(&s, 8, down);
    assert_eq!(under.kept, 0, "sunlight reached the quad's underside");

    // A directional light along the sun's axis: every photon path carries E π R² / pmf, so only
    // whether it lands varies.
    let irradiance = Color::new(2.0, 3.0, 1.0);
    let directional = LightDesc::Directional {
        direction: axis,
        irradiance,
    };
    let unit_sphere = ShapeGeometry::Sphere {
        center: Vec3::ZERO,
        radius: 1.0,
    };
    let s = caught(unit_sphere, directional.clone());
    cases.push(Case {
        name: "directional on a sphere",
        flux: landing_flux(&s, 9, |_| true),
        expected: irradiance * PI,
        power: Some(s.lights[0].power(s.bounding_sphere) as f64 * catch_fraction(&s)),
        closed: false,
    });
    let s = caught(plane(), directional);
    cases.push(Case {
        name: "directional on a quad, facing it",
        flux: landing_flux(&s, 10, up),
        expected: irradiance * (4.0 * axis.z),
        power: None,
        closed: false,
    });
    let under = landing_flux(&s, 10, down);
    assert_eq!(
        under.kept, 0,
        "directional light reached the quad's underside"
    );
    cases
}

#[test]
fn emitted_flux_equals_each_lights_power() {
    let start = std::time::Instant::now();
    let cases = flux_cases();
    let tests: usize = cases.iter().map(|c| 3 + c.power.is_some() as usize).sum();
    let t = sidak_threshold(ALPHA, tests);
    let mut failures = Vec::new();
    for c in &cases {
        if c.closed && c.flux.kept != N {
            failures.push(format!(
                "{}: {} of {N} photon paths left the closed box",
                c.name,
                N - c.flux.kept
            ));
        }
        let (r, g, b) = (
            c.expected.x as f64,
            c.expected.y as f64,
            c.expected.z as f64,
        );
        // R, G, B against the closed form; luminance against Light::power where known.
        let expected: Vec<f64> = [r, g, b].into_iter().chain(c.power).collect();
        for (k, &e) in expected.iter().enumerate() {
            let (m, se) = (c.flux.mean[k], c.flux.se[k]);
            let what = ["R", "G", "B", "luminance vs Light::power"][k];
            let z = if se > rounding(e) {
                format!("z {:.2}", (m - e) / se)
            } else {
                format!("β constant, rounding bound {:.1e}", rounding(e) / e)
            };
            let line = format!(
                "{}: {what}: flux {m:.6} ± {se:.2e} vs {e:.6} (ratio − 1 = {:.2e}, {z}), {} photons",
                c.name,
                m / e - 1.0,
                c.flux.kept
            );
            println!("{line}");
            // |z| < t, or within f32 rounding of a per-path value that is constant by
            // construction (where se is ~0).
            let ok_stat = (m - e).abs() <= t * se + rounding(e);
            // Not vacuous: the estimate is within 1 % whatever its standard error.
            let ok_rel = (m / e - 1.0).abs() < 0.01;
            if !(ok_stat && ok_rel) {
                failures.push(line);
            }
        }
    }
    println!(
        "|z| threshold {t:.2} over {tests} tests; {:?}",
        start.elapsed()
    );
    assert!(
        failures.is_empty(),
        "flux mismatches:\n{}",
        failures.join("\n")
    );
}

/// A single diffuse quad, the square [-1, 1]² at z = 0 (normal +z), seen from z = 3 (the view,
/// ±0.8 at the wall, lies inside it), and a small spherical emitter at z = ±1 outside the view:
/// behind the wall (`behind`) or on the camera's side. Behind it, every point of the scene that
/// light can reach (the emitter, at z ∈ [−1.2, −0.8], and the wall's back) lies in z ≤ 0 and faces
/// away from the front, so no path of any length carries light to the camera: the image is 0.
/// `tilted` gives the wall shading normals 37° off its geometric normal, so that some directions
/// from behind lie above the shading normal's horizon: front and back must be told apart by the
/// geometric normal.
fn thin_wall(behind: bool, tilted: bool) -> Scene {
    let camera = Camera::look_at(
        Vec3::new(0.0, 0.0, 3.0),
        Vec3::ZERO,
        Vec3::Y,
        30.0,
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
    let m = b.add_material(Material::Diffuse(Diffuse {
        albedo: Color::splat(0.8),
    }));
    let mut wall = TriangleMesh::unit_rectangle();
    if tilted {
        wall.normals = Some(vec![Vec3::new(0.6, 0.0, 0.8); 4]);
    }
    b.add_shape(ShapeGeometry::Mesh(wall), m, None, false);
    // 24° off the camera's axis, outside its 15° half-angle of view.
    let z = if behind { -1.0 } else { 1.0 };
    b.add_shape(
        ShapeGeometry::Sphere {
            center: Vec3::new(0.9, 0.0, z),
            radius: 0.2,
        },
        m,
        Some(Color::splat(5.0)),
        false,
    );
    b.build()
}

/// Every registered integrator under its defaults, and with photons for direct light where its
/// key table offers `direct` (with `direct = nee` the photons behind the wall are direct ones,
/// which are not stored, so only `direct = photons` puts gatherable photons there).
fn configurations() -> Vec<(&'static str, IntegratorParams)> {
    let mut out = Vec::new();
    for info in INTEGRATORS {
        out.push((info.name, IntegratorParams::new()));
        if documented_keys(info.source)
            .iter()
            .any(|(k, _)| k == "direct")
        {
            out.push((info.name, IntegratorParams::new().with("direct", "photons")));
        }
    }
    out
}

/// What keeps the front black for the photon mappers is that a photon is only gathered on the
/// side it arrived at. Two checks say so today: `GatherPoint::photon_value`'s side test, and
/// `Material::eval` itself (its shading/geometric side agreement plus reflection-only non-delta
/// BSDFs give 0 for ω_o and ω_p on opposite sides of n_g); the test fails if gathering becomes
/// two-sided (a photon from behind mirrored onto the front), not if only one of the two goes.
#[test]
fn a_thin_wall_lit_from_behind_stays_black_in_front() {
    let opts = RenderOptions {
        passes: 4,
        time_limit: None,
        seed: 11,
        threads: 0,
    };
    let mut failures = Vec::new();
    for tilted in [false, true] {
        let scenes = [
            (true, thin_wall(true, tilted)),
            (false, thin_wall(false, tilted)),
        ];
        for (name, params) in configurations() {
            for (behind, scene) in &scenes {
                let who = format!(
                    "{name} {:?} wall{} lit from {}",
                    params.pairs(),
                    if tilted { " (tilted normals)" } else { "" },
                    if *behind { "behind" } else { "the front" }
                );
                let est = make_integrator(name, scene, &params).unwrap();
                let r = render(scene, &est, &opts, |_| ControlFlow::Continue(())).unwrap();
                let lit = r
                    .estimate
                    .data
                    .iter()
                    .flatten()
                    .filter(|v| **v != 0.0)
                    .count();
                let sum: f64 = r.estimate.data.iter().flatten().sum();
                println!("{who}: {lit} non-zero channels, sum {sum:.4}");
                if r.invalid_samples != 0 {
                    failures.push(format!("{who}: {} invalid samples", r.invalid_samples));
                }
                // Behind: exactly black, the expected value being 0. In front: lit, so the
                // black result is not an integrator seeing nothing at all (pixels, photons and
                // gather radii reach the wall).
                if *behind && lit != 0 {
                    failures.push(format!("{who}: {lit} non-zero channels, sum {sum:e}"));
                }
                if !*behind && !(sum > 0.0) {
                    failures.push(format!("{who}: black although lit from the camera's side"));
                }
            }
        }
    }
    assert!(failures.is_empty(), "thin wall:\n{}", failures.join("\n"));
}

/// The side test keeps light behind an opaque surface out, but not light behind rough glass: a
/// photon that reached a rough dielectric from inside is gathered by a camera outside through its
/// BTDF (refusing it would drop everything rough glass transmits from photon mapping and VCM's
/// merges). The same photon at a diffuse point is refused.
#[test]
fn photons_behind_rough_glass_are_gathered_through_it() {
    use lt_core::bsdf::{microfacet, Diffuse, Material, RoughDielectric, ShadingFrame};
    use lt_integrators::density::photons::{GatherPoint, Photon};
    let mut b = SceneBuilder::new(camera(), RenderSettings::default());
    let glass = b.add_material(Material::RoughDielectric(RoughDielectric {
        distribution: microfacet::Microfacet::isotropic(microfacet::MicrofacetType::Ggx, 0.3),
        ior: 1.5,
        specular_reflectance: Color::ONE,
        specular_transmittance: Color::ONE,
    }));
    let wall = b.add_material(Material::Diffuse(Diffuse {
        albedo: Color::splat(0.5),
    }));
    let _ = black(&mut b);
    let scene = b.build();
    let n = Vec3::Z;
    let photon = Photon {
        wi: Vec3::new(0.2, 0.1, -0.97).normalize(), // came from below the surface
        ng: n,
        beta: Color::ONE,
        segments: 1,
    };
    let at = |material| GatherPoint {
        p: Vec3::ZERO,
        sf: ShadingFrame::new(n, n),
        wo: Vec3::new(-0.1, 0.3, 0.95).normalize(), // the camera is above
        material,
        beta: Color::ONE,
        segments: 1,
    };
    let through = at(glass).photon_value(&scene, &photon, 8);
    assert!(
        through.is_some_and(|v| v.x > 0.0),
        "rough glass refused light from behind: {through:?}"
    );
    assert!(at(wall).photon_value(&scene, &photon, 8).is_none());
}

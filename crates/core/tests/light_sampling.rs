//! Sampling tests of the lights, in small scenes built with `SceneBuilder`: χ² of `sample_li`
//! against `pdf_li` and of `sample_le` directions against `pdf_le`, the mass of each pdf, the
//! positional densities (binomial tests), and the consistency of every sample with the scene.

use lt_core::bsdf::{Diffuse, Material};
use lt_core::camera::{Camera, FovAxis};
use lt_core::geometry::Ray;
use lt_core::light::{EnvironmentMap, Light};
use lt_core::math::{gamma, Color, Frame, Vec2, Vec3, PI};
use lt_core::sampling::Sampler;
use lt_core::scene::{LightDesc, RenderSettings, Scene, SceneBuilder, ShapeGeometry, TriangleMesh};
use lt_core::shape::Affine;
use lt_core::testing::chi2::{self, Chi2Outcome, Chi2Test, ParallelogramChart, SphereGrid};
use lt_core::testing::{binomial_z, sidak, DIRECTION_ROUNDING};
use lt_core::texture::{Texture, UvTransform};

const ALPHA: f64 = 0.01;
const Z_MAX: f64 = 4.0;
const SUN_SMALL: f32 = 6.87e-5;
const SUN_LARGE: f32 = 0.1;

fn build(shapes: Vec<(ShapeGeometry, Option<Color>, bool)>, lights: Vec<LightDesc>) -> Scene {
    let camera = Camera::look_at(
        Vec3::new(0.0, -8.0, 3.0),
        Vec3::ZERO,
        Vec3::Z,
        40.0,
        FovAxis::X,
        8,
        8,
    )
    .unwrap();
    let mut b = SceneBuilder::new(camera, RenderSettings::default());
    let mat = b.add_material(Material::Diffuse(Diffuse {
        albedo: Color::splat(0.5),
    }));
    for (g, e, flip) in shapes {
        b.add_shape(g, mat, e, flip);
    }
    for l in lights {
        b.add_light(l);
    }
    b.build()
}

/// A quadrilateral light at z = 2 facing down (−z), split along y = x into triangles of area 1
/// (y < x) and 0.5 (y > x).
fn quad_scene() -> Scene {
    let h = 2.0;
    let (a, b, c, d) = (
        Vec3::new(0.0, 0.0, h),
        Vec3::new(2.0, 0.0, h),
        Vec3::new(1.0, 1.0, h),
        Vec3::new(0.0, 1.0, h),
    );
    let mesh = TriangleMesh {
        positions: vec![a, b, c, d],
        normals: None,
        uvs: None,
        indices: vec![[0, 2, 1], [0, 3, 2]],
        attributes: Vec::new(),
    };
    build(
        vec![(ShapeGeometry::Mesh(mesh), Some(Color::ONE), false)],
        vec![],
    )
}
const QUAD_AREAS: [f64; 2] = [1.0, 0.5];
const QUAD_NORMAL: Vec3 = Vec3::new(0.0, 0.0, -1.0);

/// A tilted parallelogram light corner + u·e1 + v·e2 (two triangles), for the direction tests:
/// charted by its own (u, v), its edges are bin edges.
const PAR: [Vec3; 3] = [
    Vec3::new(-0.5, -0.3, 2.0),
    Vec3::new(1.5, 0.2, 0.0),
    Vec3::new(0.4, 1.0, 0.3),
];
fn parallelogram_scene() -> Scene {
    let [c, e1, e2] = PAR;
    let mesh = TriangleMesh {
        positions: vec![c, c + e1, c + e1 + e2, c + e2],
        normals: None,
        uvs: None,
        indices: vec![[0, 1, 2], [0, 2, 3]],
        attributes: Vec::new(),
    };
    build(
        vec![(ShapeGeometry::Mesh(mesh), Some(Color::ONE), false)],
        vec![],
    )
}

const SPHERE_C: Vec3 = Vec3::new(0.2, -0.1, 0.3);
const SPHERE_R: f32 = 1.0;
fn sphere_scene(flip: bool) -> Scene {
    build(
        vec![(
            ShapeGeometry::Sphere {
                center: SPHERE_C,
                radius: SPHERE_R,
            },
            Some(Color::ONE),
            flip,
        )],
        vec![],
    )
}

fn floor() -> (ShapeGeometry, Option<Color>, bool) {
    (
        ShapeGeometry::Mesh(TriangleMesh::unit_rectangle()),
        None,
        false,
    )
}
fn sun_dir() -> Vec3 {
    Vec3::new(0.3, 0.2, 1.0).normalize()
}
fn sun_scene(solid_angle: f32) -> Scene {
    build(
        vec![floor()],
        vec![LightDesc::Sun {
            direction: sun_dir(),
            solid_angle,
            radiance: Color::splat(3.0),
        }],
    )
}
fn directional_scene() -> Scene {
    build(
        vec![floor()],
        vec![LightDesc::Directional {
            direction: sun_dir(),
            irradiance: Color::new(3.0, 2.0, 1.0),
        }],
    )
}
fn env_scene() -> Scene {
    build(
        vec![floor()],
        vec![LightDesc::Environment {
            radiance: Color::splat(0.7),
        }],
    )
}

const SPOT_CUTOFF: f32 = 0.5;
const SPOT_ROTATION: glam::Mat3 = glam::Mat3::from_cols(
    Vec3::new(0.0, 0.0, 1.0),
    Vec3::new(1.0, 0.0, 0.0),
    Vec3::new(0.0, 1.0, 0.0),
);
/// A textured spot light at the origin aimed along +y (the rotation cycles the axes).
fn spot_scene() -> Scene {
    build(
        vec![floor()],
        vec![LightDesc::Spot {
            position: Vec3::ZERO,
            to_world: SPOT_ROTATION,
            intensity: Color::new(3.0, 2.0, 1.0),
            texture: Some(Texture::Checkerboard {
                color0: Color::splat(0.2),
                color1: Color::ONE,
                to_uv: UvTransform::IDENTITY,
            }),
            cutoff: SPOT_CUTOFF,
            beam_width: 0.3,
        }],
    )
}
const PROJ_POS: Vec3 = Vec3::new(0.1, -0.2, 0.3);
const PROJ_TAN: Vec2 = Vec2::new(1.2, 0.7);
fn projector_scene() -> Scene {
    build(
        vec![floor()],
        vec![LightDesc::Projector {
            position: PROJ_POS,
            to_world: SPOT_ROTATION,
            irradiance: Texture::Constant(Color::ONE),
            scale: 2.0,
            tan_half: PROJ_TAN,
        }],
    )
}
const ENVMAP_SIZE: (usize, usize) = (12, 7);
const ENVMAP_ROTATION: glam::Mat3 = glam::Mat3::from_cols(
    Vec3::new(0.0, 1.0, 0.0),
    Vec3::new(0.0, 0.0, 1.0),
    Vec3::new(1.0, 0.0, 0.0),
);
/// A 12 × 7 map: a dim gradient sky, a black row and one texel 200 times brighter (a sun), turned
/// so that the map's pole is world +z.
fn envmap_scene() -> Scene {
    let (w, h) = ENVMAP_SIZE;
    let texels = (0..w * h)
        .map(|k| match (k % w, k / w) {
            (4, 2) => Color::new(90.0, 80.0, 60.0),
            (_, 5) => Color::ZERO,
            (x, y) => Color::new(0.2 + 0.05 * x as f32, 0.3, 0.1 + 0.1 * y as f32),
        })
        .collect();
    let map = EnvironmentMap::new(w, h, texels, 1.5, ENVMAP_ROTATION).unwrap();
    build(
        vec![floor()],
        vec![LightDesc::EnvironmentMap {
            map: std::sync::Arc::new(map),
        }],
    )
}

/// The sphere charted by an environment map's own coordinates (Mitsuba's latitude–longitude:
/// local (sin φ sin θ, cos θ, −cos φ sin θ) with (u, v) = (φ / 2π, θ / π)), a = v and b = u, with
/// dω = 2π² sin θ du dv: the map's cells are bins (each split in two both ways), and the
/// integrand pdf · Jacobian is the piecewise-constant density in (u, v) itself, with no 1/sin θ
/// for the cubature to chase at the poles.
struct LatLongChart {
    to_world: glam::Mat3,
    v_edges: Vec<f64>,
    u_edges: Vec<f64>,
}

impl LatLongChart {
    fn new(to_world: glam::Mat3, (w, h): (usize, usize)) -> LatLongChart {
        let edges = |n: usize| (0..=2 * n).map(|k| k as f64 / (2 * n) as f64).collect();
        LatLongChart {
            to_world,
            v_edges: edges(h),
            u_edges: edges(w),
        }
    }
}

impl chi2::Chart for LatLongChart {
    fn a_edges(&self) -> &[f64] {
        &self.v_edges
    }
    fn b_edges(&self) -> &[f64] {
        &self.u_edges
    }
    fn direction(&self, v: f64, u: f64) -> (Vec3, f64) {
        let (st, ct) = (std::f64::consts::PI * v).sin_cos();
        let (sp, cp) = (2.0 * std::f64::consts::PI * u).sin_cos();
        let local = Vec3::new((sp * st) as f32, ct as f32, (-cp * st) as f32);
        let jac = 2.0 * std::f64::consts::PI * std::f64::consts::PI * st;
        ((self.to_world * local).normalize(), jac)
    }
    fn coords(&self, w: Vec3) -> Option<(f64, f64)> {
        let d = (self.to_world.transpose() * w).as_dvec3();
        let theta = (d.x * d.x + d.z * d.z).sqrt().atan2(d.y);
        let u = d.x.atan2(-d.z) / (2.0 * std::f64::consts::PI);
        Some((theta / std::f64::consts::PI, u.rem_euclid(1.0)))
    }
    fn covers_sphere(&self) -> bool {
        true
    }
}

/// pdf_li for any direction: the light's point and normal come from tracing the ray, as an
/// integrator that hit the light by BSDF sampling would do. Zero when the ray misses the light.
fn pdf_li_traced(scene: &Scene, light: usize, p: Vec3, w: Vec3) -> f32 {
    let l = &scene.lights[light];
    if l.is_infinite() {
        return l.pdf_li(p, w, w, -w);
    }
    match scene.intersect(&Ray::new(p, w)) {
        Some(hit) if hit.light == Some(light as u32) => l.pdf_li(p, w, hit.p, hit.ng),
        _ => 0.0,
    }
}

/// Every `sample_li` sample against the scene: pdf_li agrees, the point lies where the ray
/// meets the light, and the radiance is what the light emits there.
fn check_li_samples(scene: &Scene, light: usize, p: Vec3, label: &str) -> Result<(), String> {
    let l = &scene.lights[light];
    let mut s = Sampler::new(3, light as u64, 0);
    for _ in 0..20_000 {
        let Some(ls) = l.sample_li(p, s.next_2d()) else {
            return Err(format!("{label}: sample_li failed"));
        };
        let pdf = l.pdf_li(p, ls.wi, ls.p, ls.n);
        if !((pdf - ls.pdf_w).abs() <= gamma(4) * ls.pdf_w) {
            return Err(format!(
                "{label}: pdf_w {} but pdf_li {pdf} for {ls:?}",
                ls.pdf_w
            ));
        }
        if l.is_infinite() {
            if l.escaped(ls.wi) != ls.radiance {
                return Err(format!(
                    "{label}: escaped {} vs sampled radiance {} at {}",
                    l.escaped(ls.wi),
                    ls.radiance,
                    ls.wi
                ));
            }
            continue;
        }
        // Positions carry ~γ(8) relative error of their magnitude; directions add their own.
        let to = ls.p - p;
        let tol = (p.length() + ls.p.length()) * gamma(8) / to.length() + DIRECTION_ROUNDING;
        if (to.normalize() - ls.wi).length() > tol
            || (to.length() - ls.distance).abs() > tol * ls.distance
        {
            return Err(format!(
                "{label}: point {} not along wi {} at distance {}",
                ls.p, ls.wi, ls.distance
            ));
        }
        if l.emitted(ls.n, -ls.wi, ls.uv) != ls.radiance {
            return Err(format!(
                "{label}: radiance {} vs emitted {}",
                ls.radiance,
                l.emitted(ls.n, -ls.wi, ls.uv)
            ));
        }
    }
    Ok(())
}

/// Ring edges uniform in h over [0, h_in] (where a cone pdf is constant), then uniform out to 2:
/// the cone's rim falls on a ring edge.
fn cone_edges(h_in: f64, n_in: usize, n_out: usize) -> Vec<f64> {
    let mut e: Vec<f64> = (0..=n_in).map(|i| h_in * i as f64 / n_in as f64).collect();
    e.extend((1..=n_out).map(|i| h_in + (2.0 - h_in) * i as f64 / n_out as f64));
    e
}

fn sphere_cone_h(p: Vec3) -> f64 {
    let d2 = (p - SPHERE_C).length_squared() as f64;
    let sin2 = (SPHERE_R * SPHERE_R) as f64 / d2;
    sin2 / (1.0 + (1.0 - sin2).sqrt())
}

#[test]
fn light_directions_follow_their_pdfs_chi2() {
    let mut runs: Vec<Chi2Outcome> = Vec::new();
    let mut problems: Vec<String> = Vec::new();
    let mut seed = 100u64;
    let mut next_cfg = || {
        seed += 1;
        Chi2Test {
            samples: 1_000_000,
            seed,
        }
    };

    // Parallelogram: from below, obliquely, and from behind (the pdf does not depend on the side).
    let par = parallelogram_scene();
    for p in [
        Vec3::new(0.5, 0.3, 0.0),
        Vec3::new(3.0, -1.0, 1.5),
        Vec3::new(0.4, 0.6, 3.5),
    ] {
        let label = format!("parallelogram li p={p}");
        let chart = ParallelogramChart::new(p, PAR[0], PAR[1], PAR[2], 30, 29);
        let l = &par.lights[0];
        runs.push(chi2::run(
            &label,
            next_cfg(),
            &chart,
            |s| l.sample_li(p, s.next_2d()).map(|x| x.wi),
            |w| pdf_li_traced(&par, 0, p, w),
        ));
        problems.extend(check_li_samples(&par, 0, p, &label).err());
    }
    let quad = quad_scene();
    problems.extend(check_li_samples(&quad, 0, Vec3::new(0.5, 0.3, 0.0), "quad li").err());

    // Sphere from outside, near and far: the cone it subtends, its rim on a ring edge.
    let sphere = sphere_scene(false);
    for p in [Vec3::new(0.2, -0.1, 1.9), Vec3::new(5.0, -3.0, 4.0)] {
        let label = format!("sphere li outside p={p}");
        let grid = SphereGrid::with_edges(
            Frame::from_z((SPHERE_C - p).normalize()),
            cone_edges(sphere_cone_h(p), 20, 6),
            40,
        );
        let l = &sphere.lights[0];
        runs.push(chi2::run(
            &label,
            next_cfg(),
            &grid,
            |s| l.sample_li(p, s.next_2d()).map(|x| x.wi),
            |w| pdf_li_traced(&sphere, 0, p, w),
        ));
        problems.extend(check_li_samples(&sphere, 0, p, &label).err());
    }
    // Sphere from inside (both orientations): every direction sees it.
    for flip in [false, true] {
        let scene = sphere_scene(flip);
        let p = SPHERE_C + Vec3::new(0.3, -0.2, 0.5);
        let label = format!("sphere li inside flip={flip}");
        let grid = SphereGrid::sphere(Frame::from_z(Vec3::Z), 40, 80);
        let l = &scene.lights[0];
        runs.push(chi2::run(
            &label,
            next_cfg(),
            &grid,
            |s| l.sample_li(p, s.next_2d()).map(|x| x.wi),
            |w| pdf_li_traced(&scene, 0, p, w),
        ));
        problems.extend(check_li_samples(&scene, 0, p, &label).err());
    }

    // Suns: bins over their own cone (1 − cos θ, φ) — uniform means equal expected counts.
    for omega in [SUN_SMALL, SUN_LARGE] {
        let scene = sun_scene(omega);
        let li = scene
            .lights
            .iter()
            .position(|l| matches!(l, Light::Sun(_)))
            .unwrap();
        let l = &scene.lights[li];
        let h = omega as f64 / (2.0 * std::f64::consts::PI);
        let grid = SphereGrid::cap(Frame::from_z(sun_dir()), h, 10, 20, 1.0);
        let label = format!("sun li Ω={omega}");
        runs.push(chi2::run(
            &label,
            next_cfg(),
            &grid,
            |s| l.sample_li(Vec3::ZERO, s.next_2d()).map(|x| x.wi),
            |w| pdf_li_traced(&scene, li, Vec3::ZERO, w),
        ));
        problems.extend(check_li_samples(&scene, li, Vec3::ZERO, &label).err());
        let bounds = scene.bounding_sphere;
        let grid = SphereGrid::cap(Frame::from_z(-sun_dir()), h, 10, 20, 1.0);
        runs.push(chi2::run(
            &format!("sun le Ω={omega}"),
            next_cfg(),
            &grid,
            |s| {
                l.sample_le(s.next_2d(), s.next_2d(), bounds)
                    .map(|x| x.ray.d)
            },
            |w| l.pdf_le(w, w, bounds).1,
        ));
        // The pdf vanishes just outside the cone and nowhere inside it.
        for (k, expect) in [(0.999f64, true), (1.001, false)] {
            let w = grid.at(h * k, 1.0);
            let back = SphereGrid::cap(Frame::from_z(sun_dir()), h, 1, 1, 1.0).at(h * k, 1.0);
            if (l.pdf_li(Vec3::ZERO, back, back, -back) > 0.0) != expect
                || (l.pdf_le(w, w, bounds).1 > 0.0) != expect
            {
                problems.push(format!(
                    "sun Ω={omega}: pdf at {k}·θmax should be {}",
                    if expect { "positive" } else { "zero" }
                ));
            }
        }
    }

    let env = env_scene();
    let li = env
        .lights
        .iter()
        .position(|l| matches!(l, Light::Environment(_)))
        .unwrap();
    let l = &env.lights[li];
    let bounds = env.bounding_sphere;
    let grid = SphereGrid::sphere(Frame::from_z(Vec3::new(0.1, 0.9, 0.3).normalize()), 20, 40);
    runs.push(chi2::run(
        "environment li",
        next_cfg(),
        &grid,
        |s| l.sample_li(Vec3::ZERO, s.next_2d()).map(|x| x.wi),
        |w| pdf_li_traced(&env, li, Vec3::ZERO, w),
    ));
    problems.extend(check_li_samples(&env, li, Vec3::ZERO, "environment li").err());
    runs.push(chi2::run(
        "environment le",
        next_cfg(),
        &grid,
        |s| {
            l.sample_le(s.next_2d(), s.next_2d(), bounds)
                .map(|x| x.ray.d)
        },
        |w| l.pdf_le(w, w, bounds).1,
    ));

    // Emission directions of area lights: cosine-weighted about the normal at the origin.
    let l = &quad.lights[0];
    let bounds = quad.bounding_sphere;
    let grid = SphereGrid::sphere(Frame::from_z(QUAD_NORMAL), 40, 80);
    runs.push(chi2::run(
        "quad le",
        next_cfg(),
        &grid,
        |s| {
            l.sample_le(s.next_2d(), s.next_2d(), bounds)
                .map(|x| x.ray.d)
        },
        |w| l.pdf_le(QUAD_NORMAL, w, bounds).1,
    ));
    for flip in [false, true] {
        let scene = sphere_scene(flip);
        let l = &scene.lights[0];
        let bounds = scene.bounding_sphere;
        let u_pos = Vec2::new(0.3, 0.7);
        let n = l.sample_le(u_pos, Vec2::splat(0.5), bounds).unwrap().n;
        let grid = SphereGrid::sphere(Frame::from_z(n), 40, 80);
        let label = format!("sphere le flip={flip}");
        runs.push(chi2::run(
            &label,
            next_cfg(),
            &grid,
            |s| l.sample_le(u_pos, s.next_2d(), bounds).map(|x| x.ray.d),
            |w| l.pdf_le(n, w, bounds).1,
        ));
    }

    // Spot light: emitted directions uniform in the cutoff cone, the rim on a ring edge.
    let spot = spot_scene();
    let l = &spot.lights[0];
    let bounds = spot.bounding_sphere;
    let axis = SPOT_ROTATION * Vec3::Z;
    let h = 1.0 - (SPOT_CUTOFF as f64).cos();
    let grid = SphereGrid::with_edges(Frame::from_z(axis), cone_edges(h, 12, 4), 24);
    runs.push(chi2::run(
        "spot le",
        next_cfg(),
        &grid,
        |s| {
            l.sample_le(s.next_2d(), s.next_2d(), bounds)
                .map(|x| x.ray.d)
        },
        |w| l.pdf_le(Vec3::ZERO, w, bounds).1,
    ));

    // Projector: emitted directions through the image plane, charted by the image's own (u, v)
    // (the frustum's edges are the chart's).
    let proj = projector_scene();
    let l = &proj.lights[0];
    let bounds = proj.bounding_sphere;
    let (tx, ty) = (PROJ_TAN.x, PROJ_TAN.y);
    let chart = ParallelogramChart::new(
        PROJ_POS,
        PROJ_POS + SPOT_ROTATION * Vec3::new(-tx, -ty, 1.0),
        SPOT_ROTATION * Vec3::new(2.0 * tx, 0.0, 0.0),
        SPOT_ROTATION * Vec3::new(0.0, 2.0 * ty, 0.0),
        24,
        16,
    );
    runs.push(chi2::run(
        "projector le",
        next_cfg(),
        &chart,
        |s| {
            l.sample_le(s.next_2d(), s.next_2d(), bounds)
                .map(|x| x.ray.d)
        },
        |w| l.pdf_le(Vec3::ZERO, w, bounds).1,
    ));

    // Environment map: NEE and emitted directions against the map's piecewise-constant pdf,
    // charted by the map's own (v, u), each cell split in two both ways.
    let env = envmap_scene();
    let l = &env.lights[0];
    let bounds = env.bounding_sphere;
    let chart = LatLongChart::new(ENVMAP_ROTATION, ENVMAP_SIZE);
    runs.push(chi2::run(
        "envmap li",
        next_cfg(),
        &chart,
        |s| l.sample_li(Vec3::ZERO, s.next_2d()).map(|x| x.wi),
        |w| pdf_li_traced(&env, 0, Vec3::ZERO, w),
    ));
    problems.extend(check_li_samples(&env, 0, Vec3::ZERO, "envmap li").err());
    runs.push(chi2::run(
        "envmap le",
        next_cfg(),
        &chart,
        // Light travels along −wi: charted by the direction it comes from.
        |s| {
            l.sample_le(s.next_2d(), s.next_2d(), bounds)
                .map(|x| -x.ray.d)
        },
        |w| l.pdf_le(w, -w, bounds).1,
    ));

    let level = sidak(ALPHA, runs.len());
    for r in &runs {
        eprintln!("{:<40} {}", r.name, r.summary());
        problems.extend(r.check(level).err());
        problems.extend(r.check_mass().err());
        // Lights never reject: their pdfs must integrate to 1 over what they cover.
        if r.accepted != r.samples || r.in_domain != r.samples {
            problems.push(format!(
                "{}: {} accepted, {} in the binned domain, of {}",
                r.name, r.accepted, r.in_domain, r.samples
            ));
        }
    }
    let worst = runs.iter().map(|o| o.p_value).fold(f64::INFINITY, f64::min);
    eprintln!(
        "{} χ² tests, per-test level {level:.2e}, smallest p = {worst:.4}",
        runs.len()
    );
    assert!(
        problems.is_empty(),
        "{} problems (level {level:.2e}):\n{}",
        problems.len(),
        problems.join("\n")
    );
}

#[test]
fn area_light_positions_are_uniform_by_area() {
    let n = 200_000u64;
    let mut worst = 0.0f64;
    // Two triangles of unequal area: each is chosen in proportion to its area.
    let quad = quad_scene();
    let l = &quad.lights[0];
    let Light::Area(area) = l else { unreachable!() };
    let total: f64 = QUAD_AREAS.iter().sum();
    assert!(
        (area.area as f64 - total).abs() <= gamma(4) as f64 * total,
        "area {} vs {total}",
        area.area
    );
    let mut s = Sampler::new(5, 0, 0);
    let (mut on_big, mut on_big_li) = (0u64, 0u64);
    let p = Vec3::new(0.5, 0.3, 0.0);
    for _ in 0..n {
        let le = l
            .sample_le(s.next_2d(), s.next_2d(), quad.bounding_sphere)
            .unwrap();
        assert_eq!(le.pdf_pos, 1.0 / area.area);
        assert_eq!(l.pdf_le(le.n, le.ray.d, quad.bounding_sphere).0, le.pdf_pos);
        on_big += u64::from(le.ray.o.y < le.ray.o.x);
        let li = l.sample_li(p, s.next_2d()).unwrap();
        on_big_li += u64::from(li.p.y < li.p.x);
    }
    let frac = QUAD_AREAS[0] / total;
    for (what, k) in [("sample_le", on_big), ("sample_li", on_big_li)] {
        let z = binomial_z(k, n, frac);
        worst = worst.max(z.abs());
        assert!(
            z.abs() < Z_MAX,
            "quad {what}: {k}/{n} on the larger triangle, expected {frac:.4}: z = {z:.2}"
        );
    }

    // Sphere: uniform on its surface, so each hemisphere (any axis) gets half.
    let sphere = sphere_scene(false);
    let l = &sphere.lights[0];
    let axis = Vec3::new(0.3, -0.4, 0.8).normalize();
    let mut upper = 0u64;
    for _ in 0..n {
        let le = l
            .sample_le(s.next_2d(), s.next_2d(), sphere.bounding_sphere)
            .unwrap();
        assert!(
            (le.pdf_pos - 1.0 / (4.0 * PI * SPHERE_R * SPHERE_R)).abs() <= gamma(4) * le.pdf_pos
        );
        upper += u64::from((le.ray.o - SPHERE_C).dot(axis) > 0.0);
    }
    let z = binomial_z(upper, n, 0.5);
    worst = worst.max(z.abs());
    assert!(
        z.abs() < Z_MAX,
        "sphere: {upper}/{n} in one hemisphere: z = {z:.2}"
    );
    eprintln!("worst |z| of positional tests: {worst:.2}");
}

#[test]
fn distant_lights_emit_over_the_bounding_disk() {
    // Ray origins are uniform on the disk of the bounding sphere's radius r, perpendicular to the
    // ray, upstream of the scene: half of them lie within r/√2 of its centre.
    let n = 200_000u64;
    for scene in [sun_scene(SUN_LARGE), env_scene(), directional_scene()] {
        let li = scene.lights.iter().position(|l| l.is_infinite()).unwrap();
        let l = &scene.lights[li];
        let (c, r) = scene.bounding_sphere;
        let mut s = Sampler::new(9, li as u64, 0);
        let mut inner = 0u64;
        for _ in 0..n {
            let le = l.sample_le(s.next_2d(), s.next_2d(), (c, r)).unwrap();
            let d = le.ray.d;
            let q = le.ray.o - (c - d * r);
            assert!(
                q.dot(d).abs() <= 4.0 * gamma(8) * (c.length() + 2.0 * r),
                "origin off the disk plane: {q}"
            );
            assert!(
                q.length() <= r * (1.0 + gamma(8)),
                "origin outside the disk: |q| = {} > {r}",
                q.length()
            );
            assert!((le.pdf_pos - 1.0 / (PI * r * r)).abs() <= gamma(4) * le.pdf_pos);
            assert_eq!(l.pdf_le(le.n, d, (c, r)), (le.pdf_pos, le.pdf_dir));
            inner += u64::from(q.length_squared() < 0.5 * r * r);
        }
        let z = binomial_z(inner, n, 0.5);
        assert!(
            z.abs() < Z_MAX,
            "{:?}: {inner}/{n} origins in the inner half of the disk: z = {z:.2}",
            l
        );
    }
}

#[test]
fn sun_samples_at_the_rim_keep_a_nonzero_pdf() {
    // u.x → 1 samples the rim; f32 rounding of the rotated direction must not put it where
    // pdf_li / pdf_le / escaped say the sun is not (a sampled direction with pdf 0 breaks MIS).
    for omega in [SUN_SMALL, SUN_LARGE] {
        let scene = sun_scene(omega);
        let l = scene
            .lights
            .iter()
            .find(|l| matches!(l, Light::Sun(_)))
            .unwrap();
        let b = scene.bounding_sphere;
        let n = 100_000;
        for k in 0..n {
            let u = Vec2::new(1.0 - 1.0 / (1u32 << 24) as f32, k as f32 / n as f32);
            let s = l.sample_li(Vec3::ZERO, u).unwrap();
            assert!(
                l.pdf_li(Vec3::ZERO, s.wi, s.p, s.n) > 0.0 && l.escaped(s.wi) == s.radiance,
                "Ω={omega}: rim sample_li {} outside the cone",
                s.wi
            );
            let e = l.sample_le(Vec2::splat(0.5), u, b).unwrap();
            assert!(
                l.pdf_le(e.n, e.ray.d, b).1 > 0.0,
                "Ω={omega}: rim sample_le {} outside the cone",
                e.ray.d
            );
        }
    }
}

#[test]
fn directional_light_is_a_delta_in_direction() {
    // Delta in direction, not position; at infinity. NEE returns its one direction with the
    // discrete density 1 and the irradiance; no direction has a solid-angle pdf or escaping
    // radiance; emitted rays all travel along −direction from the bounding disk.
    let scene = directional_scene();
    let l = &scene.lights[0];
    let e = Color::new(3.0, 2.0, 1.0);
    let Light::Directional(d) = l else {
        panic!("not a directional light: {l:?}")
    };
    assert!((d.direction - sun_dir()).length() < 1e-6);
    assert!(l.is_infinite() && l.delta_direction() && !l.delta_position() && l.is_delta());
    assert_eq!(scene.infinite_lights, vec![0]);
    let b = scene.bounding_sphere;
    let mut s = Sampler::new(5, 0, 0);
    for _ in 0..1000 {
        let p = Vec3::new(s.next_f32() - 0.5, 0.0, s.next_f32() - 0.5);
        let ls = l.sample_li(p, s.next_2d()).unwrap();
        assert_eq!(ls.wi, d.direction);
        assert!(ls.delta && ls.pdf_w == 1.0 && ls.radiance == e && ls.distance.is_infinite());
        assert_eq!(l.pdf_li(p, ls.wi, ls.p, ls.n), 0.0);
        assert_eq!(l.escaped(ls.wi), Color::ZERO);
        let w = Vec3::new(s.next_f32() - 0.5, s.next_f32(), s.next_f32() - 0.5).normalize();
        assert_eq!(l.pdf_li(p, w, w, -w), 0.0);
        assert_eq!(l.emitted(-w, w, Default::default()), Color::ZERO);
        let le = l.sample_le(s.next_2d(), s.next_2d(), b).unwrap();
        assert_eq!(le.ray.d, -d.direction);
        assert!(le.pdf_dir == 1.0 && le.radiance == e);
        assert!((le.pdf_pos - 1.0 / (PI * b.1 * b.1)).abs() <= gamma(4) * le.pdf_pos);
        assert_eq!(l.pdf_le(le.n, le.ray.d, b), (le.pdf_pos, 1.0));
    }
    // Power: the luminance of the flux through the bounding disk, E π R².
    let lum = 0.2126 * 3.0 + 0.7152 * 2.0 + 0.0722 * 1.0;
    let expected = lum * PI * b.1 * b.1;
    assert!((l.power(b) - expected).abs() <= 1e-6 * expected);
}

/// An emitting ellipse (semi-axes 1.5 and 2.5, tilted) and an emitting open cylinder (radius 0.7,
/// length 1.6, tilted): Mitsuba's disk and cylinder under their `to_world`.
fn quadric_scenes() -> Vec<(&'static str, Scene, Vec3)> {
    let r = glam::Mat3::from_rotation_x(-0.6) * glam::Mat3::from_rotation_y(0.4);
    let disk = Affine::new(
        r * glam::Mat3::from_diagonal(Vec3::new(1.5, 2.5, 1.0)),
        Vec3::new(0.2, 0.1, -0.3),
    );
    let tube = Affine::new(
        r * glam::Mat3::from_diagonal(Vec3::new(0.7, 0.7, 1.6)),
        Vec3::new(-0.1, 0.3, 0.2),
    );
    vec![
        (
            "disk",
            build(
                vec![(
                    ShapeGeometry::Disk { to_world: disk },
                    Some(Color::ONE),
                    false,
                )],
                vec![],
            ),
            // On the emitting side, off the plane.
            disk.point(Vec3::new(0.3, -0.2, 0.0)) + 0.8 * (r * Vec3::Z),
        ),
        (
            "cylinder",
            build(
                vec![(
                    ShapeGeometry::Cylinder { to_world: tube },
                    Some(Color::ONE),
                    true,
                )],
                vec![],
            ),
            // Inside, with inward normals (flip): every direction meets the side at most once and
            // every point of it is seen, so the solid-angle pdf integrates to one.
            tube.point(Vec3::new(0.2, -0.3, 0.45)),
        ),
    ]
}

/// Disk and cylinder lights: the pdf of `sample_li` traced over the sphere of directions sums to
/// one, every sample agrees with the scene, and the area is the closed form.
#[test]
fn disk_and_cylinder_light_pdfs_integrate_to_one() {
    let expected_area = [PI * 1.5 * 2.5, 2.0 * PI * 0.7 * 1.6];
    for ((label, scene, p), area) in quadric_scenes().into_iter().zip(expected_area) {
        let Light::Area(a) = &scene.lights[0] else {
            unreachable!()
        };
        assert!(
            (a.area - area).abs() <= 1e-5 * area,
            "{label}: area {}",
            a.area
        );
        check_li_samples(&scene, 0, p, label).unwrap();
        let n = 400_000;
        let mut s = Sampler::new(11, 0, 0);
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let w = lt_core::sampling::sample_uniform_sphere(s.next_2d());
            let f = pdf_li_traced(&scene, 0, p, w) as f64 * 4.0 * std::f64::consts::PI;
            sum += f;
            sum2 += f * f;
        }
        let mean = sum / n as f64;
        let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
        assert!(
            ((mean - 1.0) / se).abs() < Z_MAX,
            "{label}: ∫ pdf_w dω = {mean:.4} ± {se:.4}"
        );
        // The hit the light's samples land on is the surface the ray meets (uv, normal side).
        let ls = scene.lights[0].sample_li(p, Vec2::new(0.3, 0.6)).unwrap();
        let hit = scene.intersect(&Ray::new(p, ls.wi)).unwrap();
        assert!(
            (hit.p - ls.p).length() < 1e-4,
            "{label}: {} vs {}",
            hit.p,
            ls.p
        );
        assert!(
            (hit.ng - ls.n).length() < 1e-4,
            "{label}: {} vs {}",
            hit.ng,
            ls.n
        );
    }
}

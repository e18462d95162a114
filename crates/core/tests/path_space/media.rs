//! Paths through participating media: two scenes with a homogeneous grey medium, and walks that
//! sample free flights and phase functions and record, independently of `Path`, the densities and
//! factors they used. The transmittance of every connection is computed here from the scene's
//! known geometry (the length of the segment inside the medium), not by the scene's queries.

use super::scenes::quad;
use super::walks::Made;
use glam::DVec3;
use lt_core::bsdf::{Diffuse, Material, Null};
use lt_core::camera::{Camera, FovAxis};
use lt_core::math::{Color, Frame, Mat4, Vec2, Vec3};
use lt_core::measure::solid_angle_to_area;
use lt_core::medium::{FreeFlight, Homogeneous, Medium, MediumId, PhaseFunction};
use lt_core::path::{Path, PathVertex};
use lt_core::sampling::Sampler;
use lt_core::scene::{
    MediumInterface, RenderSettings, SceneBuilder, ShapeGeometry, SurfaceHit, TriangleMesh,
};
use lt_core::Scene;

/// A scene with one homogeneous grey medium and the length of any segment inside it.
pub struct FogScene {
    pub scene: Scene,
    pub sigma_t: f32,
    pub albedo: f32,
    /// Length of the segment a → b inside the medium.
    pub fog_length: fn(Vec3, Vec3) -> f32,
}

impl FogScene {
    fn medium(&self) -> MediumId {
        0
    }
    /// T(a ↔ b) from the geometry alone.
    fn transmittance(&self, a: Vec3, b: Vec3) -> f64 {
        (-(self.sigma_t as f64) * (self.fog_length)(a, b) as f64).exp()
    }
}

fn fog(b: &mut SceneBuilder, sigma_t: f32, albedo: f32, g: f32) -> MediumId {
    b.add_medium(Medium::Homogeneous(Homogeneous {
        sigma_t: Color::splat(sigma_t),
        albedo: Color::splat(albedo),
        phase: if g == 0.0 {
            PhaseFunction::Isotropic
        } else {
            PhaseFunction::HenyeyGreenstein { g }
        },
    }))
}

/// The closed box [-1,1]³ filled with fog (σt 0.8, albedo 0.7, HG g = 0.4), its inward-facing
/// walls diffuse, the whole ceiling a light facing down; the camera inside. Convex: nothing
/// occludes, so every path f(x̄) counts is visible.
pub fn fog_box() -> FogScene {
    let cam = Camera::look_at(
        Vec3::new(0.0, 0.0, 0.8),
        Vec3::new(0.0, -0.2, -1.0),
        Vec3::Y,
        70.0,
        FovAxis::X,
        8,
        6,
    )
    .unwrap();
    let mut b = SceneBuilder::new(cam, RenderSettings::default());
    let m = fog(&mut b, 0.8, 0.7, 0.4);
    b.set_camera_medium(Some(m));
    let white = b.add_material(Material::Diffuse(Diffuse {
        albedo: Color::splat(0.6),
    }));
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    // Each wall's normal faces into the box: the fog is its exterior.
    let walls = [
        (quad(-y, z, x), None),                   // floor, +y
        (quad(y, x, z), Some(Color::splat(1.5))), // ceiling light, −y
        (quad(-z, x, y), None),                   // back, +z
        (quad(z, y, x), None),                    // front, −z
        (quad(-x, y, z), None),                   // left, +x
        (quad(x, z, y), None),                    // right, −x
    ];
    for (geometry, emission) in walls {
        b.add_shape(geometry, white, emission, false);
        b.set_last_shape_media(MediumInterface {
            interior: None,
            exterior: Some(m),
        });
    }
    FogScene {
        scene: b.build(),
        sigma_t: 0.8,
        albedo: 0.7,
        fog_length: |a, b| a.distance(b),
    }
}

/// A `null`-bounded cube [-½,½]³ of fog (σt 1.5, albedo 0.8, isotropic) in air above a diffuse
/// floor, under a quad light facing down; the camera outside.
pub fn null_box_in_air() -> FogScene {
    let cam = Camera::look_at(
        Vec3::new(0.3, 0.6, 3.0),
        Vec3::new(0.0, -0.2, 0.0),
        Vec3::Y,
        45.0,
        FovAxis::X,
        8,
        6,
    )
    .unwrap();
    let mut b = SceneBuilder::new(cam, RenderSettings::default());
    let m = fog(&mut b, 1.5, 0.8, 0.0);
    let white = b.add_material(Material::Diffuse(Diffuse {
        albedo: Color::splat(0.6),
    }));
    let null = b.add_material(Material::Null(Null));
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    b.add_shape(quad(-y, 3.0 * z, 3.0 * x), white, None, false); // floor, +y
    b.add_shape(
        quad(1.5 * y, 0.6 * x, 0.6 * z), // normal −y
        white,
        Some(Color::splat(6.0)),
        false,
    );
    let cube = TriangleMesh::unit_cube().transformed(&Mat4::from_scale(Vec3::splat(0.5)));
    b.add_shape(ShapeGeometry::Mesh(cube), null, None, false);
    b.set_last_shape_media(MediumInterface {
        interior: Some(m),
        exterior: None,
    });
    FogScene {
        scene: b.build(),
        sigma_t: 1.5,
        albedo: 0.8,
        fog_length: cube_chord,
    }
}

/// Length of the segment a → b inside [-½,½]³ (slabs).
fn cube_chord(a: Vec3, b: Vec3) -> f32 {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    for k in 0..3 {
        if d[k] == 0.0 {
            if a[k].abs() > 0.5 {
                return 0.0;
            }
            continue;
        }
        let (u, v) = ((-0.5 - a[k]) / d[k], (0.5 - a[k]) / d[k]);
        t0 = t0.max(u.min(v));
        t1 = t1.min(u.max(v));
    }
    (t1 - t0).max(0.0) * d.length()
}

/// Samples a direction from the phase function exactly (Henyey–Greenstein by inversion of its
/// cosine about the propagation direction −`wo`); the density is the phase function itself.
pub fn sample_phase(phase: PhaseFunction, wo: Vec3, u: Vec2) -> Vec3 {
    let g = match phase {
        PhaseFunction::Isotropic => 0.0,
        PhaseFunction::HenyeyGreenstein { g } => g,
    };
    let cos = if g.abs() < 1e-3 {
        1.0 - 2.0 * u.x
    } else {
        let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u.x);
        ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
    };
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u.y;
    Frame::from_z(-wo).to_world(Vec3::new(sin * phi.cos(), sin * phi.sin(), cos))
}

/// Where a ray's free flights end: a scattering in the medium, or a surface that is not null.
enum Stop {
    Medium(Vec3),
    Surface(SurfaceHit),
    Escaped,
}

/// What a walk knows after one flight: where it stopped, the density of that (the product of the
/// pieces' σt e^{−σt t} or e^{−σt t}, computed here from the sampled lengths), the factor T σs
/// (or T) it contributes to f, and the throughput weight the medium's sampler gave.
struct Flight {
    stop: Stop,
    density: f64,
    factor: f64,
    weight: Color,
}

/// Follows a ray from a vertex through null boundaries, sampling a free flight in every medium
/// piece with `Medium::sample_free_flight`.
fn fly(
    fs: &FogScene,
    mut o: Vec3,
    d: Vec3,
    mut medium: Option<MediumId>,
    rng: &mut Sampler,
) -> Flight {
    let scene = &fs.scene;
    let sigma = fs.sigma_t as f64;
    let (mut density, mut factor, mut weight) = (1.0f64, 1.0f64, Color::ONE);
    let mut ray = lt_core::geometry::Ray::new(o, d);
    loop {
        let hit = scene.intersect(&ray);
        let t_max = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
        if let Some(m) = medium {
            match scene.media[m as usize].sample_free_flight(ray.o, d, t_max, rng) {
                FreeFlight::Scattered { t, weight: w } => {
                    let tr = (-sigma * t as f64).exp();
                    return Flight {
                        stop: Stop::Medium(ray.o + d * t),
                        density: density * sigma * tr,
                        factor: factor * tr * sigma * fs.albedo as f64,
                        weight: weight * w,
                    };
                }
                FreeFlight::Passed { weight: w } => {
                    let tr = (-sigma * (hit.as_ref().unwrap().p - o).length() as f64).exp();
                    (density, factor, weight) = (density * tr, factor * tr, weight * w);
                }
            }
        }
        let Some(h) = hit else {
            return Flight {
                stop: Stop::Escaped,
                density,
                factor,
                weight,
            };
        };
        if !scene.shapes[h.shape as usize].null {
            return Flight {
                stop: Stop::Surface(h),
                density,
                factor,
                weight,
            };
        }
        medium = scene.medium_across(h.interface, h.ng, d);
        ray = h.spawn_ray(d);
        o = h.p;
    }
}

/// The vertex a flight stopped at, built by the constructors integrators use.
fn vertex_at(
    fs: &FogScene,
    fl: &Flight,
    d: Vec3,
    beta: Color,
    pdf_w: f32,
    prev: &PathVertex,
) -> Option<PathVertex> {
    match &fl.stop {
        Stop::Medium(p) => Some(PathVertex::medium(
            fs.medium(),
            *p,
            -d,
            beta,
            pdf_w,
            fl.density as f32,
            prev,
        )),
        Stop::Surface(h) => Some(PathVertex::surface_through_media(
            h,
            -d,
            beta,
            pdf_w,
            fl.density as f32,
            prev,
        )),
        Stop::Escaped => None,
    }
}

/// The geometric arrival factor at a vertex: |cos|/d² at a surface, 1/d² in the medium.
fn arrival(from: Vec3, v: &PathVertex) -> f64 {
    if v.in_medium() {
        1.0 / (v.p - from).length_squared() as f64
    } else {
        solid_angle_to_area(1.0, from, v.p, v.ng) as f64
    }
}

/// Scattering at a vertex of the walk: the factor f_cos (or σs·p, no cosine, in the medium), the
/// sampled direction and its density, or `None` when the walk ends.
struct Bounce {
    f: f64,
    wi: Vec3,
    pdf_w: f32,
    weight: Color,
}

fn bounce(
    fs: &FogScene,
    v: &PathVertex,
    hit: Option<&SurfaceHit>,
    rng: &mut Sampler,
    mode: lt_core::bsdf::TransportMode,
) -> Option<Bounce> {
    match hit {
        None => {
            let phase = fs.scene.media[0].phase();
            let wi = sample_phase(phase, v.wo, rng.next_2d());
            let p = phase.eval(v.wo, wi);
            Some(Bounce {
                f: p as f64,
                wi,
                pdf_w: p,
                weight: Color::ONE,
            })
        }
        Some(h) => {
            let m = fs.scene.material(h.material);
            let bs = m.sample(
                &h.shading_frame(),
                v.wo,
                rng.next_f32(),
                rng.next_2d(),
                mode,
            )?;
            Some(Bounce {
                f: (bs.weight.x * bs.pdf_w) as f64,
                wi: bs.wi,
                pdf_w: bs.pdf_w,
                weight: bs.weight,
            })
        }
    }
}

/// The value f_cos of scattering at `v` from `wo` into `wi` (σs·p in the medium, whose σs the
/// flight's factor already holds: here p alone).
fn eval_at(
    fs: &FogScene,
    v: &PathVertex,
    hit: Option<&SurfaceHit>,
    wi: Vec3,
    mode: lt_core::bsdf::TransportMode,
) -> f64 {
    match hit {
        None => fs.scene.media[0].phase().eval(v.wo, wi) as f64,
        Some(h) => {
            fs.scene
                .material(h.material)
                .eval(&h.shading_frame(), v.wo, wi, mode)
                .f_cos
                .x as f64
        }
    }
}

fn grey(x: f64) -> DVec3 {
    DVec3::splat(x)
}

/// One camera walk through fog of at most `max_k` segments: s = 0 when it reaches the light and
/// s = 1 (next-event estimation, T from the geometry) at every vertex, medium or surface.
pub fn camera_walk(fs: &FogScene, rng: &mut Sampler, max_k: usize, out: &mut dyn FnMut(Made)) {
    use lt_core::bsdf::TransportMode::Radiance;
    let scene = &fs.scene;
    let cam = &scene.camera;
    let raster = rng.next_2d() * Vec2::new(cam.width as f32, cam.height as f32);
    let ray = cam.generate_ray(raster);
    let mut verts = vec![PathVertex::camera(cam, Color::ONE)];
    let (mut o, mut d) = (ray.o, ray.d);
    let mut pdf_w = cam.pdf_dir(ray.o, ray.d);
    let mut medium = scene.camera_medium;
    let mut pdf = 1.0f64;
    let mut f = grey((cam.importance(ray.o, ray.d) * cam.forward().dot(ray.d)) as f64);
    let mut beta = DVec3::ONE;
    for k in 1..=max_k {
        let prev = *verts.last().unwrap();
        let fl = fly(fs, o, d, medium, rng);
        let Some(v) = vertex_at(fs, &fl, d, beta.as_vec3(), pdf_w, &prev) else {
            return;
        };
        let hit = match &fl.stop {
            Stop::Surface(h) => Some(*h),
            _ => None,
        };
        let pa = pdf_w as f64 * fl.density * arrival(prev.p, &v);
        assert!(
            super::scenes::rel_close(v.pdf_fwd as f64, pa, 1e-4),
            "the vertex stores the density the walk used: {} vs {pa}",
            v.pdf_fwd
        );
        pdf *= pa;
        f *= fl.factor * arrival(prev.p, &v);
        beta *= fl.weight.as_dvec3();
        if let Some(h) = &hit {
            if let Some(x0) = v.as_light_endpoint() {
                let le = scene.lights[h.light.unwrap() as usize]
                    .emitted(h.ng, -d, h.uv)
                    .x as f64;
                out(Made {
                    path: Path::from_subpaths(&[x0], &verts),
                    s: 0,
                    pdf,
                    f: f * le,
                    estimate: beta * le,
                });
                return;
            }
        }
        let mut sub = verts.clone();
        sub.push(v);
        if k < max_k {
            nee(fs, rng, (&sub, hit.as_ref()), (pdf, f, beta), out);
        }
        let Some(b) = bounce(fs, &v, hit.as_ref(), rng, Radiance) else {
            return;
        };
        f *= b.f;
        beta *= b.weight.as_dvec3();
        pdf_w = b.pdf_w;
        medium = v.medium_towards(scene, b.wi);
        verts.push(v);
        o = v.p;
        d = b.wi;
        if let Some(h) = &hit {
            o = h.spawn_ray(d).o;
        }
    }
}

/// Next-event estimation from the walk's last vertex: x0 on the light chosen by `sample_li`,
/// the connection's T from the geometry.
fn nee(
    fs: &FogScene,
    rng: &mut Sampler,
    (sub, hit): (&[PathVertex], Option<&SurfaceHit>),
    (pdf, f, beta): (f64, DVec3, DVec3),
    out: &mut dyn FnMut(Made),
) {
    let scene = &fs.scene;
    let v = sub.last().unwrap();
    let Some((li, pmf, _)) = scene.light_sampler.sample(rng.next_f32()) else {
        return;
    };
    let Some(ls) = scene.lights[li].sample_li(v.p, rng.next_2d()) else {
        return;
    };
    let x0 = PathVertex::light_sampled(scene, li as u32, &ls, pmf, v);
    let tr = fs.transmittance(v.p, ls.p);
    // In the medium σs is already in f (the flight's factor): the phase function alone here.
    let fv = eval_at(fs, v, hit, ls.wi, lt_core::bsdf::TransportMode::Radiance);
    let pa = solid_angle_to_area(ls.pdf_w, v.p, ls.p, ls.n) as f64;
    let g = solid_angle_to_area(1.0, v.p, ls.p, ls.n) as f64;
    let le = ls.radiance.x as f64;
    out(Made {
        path: Path::from_subpaths(&[x0], sub),
        s: 1,
        pdf: pdf * pmf as f64 * pa,
        f: f * fv * g * tr * le,
        estimate: beta * fv * tr * le / (pmf * ls.pdf_w) as f64,
    });
}

/// One light walk through fog of at most `max_k` segments, connected to the camera (s = k) at
/// every vertex that projects onto the film (T from the geometry; visibility is not tested).
pub fn light_walk(fs: &FogScene, rng: &mut Sampler, max_k: usize, out: &mut dyn FnMut(Made)) {
    use lt_core::bsdf::TransportMode::Importance;
    let scene = &fs.scene;
    let cam = &scene.camera;
    let Some((li, pmf, _)) = scene.light_sampler.sample(rng.next_f32()) else {
        return;
    };
    let light = &scene.lights[li];
    let Some(le) = light.sample_le(rng.next_2d(), rng.next_2d(), scene.bounding_sphere) else {
        return;
    };
    let x0 = PathVertex::light_emitted(scene, li as u32, &le, pmf);
    let cos0 = le.n.dot(le.ray.d).abs() as f64;
    let mut verts = vec![x0];
    let mut pdf = (pmf * le.pdf_pos) as f64;
    let mut f = le.radiance.as_dvec3() * cos0;
    let mut beta = f / (pmf * le.pdf_pos * le.pdf_dir) as f64;
    let mut pdf_w = le.pdf_dir;
    let (mut o, mut d) = (le.ray.o, le.ray.d);
    let mut medium = scene.light_medium_towards(li as u32, (&x0).into(), le.ray.d);
    for k in 1..max_k {
        let prev = *verts.last().unwrap();
        let fl = fly(fs, o, d, medium, rng);
        let Some(v) = vertex_at(fs, &fl, d, beta.as_vec3(), pdf_w, &prev) else {
            return;
        };
        let hit = match &fl.stop {
            Stop::Surface(h) => Some(*h),
            _ => None,
        };
        pdf *= pdf_w as f64 * fl.density * arrival(prev.p, &v);
        f *= fl.factor * arrival(prev.p, &v);
        beta *= fl.weight.as_dvec3();
        if let Some(proj) = cam.project(v.p) {
            let e = eval_at(fs, &v, hit.as_ref(), -proj.dir, Importance);
            let cos_c = cam.forward().dot(proj.dir) as f64;
            let tr = fs.transmittance(v.p, cam.eye);
            let arrive = proj.importance as f64 * cos_c / (proj.distance * proj.distance) as f64;
            let mut sub = verts.clone();
            sub.push(v);
            out(Made {
                path: Path::from_subpaths(&sub, &[PathVertex::camera(cam, Color::ONE)]),
                s: k + 1,
                pdf,
                f: f * e * tr * arrive,
                estimate: beta * e * tr * arrive / cam.pixel_count() as f64,
            });
        }
        let Some(b) = bounce(fs, &v, hit.as_ref(), rng, Importance) else {
            return;
        };
        f *= b.f;
        beta *= b.weight.as_dvec3();
        pdf_w = b.pdf_w;
        medium = v.medium_towards(scene, b.wi);
        verts.push(v);
        o = v.p;
        d = b.wi;
        if let Some(h) = &hit {
            o = h.spawn_ray(d).o;
        }
    }
}

pub fn collect(fs: &FogScene, seed: u64, n: u64, camera: bool, max_k: usize) -> Vec<Made> {
    let mut made = Vec::new();
    for i in 0..n {
        let mut rng = Sampler::new(seed, i, 0);
        let mut push = |m: Made| made.push(m);
        if camera {
            camera_walk(fs, &mut rng, max_k, &mut push);
        } else {
            light_walk(fs, &mut rng, max_k, &mut push);
        }
    }
    made
}

/// The region A of path space the agreement test integrates over: every inner vertex at least
/// 0.3 from the camera and at least 0.3 below the ceiling light. A point in a medium next to the
/// pinhole (light tracing's splat ∝ 1/d²) or next to an area light (next-event estimation by area,
/// ∝ 1/d²) has f/p with an infinite second moment (∫ r⁻⁴ r² dr diverges), so the sample mean
/// there is no test; on A every technique estimates the same ∫_A f with finite variance.
fn away_from_singularities(scene: &Scene, path: &Path) -> bool {
    let v = &path.vertices;
    v[1..v.len() - 1]
        .iter()
        .all(|x| x.p.distance(scene.camera.eye) >= 0.3 && x.p.y <= 0.7)
}

/// One technique's mean per walk of f/(N p_s) (`Path::estimate`) over the paths of exactly `k`
/// segments it made, with its standard error. Over the whole film every technique estimates the
/// same number, the image's mean pixel value over the paths of A (`away_from_singularities`): a camera sample uniform on the film estimates it by
/// f/(N p_s), a light path by the sum of its splats f/(N p_k) (one light path per camera sample).
pub fn film_estimate(fs: &FogScene, s: usize, k: usize, n: u64) -> (f64, f64) {
    let light_tracing = s == k;
    let mut stats = super::scenes::Stats::default();
    for i in 0..n {
        let mut rng = Sampler::new(900 + 10 * s as u64 + k as u64, i, 0);
        let mut x = 0.0;
        let mut visit = |m: Made| {
            if m.path.k() == k && m.s == s && away_from_singularities(&fs.scene, &m.path) {
                x += m.path.estimate(&fs.scene, s).x as f64;
            }
        };
        if light_tracing {
            light_walk(fs, &mut rng, k, &mut visit);
        } else {
            camera_walk(fs, &mut rng, k, &mut visit);
        }
        stats.add(x);
    }
    (stats.mean(), stats.se())
}

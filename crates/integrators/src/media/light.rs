//! `light` through participating media: light subpaths leave the emitter in the medium it sits in
//! (`Scene::light_medium_towards`), free-flight sampling along each segment either scatters — a medium
//! vertex, born here, whose phase function is sampled to go on — or passes to the next surface;
//! `null` surfaces are crossed without a vertex. Every vertex that can be joined (x0 on an area
//! light, a non-delta surface, a medium vertex) is connected to a lens point (t = 1) and splatted
//! with β · f · T · We · cos θ_c / d², f the BSDF (with its cosine, importance mode) or the phase
//! function (no cosine), T an unbiased transmittance estimate through null boundaries and thin
//! dielectric panes (crossed as null events, as `pt`'s walk crosses them). Lights at
//! infinity are joined at x0 by the camera's direction towards them (`Camera::connect_direction`),
//! through the camera's medium.

use super::{is_null, point_end, surface_end};
use crate::splat::Splats;
use crate::subpath::media_step::{scatter_in_medium, NullCrossings};
use crate::subpath::walk::{continue_path, Emission, WalkPoint, WalkStart};
use lt_core::bsdf::TransportMode;
use lt_core::geometry::Ray;
use lt_core::light::Light;
use lt_core::math::{Color, Vec3};
use lt_core::medium::{FreeFlight, MediumId};
use lt_core::sampling::Sampler;
use lt_core::scene::ConnectionEnd;
use lt_core::Scene;

/// How long the walk may grow and what each splat is scaled by (1 / light paths per pass).
#[derive(Clone, Copy, Debug)]
pub struct LightWalk {
    pub max_depth: u32,
    pub rr_depth: u32,
    pub scale: f32,
}

/// Traces one light subpath through media and splats every joinable vertex into `splats`.
pub fn trace(scene: &Scene, walk: LightWalk, sampler: &mut Sampler, splats: &mut Splats) {
    let Some(emission) = Emission::sample(scene, sampler) else {
        return;
    };
    let (li, pmf, le) = (emission.light, emission.pmf, &emission.le);
    let light = &scene.lights[li];
    let mut medium = emission.medium(scene);
    if let Light::Area(_) = light {
        // x0 seen by the camera: Le towards the lens |cos θ0| / (pmf pdf_pos).
        let from = emission.at();
        let emitted = |to_camera: Vec3| {
            light.emitted(le.n, to_camera, le.uv) * (le.n.dot(to_camera).abs() / (pmf * le.pdf_pos))
        };
        let towards = |w: Vec3| scene.light_medium_towards(li as u32, from, w);
        splat(scene, walk, (le.p, from), towards, sampler, splats, emitted);
    } else if light.is_infinite() && !light.delta_direction() {
        let dir = -le.ray.d;
        splat_at_infinity(
            scene,
            walk,
            dir,
            light.escaped(dir) / (pmf * le.pdf_dir),
            sampler,
            splats,
        );
    }
    if walk.max_depth < 2 {
        return;
    }
    let start = emission.walk_start(scene);
    let rules = start.rules(walk.rr_depth);
    let WalkStart {
        mut ray, mut beta, ..
    } = start;
    // The index of the vertex the walk finds next (x0 on the light is 0).
    let mut n = 1;
    let mut crossings = NullCrossings::default();
    loop {
        let hit = scene.intersect(&ray);
        if let Some(m) = medium {
            let t_max = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
            let mm = &scene.media[m as usize];
            match mm.sample_free_flight(ray.o, ray.d, t_max, sampler) {
                FreeFlight::Scattered { t, weight } => {
                    beta *= weight;
                    if beta == Color::ZERO {
                        return;
                    }
                    let x = ray.o + ray.d * t;
                    let wo = -ray.d;
                    let phase = mm.phase();
                    let b = beta;
                    let value = |wi: Vec3| b * phase.eval(wo, wi);
                    splat(
                        scene,
                        walk,
                        (x, point_end(x)),
                        |_| Some(m),
                        sampler,
                        splats,
                        value,
                    );
                    if n + 1 >= walk.max_depth {
                        return;
                    }
                    let Some(ps) = scatter_in_medium(phase, wo, &rules, &mut beta, n, sampler)
                    else {
                        return;
                    };
                    ray = Ray::new(x, ps.wi);
                    n += 1;
                    crossings.reset();
                    continue;
                }
                FreeFlight::Passed { weight } => {
                    beta *= weight;
                    if beta == Color::ZERO {
                        return;
                    }
                }
            }
        }
        let Some(hit) = hit else {
            return;
        };
        if is_null(scene, &hit) {
            if !crossings.cross(scene, &hit, &mut ray, &mut medium) {
                return;
            }
            continue;
        }
        crossings.reset();
        let sf = hit.shading_frame();
        let at = WalkPoint {
            hit: &hit,
            sf: &sf,
            wo: -ray.d,
        };
        if !scene.material_is_delta(hit.material) {
            let material = scene.material(hit.material);
            let b = beta;
            let value = |wi: Vec3| {
                b * material
                    .eval(&sf, at.wo, wi, TransportMode::Importance)
                    .f_cos
            };
            let arrived = medium;
            let towards = |wi: Vec3| scene.medium_after(hit.interface, hit.ng, wi, arrived);
            let from = (hit.p, surface_end(&hit));
            splat(scene, walk, from, towards, sampler, splats, value);
        }
        // A pane's pass-through is no bounce (Mitsuba's null event, `pt`'s media walk alike).
        let pane = scene.has_null_transmission(hit.material);
        if n + 1 >= walk.max_depth && !pane {
            return;
        }
        let Some(bs) = continue_path(scene, &at, &rules, &mut beta, n, sampler) else {
            return;
        };
        let crossed = pane && scene.is_null_transmission(hit.material, sf.ns(), at.wo, bs.wi);
        if n + 1 >= walk.max_depth && !crossed {
            return;
        }
        medium = scene.medium_after(hit.interface, hit.ng, bs.wi, medium);
        ray = hit.spawn_ray(bs.wi);
        if !crossed {
            n += 1;
        }
    }
}

/// Joins the vertex at `p` to a lens point and splats `value(ω)` (ω towards the lens: β times
/// the vertex's BSDF-with-cosine or phase function, or x0's emission) times the transmittance
/// from the vertex's end `from`, starting in `medium_towards(ω)`, and the camera's We cos θ_c / d².
fn splat(
    scene: &Scene,
    walk: LightWalk,
    (p, from): (Vec3, ConnectionEnd),
    medium_towards: impl Fn(Vec3) -> Option<MediumId>,
    sampler: &mut Sampler,
    splats: &mut Splats,
    value: impl Fn(Vec3) -> Color,
) {
    let cam = &scene.camera;
    let Some(lens) = cam.connect(p, sampler) else {
        return;
    };
    let v = value(-lens.dir);
    if v == Color::ZERO {
        return;
    }
    let medium = medium_towards(-lens.dir);
    let tr = scene
        .transmittance_estimate_past_panes(from, point_end(lens.origin), medium, sampler)
        .unwrap_or(Color::ZERO);
    if tr == Color::ZERO {
        return;
    }
    let we = lens.importance * lens.cos_lens / lens.distance_squared;
    splats.add_filtered(cam.film(), lens.raster, v * tr * (we * walk.scale));
}

/// x0 on a light at infinity seen along `dir` (from the scene towards the light), Le / (pmf
/// pdf_dir) at its ray: joined to a lens point by direction, through the camera's medium.
fn splat_at_infinity(
    scene: &Scene,
    walk: LightWalk,
    dir: Vec3,
    value: Color,
    sampler: &mut Sampler,
    splats: &mut Splats,
) {
    let cam = &scene.camera;
    let Some(lens) = cam.connect_direction(dir, sampler) else {
        return;
    };
    if value == Color::ZERO {
        return;
    }
    let far = ConnectionEnd {
        p: dir,
        p_err: Vec3::ZERO,
        ng: Vec3::ZERO,
        infinite: true,
    };
    let from = point_end(lens.origin);
    let tr = scene
        .transmittance_estimate_past_panes(from, far, scene.camera_medium, sampler)
        .unwrap_or(Color::ZERO);
    if tr == Color::ZERO {
        return;
    }
    let we = lens.importance * lens.cos_lens / lens.distance_squared;
    splats.add_filtered(cam.film(), lens.raster, value * tr * (we * walk.scale));
}

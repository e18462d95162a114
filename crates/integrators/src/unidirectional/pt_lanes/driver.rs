//! One image row walked `LANES` paths at a time, bounce by bounce, following `Pt::radiance`
//! (without a recorder) step for step: each step runs over the live lanes, the closest hits
//! through the ray core's packet query, the other scene queries per lane through the scalar
//! functions, the arithmetic of the estimate through the lane kernels. A lane whose path ends
//! is refilled with the row's next pixel before the next bounce, so the packet stays full until
//! the row runs out (each pixel draws from its own stream, so the order pixels are taken in
//! changes no bits).

use super::kernels::{self, NextEventLanes};
use super::state::{ColorLanes, Mask, PathLanes, LANES};
use crate::film::pixel::{pixel_sample, weighted};
use crate::pt::{Pt, Techniques};
use crate::subpath::walk::{continue_path, escaped_radiance, WalkPoint, WalkRules};
use lt_core::bsdf::{ShadingFrame, TransportMode};
use lt_core::geometry::Ray;
use lt_core::math::{is_valid_color, Color, Vec3};
use lt_core::sampling::{Domain, Sampler};
use lt_core::scene::SurfaceHit;
use lt_core::Scene;

/// Renders pixels `first .. first + row.len()` of pass `pass` of the run seeded by `seed` into
/// `row`, as `film::pixel::pixel_pass` does (filter weight, invalid estimates left at zero);
/// returns how many were invalid.
pub fn run_row(
    pt: &Pt,
    scene: &Scene,
    (seed, pass): (u64, u32),
    first: u64,
    row: &mut [[f64; 3]],
) -> u64 {
    let nee = pt.params.techniques != Techniques::Bsdf;
    let rules = WalkRules::camera(pt.params.rr_depth);
    let mut lanes = idle_lanes();
    let mut next = 0;
    let mut bad = 0;
    loop {
        for i in 0..LANES {
            while !lanes.alive[i] && next < row.len() {
                start(scene, (seed, pass), first, &mut lanes, i, next);
                next += 1;
            }
        }
        let was_alive = lanes.alive;
        if !was_alive.iter().any(|&a| a) {
            break;
        }
        // `Pt::radiance`'s loop runs no bounce when max_depth is 0.
        if pt.params.max_depth == 0 {
            lanes.alive = [false; LANES];
        } else {
            bounce(pt, scene, &mut lanes, nee, &rules);
        }
        for i in 0..LANES {
            if was_alive[i] && !lanes.alive[i] {
                let c = weighted(lanes.l.get(i), lanes.film_weight[i]);
                if is_valid_color(c) {
                    row[lanes.pixel[i]] = [c.x as f64, c.y as f64, c.z as f64];
                } else {
                    bad += 1;
                }
            }
        }
    }
    bad
}

/// One turn of `Pt::radiance`'s loop on every live lane, each at its own depth; lanes whose path
/// ends retire (`alive` cleared).
fn bounce(pt: &Pt, scene: &Scene, lanes: &mut PathLanes, nee: bool, rules: &WalkRules) {
    let hits = scene.intersect_packet(&lanes.ray, &lanes.alive);
    escape(pt, scene, lanes, &hits);
    emitters(pt, scene, lanes, &hits);
    for i in live(&lanes.alive.clone()) {
        if lanes.depth[i] == pt.params.max_depth {
            lanes.alive[i] = false;
        }
    }
    // Each surviving lane's shading frame, built once for both steps below (as `Pt::radiance`
    // builds it once per bounce).
    let frames: [Option<ShadingFrame>; LANES] = std::array::from_fn(|i| {
        let hit = hits[i].as_ref().filter(|_| lanes.alive[i]);
        hit.map(SurfaceHit::shading_frame)
    });
    if nee {
        next_event(pt, scene, lanes, &hits, &frames);
    }
    scatter(scene, lanes, &hits, &frames, rules);
    for i in live(&lanes.alive) {
        lanes.depth[i] += 1;
    }
}

/// The live lanes' indices.
fn live(alive: &Mask) -> impl Iterator<Item = usize> + '_ {
    (0..LANES).filter(move |&i| alive[i])
}

/// Lanes with no pixel yet.
fn idle_lanes() -> PathLanes {
    PathLanes {
        alive: [false; LANES],
        pixel: [0; LANES],
        depth: [1; LANES],
        samplers: std::array::from_fn(|_| None),
        film_weight: [0.0; LANES],
        ray: [idle_ray(); LANES],
        beta: ColorLanes::splat(Color::ONE),
        l: ColorLanes::splat(Color::ZERO),
        prev_pdf_w: [0.0; LANES],
        prev_delta: [true; LANES],
        prev_p: [Vec3::ZERO; LANES],
    }
}

/// Lane `i` takes the row's pixel `x`: its stream, film position and camera ray (`pixel_pass`,
/// then the first lines of `Pt::radiance`). A sample the filter moved off the film leaves the
/// pixel at zero and the lane idle.
fn start(
    scene: &Scene,
    (seed, pass): (u64, u32),
    first: u64,
    lanes: &mut PathLanes,
    i: usize,
    x: usize,
) {
    let pixel = first + x as u64;
    let mut s = Sampler::for_item(Domain::Camera, seed, pixel, pass as u64);
    let Some(film) = pixel_sample(scene, pixel, &mut s) else {
        return;
    };
    let ray = scene.camera.sample_ray(film.raster, &mut s);
    lanes.alive[i] = true;
    lanes.pixel[i] = x;
    lanes.depth[i] = 1;
    lanes.samplers[i] = Some(s);
    lanes.film_weight[i] = film.weight;
    lanes.ray[i] = ray;
    lanes.beta.set(i, Color::ONE);
    lanes.l.set(i, Color::ZERO);
    lanes.prev_pdf_w[i] = 0.0;
    lanes.prev_delta[i] = true;
    lanes.prev_p[i] = ray.o;
}

/// The ray slot of a lane without a sample (never traced).
fn idle_ray() -> Ray {
    Ray::new(Vec3::ZERO, Vec3::Z)
}

/// Lanes whose ray left the scene: lights at infinity complete them and they retire
/// (`Pt::radiance`'s `None` arm of `scene.intersect`; per lane, scalar).
fn escape(pt: &Pt, scene: &Scene, lanes: &mut PathLanes, hits: &[Option<SurfaceHit>; LANES]) {
    for i in live(&lanes.alive.clone()) {
        if hits[i].is_some() {
            continue;
        }
        let d = lanes.ray[i].d;
        let (beta, prev_p) = (lanes.beta.get(i), lanes.prev_p[i]);
        let (prev_delta, prev_pdf_w) = (lanes.prev_delta[i], lanes.prev_pdf_w[i]);
        let le = escaped_radiance(scene, d, |li| {
            let light_pdf = scene.light_sampler.pmf(li as usize)
                * scene.lights[li as usize].pdf_li(prev_p, d, d, -d);
            pt.hit_weights(prev_delta, prev_pdf_w, light_pdf).0
        });
        lanes.l.set(i, lanes.l.get(i) + beta * le);
        lanes.alive[i] = false;
    }
}

/// Lanes that hit an emitter add its radiance under the MIS weight against next-event estimation
/// (scene queries per lane, `kernels::hit_weight` and `kernels::add_emitted` across lanes).
fn emitters(pt: &Pt, scene: &Scene, lanes: &mut PathLanes, hits: &[Option<SurfaceHit>; LANES]) {
    let mut lit = [false; LANES];
    let mut le = ColorLanes::default();
    let mut light_pdf = [0.0f32; LANES];
    for i in live(&lanes.alive) {
        let Some(hit) = &hits[i] else { continue };
        let Some(li) = hit.light else { continue };
        let light = &scene.lights[li as usize];
        let e = light.emitted(hit.ng, -lanes.ray[i].d, hit.uv);
        if e == Color::ZERO {
            continue;
        }
        lit[i] = true;
        le.set(i, e);
        light_pdf[i] = scene.light_sampler.pmf(li as usize)
            * light.pdf_li(lanes.prev_p[i], lanes.ray[i].d, hit.p, hit.ng);
    }
    if !lit.iter().any(|&x| x) {
        return;
    }
    let w = kernels::hit_weight(pt, &lanes.prev_delta, &lanes.prev_pdf_w, &light_pdf);
    kernels::add_emitted(&mut lanes.l, &lit, &lanes.beta, &le, &w);
}

/// Next-event estimation at every live non-delta vertex: `Pt::direct_light`'s draws and queries
/// per lane, its weight and sum through `kernels::add_next_event`.
fn next_event(
    pt: &Pt,
    scene: &Scene,
    lanes: &mut PathLanes,
    hits: &[Option<SurfaceHit>; LANES],
    frames: &[Option<ShadingFrame>; LANES],
) {
    let mut ran = [false; LANES];
    let mut ne = NextEventLanes::default();
    for i in live(&lanes.alive) {
        let (Some(hit), Some(sf)) = (&hits[i], &frames[i]) else {
            continue;
        };
        if scene.material_is_delta(hit.material) {
            continue;
        }
        ran[i] = true;
        let sampler = lanes.samplers[i]
            .as_mut()
            .expect("a live lane has a stream");
        let Some((li, pmf, _)) = scene.light_sampler.sample(sampler.next_f32()) else {
            continue;
        };
        let u = sampler.next_2d();
        let Some(ls) = scene.lights[li].sample_li(hit.p, u) else {
            continue;
        };
        if ls.radiance == Color::ZERO || ls.pdf_w == 0.0 {
            continue;
        }
        let wo = -lanes.ray[i].d;
        let ev = scene
            .material(hit.material)
            .eval(sf, wo, ls.wi, TransportMode::Radiance);
        if ev.f_cos == Color::ZERO || !scene.visible_light(hit, &ls) {
            continue;
        }
        ne.found[i] = true;
        ne.f_cos.set(i, ev.f_cos);
        ne.radiance.set(i, ls.radiance);
        ne.light_pdf[i] = pmf * ls.pdf_w;
        ne.bsdf_pdf[i] = ev.pdf_w;
        ne.weight_one[i] = ls.delta || pt.params.techniques == Techniques::Light;
    }
    kernels::add_next_event(pt, &mut lanes.l, &ran, &lanes.beta, &ne);
}

/// Each live lane samples its BSDF, updates its throughput and plays Russian roulette
/// (`continue_path`, per lane, at the lane's own depth); lanes that stop retire.
fn scatter(
    scene: &Scene,
    lanes: &mut PathLanes,
    hits: &[Option<SurfaceHit>; LANES],
    frames: &[Option<ShadingFrame>; LANES],
    rules: &WalkRules,
) {
    for i in live(&lanes.alive.clone()) {
        let (Some(hit), Some(sf)) = (&hits[i], &frames[i]) else {
            continue;
        };
        let at = WalkPoint {
            hit,
            sf,
            wo: -lanes.ray[i].d,
        };
        let sampler = lanes.samplers[i]
            .as_mut()
            .expect("a live lane has a stream");
        let mut beta = lanes.beta.get(i);
        let next = continue_path(scene, &at, rules, &mut beta, lanes.depth[i], sampler);
        lanes.beta.set(i, beta);
        let Some(bs) = next else {
            lanes.alive[i] = false;
            continue;
        };
        lanes.prev_pdf_w[i] = bs.pdf_w;
        lanes.prev_delta[i] = bs.delta;
        lanes.prev_p[i] = hit.p;
        lanes.ray[i] = hit.spawn_ray(bs.wi);
    }
}

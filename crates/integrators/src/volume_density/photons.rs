//! Volume photons: the medium vertices of light subpaths, and nothing else (surfaces are left to
//! the camera walk's `pt`, see `mod.rs`), so a scene without media stores none.
//!
//! The walk is `media/light.rs`'s (free flight in the ray's medium, null boundaries crossed
//! without a vertex, thin panes as null events, importance transport at surfaces), storing a
//! photon where light tracing would splat a medium vertex. A photon's `power` is the subpath's
//! throughput *without* σs at its vertex: β = Le cos/(p…) · Π(f/p) · T/p_ff, so that
//! E[Σ_photons power · g(x, ω)] = ∫_V ∫_S² L(x, −ω) g(x, ω) dω dx for any g (the collision
//! density times its weight σs T/p_ff, divided by σs): the kernel estimates in `points.rs` and
//! `beams.rs` then multiply σs back at the query point, where the camera walk needs it.

use crate::subpath::media_step::NullCrossings;
use crate::subpath::walk::{continue_path, russian_roulette, Emission, WalkPoint, WalkStart};
use lt_core::geometry::Ray;
use lt_core::math::{Color, Vec3};
use lt_core::medium::{FreeFlight, MediumId};
use lt_core::sampling::{Domain, Sampler};
use lt_core::Scene;
use rayon::prelude::*;

/// What a photon carries besides its position (kept apart, in `VolumePhotons::points`, for the
/// grids). 12 + 12 + 4 + 4 = 32 bytes, plus 12 for the position.
#[derive(Clone, Copy, Debug)]
pub struct PhotonData {
    /// Unit direction towards the previous light-subpath vertex (where the light came from).
    pub wi: Vec3,
    /// Throughput without σs at the vertex (module comment), scaled by 1 / photon paths.
    pub power: Color,
    pub medium: MediumId,
    /// Segments from the light (x0) to this vertex: a camera prefix of t segments may join it
    /// while t + segments ≤ max_depth.
    pub segments: u32,
}

/// One pass's photons, in the order of their paths (then along each path): the same for any
/// thread count.
#[derive(Default)]
pub struct VolumePhotons {
    pub points: Vec<Vec3>,
    pub data: Vec<PhotonData>,
}

impl VolumePhotons {
    /// Bytes held per photon (position and data).
    pub const BYTES_PER_PHOTON: usize =
        std::mem::size_of::<Vec3>() + std::mem::size_of::<PhotonData>();
}

/// What a light walk leaves behind: photon points at its medium vertices (`VolumePhotons`) or
/// photon beams along its flights through media (`photon_beams.rs`). One walk, so both see the
/// same light subpaths from the same streams.
pub trait LightRecord: Default + Send {
    /// A flight in medium `m` along `ray` up to `t_max` (the next surface, or infinity), whose
    /// scattering vertex would be the subpath's `n`-th; `beta` is the throughput at its start,
    /// already scaled by 1 / photon paths.
    fn flight(&mut self, _ray: &Ray, _t_max: f32, _m: MediumId, _beta: Color, _n: u32) {}
    /// A medium vertex at `x` (its data as a photon point).
    fn scatter(&mut self, _x: Vec3, _photon: PhotonData) {}
    /// Appends another path's record (paths kept in order).
    fn append(&mut self, other: Self);
}

impl LightRecord for VolumePhotons {
    fn scatter(&mut self, x: Vec3, photon: PhotonData) {
        self.points.push(x);
        self.data.push(photon);
    }

    fn append(&mut self, other: Self) {
        self.points.extend(other.points);
        self.data.extend(other.data);
    }
}

/// Traces `paths` light subpaths of pass `pass` (streams `Domain::Light`, item = path index) and
/// keeps their medium vertices with at most `max_depth − 1` segments (a camera prefix has at
/// least one).
pub fn trace(
    scene: &Scene,
    max_depth: u32,
    rr_depth: u32,
    paths: u64,
    seed: u64,
    pass: u32,
) -> VolumePhotons {
    trace_records(scene, max_depth, rr_depth, paths, seed, pass)
}

/// `trace` for any record: the same walks, recorded by `R`, in path order.
pub fn trace_records<R: LightRecord>(
    scene: &Scene,
    max_depth: u32,
    rr_depth: u32,
    paths: u64,
    seed: u64,
    pass: u32,
) -> R {
    let mut all = R::default();
    if !scene.has_media || paths == 0 || max_depth < 2 {
        return all;
    }
    let scale = 1.0 / paths as f32;
    let per_path: Vec<R> = (0..paths)
        .into_par_iter()
        .map(|j| {
            let mut s = Sampler::for_item(Domain::Light, seed, j, pass as u64);
            let mut out = R::default();
            walk(scene, max_depth, rr_depth, scale, &mut s, &mut out);
            out
        })
        .collect();
    for r in per_path {
        all.append(r);
    }
    all
}

/// `v / σs` per channel, zero where σs is (β is zero there too).
fn without_sigma_s(v: Color, sigma_s: Color) -> Color {
    Color::select(sigma_s.cmpgt(Color::ZERO), v / sigma_s, Color::ZERO)
}

fn walk(
    scene: &Scene,
    max_depth: u32,
    rr_depth: u32,
    scale: f32,
    sampler: &mut Sampler,
    out: &mut impl LightRecord,
) {
    // The light subpath's start, as every light walk draws it (same numbers, same β).
    let Some(emission) = Emission::sample(scene, sampler) else {
        return;
    };
    let mut medium = emission.medium(scene);
    let start = emission.walk_start(scene);
    let rules = start.rules(rr_depth);
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
            out.flight(&ray, t_max, m, beta * scale, n);
            match mm.sample_free_flight(ray.o, ray.d, t_max, sampler) {
                FreeFlight::Scattered { t, weight } => {
                    beta *= weight;
                    if beta == Color::ZERO {
                        return;
                    }
                    let x = ray.o + ray.d * t;
                    let wo = -ray.d;
                    let power = without_sigma_s(beta, mm.sigma_s(x)) * scale;
                    out.scatter(
                        x,
                        PhotonData {
                            wi: wo,
                            power,
                            medium: m,
                            segments: n,
                        },
                    );
                    if n + 1 >= max_depth {
                        return;
                    }
                    let Some(ps) = mm.phase().sample(wo, sampler.next_2d()) else {
                        return;
                    };
                    beta *= ps.value / ps.pdf;
                    if !russian_roulette(&mut beta, rules.rr_reference, n, rr_depth, sampler) {
                        return;
                    }
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
        if scene.shapes[hit.shape as usize].null {
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
        // A pane's pass-through is no bounce (Mitsuba's null event, as in `media/light.rs`).
        let pane = scene.has_null_transmission(hit.material);
        if n + 1 >= max_depth && !pane {
            return;
        }
        let Some(bs) = continue_path(scene, &at, &rules, &mut beta, n, sampler) else {
            return;
        };
        let crossed = pane && scene.is_null_transmission(hit.material, sf.ns(), at.wo, bs.wi);
        if n + 1 >= max_depth && !crossed {
            return;
        }
        medium = scene.medium_after(hit.interface, hit.ng, bs.wi, medium);
        ray = hit.spawn_ray(bs.wi);
        if !crossed {
            n += 1;
        }
    }
}

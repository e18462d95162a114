//! Camera paths of the photon-mapping family, shared by them and owned by none: from the pinhole
//! through delta bounces (mirror, glass) to the first non-delta vertex — the visible point where
//! photons are gathered — collecting on the way what photons cannot give: emission seen directly
//! or through delta bounces, and, when direct light is not left to photons, next-event estimation
//! at the visible point.

use crate::density::photons::GatherPoint;
use crate::subpath::walk::{continue_path, escaped_radiance, WalkPoint, WalkRules};
use lt_core::bsdf::{ShadingFrame, TransportMode};
use lt_core::math::{Color, Vec2, Vec3};
use lt_core::sampling::Sampler;
use lt_core::scene::SurfaceHit;
use lt_core::Scene;

/// Who accounts for light arriving straight from an emitter at the visible point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direct {
    /// Next-event estimation at the visible point; photons that arrived straight from an emitter
    /// are not stored.
    Nee,
    /// Photons, like every other bounce.
    Photons,
}

impl Direct {
    pub fn parse(s: &str) -> Result<Direct, String> {
        match s {
            "nee" => Ok(Direct::Nee),
            "photons" => Ok(Direct::Photons),
            _ => Err(format!("unknown direct '{s}' (known: nee, photons)")),
        }
    }
}

/// A visible point and the pixel's footprint there.
#[derive(Clone, Copy, Debug)]
pub struct VisiblePoint {
    pub gp: GatherPoint,
    /// The surface point itself (next-event estimation from it again, for `ppm`).
    pub hit: SurfaceHit,
    /// One pixel's footprint at the point, in scene units: the camera's pixel footprint at the
    /// length of the path to it (exact through flat mirrors, a guide through curved ones).
    pub footprint: f32,
}

/// What one camera sample found.
#[derive(Clone, Copy, Debug, Default)]
pub struct CameraPrefix {
    pub vp: Option<VisiblePoint>,
    /// Emission seen directly or through delta bounces (photons cannot give it).
    pub emitted: Color,
    /// Next-event estimation at the visible point, times its throughput (zero with
    /// `Direct::Photons`).
    pub nee: Color,
}

impl CameraPrefix {
    /// The prefix of a camera sample weighted by the pixel filter (`pixel::pixel_sample`): its
    /// throughput, emission and next-event estimate scaled alike, so every photon gathered at it
    /// is too. An off-film sample (`None`) finds nothing.
    pub fn weighted(sample: Option<(Self, f32)>) -> CameraPrefix {
        let Some((mut p, w)) = sample else {
            return CameraPrefix::default();
        };
        if w != 1.0 {
            p.emitted *= w;
            p.nee *= w;
            if let Some(vp) = p.vp.as_mut() {
                vp.gp.beta *= w;
            }
        }
        p
    }

    /// Everything but the photons' share.
    pub fn direct(&self) -> Color {
        self.emitted + self.nee
    }
}

/// Traces the camera path through `raster` to its first non-delta vertex within `max_depth`
/// segments. Delta chains play no Russian roulette (their throughput only falls by Fresnel).
pub fn trace_visible_point(
    scene: &Scene,
    raster: Vec2,
    sampler: &mut Sampler,
    max_depth: u32,
    direct: Direct,
) -> CameraPrefix {
    let mut ray = scene.camera.sample_ray(raster, sampler);
    let mut beta = Color::ONE;
    let mut out = CameraPrefix::default();
    let mut length = 0.0;
    for depth in 1..=max_depth {
        let Some(hit) = scene.intersect(&ray) else {
            out.emitted += beta * escaped_radiance(scene, ray.d, |_| 1.0);
            return out;
        };
        length += hit.t;
        let wo = -ray.d;
        if let Some(li) = hit.light {
            out.emitted += beta * scene.lights[li as usize].emitted(hit.ng, wo, hit.uv);
        }
        let material = scene.material(hit.material);
        let sf = hit.shading_frame();
        // A delta lobe beside smooth ones (plastic's coating): the path follows it with the
        // probability P the material gives it, else stops here with the visible point weighted
        // by 1/(1 − P), so each part of the BSDF is estimated by one branch. Other materials
        // draw nothing here (their images keep their bits).
        let mut follow_delta = None;
        if !material.is_delta() && material.has_delta_lobe() {
            let p = material.delta_lobe_probability(&sf, wo);
            let u_lobe = sampler.next_f32();
            if u_lobe < p {
                follow_delta = Some(u_lobe);
            } else {
                beta /= 1.0 - p;
            }
        }
        if !material.is_delta() && follow_delta.is_none() {
            if direct == Direct::Nee && depth < max_depth {
                out.nee = beta * next_event(scene, &hit, &sf, wo, sampler);
            }
            out.vp = Some(VisiblePoint {
                gp: GatherPoint {
                    p: hit.p,
                    sf,
                    wo,
                    material: hit.material,
                    beta,
                    segments: depth,
                },
                hit,
                footprint: scene.camera.pixel_footprint(length),
            });
            return out;
        }
        if depth == max_depth {
            return out;
        }
        let mode = TransportMode::Radiance;
        if let Some(u_lobe) = follow_delta {
            // u_lobe < P picks the delta lobe; its weight already divides by P.
            let Some(bs) = material.sample(&sf, wo, u_lobe, sampler.next_2d(), mode) else {
                return out;
            };
            debug_assert!(bs.delta);
            beta *= bs.weight;
            ray = hit.spawn_ray(bs.wi);
            continue;
        }
        let at = WalkPoint {
            hit: &hit,
            sf: &sf,
            wo,
        };
        let no_rr = WalkRules::camera(u32::MAX);
        let Some(bs) = continue_path(scene, &at, &no_rr, &mut beta, depth, sampler) else {
            return out;
        };
        ray = hit.spawn_ray(bs.wi);
    }
    out
}

/// Next-event estimation at a non-delta surface point: one light chosen by power, one sample of
/// it, no MIS (the camera path stops here, so nothing else samples these paths).
pub fn next_event(
    scene: &Scene,
    hit: &SurfaceHit,
    sf: &ShadingFrame,
    wo: Vec3,
    sampler: &mut Sampler,
) -> Color {
    let Some((li, pmf, _)) = scene.light_sampler.sample(sampler.next_f32()) else {
        return Color::ZERO;
    };
    let u = sampler.next_2d();
    let Some(ls) = scene.lights[li].sample_li(hit.p, u) else {
        return Color::ZERO;
    };
    if ls.radiance == Color::ZERO || !(ls.pdf_w > 0.0) {
        return Color::ZERO;
    }
    let ev = scene
        .material(hit.material)
        .eval(sf, wo, ls.wi, TransportMode::Radiance);
    if ev.f_cos == Color::ZERO || !scene.visible_light(hit, &ls) {
        return Color::ZERO;
    }
    ev.f_cos * ls.radiance / (pmf * ls.pdf_w)
}

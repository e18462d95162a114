//! `pt` — unidirectional path tracing with next-event estimation, combined with BSDF sampling by
//! multiple importance sampling (power heuristic, Veach & Guibas 1995).
//!
//! At every non-delta vertex one light is chosen by power and sampled towards the vertex (NEE);
//! the BSDF-sampled continuation may hit an emitter too. Both techniques can produce the same path,
//! so each contribution is weighted by the power heuristic over their solid-angle pdfs at the
//! vertex. Delta lights (point) and delta BSDF lobes (mirror, glass) are reached by one technique
//! only and get weight one.
//!
//! | key | type | default | meaning |
//! |---|---|---|---|
//! | `max_depth` | u32 | scene `[render] max_depth` (8) | longest path in segments, camera ray included |
//! | `rr_depth` | u32 | scene `[render] rr_depth` (5) | Russian roulette from this many segments on |

use crate::pixel::pixel_pass;
use crate::Integrator;
use lt_core::bsdf::{ShadingFrame, TransportMode};
use lt_core::math::Color;
use lt_core::sampling::{power_heuristic, Sampler};
use lt_core::scene::SurfaceHit;
use lt_core::{Scene, Vec2};
use lt_estimators::Image;

#[derive(Clone, Copy, Debug)]
pub struct PtParams {
    pub max_depth: u32,
    pub rr_depth: u32,
}

pub struct Pt {
    pub params: PtParams,
}

/// Russian roulette: continue with probability min(max βᵢ, 0.95) and reweight. Returns false to stop.
#[inline]
pub(crate) fn russian_roulette(
    beta: &mut Color,
    depth: u32,
    rr_depth: u32,
    sampler: &mut Sampler,
) -> bool {
    if depth < rr_depth {
        return true;
    }
    let q = beta.max_element().min(0.95);
    if sampler.next_f32() >= q {
        return false;
    }
    *beta /= q;
    true
}

/// Radiance from every light at infinity along a ray leaving the scene, each weighted by `weight`.
#[inline]
pub(crate) fn escaped_radiance(
    scene: &Scene,
    dir: lt_core::Vec3,
    weight: impl Fn(u32) -> f32,
) -> Color {
    let mut l = Color::ZERO;
    for &i in &scene.infinite_lights {
        let le = scene.lights[i as usize].escaped(dir);
        if le != Color::ZERO {
            l += le * weight(i);
        }
    }
    l
}

/// Continues a camera path at `hit` by sampling its BSDF: multiplies the throughput by the sample
/// weight and plays Russian roulette. `None` ends the path.
#[inline]
pub(crate) fn continue_path(
    scene: &Scene,
    hit: &SurfaceHit,
    sf: &ShadingFrame,
    wo: lt_core::Vec3,
    beta: &mut Color,
    depth: u32,
    rr_depth: u32,
    sampler: &mut Sampler,
) -> Option<lt_core::bsdf::BsdfSample> {
    let u_lobe = sampler.next_f32();
    let u = sampler.next_2d();
    let bs = scene
        .material(hit.material)
        .sample(sf, wo, u_lobe, u, TransportMode::Radiance)?;
    *beta *= bs.weight;
    (*beta != Color::ZERO && russian_roulette(beta, depth, rr_depth, sampler)).then_some(bs)
}

impl Pt {
    /// Next-event estimation at `hit`: one light chosen by power, MIS-weighted against the BSDF.
    fn direct_light(
        &self,
        scene: &Scene,
        hit: &SurfaceHit,
        sf: &ShadingFrame,
        wo: lt_core::Vec3,
        sampler: &mut Sampler,
    ) -> Color {
        let Some((li, pmf, _)) = scene.light_sampler.sample(sampler.next_f32()) else {
            return Color::ZERO;
        };
        let u = sampler.next_2d();
        let light = &scene.lights[li];
        let Some(ls) = light.sample_li(hit.p, u) else {
            return Color::ZERO;
        };
        if ls.radiance == Color::ZERO || ls.pdf_w == 0.0 {
            return Color::ZERO;
        }
        let material = scene.material(hit.material);
        let ev = material.eval(sf, wo, ls.wi, TransportMode::Radiance);
        if ev.f_cos == Color::ZERO {
            return Color::ZERO;
        }
        let unoccluded = if ls.distance.is_finite() {
            scene.visible(hit, ls.p)
        } else {
            scene.unoccluded_towards(hit, ls.wi)
        };
        if !unoccluded {
            return Color::ZERO;
        }
        let light_pdf = pmf * ls.pdf_w;
        let w = if ls.delta {
            1.0
        } else {
            power_heuristic(light_pdf, ev.pdf_w)
        };
        ev.f_cos * ls.radiance * (w / light_pdf)
    }

    pub fn radiance(&self, scene: &Scene, raster: Vec2, sampler: &mut Sampler) -> Color {
        let mut ray = scene.camera.generate_ray(raster);
        let mut beta = Color::ONE;
        let mut l = Color::ZERO;
        // The previous vertex's BSDF pdf (solid angle) and whether it was a delta lobe; the camera
        // counts as a delta so emitters seen directly get full weight.
        let mut prev_pdf_w = 0.0f32;
        let mut prev_delta = true;
        let mut prev_p = ray.o;
        for depth in 1..=self.params.max_depth {
            let Some(hit) = scene.intersect(&ray) else {
                l += beta
                    * escaped_radiance(scene, ray.d, |i| {
                        if prev_delta {
                            1.0
                        } else {
                            let light_pdf = scene.light_sampler.pmf(i as usize)
                                * scene.lights[i as usize].pdf_li(prev_p, ray.d, ray.d, -ray.d);
                            power_heuristic(prev_pdf_w, light_pdf)
                        }
                    });
                break;
            };
            let wo = -ray.d;
            if let Some(li) = hit.light {
                let light = &scene.lights[li as usize];
                let le = light.emitted(hit.ng, wo);
                if le != Color::ZERO {
                    let w = if prev_delta {
                        1.0
                    } else {
                        let light_pdf = scene.light_sampler.pmf(li as usize)
                            * light.pdf_li(prev_p, ray.d, hit.p, hit.ng);
                        power_heuristic(prev_pdf_w, light_pdf)
                    };
                    l += beta * le * w;
                }
            }
            if depth == self.params.max_depth {
                break;
            }
            let material = scene.material(hit.material);
            let sf = hit.shading_frame();
            if !material.is_delta() {
                l += beta * self.direct_light(scene, &hit, &sf, wo, sampler);
            }
            let Some(bs) = continue_path(
                scene,
                &hit,
                &sf,
                wo,
                &mut beta,
                depth,
                self.params.rr_depth,
                sampler,
            ) else {
                break;
            };
            prev_pdf_w = bs.pdf_w;
            prev_delta = bs.delta;
            prev_p = hit.p;
            ray = hit.spawn_ray(bs.wi);
        }
        l
    }
}

impl Integrator for Pt {
    fn name(&self) -> &'static str {
        "pt"
    }

    fn render_pass(&self, scene: &Scene, seed: u64, pass: u32) -> (Image, u64) {
        pixel_pass(scene, seed, pass, |s, raster| {
            self.radiance(scene, raster, s)
        })
    }
}

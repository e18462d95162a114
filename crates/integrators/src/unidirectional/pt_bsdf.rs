//! `pt-bsdf` — path tracing by BSDF sampling alone: light is found only when a sampled path hits an
//! emitter or escapes to a light at infinity. It shares no light-sampling code with `pt`, which is
//! why it is the independent cross-check of `pt` (the two must agree within their standard errors).
//! It cannot see delta lights (point and directional lights: a BSDF sample never hits a point or
//! a single direction), and converges slowly for small lights.
//!
//! | key | type | default | meaning |
//! |---|---|---|---|
//! | `max_depth` | u32 | scene `[render] max_depth` (8) | longest path in segments, camera ray included |
//! | `rr_depth` | u32 | scene `[render] rr_depth` (5) | Russian roulette from this many segments on |

use crate::film::pixel::pixel_pass;
use crate::params::ParamReader;
use crate::subpath::walk::{continue_path, escaped_radiance, WalkPoint, WalkRules};
use crate::Integrator;
use lt_core::math::Color;
use lt_core::sampling::Sampler;
use lt_core::{Scene, Vec2};
use lt_estimators::Image;

#[derive(Clone, Copy, Debug)]
pub struct PtBsdfParams {
    pub max_depth: u32,
    pub rr_depth: u32,
}

impl PtBsdfParams {
    pub fn read(scene: &Scene, r: &ParamReader) -> Result<PtBsdfParams, String> {
        Ok(PtBsdfParams {
            max_depth: r.max_depth(scene)?,
            rr_depth: r.rr_depth(scene)?,
        })
    }
}

pub struct PtBsdf {
    pub params: PtBsdfParams,
}

impl PtBsdf {
    /// `pt` with BSDF (and phase) sampling alone: the walk `pt-bsdf` runs through media.
    fn as_bsdf_only_pt(&self) -> crate::pt::Pt {
        crate::pt::Pt {
            params: crate::pt::PtParams {
                max_depth: self.params.max_depth,
                rr_depth: self.params.rr_depth,
                mis: lt_core::path::Heuristic::Power,
                techniques: crate::pt::Techniques::Bsdf,
            },
        }
    }

    pub fn radiance(&self, scene: &Scene, raster: Vec2, sampler: &mut Sampler) -> Color {
        let mut ray = scene.camera.sample_ray(raster, sampler);
        let mut beta = Color::ONE;
        let mut l = Color::ZERO;
        for depth in 1..=self.params.max_depth {
            let Some(hit) = scene.intersect(&ray) else {
                l += beta * escaped_radiance(scene, ray.d, |_| 1.0);
                break;
            };
            let wo = -ray.d;
            if let Some(li) = hit.light {
                l += beta * scene.lights[li as usize].emitted(hit.ng, wo, hit.uv);
            }
            if depth == self.params.max_depth {
                break;
            }
            let at = WalkPoint {
                hit: &hit,
                sf: &hit.shading_frame(),
                wo,
            };
            let rules = WalkRules::camera(self.params.rr_depth);
            let Some(bs) = continue_path(scene, &at, &rules, &mut beta, depth, sampler) else {
                break;
            };
            ray = hit.spawn_ray(bs.wi);
        }
        l
    }
}

impl Integrator for PtBsdf {
    fn name(&self) -> &'static str {
        "pt-bsdf"
    }

    fn render_pass(&self, scene: &Scene, seed: u64, pass: u32) -> (Image, u64) {
        if scene.has_media {
            let pt = self.as_bsdf_only_pt();
            return pixel_pass(scene, seed, pass, |s, raster| {
                crate::media::pt::radiance(&pt, scene, raster, s)
            });
        }
        pixel_pass(scene, seed, pass, |s, raster| {
            self.radiance(scene, raster, s)
        })
    }
}

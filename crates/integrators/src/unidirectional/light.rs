//! `light` — light tracing (Veach 1997, §10.2 with t = 1; the seed's "splat to the image at each
//! vertex"): light subpaths are traced in importance mode and every vertex that can be connected —
//! x0 on an emitter included — is joined to the lens (the pinhole, or a sampled point of a thin
//! lens) and splatted through the pixel filter to the pixels around where it lands.
//!
//! One technique only, so no MIS: each splat is β · f · We · cos θ_c / d² over the M light
//! subpaths of the pass. It cannot render what the camera sees through a delta surface (a mirror
//! or glass seen directly, or an emitter behind glass): the connection would end at a delta
//! vertex, whose density of being reached is zero. A point light or a directional light is never
//! seen directly either, by any technique (its x0 is not connectable or emits nothing towards
//! the camera). Tests comparing `light` with other integrators exclude exactly those paths.
//!
//! | key | type | default | meaning |
//! |---|---|---|---|
//! | `max_depth` | u32 | scene `[render] max_depth` (8) | longest path in segments, camera ray included |
//! | `rr_depth` | u32 | scene `[render] rr_depth` (5) | Russian roulette from this many segments on |
//! | `light_paths` | u64 | the pixel count | light subpaths per pass |
//! | `lanes` | 1/8 | 1 | 8: the same image bit for bit, eight subpaths at a time (`light_lanes`; no media) |

pub use super::light_params::LightParams;
use super::light_params::CHUNK;
use crate::film::splat::splat_pass_with;
use crate::subpath::connect::connect_to_camera;
use crate::subpath::walk::{light_subpath, Subpath};
use crate::Integrator;
use lt_core::path::scatter::connectable;
use lt_core::sampling::{Domain, Sampler};
use lt_core::Scene;
use lt_estimators::Image;

pub struct LightTracer {
    pub params: LightParams,
}

impl Integrator for LightTracer {
    fn name(&self) -> &'static str {
        "light"
    }

    fn render_pass(&self, scene: &Scene, seed: u64, pass: u32) -> (Image, u64) {
        let cam = &scene.camera;
        let m = self.params.light_paths.unwrap_or(cam.pixel_count() as u64);
        if self.params.lanes {
            return super::light_lanes::render_pass(&self.params, scene, seed, pass);
        }
        let limits = self.params.walk_limits();
        let scale = 1.0 / m as f32;
        let (w, h) = (cam.width as usize, cam.height as usize);
        if scene.has_media {
            let walk = crate::media::light::LightWalk {
                max_depth: self.params.max_depth,
                rr_depth: self.params.rr_depth,
                scale,
            };
            return splat_pass_with(
                w,
                h,
                m,
                CHUNK,
                || (),
                |i, splats, _| {
                    let mut sampler = Sampler::for_item(Domain::Light, seed, i, pass as u64);
                    crate::media::light::trace(scene, walk, &mut sampler, splats);
                },
            );
        }
        let scratch = || Subpath::with_capacity(limits.max_vertices);
        splat_pass_with(w, h, m, CHUNK, scratch, |i, splats, sub| {
            let mut sampler = Sampler::for_item(Domain::Light, seed, i, pass as u64);
            light_subpath(scene, &mut sampler, limits, sub);
            for y in &sub.vertices {
                if !connectable(scene, y) {
                    continue;
                }
                if let Some(c) = connect_to_camera(scene, y, &mut sampler) {
                    splats.add_filtered(cam.film(), c.raster, c.value * scale);
                }
            }
        })
    }
}

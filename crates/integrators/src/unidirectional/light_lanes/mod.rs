//! `light` with `lanes=8`: the same estimator as `light` (`unidirectional::light`), run eight
//! light subpaths at a time (issue 47, item 3).
//!
//! Each lane is one light subpath drawing from exactly the stream the scalar `light` uses for it
//! (`Sampler::for_item(Domain::Light, seed, item, pass)`), through the scalar functions in the
//! scalar order, so every splat is the scalar splat's bits; the splats are recorded in the scalar
//! order (subpath by subpath, vertex by vertex) into the same chunks of `light::CHUNK` subpaths
//! (`film::splat::splat_pass_with`), so the image is the scalar `light`'s bit for bit at any
//! thread count — which is the whole test (`tests/light_lanes.rs`). The scalar `light` stays the
//! reference.
//!
//! What runs lane-wide and what per lane (`walk.rs`, `connect.rs`):
//! - the closest hits of the eight walks' rays, bounce by bounce: the ray core's packet query
//!   (`Scene::intersect_packet`); a lane whose walk ends takes the chunk's next subpath, so the
//!   packets stay full until the chunk runs out;
//! - the shadow rays of the connections to the lens: the packet occlusion query
//!   (`Scene::resolve_shadow_packet`), eight connections at a time, whichever subpaths they come
//!   from; the visible ones are splatted after the chunk's walks, in the scalar order;
//! - per lane, through the scalar functions: emission sampling, vertex construction, BSDF
//!   sampling and Russian roulette, the lens sample and the BSDF towards it.
//!
//! Participating media are not handled: `lanes=8` on a scene with media is refused in one line
//! (`light::LightParams::read`).

mod connect;
mod walk;

use super::light_params::{LightParams, CHUNK};
use crate::film::splat::splat_pass_with;
use connect::Connections;
use lt_core::Scene;
use lt_estimators::Image;
use walk::WalkLanes;

pub use super::light_params::LANES;

/// `LightTracer::render_pass` for a scene without media, `LANES` subpaths at a time, in the scalar
/// chunks of `CHUNK` subpaths: each chunk records exactly the splats the scalar chunk records, in
/// its order.
pub fn render_pass(params: &LightParams, scene: &Scene, seed: u64, pass: u32) -> (Image, u64) {
    let cam = &scene.camera;
    let m = params.light_paths.unwrap_or(cam.pixel_count() as u64);
    let scale = 1.0 / m as f32;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let limits = params.walk_limits();
    // Four connections per subpath: growing the list from empty in every chunk cost 3 % of the
    // instructions in copies (Cornell box: 2–3 connections per subpath).
    let room = 4 * CHUNK as usize;
    let scratch = || (WalkLanes::new(limits), Connections::with_capacity(room));
    // One work item per scalar chunk.
    splat_pass_with(
        w,
        h,
        m.div_ceil(CHUNK),
        1,
        scratch,
        |c, splats, (lanes, found)| {
            let items = c * CHUNK..((c + 1) * CHUNK).min(m);
            found.clear(items.start, (items.end - items.start) as usize);
            lanes.walk(scene, (seed, pass), items, |item, sub, sampler| {
                found.add_subpath(scene, item, sub, sampler)
            });
            found.splat(scene, scale, splats);
        },
    )
}

//! The walks of a batch of light subpaths, bounce by bounce: `subpath::walk::light_subpath`
//! (`light_start`, then `random_walk` in importance mode) on every lane, the closest hits through
//! the packet query.

use super::LANES;
use crate::subpath::walk::{continue_path, Emission, Subpath, WalkLimits, WalkPoint, WalkRules};
use lt_core::geometry::Ray;
use lt_core::math::{Color, Vec3};
use lt_core::path::PathVertex;
use lt_core::sampling::{Domain, Sampler};
use lt_core::Scene;
use std::ops::Range;

/// A batch's subpaths and each lane's stream, kept across the batches of a chunk (buffers reused).
pub struct Batch {
    limits: WalkLimits,
    /// Subpaths in the batch (≤ `LANES`; fewer in the pass's last batch).
    pub len: usize,
    pub subpaths: [Subpath; LANES],
    pub samplers: [Sampler; LANES],
}

/// The state `random_walk` keeps in locals, per lane.
struct WalkLanes {
    alive: [bool; LANES],
    ray: [Ray; LANES],
    beta: [Color; LANES],
    pdf: [f32; LANES],
    rules: [WalkRules; LANES],
}

impl Batch {
    pub fn new(limits: WalkLimits) -> Batch {
        Batch {
            limits,
            len: 0,
            subpaths: std::array::from_fn(|_| Subpath::with_capacity(limits.max_vertices)),
            samplers: std::array::from_fn(|_| Sampler::for_item(Domain::Light, 0, 0, 0)),
        }
    }

    /// Traces the light subpaths `items` of pass `pass` of the run seeded by `seed`, as
    /// `light_subpath` traces each.
    pub fn walk(&mut self, scene: &Scene, (seed, pass): (u64, u32), items: Range<u64>) {
        self.len = items.clone().count();
        let mut lanes = WalkLanes {
            alive: [false; LANES],
            ray: [Ray::new(Vec3::ZERO, Vec3::Z); LANES], // idle lanes' rays are never traced
            beta: [Color::ZERO; LANES],
            pdf: [0.0; LANES],
            rules: [WalkRules::camera(0); LANES],
        };
        for (i, item) in items.enumerate() {
            self.samplers[i] = Sampler::for_item(Domain::Light, seed, item, pass as u64);
            self.start(scene, i, &mut lanes);
        }
        while lanes.alive.iter().any(|&a| a) {
            let hits = scene.intersect_packet(&lanes.ray, &lanes.alive);
            for (i, hit) in hits.iter().enumerate() {
                if lanes.alive[i] {
                    lanes.alive[i] = self.step(scene, i, hit.as_ref(), &mut lanes);
                }
            }
        }
    }

    /// `light_start` on lane `i`: y0 on a light, and the emitted ray (the lane stays idle when
    /// nothing is emitted or the limits allow y0 alone).
    fn start(&mut self, scene: &Scene, i: usize, lanes: &mut WalkLanes) {
        let (out, sampler) = (&mut self.subpaths[i], &mut self.samplers[i]);
        out.vertices.clear();
        out.escape = None;
        let Some(e) = Emission::sample(scene, sampler) else {
            return;
        };
        out.vertices.push(PathVertex::light_emitted(
            scene,
            e.light as u32,
            &e.le,
            e.pmf,
        ));
        if self.limits.max_vertices < 2 {
            return;
        }
        let start = e.walk_start(scene);
        lanes.rules[i] = start.rules(self.limits.rr_depth);
        lanes.alive[i] = true;
        lanes.ray[i] = start.ray;
        lanes.beta[i] = start.beta;
        lanes.pdf[i] = start.pdf;
    }

    /// One turn of `random_walk`'s loop on lane `i`, whose ray's closest hit is `hit`; false when
    /// the walk ends. (A light walk records no escape: that is for radiance-mode walks.)
    fn step(
        &mut self,
        scene: &Scene,
        i: usize,
        hit: Option<&lt_core::scene::SurfaceHit>,
        lanes: &mut WalkLanes,
    ) -> bool {
        let Some(hit) = hit else {
            return false;
        };
        let out = &mut self.subpaths[i];
        let wo = -lanes.ray[i].d;
        let n = out.vertices.len();
        let prev = out.vertices.last().expect("the endpoint is pushed first");
        let v = PathVertex::surface(hit, wo, lanes.beta[i], lanes.pdf[i], prev);
        out.vertices.push(v);
        if n + 1 >= self.limits.max_vertices {
            return false;
        }
        // `continue_subpath` without its `pdf_rev` of the vertex before, which only MIS reads
        // (light tracing has one technique).
        let sf = hit.shading_frame();
        let at = WalkPoint { hit, sf: &sf, wo };
        let sampler = &mut self.samplers[i];
        let depth = n as u32;
        let Some(bs) = continue_path(
            scene,
            &at,
            &lanes.rules[i],
            &mut lanes.beta[i],
            depth,
            sampler,
        ) else {
            return false;
        };
        out.vertices[n].delta = bs.delta;
        lanes.pdf[i] = bs.pdf_w;
        lanes.ray[i] = hit.spawn_ray(bs.wi);
        true
    }
}

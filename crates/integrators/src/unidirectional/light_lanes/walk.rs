//! The walks of a chunk's light subpaths, `LANES` at a time and bounce by bounce:
//! `subpath::walk::light_subpath` (`light_start`, then `random_walk` in importance mode) on every
//! lane, the closest hits through the packet query. A lane whose walk ends hands its subpath to
//! the caller and takes the chunk's next subpath before the next bounce, so packets stay full
//! until the chunk runs out.

use super::LANES;
use crate::subpath::walk::{continue_path, Emission, Subpath, WalkLimits, WalkPoint, WalkRules};
use lt_core::geometry::Ray;
use lt_core::math::{Color, Vec3};
use lt_core::path::PathVertex;
use lt_core::sampling::{Domain, Sampler};
use lt_core::scene::SurfaceHit;
use lt_core::Scene;
use std::ops::Range;

/// The state `random_walk` keeps in locals, per lane, with each lane's subpath and stream
/// (buffers reused across the chunks a thread renders).
pub struct WalkLanes {
    limits: WalkLimits,
    alive: [bool; LANES],
    /// Each lane's subpath, as its index in the pass.
    item: [u64; LANES],
    subpaths: [Subpath; LANES],
    samplers: [Sampler; LANES],
    ray: [Ray; LANES],
    beta: [Color; LANES],
    pdf: [f32; LANES],
    rules: [WalkRules; LANES],
}

impl WalkLanes {
    pub fn new(limits: WalkLimits) -> WalkLanes {
        WalkLanes {
            limits,
            alive: [false; LANES],
            item: [0; LANES],
            subpaths: std::array::from_fn(|_| Subpath::with_capacity(limits.max_vertices)),
            samplers: std::array::from_fn(|_| Sampler::for_item(Domain::Light, 0, 0, 0)),
            ray: [Ray::new(Vec3::ZERO, Vec3::Z); LANES], // idle lanes' rays are never traced
            beta: [Color::ZERO; LANES],
            pdf: [0.0; LANES],
            rules: [WalkRules::camera(0); LANES],
        }
    }

    /// Traces the light subpaths `items` of pass `pass` of the run seeded by `seed`, each as
    /// `light_subpath` traces it, and calls `done(item, subpath, its stream)` once per subpath
    /// when its walk has ended (in the order walks end, not item order).
    pub fn walk(
        &mut self,
        scene: &Scene,
        (seed, pass): (u64, u32),
        items: Range<u64>,
        mut done: impl FnMut(u64, &Subpath, &mut Sampler),
    ) {
        let mut next = items.start;
        loop {
            for i in 0..LANES {
                while !self.alive[i] && next < items.end {
                    self.item[i] = next;
                    self.samplers[i] = Sampler::for_item(Domain::Light, seed, next, pass as u64);
                    next += 1;
                    self.start(scene, i);
                    if !self.alive[i] {
                        done(self.item[i], &self.subpaths[i], &mut self.samplers[i]);
                    }
                }
            }
            if !self.alive.iter().any(|&a| a) {
                return;
            }
            let hits = scene.intersect_packet(&self.ray, &self.alive);
            for (i, hit) in hits.iter().enumerate() {
                if self.alive[i] {
                    self.alive[i] = self.step(scene, i, hit.as_ref());
                    if !self.alive[i] {
                        done(self.item[i], &self.subpaths[i], &mut self.samplers[i]);
                    }
                }
            }
        }
    }

    /// `light_start` on lane `i`: y0 on a light, and the emitted ray (the lane stays idle when
    /// nothing is emitted or the limits allow y0 alone).
    fn start(&mut self, scene: &Scene, i: usize) {
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
        self.rules[i] = start.rules(self.limits.rr_depth);
        self.alive[i] = true;
        self.ray[i] = start.ray;
        self.beta[i] = start.beta;
        self.pdf[i] = start.pdf;
    }

    /// One turn of `random_walk`'s loop on lane `i`, whose ray's closest hit is `hit`; false when
    /// the walk ends. (A light walk records no escape: that is for radiance-mode walks.)
    fn step(&mut self, scene: &Scene, i: usize, hit: Option<&SurfaceHit>) -> bool {
        let Some(hit) = hit else {
            return false;
        };
        let out = &mut self.subpaths[i];
        let wo = -self.ray[i].d;
        let n = out.vertices.len();
        let prev = out.vertices.last().expect("the endpoint is pushed first");
        let v = PathVertex::surface(hit, wo, self.beta[i], self.pdf[i], prev);
        out.vertices.push(v);
        if n + 1 >= self.limits.max_vertices {
            return false;
        }
        // `continue_subpath` without its `pdf_rev` of the vertex before, which only MIS reads
        // (light tracing has one technique).
        let sf = hit.shading_frame();
        let at = WalkPoint { hit, sf: &sf, wo };
        let (rules, sampler) = (&self.rules[i], &mut self.samplers[i]);
        let Some(bs) = continue_path(scene, &at, rules, &mut self.beta[i], n as u32, sampler)
        else {
            return false;
        };
        out.vertices[n].delta = bs.delta;
        self.pdf[i] = bs.pdf_w;
        self.ray[i] = hit.spawn_ray(bs.wi);
        true
    }
}

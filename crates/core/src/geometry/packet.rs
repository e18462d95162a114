//! Packet queries: the closest hits, or the occlusion, of `PACKET` rays at once (the rays of one
//! bounce, or the shadow rays, of the lane-parallel `pt` and `light`, issue 47 item 3).
//!
//! The flat core (`flat.rs`) vectorises one ray over many parallelograms; here the axes swap:
//! each parallelogram is loaded once and tested against the packet's rays in one loop the
//! compiler vectorises across rays, and each ray keeps its nearest (distance, index) pair in its
//! own lane, so no lane-to-scalar reduction runs per group (the single-ray loop's `take_hits`).
//! A Cornell box's 18 parallelograms cost 18 packet tests per 8 rays instead of 3 chunk tests and
//! a reduction per ray. Spheres and the one-by-one primitives (triangles, disks, cylinders) are
//! tested per ray as `Flat::closest` tests them.
//!
//! Bits: each lane runs `quad::distance`, the scalar test's operations in the scalar order, on
//! its own ray, and the nearest hit is the smallest (distance, index) pair — a total order, so
//! the order the candidates arrive in cannot change it. Every ray's hit is therefore
//! `Flat::closest`'s (held to it by `accel`'s test `packet_query_is_the_single_ray_query_bit_for_bit`).
//! Other cores answer a packet one ray at a time (`Accel::intersect_packet`).
//!
//! Occlusion (`Flat::occluded_packet`) runs the same loop with a blocked flag per lane in place of
//! the nearest pair, and stops once every active lane is blocked. Whether a ray is blocked is
//! whether any primitive's distance is finite — an "or" over the same per-primitive tests
//! `Flat::occluded` runs, which no order of evaluation can change.

use super::flat::{blocks, nearer, take_hits, Flat, Isa, NONE};
use super::primitive::{PrimHit, Primitive};
use super::ray::Ray;
use super::soa::CHUNK;
use super::triangle::ShearedRay;
use crate::math::Vec3;

/// Rays per packet (eight f32 lanes: one AVX2 register).
pub const PACKET: usize = 8;

impl Flat {
    /// Per ray of `rays` whose `active` flag is set, `Flat::closest`'s answer; `None` on the
    /// others. `sheared[i]` is ray i's triangle setup (as the single-ray query takes it).
    pub fn closest_packet(
        &self,
        prims: &[Primitive],
        rays: &[Ray; PACKET],
        sheared: &[ShearedRay; PACKET],
        active: &[bool; PACKET],
    ) -> [Option<PrimHit>; PACKET] {
        // SAFETY: `isa` is only ever a set this CPU runs (`Isa::detect`/`Isa::available`); AVX-512
        // implies AVX2.
        let best = match self.isa {
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 | Isa::Avx512 => unsafe { self.packet_avx2(prims, rays, sheared, active) },
            _ => self.packet_in::<4>(prims, rays, sheared, active),
        };
        std::array::from_fn(|i| (active[i] && best[i].t.is_finite()).then_some(best[i]))
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn packet_avx2(
        &self,
        prims: &[Primitive],
        rays: &[Ray; PACKET],
        sheared: &[ShearedRay; PACKET],
        active: &[bool; PACKET],
    ) -> [PrimHit; PACKET] {
        self.packet_in::<8>(prims, rays, sheared, active)
    }

    /// Parallelograms across the packet; spheres `W` at a time and the rest one by one, per ray.
    #[inline(always)]
    fn packet_in<const W: usize>(
        &self,
        prims: &[Primitive],
        rays: &[Ray; PACKET],
        sheared: &[ShearedRay; PACKET],
        active: &[bool; PACKET],
    ) -> [PrimHit; PACKET] {
        // The rays component by component, so the loop below reads whole lanes.
        let lane = |f: fn(&Ray) -> f32| -> [f32; PACKET] { std::array::from_fn(|i| f(&rays[i])) };
        let (ox, oy, oz) = (lane(|r| r.o.x), lane(|r| r.o.y), lane(|r| r.o.z));
        let (dx, dy, dz) = (lane(|r| r.d.x), lane(|r| r.d.y), lane(|r| r.d.z));
        let t_max = lane(|r| r.t_max);
        let mut best_t = [f32::INFINITY; PACKET];
        let mut best_prim = [u32::MAX; PACKET];
        for (j, &id) in self.quad_ids.iter().enumerate() {
            if id == u32::MAX {
                break; // padding, which only ends the list
            }
            let (f, l) = (&self.quads.chunks[j / CHUNK], j % CHUNK);
            let v = |k: usize| Vec3::new(f[k][l], f[k + 1][l], f[k + 2][l]);
            let q = [v(0), v(3), v(6), v(9), v(12), v(15), v(18), v(21)];
            for i in 0..PACKET {
                let o = Vec3::new(ox[i], oy[i], oz[i]);
                let d = Vec3::new(dx[i], dy[i], dz[i]);
                let t = super::quad::distance(q, o, o.abs(), d, t_max[i]);
                // `nearer`, as a select per lane.
                let take = (t < best_t[i]) | ((t == best_t[i]) & (id < best_prim[i]));
                best_t[i] = if take { t } else { best_t[i] };
                best_prim[i] = if take { id } else { best_prim[i] };
            }
        }
        std::array::from_fn(|i| {
            let mut best = PrimHit {
                t: best_t[i],
                prim: best_prim[i],
            };
            if !active[i] {
                return NONE;
            }
            let (o, d, t_max) = (rays[i].o, rays[i].d, rays[i].t_max);
            for (g, ids) in self.sphere_ids.chunks_exact(W).enumerate() {
                if ids[0] != u32::MAX {
                    let ts = self.spheres.distances::<W>(g * W, o, d, t_max);
                    take_hits(&mut best, &ts, ids);
                }
            }
            for &p in &self.triangles {
                let t = prims[p as usize].intersect(&sheared[i], o, d, t_max);
                best = nearer(best, t, p);
            }
            best
        })
    }

    /// Per ray of `rays` whose `active` flag is set, `Flat::occluded`'s answer; false on the
    /// others.
    pub fn occluded_packet(
        &self,
        prims: &[Primitive],
        rays: &[Ray; PACKET],
        sheared: &[ShearedRay; PACKET],
        active: &[bool; PACKET],
    ) -> [bool; PACKET] {
        // SAFETY: as in `closest_packet`.
        match self.isa {
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 | Isa::Avx512 => unsafe {
                self.occluded_packet_avx2(prims, rays, sheared, active)
            },
            _ => self.occluded_packet_in::<4>(prims, rays, sheared, active),
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn occluded_packet_avx2(
        &self,
        prims: &[Primitive],
        rays: &[Ray; PACKET],
        sheared: &[ShearedRay; PACKET],
        active: &[bool; PACKET],
    ) -> [bool; PACKET] {
        self.occluded_packet_in::<8>(prims, rays, sheared, active)
    }

    /// Parallelograms across the packet until every active lane is blocked; then, per lane still
    /// open, spheres `W` at a time and the rest one by one (`Flat::occluded_in`'s order per ray).
    #[inline(always)]
    fn occluded_packet_in<const W: usize>(
        &self,
        prims: &[Primitive],
        rays: &[Ray; PACKET],
        sheared: &[ShearedRay; PACKET],
        active: &[bool; PACKET],
    ) -> [bool; PACKET] {
        let lane = |f: fn(&Ray) -> f32| -> [f32; PACKET] { std::array::from_fn(|i| f(&rays[i])) };
        let (ox, oy, oz) = (lane(|r| r.o.x), lane(|r| r.o.y), lane(|r| r.o.z));
        let (dx, dy, dz) = (lane(|r| r.d.x), lane(|r| r.d.y), lane(|r| r.d.z));
        let t_max = lane(|r| r.t_max);
        // Inactive lanes start "blocked", so they never hold the loop open; they answer false.
        let mut done = active.map(|a| !a);
        for (j, &id) in self.quad_ids.iter().enumerate() {
            // Padding only ends the list; whether anything is left to decide is asked once per
            // `CHUNK` parallelograms (asked per parallelogram it cost more than it saved).
            if id == u32::MAX || (j % CHUNK == 0 && done.iter().all(|&b| b)) {
                break;
            }
            let (f, l) = (&self.quads.chunks[j / CHUNK], j % CHUNK);
            let v = |k: usize| Vec3::new(f[k][l], f[k + 1][l], f[k + 2][l]);
            let q = [v(0), v(3), v(6), v(9), v(12), v(15), v(18), v(21)];
            for i in 0..PACKET {
                let o = Vec3::new(ox[i], oy[i], oz[i]);
                let d = Vec3::new(dx[i], dy[i], dz[i]);
                let t = super::quad::distance(q, o, o.abs(), d, t_max[i]);
                done[i] |= t < f32::INFINITY;
            }
        }
        std::array::from_fn(|i| {
            if !active[i] {
                return false;
            }
            if done[i] {
                return true;
            }
            let (o, d, t_max) = (rays[i].o, rays[i].d, rays[i].t_max);
            for (g, ids) in self.sphere_ids.chunks_exact(W).enumerate() {
                if ids[0] != u32::MAX && blocks(&self.spheres.distances::<W>(g * W, o, d, t_max)) {
                    return true;
                }
            }
            self.triangles.iter().any(|&p| {
                prims[p as usize]
                    .intersect(&sheared[i], o, d, t_max)
                    .is_finite()
            })
        })
    }
}

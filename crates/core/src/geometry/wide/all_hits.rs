//! The wide BVH's every-hit query (`segment_hits.rs`): the closest-hit walk without its
//! pruning, every child box the ray meets within (0, t_max) opened in any order.

use super::{pack_distances, Entry, Slabs, WideBvh, LEAF, STACK};
use crate::geometry::primitive::{PrimHit, Primitive};
use crate::geometry::ray::Ray;
use crate::geometry::triangle::ShearedRay;
use crate::geometry::triangle_pack::PACK;
use std::mem::MaybeUninit;

impl WideBvh {
    /// Appends every (t, primitive) hit within (0, t_max) to `out`, unordered.
    pub fn all_hits(
        &self,
        prims: &[Primitive],
        ray: &Ray,
        sheared: &ShearedRay,
        out: &mut Vec<PrimHit>,
    ) {
        if self.stack_need <= STACK {
            let mut stack = [const { MaybeUninit::uninit() }; STACK];
            self.all_hits_dispatch(prims, ray, sheared, &mut stack, out)
        } else {
            let mut stack = vec![MaybeUninit::uninit(); self.stack_need];
            self.all_hits_dispatch(prims, ray, sheared, &mut stack, out)
        }
    }

    #[inline(always)]
    fn all_hits_dispatch(
        &self,
        prims: &[Primitive],
        ray: &Ray,
        s: &ShearedRay,
        stack: &mut [Entry],
        out: &mut Vec<PrimHit>,
    ) {
        // SAFETY: `isa` is only ever a set this CPU runs (`Isa::detect`/`Isa::available`).
        match self.isa {
            #[cfg(target_arch = "x86_64")]
            super::Isa::Avx2 | super::Isa::Avx512 => unsafe {
                self.all_hits_avx2(prims, ray, s, stack, out)
            },
            _ => self.all_hits_in::<false>(prims, ray, s, stack, out),
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn all_hits_avx2(
        &self,
        prims: &[Primitive],
        ray: &Ray,
        s: &ShearedRay,
        stack: &mut [Entry],
        out: &mut Vec<PrimHit>,
    ) {
        self.all_hits_in::<true>(prims, ray, s, stack, out)
    }

    #[inline(always)]
    fn all_hits_in<const AVX2: bool>(
        &self,
        prims: &[Primitive],
        ray: &Ray,
        sheared: &ShearedRay,
        stack: &mut [Entry],
        out: &mut Vec<PrimHit>,
    ) {
        let slabs = Slabs::new(ray, self.magnitude);
        let t_max = ray.t_max;
        let mut sp = 0;
        let mut node = 0usize;
        loop {
            let n = &self.nodes[node];
            let (_, mut mask) = slabs.test::<AVX2>(n, t_max);
            // At most 8 pushed per node popped: the `stack_need` bound of the closest-hit walk.
            while mask != 0 {
                let i = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                stack[sp] = MaybeUninit::new((n.child[i], 0.0));
                sp += 1;
            }
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                // SAFETY: entries below `sp` were written above.
                let (child, _) = unsafe { stack[sp].assume_init() };
                if child & LEAF == 0 {
                    node = child as usize;
                    break;
                }
                let leaf = &self.leaves[(child & !LEAF) as usize];
                for p in leaf.packs.clone() {
                    let ts = pack_distances::<AVX2>(&self.packs[p as usize], sheared, t_max);
                    let ids = &self.pack_ids[p as usize];
                    for lane in 0..PACK {
                        if ts[lane] < f32::INFINITY {
                            out.push(PrimHit {
                                t: ts[lane],
                                prim: ids[lane],
                            });
                        }
                    }
                }
                for &i in &self.others[leaf.others.start as usize..leaf.others.end as usize] {
                    let t = prims[i as usize].intersect(sheared, ray.o, ray.d, t_max);
                    if t.is_finite() {
                        out.push(PrimHit { t, prim: i });
                    }
                }
            }
        }
    }
}

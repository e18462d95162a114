//! One obvhs compressed-wide BVH over every primitive in the scene: triangles, parallelograms and
//! analytic spheres live in the same tree, so a scene pays only for the kinds it has.

use super::quad::Parallelogram;
use super::ray::Ray;
use super::sphere::intersect_sphere;
use super::triangle::{intersect_triangle, ShearedRay};
use crate::math::Vec3;
use glam::{UVec2, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::cwbvh::builder::build_cwbvh;
use obvhs::cwbvh::CwBvh;
use obvhs::faststack::StackStack;
use obvhs::{Boundable, BvhBuildParams};

/// A primitive in the BVH. `shape` indexes the scene's shapes; `index` is the triangle within its mesh.
#[derive(Clone, Copy, Debug)]
pub enum Primitive {
    Triangle {
        p: [Vec3; 3],
        shape: u32,
        index: u32,
    },
    /// Triangles `index` and `index + 1` of a mesh that form a parallelogram.
    Quad {
        q: Parallelogram,
        shape: u32,
        index: u32,
    },
    Sphere {
        center: Vec3,
        radius: f32,
        shape: u32,
    },
}

impl Primitive {
    pub fn shape(&self) -> u32 {
        match *self {
            Primitive::Triangle { shape, .. }
            | Primitive::Quad { shape, .. }
            | Primitive::Sphere { shape, .. } => shape,
        }
    }

    /// Hit distance in (0, t_max) from the ray's true origin, or +∞. Always inlined into the
    /// traversal loops: as a call it costs a few per cent of a path tracer's time.
    #[inline(always)]
    pub fn intersect(&self, r: &ShearedRay, o: Vec3, d: Vec3, t_max: f32) -> f32 {
        match self {
            Primitive::Triangle { p, .. } => intersect_triangle(r, t_max, p).0,
            Primitive::Quad { q, .. } => q.intersect(o, d, t_max).0,
            &Primitive::Sphere { center, radius, .. } => {
                intersect_sphere(o, d, t_max, center, radius)
            }
        }
    }
}

impl Boundable for Primitive {
    fn aabb(&self) -> Aabb {
        match *self {
            Primitive::Triangle { p, .. } => {
                let [a, b, c] = p.map(Vec3A::from);
                Aabb::new(a.min(b).min(c), a.max(b).max(c))
            }
            Primitive::Quad { q, .. } => {
                let c = [q.p0, q.p0 + q.e1, q.p0 + q.e2, q.p0 + q.e1 + q.e2].map(Vec3A::from);
                Aabb::new(
                    c[0].min(c[1]).min(c[2]).min(c[3]),
                    c[0].max(c[1]).max(c[2]).max(c[3]),
                )
            }
            Primitive::Sphere { center, radius, .. } => {
                let c = Vec3A::from(center);
                Aabb::new(c - radius, c + radius)
            }
        }
    }
}

/// The closest hit of a ray: its distance and the primitive's index in `Accel::primitive`.
#[derive(Clone, Copy, Debug)]
pub struct PrimHit {
    pub t: f32,
    pub prim: u32,
}

pub struct Accel {
    bvh: CwBvh,
    /// Primitives in BVH order, so traversal ids index this directly.
    prims: Vec<Primitive>,
    bounds: (Vec3, Vec3),
    /// Whether any primitive is a triangle: only triangles need the per-ray shear.
    has_triangles: bool,
    /// Whether the tree is shallow enough for the small traversal stack (`SMALL_STACK`).
    shallow: bool,
}

/// obvhs's own traversal state zeroes a 32-entry stack (256 bytes, a `memset` call) for every ray,
/// which costs about as much as traversing a tree of a few nodes. Scenes whose tree is at most
/// `SMALL_STACK - 2` levels deep (every Cornell-box variant) traverse with an 8-entry stack
/// instead; deeper trees keep obvhs's 32. The traversal itself is obvhs's `traverse!` macro, so
/// the nodes and primitives visited, their order and every result are the same either way.
const SMALL_STACK: usize = 8;
const FULL_STACK: usize = 32;

/// The fields obvhs's `traverse!` macro reads and writes, with a stack of `N` entries (it holds
/// `N − 1`: a push onto a full `StackStack` overwrites its last entry).
struct Traversal<const N: usize> {
    stack: StackStack<UVec2, N>,
    current_group: UVec2,
    primitive_group: UVec2,
    oct_inv4: u32,
    primitive_id: u32,
    hitmask: u32,
}

impl<const N: usize> Traversal<N> {
    /// Starts at the root (a tree with nodes), children visited in the order `d`'s octant gives.
    #[inline(always)]
    fn new(d: Vec3) -> Self {
        // The octant code obvhs's node test expects: per axis, one bit in every byte when that
        // component is non-negative (x 4, y 2, z 1).
        let bit = |c: f32, b: u32| if c < 0.0 { 0 } else { b * 0x0101_0101 };
        Traversal {
            stack: StackStack::default(),
            current_group: UVec2::new(0, 0x8000_0000),
            primitive_group: UVec2::ZERO,
            oct_inv4: bit(d.x, 4) | bit(d.y, 2) | bit(d.z, 1),
            primitive_id: 0,
            hitmask: 0,
        }
    }
}

/// Levels of inner nodes below and including `node` (a leaf-only node counts 1). The inner
/// children of a node are stored contiguously from `child_base_idx`, one per set `imask` bit.
fn tree_depth(bvh: &CwBvh, node: usize) -> usize {
    let n = &bvh.nodes[node];
    let base = n.child_base_idx as usize;
    1 + (0..n.imask.count_ones() as usize)
        .map(|k| tree_depth(bvh, base + k))
        .max()
        .unwrap_or(0)
}

impl Accel {
    pub fn build(prims: Vec<Primitive>) -> Accel {
        if prims.is_empty() {
            return Accel {
                bvh: CwBvh::default(),
                prims,
                bounds: (Vec3::ZERO, Vec3::ZERO),
                has_triangles: false,
                shallow: true,
            };
        }
        let mut build_time = Default::default();
        let bvh = build_cwbvh(&prims, BvhBuildParams::medium_build(), &mut build_time);
        let ordered: Vec<Primitive> = bvh
            .primitive_indices
            .iter()
            .map(|&i| prims[i as usize])
            .collect();
        let total = prims
            .iter()
            .fold(Aabb::empty(), |acc, p| acc.union(&p.aabb()));
        let has_triangles = prims
            .iter()
            .any(|p| matches!(p, Primitive::Triangle { .. }));
        let shallow = bvh.nodes.is_empty() || tree_depth(&bvh, 0) + 2 <= SMALL_STACK;
        Accel {
            has_triangles,
            shallow,
            bvh,
            prims: ordered,
            bounds: (total.min.into(), total.max.into()),
        }
    }

    /// The triangle test's per-ray setup, skipped (never read) in scenes without triangles.
    #[inline]
    fn sheared(&self, o: Vec3, d: Vec3) -> ShearedRay {
        if self.has_triangles {
            ShearedRay::new(o, d)
        } else {
            ShearedRay::UNUSED
        }
    }

    #[inline]
    pub fn primitive(&self, i: u32) -> &Primitive {
        &self.prims[i as usize]
    }

    pub fn primitive_count(&self) -> usize {
        self.prims.len()
    }

    /// Axis-aligned bounds of all primitives (min, max).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }

    /// obvhs's wide-node test clamps the entry distance to an absolute 1e-4 (`cwbvh::node::EPSILON`),
    /// which would cull every box closer than 1e-4 scene units — at millimetre scale, whole walls.
    /// Traversal therefore starts `TRAVERSAL_BACKOFF` behind the real origin, so every true hit is
    /// at least that far along the traversal ray; primitive tests subtract it again.
    #[inline]
    fn obvhs_ray(ray: &Ray) -> obvhs::ray::Ray {
        let o = ray.o - ray.d * TRAVERSAL_BACKOFF;
        obvhs::ray::Ray::new(o.into(), ray.d.into(), 0.0, ray.t_max + TRAVERSAL_BACKOFF)
    }

    /// Closest hit along the ray within (0, t_max).
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        if self.prims.is_empty() {
            return None;
        }
        if self.shallow {
            self.closest::<SMALL_STACK>(ray)
        } else {
            self.closest::<FULL_STACK>(ray)
        }
    }

    /// `intersect` with a traversal stack of `N` entries: obvhs's `ray_traverse`, on our state.
    #[inline(always)]
    fn closest<const N: usize>(&self, ray: &Ray) -> Option<PrimHit> {
        let prims = &self.prims;
        let (o, d) = (ray.o, ray.d);
        let sheared = self.sheared(o, d);
        let mut traverse_ray = Self::obvhs_ray(ray);
        let t_limit = traverse_ray.tmax;
        let mut best = PrimHit {
            t: f32::INFINITY,
            prim: u32::MAX,
        };
        let mut state = Traversal::<N>::new(d);
        let mut node;
        obvhs::traverse!(
            self.bvh,
            node,
            state,
            node.intersect_ray(&traverse_ray, state.oct_inv4),
            {
                let id = state.primitive_id;
                // Tested from the real origin; the result is reported in traversal-ray distance.
                let t = prims[id as usize].intersect(
                    &sheared,
                    o,
                    d,
                    traverse_ray.tmax - TRAVERSAL_BACKOFF,
                ) + TRAVERSAL_BACKOFF;
                if t < traverse_ray.tmax {
                    best = PrimHit { t, prim: id };
                    traverse_ray.tmax = t;
                }
            }
        );
        (best.t < t_limit).then_some(PrimHit {
            t: best.t - TRAVERSAL_BACKOFF,
            prim: best.prim,
        })
    }

    /// True when anything blocks the ray within (0, t_max). Stops at the first blocker.
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        if self.prims.is_empty() {
            return false;
        }
        if self.shallow {
            self.any_hit::<SMALL_STACK>(ray)
        } else {
            self.any_hit::<FULL_STACK>(ray)
        }
    }

    /// `occluded` with a traversal stack of `N` entries: obvhs's `ray_traverse_miss`, negated.
    #[inline(always)]
    fn any_hit<const N: usize>(&self, ray: &Ray) -> bool {
        let prims = &self.prims;
        let (o, d, t_max) = (ray.o, ray.d, ray.t_max);
        let sheared = self.sheared(o, d);
        let traverse_ray = Self::obvhs_ray(ray);
        let mut state = Traversal::<N>::new(d);
        let mut node;
        let mut hit = false;
        'outer: {
            obvhs::traverse!(
                self.bvh,
                node,
                state,
                node.intersect_ray(&traverse_ray, state.oct_inv4),
                {
                    let t = prims[state.primitive_id as usize].intersect(&sheared, o, d, t_max)
                        + TRAVERSAL_BACKOFF;
                    if t < traverse_ray.tmax {
                        hit = true;
                        break 'outer;
                    }
                }
            );
        }
        hit
    }
}

/// How far behind its origin a ray's BVH traversal starts (see `Accel::obvhs_ray`): twice obvhs's
/// clamp. Only box tests see it; primitives are always intersected from the true origin.
const TRAVERSAL_BACKOFF: f32 = 2e-4;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{sample_uniform_sphere, Sampler};

    fn brute_force(prims: &[Primitive], ray: &Ray) -> f32 {
        let r = ShearedRay::new(ray.o, ray.d);
        prims
            .iter()
            .map(|p| p.intersect(&r, ray.o, ray.d, ray.t_max))
            .fold(f32::INFINITY, f32::min)
    }

    /// Random triangles and spheres at scale `scale`; rays from random points and from points on
    /// the primitives (the short hits near edges and corners that a fixed epsilon would lose).
    fn agrees_with_brute_force_at(scale: f32) {
        let mut s = Sampler::new(1, scale.to_bits() as u64, 0);
        let mut prims = Vec::new();
        for i in 0..200u32 {
            let c = (s.next_2d().extend(s.next_f32()) - 0.5) * 10.0 * scale;
            if i % 3 == 0 {
                prims.push(Primitive::Sphere {
                    center: c,
                    radius: (0.3 * s.next_f32() + 0.01) * scale,
                    shape: i,
                });
            } else {
                let e1 = sample_uniform_sphere(s.next_2d()) * scale;
                let e2 = sample_uniform_sphere(s.next_2d()) * scale;
                if i % 3 == 1 {
                    prims.push(Primitive::Triangle {
                        p: [c, c + e1, c + e2],
                        shape: i,
                        index: 0,
                    });
                } else {
                    let q = crate::geometry::quad::Parallelogram::new(c, e1, e2);
                    prims.push(Primitive::Quad {
                        q,
                        shape: i,
                        index: 0,
                    });
                }
            }
        }
        let accel = Accel::build(prims.clone());
        for k in 0..4000 {
            let o = if k % 2 == 0 {
                (s.next_2d().extend(s.next_f32()) - 0.5) * 12.0 * scale
            } else {
                match prims[k % prims.len()] {
                    Primitive::Triangle { p, .. } => 0.4 * p[0] + 0.3 * p[1] + 0.3 * p[2],
                    Primitive::Quad { q, .. } => q.p0 + 0.3 * q.e1 + 0.6 * q.e2,
                    Primitive::Sphere { center, radius, .. } => center + Vec3::X * radius * 1.001,
                }
            };
            let mut ray = Ray::new(o, sample_uniform_sphere(s.next_2d()));
            if s.next_f32() < 0.3 {
                ray.t_max = 3.0 * scale;
            }
            let expected = brute_force(&prims, &ray);
            match accel.intersect(&ray) {
                Some(h) => {
                    // Adding and removing the traversal back-off rounds t by at most an ulp each way.
                    let tol = 2.0 * f32::EPSILON * (expected + TRAVERSAL_BACKOFF);
                    assert!(
                        (h.t - expected).abs() <= tol,
                        "scale {scale}: {} vs {expected}",
                        h.t
                    );
                    let p = accel.primitive(h.prim);
                    assert_eq!(
                        p.intersect(&ShearedRay::new(ray.o, ray.d), ray.o, ray.d, ray.t_max),
                        expected
                    );
                }
                None => assert!(
                    expected.is_infinite(),
                    "scale {scale}: BVH missed a hit at {expected}"
                ),
            }
            assert_eq!(accel.occluded(&ray), expected.is_finite());
        }
    }

    /// The small traversal stack and obvhs's full-size one visit the same nodes in the same
    /// order, so closest hits and occlusion agree bit for bit.
    #[test]
    fn small_and_full_traversal_stacks_agree() {
        let mut s = Sampler::new(2, 0, 0);
        let prims: Vec<Primitive> = (0..300u32)
            .map(|i| {
                let c = (s.next_2d().extend(s.next_f32()) - 0.5) * 10.0;
                let e1 = sample_uniform_sphere(s.next_2d());
                let e2 = sample_uniform_sphere(s.next_2d());
                Primitive::Quad {
                    q: crate::geometry::quad::Parallelogram::new(c, e1, e2),
                    shape: i,
                    index: 0,
                }
            })
            .collect();
        let accel = Accel::build(prims);
        assert!(accel.shallow, "depth {}", tree_depth(&accel.bvh, 0));
        for _ in 0..4000 {
            let o = (s.next_2d().extend(s.next_f32()) - 0.5) * 12.0;
            let mut ray = Ray::new(o, sample_uniform_sphere(s.next_2d()));
            if s.next_f32() < 0.5 {
                ray.t_max = 4.0 * s.next_f32();
            }
            let (a, b) = (
                accel.closest::<SMALL_STACK>(&ray),
                accel.closest::<FULL_STACK>(&ray),
            );
            assert_eq!(
                a.map(|h| (h.t.to_bits(), h.prim)),
                b.map(|h| (h.t.to_bits(), h.prim))
            );
            assert_eq!(
                accel.any_hit::<SMALL_STACK>(&ray),
                accel.any_hit::<FULL_STACK>(&ray)
            );
        }
    }

    #[test]
    fn bvh_agrees_with_brute_force_at_every_scale() {
        for scale in [1e-3, 1.0, 1e6] {
            agrees_with_brute_force_at(scale);
        }
    }
}

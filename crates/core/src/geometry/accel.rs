//! One obvhs compressed-wide BVH over every primitive in the scene: triangles and analytic spheres
//! live in the same tree, so a scene without spheres pays nothing for them and vice versa.

use super::ray::Ray;
use super::sphere::intersect_sphere;
use super::triangle::intersect_triangle;
use crate::math::Vec3;
use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::cwbvh::builder::build_cwbvh;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::RayHit;
use obvhs::{Boundable, BvhBuildParams};

/// A primitive in the BVH. `shape` indexes the scene's shapes; `index` is the triangle within its mesh.
#[derive(Clone, Copy, Debug)]
pub enum Primitive {
    Triangle { p0: Vec3, e1: Vec3, e2: Vec3, shape: u32, index: u32 },
    Sphere { center: Vec3, radius: f32, shape: u32 },
}

impl Primitive {
    pub fn shape(&self) -> u32 {
        match *self {
            Primitive::Triangle { shape, .. } | Primitive::Sphere { shape, .. } => shape,
        }
    }

    #[inline]
    fn intersect(&self, o: Vec3, d: Vec3, t_max: f32) -> f32 {
        match *self {
            Primitive::Triangle { p0, e1, e2, .. } => intersect_triangle(o, d, t_max, p0, e1, e2).0,
            Primitive::Sphere { center, radius, .. } => intersect_sphere(o, d, t_max, center, radius),
        }
    }
}

impl Boundable for Primitive {
    fn aabb(&self) -> Aabb {
        match *self {
            Primitive::Triangle { p0, e1, e2, .. } => {
                let a = Vec3A::from(p0);
                let b = Vec3A::from(p0 + e1);
                let c = Vec3A::from(p0 + e2);
                Aabb::new(a.min(b).min(c), a.max(b).max(c))
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
}

impl Accel {
    pub fn build(prims: Vec<Primitive>) -> Accel {
        if prims.is_empty() {
            return Accel { bvh: CwBvh::default(), prims, bounds: (Vec3::ZERO, Vec3::ZERO) };
        }
        let mut build_time = Default::default();
        let bvh = build_cwbvh(&prims, BvhBuildParams::medium_build(), &mut build_time);
        let ordered: Vec<Primitive> = bvh.primitive_indices.iter().map(|&i| prims[i as usize]).collect();
        let total = prims.iter().fold(Aabb::empty(), |acc, p| acc.union(&p.aabb()));
        Accel { bvh, prims: ordered, bounds: (total.min.into(), total.max.into()) }
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

    #[inline]
    fn obvhs_ray(ray: &Ray) -> obvhs::ray::Ray {
        obvhs::ray::Ray::new(ray.o.into(), ray.d.into(), 0.0, ray.t_max)
    }

    /// Closest hit along the ray within (0, t_max).
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        if self.prims.is_empty() {
            return None;
        }
        let mut hit = RayHit::none();
        let prims = &self.prims;
        let found = self.bvh.ray_traverse(Self::obvhs_ray(ray), &mut hit, |r, id| {
            prims[id].intersect(r.origin.into(), r.direction.into(), r.tmax)
        });
        found.then_some(PrimHit { t: hit.t, prim: hit.primitive_id })
    }

    /// True when anything blocks the ray within (0, t_max). Stops at the first blocker.
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        if self.prims.is_empty() {
            return false;
        }
        let prims = &self.prims;
        !self.bvh.ray_traverse_miss(Self::obvhs_ray(ray), |r, id| {
            prims[id].intersect(r.origin.into(), r.direction.into(), r.tmax)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{sample_uniform_sphere, Sampler};

    fn brute_force(prims: &[Primitive], ray: &Ray) -> f32 {
        prims.iter().map(|p| p.intersect(ray.o, ray.d, ray.t_max)).fold(f32::INFINITY, f32::min)
    }

    #[test]
    fn bvh_agrees_with_brute_force_on_random_rays() {
        let mut s = Sampler::new(1, 0, 0);
        let mut prims = Vec::new();
        for i in 0..200u32 {
            let c = (s.next_2d().extend(s.next_f32()) - 0.5) * 10.0;
            if i % 3 == 0 {
                prims.push(Primitive::Sphere { center: c, radius: 0.3 * s.next_f32() + 0.01, shape: i, });
            } else {
                let e1 = sample_uniform_sphere(s.next_2d());
                let e2 = sample_uniform_sphere(s.next_2d());
                prims.push(Primitive::Triangle { p0: c, e1, e2, shape: i, index: 0 });
            }
        }
        let accel = Accel::build(prims.clone());
        for _ in 0..2000 {
            let o = (s.next_2d().extend(s.next_f32()) - 0.5) * 12.0;
            let mut ray = Ray::new(o, sample_uniform_sphere(s.next_2d()));
            if s.next_f32() < 0.3 {
                ray.t_max = 3.0;
            }
            let expected = brute_force(&prims, &ray);
            match accel.intersect(&ray) {
                Some(h) => {
                    assert_eq!(h.t, expected);
                    let p = accel.primitive(h.prim);
                    assert_eq!(p.intersect(ray.o, ray.d, ray.t_max), h.t);
                }
                None => assert!(expected.is_infinite()),
            }
            assert_eq!(accel.occluded(&ray), expected.is_finite());
        }
    }
}

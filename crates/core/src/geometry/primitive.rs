//! What the ray cores store and return: `Primitive` (a triangle, parallelogram or sphere with the
//! scene shape it belongs to) and `PrimHit` (a closest hit). Both cores, the BVH (`accel.rs`) and
//! the flat loops (`flat.rs`), share them.

use super::quad::Parallelogram;
use super::quadric::{cylinder_bounds, disk_bounds, intersect_cylinder, intersect_disk, Affine};
use super::sdf::SdfVoxel;
use super::sphere::intersect_sphere;
use super::triangle::{intersect_triangle, ShearedRay};
use crate::math::Vec3;
use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::Boundable;

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
    /// Mitsuba's disk: the unit disk under the inverse of `to_object` (`quadric.rs`).
    Disk { to_object: Affine, shape: u32 },
    /// Mitsuba's open cylinder: the unit cylinder under the inverse of `to_object`.
    Cylinder { to_object: Affine, shape: u32 },
    /// One voxel of an `sdfgrid` that the surface may cross (`sdf.rs`).
    SdfVoxel { voxel: SdfVoxel, shape: u32 },
}

impl Primitive {
    pub fn shape(&self) -> u32 {
        match *self {
            Primitive::Triangle { shape, .. }
            | Primitive::Quad { shape, .. }
            | Primitive::Sphere { shape, .. }
            | Primitive::Disk { shape, .. }
            | Primitive::Cylinder { shape, .. }
            | Primitive::SdfVoxel { shape, .. } => shape,
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
            Primitive::Disk { to_object, .. } => intersect_disk(o, d, t_max, to_object),
            Primitive::Cylinder { to_object, .. } => intersect_cylinder(o, d, t_max, to_object),
            Primitive::SdfVoxel { voxel, .. } => voxel.intersect(o, d, t_max),
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
            Primitive::Disk { to_object, .. } => {
                let (lo, hi) = disk_bounds(&to_object.inverse());
                Aabb::new(lo.into(), hi.into())
            }
            Primitive::Cylinder { to_object, .. } => {
                let (lo, hi) = cylinder_bounds(&to_object.inverse());
                Aabb::new(lo.into(), hi.into())
            }
            Primitive::SdfVoxel { voxel, .. } => {
                let (lo, hi) = voxel.bounds();
                Aabb::new(lo.into(), hi.into())
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

//! A ray's closest hit turned into the local geometry integrators shade with.

use super::{Scene, ShapeGeometry};
use crate::bsdf::ShadingFrame;
use crate::geometry::ray::barycentric_error;
use crate::geometry::sphere::refine_sphere_hit;
use crate::geometry::triangle::{intersect_triangle, ShearedRay};
use crate::geometry::{offset_ray_origin, PrimHit, Primitive, Ray, SHADOW_EPSILON};
use crate::math::{Vec2, Vec3, PI};

#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    pub p: Vec3,
    /// Conservative per-axis bound on the rounding error of `p`.
    pub p_err: Vec3,
    /// Geometric normal, unit, on the shape's outside (after `flip_normals`).
    pub ng: Vec3,
    /// Shading normal, unit, on the same side as `ng`.
    pub ns: Vec3,
    pub t: f32,
    /// Texture coordinates (Mitsuba's parameterisation of each shape).
    pub uv: Vec2,
    pub shape: u32,
    pub material: u32,
    /// Index into `Scene::lights` when the surface emits.
    pub light: Option<u32>,
}

impl SurfaceHit {
    pub(crate) fn new(scene: &Scene, ray: &Ray, h: PrimHit) -> SurfaceHit {
        let prim = *scene.accel.primitive(h.prim);
        let shape = &scene.shapes[prim.shape() as usize];
        let (p, p_err, mut ng, mut ns, uv) = match prim {
            Primitive::Triangle {
                p: [p0, p1, p2],
                index,
                ..
            } => {
                let sheared = ShearedRay::new(ray.o, ray.d);
                let (_, [b0, b1, b2]) = intersect_triangle(&sheared, f32::INFINITY, &[p0, p1, p2]);
                let p = b0 * p0 + b1 * p1 + b2 * p2;
                let err = barycentric_error([b0, b1, b2], [p0, p1, p2]);
                let ng = (p1 - p0).cross(p2 - p0).normalize();
                let (ns, uv) = match &shape.geometry {
                    ShapeGeometry::Mesh(m) => (
                        m.shading_normal(index as usize, b0, b1, b2).unwrap_or(ng),
                        m.uv(index as usize, b0, b1, b2),
                    ),
                    ShapeGeometry::Sphere { .. } => (ng, Vec2::ZERO),
                };
                (p, err, ng, ns, uv)
            }
            Primitive::Quad { q, index, .. } => {
                let (p, err, u, v) = q.hit_point(ray.o, ray.d, h.t);
                let ng = q.e1.cross(q.e2).normalize();
                // Which of the two source triangles holds (u, v), with its barycentrics.
                let (tri, b) = if u >= v {
                    (index, [1.0 - u, u - v, v])
                } else {
                    (index + 1, [1.0 - v, u, v - u])
                };
                let (ns, uv) = match &shape.geometry {
                    ShapeGeometry::Mesh(m) => (
                        m.shading_normal(tri as usize, b[0], b[1], b[2])
                            .unwrap_or(ng),
                        m.uv(tri as usize, b[0], b[1], b[2]),
                    ),
                    ShapeGeometry::Sphere { .. } => (ng, Vec2::ZERO),
                };
                (p, err, ng, ns, uv)
            }
            Primitive::Sphere { center, radius, .. } => {
                let (p, err) = refine_sphere_hit(ray.at(h.t), center, radius);
                let n = (p - center).normalize();
                (p, err, n, n, sphere_uv(n))
            }
        };
        if shape.flip_normals {
            ng = -ng;
            ns = -ns;
        }
        // Interpolated normals may face the other way than the geometry; keep them on ng's side.
        if ns.dot(ng) < 0.0 {
            ns = -ns;
        }
        SurfaceHit {
            p,
            p_err,
            ng,
            ns,
            t: h.t,
            uv,
            shape: prim.shape(),
            material: shape.material,
            light: shape.light,
        }
    }

    #[inline]
    pub fn shading_frame(&self) -> ShadingFrame {
        ShadingFrame::new(self.ng, self.ns).with_uv(self.uv)
    }

    /// A ray leaving the surface in direction `dir`, started safely off the surface.
    #[inline]
    pub fn spawn_ray(&self, dir: Vec3) -> Ray {
        Ray::new(offset_ray_origin(self.p, self.p_err, self.ng, dir), dir)
    }

    /// A shadow ray towards `to`, stopping just short of it.
    #[inline]
    pub fn spawn_ray_to(&self, to: Vec3) -> Ray {
        let o = offset_ray_origin(self.p, self.p_err, self.ng, to - self.p);
        let d = to - o;
        let len = d.length();
        Ray {
            o,
            d: d / len,
            t_max: len * (1.0 - SHADOW_EPSILON),
        }
    }
}

/// Mitsuba's sphere parameterisation from the unit outward normal (object frame = world axes:
/// a sphere's rotation is not kept): u = φ / 2π with φ = atan2(y, x) in [0, 2π), v = θ / π.
fn sphere_uv(n: Vec3) -> Vec2 {
    let phi = n.y.atan2(n.x);
    let phi = if phi < 0.0 { phi + 2.0 * PI } else { phi };
    Vec2::new(phi / (2.0 * PI), n.z.clamp(-1.0, 1.0).acos() / PI)
}

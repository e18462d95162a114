//! A ray's closest hit turned into the local geometry integrators shade with.

use super::{Scene, ShapeGeometry};
use crate::bsdf::ShadingFrame;
use crate::geometry::quadric::{cylinder_at, disk_at};
use crate::geometry::ray::barycentric_error;
use crate::geometry::sphere::refine_sphere_hit;
use crate::geometry::triangle::{intersect_triangle, ShearedRay};
use crate::geometry::{offset_ray_origin, PrimHit, Primitive, Ray, SHADOW_EPSILON};
use crate::math::{Color, Vec2, Vec3, PI};
use crate::texture::TexPoint;

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
    /// Texture coordinates (Mitsuba's parameterisation of each shape), with the mesh attribute
    /// the material reads.
    pub uv: TexPoint,
    /// Where the shading frame's x axis points: ∂p/∂u made orthogonal to the unperturbed shading
    /// normal (Mitsuba's `sh_frame.s`), for anisotropic materials only (`needs_tangent`); zero
    /// for every other material, whose frame keeps `Frame::from_z`'s arbitrary tangent. Born
    /// here, carried by `PathVertex::tangent`: every frame is rebuilt from (ng, ns, tangent).
    pub tangent: Vec3,
    pub shape: u32,
    pub material: u32,
    /// Index into `Scene::lights` when the surface emits.
    pub light: Option<u32>,
    /// The shape's media (`Scene::interfaces`; 0 without media), copied into its path vertex.
    pub interface: u16,
}

/// Where a ray met primitive `h.prim`: the point, its error bound, the geometric normal (before
/// `flip_normals`), and — when `SHADE` — the shading normal and uv (else `ng` and zero). The first
/// stage of `SurfaceHit::new` (`SHADE`) and all of `BoundaryHit::new` (not): one computation, so a
/// boundary crossing and a full hit of the same ray agree bit for bit.
#[inline(always)]
fn locate<const SHADE: bool>(scene: &Scene, ray: &Ray, h: PrimHit) -> Located {
    let prim = scene.accel.primitive(h.prim);
    let shape = &scene.shapes[prim.shape() as usize];
    // `tri`: the mesh triangle holding the point (a parallelogram's source triangle).
    // `analytic`: a disk's or cylinder's own ∂p/∂u, ∂p/∂v.
    let mut analytic = None;
    let (p, p_err, ng, ns, uv, tri, bary) = match *prim {
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
                ShapeGeometry::Mesh(m) if SHADE => (
                    m.shading_normal(index as usize, b0, b1, b2).unwrap_or(ng),
                    if shape.reads_uv {
                        m.uv(index as usize, b0, b1, b2)
                    } else {
                        Vec2::ZERO
                    },
                ),
                _ => (ng, Vec2::ZERO),
            };
            (p, err, ng, ns, uv, index, [b0, b1, b2])
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
                ShapeGeometry::Mesh(m) if SHADE => (
                    m.shading_normal(tri as usize, b[0], b[1], b[2])
                        .unwrap_or(ng),
                    if shape.reads_uv {
                        m.uv(tri as usize, b[0], b[1], b[2])
                    } else {
                        Vec2::ZERO
                    },
                ),
                _ => (ng, Vec2::ZERO),
            };
            (p, err, ng, ns, uv, tri, b)
        }
        Primitive::Sphere { center, radius, .. } => {
            let (p, err) = refine_sphere_hit(ray.at(h.t), center, radius);
            let n = (p - center).normalize();
            let uv = if SHADE && shape.reads_uv {
                crate::shape::sphere_uv(shape.geometry.sphere_to_object() * n)
            } else {
                Vec2::ZERO
            };
            (p, err, n, n, uv, 0, [1.0, 0.0, 0.0])
        }
        Primitive::Disk { to_object, .. } | Primitive::Cylinder { to_object, .. } => {
            let local = to_object.point(ray.at(h.t));
            let q = match shape.geometry {
                ShapeGeometry::Disk { to_world } => disk_at(local, &to_world, &to_object),
                ShapeGeometry::Cylinder { to_world } => cylinder_at(local, &to_world),
                _ => unreachable!("a disk or cylinder primitive of another shape"),
            };
            analytic = Some((q.dpdu, q.dpdv));
            (q.p, q.p_err, q.n, q.n, q.uv, 0, [1.0, 0.0, 0.0])
        }
        Primitive::SdfVoxel { ref voxel, .. } => {
            let ShapeGeometry::SdfGrid { grid, to_world } = &shape.geometry else {
                unreachable!("an sdf voxel of another shape")
            };
            let (p, p_err) = sdf_hit_point(ray, h.t, voxel, to_world);
            let to_object = to_world.inverse();
            let local = to_object.point(p);
            // Normals transform by the inverse transpose of to_world: to_object's transpose.
            let normal = |g: Vec3| (to_object.m.transpose() * g).normalize_or_zero();
            let ng = normal(grid.gradient(local));
            let ng = if ng == Vec3::ZERO { -ray.d } else { ng };
            let ns = if SHADE && grid.smooth {
                normal(grid.smooth_normal(local))
            } else {
                ng
            };
            let ns = if ns == Vec3::ZERO { ng } else { ns };
            (p, p_err, ng, ns, Vec2::ZERO, 0, [1.0, 0.0, 0.0])
        }
    };
    Located {
        p,
        p_err,
        ng,
        ns,
        uv,
        tri,
        bary,
        analytic,
    }
}

/// `locate`'s answer.
struct Located {
    p: Vec3,
    p_err: Vec3,
    ng: Vec3,
    ns: Vec3,
    uv: Vec2,
    tri: u32,
    bary: [f32; 3],
    /// A disk's or cylinder's own ∂p/∂u, ∂p/∂v.
    analytic: Option<(Vec3, Vec3)>,
}

/// What a walk along a segment needs of a surface it crosses (`Scene::crossings`): no shading
/// normal, uv or tangent, which a full `SurfaceHit` spends most of its time on.
#[derive(Clone, Copy, Debug)]
pub struct BoundaryHit {
    pub p: Vec3,
    pub p_err: Vec3,
    /// Geometric normal, unit, on the shape's outside (after `flip_normals`): `SurfaceHit::ng`.
    pub ng: Vec3,
    pub shape: u32,
    pub material: u32,
}

impl BoundaryHit {
    #[inline]
    pub(crate) fn new(scene: &Scene, ray: &Ray, h: PrimHit) -> BoundaryHit {
        let l = locate::<false>(scene, ray, h);
        let shape_id = scene.accel.primitive(h.prim).shape();
        let shape = &scene.shapes[shape_id as usize];
        BoundaryHit {
            p: l.p,
            p_err: l.p_err,
            ng: if shape.flip_normals { -l.ng } else { l.ng },
            shape: shape_id,
            material: shape.material,
        }
    }
}

impl SurfaceHit {
    pub(crate) fn new(scene: &Scene, ray: &Ray, h: PrimHit) -> SurfaceHit {
        let prim = scene.accel.primitive(h.prim);
        let shape = &scene.shapes[prim.shape() as usize];
        let Located {
            p,
            p_err,
            mut ng,
            mut ns,
            uv,
            tri,
            bary,
            analytic,
        } = locate::<true>(scene, ray, h);
        let uv = TexPoint {
            uv,
            attr: match (shape.attribute, &shape.geometry) {
                (Some(k), ShapeGeometry::Mesh(m)) => m.attribute(k, tri as usize, bary),
                _ => Color::ZERO,
            },
        };
        if shape.flip_normals {
            ng = -ng;
            ns = -ns;
        }
        // Interpolated normals may face the other way than the geometry; keep them on ng's side.
        if ns.dot(ng) < 0.0 {
            ns = -ns;
        }
        // A normal or bump map replaces the shading normal, and an anisotropic material orients
        // its frame along ∂p/∂u (only such materials need tangents). Under a normal map the
        // frame's x axis is the unperturbed one made orthogonal to the new normal
        // (`ShadingFrame::oriented`), as Mitsuba 3's `normalmap` rotates its frame (PR #905).
        let material = scene.material(shape.material);
        let perturbation = material.perturbation();
        let mut tangent = Vec3::ZERO;
        let oriented = shape.needs_tangent;
        if perturbation.is_some() || oriented {
            let (dpdu, dpdv) =
                analytic.unwrap_or_else(|| tangents(&shape.geometry, prim, tri as usize, p, ng));
            if oriented {
                tangent = (dpdu - ns * ns.dot(dpdu))
                    .try_normalize()
                    .unwrap_or_else(|| crate::math::Frame::from_z(ns).x);
            }
            if let Some(perturbed) = perturbation {
                ns = perturbed.normal(ng, ns, dpdu, dpdv, uv);
            }
        }
        SurfaceHit {
            p,
            p_err,
            ng,
            ns,
            t: h.t,
            uv,
            tangent,
            shape: prim.shape(),
            material: shape.material,
            light: shape.light,
            interface: shape.interface,
        }
    }

    #[inline]
    pub fn shading_frame(&self) -> ShadingFrame {
        ShadingFrame::oriented(self.ng, self.ns, self.tangent).with_uv(self.uv)
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

/// An sdf hit: the point along the ray, with a bound that covers its rounding and the
/// uncertainty of the computed zero set — a thousandth of the voxel's smallest world edge, far
/// above the rounding of a voxel's local coordinates, so a ray spawned off it never finds the
/// root it leaves (`SdfVoxel::intersect`).
fn sdf_hit_point(
    ray: &Ray,
    t: f32,
    voxel: &crate::geometry::sdf::SdfVoxel,
    to_world: &crate::shape::Affine,
) -> (Vec3, Vec3) {
    let p = ray.at(t);
    let w = voxel.to_voxel.inverse();
    let edge =
        w.m.x_axis
            .length()
            .min(w.m.y_axis.length())
            .min(w.m.z_axis.length());
    let err = (ray.o.abs() + (ray.d * t).abs()) * crate::math::gamma(3)
        + to_world.point_error(Vec3::ONE)
        + Vec3::splat(1e-3 * edge);
    (p, err)
}

/// ∂p/∂u and ∂p/∂v at `p` on a primitive, in the parameterisation `uv` comes from: a mesh
/// triangle's from its vertex uvs (Mitsuba's (b1, b2) without them), solved from the triangle's
/// edges (pbrt-v4 §6.5.1, Mitsuba's mesh); a sphere's analytically. Where the uvs are degenerate,
/// any two tangents orthogonal to the normal (Mitsuba does the same).
fn tangents(
    geometry: &ShapeGeometry,
    prim: &Primitive,
    tri: usize,
    p: Vec3,
    ng: Vec3,
) -> (Vec3, Vec3) {
    let fallback = || {
        let f = crate::math::Frame::from_z(ng);
        (f.x, f.y)
    };
    match (prim, geometry) {
        (Primitive::Triangle { .. } | Primitive::Quad { .. }, ShapeGeometry::Mesh(m)) => {
            let [p0, p1, p2] = m.triangle(tri);
            let [uv0, uv1, uv2] = match &m.uvs {
                Some(uvs) => m.indices[tri].map(|k| uvs[k as usize]),
                None => [Vec2::ZERO, Vec2::X, Vec2::Y],
            };
            let (d1, d2) = (uv1 - uv0, uv2 - uv0);
            let (e1, e2) = (p1 - p0, p2 - p0);
            let det = d1.x * d2.y - d1.y * d2.x;
            let dpdu = (e1 * d2.y - e2 * d1.y) / det;
            let dpdv = (e2 * d1.x - e1 * d2.x) / det;
            if det != 0.0 && dpdu.is_finite() && dpdv.is_finite() {
                (dpdu, dpdv)
            } else {
                fallback()
            }
        }
        (Primitive::Sphere { center, radius, .. }, _) => {
            // p(u, v) = c + R r (sin θ cos φ, sin θ sin φ, cos θ), φ = 2πu, θ = πv, in the
            // sphere's object frame (R its rotation, the identity unless it has one).
            let r = geometry.sphere_to_object().transpose();
            let d = geometry.sphere_to_object() * (p - *center);
            let (sin_t, cos_t) = ((d.x * d.x + d.y * d.y).sqrt() / radius, d.z / radius);
            let phi = d.y.atan2(d.x);
            let dpdu = Vec3::new(-d.y, d.x, 0.0) * (2.0 * PI);
            let dpdv = Vec3::new(cos_t * phi.cos(), cos_t * phi.sin(), -sin_t) * (PI * radius);
            if dpdu.length_squared() > 0.0 {
                (r * dpdu, r * dpdv)
            } else {
                fallback() // at a pole
            }
        }
        _ => fallback(),
    }
}

//! Area lights: any triangle mesh, sphere, disk or cylinder with `emission`, one-sided on its
//! normal side. Disks and cylinders are sampled uniformly by area.
//! Meshes are sampled uniformly by area (triangle chosen by area). Spheres are sampled by the cone
//! they subtend when the shading point is outside (much less variance for small, far spheres) and
//! uniformly by area from inside. A textured radiance (Mitsuba's area emitter with a `radiance`
//! texture) is read at the point's uv, in the shape's own parameterisation (the one hits report);
//! sampling stays uniform by area, as Mitsuba's, so only the value changes, not any density.

use super::{LightLeSample, LightLiSample};
use crate::geometry::quad::Parallelogram;
use crate::geometry::quadric::{cylinder_area, cylinder_at, disk_area, disk_at, Affine};
use crate::geometry::{offset_ray_origin, Ray};
use crate::math::{gamma, luminance, Color, Frame, Vec2, Vec3, PI};
use crate::sampling::{
    cosine_hemisphere_pdf, sample_concentric_disk, sample_cosine_hemisphere, sample_uniform_cone,
    sample_uniform_sphere, sample_uniform_triangle, uniform_cone_pdf, Distribution1D,
};
use crate::shape::{ShapeGeometry, TriangleMesh};
use crate::texture::{TexPoint, Texture};

/// A piece of an emitting mesh: a triangle, or a pair of triangles forming a parallelogram
/// (sampled with two uniform variates, no square root; same uniform area density).
#[derive(Clone, Debug)]
enum Piece {
    Triangle([Vec3; 3]),
    Parallelogram(Parallelogram),
}

#[derive(Clone, Debug)]
enum Emitter {
    Triangles {
        pieces: Vec<Piece>,
        pick: Distribution1D,
        /// Each piece's vertex uvs, kept only for a textured light (whose pieces are all
        /// triangles: a merged parallelogram would lose the triangles' own uvs).
        uvs: Option<Vec<[Vec2; 3]>>,
    },
    Sphere {
        center: Vec3,
        radius: f32,
    },
    /// A disk or cylinder (`quadric.rs`): sampled uniformly by area through its affine map.
    Disk {
        to_world: Affine,
        to_object: Affine,
    },
    Cylinder {
        to_world: Affine,
    },
}

#[derive(Clone, Debug)]
pub struct AreaLight {
    pub shape: u32,
    /// The radiance, or for a textured light its mean (what the light's power is judged by).
    pub emission: Color,
    /// The radiance over the shape's uv when it is not constant.
    texture: Option<Texture>,
    pub area: f32,
    flip: bool,
    /// A sphere's world-to-object rotation, for its uv (`ShapeGeometry::sphere_to_object`).
    sphere_to_object: glam::Mat3,
    emitter: Emitter,
}

/// The mesh's triangles as sampling pieces (parallelogram pairs merged, as the BVH does, unless
/// `keep_triangles`) with their areas.
fn mesh_pieces(m: &TriangleMesh, keep_triangles: bool) -> (Vec<Piece>, Vec<f32>) {
    let (mut pieces, mut areas) = (Vec::new(), Vec::new());
    let mut i = 0;
    while i < m.indices.len() {
        if i + 1 < m.indices.len() && !keep_triangles {
            if let Some(q) = Parallelogram::from_triangle_pair(m.triangle(i), m.triangle(i + 1)) {
                areas.push(m.triangle_area(i) + m.triangle_area(i + 1));
                pieces.push(Piece::Parallelogram(q));
                i += 2;
                continue;
            }
        }
        areas.push(m.triangle_area(i));
        pieces.push(Piece::Triangle(m.triangle(i)));
        i += 1;
    }
    (pieces, areas)
}

impl AreaLight {
    pub fn new(
        shape: u32,
        geometry: &ShapeGeometry,
        radiance: &Texture,
        flip_normals: bool,
    ) -> AreaLight {
        let texture = match radiance {
            Texture::Constant(_) => None,
            t => Some(t.clone()),
        };
        let (emitter, area) = match geometry {
            ShapeGeometry::Mesh(m) => {
                let (pieces, areas) = mesh_pieces(m, texture.is_some());
                let total: f64 = areas.iter().map(|&a| a as f64).sum();
                let uvs = texture.as_ref().map(|_| {
                    (0..m.indices.len())
                        .map(|i| {
                            [(1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]
                                .map(|(b0, b1, b2)| m.uv(i, b0, b1, b2))
                        })
                        .collect()
                });
                (
                    Emitter::Triangles {
                        pieces,
                        pick: Distribution1D::new(&areas),
                        uvs,
                    },
                    total as f32,
                )
            }
            &ShapeGeometry::Sphere { center, radius }
            | &ShapeGeometry::RotatedSphere { center, radius, .. } => (
                Emitter::Sphere { center, radius },
                4.0 * PI * radius * radius,
            ),
            &ShapeGeometry::Disk { to_world } => (
                Emitter::Disk {
                    to_world,
                    to_object: to_world.inverse(),
                },
                disk_area(&to_world),
            ),
            &ShapeGeometry::Cylinder { to_world } => {
                (Emitter::Cylinder { to_world }, cylinder_area(&to_world))
            }
            // The loaders refuse an emitting sdfgrid, as Mitsuba does.
            ShapeGeometry::SdfGrid { .. } => unreachable!("an sdfgrid cannot emit"),
        };
        AreaLight {
            shape,
            emission: radiance.mean(),
            texture,
            area,
            flip: flip_normals,
            sphere_to_object: geometry.sphere_to_object(),
            emitter,
        }
    }

    /// A uniformly distributed point on the surface with its outward (emitting-side) normal, its
    /// rounding bound and its uv (zero unless the light is textured).
    fn sample_area(&self, u: Vec2) -> (Vec3, Vec3, Vec3, TexPoint) {
        let (p, n, err, uv) = match &self.emitter {
            Emitter::Triangles { pieces, pick, uvs } => {
                let (i, _, ux) = pick.sample(u.x);
                match &pieces[i] {
                    &Piece::Triangle([a, b, c]) => {
                        let (b1, b2) = sample_uniform_triangle(Vec2::new(ux, u.y));
                        let b0 = 1.0 - b1 - b2;
                        let p = b0 * a + b1 * b + b2 * c;
                        let err = crate::geometry::ray::barycentric_error([b0, b1, b2], [a, b, c]);
                        // The hit's interpolation (`TriangleMesh::uv`), so both agree on a point.
                        let uv = uvs.as_ref().map_or(Vec2::ZERO, |uvs| {
                            let [t0, t1, t2] = uvs[i];
                            b0 * t0 + b1 * t1 + b2 * t2
                        });
                        (p, (b - a).cross(c - a).normalize(), err, uv)
                    }
                    Piece::Parallelogram(q) => {
                        let (e1, e2) = (ux * q.e1, u.y * q.e2);
                        let err = (q.p0.abs() + e1.abs() + e2.abs()) * gamma(3);
                        (
                            q.p0 + e1 + e2,
                            q.e1.cross(q.e2).normalize(),
                            err,
                            Vec2::ZERO,
                        )
                    }
                }
            }
            &Emitter::Sphere { center, radius } => {
                let n = sample_uniform_sphere(u);
                let p = center + radius * n;
                let uv = self.sphere_uv(n);
                (p, n, (p.abs() + center.abs()) * gamma(6), uv)
            }
            // An affine map has a constant area scale on the plane, so the image of a uniform
            // point on the unit disk is uniform on the ellipse (density 1/area).
            Emitter::Disk {
                to_world,
                to_object,
            } => {
                let q = disk_at(sample_concentric_disk(u).extend(0.0), to_world, to_object);
                (q.p, q.n, q.p_err, self.quadric_uv(q.uv))
            }
            // z and φ uniform: uniform by area on a round cylinder (area element r l dφ dz).
            Emitter::Cylinder { to_world } => {
                let (sin, cos) = (2.0 * PI * u.y).sin_cos();
                let q = cylinder_at(Vec3::new(cos, sin, u.x), to_world);
                (q.p, q.n, q.p_err, self.quadric_uv(q.uv))
            }
        };
        (p, if self.flip { -n } else { n }, err, TexPoint::at(uv))
    }

    /// A disk's or cylinder's uv when the light is textured (zero otherwise, as for spheres).
    #[inline]
    fn quadric_uv(&self, uv: Vec2) -> Vec2 {
        match self.texture {
            Some(_) => uv,
            None => Vec2::ZERO,
        }
    }

    /// The sphere's uv at outward normal `n` when the light is textured (zero otherwise).
    #[inline]
    fn sphere_uv(&self, n: Vec3) -> Vec2 {
        match self.texture {
            Some(_) => crate::shape::sphere_uv(self.sphere_to_object * n),
            None => Vec2::ZERO,
        }
    }

    #[inline]
    pub fn emitted(&self, n: Vec3, w: Vec3, uv: TexPoint) -> Color {
        if n.dot(w) > 0.0 {
            match &self.texture {
                None => self.emission,
                Some(t) => t.eval(uv),
            }
        } else {
            Color::ZERO
        }
    }

    /// The radiance as the builder was given it (a constant or a texture).
    pub fn radiance(&self) -> Texture {
        self.texture
            .clone()
            .unwrap_or(Texture::Constant(self.emission))
    }

    /// 1 − cos θmax of the cone a sphere subtends from `p`, or None when `p` is inside it or on
    /// its surface. On the surface the cone degenerates into a half-space whose near intersection
    /// is `p` itself, so points within a relative 1e-3 of the radius are sampled by area instead;
    /// `sample_li` and `pdf_li` share this test, so the choice is always consistent.
    fn sphere_cone(p: Vec3, center: Vec3, radius: f32) -> Option<f32> {
        let d2 = (p - center).length_squared();
        let r2 = radius * radius;
        if d2 <= r2 * (1.0 + 1e-3) {
            return None;
        }
        let sin2 = r2 / d2;
        let cos = (1.0 - sin2).max(0.0).sqrt();
        Some(sin2 / (1.0 + cos))
    }

    pub fn sample_li(&self, p: Vec3, u: Vec2) -> Option<LightLiSample> {
        if let Emitter::Sphere { center, radius } = self.emitter {
            if let Some(h) = Self::sphere_cone(p, center, radius) {
                return self.sample_sphere_cone(p, center, radius, h, u);
            }
        }
        let (lp, n, lp_err, uv) = self.sample_area(u);
        let to = lp - p;
        let d2 = to.length_squared();
        if !(d2 > 0.0) {
            return None;
        }
        let distance = d2.sqrt();
        let wi = to / distance;
        let cos_l = n.dot(-wi).abs();
        if cos_l == 0.0 {
            return None;
        }
        let pdf_w = d2 / (cos_l * self.area);
        Some(LightLiSample {
            wi,
            p: lp,
            n,
            p_err: lp_err,
            distance,
            uv,
            radiance: self.emitted(n, -wi, uv),
            pdf_w,
            delta: false,
        })
    }

    fn sample_sphere_cone(
        &self,
        p: Vec3,
        center: Vec3,
        radius: f32,
        h: f32,
        u: Vec2,
    ) -> Option<LightLiSample> {
        let axis = center - p;
        let dc = axis.length();
        let frame = Frame::from_z(axis / dc);
        let local = sample_uniform_cone(u, h);
        let wi = frame.to_world(local).normalize();
        // Nearest intersection of the sampled direction with the sphere, computed stably.
        let cos_t = local.z;
        let sin2_t = (1.0 - cos_t * cos_t).max(0.0);
        let ds = dc * cos_t - (radius * radius - dc * dc * sin2_t).max(0.0).sqrt();
        let lp_raw = p + wi * ds;
        let mut n = (lp_raw - center).normalize();
        let lp = center + n * radius;
        let uv = TexPoint::at(self.sphere_uv(n));
        if self.flip {
            n = -n;
        }
        let distance = (lp - p).length();
        Some(LightLiSample {
            wi,
            p: lp,
            n,
            // center + radius·n: the rounding of a sum of two terms (`sample_area`'s bound).
            p_err: (lp.abs() + center.abs()) * gamma(6),
            distance,
            uv,
            radiance: self.emitted(n, -wi, uv),
            pdf_w: uniform_cone_pdf(h),
            delta: false,
        })
    }

    pub fn pdf_li(&self, p: Vec3, wi: Vec3, light_p: Vec3, light_n: Vec3) -> f32 {
        if let Emitter::Sphere { center, radius } = self.emitter {
            if let Some(h) = Self::sphere_cone(p, center, radius) {
                return uniform_cone_pdf(h);
            }
        }
        let d2 = (light_p - p).length_squared();
        let cos_l = light_n.dot(-wi).abs();
        if cos_l == 0.0 {
            return 0.0;
        }
        d2 / (cos_l * self.area)
    }

    pub fn sample_le(&self, u_pos: Vec2, u_dir: Vec2) -> Option<LightLeSample> {
        let (p, n, err, uv) = self.sample_area(u_pos);
        let local = sample_cosine_hemisphere(u_dir);
        let pdf_dir = cosine_hemisphere_pdf(local.z);
        if pdf_dir == 0.0 {
            return None;
        }
        let d = Frame::from_z(n).to_world(local);
        let ray = Ray::new(offset_ray_origin(p, err, n, d), d);
        Some(LightLeSample {
            ray,
            p,
            p_err: err,
            n,
            uv,
            radiance: self.emitted(n, n, uv),
            pdf_pos: 1.0 / self.area,
            pdf_dir,
        })
    }

    pub fn pdf_le(&self, n: Vec3, dir: Vec3) -> (f32, f32) {
        (1.0 / self.area, cosine_hemisphere_pdf(n.dot(dir)))
    }

    pub fn power(&self) -> f32 {
        PI * self.area * luminance(self.emission)
    }
}

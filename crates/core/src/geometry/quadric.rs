//! Mitsuba's analytic disk and cylinder, each an affine image of a unit shape: the disk
//! x² + y² ≤ 1 in the plane z = 0 (normal +z), the open cylinder x² + y² = 1, 0 ≤ z ≤ 1. A ray is
//! intersected in object space: an affine map keeps a line's parameter, so the object-space t is
//! the world distance along the unit world direction (the object direction is not normalised).
//!
//! Self-intersection: a ray leaving the surface starts `offset_ray_origin`'s error box off it, and
//! the tests below also refuse the root at the origin when the origin lies on the surface within
//! the rounding of its own transform (as the parallelogram refuses its own plane), so the sign of
//! every accepted root is exact.

use crate::math::{gamma, Vec2, Vec3, PI};
use glam::{DMat3, DVec3, Mat3};

/// x ↦ m·x + t.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Affine {
    pub m: Mat3,
    pub t: Vec3,
}

impl Affine {
    pub fn new(m: Mat3, t: Vec3) -> Affine {
        Affine { m, t }
    }

    #[inline(always)]
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.m * p + self.t
    }

    #[inline(always)]
    pub fn vector(&self, v: Vec3) -> Vec3 {
        self.m * v
    }

    /// The inverse, computed in f64 and rounded once.
    pub fn inverse(&self) -> Affine {
        let mi = self.m.as_dmat3().inverse();
        let t = -(mi * self.t.as_dvec3());
        Affine {
            m: mi.as_mat3(),
            t: t.as_vec3(),
        }
    }

    /// Per-axis bound on the rounding of `point(p)`: a sum of four products (pbrt-v4 §6.8.4).
    #[inline]
    pub fn point_error(&self, p: Vec3) -> Vec3 {
        let a = Mat3::from_cols(
            self.m.x_axis.abs(),
            self.m.y_axis.abs(),
            self.m.z_axis.abs(),
        );
        (a * p.abs() + self.t.abs()) * gamma(4)
    }

    /// Row `i` of `m` (what coordinate `i` of `point` dots `p` with).
    #[inline(always)]
    fn row(&self, i: usize) -> Vec3 {
        self.m.row(i)
    }

    /// Whether the map is finite and invertible.
    pub fn is_regular(&self) -> bool {
        let det = self.m.determinant();
        det.is_finite() && det != 0.0 && self.t.is_finite()
    }
}

/// The rounding bound of coordinate `i` of `to_object.point(o)`.
#[inline(always)]
fn coord_error(to_object: &Affine, o: Vec3, i: usize) -> f32 {
    (to_object.row(i).abs().dot(o.abs()) + to_object.t[i].abs()) * gamma(4)
}

/// Distance in (0, t_max) to the unit disk under `to_object`'s inverse, or +∞.
#[inline]
pub fn intersect_disk(o: Vec3, d: Vec3, t_max: f32, to_object: &Affine) -> f32 {
    let (lo, ld) = (to_object.point(o), to_object.vector(d));
    // On the plane within rounding: the ray leaves the disk (or runs in its plane).
    if lo.z.abs() <= coord_error(to_object, o, 2) {
        return f32::INFINITY;
    }
    let t = -lo.z / ld.z;
    if !(t > 0.0 && t < t_max) {
        return f32::INFINITY;
    }
    let (x, y) = (lo.x + t * ld.x, lo.y + t * ld.y);
    if x * x + y * y <= 1.0 {
        t
    } else {
        f32::INFINITY
    }
}

/// Distance in (0, t_max) to the unit open cylinder under `to_object`'s inverse, or +∞.
#[inline]
pub fn intersect_cylinder(o: Vec3, d: Vec3, t_max: f32, to_object: &Affine) -> f32 {
    let (lo, ld) = (to_object.point(o), to_object.vector(d));
    let (f, e) = (Vec2::new(lo.x, lo.y), Vec2::new(ld.x, ld.y));
    // a t² + 2 b t + c = 0 for |f + t e|² = 1.
    let a = e.length_squared();
    if !(a > 0.0) {
        return f32::INFINITY; // along the axis: never crosses the side
    }
    let b = f.dot(e);
    let c = f.length_squared() - 1.0;
    let in_z = |t: f32| {
        let z = lo.z + t * ld.z;
        t > 0.0 && t < t_max && (0.0..=1.0).contains(&z)
    };
    // The origin on the surface within the rounding of c: the root at the origin is the ray
    // leaving, the other (sum of roots −2b/a) the far side it may cross.
    let (ex, ey) = (coord_error(to_object, o, 0), coord_error(to_object, o, 1));
    let c_err = 2.0 * (f.x.abs() * ex + f.y.abs() * ey) + gamma(3) * (f.length_squared() + 1.0);
    if c.abs() <= c_err {
        let t = -2.0 * b / a;
        return if in_z(t) { t } else { f32::INFINITY };
    }
    // b² − a c without cancellation (Haines et al., Ray Tracing Gems ch. 7): with l the point of
    // the line closest to the axis, b² − a c = a (1 − |l|²).
    let l = f - (b / a) * e;
    let disc = a * (1.0 - l.length_squared());
    if disc < 0.0 {
        return f32::INFINITY;
    }
    let q = -(b + disc.sqrt().copysign(b));
    let (mut t0, mut t1) = (c / q, q / a);
    if q == 0.0 {
        t0 = 0.0;
    }
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    if in_z(t0) {
        t0
    } else if in_z(t1) {
        t1
    } else {
        f32::INFINITY
    }
}

/// What a hit on a disk or cylinder reports: the point re-projected onto the surface, its
/// rounding bound, the unit normal, uv and ∂p/∂u, ∂p/∂v.
pub struct QuadricHit {
    pub p: Vec3,
    pub p_err: Vec3,
    pub n: Vec3,
    pub uv: Vec2,
    pub dpdu: Vec3,
    pub dpdv: Vec3,
}

/// φ = atan2(y, x) in [0, 2π).
#[inline]
fn azimuth(x: f32, y: f32) -> f32 {
    let phi = y.atan2(x);
    if phi < 0.0 {
        phi + 2.0 * PI
    } else {
        phi
    }
}

/// Mitsuba's disk at object point `local` (z ignored): uv = (r, φ/2π), ∂p/∂u = M (cos φ, sin φ, 0),
/// ∂p/∂v = M (−sin φ, cos φ, 0) (Mitsuba's, not scaled by 2π r), normal the +z normal under the
/// map (transformed by the inverse transpose: `to_object`'s third row).
pub fn disk_at(local: Vec3, to_world: &Affine, to_object: &Affine) -> QuadricHit {
    let local = Vec3::new(local.x, local.y, 0.0);
    let r = local.truncate().length();
    let (cos, sin) = if r > 0.0 {
        (local.x / r, local.y / r)
    } else {
        (1.0, 0.0)
    };
    QuadricHit {
        p: to_world.point(local),
        p_err: to_world.point_error(local) * 1.5,
        n: to_object.row(2).normalize(),
        uv: Vec2::new(r, azimuth(local.x, local.y) / (2.0 * PI)),
        dpdu: to_world.vector(Vec3::new(cos, sin, 0.0)),
        dpdv: to_world.vector(Vec3::new(-sin, cos, 0.0)),
    }
}

/// Mitsuba's cylinder at object point `local` (projected onto the side): uv = (φ/2π, z),
/// ∂p/∂u = M 2π (−y, x, 0), ∂p/∂v = M (0, 0, 1), normal ∂p/∂u × ∂p/∂v normalised.
pub fn cylinder_at(local: Vec3, to_world: &Affine) -> QuadricHit {
    let r = local.truncate().length();
    let local = if r > 0.0 {
        Vec3::new(local.x / r, local.y / r, local.z)
    } else {
        Vec3::new(1.0, 0.0, local.z)
    };
    let dpdu = to_world.vector(Vec3::new(-local.y, local.x, 0.0) * (2.0 * PI));
    let dpdv = to_world.vector(Vec3::Z);
    QuadricHit {
        p: to_world.point(local),
        p_err: to_world.point_error(local) * 1.5,
        n: dpdu.cross(dpdv).normalize(),
        uv: Vec2::new(azimuth(local.x, local.y) / (2.0 * PI), local.z),
        dpdu,
        dpdv,
    }
}

/// Axis-aligned bounds of the unit disk under `to_world`: per axis i, ±√(m_i0² + m_i1²) around
/// the centre (the extreme of a·cos φ + b·sin φ).
pub fn disk_bounds(to_world: &Affine) -> (Vec3, Vec3) {
    let e = Vec3::from_array(std::array::from_fn(|i| {
        let r = to_world.row(i);
        (r.x * r.x + r.y * r.y).sqrt()
    }));
    // Padded well beyond rounding: `Primitive::aabb` rebuilds `to_world` from its inverse.
    let e = e * (1.0 + 1e-5) + to_world.point_error(Vec3::ONE) * 8.0;
    (to_world.t - e, to_world.t + e)
}

/// Bounds of the unit cylinder under `to_world`: both end disks'.
pub fn cylinder_bounds(to_world: &Affine) -> (Vec3, Vec3) {
    let (lo0, hi0) = disk_bounds(to_world);
    let top = Affine::new(to_world.m, to_world.point(Vec3::Z));
    let (lo1, hi1) = disk_bounds(&top);
    (lo0.min(lo1), hi0.max(hi1))
}

/// Areas: the disk's is π |M e_x × M e_y| (the map's constant area scale on the plane); the
/// cylinder's 2π r l, for the maps the loaders build (a rotation times diag(r, r, l)).
pub fn disk_area(to_world: &Affine) -> f32 {
    PI * to_world.m.x_axis.cross(to_world.m.y_axis).length()
}

pub fn cylinder_area(to_world: &Affine) -> f32 {
    2.0 * PI * to_world.m.x_axis.length() * to_world.m.z_axis.length()
}

/// f64 check used by the loaders: whether `m` is a rotation (or reflection) times diag(r, r, l),
/// within a relative `tol`: the cylinders Mitsuba renders without warning (it drops shear and
/// unequal x/y scales).
pub fn is_round_cylinder_map(m: &DMat3, tol: f64) -> bool {
    let [x, y, z]: [DVec3; 3] = [m.x_axis, m.y_axis, m.z_axis];
    let (lx, ly, lz) = (x.length(), y.length(), z.length());
    lx > 0.0
        && lz > 0.0
        && (lx - ly).abs() <= tol * lx
        && x.dot(y).abs() <= tol * lx * ly
        && x.dot(z).abs() <= tol * lx * lz
        && y.dot(z).abs() <= tol * ly * lz
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The suite's disk: scale (1.5, 2.5, 1), then a rotation, then a translation.
    fn ellipse() -> Affine {
        let r = Mat3::from_rotation_x(-0.6) * Mat3::from_rotation_y(0.4);
        Affine::new(
            r * Mat3::from_diagonal(Vec3::new(1.5, 2.5, 1.0)),
            Vec3::new(0.0, 2.5, -2.0),
        )
    }

    #[test]
    fn disk_hit_at_known_distance_uv_and_normal() {
        let w = ellipse();
        let obj = w.inverse();
        // Aim at the object point (0, 0.5, 0): r = 0.5, φ = π/2.
        let target = w.point(Vec3::new(0.0, 0.5, 0.0));
        let n = obj.row(2).normalize();
        let o = target + 3.0 * n + 0.2 * w.m.x_axis.normalize();
        let d = (target - o).normalize();
        let t = intersect_disk(o, d, f32::INFINITY, &obj);
        assert!((t - (target - o).length()).abs() < 1e-5, "t = {t}");
        let h = disk_at(obj.point(o + t * d), &w, &obj);
        assert!(
            (h.uv - Vec2::new(0.5, 0.25)).abs().max_element() < 1e-5,
            "{:?}",
            h.uv
        );
        assert!((h.n - n).length() < 1e-6);
        // ∂p/∂u is the map of (cos φ, sin φ, 0) = (0, 1, 0): the scaled y axis.
        assert!((h.dpdu - w.m.y_axis).length() < 1e-5);
        // Perpendicular to every in-plane direction.
        assert!(h.n.dot(w.m.x_axis).abs() < 1e-6 && h.n.dot(w.m.y_axis).abs() < 1e-6);
        // From the hit, leaving on either side: no self-intersection.
        let from = crate::geometry::offset_ray_origin(h.p, h.p_err, h.n, n);
        assert_eq!(intersect_disk(from, n, f32::INFINITY, &obj), f32::INFINITY);
        let from = crate::geometry::offset_ray_origin(h.p, h.p_err, h.n, -n);
        assert_eq!(intersect_disk(from, -n, f32::INFINITY, &obj), f32::INFINITY);
    }

    #[test]
    fn disk_grazing_and_rim_misses() {
        let w = ellipse();
        let obj = w.inverse();
        // In the plane: never a hit.
        let o = w.point(Vec3::new(-3.0, 0.0, 0.0));
        assert_eq!(
            intersect_disk(o, w.m.x_axis.normalize(), f32::INFINITY, &obj),
            f32::INFINITY
        );
        // Just outside the rim (object r = 1.001).
        let n = obj.row(2).normalize();
        let p = w.point(Vec3::new(1.001, 0.0, 0.0));
        assert_eq!(
            intersect_disk(p + n, -n, f32::INFINITY, &obj),
            f32::INFINITY
        );
        let p = w.point(Vec3::new(0.999, 0.0, 0.0));
        assert!(intersect_disk(p + n, -n, f32::INFINITY, &obj).is_finite());
    }

    /// Radius 1.5, length 2, rotated and moved: the suite's cylinder.
    fn tube() -> Affine {
        let r = Mat3::from_rotation_x(-0.6) * Mat3::from_rotation_y(0.4);
        Affine::new(
            r * Mat3::from_diagonal(Vec3::new(1.5, 1.5, 2.0)),
            Vec3::new(0.0, -2.0, -2.0),
        )
    }

    #[test]
    fn cylinder_hit_at_known_distance_uv_and_normal() {
        let w = tube();
        let obj = w.inverse();
        // Object point (0, 1, 0.25): φ = π/2, outward normal R·(0, 1, 0).
        let target = w.point(Vec3::new(0.0, 1.0, 0.25));
        let out = (w.m * Vec3::Y).normalize();
        let o = target + 4.0 * out;
        let t = intersect_cylinder(o, -out, f32::INFINITY, &obj);
        assert!((t - 4.0).abs() < 1e-5, "t = {t}");
        let h = cylinder_at(obj.point(o - t * out), &w);
        assert!(
            (h.uv - Vec2::new(0.25, 0.25)).abs().max_element() < 1e-5,
            "{:?}",
            h.uv
        );
        assert!((h.n - out).length() < 1e-5, "{:?}", h.n);
        assert!((h.p - target).length() < 1e-5);
        // ∂p/∂u = M 2π (−1, 0, 0).
        assert!((h.dpdu + 2.0 * PI * w.m.x_axis).length() < 1e-4);
        // Leaving outward: nothing. Going inward: the far side, 2 r = 3 away.
        let from = crate::geometry::offset_ray_origin(h.p, h.p_err, h.n, out);
        assert_eq!(
            intersect_cylinder(from, out, f32::INFINITY, &obj),
            f32::INFINITY
        );
        let from = crate::geometry::offset_ray_origin(h.p, h.p_err, h.n, -out);
        let t = intersect_cylinder(from, -out, f32::INFINITY, &obj);
        assert!((t - 3.0).abs() < 1e-5, "t = {t}");
        // Open: a ray down the axis hits nothing; t_max is honoured.
        let axis = w.m.z_axis.normalize();
        assert_eq!(
            intersect_cylinder(w.t - axis, axis, f32::INFINITY, &obj),
            f32::INFINITY
        );
        assert_eq!(intersect_cylinder(o, -out, 3.9, &obj), f32::INFINITY);
    }

    #[test]
    fn cylinder_grazing_misses_and_ends_bound_it() {
        let w = tube();
        let obj = w.inverse();
        let side = (w.m * Vec3::X).normalize();
        let up = w.m.z_axis.normalize();
        let along = side.cross(up);
        // Tangent line just outside the side (object radius 1.001): a miss; just inside: a hit.
        let p = w.point(Vec3::new(1.001, 0.0, 0.5));
        assert_eq!(
            intersect_cylinder(p - 5.0 * along, along, f32::INFINITY, &obj),
            f32::INFINITY
        );
        let p = w.point(Vec3::new(0.999, 0.0, 0.5));
        assert!(intersect_cylinder(p - 5.0 * along, along, f32::INFINITY, &obj).is_finite());
        // Past the end (z = 1.01): a miss.
        let p = w.point(Vec3::new(0.0, 0.0, 1.01));
        assert_eq!(
            intersect_cylinder(p - 5.0 * side, side, f32::INFINITY, &obj),
            f32::INFINITY
        );
        // The bounds hold sampled surface points.
        let (lo, hi) = cylinder_bounds(&w);
        for k in 0..64 {
            let phi = k as f32 * 0.1;
            let q = w.point(Vec3::new(phi.cos(), phi.sin(), (k % 2) as f32));
            assert!(q.cmpge(lo).all() && q.cmple(hi).all());
        }
        assert!((cylinder_area(&w) - 2.0 * PI * 1.5 * 2.0).abs() < 1e-4);
        assert!((disk_area(&ellipse()) - PI * 1.5 * 2.5).abs() < 1e-4);
    }
}

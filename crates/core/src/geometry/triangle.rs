//! Ray–triangle intersection (Möller–Trumbore) on precomputed edges.

use super::ray::Ray;
use crate::math::Vec3;

/// Returns the hit distance in (0, ray.t_max) or +∞, plus barycentrics (b1, b2) of the hit.
#[inline]
pub fn intersect_triangle(ray_o: Vec3, ray_d: Vec3, t_max: f32, p0: Vec3, e1: Vec3, e2: Vec3) -> (f32, f32, f32) {
    let pvec = ray_d.cross(e2);
    let det = e1.dot(pvec);
    if det == 0.0 || !det.is_finite() {
        return (f32::INFINITY, 0.0, 0.0);
    }
    let inv_det = 1.0 / det;
    let tvec = ray_o - p0;
    let b1 = tvec.dot(pvec) * inv_det;
    if !(0.0..=1.0).contains(&b1) {
        return (f32::INFINITY, 0.0, 0.0);
    }
    let qvec = tvec.cross(e1);
    let b2 = ray_d.dot(qvec) * inv_det;
    if b2 < 0.0 || b1 + b2 > 1.0 {
        return (f32::INFINITY, 0.0, 0.0);
    }
    let t = e2.dot(qvec) * inv_det;
    if t > 0.0 && t < t_max {
        (t, b1, b2)
    } else {
        (f32::INFINITY, 0.0, 0.0)
    }
}

/// Convenience wrapper used by tests and non-hot paths.
pub fn hit_triangle(ray: &Ray, p: [Vec3; 3]) -> Option<(f32, f32, f32)> {
    let (t, b1, b2) = intersect_triangle(ray.o, ray.d, ray.t_max, p[0], p[1] - p[0], p[2] - p[0]);
    t.is_finite().then_some((t, b1, b2))
}

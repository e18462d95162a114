//! Exact analytic sphere intersection. The quadratic is solved in the form that stays accurate
//! when the ray starts far from a small sphere (Haines et al., "Precision Improvements for
//! Ray/Sphere Intersection", Ray Tracing Gems ch. 7), and the hit is re-projected onto the sphere.

use super::soa::{soa_chunks, CHUNK};
use crate::math::{gamma, Vec3};

/// Nearest hit distance in (0, t_max) of a unit-direction ray, or +∞.
#[inline]
pub fn intersect_sphere(o: Vec3, d: Vec3, t_max: f32, center: Vec3, radius: f32) -> f32 {
    let f = o - center;
    let b = f.dot(d);
    // Distance² from the centre to the line, computed without cancellation.
    let l = f - b * d;
    let disc = radius * radius - l.length_squared();
    if disc < 0.0 {
        return f32::INFINITY;
    }
    let c = f.length_squared() - radius * radius;
    let q = -b - disc.sqrt().copysign(b);
    let (mut t0, mut t1) = (if q != 0.0 { c / q } else { 0.0 }, q);
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    if t0 > 0.0 && t0 < t_max {
        t0
    } else if t1 > 0.0 && t1 < t_max {
        t1
    } else {
        f32::INFINITY
    }
}

/// Spheres in structure-of-arrays form (centre x, y, z, radius) in chunks of `CHUNK`, for the
/// flat ray core (`flat.rs`): `distances` runs `intersect_sphere` without branches over a chunk in
/// one loop the compiler vectorises, bit for bit the scalar result.
#[derive(Clone, Debug, Default)]
pub struct SphereSoa {
    chunks: Vec<[[f32; CHUNK]; 4]>,
}

impl SphereSoa {
    /// The spheres (centre, radius), the last chunk padded with NaN centres, which never hit.
    pub fn new(spheres: &[(Vec3, f32)]) -> SphereSoa {
        let chunks = soa_chunks(spheres, |&(c, r)| [c.x, c.y, c.z, r]);
        SphereSoa { chunks }
    }

    /// Per sphere i in `start..start + W` (as `QuadSoa::distances`), `intersect_sphere(o, d,
    /// t_max, centre_i, radius_i)`.
    #[inline(always)]
    pub fn distances<const W: usize>(
        &self,
        start: usize,
        o: Vec3,
        d: Vec3,
        t_max: f32,
    ) -> [f32; W] {
        let ([cx, cy, cz, r], l) = (&self.chunks[start / CHUNK], start % CHUNK);
        let mut out = [0.0; W];
        for (i, t) in out.iter_mut().enumerate() {
            *t = distance(
                o,
                d,
                t_max,
                Vec3::new(cx[l + i], cy[l + i], cz[l + i]),
                r[l + i],
            );
        }
        out
    }
}

/// `intersect_sphere` without branches: both roots and every comparison are evaluated, then
/// selected, with NaN comparing false as in the branching version.
#[inline(always)]
fn distance(o: Vec3, d: Vec3, t_max: f32, center: Vec3, radius: f32) -> f32 {
    let f = o - center;
    let b = f.dot(d);
    let l = f - b * d;
    let disc = radius * radius - l.length_squared();
    let c = f.length_squared() - radius * radius;
    let q = -b - disc.sqrt().copysign(b);
    let t0 = if q != 0.0 { c / q } else { 0.0 };
    let t1 = q;
    let swap = t0 > t1;
    let (near, far) = if swap { (t1, t0) } else { (t0, t1) };
    let near_ok = (near > 0.0) & (near < t_max);
    let far_ok = (far > 0.0) & (far < t_max);
    let t = if near_ok { near } else { far };
    if !(disc < 0.0) & (near_ok | far_ok) {
        t
    } else {
        f32::INFINITY
    }
}

/// Projects a computed hit point back onto the sphere and bounds its error per axis.
pub fn refine_sphere_hit(p: Vec3, center: Vec3, radius: f32) -> (Vec3, Vec3) {
    let local = p - center;
    let len = local.length();
    let local = if len > 0.0 {
        local * (radius / len)
    } else {
        Vec3::new(0.0, 0.0, radius)
    };
    let p = center + local;
    let err = (local.abs() + center.abs()) * gamma(6);
    (p, err)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_a_tiny_far_sphere_accurately() {
        let c = Vec3::new(0.0, 0.0, 1e5);
        let r = 1e-2;
        let t = intersect_sphere(Vec3::ZERO, Vec3::Z, f32::INFINITY, c, r);
        assert!((t - (1e5 - 1e-2)).abs() < 1e-2 * 1e-2, "t = {t}");
    }

    #[test]
    fn inside_ray_hits_the_far_side() {
        let t = intersect_sphere(Vec3::ZERO, Vec3::X, f32::INFINITY, Vec3::ZERO, 2.0);
        assert!((t - 2.0).abs() < 1e-6);
    }
}

//! Rays and robust spawning of secondary rays from surface points.
//!
//! Self-intersection is avoided with floating-point error bounds (pbrt-v4, §6.8): every hit point
//! carries a conservative bound `p_err` on its rounding error, and a new ray starts just outside
//! that box along the geometric normal. The offset therefore scales with the magnitude of the hit
//! point, so the same code works for scenes measured in millimetres or in thousands of kilometres.

use crate::math::{gamma, Vec3};

#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub o: Vec3,
    /// Unit direction.
    pub d: Vec3,
    pub t_max: f32,
}

impl Ray {
    pub fn new(o: Vec3, d: Vec3) -> Ray {
        Ray {
            o,
            d,
            t_max: f32::INFINITY,
        }
    }
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }
}

/// A shadow ray stops this fraction short of its target so the target's own surface is not hit.
/// It is relative to the segment length, so it is the same at every scene scale.
pub const SHADOW_EPSILON: f32 = 1e-4;

/// Moves `p` (with per-axis error bound `p_err`) off the surface with geometric normal `ng`, to the
/// side that `w` points into, far enough that the new origin is provably on that side.
pub fn offset_ray_origin(p: Vec3, p_err: Vec3, ng: Vec3, w: Vec3) -> Vec3 {
    let d = ng.abs().dot(p_err);
    let mut offset = d * ng;
    if w.dot(ng) < 0.0 {
        offset = -offset;
    }
    let po = p + offset;
    // Push each moved coordinate at least one ulp further from p, so the rounding of the addition
    // cannot pull the point back into the error box (a branch-free stand-in for next-float-up/down).
    let away = Vec3::select(offset.cmpeq(Vec3::ZERO), Vec3::ZERO, offset.signum());
    po + away * (po.abs() * f32::EPSILON + Vec3::splat(f32::MIN_POSITIVE))
}

/// Error bound of a point computed as a sum of three products b_i·p_i (triangle barycentrics).
pub fn barycentric_error(b: [f32; 3], p: [Vec3; 3]) -> Vec3 {
    ((b[0] * p[0]).abs() + (b[1] * p[1]).abs() + (b[2] * p[2]).abs()) * gamma(7)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_leaves_the_error_box_on_the_requested_side() {
        for scale in [1e-3f32, 1.0, 1e3, 1e6] {
            let p = Vec3::new(0.3, 0.7, -0.2) * scale;
            let err = p.abs() * gamma(7);
            let n = Vec3::new(0.0, 1.0, 0.0);
            let up = offset_ray_origin(p, err, n, Vec3::new(0.1, 0.9, 0.0));
            let down = offset_ray_origin(p, err, n, Vec3::new(0.1, -0.9, 0.0));
            assert!(
                up.y > p.y + err.y * 0.999 && down.y < p.y - err.y * 0.999,
                "scale {scale}"
            );
            // Offsets stay tiny relative to the scene scale.
            assert!((up - p).length() < 1e-5 * scale);
        }
    }
}

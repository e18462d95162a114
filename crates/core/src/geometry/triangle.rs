//! Watertight ray–triangle intersection (Woop, Benthin & Wald, "Watertight Ray/Triangle
//! Intersection", JCGT 2013). The ray is sheared so it runs along +z from the origin; the three
//! 2-D edge functions are then evaluated exactly enough that a ray through a shared edge or vertex
//! hits at least one of the triangles sharing it (Möller–Trumbore lets such rays slip through).

use crate::math::{gamma, Vec3};

/// The per-ray part of the test, computed once and reused for every triangle the ray meets.
#[derive(Clone, Copy, Debug)]
pub struct ShearedRay {
    pub(super) o: Vec3,
    pub(super) k: [usize; 3],
    pub(super) s: Vec3,
}

impl ShearedRay {
    /// Placeholder for rays that will meet no triangle.
    pub const UNUSED: ShearedRay = ShearedRay {
        o: Vec3::ZERO,
        k: [0, 1, 2],
        s: Vec3::ZERO,
    };

    pub fn new(o: Vec3, d: Vec3) -> ShearedRay {
        let a = d.abs();
        let kz = if a.x > a.y {
            if a.x > a.z {
                0
            } else {
                2
            }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        // Keep the winding: swapping x and y mirrors the shear when the dominant axis is negative.
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        ShearedRay {
            o,
            k: [kx, ky, kz],
            s: Vec3::new(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]),
        }
    }
}

/// Returns the hit distance in (0, t_max) or +∞, plus barycentrics (b0, b1, b2) of p0, p1, p2.
#[inline]
pub fn intersect_triangle(r: &ShearedRay, t_max: f32, p: &[Vec3; 3]) -> (f32, [f32; 3]) {
    const MISS: (f32, [f32; 3]) = (f32::INFINITY, [0.0; 3]);
    let [kx, ky, kz] = r.k;
    let a = p[0] - r.o;
    let b = p[1] - r.o;
    let c = p[2] - r.o;
    let (ax, ay) = (a[kx] - r.s.x * a[kz], a[ky] - r.s.y * a[kz]);
    let (bx, by) = (b[kx] - r.s.x * b[kz], b[ky] - r.s.y * b[kz]);
    let (cx, cy) = (c[kx] - r.s.x * c[kz], c[ky] - r.s.y * c[kz]);
    let mut u = cx * by - cy * bx;
    let mut v = ax * cy - ay * cx;
    let mut w = bx * ay - by * ax;
    // An edge function that rounds to exactly zero is re-evaluated in double precision, which
    // decides the edge case consistently for both triangles sharing the edge.
    if u == 0.0 || v == 0.0 || w == 0.0 {
        u = (cx as f64 * by as f64 - cy as f64 * bx as f64) as f32;
        v = (ax as f64 * cy as f64 - ay as f64 * cx as f64) as f32;
        w = (bx as f64 * ay as f64 - by as f64 * ax as f64) as f32;
    }
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return MISS;
    }
    let det = u + v + w;
    if det == 0.0 || !det.is_finite() {
        return MISS;
    }
    let (az, bz, cz) = (r.s.z * a[kz], r.s.z * b[kz], r.s.z * c[kz]);
    let t_scaled = u * az + v * bz + w * cz;
    // Compare t against (0, t_max) before dividing, with the sign of det folded in.
    let hit = if det < 0.0 {
        t_scaled < 0.0 && t_scaled > t_max * det
    } else {
        t_scaled > 0.0 && t_scaled < t_max * det
    };
    if !hit {
        return MISS;
    }
    let inv = 1.0 / det;
    let t = t_scaled * inv;
    // A ray leaving a surface point that lies exactly on the plane (zero error bound, so zero
    // offset) would otherwise re-hit it at a rounding-sized t. Reject t within the conservative
    // rounding bound of the computation above (pbrt-v4 §6.8.7, after Woop et al.).
    let max_z = az.abs().max(bz.abs()).max(cz.abs());
    let max_x = ax.abs().max(bx.abs()).max(cx.abs());
    let max_y = ay.abs().max(by.abs()).max(cy.abs());
    let delta_z = gamma(3) * max_z;
    let delta_x = gamma(5) * (max_x + max_z);
    let delta_y = gamma(5) * (max_y + max_z);
    let delta_e = 2.0 * (gamma(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    let max_e = u.abs().max(v.abs()).max(w.abs());
    let delta_t = 3.0 * (gamma(3) * max_e * max_z + delta_e * max_z + delta_z * max_e) * inv.abs();
    if t <= delta_t {
        return MISS;
    }
    (t, [u * inv, v * inv, w * inv])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{sample_uniform_sphere, Sampler};

    #[test]
    fn rays_through_a_shared_edge_never_slip_between_the_triangles() {
        // A quad split along its diagonal; rays aimed exactly at points of the diagonal.
        let q = [
            Vec3::new(-1.0, -1.0, 0.3),
            Vec3::new(1.0, -1.0, 0.3),
            Vec3::new(1.0, 1.0, 0.3),
            Vec3::new(-1.0, 1.0, 0.3),
        ];
        let (t1, t2) = ([q[0], q[1], q[2]], [q[0], q[2], q[3]]);
        let mut s = Sampler::new(5, 0, 0);
        for _ in 0..20_000 {
            let target = q[0].lerp(q[2], s.next_f32());
            let o = target + sample_uniform_sphere(s.next_2d()) * (0.1 + 10.0 * s.next_f32());
            let d = (target - o).normalize();
            let r = ShearedRay::new(o, d);
            let hit = intersect_triangle(&r, f32::INFINITY, &t1).0.is_finite()
                || intersect_triangle(&r, f32::INFINITY, &t2).0.is_finite();
            assert!(
                hit,
                "ray from {o} towards {target} slipped through the diagonal"
            );
        }
    }

    #[test]
    fn rays_leaving_a_triangle_on_a_coordinate_plane_do_not_rehit_it() {
        // On y = 0 the hit point is exact, its error bound is zero and so is the origin offset.
        let p = [
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(0.0, 0.0, 1.0),
        ];
        let mut s = Sampler::new(9, 0, 0);
        for _ in 0..20_000 {
            let o = Vec3::new(s.next_f32() - 0.5, 0.0, s.next_f32() - 0.5) * 0.8;
            let mut d = sample_uniform_sphere(s.next_2d());
            d.y = d.y.abs();
            let t = intersect_triangle(&ShearedRay::new(o, d), f32::INFINITY, &p).0;
            assert!(t.is_infinite(), "re-hit at t = {t} from {o} along {d}");
        }
    }

    #[test]
    fn barycentrics_reconstruct_the_hit_point() {
        let p = [
            Vec3::new(0.0, 0.0, 2.0),
            Vec3::new(1.0, 0.0, 2.0),
            Vec3::new(0.0, 1.0, 2.5),
        ];
        let o = Vec3::new(0.2, 0.3, -1.0);
        let d = (Vec3::new(0.25, 0.25, 2.125) - o).normalize();
        let (t, b) = intersect_triangle(&ShearedRay::new(o, d), f32::INFINITY, &p);
        let from_b = b[0] * p[0] + b[1] * p[1] + b[2] * p[2];
        assert!(
            (o + d * t - from_b).length() < 1e-5
                && (from_b - Vec3::new(0.25, 0.25, 2.125)).length() < 1e-5
        );
        assert!(intersect_triangle(&ShearedRay::new(o, d), t * 0.999, &p)
            .0
            .is_infinite());
        assert!(
            intersect_triangle(&ShearedRay::new(o, -d), f32::INFINITY, &p)
                .0
                .is_infinite()
        );
    }
}

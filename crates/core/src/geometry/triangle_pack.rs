//! Eight triangles against one ray at once: the wide BVH's leaves (`wide.rs`). Each lane performs
//! `triangle::intersect_triangle`'s IEEE operations in its order (Rust neither fuses nor
//! reassociates them), so a lane's distance is the scalar test's bit for bit. The one branch the
//! lanes cannot share — an edge function that rounds to exactly zero, re-evaluated in double
//! precision — sends that lane to the scalar test itself.

use super::triangle::{intersect_triangle, ShearedRay};
use crate::math::{gamma, Vec3};

/// Triangles per pack: one AVX2 vector, two SSE ones.
pub const PACK: usize = 8;

/// Up to `PACK` triangles component by component: `v[3 j + axis][lane]` is coordinate `axis` of
/// vertex j. Empty lanes hold NaN, which every comparison of the test rejects.
#[derive(Clone, Debug)]
pub struct TrianglePack {
    v: [[f32; PACK]; 9],
}

impl TrianglePack {
    pub fn new(triangles: &[[Vec3; 3]]) -> TrianglePack {
        assert!(triangles.len() <= PACK);
        let mut v = [[f32::NAN; PACK]; 9];
        for (lane, p) in triangles.iter().enumerate() {
            for (j, vertex) in p.iter().enumerate() {
                for axis in 0..3 {
                    v[3 * j + axis][lane] = vertex[axis];
                }
            }
        }
        TrianglePack { v }
    }

    fn vertices(&self, lane: usize) -> [Vec3; 3] {
        let c = |j: usize| {
            Vec3::new(
                self.v[3 * j][lane],
                self.v[3 * j + 1][lane],
                self.v[3 * j + 2][lane],
            )
        };
        [c(0), c(1), c(2)]
    }

    /// Each lane's `intersect_triangle(r, t_max, p).0`: its distance in (0, t_max), or +∞.
    #[inline(always)]
    pub fn distances(&self, r: &ShearedRay, t_max: f32) -> [f32; PACK] {
        let [kx, ky, kz] = r.k;
        let (o, s) = (r.o, r.s);
        // The vertex coordinates relative to the origin along the shear's axes, as
        // `a = p[0] - r.o; a[kx]` computes them.
        let rel = |j: usize, k: usize| -> [f32; PACK] {
            let row = &self.v[3 * j + k];
            std::array::from_fn(|i| row[i] - o[k])
        };
        let (ax_, ay_, az_) = (rel(0, kx), rel(0, ky), rel(0, kz));
        let (bx_, by_, bz_) = (rel(1, kx), rel(1, ky), rel(1, kz));
        let (cx_, cy_, cz_) = (rel(2, kx), rel(2, ky), rel(2, kz));
        // Stage 1, the sheared vertices and edge functions; most packs stop here, every lane
        // outside its triangle (the scalar test's first early exit).
        let mut sx = [[0.0f32; PACK]; 6]; // ax, ay, bx, by, cx, cy
        let mut e = [[0.0f32; PACK]; 3]; // u, v, w
        let (mut zero_edge, mut inside) = (0u32, 0u32);
        for i in 0..PACK {
            let (ax, ay) = (ax_[i] - s.x * az_[i], ay_[i] - s.y * az_[i]);
            let (bx, by) = (bx_[i] - s.x * bz_[i], by_[i] - s.y * bz_[i]);
            let (cx, cy) = (cx_[i] - s.x * cz_[i], cy_[i] - s.y * cz_[i]);
            let u = cx * by - cy * bx;
            let v = ax * cy - ay * cx;
            let w = bx * ay - by * ax;
            let mixed = ((u < 0.0) | (v < 0.0) | (w < 0.0)) & ((u > 0.0) | (v > 0.0) | (w > 0.0));
            zero_edge |= (((u == 0.0) | (v == 0.0) | (w == 0.0)) as u32) << i;
            inside |= (!mixed as u32) << i;
            [sx[0][i], sx[1][i], sx[2][i], sx[3][i], sx[4][i], sx[5][i]] = [ax, ay, bx, by, cx, cy];
            [e[0][i], e[1][i], e[2][i]] = [u, v, w];
        }
        let mut t_out = [f32::INFINITY; PACK];
        if inside & !zero_edge != 0 {
            for i in 0..PACK {
                let [ax, ay, bx, by, cx, cy] = sx.map(|row| row[i]);
                let [u, v, w] = e.map(|row| row[i]);
                let det = u + v + w;
                let degenerate = (det == 0.0) | !det.is_finite();
                let (az, bz, cz) = (s.z * az_[i], s.z * bz_[i], s.z * cz_[i]);
                let t_scaled = u * az + v * bz + w * cz;
                let in_range = if det < 0.0 {
                    (t_scaled < 0.0) & (t_scaled > t_max * det)
                } else {
                    (t_scaled > 0.0) & (t_scaled < t_max * det)
                };
                let inv = 1.0 / det;
                let t = t_scaled * inv;
                // The rounding bound below which a hit is a re-hit of the origin's own surface
                // (pbrt-v4 §6.8.7), as in the scalar test.
                let max_z = az.abs().max(bz.abs()).max(cz.abs());
                let max_x = ax.abs().max(bx.abs()).max(cx.abs());
                let max_y = ay.abs().max(by.abs()).max(cy.abs());
                let delta_z = gamma(3) * max_z;
                let delta_x = gamma(5) * (max_x + max_z);
                let delta_y = gamma(5) * (max_y + max_z);
                let delta_e = 2.0 * (gamma(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
                let max_e = u.abs().max(v.abs()).max(w.abs());
                let delta_t = 3.0
                    * (gamma(3) * max_e * max_z + delta_e * max_z + delta_z * max_e)
                    * inv.abs();
                let hit = ((inside >> i) & 1 != 0) & !degenerate & in_range & !(t <= delta_t);
                t_out[i] = if hit { t } else { f32::INFINITY };
            }
        }
        // Lanes whose edge function rounded to zero take the scalar test's double-precision path.
        while zero_edge != 0 {
            let i = zero_edge.trailing_zeros() as usize;
            zero_edge &= zero_edge - 1;
            t_out[i] = intersect_triangle(r, t_max, &self.vertices(i)).0;
        }
        t_out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{sample_uniform_sphere, Sampler};

    /// Every lane gives the scalar test's distance bit for bit: random triangles at scales 1e-3 to
    /// 1e6, rays from random points and from the triangles themselves (re-hit rejection), rays
    /// through vertices (zero edge functions), some with a finite t_max.
    #[test]
    fn each_lane_is_the_scalar_triangle_test_bit_for_bit() {
        let mut s = Sampler::new(11, 0, 0);
        let mut hits = 0;
        for scale in [1e-3f32, 1.0, 1e6] {
            for _ in 0..400 {
                let n = 1 + (s.next_f32() * PACK as f32) as usize % PACK;
                let tris: Vec<[Vec3; 3]> = (0..n)
                    .map(|_| {
                        let c = (s.next_2d().extend(s.next_f32()) - 0.5) * 4.0 * scale;
                        [
                            c,
                            c + sample_uniform_sphere(s.next_2d()) * scale,
                            c + sample_uniform_sphere(s.next_2d()) * scale,
                        ]
                    })
                    .collect();
                let pack = TrianglePack::new(&tris);
                for k in 0..16 {
                    let p = tris[k % n];
                    let (o, target) = match k % 4 {
                        0 => (
                            (s.next_2d().extend(s.next_f32()) - 0.5) * 8.0 * scale,
                            p[k % 3],
                        ),
                        1 => (
                            0.2 * p[0] + 0.3 * p[1] + 0.5 * p[2],
                            (s.next_2d().extend(s.next_f32()) - 0.5) * 8.0 * scale,
                        ),
                        _ => (
                            (s.next_2d().extend(s.next_f32()) - 0.5) * 8.0 * scale,
                            0.3 * p[0] + 0.3 * p[1] + 0.4 * p[2],
                        ),
                    };
                    let d = (target - o).normalize();
                    if !d.is_finite() {
                        continue;
                    }
                    let t_max = if k % 5 == 0 {
                        4.0 * scale * s.next_f32()
                    } else {
                        f32::INFINITY
                    };
                    let r = ShearedRay::new(o, d);
                    let lanes = pack.distances(&r, t_max);
                    for (i, tri) in tris.iter().enumerate() {
                        let t = intersect_triangle(&r, t_max, tri).0;
                        hits += t.is_finite() as usize;
                        assert_eq!(
                            lanes[i].to_bits(),
                            t.to_bits(),
                            "lane {i}, scale {scale}, o {o}, d {d}"
                        );
                    }
                    assert!(lanes[n..].iter().all(|t| t.is_infinite()));
                }
            }
        }
        assert!(hits > 5000, "only {hits} hits");
    }
}

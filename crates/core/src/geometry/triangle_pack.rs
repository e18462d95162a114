//! Eight triangles against one ray at once: the wide BVH's leaves (`wide.rs`). The vectorised
//! part is the watertight test's first stage — shear the vertices, evaluate the three edge
//! functions, reject lanes whose signs differ — with each lane performing
//! `triangle::intersect_triangle`'s IEEE operations in its order (Rust and the intrinsics neither
//! fuse nor reassociate them), so a lane it rejects is one the scalar test rejects. The few
//! lanes left (the ray passes inside the triangle, or an edge function rounded to exactly zero and
//! the scalar test would re-evaluate it in double precision) are finished by `intersect_triangle`
//! itself, so every distance is the scalar test's bit for bit.

use super::triangle::{intersect_triangle, ShearedRay};
use crate::math::Vec3;

/// Triangles per pack: one AVX2 vector, two SSE ones.
pub const PACK: usize = 8;

/// Up to `PACK` triangles component by component: `v[3 j + axis][lane]` is coordinate `axis` of
/// vertex j. Empty lanes hold NaN and are masked out by `lanes`.
#[derive(Clone, Debug)]
pub struct TrianglePack {
    v: [[f32; PACK]; 9],
    /// A bit per occupied lane.
    lanes: u32,
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
        TrianglePack {
            v,
            lanes: (1u32 << triangles.len()) - 1,
        }
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

    /// Each lane's `intersect_triangle(r, t_max, p).0`: its distance in (0, t_max), or +∞, with
    /// the first stage in portable loops.
    #[inline(always)]
    pub fn distances(&self, r: &ShearedRay, t_max: f32) -> [f32; PACK] {
        self.finish(r, t_max, self.candidates(r))
    }

    /// `distances` with the first stage in AVX2 intrinsics.
    ///
    /// # Safety
    /// The CPU must run AVX2.
    #[cfg(target_arch = "x86_64")]
    #[inline]
    #[target_feature(enable = "avx2")]
    pub unsafe fn distances_avx2(&self, r: &ShearedRay, t_max: f32) -> [f32; PACK] {
        self.finish(r, t_max, self.candidates_avx2(r))
    }

    /// The scalar test on the lanes in `candidates`; +∞ elsewhere.
    #[inline(always)]
    fn finish(&self, r: &ShearedRay, t_max: f32, mut candidates: u32) -> [f32; PACK] {
        let mut t = [f32::INFINITY; PACK];
        while candidates != 0 {
            let lane = candidates.trailing_zeros() as usize;
            candidates &= candidates - 1;
            t[lane] = intersect_triangle(r, t_max, &self.vertices(lane)).0;
        }
        t
    }

    /// The occupied lanes the first stage does not reject: edge functions not of mixed sign, or
    /// one of them exactly zero.
    #[inline(always)]
    fn candidates(&self, r: &ShearedRay) -> u32 {
        let [kx, ky, kz] = r.k;
        let (o, s) = (r.o, r.s);
        let row = |j: usize, k: usize| &self.v[3 * j + k];
        let (pax, pay, paz) = (row(0, kx), row(0, ky), row(0, kz));
        let (pbx, pby, pbz) = (row(1, kx), row(1, ky), row(1, kz));
        let (pcx, pcy, pcz) = (row(2, kx), row(2, ky), row(2, kz));
        let mut keep = 0u32;
        for i in 0..PACK {
            // a = p[0] − o, then a[kx] − s.x · a[kz], …, as the scalar test.
            let (az, bz, cz) = (paz[i] - o[kz], pbz[i] - o[kz], pcz[i] - o[kz]);
            let (ax, ay) = ((pax[i] - o[kx]) - s.x * az, (pay[i] - o[ky]) - s.y * az);
            let (bx, by) = ((pbx[i] - o[kx]) - s.x * bz, (pby[i] - o[ky]) - s.y * bz);
            let (cx, cy) = ((pcx[i] - o[kx]) - s.x * cz, (pcy[i] - o[ky]) - s.y * cz);
            let u = cx * by - cy * bx;
            let v = ax * cy - ay * cx;
            let w = bx * ay - by * ax;
            let mixed = ((u < 0.0) | (v < 0.0) | (w < 0.0)) & ((u > 0.0) | (v > 0.0) | (w > 0.0));
            let zero = (u == 0.0) | (v == 0.0) | (w == 0.0);
            keep |= ((!mixed | zero) as u32) << i;
        }
        keep & self.lanes
    }

    /// `candidates` in AVX2 intrinsics: the same operations on the same operands, in the same
    /// order, so the same lanes.
    #[cfg(target_arch = "x86_64")]
    #[inline]
    #[target_feature(enable = "avx2")]
    fn candidates_avx2(&self, r: &ShearedRay) -> u32 {
        use std::arch::x86_64::*;
        let [kx, ky, kz] = r.k;
        let (o, s) = (r.o, r.s);
        // SAFETY: each row is PACK = 8 contiguous f32.
        let load = |j: usize, k: usize| unsafe { _mm256_loadu_ps(self.v[3 * j + k].as_ptr()) };
        let (sx, sy) = (_mm256_set1_ps(s.x), _mm256_set1_ps(s.y));
        let (ox, oy, oz) = (
            _mm256_set1_ps(o[kx]),
            _mm256_set1_ps(o[ky]),
            _mm256_set1_ps(o[kz]),
        );
        let shear = |j: usize| {
            let z = _mm256_sub_ps(load(j, kz), oz);
            let x = _mm256_sub_ps(_mm256_sub_ps(load(j, kx), ox), _mm256_mul_ps(sx, z));
            let y = _mm256_sub_ps(_mm256_sub_ps(load(j, ky), oy), _mm256_mul_ps(sy, z));
            (x, y)
        };
        let ((ax, ay), (bx, by), (cx, cy)) = (shear(0), shear(1), shear(2));
        let edge = |p: __m256, q: __m256, r: __m256, t: __m256| {
            _mm256_sub_ps(_mm256_mul_ps(p, q), _mm256_mul_ps(r, t))
        };
        let u = edge(cx, by, cy, bx);
        let v = edge(ax, cy, ay, cx);
        let w = edge(bx, ay, by, ax);
        let zero = _mm256_setzero_ps();
        let any = |f: fn(__m256, __m256) -> __m256| {
            _mm256_or_ps(_mm256_or_ps(f(u, zero), f(v, zero)), f(w, zero))
        };
        let neg = any(|a, b| _mm256_cmp_ps::<_CMP_LT_OQ>(a, b));
        let pos = any(|a, b| _mm256_cmp_ps::<_CMP_GT_OQ>(a, b));
        let is_zero = any(|a, b| _mm256_cmp_ps::<_CMP_EQ_OQ>(a, b));
        let mixed = _mm256_movemask_ps(_mm256_and_ps(neg, pos)) as u32;
        let zeros = _mm256_movemask_ps(is_zero) as u32;
        (!mixed | zeros) & self.lanes
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
                    #[cfg(target_arch = "x86_64")]
                    if std::arch::is_x86_feature_detected!("avx2") {
                        // SAFETY: checked just above.
                        let avx2 = unsafe { pack.distances_avx2(&r, t_max) };
                        assert_eq!(avx2.map(f32::to_bits), lanes.map(f32::to_bits));
                    }
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

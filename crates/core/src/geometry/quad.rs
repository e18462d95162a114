//! Analytic parallelograms. Mitsuba-style rectangles and cube faces arrive as two-triangle meshes;
//! the scene builder recognises each such pair and intersects it as one parallelogram: one plane
//! test and two dot products instead of two sheared triangle tests, and no diagonal seam.
//!
//! The parameter bounds are widened by the rounding bound of the hit point, so neighbouring
//! parallelograms (a box's faces) overlap by rounding-sized slivers instead of leaving cracks,
//! and hits within the rounding bound of the origin's own plane are rejected (no self-hits).

use super::soa::{soa_chunks, CHUNK};
use crate::math::{gamma, Vec3};

/// p0 + u·e1 + v·e2 for (u, v) in [0, 1]².
#[derive(Clone, Copy, Debug)]
pub struct Parallelogram {
    pub p0: Vec3,
    pub e1: Vec3,
    pub e2: Vec3,
    /// (e1 × e2) / |e1 × e2|²: the plane normal scaled so that the dual basis below is exact.
    n: Vec3,
    /// The dual basis e2 × n, n × e1 (see `dual`), computed once here rather than per ray test:
    /// the same operations on the same values, so every result keeps its bits.
    a1: Vec3,
    a2: Vec3,
}

impl Parallelogram {
    pub fn new(p0: Vec3, e1: Vec3, e2: Vec3) -> Parallelogram {
        let n = e1.cross(e2);
        let n = n / n.length_squared();
        Parallelogram {
            p0,
            e1,
            e2,
            n,
            a1: e2.cross(n),
            a2: n.cross(e1),
        }
    }

    /// The two triangles (p0, p0+e1, p0+e1+e2) and (p0, p0+e1+e2, p0+e2), if `a` and `b` are that
    /// split of a parallelogram up to rounding (relative 1e-6 of the edge lengths).
    pub fn from_triangle_pair(a: [Vec3; 3], b: [Vec3; 3]) -> Option<Parallelogram> {
        if a[0] != b[0] || a[2] != b[1] {
            return None;
        }
        let (p0, p1, p2, p3) = (a[0], a[1], a[2], b[2]);
        let (e1, e2) = (p1 - p0, p3 - p0);
        let mismatch = (p0 + e1 + e2 - p2).length();
        let size = e1.length() + e2.length();
        (size > 0.0 && mismatch <= 1e-6 * size && e1.cross(e2).length_squared() > 0.0)
            .then(|| Parallelogram::new(p0, e1, e2))
    }

    /// Dual basis: (u, v) = (q · a1, q · a2) for q = p − p0 in the plane.
    #[inline]
    fn dual(&self) -> (Vec3, Vec3) {
        (self.a1, self.a2)
    }

    /// Parameters (u, v) of a point in the parallelogram's plane.
    #[inline]
    pub fn uv_at(&self, p: Vec3) -> (f32, f32) {
        let q = p - self.p0;
        let (a1, a2) = self.dual();
        (q.dot(a1), q.dot(a2))
    }

    /// The crossing of the ray's line with the plane at distance `t`, relative to p0, and a
    /// per-axis bound on its rounding error. Everything is computed from `o − p0`, so the bound
    /// scales with the distances involved, not with how far from the world origin the quad sits:
    /// `o − p0` rounds once (relative error u), and `d·t − (p0 − o)` adds three more roundings.
    #[inline]
    fn crossing(&self, o: Vec3, d: Vec3, t: f32) -> (Vec3, Vec3) {
        let to = self.p0 - o;
        let q = d * t - to;
        (q, (to.abs() + (d * t).abs()) * gamma(4))
    }

    /// (t, u, v) of the hit in (0, t_max), or t = +∞. Always inlined into the traversal loops
    /// (as a call, with traversal specialised by stack size, it costs a few per cent of `pt`).
    #[inline(always)]
    pub fn intersect(&self, o: Vec3, d: Vec3, t_max: f32) -> (f32, f32, f32) {
        const MISS: (f32, f32, f32) = (f32::INFINITY, 0.0, 0.0);
        let denom = d.dot(self.n);
        let to = self.p0 - o;
        let num = to.dot(self.n);
        let t = num / denom;
        if !(t > 0.0 && t < t_max) {
            return MISS;
        }
        // An origin within the rounding of its coordinates of this plane (the size of any hit
        // point's error box there) cannot be told apart from a point on it: the ray is taken to
        // leave the plane, not to cross it (no self-hits, and no hits on a neighbour that an
        // origin near a shared edge rounds onto the wrong side of).
        let num_err = gamma(3) * (self.p0.abs() + o.abs()).dot(self.n.abs());
        if num.abs() <= num_err {
            return MISS;
        }
        let (q, q_err) = self.crossing(o, d, t);
        let (a1, a2) = self.dual();
        let (u, v) = (q.dot(a1), q.dot(a2));
        // Widen by the rounding of (u, v), relative to the crossing, plus a few ulps of the
        // parameter itself for the rounding of e1, e2 and the dual basis, so that neighbours
        // sharing an edge overlap by rounding-sized slivers instead of leaving cracks.
        let (eu, ev) = (
            q_err.dot(a1.abs()) + gamma(6) * (q.abs().dot(a1.abs()) + 1.0),
            q_err.dot(a2.abs()) + gamma(6) * (q.abs().dot(a2.abs()) + 1.0),
        );
        if u < -eu || u > 1.0 + eu || v < -ev || v > 1.0 + ev {
            return MISS;
        }
        (t, u, v)
    }

    /// The hit point at ray distance `t` (from `intersect`), its parameters and a per-axis bound
    /// on its rounding error: the rounding of p0 + u·e1 + v·e2 (absolute, as any stored point), plus
    /// how far (u, v) may sit from the exact crossing (relative to the distances, see `crossing`).
    pub fn hit_point(&self, o: Vec3, d: Vec3, t: f32) -> (Vec3, Vec3, f32, f32) {
        let (q, q_err) = self.crossing(o, d, t);
        let (a1, a2) = self.dual();
        let (u, v) = (q.dot(a1), q.dot(a2));
        let p = self.p0 + u * self.e1 + v * self.e2;
        let (eu, ev) = (
            q_err.dot(a1.abs()) + gamma(4) * q.abs().dot(a1.abs()),
            q_err.dot(a2.abs()) + gamma(4) * q.abs().dot(a2.abs()),
        );
        let err = (self.p0.abs() + (u * self.e1).abs() + (v * self.e2).abs()) * gamma(5)
            + eu * self.e1.abs()
            + ev * self.e2.abs();
        (p, err, u, v)
    }
}

/// Parallelograms in structure-of-arrays form, for the flat ray core (`flat.rs`), in chunks of
/// `CHUNK` whose tests run in one fixed-length loop the compiler vectorises. Lane for lane it is
/// `Parallelogram::intersect`'s distance bit for bit: the same operations in the same order, with
/// the absolute values the test reads stored (which changes no bits) and no early outs.
#[derive(Clone, Debug, Default)]
pub struct QuadSoa {
    /// Per chunk, p0, |p0|, n, |n|, a1, |a1|, a2, |a2| component by component: `[k][i]` is
    /// component k % 3 of vector k / 3 of the chunk's parallelogram i.
    pub(super) chunks: Vec<[[f32; CHUNK]; 24]>,
}

impl QuadSoa {
    /// The parallelograms, the last chunk padded with NaN corners, which never hit (t is NaN).
    pub fn new(quads: &[Parallelogram]) -> QuadSoa {
        let chunks = soa_chunks(quads, |q| {
            let v = [
                q.p0,
                q.p0.abs(),
                q.n,
                q.n.abs(),
                q.a1,
                q.a1.abs(),
                q.a2,
                q.a2.abs(),
            ];
            std::array::from_fn(|k| v[k / 3][k % 3])
        });
        QuadSoa { chunks }
    }

    /// Per parallelogram i in `start..start + W` (`start` a multiple of `W`, `W` dividing `CHUNK`),
    /// `Parallelogram::intersect(o, d, t_max).0`. Always inlined, so it vectorises `W` wide with
    /// the target features of the caller.
    #[inline(always)]
    pub fn distances<const W: usize>(
        &self,
        start: usize,
        o: Vec3,
        o_abs: Vec3,
        d: Vec3,
        t_max: f32,
    ) -> [f32; W] {
        let (f, lane0) = (&self.chunks[start / CHUNK], start % CHUNK);
        let v = |k: usize, i: usize| {
            Vec3::new(f[k][lane0 + i], f[k + 1][lane0 + i], f[k + 2][lane0 + i])
        };
        let mut out = [0.0; W];
        for (i, t) in out.iter_mut().enumerate() {
            *t = distance(
                [
                    v(0, i),
                    v(3, i),
                    v(6, i),
                    v(9, i),
                    v(12, i),
                    v(15, i),
                    v(18, i),
                    v(21, i),
                ],
                o,
                o_abs,
                d,
                t_max,
            );
        }
        out
    }
}

/// `Parallelogram::intersect`'s distance without branches, from [p0, |p0|, n, |n|, a1, |a1|, a2,
/// |a2|]: every comparison is evaluated and combined with `&`/`|`, so a loop over many
/// parallelograms vectorises. NaN compares false here exactly as in the branching version.
#[inline(always)]
pub(super) fn distance(q: [Vec3; 8], o: Vec3, o_abs: Vec3, d: Vec3, t_max: f32) -> f32 {
    let [p0, p0_abs, n, n_abs, a1, a1_abs, a2, a2_abs] = q;
    let denom = d.dot(n);
    let to = p0 - o;
    let num = to.dot(n);
    let t = num / denom;
    let in_range = (t > 0.0) & (t < t_max);
    let num_err = gamma(3) * (p0_abs + o_abs).dot(n_abs);
    let leaves_plane = num.abs() <= num_err;
    // `crossing`, expanded.
    let dt = d * t;
    let q = dt - to;
    let q_err = (to.abs() + dt.abs()) * gamma(4);
    let (u, v) = (q.dot(a1), q.dot(a2));
    let q_abs = q.abs();
    let eu = q_err.dot(a1_abs) + gamma(6) * (q_abs.dot(a1_abs) + 1.0);
    let ev = q_err.dot(a2_abs) + gamma(6) * (q_abs.dot(a2_abs) + 1.0);
    let outside = (u < -eu) | (u > 1.0 + eu) | (v < -ev) | (v > 1.0 + ev);
    if in_range & !leaves_plane & !outside {
        t
    } else {
        f32::INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::triangle::{intersect_triangle, ShearedRay};
    use crate::sampling::{sample_uniform_sphere, Sampler};

    fn quad() -> ([Vec3; 3], [Vec3; 3]) {
        let p = [
            Vec3::new(-1.0, -0.5, 0.2),
            Vec3::new(1.0, -0.4, 0.3),
            Vec3::new(1.2, 0.8, 0.5),
            Vec3::new(-0.8, 0.7, 0.4),
        ];
        ([p[0], p[1], p[2]], [p[0], p[2], p[3]])
    }

    #[test]
    fn agrees_with_its_two_triangles() {
        let (a, b) = quad();
        let q = Parallelogram::from_triangle_pair(a, b).expect("a parallelogram");
        let mut s = Sampler::new(4, 0, 0);
        let mut hits = 0;
        for _ in 0..20_000 {
            let o = sample_uniform_sphere(s.next_2d()) * 3.0;
            // Aim at the parallelogram grown by 20 % on each side: hits, misses and edges.
            let (u, v) = (1.4 * s.next_f32() - 0.2, 1.4 * s.next_f32() - 0.2);
            let d = (q.p0 + u * q.e1 + v * q.e2 - o).normalize();
            let r = ShearedRay::new(o, d);
            let tri = intersect_triangle(&r, f32::INFINITY, &a)
                .0
                .min(intersect_triangle(&r, f32::INFINITY, &b).0);
            let (t, u, v) = q.intersect(o, d, f32::INFINITY);
            // Only rays grazing the boundary (within rounding) may disagree on hit or miss.
            let near_edge = [u, v]
                .iter()
                .any(|x| x.abs() < 1e-5 || (x - 1.0).abs() < 1e-5);
            if tri.is_finite() != t.is_finite() {
                assert!(near_edge, "disagree: tri {tri} quad {t}");
                continue;
            }
            if t.is_finite() {
                hits += 1;
                // Both distances are ill-conditioned at grazing incidence, like 1/|cos θ|.
                let cos = d.dot(q.e1.cross(q.e2).normalize()).abs();
                assert!(
                    (t - tri).abs() <= 1e-5 * t / cos,
                    "{t} vs {tri} at cos {cos}"
                );
                assert!((o + d * t - (q.p0 + u * q.e1 + v * q.e2)).length() < 1e-5);
            }
        }
        assert!(hits > 5000, "{hits}");
    }

    #[test]
    fn stored_dual_basis_is_the_computed_one_bit_for_bit() {
        let mut s = Sampler::new(8, 0, 0);
        for _ in 0..1000 {
            let e1 = sample_uniform_sphere(s.next_2d()) * (10.0 * s.next_f32() + 1e-3);
            let e2 = sample_uniform_sphere(s.next_2d()) * (10.0 * s.next_f32() + 1e-3);
            let q = Parallelogram::new(Vec3::ZERO, e1, e2);
            let (a1, a2) = q.dual();
            assert_eq!(
                a1.to_array().map(f32::to_bits),
                e2.cross(q.n).to_array().map(f32::to_bits)
            );
            assert_eq!(
                a2.to_array().map(f32::to_bits),
                q.n.cross(e1).to_array().map(f32::to_bits)
            );
        }
    }

    #[test]
    fn rejects_non_parallelograms() {
        let (a, mut b) = quad();
        b[2] += Vec3::new(0.0, 0.01, 0.0);
        assert!(Parallelogram::from_triangle_pair(a, b).is_none());
    }

    #[test]
    fn no_self_hits_and_no_cracks_at_shared_edges() {
        // Two faces of a box meeting at the edge x = 1, z in [-1, 1]; rays from inside aimed at the edge.
        let top = Parallelogram::new(
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 2.0),
        );
        let side = Parallelogram::new(
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::new(0.0, 0.0, 2.0),
        );
        let mut s = Sampler::new(6, 0, 0);
        for _ in 0..20_000 {
            let target = Vec3::new(1.0, 1.0, 2.0 * s.next_f32() - 1.0);
            let o = Vec3::new(s.next_f32(), s.next_f32(), s.next_f32()) * 1.8 - 0.9;
            let d = (target - o).normalize();
            let hit = top.intersect(o, d, f32::INFINITY).0.is_finite()
                || side.intersect(o, d, f32::INFINITY).0.is_finite();
            assert!(hit, "ray from {o} slipped through the edge at {target}");
            // Leaving the top face from its own plane (y = 1 exactly) must not re-hit it.
            let p = Vec3::new(s.next_f32() - 0.5, 1.0, s.next_f32() - 0.5);
            let mut w = sample_uniform_sphere(s.next_2d());
            w.y = -w.y.abs();
            assert!(top.intersect(p, w, f32::INFINITY).0.is_infinite());
        }
    }
}

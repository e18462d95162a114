//! Majorants of a heterogeneous σt along a ray: piecewise constant per supervoxel of a coarse grid
//! over the volume's unit cube, and the volume's maximum outside it, walked by a 3-D DDA
//! (Amanatides & Woo 1987). Free-flight sampling and the tracking estimators draw tentative
//! collisions at rate μ̄ segment by segment (memorylessness of the exponential lets each segment
//! restart at its entry: Novák et al. 2014 §3, Kutz et al. 2017 §4, "piecewise-constant majorants").

use super::volume::GridVolume;
use crate::math::{Color, Vec3};

/// Samples per supervoxel side.
pub const SAMPLES_PER_SUPERVOXEL: usize = 4;

/// Per-channel upper bounds of a field on the supervoxels of its unit cube.
#[derive(Clone, Debug, PartialEq)]
pub struct MajorantGrid {
    n: [usize; 3],
    max: Vec<Color>,
    /// Bound everywhere (the largest sample), used outside the unit cube.
    everywhere: Color,
}

impl MajorantGrid {
    /// Majorants of `scale` × the trilinear field of `vol`. A supervoxel spanning sample-space
    /// [u_lo, u_hi] per axis is bounded by the samples ⌈u_lo⌉ − 1 … ⌊u_hi⌋ + 1 (wrapped): the
    /// interpolant on the closed interval is a convex combination of exactly those (a face on a
    /// sample plane takes the sample beyond it too, for a point the DDA rounds across the face).
    pub fn new(vol: &GridVolume, scale: f32, samples_per_supervoxel: usize) -> MajorantGrid {
        let res = vol.grid.res;
        let n = res.map(|r| r.div_ceil(samples_per_supervoxel.max(1)));
        let mut max = Vec::with_capacity(n[0] * n[1] * n[2]);
        for k in 0..n[2] {
            let zs = sample_range(k, n[2], res[2]);
            for j in 0..n[1] {
                let ys = sample_range(j, n[1], res[1]);
                for i in 0..n[0] {
                    let xs = sample_range(i, n[0], res[0]);
                    let mut m = Color::ZERO;
                    for z in zs.clone() {
                        for y in ys.clone() {
                            for x in xs.clone() {
                                let at =
                                    [(x, 0), (y, 1), (z, 2)].map(|(v, a)| vol.wrap_index(v, a));
                                m = m.max(vol.grid.at(at[0], at[1], at[2]));
                            }
                        }
                    }
                    max.push(m * scale);
                }
            }
        }
        MajorantGrid {
            n,
            max,
            everywhere: vol.grid.range().1 * scale,
        }
    }

    /// The bound that holds everywhere.
    pub fn everywhere(&self) -> Color {
        self.everywhere
    }

    /// Segments (t0, t1, μ̄) covering [0, t_max] of o + t·d (world t), in order.
    pub fn segments(&self, vol: &GridVolume, o: Vec3, d: Vec3, t_max: f32) -> MajorantSegments<'_> {
        let nf = Vec3::new(self.n[0] as f32, self.n[1] as f32, self.n[2] as f32);
        let s0 = vol.local(o) * nf;
        let ds = vol.local_dir(d) * nf;
        // Slab clip against [0, n]³.
        let (mut t_in, mut t_out) = (0.0f32, t_max);
        for a in 0..3 {
            if ds[a] == 0.0 {
                if !(0.0..=nf[a]).contains(&s0[a]) {
                    (t_in, t_out) = (t_max, t_max);
                }
                continue;
            }
            let (ta, tb) = ((0.0 - s0[a]) / ds[a], (nf[a] - s0[a]) / ds[a]);
            t_in = t_in.max(ta.min(tb));
            t_out = t_out.min(ta.max(tb));
        }
        let inside = t_in < t_out;
        let mut seg = MajorantSegments {
            grid: self,
            s0,
            ds,
            cell: [0; 3],
            plane: Vec3::ZERO,
            t: 0.0,
            t_in: if inside { t_in } else { t_max },
            t_out: if inside { t_out } else { t_max },
            t_max,
        };
        if inside {
            let mid = s0 + ds * t_in.max(0.0);
            for a in 0..3 {
                seg.cell[a] = (mid[a].floor().max(0.0) as usize).min(self.n[a] - 1);
                seg.plane[a] = seg.cell[a] as f32 + if ds[a] > 0.0 { 1.0 } else { 0.0 };
            }
        }
        seg
    }
}

/// Integer sample indices bounding supervoxel `i` of `n` on an axis of `res` samples.
fn sample_range(i: usize, n: usize, res: usize) -> std::ops::RangeInclusive<i64> {
    let to_u = |x: f64| x * res as f64 - 0.5;
    let lo = to_u(i as f64 / n as f64).ceil() as i64 - 1;
    let hi = to_u((i + 1) as f64 / n as f64).floor() as i64 + 1;
    lo..=hi
}

/// Iterator over (t0, t1, μ̄) of [`MajorantGrid::segments`]: the part before the unit cube, the
/// supervoxels the ray crosses, the part after, each with its bound. Allocation-free.
pub struct MajorantSegments<'a> {
    grid: &'a MajorantGrid,
    s0: Vec3,
    ds: Vec3,
    cell: [usize; 3],
    /// Supervoxel-space coordinate of the next face per axis.
    plane: Vec3,
    t: f32,
    t_in: f32,
    t_out: f32,
    t_max: f32,
}

impl Iterator for MajorantSegments<'_> {
    type Item = (f32, f32, Color);
    fn next(&mut self) -> Option<(f32, f32, Color)> {
        if self.t >= self.t_max {
            return None;
        }
        let t0 = self.t;
        if t0 < self.t_in || t0 >= self.t_out {
            // Outside the cube: before it (up to t_in) or after it (to t_max).
            let t1 = if t0 < self.t_in {
                self.t_in
            } else {
                self.t_max
            };
            self.t = t1;
            return Some((t0, t1, self.grid.everywhere));
        }
        let n = self.grid.n;
        let idx = (self.cell[2] * n[1] + self.cell[1]) * n[0] + self.cell[0];
        let mu = self.grid.max[idx];
        let next = [0, 1, 2].map(|a| {
            if self.ds[a] == 0.0 {
                f32::INFINITY
            } else {
                (self.plane[a] - self.s0[a]) / self.ds[a]
            }
        });
        let a = (0..3).min_by(|&i, &j| next[i].total_cmp(&next[j])).unwrap();
        let t1 = next[a].max(t0).min(self.t_out);
        self.t = t1;
        // Step into the neighbour; leaving the grid ends the inside part.
        let step_out = if self.ds[a] > 0.0 {
            self.cell[a] + 1 >= n[a]
        } else {
            self.cell[a] == 0
        };
        if step_out || t1 >= self.t_out {
            self.t_out = t1;
        } else if self.ds[a] > 0.0 {
            self.cell[a] += 1;
            self.plane[a] += 1.0;
        } else {
            self.cell[a] -= 1;
            self.plane[a] -= 1.0;
        }
        Some((t0, t1, mu))
    }
}

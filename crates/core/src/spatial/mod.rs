//! A hashed uniform grid over point positions: the one spatial index shared by photon mapping
//! (photons), progressive photon mapping (visible points with their own radii) and VCM (light
//! vertices).
//!
//! Space is cut into cubes of edge `cell`, addressed by integer coordinates relative to the
//! points' bounding-box minimum; each cell is hashed into a power-of-two table of at least as many
//! buckets as points. A counting sort leaves one offsets array and one index array, so a bucket is
//! a contiguous slice and a query allocates nothing. Points are scattered in increasing index
//! order, so each bucket lists its points by index; queries walk cells in a fixed order. The
//! structure, and every query's visiting order, is therefore the same for any rayon thread count,
//! which keeps renders bit-reproducible. A hash collision only costs time: every candidate is
//! filtered by its true distance and by its own cell, so a bucket shared by two cells of one query
//! still yields each point once.
//!
//! Inputs are assumed free of NaN (positions, query points and radii).
//!
//! Measured on the workload of `cargo bench -p lt-core --features bench --bench spatial` (250k photon-like points
//! in random order on the five walls of a 2×2×2 box, 1M queries of radius 0.035 finding 48
//! neighbours on average, cell 2r; best of 4 interleaved rounds on a loaded 2-core machine): the
//! grid builds in 1.1 ms on 2 threads against 9.7 ms for a Vec sorted by cell key (parallel sort),
//! and answers the queries in 2.3 s of CPU time against 2.8 s for the sorted Vec's one binary
//! search per row of cells. Fetching candidates from the caller's array dominates: a copy of the
//! positions in bucket order (12 bytes a point) measured 1.7 s.

use crate::math::Vec3;
use rayon::prelude::*;

#[cfg(test)]
mod tests;

/// A hashed uniform grid over `points`, storing indices into the caller's array.
#[derive(Clone, Debug, PartialEq)]
pub struct PointGrid {
    /// Bounding-box minimum of the points: the origin of the cell coordinates.
    min: Vec3,
    cell: f32,
    inv_cell: f32,
    /// The cell of the bounding-box maximum: every point's cell lies in `[0, max_cell]` per axis.
    max_cell: [i32; 3],
    /// `log2` of the bucket count.
    bits: u32,
    /// Bucket `b` holds `indices[starts[b]..starts[b + 1]]`.
    starts: Vec<u32>,
    indices: Vec<u32>,
}

/// Max-heap and sort key: `(d², index)` packed so the integer order is the lexicographic one
/// (the bits of a non-negative f32 order like its value; a squared length is never -0).
#[inline]
fn key((i, d2): (u32, f32)) -> u64 {
    ((d2.to_bits() as u64) << 32) | i as u64
}

impl PointGrid {
    /// Builds over `points` with cells of edge `cell` (> 0; callers pass their largest query
    /// radius, or 2r). Built in parallel with rayon, but the result is identical for any thread
    /// count: points within a cell are stored in increasing index order.
    pub fn build(points: &[Vec3], cell: f32) -> PointGrid {
        assert!(
            cell > 0.0,
            "PointGrid cell size must be positive, got {cell}"
        );
        assert!(
            points.len() < u32::MAX as usize,
            "PointGrid indexes points with u32"
        );
        let n = points.len();
        let (lo, hi) = points
            .par_iter()
            .fold(
                || (Vec3::INFINITY, Vec3::NEG_INFINITY),
                |(lo, hi), &p| (lo.min(p), hi.max(p)),
            )
            .reduce(
                || (Vec3::INFINITY, Vec3::NEG_INFINITY),
                |a, b| (a.0.min(b.0), a.1.max(b.1)),
            );
        // min/max commute, except that which of -0 and +0 survives depends on the split;
        // adding +0 turns -0 into +0 so the stored origin does not depend on the thread count.
        let min = if n == 0 { Vec3::ZERO } else { lo + Vec3::ZERO };
        // At least two buckets so the hash always keeps a bit.
        let bits = n.next_power_of_two().max(2).trailing_zeros();
        let mut grid = PointGrid {
            min,
            cell,
            inv_cell: 1.0 / cell,
            max_cell: [-1; 3],
            bits,
            starts: Vec::new(),
            indices: Vec::new(),
        };
        if n > 0 {
            grid.max_cell = grid.cell_of(hi);
        }

        let buckets = 1usize << bits;
        // The float work (cell coordinates and hash) is the parallel part; the scatter below is
        // sequential so that each bucket receives its points in increasing index order.
        let bucket_of: Vec<u32> = points
            .par_iter()
            .map(|&p| grid.bucket(grid.cell_of(p)))
            .collect();
        let mut starts = vec![0u32; buckets + 1];
        for &b in &bucket_of {
            starts[b as usize] += 1;
        }
        // Inclusive prefix sums: `starts[b]` is the end of bucket b; `starts[buckets]` stays n.
        let mut sum = 0;
        for s in &mut starts {
            sum += *s;
            *s = sum;
        }
        // Filling each bucket from its end while walking indices downwards leaves it in
        // increasing index order and turns every end into a start, with no second array.
        let mut indices = vec![0u32; n];
        for (i, &b) in bucket_of.iter().enumerate().rev() {
            let s = &mut starts[b as usize];
            *s -= 1;
            indices[*s as usize] = i as u32;
        }
        grid.starts = starts;
        grid.indices = indices;
        grid
    }

    /// Number of points indexed.
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// Edge of a cell, as passed to `build`.
    pub fn cell_size(&self) -> f32 {
        self.cell
    }

    /// Every point's index in bucket order, the order in which queries meet them. Points stored
    /// in this order (and the grid built again over them) lie next to their grid neighbours in
    /// memory, so a query reads a few contiguous runs instead of scattered points; the rebuilt
    /// grid's buckets then hold consecutive indices.
    pub fn bucket_order(&self) -> &[u32] {
        &self.indices
    }

    /// Reorders `points`, and `payload` alike, into bucket order and builds the grid over them;
    /// returns it with `original`, where `original[s]` is the index stored point s had. Within a
    /// bucket the points keep their relative order, so every query meets the same points in the
    /// same order as the grid over the unordered points would have (an order-dependent sum over
    /// a query keeps its bits), while the points it meets now lie together in memory: the
    /// photon-mapping family's queries were bound by cache misses on scattered points.
    pub fn build_reordered<T: Copy>(
        points: &mut Vec<Vec3>,
        payload: &mut Vec<T>,
        cell: f32,
    ) -> (PointGrid, Vec<u32>) {
        assert_eq!(points.len(), payload.len(), "one payload per point");
        let original = PointGrid::build(points, cell).bucket_order().to_vec();
        *points = original.iter().map(|&i| points[i as usize]).collect();
        *payload = original.iter().map(|&i| payload[i as usize]).collect();
        (PointGrid::build(points, cell), original)
    }

    /// Calls `f(index, squared distance)` for every point with `|p - q|² <= r²` (computed exactly
    /// as `(p - q).length_squared() <= r * r` in f32), each exactly once, in a deterministic order:
    /// cells by z, then y, then x, indices increasing within a cell. Works for any `r >= 0`; when
    /// the covered cell range has more cells than the table has buckets, it scans every point in
    /// bucket order instead (still each once, still deterministic).
    pub fn for_each_within(&self, points: &[Vec3], q: Vec3, r: f32, f: impl FnMut(u32, f32)) {
        debug_assert_eq!(
            points.len(),
            self.len(),
            "points differ from those built over"
        );
        debug_assert!(r >= 0.0);
        self.for_each_within_bounds(points, q, r, r * r, f);
    }

    /// As `for_each_within`, for the points with `|p - q|² <= r2` (the test made against `r2`
    /// itself, so a caller holding squared radii gets exactly its own test, with no square root
    /// rounded in between).
    pub fn for_each_within_squared(
        &self,
        points: &[Vec3],
        q: Vec3,
        r2: f32,
        f: impl FnMut(u32, f32),
    ) {
        debug_assert!(r2 >= 0.0);
        // cell_range pads r by a relative 1e-5, far more than sqrt's half-ulp rounding.
        self.for_each_within_bounds(points, q, r2.sqrt(), r2, f);
    }

    /// Visits the cells within `r` of `q` and calls `f` for their points with `d² <= r2`
    /// (`r2` ≤ r² up to rounding).
    fn for_each_within_bounds(
        &self,
        points: &[Vec3],
        q: Vec3,
        r: f32,
        r2: f32,
        mut f: impl FnMut(u32, f32),
    ) {
        let Some((lo, hi)) = self.cell_range(q, r) else {
            return;
        };
        let cells: u64 = (0..3).map(|a| (hi[a] - lo[a]) as u64 + 1).product();
        if cells > self.starts.len() as u64 - 1 {
            for &i in &self.indices {
                let d2 = (points[i as usize] - q).length_squared();
                if d2 <= r2 {
                    f(i, d2);
                }
            }
            return;
        }
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let c = [x, y, z];
                    for &i in self.bucket_slice(c) {
                        let p = points[i as usize];
                        let d2 = (p - q).length_squared();
                        // The cell test drops points of another cell sharing this bucket: they
                        // are either out of range or visited with their own cell.
                        if d2 <= r2 && self.cell_of(p) == c {
                            f(i, d2);
                        }
                    }
                }
            }
        }
    }

    /// The `k` nearest points to `q` with `|p - q| <= max_r` (`max_r` may be `f32::INFINITY`),
    /// sorted by (squared distance, index) ascending, written into `out` (cleared first). Fewer
    /// than `k` come back when fewer qualify. Searches shells of cells ring by ring around `q`'s
    /// cell until the k-th distance is below the distance to the unsearched region.
    pub fn k_nearest(
        &self,
        points: &[Vec3],
        q: Vec3,
        k: usize,
        max_r: f32,
        out: &mut Vec<(u32, f32)>,
    ) {
        debug_assert_eq!(
            points.len(),
            self.len(),
            "points differ from those built over"
        );
        debug_assert!(max_r >= 0.0);
        out.clear();
        if k == 0 || self.is_empty() {
            return;
        }
        if k >= self.len() {
            // Every point within max_r qualifies: no shell search needed.
            self.for_each_within(points, q, max_r, |i, d2| out.push((i, d2)));
            out.sort_unstable_by_key(|&e| key(e));
            return;
        }
        let max_r2 = max_r * max_r;
        let buckets = self.starts.len() as u64 - 1;
        let qc = self.cell_of(q);
        // A query outside the box starts from the nearest cell of the grid.
        let c0: [i64; 3] = std::array::from_fn(|a| qc[a].clamp(0, self.max_cell[a]) as i64);
        let max: [i64; 3] = self.max_cell.map(|m| m as i64);
        let mut s: i64 = 0;
        loop {
            let lo: [i64; 3] = std::array::from_fn(|a| (c0[a] - s).max(0));
            let hi: [i64; 3] = std::array::from_fn(|a| (c0[a] + s).min(max[a]));
            let volume: u64 = (0..3).map(|a| (hi[a] - lo[a] + 1) as u64).product();
            if volume > buckets {
                // The shells would visit more cells than there are buckets: one pass over all
                // points is cheaper, and visits each once without the cell test.
                out.clear();
                for &i in &self.indices {
                    let d2 = (points[i as usize] - q).length_squared();
                    if d2 <= max_r2 {
                        offer(out, k, (i, d2));
                    }
                }
                break;
            }
            // Shell s: the cells of the box at Chebyshev distance exactly s from c0.
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    let face = (z - c0[2]).abs() == s || (y - c0[1]).abs() == s;
                    let mut visit = |x: i64| {
                        let c = [x as i32, y as i32, z as i32];
                        for &i in self.bucket_slice(c) {
                            let p = points[i as usize];
                            let d2 = (p - q).length_squared();
                            if d2 <= max_r2
                                && (out.len() < k || key((i, d2)) < key(out[0]))
                                && self.cell_of(p) == c
                            {
                                offer(out, k, (i, d2));
                            }
                        }
                    };
                    if face {
                        (lo[0]..=hi[0]).for_each(&mut visit);
                    } else {
                        // Interior rows of the shell: only their two ends are new.
                        if c0[0] - s >= 0 {
                            visit(c0[0] - s);
                        }
                        if c0[0] + s <= max[0] {
                            visit(c0[0] + s);
                        }
                    }
                }
            }
            let d = self.unsearched_distance(q, c0, s);
            if d.is_infinite() {
                break; // the box covers the whole grid
            }
            // A lower bound on the f32 squared distance of any point outside the box: true
            // d² shrunk by far more than the f32 rounding of (p - q).length_squared(), less an
            // absolute term for the subnormal range where relative bounds fail.
            let bound = d * d * (1.0 - 1e-5) - 1e-37;
            if bound > max_r2 as f64 || (out.len() == k && (out[0].1 as f64) < bound) {
                break;
            }
            s += 1;
        }
        out.sort_unstable_by_key(|&e| key(e));
    }

    /// Integer cell coordinates of `p`. `as i32` saturates, so far-away or tiny-cell coordinates
    /// cannot overflow. Every point lies at or above `min`, where truncation is floor (and much
    /// cheaper: without SSE4.1 `floor` is a libm call, which tripled the build time). Below the
    /// box, where only query ends land, truncation errs upwards, but the map stays monotone in
    /// each coordinate, and monotonicity is all the range logic relies on.
    #[inline]
    fn cell_of(&self, p: Vec3) -> [i32; 3] {
        let c = (p - self.min) * self.inv_cell;
        [c.x as i32, c.y as i32, c.z as i32]
    }

    #[inline]
    fn bucket(&self, c: [i32; 3]) -> u32 {
        let h = (c[0] as u32 as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)
            ^ (c[1] as u32 as u64).wrapping_mul(0xc2b2_ae3d_27d4_eb4f)
            ^ (c[2] as u32 as u64).wrapping_mul(0x1656_67b1_9e37_79f9);
        // Multiplication only carries upwards: keep the top bits, which depend on all inputs.
        (h >> (64 - self.bits)) as u32
    }

    #[inline]
    fn bucket_slice(&self, c: [i32; 3]) -> &[u32] {
        let b = self.bucket(c) as usize;
        &self.indices[self.starts[b] as usize..self.starts[b + 1] as usize]
    }

    /// The grid cells that can hold a point within `r` of `q`, or None if none do. The ends are
    /// pushed outwards by a relative 1e-5 and one ulp, which covers every rounding that could let
    /// `(p - q).length_squared() <= r * r` hold for a point just beyond `r` (or a point be floored
    /// into the next cell); the extra cells this rarely adds are filtered by distance.
    fn cell_range(&self, q: Vec3, r: f32) -> Option<([i32; 3], [i32; 3])> {
        let rp = r * (1.0 + 1e-5);
        let a = Vec3::new(
            (q.x - rp).next_down(),
            (q.y - rp).next_down(),
            (q.z - rp).next_down(),
        );
        let b = Vec3::new(
            (q.x + rp).next_up(),
            (q.y + rp).next_up(),
            (q.z + rp).next_up(),
        );
        let (ca, cb) = (self.cell_of(a), self.cell_of(b));
        let lo: [i32; 3] = std::array::from_fn(|i| ca[i].max(0));
        let hi: [i32; 3] = std::array::from_fn(|i| cb[i].min(self.max_cell[i]));
        (0..3).all(|i| lo[i] <= hi[i]).then_some((lo, hi))
    }

    /// A lower bound (f64) on the distance from `q` to any point whose cell lies outside the box
    /// of cells `c0 ± s`, or +∞ when the box, clamped to the grid, covers all of it. A point
    /// floored into cell h ≥ 1 has `p - min >= h · cell · (1 - 1e-6)` and one floored into cell
    /// h has `p - min < (h + 1) · cell · (1 + 1e-6)`: three f32 roundings are below 2e-7.
    fn unsearched_distance(&self, q: Vec3, c0: [i64; 3], s: i64) -> f64 {
        let mut d = f64::INFINITY;
        let cell = self.cell as f64;
        for a in 0..3 {
            let (qa, mina) = (q[a] as f64, self.min[a] as f64);
            if c0[a] - s > 0 {
                // Cells below c0 - s exist and are unsearched.
                d = d.min(qa - (mina + (c0[a] - s) as f64 * cell * (1.0 + 1e-6)));
            }
            if c0[a] + s < self.max_cell[a] as i64 {
                d = d.min((mina + (c0[a] + s + 1) as f64 * cell * (1.0 - 1e-6)) - qa);
            }
        }
        d.max(0.0)
    }
}

/// Keeps the `k` smallest keys seen in `heap`, a max-heap on `key` (root at 0).
#[inline]
fn offer(heap: &mut Vec<(u32, f32)>, k: usize, e: (u32, f32)) {
    if heap.len() < k {
        heap.push(e);
        let mut i = heap.len() - 1;
        while i > 0 {
            let parent = (i - 1) / 2;
            if key(heap[parent]) >= key(heap[i]) {
                break;
            }
            heap.swap(parent, i);
            i = parent;
        }
    } else if key(e) < key(heap[0]) {
        heap[0] = e;
        let mut i = 0;
        loop {
            let (l, r) = (2 * i + 1, 2 * i + 2);
            let mut top = i;
            if l < heap.len() && key(heap[l]) > key(heap[top]) {
                top = l;
            }
            if r < heap.len() && key(heap[r]) > key(heap[top]) {
                top = r;
            }
            if top == i {
                break;
            }
            heap.swap(top, i);
            i = top;
        }
    }
}

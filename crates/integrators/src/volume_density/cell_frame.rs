//! A uniform grid's geometry (box, cell size, dimensions) and the walk of a ray through its cells
//! (3-D DDA, Amanatides & Woo 1987), shared by the index of photon points for camera beams
//! (`beams.rs`, pb2d) and the index of photon beams (`beam_grid.rs`, bb1d): both list items per
//! cell and visit the cells a camera beam crosses.

use lt_core::geometry::Ray;
use lt_core::math::Vec3;

/// A box cut into cubic cells.
#[derive(Clone, Copy, Debug)]
pub struct CellFrame {
    pub lo: Vec3,
    pub cell: f32,
    pub dims: [i32; 3],
}

impl CellFrame {
    /// Covers [lo, hi] with cubic cells of side at least `min_cell` and at most `max_per_axis`
    /// cells along the longest side.
    pub fn new(lo: Vec3, hi: Vec3, min_cell: f32, max_per_axis: f32) -> CellFrame {
        let cell = min_cell.max((hi - lo).max_element() / max_per_axis);
        let ext = (hi - lo) / cell;
        CellFrame {
            lo,
            cell,
            dims: [
                (ext.x.ceil() as i32).max(1),
                (ext.y.ceil() as i32).max(1),
                (ext.z.ceil() as i32).max(1),
            ],
        }
    }

    pub fn cell_count(&self) -> usize {
        (self.dims[0] * self.dims[1] * self.dims[2]) as usize
    }

    pub fn hi(&self) -> Vec3 {
        self.lo
            + Vec3::new(
                self.dims[0] as f32,
                self.dims[1] as f32,
                self.dims[2] as f32,
            ) * self.cell
    }

    /// The cell holding `p`, clamped into the grid.
    pub fn cell_of(&self, p: Vec3) -> [i32; 3] {
        let q = (p - self.lo) / self.cell;
        [
            (q.x.floor() as i32).clamp(0, self.dims[0] - 1),
            (q.y.floor() as i32).clamp(0, self.dims[1] - 1),
            (q.z.floor() as i32).clamp(0, self.dims[2] - 1),
        ]
    }

    #[inline]
    pub fn index(&self, c: [i32; 3]) -> usize {
        ((c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]) as usize
    }

    /// The centre of cell `c`.
    pub fn centre(&self, c: [i32; 3]) -> Vec3 {
        self.lo + (Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) + Vec3::splat(0.5)) * self.cell
    }

    /// Every cell of the box [a, b] (clamped), x fastest.
    pub fn for_cells_of_box(&self, a: Vec3, b: Vec3, mut f: impl FnMut(usize)) {
        let (ca, cb) = (self.cell_of(a), self.cell_of(b));
        for z in ca[2]..=cb[2] {
            for y in ca[1]..=cb[1] {
                for x in ca[0]..=cb[0] {
                    f(self.index([x, y, z]));
                }
            }
        }
    }

    /// Calls `f(cell, coordinates, t_lo, t_hi)` for every cell the ray's [0, t_max) crosses, in
    /// order, with the cell's interval of t: the intervals partition the part of the ray inside
    /// the grid's box.
    pub fn for_cells_along(
        &self,
        ray: &Ray,
        t_max: f32,
        mut f: impl FnMut(usize, [i32; 3], f32, f32),
    ) {
        let hi = self.hi();
        // Slab clip of [0, t_max) to the grid's box.
        let inv = ray.d.recip();
        let (t0, t1) = ((self.lo - ray.o) * inv, (hi - ray.o) * inv);
        let t_enter = t0.min(t1).max_element().max(0.0);
        let t_end = t0.max(t1).min_element().min(t_max);
        if !(t_enter < t_end) {
            return;
        }
        let o = ray.o;
        let d = ray.d;
        let mut c = self.cell_of(o + d * t_enter);
        let dd = [d.x, d.y, d.z];
        let (oo, lo) = ([o.x, o.y, o.z], [self.lo.x, self.lo.y, self.lo.z]);
        let step = dd.map(|v| if v > 0.0 { 1 } else { -1 });
        // The t where the ray leaves cell c across axis k.
        let boundary = |k: usize, ck: i32| -> f32 {
            if dd[k] == 0.0 {
                return f32::INFINITY;
            }
            let edge = if dd[k] > 0.0 { ck + 1 } else { ck };
            (lo[k] + edge as f32 * self.cell - oo[k]) / dd[k]
        };
        let mut t_exit = [boundary(0, c[0]), boundary(1, c[1]), boundary(2, c[2])];
        let mut t_cur = t_enter;
        loop {
            let k = if t_exit[0] <= t_exit[1] && t_exit[0] <= t_exit[2] {
                0
            } else if t_exit[1] <= t_exit[2] {
                1
            } else {
                2
            };
            let t_next = t_exit[k].min(t_end);
            f(self.index(c), c, t_cur, t_next);
            if t_next >= t_end {
                break;
            }
            c[k] += step[k];
            if c[k] < 0 || c[k] >= self.dims[k] {
                break;
            }
            t_exit[k] = boundary(k, c[k]);
            t_cur = t_next;
        }
    }
}

/// Items listed per cell: cell `c` lists `entries[starts[c]..starts[c + 1]]`, item indices in
/// increasing order (so a walk visits them in a fixed order: the same sum at any thread count).
pub struct CellLists {
    pub frame: CellFrame,
    starts: Vec<u32>,
    entries: Vec<u32>,
}

impl CellLists {
    /// `cells_of(item, emit)` emits each cell an item is listed in, once each; called twice per
    /// item (count, then fill), so it must emit the same cells both times.
    pub fn build(
        frame: CellFrame,
        items: usize,
        mut cells_of: impl FnMut(usize, &mut dyn FnMut(usize)),
    ) -> CellLists {
        let cells = frame.cell_count();
        let mut counts = vec![0u32; cells + 1];
        for i in 0..items {
            cells_of(i, &mut |c| counts[c + 1] += 1);
        }
        for c in 0..cells {
            counts[c + 1] += counts[c];
        }
        let mut fill = counts.clone();
        let mut entries = vec![0u32; counts[cells] as usize];
        for i in 0..items {
            cells_of(i, &mut |c| {
                entries[fill[c] as usize] = i as u32;
                fill[c] += 1;
            });
        }
        CellLists {
            frame,
            starts: counts,
            entries,
        }
    }

    /// The items listed in cell `c`.
    #[inline]
    pub fn items(&self, c: usize) -> &[u32] {
        &self.entries[self.starts[c] as usize..self.starts[c + 1] as usize]
    }

    /// Bytes held: 4 per entry and 4 per cell.
    pub fn bytes(&self) -> usize {
        4 * (self.starts.len() + self.entries.len())
    }
}

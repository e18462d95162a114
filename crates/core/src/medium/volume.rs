//! Volumes: a colour per point of space (Mitsuba's `gridvolume` and `constvolume`), the fields a
//! heterogeneous medium's σt and albedo are read from.
//!
//! **Mitsuba's lookup convention** (Mitsuba 3, `src/volumes/grid.cpp` on Dr.Jit's `Texture3f`),
//! followed here:
//! - A point p goes to the volume's local coordinates by `to_local` = B · to_world⁻¹, where B is
//!   the identity unless `use_grid_bbox`, then the map of the file's bounding box onto [0, 1]³.
//!   Without `use_grid_bbox` the grid spans the unit cube [0, 1]³ of `to_world` and the file's
//!   bounding box is ignored.
//! - Samples are cell-centred: value i of an axis of resolution n sits at local (i + ½)/n, so the
//!   trilinear lookup is at u = x·n − ½ in sample space, between samples ⌊u⌋ and ⌊u⌋ + 1.
//! - Wrap modes act on those sample indices: `clamp` (default) clamps them into [0, n − 1], so the
//!   field is constant within half a cell of each face and beyond the cube; `repeat` tiles;
//!   `mirror` reflects.
//!
//! Whatever the wrap mode, the field is trilinear between consecutive sample planes (u integer),
//! which [`GridVolume::sample_planes`] exposes: along a straight segment it is a cubic in the
//! distance between two plane crossings (what makes the deterministic transmittance exact).

use crate::math::{Color, Mat4, Vec3};
use std::sync::Arc;

/// How sample indices beyond the grid are mapped back into it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WrapMode {
    Clamp,
    Repeat,
    Mirror,
}

/// The content of a `.vol` file: f32 values, x fastest, then y, then z, channels interleaved.
#[derive(Clone, Debug, PartialEq)]
pub struct VolumeGrid {
    pub res: [usize; 3],
    /// 1 or 3.
    pub channels: usize,
    pub data: Vec<f32>,
    /// The file's bounding box (min, max), used with `use_grid_bbox`.
    pub bbox: [Vec3; 2],
}

impl VolumeGrid {
    /// Checks the shape: resolution ≥ 1 per axis, 1 or 3 channels, as many values as they call
    /// for, every value finite, a bounding box with min < max.
    pub fn new(
        res: [usize; 3],
        channels: usize,
        data: Vec<f32>,
        bbox: [Vec3; 2],
    ) -> Result<VolumeGrid, String> {
        if res.contains(&0) {
            return Err(format!(
                "resolution {}×{}×{} has an empty axis",
                res[0], res[1], res[2]
            ));
        }
        if channels != 1 && channels != 3 {
            return Err(format!("{channels} channels: a volume has 1 or 3"));
        }
        let need = res[0]
            .checked_mul(res[1])
            .and_then(|n| n.checked_mul(res[2]))
            .and_then(|n| n.checked_mul(channels))
            .ok_or("its resolution overflows")?;
        if data.len() != need {
            return Err(format!(
                "{}×{}×{} × {channels} channels need {need} values, not {}",
                res[0],
                res[1],
                res[2],
                data.len()
            ));
        }
        if let Some(k) = data.iter().position(|v| !v.is_finite()) {
            return Err(format!("value {k} is NaN or infinite"));
        }
        Ok(VolumeGrid {
            res,
            channels,
            data,
            bbox,
        })
    }

    /// The sample at integer indices inside the grid, as a colour (one channel spread over three).
    #[inline]
    pub fn at(&self, i: usize, j: usize, k: usize) -> Color {
        let idx = ((k * self.res[1] + j) * self.res[0] + i) * self.channels;
        if self.channels == 1 {
            Color::splat(self.data[idx])
        } else {
            Color::new(self.data[idx], self.data[idx + 1], self.data[idx + 2])
        }
    }

    /// Smallest and largest sample per channel.
    pub fn range(&self) -> (Color, Color) {
        let mut lo = Color::splat(f32::INFINITY);
        let mut hi = Color::splat(f32::NEG_INFINITY);
        for k in 0..self.res[2] {
            for j in 0..self.res[1] {
                for i in 0..self.res[0] {
                    let v = self.at(i, j, k);
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
        }
        (lo, hi)
    }
}

/// A `gridvolume`: a grid placed in the scene, looked up trilinearly.
#[derive(Clone, Debug, PartialEq)]
pub struct GridVolume {
    pub grid: Arc<VolumeGrid>,
    /// World → local (the unit cube).
    to_local: Mat4,
    pub wrap: WrapMode,
}

impl GridVolume {
    /// Places `grid` by `to_world` (and, with `use_grid_bbox`, its file's bounding box); errors on
    /// a singular transform or an empty bounding box.
    pub fn new(
        grid: Arc<VolumeGrid>,
        to_world: Mat4,
        use_grid_bbox: bool,
        wrap: WrapMode,
    ) -> Result<GridVolume, String> {
        let det = to_world.determinant();
        if !(det.is_finite() && det != 0.0 && to_world.is_finite()) {
            return Err("to_world is singular or not finite".into());
        }
        let mut to_local = to_world.inverse();
        if use_grid_bbox {
            let [lo, hi] = grid.bbox;
            let extent = hi - lo;
            if !(extent.min_element() > 0.0 && extent.is_finite()) {
                return Err(format!(
                    "use_grid_bbox: the grid's bounding box {lo} – {hi} is empty or not finite"
                ));
            }
            let unit = Mat4::from_scale(extent.recip()) * Mat4::from_translation(-lo);
            to_local = unit * to_local;
        }
        Ok(GridVolume {
            grid,
            to_local,
            wrap,
        })
    }

    /// World-space bounding box of the unit cube the grid spans (where it is not extended by the
    /// wrap mode): its eight corners mapped by to_local⁻¹.
    pub fn world_bounds(&self) -> [Vec3; 2] {
        placed_unit_cube(&self.to_local.inverse())
    }

    /// Sample-space coordinates u = local·n − ½ of a world point (samples at integer u).
    #[inline]
    pub fn sample_space(&self, p: Vec3) -> Vec3 {
        self.to_local.transform_point3(p) * self.res_f() - 0.5
    }

    /// The linear part of the world → sample-space map applied to a direction.
    #[inline]
    pub fn sample_space_dir(&self, d: Vec3) -> Vec3 {
        self.to_local.transform_vector3(d) * self.res_f()
    }

    /// World → local unit cube.
    #[inline]
    pub fn local(&self, p: Vec3) -> Vec3 {
        self.to_local.transform_point3(p)
    }

    #[inline]
    pub fn local_dir(&self, d: Vec3) -> Vec3 {
        self.to_local.transform_vector3(d)
    }

    #[inline]
    fn res_f(&self) -> Vec3 {
        Vec3::new(
            self.grid.res[0] as f32,
            self.grid.res[1] as f32,
            self.grid.res[2] as f32,
        )
    }

    /// Trilinear value at a world point.
    #[inline]
    pub fn eval(&self, p: Vec3) -> Color {
        self.eval_sample_space(self.sample_space(p))
    }

    /// Trilinear value at sample-space u.
    pub fn eval_sample_space(&self, u: Vec3) -> Color {
        let base = u.floor();
        let w = u - base;
        let ix = self.wrapped_pair(base.x, 0);
        let iy = self.wrapped_pair(base.y, 1);
        let iz = self.wrapped_pair(base.z, 2);
        let g = &self.grid;
        let lerp = |a: Color, b: Color, t: f32| a * (1.0 - t) + b * t;
        let x00 = lerp(g.at(ix[0], iy[0], iz[0]), g.at(ix[1], iy[0], iz[0]), w.x);
        let x10 = lerp(g.at(ix[0], iy[1], iz[0]), g.at(ix[1], iy[1], iz[0]), w.x);
        let x01 = lerp(g.at(ix[0], iy[0], iz[1]), g.at(ix[1], iy[0], iz[1]), w.x);
        let x11 = lerp(g.at(ix[0], iy[1], iz[1]), g.at(ix[1], iy[1], iz[1]), w.x);
        lerp(lerp(x00, x10, w.y), lerp(x01, x11, w.y), w.z)
    }

    /// Grid indices of samples ⌊u⌋ and ⌊u⌋ + 1 along `axis`, after the wrap mode.
    #[inline]
    fn wrapped_pair(&self, floor_u: f32, axis: usize) -> [usize; 2] {
        // Far outside the grid every mode saturates or cycles; keep the i64 in range.
        let i = floor_u.clamp(-1e9, 1e9) as i64;
        [self.wrap_index(i, axis), self.wrap_index(i + 1, axis)]
    }

    /// Grid index of integer sample index `i` along `axis` under the wrap mode.
    #[inline]
    pub fn wrap_index(&self, i: i64, axis: usize) -> usize {
        let n = self.grid.res[axis] as i64;
        (match self.wrap {
            WrapMode::Clamp => i.clamp(0, n - 1),
            WrapMode::Repeat => i.rem_euclid(n),
            WrapMode::Mirror => {
                let m = i.rem_euclid(2 * n);
                if m < n {
                    m
                } else {
                    2 * n - 1 - m
                }
            }
        }) as usize
    }
}

/// A volume: Mitsuba's `constvolume` or `gridvolume`.
///
/// Every Mitsuba volume also has a bounding box, the world box of the unit cube its `to_world`
/// places (`Volume::update_bbox`; with `use_grid_bbox` the file's box): a `heterogeneous` medium
/// exists only inside its σt volume's box (`Medium::intersect_aabb`), whatever the wrap mode says
/// beyond it. A constant has one too: a `constvolume` without `to_world`, and the `constvolume`
/// Mitsuba makes of a plain value (`Properties::get_volume`), span the unit cube [0, 1]³.
#[derive(Clone, Debug, PartialEq)]
pub enum Volume {
    Constant { value: Color, bounds: [Vec3; 2] },
    Grid(GridVolume),
}

impl Volume {
    /// A `constvolume` with no `to_world` (or a plain value): `value` on the unit cube.
    pub fn constant(value: Color) -> Volume {
        Volume::Constant {
            value,
            bounds: [Vec3::ZERO, Vec3::ONE],
        }
    }

    /// A `constvolume` placed by `to_world` (its box is the placed unit cube); errors on a
    /// singular or non-finite transform, as a grid's placement does.
    pub fn placed_constant(value: Color, to_world: Mat4) -> Result<Volume, String> {
        let det = to_world.determinant();
        if !(det.is_finite() && det != 0.0 && to_world.is_finite()) {
            return Err("to_world is singular or not finite".into());
        }
        Ok(Volume::Constant {
            value,
            bounds: placed_unit_cube(&to_world),
        })
    }

    #[inline]
    pub fn eval(&self, p: Vec3) -> Color {
        match self {
            Volume::Constant { value, .. } => *value,
            Volume::Grid(g) => g.eval(p),
        }
    }

    /// Mitsuba's bounding box of the volume, in world space (see the type's doc).
    pub fn bounds(&self) -> [Vec3; 2] {
        match self {
            Volume::Constant { bounds, .. } => *bounds,
            Volume::Grid(g) => g.world_bounds(),
        }
    }

    /// Smallest and largest value per channel anywhere in space (a trilinear interpolant stays
    /// within its samples' range).
    pub fn range(&self) -> (Color, Color) {
        match self {
            Volume::Constant { value, .. } => (*value, *value),
            Volume::Grid(g) => g.grid.range(),
        }
    }

    /// The sample-space map of a grid, for the exact integration along segments.
    pub fn as_grid(&self) -> Option<&GridVolume> {
        match self {
            Volume::Constant { .. } => None,
            Volume::Grid(g) => Some(g),
        }
    }
}

/// World box of the unit cube [0, 1]³ placed by `to_world`: its eight corners' bounds.
fn placed_unit_cube(to_world: &Mat4) -> [Vec3; 2] {
    let mut b = [Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)];
    for i in 0..8 {
        let c = Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, (i >> 2) as f32);
        let w = to_world.transform_point3(c);
        b = [b[0].min(w), b[1].max(w)];
    }
    b
}

/// Distances along o + t·d, t ∈ (0, t_max), where the sample-space point crosses an integer plane
/// of any axis, in increasing order, followed by t_max: between two consecutive ones a trilinear
/// field is a cubic in t. Allocation-free (a 3-axis DDA).
pub struct PlaneCrossings {
    u0: Vec3,
    inv: Vec3,
    /// The next integer plane per axis, and the step to the one after (±1).
    plane: Vec3,
    sign: Vec3,
    t_max: f32,
    done: bool,
}

impl PlaneCrossings {
    /// `u0`, `du`: the sample-space origin and direction (per unit t).
    pub fn new(u0: Vec3, du: Vec3, t_max: f32) -> PlaneCrossings {
        let (mut inv, mut plane, mut sign) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
        for a in 0..3 {
            if du[a] != 0.0 {
                inv[a] = 1.0 / du[a];
                sign[a] = du[a].signum();
                plane[a] = if du[a] > 0.0 {
                    u0[a].floor() + 1.0
                } else {
                    u0[a].ceil() - 1.0
                };
            }
        }
        PlaneCrossings {
            u0,
            inv,
            plane,
            sign,
            t_max,
            done: false,
        }
    }

    /// Distance to the next plane of axis `a` (∞ for an axis the segment runs parallel to),
    /// computed afresh from the origin each time so that rounding does not accumulate.
    #[inline]
    fn next_on(&self, a: usize) -> f32 {
        if self.sign[a] == 0.0 {
            f32::INFINITY
        } else {
            (self.plane[a] - self.u0[a]) * self.inv[a]
        }
    }
}

impl Iterator for PlaneCrossings {
    type Item = f32;
    fn next(&mut self) -> Option<f32> {
        if self.done {
            return None;
        }
        let t = [0, 1, 2].map(|a| self.next_on(a));
        let a = (0..3).min_by(|&i, &j| t[i].total_cmp(&t[j])).unwrap();
        if !(t[a] < self.t_max) {
            self.done = true;
            return Some(self.t_max);
        }
        self.plane[a] += self.sign[a];
        Some(t[a])
    }
}

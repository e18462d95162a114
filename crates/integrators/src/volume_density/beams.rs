//! `pb2d`'s query: the beam radiance estimate (Jarosz, Zwicker & Jensen 2008; Jarosz et al.
//! 2011's "point–beam 2-D"), photon points gathered along a camera beam.
//!
//! The camera walk's flight from o along ω (unit) in medium m up to t_max (the next surface, or
//! infinity) is a beam. Every path whose first medium vertex from the camera lies on it
//! contributes β ∫₀^t_max T(o, x_t) σs(x_t) L_i(x_t, −ω) dt, estimated from the photons within r
//! of the beam by the 2-D kernel across it:
//!
//!   Σ_{dist(x_p, beam) ≤ r, 0 ≤ t_p < t_max} T(o, x_{t_p}) σs(x_{t_p}) f_p(−ω, ω_p) power_p / (π r²),
//!
//! t_p = (x_p − o)·ω the photon's projection on the beam (T deterministic, `Medium::transmittance`:
//! exact for homogeneous media and trilinear grids). These are "long" camera beams: the whole
//! flight, T inside the estimate.
//!
//! **The acceleration structure.** A uniform grid over the photons' spheres of radius r (each
//! photon listed in every cell its sphere's box touches, ≤ 8 with cells ≥ 2r), walked along the
//! beam by a 3-D DDA (Amanatides & Woo 1987; `cell_frame.rs`). The cells' t intervals partition
//! the beam, and a photon counts only in the cell whose interval holds its t_p (that cell holds
//! x_{t_p}, which lies within r of the photon, so the photon is listed there): each photon once,
//! in a fixed order, so the sum is the same bits at any thread count.

use super::cell_frame::{CellFrame, CellLists};
use super::photons::VolumePhotons;
use crate::media::pt::MediumEvents;
use lt_core::geometry::Ray;
use lt_core::math::{Color, Vec3};
use lt_core::medium::MediumId;
use lt_core::Scene;

/// The grid's longest side in cells at most: bounds memory when r is small against the medium.
const MAX_CELLS_PER_AXIS: f32 = 128.0;

/// Photon spheres of radius r in a uniform grid, for beam queries.
pub struct BeamGrid {
    lists: CellLists,
}

impl BeamGrid {
    pub fn build(points: &[Vec3], r: f32) -> Option<BeamGrid> {
        if points.is_empty() {
            return None;
        }
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for &p in points {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        // A margin past r: DDA boundaries carry rounding, and x_{t_p} must stay inside.
        let margin = Vec3::splat(r * 1.01 + 1e-4 * (hi - lo).max_element());
        let frame = CellFrame::new(lo - margin, hi + margin, 2.0 * r, MAX_CELLS_PER_AXIS);
        let pad = Vec3::splat(r * 1.001);
        let lists = CellLists::build(frame, points.len(), |i, emit| {
            frame.for_cells_of_box(points[i] - pad, points[i] + pad, emit)
        });
        Some(BeamGrid { lists })
    }

    /// Bytes held: per photon about 4 × the cells it touches (≤ 8), plus 4 per cell.
    pub fn bytes(&self) -> usize {
        self.lists.bytes()
    }

    /// Calls `f(photon, t_lo, t_hi)` for every photon listed in every cell the ray's [0, t_max)
    /// crosses, in DDA order, with the cell's interval [t_lo, t_hi) of t: the intervals partition
    /// the clipped ray, so the caller counts a photon only when its t_p lies in the interval.
    pub fn for_each_along(&self, ray: &Ray, t_max: f32, mut f: impl FnMut(u32, f32, f32)) {
        self.lists
            .frame
            .for_cells_along(ray, t_max, |cell, _, t_lo, t_hi| {
                for &i in self.lists.items(cell) {
                    f(i, t_lo, t_hi);
                }
            });
    }
}

/// One pass's photons indexed for beam queries at radius `r`.
pub struct BeamQuery<'a> {
    pub scene: &'a Scene,
    pub photons: &'a VolumePhotons,
    pub grid: Option<BeamGrid>,
    pub r: f32,
    /// 1 / (π r²): the 2-D kernel's normalisation across the beam.
    pub norm: f32,
    pub max_depth: u32,
}

impl<'a> BeamQuery<'a> {
    pub fn new(
        scene: &'a Scene,
        photons: &'a VolumePhotons,
        r: f32,
        max_depth: u32,
    ) -> BeamQuery<'a> {
        BeamQuery {
            scene,
            photons,
            grid: BeamGrid::build(&photons.points, r),
            r,
            norm: 1.0 / (std::f32::consts::PI * r * r),
            max_depth,
        }
    }
}

impl MediumEvents for BeamQuery<'_> {
    fn along_flight(&self, ray: &Ray, t_max: f32, m: MediumId, depth: u32) -> Option<Color> {
        let grid = self.grid.as_ref()?;
        let longest = self.max_depth.saturating_sub(depth);
        if longest == 0 {
            return None;
        }
        let medium = &self.scene.media[m as usize];
        let phase = medium.phase();
        let wo = -ray.d;
        let r2 = self.r * self.r;
        let mut sum = Color::ZERO;
        grid.for_each_along(ray, t_max, |i, t_lo, t_hi| {
            let ph = &self.photons.data[i as usize];
            if ph.medium != m || ph.segments > longest {
                return;
            }
            let to = self.photons.points[i as usize] - ray.o;
            let t = to.dot(ray.d);
            if !(t >= t_lo && t < t_hi && t < t_max) {
                return;
            }
            let x = ray.o + ray.d * t;
            if (to - ray.d * t).length_squared() > r2 {
                return;
            }
            let tr = medium.transmittance(ray.o, x);
            sum += tr * medium.sigma_s(x) * ph.power * phase.eval(wo, ph.wi);
        });
        Some(sum * self.norm)
    }

    /// The beam counted every medium vertex of the flight: a sampled scattering ends the walk
    /// (only flights that pass go on, weighted T/P).
    fn at_scatter(&self, _x: Vec3, _wo: Vec3, _m: MediumId, _depth: u32) -> Option<Color> {
        Some(Color::ZERO)
    }
}

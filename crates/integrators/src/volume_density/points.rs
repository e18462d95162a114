//! `pp3d`'s query: photon points gathered by a point (Jarosz et al. 2011's "point–point 3-D";
//! Jensen & Christensen 1998's volume radiance estimate).
//!
//! At the camera walk's medium vertex x (β holding σs(x), `media::pt::MediumEvents`), the
//! in-scattered radiance L_i(x, ω_o) = ∫ f_p(ω_o, ω) L(x, ω) dω is
//!
//!   L_i(x, ω_o) ≈ Σ_{|x_p − x| ≤ r} f_p(ω_o, ω_p) · power_p / ((4/3) π r³),
//!
//! over the photons of the same medium whose subpath is short enough to complete a path of at
//! most max_depth segments. `power` already carries 1/N (photons.rs), so no further division.

use super::photons::VolumePhotons;
use crate::media::pt::MediumEvents;
use lt_core::math::{Color, Vec3};
use lt_core::medium::MediumId;
use lt_core::spatial::PointGrid;
use lt_core::Scene;

/// One pass's photons indexed for radius queries at radius `r`.
pub struct PointQuery<'a> {
    pub scene: &'a Scene,
    pub photons: &'a VolumePhotons,
    pub grid: Option<PointGrid>,
    pub r: f32,
    /// 1 / ((4/3) π r³): the 3-D kernel's normalisation.
    pub norm: f32,
    pub max_depth: u32,
}

impl<'a> PointQuery<'a> {
    pub fn new(
        scene: &'a Scene,
        photons: &'a VolumePhotons,
        r: f32,
        max_depth: u32,
    ) -> PointQuery<'a> {
        let grid = (!photons.points.is_empty()).then(|| PointGrid::build(&photons.points, r));
        PointQuery {
            scene,
            photons,
            grid,
            r,
            norm: 1.0 / (4.0 / 3.0 * std::f32::consts::PI * r * r * r),
            max_depth,
        }
    }
}

impl MediumEvents for PointQuery<'_> {
    fn at_scatter(&self, x: Vec3, wo: Vec3, m: MediumId, depth: u32) -> Option<Color> {
        let Some(grid) = &self.grid else {
            return Some(Color::ZERO);
        };
        let phase = self.scene.media[m as usize].phase();
        let longest = self.max_depth.saturating_sub(depth);
        let mut sum = Color::ZERO;
        grid.for_each_within(&self.photons.points, x, self.r, |i, _| {
            let ph = &self.photons.data[i as usize];
            if ph.medium == m && ph.segments <= longest {
                sum += ph.power * phase.eval(wo, ph.wi);
            }
        });
        Some(sum * self.norm)
    }
}

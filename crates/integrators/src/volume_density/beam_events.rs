//! What the camera walk asks of one pass's photon beams (`BeamQuery`): BB1D's estimate along each
//! camera flight, or BP2D's at each sampled camera point, by the query's kernel. Apart from
//! `photon_beams`, which stores and indexes the beams, so the kernels' files depend on it alone.

use super::beam_beam::along_camera_beam;
use super::photon_beams::{BeamKernel, BeamQuery};
use super::point_beam::at_camera_point;
use crate::media::pt::MediumEvents;
use lt_core::geometry::Ray;
use lt_core::math::{Color, Vec3};
use lt_core::medium::MediumId;

impl MediumEvents for BeamQuery<'_> {
    fn along_flight(&self, ray: &Ray, t_max: f32, m: MediumId, depth: u32) -> Option<Color> {
        match self.kernel {
            BeamKernel::Line1d => along_camera_beam(self, ray, t_max, m, depth),
            BeamKernel::Point2d => None,
        }
    }

    fn at_scatter(&self, x: Vec3, wo: Vec3, m: MediumId, depth: u32) -> Option<Color> {
        match self.kernel {
            BeamKernel::Point2d => at_camera_point(self, x, wo, m, depth),
            // The beam counted every medium vertex of the flight: a sampled scattering ends the
            // walk (only flights that pass go on, weighted T/P), as in `pb2d`.
            BeamKernel::Line1d => Some(Color::ZERO),
        }
    }
}

//! The path state of `LANES` camera samples as a structure of arrays: one array per quantity,
//! one slot per lane, so the lane kernels read and write whole arrays.

use lt_core::geometry::Ray;
use lt_core::math::{Color, Vec3};
use lt_core::sampling::Sampler;

/// Paths per batch.
pub const LANES: usize = 8;

/// `LANES` colours, one array per channel.
#[derive(Clone, Copy, Debug, Default)]
pub struct ColorLanes {
    pub r: [f32; LANES],
    pub g: [f32; LANES],
    pub b: [f32; LANES],
}

impl ColorLanes {
    pub fn splat(c: Color) -> ColorLanes {
        ColorLanes {
            r: [c.x; LANES],
            g: [c.y; LANES],
            b: [c.z; LANES],
        }
    }

    #[inline]
    pub fn get(&self, i: usize) -> Color {
        Color::new(self.r[i], self.g[i], self.b[i])
    }

    #[inline]
    pub fn set(&mut self, i: usize, c: Color) {
        self.r[i] = c.x;
        self.g[i] = c.y;
        self.b[i] = c.z;
    }
}

/// Which lanes an operation applies to.
pub type Mask = [bool; LANES];

/// The state `pt::Pt::radiance` keeps in locals, for `LANES` paths.
pub struct PathLanes {
    /// Lanes whose path is still being walked.
    pub alive: Mask,
    /// Each lane's pixel, as an index into the row being rendered.
    pub pixel: [usize; LANES],
    /// Each lane's bounce: `Pt::radiance`'s loop counter (lanes refilled at different times walk
    /// different bounces).
    pub depth: [u32; LANES],
    /// Each lane's pixel stream (`None`: the lane has not been given a pixel yet).
    pub samplers: [Option<Sampler>; LANES],
    /// The film filter's weight of each lane's sample.
    pub film_weight: [f32; LANES],
    pub ray: [Ray; LANES],
    pub beta: ColorLanes,
    pub l: ColorLanes,
    /// The previous vertex's BSDF pdf (solid angle) and whether it was a delta lobe.
    pub prev_pdf_w: [f32; LANES],
    pub prev_delta: Mask,
    pub prev_p: [Vec3; LANES],
}

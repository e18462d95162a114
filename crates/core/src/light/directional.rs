//! A directional light: all of its light arrives along one direction, a delta in *direction*
//! (pbrt's `DistantLight`, SmallVCM's `DirectionalLight`). It sits at infinity like the sun and
//! the environment — a path vertex x0 on it is a direction — but unlike the sun's finite cone it
//! has no solid-angle density at all: no walk can hit it and no deterministic connection can end
//! at it; only next-event estimation (which samples its Dirac) and its own emitted rays reach it.
//! (A point light is the opposite delta: in position, with a uniform direction.)
//!
//! Measures, delta-stripped as everywhere in `path` (the Dirac δ(ω − ω_L) is shared by every
//! technique that samples it, so it cancels in f/p and is left out of both):
//! - emitted "radiance" = `irradiance` E, W/m² on a surface facing the light: the factor that
//!   f_s·cos multiplies, as a point light's intensity / d² is;
//! - `sample_li`: wi = `direction` with the discrete density 1 (`delta`); `pdf_li` = 0 for any
//!   given direction (a BSDF sample never lands on the Dirac);
//! - `sample_le`: origin uniform on the disk of the scene's bounding sphere perpendicular to the
//!   direction (area density 1/(πR²)), ray along −`direction` with the discrete density 1;
//! - power: E · πR², the flux through that disk (luminance of E for light selection).

use super::environment::{disk_pdf, distant_le};
use super::{LightLeSample, LightLiSample};
use crate::math::{luminance, Color, Vec2, Vec3, PI};
use crate::texture::TexPoint;

#[derive(Clone, Debug)]
pub struct DirectionalLight {
    /// Unit direction from the scene towards the light (light travels along −direction).
    pub direction: Vec3,
    /// Irradiance on a surface facing the light (W/m²).
    pub irradiance: Color,
}

impl DirectionalLight {
    /// `direction` is normalised here (the loader refuses the zero vector).
    pub fn new(direction: Vec3, irradiance: Color) -> DirectionalLight {
        DirectionalLight {
            direction: direction.normalize(),
            irradiance,
        }
    }

    /// The only direction towards the light, with the discrete density 1.
    pub fn sample_li(&self) -> LightLiSample {
        let wi = self.direction;
        LightLiSample {
            uv: TexPoint::default(),
            p_err: Vec3::ZERO,
            wi,
            p: wi,
            n: -wi,
            distance: f32::INFINITY,
            radiance: self.irradiance,
            pdf_w: 1.0,
            delta: true,
        }
    }

    /// A ray along −direction from a point uniform on the bounding disk upstream of the scene:
    /// pdf_pos = 1/(πR²) (area on the disk), pdf_dir = 1 (discrete: the delta direction).
    pub fn sample_le(&self, u_pos: Vec2, bounds: (Vec3, f32)) -> LightLeSample {
        distant_le(-self.direction, u_pos, bounds, self.irradiance, 1.0)
    }

    /// (disk area density, discrete 1) for the emitted ray; the direction is not checked — a
    /// delta-stripped density, like a point light's positional 1.
    pub fn pdf_le(&self, bounds: (Vec3, f32)) -> (f32, f32) {
        (disk_pdf(bounds), 1.0)
    }

    /// Luminance of the flux through the bounding disk: E · πR².
    pub fn power(&self, bounds: (Vec3, f32)) -> f32 {
        luminance(self.irradiance) * PI * bounds.1 * bounds.1
    }
}

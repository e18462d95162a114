//! Lights. Every light answers three questions (pdf measures are in the names):
//! (a) `sample_li`: a direction towards it from a shading point (next-event estimation), with the
//!     solid-angle pdf at that point — `pdf_li` gives that same pdf for a given direction;
//! (b) `sample_le`: an emitted ray, with the positional pdf (area on the light, or on the disk a
//!     distant light emits over) and the directional pdf (solid angle) kept separate;
//! (c) `pdf_le`: those two pdfs for a given emitted ray.
//! Delta lights report a pdf of 1 in their delta dimension and say so with `delta_position`
//! (point, spot, projector: the position is a Dirac, the directions have a density) / `delta_direction`
//! (directional: its direction is a Dirac, the positions of its emitted rays have a density on the
//! bounding disk). Either way `sample_li` returns `delta` with the discrete pdf 1, `pdf_li` is 0
//! and no walk can hit the light; only a delta in direction also forbids deterministic
//! connections to it (see `path::scatter::connectable` and `path::mis::Chain::valid`). Light
//! selection (by power) is `LightSampler`; its pmf is never folded into the pdfs here.

mod area;
mod directional;
mod environment;
mod envmap;
mod point;
mod projector;
mod spot;
mod sun;

pub use area::AreaLight;
pub use directional::DirectionalLight;
pub use environment::EnvironmentLight;
pub use envmap::{EnvironmentMap, EnvironmentMapLight};
pub use point::PointLight;
pub use projector::ProjectorLight;
pub use spot::SpotLight;
pub use sun::SunLight;

use crate::geometry::Ray;
use crate::math::{luminance, Color, Vec2, Vec3};
use crate::sampling::Distribution1D;
use crate::shape::ShapeGeometry;
use crate::texture::{TexPoint, Texture};
use glam::Mat3;

/// Lights that are not shapes.
#[derive(Clone, Debug)]
pub enum LightDesc {
    Point {
        position: Vec3,
        intensity: Color,
    },
    /// Mitsuba's `spot` (`light::SpotLight`): angles in radians, `to_world` a rotation taking
    /// +z to the beam's axis.
    Spot {
        position: Vec3,
        to_world: Mat3,
        intensity: Color,
        texture: Option<Texture>,
        cutoff: f32,
        beam_width: f32,
    },
    /// Mitsuba's `projector` (`light::ProjectorLight`): `to_world` a rotation taking +z to the
    /// optical axis, `tan_half` the image's half extents on the plane z = 1.
    Projector {
        position: Vec3,
        to_world: Mat3,
        irradiance: Texture,
        scale: f32,
        tan_half: Vec2,
    },
    /// A distant disk light. `direction` points from the scene towards the sun.
    Sun {
        direction: Vec3,
        solid_angle: f32,
        radiance: Color,
    },
    /// A light delta in direction: `direction` (unit) points from the scene towards it, and
    /// `irradiance` is what a surface facing it receives (W/m²). See `light::DirectionalLight`.
    Directional {
        direction: Vec3,
        irradiance: Color,
    },
    Environment {
        radiance: Color,
    },
    /// An image of radiance at infinity (Mitsuba's `envmap`, `light::EnvironmentMap`).
    EnvironmentMap {
        map: std::sync::Arc<EnvironmentMap>,
    },
}

impl LightDesc {
    /// The position of a light that has one (point, spot, projector): what recentring and
    /// translation move.
    pub fn position_mut(&mut self) -> Option<&mut Vec3> {
        match self {
            LightDesc::Point { position, .. }
            | LightDesc::Spot { position, .. }
            | LightDesc::Projector { position, .. } => Some(position),
            _ => None,
        }
    }
}

/// A direction towards a light from a shading point.
#[derive(Clone, Copy, Debug)]
pub struct LightLiSample {
    /// Unit direction from the shading point towards the light.
    pub wi: Vec3,
    /// The point on the light (for distant lights, unused: `distance` is infinite).
    pub p: Vec3,
    /// The light's surface normal at `p` (for distant lights, −wi).
    pub n: Vec3,
    /// Rounding-error bound of `p` (zero for point and distant lights), so a shadow ray can stop
    /// short of the light's surface by its real error instead of a guessed one.
    pub p_err: Vec3,
    pub distance: f32,
    /// Texture coordinates of `p` on an area light (zero for other lights).
    pub uv: TexPoint,
    /// Radiance arriving along −wi, delta-stripped for delta lights: intensity / distance² for a
    /// point light, irradiance for a directional light (what f_s·cos multiplies in both cases).
    pub radiance: Color,
    /// Solid-angle pdf at the shading point; 1 for a delta light.
    pub pdf_w: f32,
    pub delta: bool,
}

/// A ray leaving a light.
#[derive(Clone, Copy, Debug)]
pub struct LightLeSample {
    /// Starts just off the light (offset by `p_err`), ready to trace.
    pub ray: Ray,
    /// The sampled point itself (on the bounding disk for lights at infinity) and its rounding
    /// bound, for the path vertex that records it.
    pub p: Vec3,
    pub p_err: Vec3,
    /// Normal at the ray origin (for distant lights: the ray direction).
    pub n: Vec3,
    /// Texture coordinates of `p` on an area light (zero for other lights).
    pub uv: TexPoint,
    /// Emitted radiance along the ray (point lights: intensity; directional lights: irradiance).
    pub radiance: Color,
    /// Area pdf of the origin (1 for a point light).
    pub pdf_pos: f32,
    /// Solid-angle pdf of the direction (the discrete 1 for a delta direction).
    pub pdf_dir: f32,
}

#[derive(Clone, Debug)]
pub enum Light {
    Area(AreaLight),
    Point(PointLight),
    Spot(SpotLight),
    Projector(ProjectorLight),
    Sun(SunLight),
    Directional(DirectionalLight),
    Environment(EnvironmentLight),
    EnvironmentMap(EnvironmentMapLight),
}

impl Light {
    pub fn area(
        shape: u32,
        geometry: &ShapeGeometry,
        radiance: &Texture,
        flip_normals: bool,
    ) -> Light {
        Light::Area(AreaLight::new(shape, geometry, radiance, flip_normals))
    }

    pub fn from_desc(desc: &LightDesc) -> Light {
        match *desc {
            LightDesc::Point {
                position,
                intensity,
            } => Light::Point(PointLight {
                position,
                intensity,
            }),
            LightDesc::Spot {
                position,
                to_world,
                intensity,
                ref texture,
                cutoff,
                beam_width,
            } => Light::Spot(SpotLight::new(
                position,
                to_world,
                intensity,
                texture.clone(),
                cutoff,
                beam_width,
            )),
            LightDesc::Projector {
                position,
                to_world,
                ref irradiance,
                scale,
                tan_half,
            } => Light::Projector(ProjectorLight::new(
                position,
                to_world,
                irradiance.clone(),
                scale,
                tan_half,
            )),
            LightDesc::Sun {
                direction,
                solid_angle,
                radiance,
            } => Light::Sun(SunLight::new(direction, solid_angle, radiance)),
            LightDesc::Directional {
                direction,
                irradiance,
            } => Light::Directional(DirectionalLight::new(direction, irradiance)),
            LightDesc::Environment { radiance } => {
                Light::Environment(EnvironmentLight { radiance })
            }
            LightDesc::EnvironmentMap { ref map } => {
                Light::EnvironmentMap(EnvironmentMapLight { map: map.clone() })
            }
        }
    }

    /// At infinity (sun, directional, environment): a path vertex on it is a direction, and its
    /// emitted rays start on the bounding disk. Rays leaving the scene reach the sun and the
    /// environment (`escaped`), never the Dirac of a directional light.
    pub fn is_infinite(&self) -> bool {
        matches!(
            self,
            Light::Sun(_)
                | Light::Directional(_)
                | Light::Environment(_)
                | Light::EnvironmentMap(_)
        )
    }

    /// A point, spot or projector light: a delta in position (with a density in direction).
    pub fn delta_position(&self) -> bool {
        matches!(self, Light::Point(_) | Light::Spot(_) | Light::Projector(_))
    }

    /// Intensity (W/sr) a light delta in position emits in direction `w` (leaving it): what
    /// stands for Le at its path vertex. Zero for every other light.
    pub fn intensity_towards(&self, w: Vec3) -> Color {
        match self {
            Light::Point(l) => l.intensity,
            Light::Spot(l) => l.intensity_towards(w),
            Light::Projector(l) => l.intensity_towards(w),
            _ => Color::ZERO,
        }
    }

    /// A directional light: a delta in direction (its emitted rays have an area density on the
    /// bounding disk). The sun is not: its finite cone has a solid-angle pdf and takes part in MIS.
    #[inline]
    pub fn delta_direction(&self) -> bool {
        matches!(self, Light::Directional(_))
    }

    /// Delta in position or direction: `sample_li` picks it with the discrete density 1 (so
    /// next-event estimation chooses x0 with the light-selection pmf alone), `pdf_li` is 0, and
    /// no walk can hit it (c_0 = 0).
    pub fn is_delta(&self) -> bool {
        self.delta_position() || self.delta_direction()
    }

    pub fn sample_li(&self, p: Vec3, u: Vec2) -> Option<LightLiSample> {
        match self {
            Light::Area(l) => l.sample_li(p, u),
            Light::Point(l) => l.sample_li(p),
            Light::Spot(l) => l.sample_li(p),
            Light::Projector(l) => l.sample_li(p),
            Light::Sun(l) => l.sample_li(u),
            Light::Directional(l) => Some(l.sample_li()),
            Light::Environment(l) => l.sample_li(u),
            Light::EnvironmentMap(l) => l.sample_li(u),
        }
    }

    /// Solid-angle pdf at `p` of `sample_li` choosing the point `light_p` (normal `light_n`) in
    /// direction `wi`. For lights at infinity only `wi` matters. Zero for delta lights.
    pub fn pdf_li(&self, p: Vec3, wi: Vec3, light_p: Vec3, light_n: Vec3) -> f32 {
        match self {
            Light::Area(l) => l.pdf_li(p, wi, light_p, light_n),
            Light::Point(_) | Light::Spot(_) | Light::Projector(_) | Light::Directional(_) => 0.0,
            Light::Sun(l) => l.pdf_li(wi),
            Light::Environment(_) => environment::pdf_li(),
            Light::EnvironmentMap(l) => l.pdf_li(wi),
        }
    }

    /// Radiance an area light emits from a point with normal `n` and texture coordinates `uv`
    /// in direction `w` (one-sided).
    pub fn emitted(&self, n: Vec3, w: Vec3, uv: TexPoint) -> Color {
        match self {
            Light::Area(l) => l.emitted(n, w, uv),
            _ => Color::ZERO,
        }
    }

    /// Radiance a light at infinity sends along a ray leaving the scene in direction `dir`; zero
    /// for a directional light, whose single direction no ray hits (it has measure zero).
    pub fn escaped(&self, dir: Vec3) -> Color {
        match self {
            Light::Sun(l) => l.escaped(dir),
            Light::Environment(l) => l.radiance,
            Light::EnvironmentMap(l) => l.escaped(dir),
            _ => Color::ZERO,
        }
    }

    pub fn sample_le(
        &self,
        u_pos: Vec2,
        u_dir: Vec2,
        bounds: (Vec3, f32),
    ) -> Option<LightLeSample> {
        match self {
            Light::Area(l) => l.sample_le(u_pos, u_dir),
            Light::Point(l) => Some(l.sample_le(u_dir)),
            Light::Spot(l) => Some(l.sample_le(u_dir)),
            Light::Projector(l) => Some(l.sample_le(u_dir)),
            Light::Sun(l) => Some(l.sample_le(u_pos, u_dir, bounds)),
            Light::Directional(l) => Some(l.sample_le(u_pos, bounds)),
            Light::Environment(l) => Some(l.sample_le(u_pos, u_dir, bounds)),
            Light::EnvironmentMap(l) => l.sample_le(u_pos, u_dir, bounds),
        }
    }

    /// (area pdf of the origin, solid-angle pdf of the direction) of an emitted ray.
    /// For lights at infinity `dir` is the direction light travels and `p`, `n` are ignored.
    /// Delta dimensions report the discrete 1 (a point light's position, a directional light's
    /// direction).
    pub fn pdf_le(&self, n: Vec3, dir: Vec3, bounds: (Vec3, f32)) -> (f32, f32) {
        match self {
            Light::Area(l) => l.pdf_le(n, dir),
            Light::Point(_) => (1.0, crate::sampling::UNIFORM_SPHERE_PDF),
            Light::Spot(l) => (1.0, l.pdf_dir(dir)),
            Light::Projector(l) => (1.0, l.pdf_dir(dir)),
            Light::Sun(l) => l.pdf_le(dir, bounds),
            Light::Directional(l) => l.pdf_le(bounds),
            Light::Environment(_) => environment::pdf_le(bounds),
            Light::EnvironmentMap(l) => l.pdf_le(dir, bounds),
        }
    }

    /// Emitted power (luminance), the weight of this light in light selection.
    pub fn power(&self, bounds: (Vec3, f32)) -> f32 {
        match self {
            Light::Area(l) => l.power(),
            Light::Point(l) => 4.0 * crate::math::PI * luminance(l.intensity),
            Light::Spot(l) => l.power(),
            Light::Projector(l) => l.power(),
            Light::Sun(l) => l.power(bounds),
            Light::Directional(l) => l.power(bounds),
            Light::Environment(l) => environment::power(l, bounds),
            Light::EnvironmentMap(l) => l.power(bounds),
        }
    }
}

/// Chooses a light: half by emitted power, half uniformly among the lights that emit.
///
/// Power alone misjudges lights at infinity, whose power is taken over the disk bounding the
/// scene (π r² ∫ L dω, as pbrt does): in Mitsuba's spot render test a dim environment around a
/// small scene outweighs the spot light 50 to 1 though the spot lights the view, so the spot's
/// light is a rare, heavy-tailed event (its standard errors fail the test). The uniform half
/// bounds every emitting light's probability below by 1 / 2N; one light is chosen with
/// probability 1 as before.
#[derive(Clone, Debug, Default)]
pub struct LightSampler {
    dist: Distribution1D,
}

impl LightSampler {
    pub fn new(lights: &[Light], bounds: (Vec3, f32)) -> LightSampler {
        let power: Vec<f64> = lights
            .iter()
            .map(|l| l.power(bounds).max(0.0) as f64)
            .collect();
        let total: f64 = power.iter().sum();
        let emitting = power.iter().filter(|&&p| p > 0.0).count() as f64;
        let w: Vec<f32> = power
            .iter()
            .map(|&p| {
                if p > 0.0 {
                    (0.5 * p / total + 0.5 / emitting) as f32
                } else {
                    0.0
                }
            })
            .collect();
        LightSampler {
            dist: Distribution1D::new(&w),
        }
    }

    /// (light index, its selection probability, u reused within the choice) or None without lights.
    pub fn sample(&self, u: f32) -> Option<(usize, f32, f32)> {
        (!self.dist.is_empty()).then(|| self.dist.sample(u))
    }

    pub fn pmf(&self, light: usize) -> f32 {
        if self.dist.is_empty() {
            0.0
        } else {
            self.dist.pmf(light)
        }
    }
}

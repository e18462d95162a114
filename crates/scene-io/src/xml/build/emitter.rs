//! `<emitter>` at the top level: point, constant, directional, envmap, spot, projector, and lt's
//! own `sun` (a distant disk of finite solid angle, which Mitsuba 3 lacks: TOML's `sun` light).

use super::Loader;
use crate::image_file::read_environment_map;
use crate::world::out_of_range_message;
use crate::xml::doc::Elem;
use crate::xml::props::{ColorUse, Plugin};
use crate::xml::resolve::Resolver;
use crate::SceneError;
use glam::DVec3;
use lt_core::math::{Color, Vec2};
use lt_core::scene::LightDesc;
use lt_core::texture::Texture;

/// The emitters lt reads (`area` only inside a shape, or referenced from one by id).
pub(super) const EMITTERS: [&str; 8] = [
    "area",
    "point",
    "spot",
    "projector",
    "constant",
    "directional",
    "envmap",
    "sun",
];

impl<'a> Loader<'a> {
    /// The light and, for a point light, its world position in f64 (`WorldBuilder` rounds it).
    pub(super) fn emitter(
        &mut self,
        e: &'a Elem,
    ) -> Result<Option<(LightDesc, Option<DVec3>)>, SceneError> {
        let p = self.plugin(e)?;
        self.emitter_medium = self.media_of(&p, &["medium"])?.first().map(|&(_, m)| m);
        let opts = self.opts;
        let desc = match p.kind {
            "point" => {
                let intensity = p
                    .color("intensity", ColorUse::Emission, opts, &mut self.report)?
                    .unwrap_or(Color::ONE);
                let pos = p.vec3("position")?;
                let xf = p.transform("to_world")?;
                let position = match (pos, xf) {
                    (Some(_), Some((_, te))) => {
                        return Err(
                            p.err(te, "give a point light `position` or `to_world`, not both")
                        )
                    }
                    (Some(v), None) => DVec3::from_array(v),
                    (None, Some((x, _))) => x.m.transform_point3(DVec3::ZERO),
                    (None, None) => DVec3::ZERO,
                };
                if !crate::world::in_range(position) {
                    return Err(p.err(e, out_of_range_message("the point light", position)));
                }
                p.finish(&["sampling_weight"], &mut self.report)?;
                return Ok((intensity.max_element() > 0.0).then_some((
                    LightDesc::Point {
                        position: glam::Vec3::ZERO,
                        intensity,
                    },
                    Some(position),
                )));
            }
            "constant" => LightDesc::Environment {
                radiance: p
                    .color("radiance", ColorUse::Emission, opts, &mut self.report)?
                    .unwrap_or(Color::ONE),
            },
            "directional" => {
                let irradiance = p
                    .color("irradiance", ColorUse::Emission, opts, &mut self.report)?
                    .unwrap_or(Color::ONE);
                let d = p.vec3("direction")?;
                let xf = p.transform("to_world")?;
                // Mitsuba's direction is the one the light travels along; lt's points to the light.
                let travel = match (d, xf) {
                    (Some(_), Some((_, te))) => {
                        return Err(p.err(
                            te,
                            "give a directional light `direction` or `to_world`, not both",
                        ))
                    }
                    (Some(v), None) => DVec3::from_array(v),
                    (None, Some((x, _))) => x.m.transform_vector3(DVec3::Z),
                    (None, None) => DVec3::Z,
                };
                // Normalised in f32 as the TOML loader does, so a converted scene reads back exactly.
                let towards = -travel.as_vec3();
                if !(towards.length() > 0.0) || !towards.is_finite() {
                    return Err(p.err(e, "the directional light's `direction` is the zero vector"));
                }
                LightDesc::Directional {
                    direction: towards.normalize(),
                    irradiance,
                }
            }
            "sun" => sun(&p, &mut self.report)?,
            "area" => return Err(p.err(e, "an area emitter must be nested in a shape")),
            "envmap" => {
                let Some((file, fe)) = p.string("filename")? else {
                    return Err(p.err(e, "an envmap needs a `filename`"));
                };
                let path = self.doc.resolver.resolve(file).map_err(|looked| {
                    p.err(fe, Resolver::not_found("environment map", file, &looked))
                })?;
                let scale = p.float("scale")?.unwrap_or(1.0) as f32;
                let (to_world, _) = rigid_to_world(&p, "an envmap")?;
                if p.has("mis_compensation") {
                    return Err(p.err(e, "`mis_compensation` of an envmap is not supported"));
                }
                let map = read_environment_map(&path, scale, to_world).map_err(|m| p.err(fe, m))?;
                self.meshes.push(path);
                LightDesc::EnvironmentMap {
                    map: std::sync::Arc::new(map),
                }
            }
            "spot" => return self.spot(p).map(|d| d.map(|(d, at)| (d, Some(at)))),
            "projector" => return self.projector(p).map(|d| d.map(|(d, at)| (d, Some(at)))),
            _ => return Err(super::kinds::unknown_type(self.doc, e)),
        };
        p.finish(&["sampling_weight"], &mut self.report)?;
        let power = match &desc {
            LightDesc::Point { intensity: c, .. }
            | LightDesc::Directional { irradiance: c, .. }
            | LightDesc::Environment { radiance: c }
            | LightDesc::Sun { radiance: c, .. } => c.max_element(),
            LightDesc::EnvironmentMap { map } => map.integral(),
            LightDesc::Spot { .. } | LightDesc::Projector { .. } => {
                unreachable!("spot and projector return above")
            }
        };
        Ok((power > 0.0).then_some((desc, None)))
    }

    /// Mitsuba's `spot`: `intensity` (default 1), an optional `texture` over the cone,
    /// `cutoff_angle` (degrees, default 20), `beam_width` (default ¾ of the cutoff), `to_world`
    /// (a rigid motion: +z is the beam's axis). None when it emits nothing.
    pub(super) fn spot(&mut self, p: Plugin<'a>) -> Result<Option<(LightDesc, DVec3)>, SceneError> {
        let e = p.elem;
        let opts = self.opts;
        let intensity = p
            .color("intensity", ColorUse::Emission, opts, &mut self.report)?
            .unwrap_or(Color::ONE);
        let texture = match p.texture("texture") {
            Some(t) => Some(self.texture(t)?),
            None if p.has("texture") => {
                return Err(p.err(e, "a spot light's `texture` must be a <texture>"))
            }
            None => None,
        };
        let cutoff = p.float("cutoff_angle")?.unwrap_or(20.0);
        let beam = p.float("beam_width")?.unwrap_or(0.75 * cutoff);
        // The texture lies on the plane z = 1 in front of the light, so its cone must be too.
        let max = if texture.is_some() { 90.0 } else { 180.0 };
        if !(cutoff > 0.0 && cutoff < max) {
            return Err(p.err(
                e,
                format!(
                    "a spot light's `cutoff_angle` must lie in (0°, {max}°){}, got {cutoff}",
                    if texture.is_some() {
                        " with a texture"
                    } else {
                        ""
                    }
                ),
            ));
        }
        if !(beam >= 0.0 && beam.is_finite()) {
            return Err(p.err(e, format!("a spot light's `beam_width` must be a non-negative angle in degrees, got {beam}")));
        }
        let (to_world, position) = rigid_to_world(&p, "a spot light")?;
        p.finish(&["sampling_weight"], &mut self.report)?;
        let dark = intensity.max_element() <= 0.0
            || texture.as_ref().is_some_and(|t| t.max_value() <= 0.0);
        Ok((!dark).then_some((
            LightDesc::Spot {
                position: glam::Vec3::ZERO,
                to_world,
                intensity,
                texture,
                cutoff: (cutoff as f32).to_radians(),
                beam_width: (beam as f32).to_radians(),
            },
            position,
        )))
    }

    /// Mitsuba's `projector`: `irradiance` (a colour or a texture on the image plane at z = 1,
    /// default 1), `scale` (default 1), the field of view as a perspective sensor gives it (`fov`
    /// with `fov_axis`, or `focal_length` 50mm by default) for the image's aspect ratio (1 for a
    /// colour), `to_world` (a rigid motion: +z is the optical axis). None when it emits nothing.
    pub(super) fn projector(
        &mut self,
        p: Plugin<'a>,
    ) -> Result<Option<(LightDesc, DVec3)>, SceneError> {
        let e = p.elem;
        let opts = self.opts;
        let (irradiance, aspect) = match p.texture("irradiance") {
            Some(t) => {
                let tex = self.texture(t)?;
                let aspect = match &tex {
                    Texture::Bitmap(b) => b.width as f64 / b.height as f64,
                    _ => 1.0,
                };
                (tex, aspect)
            }
            None => (
                Texture::Constant(
                    p.color("irradiance", ColorUse::Emission, opts, &mut self.report)?
                        .unwrap_or(Color::ONE),
                ),
                1.0,
            ),
        };
        let scale = p.float("scale")?.unwrap_or(1.0);
        if !(scale >= 0.0 && scale.is_finite()) {
            return Err(p.err(
                e,
                format!("a projector's `scale` must be finite and non-negative, got {scale}"),
            ));
        }
        let tan_x = projector_tan_half_x(&p, aspect)?;
        let (to_world, position) = rigid_to_world(&p, "a projector")?;
        p.finish(&["sampling_weight"], &mut self.report)?;
        let dark = scale == 0.0 || irradiance.max_value() <= 0.0;
        Ok((!dark).then_some((
            LightDesc::Projector {
                position: glam::Vec3::ZERO,
                to_world,
                irradiance,
                scale: scale as f32,
                tan_half: Vec2::new(tan_x as f32, (tan_x / aspect) as f32),
            },
            position,
        )))
    }
}

/// lt's `sun`: `direction` (the light's travel, as Mitsuba's `directional`), `solid_angle` (sr,
/// in (0, 2π)), and `radiance` or `irradiance` (what a surface facing it receives, turned into
/// radiance by `SunLight::radiance_from_irradiance`).
fn sun(p: &Plugin, report: &mut crate::LoadReport) -> Result<LightDesc, SceneError> {
    let e = p.elem;
    let opts = crate::LoadOptions::default();
    let Some(travel) = p.vec3("direction")? else {
        return Err(p.err(e, "a sun needs a `direction`"));
    };
    let towards = -DVec3::from_array(travel).as_vec3();
    if !(towards.length() > 0.0) || !towards.is_finite() {
        return Err(p.err(e, "the sun's `direction` is the zero vector"));
    }
    let Some(solid_angle) = p.float("solid_angle")? else {
        return Err(p.err(e, "a sun needs a `solid_angle`"));
    };
    let solid_angle = solid_angle as f32;
    if !(solid_angle > 0.0 && solid_angle < 2.0 * lt_core::math::PI) {
        return Err(p.err(
            e,
            format!("a sun's `solid_angle` must lie in (0, 2π) sr, got {solid_angle}"),
        ));
    }
    let radiance = p.color("radiance", ColorUse::Emission, &opts, report)?;
    let irradiance = p.color("irradiance", ColorUse::Emission, &opts, report)?;
    let radiance = match (radiance, irradiance) {
        (Some(r), None) => r,
        (None, Some(i)) => {
            let l = lt_core::light::SunLight::radiance_from_irradiance(i, solid_angle);
            if !l.is_finite() {
                return Err(p.err(e, format!("a sun's `solid_angle` {solid_angle} is too small to turn the irradiance into a finite radiance")));
            }
            l
        }
        _ => return Err(p.err(e, "a sun takes `radiance` or `irradiance` (one of them)")),
    };
    Ok(LightDesc::Sun {
        direction: towards.normalize(),
        solid_angle,
        radiance,
    })
}

/// The rotation and the translation of a light's `to_world` (identity when absent), which must
/// be a rigid motion: angles and directions in the light's frame keep their meaning only then.
pub(super) fn rigid_to_world(p: &Plugin, what: &str) -> Result<(glam::Mat3, DVec3), SceneError> {
    let Some((x, te)) = p.transform("to_world")? else {
        return Ok((glam::Mat3::IDENTITY, DVec3::ZERO));
    };
    let m = glam::DMat3::from_mat4(x.m);
    let ortho = (m.transpose() * m - glam::DMat3::IDENTITY)
        .to_cols_array()
        .iter()
        .fold(0.0f64, |a, v| a.max(v.abs()));
    if !(ortho < 1e-6) || m.determinant() < 0.0 {
        return Err(p.err(
            te,
            format!("{what}'s to_world must be a rotation (no scale, shear or mirror)"),
        ));
    }
    let position = x.m.transform_point3(DVec3::ZERO);
    if !crate::world::in_range(position) {
        return Err(p.err(te, out_of_range_message(what, position)));
    }
    Ok((crate::transform::positive_zeros(m).as_mat3(), position))
}

/// tan(fov_x / 2) of a projector whose image has width / height = `aspect`, read as Mitsuba reads
/// a perspective sensor's field of view: `fov` across `fov_axis` (x, y, diagonal, smaller or
/// larger; default x), or a 35 mm `focal_length` (default 50mm) across the diagonal.
pub(super) fn projector_tan_half_x(p: &Plugin, aspect: f64) -> Result<f64, SceneError> {
    let e = p.elem;
    let axis = match p.string("fov_axis")? {
        None => "x",
        Some((a @ ("x" | "y" | "diagonal" | "smaller" | "larger"), _)) => a,
        Some((a, ae)) => {
            return Err(p.err(
                ae,
                format!("`fov_axis` must be x, y, diagonal, smaller or larger, got `{a}`"),
            ))
        }
    };
    let (tan_half, axis) = match (p.float("fov")?, p.string("focal_length")?) {
        (Some(_), Some((_, fe))) => {
            return Err(p.err(fe, "give the projector `fov` or `focal_length`, not both"))
        }
        (Some(f), None) => {
            if !(f > 0.0 && f < 180.0) {
                return Err(p.err(
                    e,
                    format!("a projector's `fov` must lie in (0°, 180°), got {f}"),
                ));
            }
            ((0.5 * f).to_radians().tan(), axis)
        }
        (None, f) => {
            let (text, at) = f.unwrap_or(("50mm", e));
            let mm = text.trim().trim_end_matches("mm").trim();
            let f: f64 = mm.parse().ok().filter(|f: &f64| *f > 0.0 && f.is_finite()).ok_or_else(|| {
                p.err(at, format!("`focal_length` must be a positive length in mm like \"50mm\", got `{text}`"))
            })?;
            // 35 mm film equivalent: half the 36 × 24 mm frame's diagonal over the focal length.
            (
                (36.0f64 * 36.0 + 24.0 * 24.0).sqrt() / (2.0 * f),
                "diagonal",
            )
        }
    };
    let to_x = match axis {
        "y" => aspect,
        "diagonal" => aspect / (1.0 + aspect * aspect).sqrt(),
        "smaller" if aspect > 1.0 => aspect,
        "larger" if aspect < 1.0 => aspect,
        _ => 1.0,
    };
    Ok(tan_half * to_x)
}

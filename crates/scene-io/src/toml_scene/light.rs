//! A TOML `[[lights]]` entry: point, spot, projector, sun, directional, environment, envmap.

use crate::error::Ctx;
use crate::toml_scene::schema::{LightDef, S};
use crate::SceneError;
use glam::DVec3;
use lt_core::light::SunLight;
use lt_core::math::PI;
use lt_core::scene::LightDesc;

/// A light with a world position (kept in f64 until the one rounding) or without one.
pub(super) enum Placed {
    At(DVec3, LightDesc),
    Anywhere(LightDesc),
}

/// What every light builder reads: the file, the entry, its span, how errors name it, and the
/// keys it gives (to refuse those its type does not take).
pub(super) struct Entry<'f> {
    ctx: &'f Ctx<'f>,
    d: &'f LightDef,
    span: std::ops::Range<usize>,
    what: String,
    given: Vec<(&'static str, Option<std::ops::Range<usize>>)>,
}

type Given<'g> = &'g [(&'static str, Option<std::ops::Range<usize>>)];

impl<'f> Entry<'f> {
    fn parts(
        &self,
    ) -> (
        &'f Ctx<'f>,
        &'f LightDef,
        std::ops::Range<usize>,
        &str,
        Given<'_>,
    ) {
        (self.ctx, self.d, self.span.clone(), &self.what, &self.given)
    }
}

/// A light builder: the light, or None when it emits nothing.
type LightBuilder = fn(&Entry) -> Result<Option<Placed>, SceneError>;

/// Every TOML light type with its builder.
const LIGHTS: &[(&str, LightBuilder)] = &[
    ("point", point),
    ("spot", spot),
    ("projector", projector),
    ("sun", sun),
    ("directional", directional),
    ("environment", environment),
    ("envmap", envmap),
];

/// The light, or None when it emits nothing.
pub(super) fn light<'f>(
    ctx: &'f Ctx<'f>,
    def: &'f S<LightDef>,
) -> Result<Option<Placed>, SceneError> {
    let d = def.get_ref();
    let kind = d.kind.get_ref().as_str();
    let Some(&(_, build)) = LIGHTS.iter().find(|(name, _)| *name == kind) else {
        let known: Vec<&str> = LIGHTS.iter().map(|(name, _)| *name).collect();
        let (last, rest) = known.split_last().expect("LIGHTS is not empty");
        return Err(ctx.at(
            d.kind.span(),
            format!(
                "unknown light type `{kind}` (expected {} or {last})",
                rest.join(", ")
            ),
        ));
    };
    let given = vec![
        ("position", d.position.as_ref().map(S::span)),
        ("intensity", d.intensity.as_ref().map(S::span)),
        ("direction", d.direction.as_ref().map(S::span)),
        ("solid_angle", d.solid_angle.as_ref().map(S::span)),
        ("radiance", d.radiance.as_ref().map(S::span)),
        ("irradiance", d.irradiance.as_ref().map(S::span)),
        ("file", d.file.as_ref().map(S::span)),
        ("scale", d.scale.as_ref().map(S::span)),
        ("rotate", d.rotate.as_ref().map(S::span)),
        ("target", d.target.as_ref().map(S::span)),
        ("up", d.up.as_ref().map(S::span)),
        ("cutoff_angle", d.cutoff_angle.as_ref().map(S::span)),
        ("beam_width", d.beam_width.as_ref().map(S::span)),
        ("texture", d.texture.as_ref().map(S::span)),
        ("fov", d.fov.as_ref().map(S::span)),
    ];
    build(&Entry {
        ctx,
        d,
        span: def.span(),
        what: format!("a {kind} light"),
        given,
    })
}

fn point(entry: &Entry) -> Result<Option<Placed>, SceneError> {
    let (ctx, d, span, what, given) = entry.parts();
    ctx.only(&given, &["position", "intensity"], &what)?;
    let position = ctx.dvec3(ctx.need(&d.position, "position", &span, &what)?, "position")?;
    let intensity = ctx.color(
        ctx.need(&d.intensity, "intensity", &span, &what)?,
        "intensity",
        false,
    )?;
    let desc = LightDesc::Point {
        position: glam::Vec3::ZERO,
        intensity,
    };
    Ok((intensity.max_element() > 0.0).then_some(Placed::At(position, desc)))
}

fn sun(entry: &Entry) -> Result<Option<Placed>, SceneError> {
    let (ctx, d, span, what, given) = entry.parts();
    ctx.only(
        &given,
        &["direction", "solid_angle", "radiance", "irradiance"],
        &what,
    )?;
    let dir = ctx.need(&d.direction, "direction", &span, &what)?;
    let direction = ctx.vec3(dir, "direction")?;
    if !(direction.length() > 0.0) {
        return Err(ctx.at(
            dir.span(),
            "`direction` (towards the sun) is the zero vector",
        ));
    }
    let sa = ctx.need(&d.solid_angle, "solid_angle", &span, &what)?;
    let solid_angle = ctx.positive(sa, "solid_angle")?;
    if !(solid_angle < 2.0 * PI) {
        return Err(ctx.at(
            sa.span(),
            format!("`solid_angle` must be below 2π sr (a hemisphere), got {solid_angle}"),
        ));
    }
    let radiance = match (&d.radiance, &d.irradiance) {
        (Some(r), None) => ctx.color(r, "radiance", false)?,
        (None, Some(e)) => {
            let l =
                SunLight::radiance_from_irradiance(ctx.color(e, "irradiance", false)?, solid_angle);
            if !l.is_finite() {
                return Err(ctx.at(sa.span(), format!("`solid_angle` {solid_angle} is too small to turn the irradiance into a finite radiance")));
            }
            l
        }
        (Some(_), Some(e)) => {
            return Err(ctx.at(
                e.span(),
                "give the sun `radiance` or `irradiance`, not both",
            ))
        }
        (None, None) => {
            return Err(ctx.at(
                span,
                "missing required key `radiance` or `irradiance` for a sun light",
            ))
        }
    };
    let desc = LightDesc::Sun {
        direction: direction.normalize(),
        solid_angle,
        radiance,
    };
    Ok(emitting(desc))
}

fn directional(entry: &Entry) -> Result<Option<Placed>, SceneError> {
    let (ctx, d, span, what, given) = entry.parts();
    // A delta in direction has no solid angle, so no radiance: say so before the generic
    // "does not apply" check would.
    if let Some(r) = &d.radiance {
        return Err(ctx.at(
            r.span(),
            "a directional light takes `irradiance` (W/m² on a surface facing it), not \
             `radiance`: it is a delta in direction, with no solid angle to spread a \
             radiance over (for a light of finite angular size use type = \"sun\")",
        ));
    }
    ctx.only(&given, &["direction", "irradiance"], &what)?;
    let dir = ctx.need(&d.direction, "direction", &span, &what)?;
    let direction = ctx.vec3(dir, "direction")?;
    if !(direction.length() > 0.0) {
        return Err(ctx.at(
            dir.span(),
            "`direction` (towards the light) is the zero vector",
        ));
    }
    let irradiance = ctx.color(
        ctx.need(&d.irradiance, "irradiance", &span, &what)?,
        "irradiance",
        false,
    )?;
    let desc = LightDesc::Directional {
        direction: direction.normalize(),
        irradiance,
    };
    Ok(emitting(desc))
}

fn environment(entry: &Entry) -> Result<Option<Placed>, SceneError> {
    let (ctx, d, span, what, given) = entry.parts();
    ctx.only(&given, &["radiance"], &what)?;
    let desc = LightDesc::Environment {
        radiance: ctx.color(
            ctx.need(&d.radiance, "radiance", &span, &what)?,
            "radiance",
            false,
        )?,
    };
    Ok(emitting(desc))
}

fn envmap(entry: &Entry) -> Result<Option<Placed>, SceneError> {
    let (ctx, d, span, what, given) = entry.parts();
    ctx.only(&given, &["file", "scale", "rotate"], &what)?;
    let file = ctx.need(&d.file, "file", &span, &what)?;
    let scale = match &d.scale {
        None => 1.0,
        Some(s) => ctx.num(s, "scale")?,
    };
    let to_world = match &d.rotate {
        None => glam::Mat3::IDENTITY,
        Some(r) => crate::transform::rotate_def(ctx, r)?.as_mat3(),
    };
    let path = ctx.base_dir.join(file.get_ref());
    let map = crate::image_file::read_environment_map(&path, scale, to_world)
        .map_err(|m| ctx.at(file.span(), m))?;
    let desc = LightDesc::EnvironmentMap {
        map: std::sync::Arc::new(map),
    };
    Ok(emitting(desc))
}

fn spot(entry: &Entry) -> Result<Option<Placed>, SceneError> {
    let (ctx, d, span, what, given) = entry.parts();
    ctx.only(
        &given,
        &[
            "position",
            "target",
            "up",
            "intensity",
            "cutoff_angle",
            "beam_width",
            "texture",
        ],
        &what,
    )?;
    let (position, to_world) = aimed(ctx, d, &span, &what)?;
    let intensity = ctx.color(
        ctx.need(&d.intensity, "intensity", &span, &what)?,
        "intensity",
        false,
    )?;
    let cutoff = match &d.cutoff_angle {
        None => 20.0,
        Some(c) => ctx.positive(c, "cutoff_angle")?,
    };
    let texture = match &d.texture {
        None => None,
        Some(t) => Some(crate::toml_scene::texture::texture(ctx, t)?),
    };
    let max = if texture.is_some() { 90.0 } else { 180.0 };
    if !(cutoff < max) {
        let at = d.cutoff_angle.as_ref().map_or(span.clone(), S::span);
        return Err(ctx.at(
            at,
            format!(
                "`cutoff_angle` must be below {max}°{}, got {cutoff}",
                if texture.is_some() {
                    " with a texture (it lies on a plane in front of the light)"
                } else {
                    ""
                }
            ),
        ));
    }
    let beam = match &d.beam_width {
        None => 0.75 * cutoff,
        Some(b) => {
            let b = ctx.num(b, "beam_width")?;
            if !(b >= 0.0) {
                return Err(ctx.at(
                    d.beam_width.as_ref().unwrap().span(),
                    format!("`beam_width` must be a non-negative angle in degrees, got {b}"),
                ));
            }
            b
        }
    };
    let dark =
        intensity.max_element() <= 0.0 || texture.as_ref().is_some_and(|t| t.max_value() <= 0.0);
    let desc = LightDesc::Spot {
        position: glam::Vec3::ZERO,
        to_world,
        intensity,
        texture,
        cutoff: cutoff.to_radians(),
        beam_width: beam.to_radians(),
    };
    Ok((!dark).then_some(Placed::At(position, desc)))
}

fn projector(entry: &Entry) -> Result<Option<Placed>, SceneError> {
    let (ctx, d, span, what, given) = entry.parts();
    ctx.only(
        &given,
        &[
            "position",
            "target",
            "up",
            "irradiance",
            "texture",
            "scale",
            "fov",
        ],
        &what,
    )?;
    let (position, to_world) = aimed(ctx, d, &span, &what)?;
    let (irradiance, aspect) = match (&d.texture, &d.irradiance) {
        (Some(_), Some(e)) => {
            return Err(ctx.at(
                e.span(),
                "give the projector `irradiance` or `texture`, not both",
            ))
        }
        (Some(t), None) => {
            let tex = crate::toml_scene::texture::texture(ctx, t)?;
            let aspect = match &tex {
                lt_core::texture::Texture::Bitmap(b) => b.width as f64 / b.height as f64,
                _ => 1.0,
            };
            (tex, aspect)
        }
        (None, Some(e)) => (
            lt_core::texture::Texture::Constant(ctx.color(e, "irradiance", false)?),
            1.0,
        ),
        (None, None) => {
            return Err(ctx.at(
                span,
                "missing required key `irradiance` or `texture` for a projector light",
            ))
        }
    };
    let scale = match &d.scale {
        None => 1.0,
        Some(s) => ctx.num(s, "scale")?,
    };
    let fov_def = ctx.need(&d.fov, "fov", &span, &what)?;
    // In f64, as the XML loader computes it, so that a converted scene reads back exactly.
    let fov = *fov_def.get_ref();
    if !(fov > 0.0 && fov < 180.0 && scale >= 0.0) {
        return Err(ctx.at(fov_def.span(), format!("a projector needs 0 < `fov` < 180 (degrees) and `scale` ≥ 0, got {fov} and {scale}")));
    }
    let tan_x = (0.5 * fov).to_radians().tan();
    let dark = scale == 0.0 || irradiance.max_value() <= 0.0;
    let desc = LightDesc::Projector {
        position: glam::Vec3::ZERO,
        to_world,
        irradiance,
        scale,
        tan_half: glam::Vec2::new(tan_x as f32, (tan_x / aspect) as f32),
    };
    Ok((!dark).then_some(Placed::At(position, desc)))
}

/// A light placed nowhere in particular, or None when it emits nothing.
fn emitting(desc: LightDesc) -> Option<Placed> {
    let power = match &desc {
        LightDesc::Point { intensity: c, .. }
        | LightDesc::Sun { radiance: c, .. }
        | LightDesc::Directional { irradiance: c, .. }
        | LightDesc::Environment { radiance: c } => c.max_element(),
        LightDesc::EnvironmentMap { map } => map.integral(),
        LightDesc::Spot { .. } | LightDesc::Projector { .. } => {
            unreachable!("spot and projector are placed at their position")
        }
    };
    (power > 0.0).then_some(Placed::Anywhere(desc))
}

/// The world position and the rotation (Mitsuba's lookat) of a light aimed from `position` at
/// `target`, with `up` or its default (`transform::default_up`).
pub(super) fn aimed(
    ctx: &Ctx,
    d: &LightDef,
    span: &std::ops::Range<usize>,
    what: &str,
) -> Result<(DVec3, glam::Mat3), SceneError> {
    let position = ctx.dvec3(ctx.need(&d.position, "position", span, what)?, "position")?;
    let target_def = ctx.need(&d.target, "target", span, what)?;
    let target = ctx.dvec3(target_def, "target")?;
    let up = match &d.up {
        Some(u) => ctx.dvec3(u, "up")?,
        None => crate::transform::default_up(target - position),
    };
    let at = d.up.as_ref().map_or(target_def.span(), S::span);
    let r = crate::transform::look_at_rotation(position, target, up).map_err(|m| ctx.at(at, m))?;
    Ok((position, r.as_mat3()))
}

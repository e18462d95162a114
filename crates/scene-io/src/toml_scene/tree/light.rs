//! A TOML `[[lights]]` entry as an `<emitter>`: `point` → `point` (`position`, `intensity`),
//! `environment` → `constant`, `directional` → `directional` (its `direction`, towards the light
//! here, negated: Mitsuba's is the light's travel), `envmap` → `envmap` (`file` → `filename`,
//! `rotate` → a `to_world` rotation), `spot` and `projector` → the same types with `position`,
//! `target`, `up` → a `to_world` look-at (`up`'s default, `transform::default_up`, written out),
//! `sun` → lt's own `sun` emitter (Mitsuba has no distant light of finite solid angle), and
//! `medium` → a `<ref name="medium">`. Positions go into the tree in f64, as given; every
//! check that speaks of TOML's keys is made here.

use super::texture::{color, texture};
use super::{elem, float, float64, plugin, point, reference, string};
use crate::error::Ctx;
use crate::toml_scene::schema::{LightDef, S};
use crate::xml::doc::Elem;
use crate::SceneError;
use glam::DVec3;
use lt_core::math::PI;
use std::ops::Range;

/// The TOML light types, for the unknown type's message.
const TYPES: [&str; 7] = [
    "point",
    "spot",
    "projector",
    "sun",
    "directional",
    "environment",
    "envmap",
];

/// The light as an `<emitter>` element.
pub(crate) fn light(ctx: &Ctx, def: &S<LightDef>) -> Result<Elem, SceneError> {
    let d = def.get_ref();
    let kind = d.kind.get_ref().as_str();
    let span = def.span();
    let what = format!("a {kind} light");
    let given = given!(d; position, intensity, direction, solid_angle, radiance, irradiance, file, scale, rotate, target, up, cutoff_angle, beam_width, texture, fov);
    let e = match kind {
        "point" => {
            ctx.only(&given, &["position", "intensity"], &what)?;
            let mut e = plugin("emitter", "point", span.clone());
            let p = ctx.need(&d.position, "position", &span, &what)?;
            e.children
                .push(point("position", ctx.dvec3(p, "position")?, p.span()));
            let i = ctx.need(&d.intensity, "intensity", &span, &what)?;
            e.children
                .push(color(ctx, i, "intensity", "intensity", false)?);
            e
        }
        "sun" => sun(ctx, d, span.clone(), &what, &given)?,
        "directional" => {
            // A delta in direction has no solid angle, so no radiance: say so before the
            // generic "does not apply" check would.
            if let Some(r) = &d.radiance {
                return Err(ctx.at(
                    r.span(),
                    "a directional light takes `irradiance` (W/m² on a surface facing it), not \
                     `radiance`: it is a delta in direction, with no solid angle to spread a \
                     radiance over (for a light of finite angular size use type = \"sun\")",
                ));
            }
            ctx.only(&given, &["direction", "irradiance"], &what)?;
            let mut e = plugin("emitter", "directional", span.clone());
            let dir = ctx.need(&d.direction, "direction", &span, &what)?;
            e.children.push(travel(ctx, dir, "the light")?);
            let i = ctx.need(&d.irradiance, "irradiance", &span, &what)?;
            e.children
                .push(color(ctx, i, "irradiance", "irradiance", false)?);
            e
        }
        "environment" => {
            ctx.only(&given, &["radiance"], &what)?;
            let mut e = plugin("emitter", "constant", span.clone());
            let r = ctx.need(&d.radiance, "radiance", &span, &what)?;
            e.children
                .push(color(ctx, r, "radiance", "radiance", false)?);
            e
        }
        "envmap" => {
            ctx.only(&given, &["file", "scale", "rotate"], &what)?;
            let mut e = plugin("emitter", "envmap", span.clone());
            let file = ctx.need(&d.file, "file", &span, &what)?;
            e.children
                .push(string("filename", file.get_ref(), file.span()));
            if let Some(s) = &d.scale {
                e.children
                    .push(float("scale", ctx.num(s, "scale")?, s.span()));
            }
            if let Some(r) = &d.rotate {
                crate::transform::rotate_def(ctx, r)?;
                let (a, deg) = (r.get_ref().axis, r.get_ref().angle);
                let mut t = elem("transform", &[("name", "to_world")], r.span());
                let (x, y, z, angle) = (
                    format!("{}", a[0]),
                    format!("{}", a[1]),
                    format!("{}", a[2]),
                    format!("{deg}"),
                );
                t.children.push(elem(
                    "rotate",
                    &[("x", &x), ("y", &y), ("z", &z), ("angle", &angle)],
                    r.span(),
                ));
                e.children.push(t);
            }
            e
        }
        "spot" => spot(ctx, d, span.clone(), &what, &given)?,
        "projector" => projector(ctx, d, span.clone(), &what, &given)?,
        other => {
            let (last, rest) = TYPES.split_last().expect("TYPES is not empty");
            return Err(ctx.at(
                d.kind.span(),
                format!(
                    "unknown light type `{other}` (expected {} or {last})",
                    rest.join(", ")
                ),
            ));
        }
    };
    Ok(e)
}

/// The light's `medium`, a reference inside it (the name checked by the caller).
pub(crate) fn with_medium(mut e: Elem, d: &LightDef) -> Elem {
    if let Some(m) = &d.medium {
        e.children.push(reference("medium", m.get_ref(), m.span()));
    }
    e
}

type Given<'g> = &'g [(&'static str, Option<Range<usize>>)];

/// A TOML `direction` (towards the light) as Mitsuba's `direction` (the light's travel): the f32
/// direction negated, which both loaders normalise.
fn travel(ctx: &Ctx, dir: &S<[f64; 3]>, towards: &str) -> Result<Elem, SceneError> {
    let u = ctx.vec3(dir, "direction")?;
    if !(u.length() > 0.0) {
        return Err(ctx.at(
            dir.span(),
            format!("`direction` (towards {towards}) is the zero vector"),
        ));
    }
    let v = format!("{}, {}, {}", -u.x, -u.y, -u.z);
    Ok(elem(
        "vector",
        &[("name", "direction"), ("value", &v)],
        dir.span(),
    ))
}

fn sun(
    ctx: &Ctx,
    d: &LightDef,
    span: Range<usize>,
    what: &str,
    given: Given,
) -> Result<Elem, SceneError> {
    ctx.only(
        given,
        &["direction", "solid_angle", "radiance", "irradiance"],
        what,
    )?;
    let mut e = plugin("emitter", "sun", span.clone());
    let dir = ctx.need(&d.direction, "direction", &span, what)?;
    e.children.push(travel(ctx, dir, "the sun")?);
    let sa = ctx.need(&d.solid_angle, "solid_angle", &span, what)?;
    let solid_angle = ctx.positive(sa, "solid_angle")?;
    if !(solid_angle < 2.0 * PI) {
        return Err(ctx.at(
            sa.span(),
            format!("`solid_angle` must be below 2π sr (a hemisphere), got {solid_angle}"),
        ));
    }
    e.children
        .push(float("solid_angle", solid_angle, sa.span()));
    match (&d.radiance, &d.irradiance) {
        (Some(r), None) => e
            .children
            .push(color(ctx, r, "radiance", "radiance", false)?),
        (None, Some(i)) => {
            let c = ctx.color(i, "irradiance", false)?;
            let l = lt_core::light::SunLight::radiance_from_irradiance(c, solid_angle);
            if !l.is_finite() {
                return Err(ctx.at(sa.span(), format!("`solid_angle` {solid_angle} is too small to turn the irradiance into a finite radiance")));
            }
            e.children
                .push(color(ctx, i, "irradiance", "irradiance", false)?);
        }
        (Some(_), Some(i)) => {
            return Err(ctx.at(
                i.span(),
                "give the sun `radiance` or `irradiance`, not both",
            ))
        }
        (None, None) => {
            return Err(ctx.at(
                span,
                "missing required key `radiance` or `irradiance` for a sun light",
            ))
        }
    }
    Ok(e)
}

/// A spot light's or projector's `to_world`: Mitsuba's look-at from `position` to `target` with
/// `up` or its default, checked as TOML's.
fn aimed(ctx: &Ctx, d: &LightDef, span: &Range<usize>, what: &str) -> Result<Elem, SceneError> {
    let p = ctx.need(&d.position, "position", span, what)?;
    let position = ctx.dvec3(p, "position")?;
    let target_def = ctx.need(&d.target, "target", span, what)?;
    let target = ctx.dvec3(target_def, "target")?;
    let up = match &d.up {
        Some(u) => ctx.dvec3(u, "up")?,
        None => crate::transform::default_up(target - position),
    };
    let at = d.up.as_ref().map_or(target_def.span(), S::span);
    crate::transform::look_at_rotation(position, target, up).map_err(|m| ctx.at(at, m))?;
    let v = |p: DVec3| format!("{}, {}, {}", p.x, p.y, p.z);
    let mut t = elem("transform", &[("name", "to_world")], p.span());
    t.children.push(elem(
        "lookat",
        &[
            ("origin", &v(position)),
            ("target", &v(target)),
            ("up", &v(up)),
        ],
        p.span(),
    ));
    Ok(t)
}

fn spot(
    ctx: &Ctx,
    d: &LightDef,
    span: Range<usize>,
    what: &str,
    given: Given,
) -> Result<Elem, SceneError> {
    ctx.only(
        given,
        &[
            "position",
            "target",
            "up",
            "intensity",
            "cutoff_angle",
            "beam_width",
            "texture",
        ],
        what,
    )?;
    let mut e = plugin("emitter", "spot", span.clone());
    e.children.push(aimed(ctx, d, &span, what)?);
    let i = ctx.need(&d.intensity, "intensity", &span, what)?;
    e.children
        .push(color(ctx, i, "intensity", "intensity", false)?);
    let cutoff = match &d.cutoff_angle {
        None => 20.0,
        Some(c) => ctx.positive(c, "cutoff_angle")?,
    };
    if let Some(t) = &d.texture {
        e.children.push(texture(ctx, t, "texture")?);
    }
    let max = if d.texture.is_some() { 90.0 } else { 180.0 };
    if !(cutoff < max) {
        let at = d.cutoff_angle.as_ref().map_or(span.clone(), S::span);
        return Err(ctx.at(
            at,
            format!(
                "`cutoff_angle` must be below {max}°{}, got {cutoff}",
                if d.texture.is_some() {
                    " with a texture (it lies on a plane in front of the light)"
                } else {
                    ""
                }
            ),
        ));
    }
    // Both angles written in f32 as TOML computes them (¾ of the cutoff in f32).
    let beam = match &d.beam_width {
        None => 0.75 * cutoff,
        Some(b) => {
            let x = ctx.num(b, "beam_width")?;
            if !(x >= 0.0) {
                return Err(ctx.at(
                    b.span(),
                    format!("`beam_width` must be a non-negative angle in degrees, got {x}"),
                ));
            }
            x
        }
    };
    let at = |o: &Option<S<f64>>| o.as_ref().map_or(span.clone(), S::span);
    e.children
        .push(float("cutoff_angle", cutoff, at(&d.cutoff_angle)));
    e.children
        .push(float("beam_width", beam, at(&d.beam_width)));
    Ok(e)
}

fn projector(
    ctx: &Ctx,
    d: &LightDef,
    span: Range<usize>,
    what: &str,
    given: Given,
) -> Result<Elem, SceneError> {
    ctx.only(
        given,
        &[
            "position",
            "target",
            "up",
            "irradiance",
            "texture",
            "scale",
            "fov",
        ],
        what,
    )?;
    let mut e = plugin("emitter", "projector", span.clone());
    e.children.push(aimed(ctx, d, &span, what)?);
    match (&d.texture, &d.irradiance) {
        (Some(_), Some(i)) => {
            return Err(ctx.at(
                i.span(),
                "give the projector `irradiance` or `texture`, not both",
            ))
        }
        (Some(t), None) => e.children.push(texture(ctx, t, "irradiance")?),
        (None, Some(i)) => e
            .children
            .push(color(ctx, i, "irradiance", "irradiance", false)?),
        (None, None) => {
            return Err(ctx.at(
                span,
                "missing required key `irradiance` or `texture` for a projector light",
            ))
        }
    }
    let scale = match &d.scale {
        None => 1.0,
        Some(s) => ctx.num(s, "scale")?,
    };
    let fov_def = ctx.need(&d.fov, "fov", &span, what)?;
    // In f64, as given: the builder computes tan(fov/2) in f64.
    let fov = *fov_def.get_ref();
    if !(fov > 0.0 && fov < 180.0 && scale >= 0.0) {
        return Err(ctx.at(fov_def.span(), format!("a projector needs 0 < `fov` < 180 (degrees) and `scale` ≥ 0, got {fov} and {scale}")));
    }
    e.children.push(float64("fov", fov, fov_def.span()));
    if let Some(s) = &d.scale {
        e.children.push(float("scale", scale, s.span()));
    }
    Ok(e)
}

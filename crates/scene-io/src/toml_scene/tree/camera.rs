//! TOML's `[camera]` (with `[camera.filter]`) and `[render]` as the tree's `<sensor>` (with its
//! `<film>`, `<rfilter>` and `<sampler>`) and `<integrator>`: `type` → the sensor type, `eye`,
//! `target`, `up` → a `to_world` look-at (f64, as given; `up` written out), `resolution` → the
//! film's `width` and `height`, `filter` → `<rfilter>`, `principal_point_offset` → its `_x`/`_y`,
//! `medium` → a `<ref name="medium">`, `spp` → the sampler's `sample_count`, `max_depth` and
//! `rr_depth` → a `path` integrator's. TOML's defaults differ from Mitsuba's (a box filter of one
//! pixel, `RenderSettings::default`), so every value is written out. An orthographic camera's
//! `half_width` becomes the sensor's `half_width`, a property of lt's own (Mitsuba scales
//! `to_world` instead, which is how `lt convert` prints it).

use super::{elem, float, integer, plugin, reference, string};
use crate::error::Ctx;
use crate::toml_scene::schema::{CameraDef, FilterDef, FovAxisName, SceneFile, S};
use crate::world::LookAt;
use crate::xml::doc::Elem;
use crate::SceneError;
use glam::DVec3;
use lt_core::scene::RenderSettings;
use std::ops::Range;

/// `[render]` checked, TOML's defaults filled in.
pub(crate) fn settings(ctx: &Ctx, file: &SceneFile) -> Result<RenderSettings, SceneError> {
    let mut s = RenderSettings::default();
    let Some(r) = &file.render else { return Ok(s) };
    let r = r.get_ref();
    if let Some(m) = &r.max_depth {
        s.max_depth = *m.get_ref();
        if s.max_depth == 0 {
            return Err(ctx.at(
                m.span(),
                "`max_depth` must be at least 1 (1 = emitters seen directly)",
            ));
        }
    }
    if let Some(spp) = &r.spp {
        s.spp = *spp.get_ref();
        if s.spp == 0 {
            return Err(ctx.at(spp.span(), "`spp` must be at least 1"));
        }
    }
    s.rr_depth = r.rr_depth.unwrap_or(s.rr_depth);
    Ok(s)
}

/// The `[render]` depths as a `path` integrator (placed at `[render]`, else the file's start).
pub(crate) fn integrator(file: &SceneFile, s: &RenderSettings) -> Elem {
    let span = file.render.as_ref().map_or(0..0, S::span);
    let mut e = plugin("integrator", "path", span.clone());
    e.children
        .push(integer("max_depth", s.max_depth.into(), span.clone()));
    e.children
        .push(integer("rr_depth", s.rr_depth.into(), span));
    e
}

/// The camera as a `<sensor>` sampling `spp` paths per pixel.
pub(crate) fn sensor(ctx: &Ctx, c: &S<CameraDef>, spp: u32) -> Result<Elem, SceneError> {
    let d = c.get_ref();
    let span = c.span();
    let kind = d
        .kind
        .as_ref()
        .map_or("perspective", |k| k.get_ref().as_str());
    let kind_span = d.kind.as_ref().map_or(span.clone(), |k| k.span());
    // Keys that belong to another camera type are refused, not ignored.
    let only = |key: &str, given: bool, types: &str| {
        if given {
            Err(ctx.at(
                span.clone(),
                format!("`{key}` belongs to a {types} camera, not `{kind}`"),
            ))
        } else {
            Ok(())
        }
    };
    if kind != "thinlens" {
        only("aperture_radius", d.aperture_radius.is_some(), "thinlens")?;
        only("focus_distance", d.focus_distance.is_some(), "thinlens")?;
    }
    if kind != "orthographic" {
        only("half_width", d.half_width.is_some(), "orthographic")?;
    }
    let mut e = plugin("sensor", kind, span.clone());
    let fov = match (&d.fov, kind) {
        (Some(f), _) => {
            let fov = ctx.num(f, "fov")?;
            e.children.push(float("fov", fov, f.span()));
            fov
        }
        // Unused by an orthographic camera (its film is `half_width` wide).
        (None, "orthographic") => 90.0,
        (None, _) => return Err(ctx.at(span, format!("a `{kind}` camera needs `fov`"))),
    };
    if kind == "orthographic" {
        only("fov", d.fov.is_some(), "perspective or thinlens")?;
    }
    let axis = d.fov_axis.unwrap_or(FovAxisName::X);
    let axis_name = match axis {
        FovAxisName::X => "x",
        FovAxisName::Y => "y",
        FovAxisName::Smaller => "smaller",
        FovAxisName::Larger => "larger",
    };
    e.children.push(string("fov_axis", axis_name, span.clone()));
    let eye = ctx.dvec3(&d.eye, "eye")?;
    let target = ctx.dvec3(&d.target, "target")?;
    let up = d.up.as_ref().map(|u| ctx.dvec3(u, "up")).transpose()?;
    let up = up.unwrap_or(DVec3::Y);
    let [width, height] = *d.resolution.get_ref();
    // Checked here, in the camera's words (the tree's <lookat> would speak of itself).
    LookAt {
        eye,
        target,
        up,
        fov_deg: fov,
        fov_axis: axis.into(),
        width,
        height,
    }
    .at(DVec3::ZERO)
    .map_err(|m| ctx.at(span.clone(), format!("degenerate camera: {m}")))?;
    e.children.push(look_at(eye, target, up, span.clone()));
    match kind {
        "perspective" => {}
        "thinlens" => {
            let (Some(r), Some(f)) = (&d.aperture_radius, &d.focus_distance) else {
                return Err(ctx.at(
                    span,
                    "a `thinlens` camera needs `aperture_radius` and `focus_distance`",
                ));
            };
            let r = float(
                "aperture_radius",
                ctx.positive(r, "aperture_radius")?,
                r.span(),
            );
            let f = float(
                "focus_distance",
                ctx.positive(f, "focus_distance")?,
                f.span(),
            );
            e.children.extend([r, f]);
        }
        "orthographic" => {
            let (hw, at) = match &d.half_width {
                Some(v) => (ctx.positive(v, "half_width")?, v.span()),
                None => (1.0, span.clone()),
            };
            e.children.push(float("half_width", hw, at));
        }
        other => {
            return Err(ctx.at(
                kind_span,
                format!(
                    "unknown camera type `{other}` (known: perspective, thinlens, orthographic)"
                ),
            ))
        }
    }
    if let Some(o) = &d.principal_point_offset {
        let [x, y] = *o.get_ref();
        for (name, v) in [
            ("principal_point_offset_x", x),
            ("principal_point_offset_y", y),
        ] {
            e.children.push(float(name, v as f32, o.span()));
        }
    }
    if let Some(m) = &d.medium {
        e.children.push(reference("medium", m.get_ref(), m.span()));
    }
    let mut sampler = plugin("sampler", "independent", span.clone());
    sampler
        .children
        .push(integer("sample_count", spp.into(), span.clone()));
    e.children.push(sampler);
    let [w, h] = *d.resolution.get_ref();
    let mut film = plugin("film", "hdrfilm", d.resolution.span());
    film.children
        .push(integer("width", w.into(), d.resolution.span()));
    film.children
        .push(integer("height", h.into(), d.resolution.span()));
    film.children.push(match &d.filter {
        Some(f) => rfilter(ctx, f)?,
        // TOML's default: the box of one pixel (Mitsuba's `box` and its default radius).
        None => plugin("rfilter", "box", span),
    });
    e.children.push(film);
    Ok(e)
}

/// `to_world` as one look-at, in f64 as given (the builder then takes it exactly).
fn look_at(eye: DVec3, target: DVec3, up: DVec3, span: Range<usize>) -> Elem {
    let v = |p: DVec3| format!("{}, {}, {}", p.x, p.y, p.z);
    let mut t = elem("transform", &[("name", "to_world")], span.clone());
    let (o, tg, u) = (v(eye), v(target), v(up));
    t.children.push(elem(
        "lookat",
        &[("origin", &o), ("target", &tg), ("up", &u)],
        span,
    ));
    t
}

/// `[camera.filter]`: Mitsuba's filter types and parameter names, so only the keys are checked.
fn rfilter(ctx: &Ctx, f: &S<FilterDef>) -> Result<Elem, SceneError> {
    let d = f.get_ref();
    let name = d.kind.get_ref().as_str();
    let allowed: &[&str] = match name {
        "box" | "tent" => &["radius"],
        "gaussian" => &["stddev"],
        "mitchell" => &["B", "C"],
        "catmullrom" => &[],
        "lanczos" => &["lobes"],
        other => {
            return Err(ctx.at(
                d.kind.span(),
                format!(
                    "unknown pixel filter `{other}` (known: box, tent, gaussian, mitchell, \
                     catmullrom, lanczos)"
                ),
            ))
        }
    };
    let given = given!(d; radius, stddev, b as "B", c as "C", lobes);
    if let Some((key, _)) = given
        .iter()
        .find(|(k, g)| g.is_some() && !allowed.contains(k))
    {
        return Err(ctx.at(f.span(), format!("the `{name}` filter takes no `{key}`")));
    }
    let mut e = plugin("rfilter", name, f.span());
    for (key, v) in [
        ("radius", &d.radius),
        ("stddev", &d.stddev),
        ("B", &d.b),
        ("C", &d.c),
    ] {
        if let Some(v) = v {
            e.children.push(float(key, ctx.num(v, key)?, v.span()));
        }
    }
    if let Some(l) = &d.lobes {
        e.children
            .push(integer("lobes", (*l.get_ref()).into(), l.span()));
    }
    Ok(e)
}

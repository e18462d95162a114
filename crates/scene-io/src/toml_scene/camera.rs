//! The TOML `[camera]` (with its `[camera.filter]`) and `[render]` tables.

use crate::error::Ctx;
use crate::toml_scene::schema::{CameraDef, FilterDef, SceneFile, S};
use crate::world::LookAt;
use crate::SceneError;
use glam::DVec3;
use lt_core::camera::{Camera, FilterShape, FovAxis, PixelFilter};
use lt_core::math::Vec2;
use lt_core::scene::RenderSettings;

/// The camera as the file places it, with its eye and target as world − `origin`.
pub(super) fn camera(ctx: &Ctx, c: &S<CameraDef>, origin: DVec3) -> Result<Camera, SceneError> {
    let d = c.get_ref();
    let up =
        d.up.as_ref()
            .map(|u| ctx.dvec3(u, "up"))
            .transpose()?
            .unwrap_or(DVec3::Y);
    let [width, height] = *d.resolution.get_ref();
    let kind = d
        .kind
        .as_ref()
        .map_or("perspective", |k| k.get_ref().as_str());
    let kind_span = d.kind.as_ref().map_or(c.span(), |k| k.span());
    // Keys that belong to another camera type are refused, not ignored.
    let only = |key: &str, given: bool, types: &str| {
        if given {
            Err(ctx.at(
                c.span(),
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
    let fov = match (&d.fov, kind) {
        (Some(f), _) => ctx.num(f, "fov")?,
        (None, "orthographic") => 90.0,
        (None, _) => return Err(ctx.at(c.span(), format!("a `{kind}` camera needs `fov`"))),
    };
    if kind == "orthographic" {
        only("fov", d.fov.is_some(), "perspective or thinlens")?;
    }
    let degenerate = |e: String| ctx.at(c.span(), format!("degenerate camera: {e}"));
    let mut camera = LookAt {
        eye: ctx.dvec3(&d.eye, "eye")?,
        target: ctx.dvec3(&d.target, "target")?,
        up,
        fov_deg: fov,
        fov_axis: d.fov_axis.map_or(FovAxis::X, FovAxis::from),
        width,
        height,
    }
    .at(origin)
    .map_err(degenerate)?;
    camera = match kind {
        "perspective" => camera,
        "thinlens" => {
            let (Some(r), Some(f)) = (&d.aperture_radius, &d.focus_distance) else {
                return Err(ctx.at(
                    c.span(),
                    "a `thinlens` camera needs `aperture_radius` and `focus_distance`",
                ));
            };
            let (r, f) = (
                ctx.positive(r, "aperture_radius")?,
                ctx.positive(f, "focus_distance")?,
            );
            camera.thin_lens(r, f).map_err(degenerate)?
        }
        "orthographic" => {
            let hw = match &d.half_width {
                Some(v) => ctx.positive(v, "half_width")?,
                None => 1.0,
            };
            camera.orthographic(hw).map_err(degenerate)?
        }
        other => {
            return Err(ctx.at(
                kind_span,
                format!(
                    "unknown camera type `{other}` (known: perspective, thinlens, orthographic)"
                ),
            ))
        }
    };
    if let Some(o) = &d.principal_point_offset {
        let [x, y] = *o.get_ref();
        camera = camera
            .with_principal_point_offset(Vec2::new(x as f32, y as f32))
            .map_err(|e| ctx.at(o.span(), e))?;
    }
    if let Some(f) = &d.filter {
        camera = camera.with_filter(filter(ctx, f)?);
    }
    Ok(camera)
}

/// `[camera.filter]` with Mitsuba's parameter names and defaults.
pub(super) fn filter(ctx: &Ctx, f: &S<FilterDef>) -> Result<PixelFilter, SceneError> {
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
    let given = [
        ("radius", d.radius.is_some()),
        ("stddev", d.stddev.is_some()),
        ("B", d.b.is_some()),
        ("C", d.c.is_some()),
        ("lobes", d.lobes.is_some()),
    ];
    if let Some((key, _)) = given.iter().find(|(k, g)| *g && !allowed.contains(k)) {
        return Err(ctx.at(f.span(), format!("the `{name}` filter takes no `{key}`")));
    }
    let num = |v: &Option<S<f64>>, key: &str, default: f32| -> Result<f32, SceneError> {
        v.as_ref().map_or(Ok(default), |v| ctx.num(v, key))
    };
    let shape = match name {
        "box" => FilterShape::Box {
            radius: num(&d.radius, "radius", 0.5)?,
        },
        "tent" => FilterShape::Tent {
            radius: num(&d.radius, "radius", 1.0)?,
        },
        "gaussian" => FilterShape::Gaussian {
            stddev: num(&d.stddev, "stddev", 0.5)?,
        },
        "mitchell" => FilterShape::Mitchell {
            b: num(&d.b, "B", 1.0 / 3.0)?,
            c: num(&d.c, "C", 1.0 / 3.0)?,
        },
        "catmullrom" => FilterShape::CatmullRom,
        _ => FilterShape::Lanczos {
            lobes: d.lobes.as_ref().map_or(3, |l| *l.get_ref()),
        },
    };
    PixelFilter::new(shape).map_err(|e| ctx.at(f.span(), e))
}

pub(super) fn render(ctx: &Ctx, file: &SceneFile) -> Result<RenderSettings, SceneError> {
    let mut s = RenderSettings::default();
    let Some(r) = &file.render else { return Ok(s) };
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

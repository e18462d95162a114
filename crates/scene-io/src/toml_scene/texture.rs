//! A TOML `*_texture` table turned into a core `Texture` (the keys are in `format::TextureDef`).

use crate::error::Ctx;
use crate::image_file::{filter_type_named, read_bitmap, wrap_mode_named};
use crate::toml_scene::schema::{TextureDef, S};
use crate::SceneError;
use lt_core::math::Vec2;
use lt_core::texture::{Texture, UvTransform};
use std::sync::Arc;

pub fn texture(ctx: &Ctx, def: &S<TextureDef>) -> Result<Texture, SceneError> {
    let d = def.get_ref();
    let scale = match &d.scale {
        None => 1.0,
        Some(s) => ctx.positive(s, "scale")?,
    };
    let to_uv = UvTransform {
        m: [[scale, 0.0], [0.0, scale]],
        t: Vec2::ZERO,
    };
    let kind = d.kind.get_ref().as_str();
    let given = [
        ("file", d.file.as_ref().map(S::span)),
        ("filter", d.filter.as_ref().map(S::span)),
        ("wrap", d.wrap.as_ref().map(S::span)),
        ("raw", d.raw.as_ref().map(S::span)),
        ("color0", d.color0.as_ref().map(S::span)),
        ("color1", d.color1.as_ref().map(S::span)),
        ("scale", d.scale.as_ref().map(S::span)),
    ];
    let what = format!("a {kind} texture");
    match kind {
        "bitmap" => {
            ctx.only(&given, &["file", "filter", "wrap", "raw", "scale"], &what)?;
            let file = ctx.need(&d.file, "file", &def.span(), &what)?;
            let path = ctx.base_dir.join(file.get_ref());
            let raw = d.raw.as_ref().is_some_and(|r| *r.get_ref());
            let filter = named(ctx, def, &d.filter, "filter", filter_type_named)?;
            let wrap = named(ctx, def, &d.wrap, "wrap", wrap_mode_named)?;
            let bitmap =
                read_bitmap(&path, raw, filter, wrap, to_uv).map_err(|m| ctx.at(file.span(), m))?;
            Ok(Texture::Bitmap(Arc::new(bitmap)))
        }
        "checkerboard" => {
            ctx.only(&given, &["color0", "color1", "scale"], &what)?;
            let color = |c: &Option<S<crate::toml_scene::schema::ColorDef>>, key, default: f32| {
                c.as_ref()
                    .map(|c| ctx.color(c, key, false))
                    .transpose()
                    .map(|c| c.unwrap_or(lt_core::math::Color::splat(default)))
            };
            Ok(Texture::Checkerboard {
                color0: color(&d.color0, "color0", 0.4)?,
                color1: color(&d.color1, "color1", 0.2)?,
                to_uv,
            })
        }
        other => Err(ctx.at(
            d.kind.span(),
            format!("unknown texture type `{other}` (expected bitmap or checkerboard)"),
        )),
    }
}

/// A name-valued key parsed by `parse`, its error placed at the key (or at the texture when the
/// key is absent).
fn named<T>(
    ctx: &Ctx,
    def: &S<TextureDef>,
    v: &Option<S<String>>,
    key: &str,
    parse: fn(Option<&str>) -> Result<T, String>,
) -> Result<T, SceneError> {
    parse(v.as_ref().map(|v| v.get_ref().as_str())).map_err(|m| {
        ctx.at(
            v.as_ref().map_or(def.span(), S::span),
            format!("`{key}` {m}"),
        )
    })
}

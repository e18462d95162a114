//! A TOML `*_texture` table turned into a core `Texture` (the keys are in `format::TextureDef`).

use crate::error::Ctx;
use crate::format::{TextureDef, S};
use crate::image_file::{read_rgb, srgb_to_linear};
use crate::SceneError;
use lt_core::math::Vec2;
use lt_core::texture::{Bitmap, FilterType, Texture, UvTransform, WrapMode};
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
            let img = read_rgb(&path).map_err(|m| ctx.at(file.span(), m))?;
            let decode = img.srgb_encoded && !d.raw.as_ref().is_some_and(|r| *r.get_ref());
            let texels = img
                .texels
                .iter()
                .map(|c| if decode { c.map(srgb_to_linear) } else { *c })
                .collect();
            let filter = match d.filter.as_ref().map(|f| (f.get_ref().as_str(), f.span())) {
                None | Some(("bilinear", _)) => FilterType::Bilinear,
                Some(("nearest", _)) => FilterType::Nearest,
                Some((other, span)) => {
                    return Err(ctx.at(
                        span,
                        format!("`filter` must be bilinear or nearest, got `{other}`"),
                    ))
                }
            };
            let wrap = match d.wrap.as_ref().map(|w| (w.get_ref().as_str(), w.span())) {
                None | Some(("repeat", _)) => WrapMode::Repeat,
                Some(("mirror", _)) => WrapMode::Mirror,
                Some(("clamp", _)) => WrapMode::Clamp,
                Some((other, span)) => {
                    return Err(ctx.at(
                        span,
                        format!("`wrap` must be repeat, mirror or clamp, got `{other}`"),
                    ))
                }
            };
            Ok(Texture::Bitmap(Arc::new(Bitmap {
                width: img.width,
                height: img.height,
                texels,
                filter,
                wrap,
                to_uv,
            })))
        }
        "checkerboard" => {
            ctx.only(&given, &["color0", "color1", "scale"], &what)?;
            let color = |c: &Option<S<crate::format::ColorDef>>, key, default: f32| {
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

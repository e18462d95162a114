//! A TOML texture table (`*_texture`, `normal_map`, …) as `<texture name=…>`: `file` →
//! `filename`, `filter` → `filter_type`, `wrap` → `wrap_mode`, `scale` → a `to_uv` scale.

use super::{boolean, elem, num, plugin, rgb, string};
use crate::error::Ctx;
use crate::image_file::{filter_type_named, wrap_mode_named};
use crate::toml_scene::schema::{ColorDef, TextureDef, S};
use crate::xml::doc::Elem;
use crate::SceneError;

/// The texture as the parameter `name` of the plugin it is nested in.
pub(crate) fn texture(ctx: &Ctx, def: &S<TextureDef>, name: &str) -> Result<Elem, SceneError> {
    let d = def.get_ref();
    let kind = d.kind.get_ref().as_str();
    let mut t = plugin("texture", kind, def.span());
    t.attrs.push(("name".into(), name.into()));
    if let Some(s) = &d.scale {
        let s = ctx.positive(s, "scale")?;
        let mut to_uv = elem("transform", &[("name", "to_uv")], def.span());
        to_uv
            .children
            .push(elem("scale", &[("value", &num(s))], def.span()));
        t.children.push(to_uv);
    }
    let given = given!(d; file, filter, wrap, raw, color0, color1, scale);
    let what = format!("a {kind} texture");
    match kind {
        "bitmap" => {
            ctx.only(&given, &["file", "filter", "wrap", "raw", "scale"], &what)?;
            let file = ctx.need(&d.file, "file", &def.span(), &what)?;
            t.children
                .push(string("filename", file.get_ref(), file.span()));
            if let Some(v) = &d.filter {
                filter_type_named(Some(v.get_ref()))
                    .map_err(|m| ctx.at(v.span(), format!("`filter` {m}")))?;
                t.children
                    .push(string("filter_type", v.get_ref(), v.span()));
            }
            if let Some(v) = &d.wrap {
                wrap_mode_named(Some(v.get_ref()))
                    .map_err(|m| ctx.at(v.span(), format!("`wrap` {m}")))?;
                t.children.push(string("wrap_mode", v.get_ref(), v.span()));
            }
            if let Some(r) = &d.raw {
                t.children.push(boolean("raw", *r.get_ref(), r.span()));
            }
        }
        "checkerboard" => {
            ctx.only(&given, &["color0", "color1", "scale"], &what)?;
            for (c, key) in [(&d.color0, "color0"), (&d.color1, "color1")] {
                if let Some(c) = c {
                    t.children.push(color(ctx, c, key, key, false)?);
                }
            }
        }
        other => {
            return Err(ctx.at(
                d.kind.span(),
                format!("unknown texture type `{other}` (expected bitmap or checkerboard)"),
            ))
        }
    }
    Ok(t)
}

/// A TOML colour under the tree's name `xml_key`, checked under its TOML name `key`.
pub(crate) fn color(
    ctx: &Ctx,
    c: &S<ColorDef>,
    key: &str,
    xml_key: &str,
    at_most_one: bool,
) -> Result<Elem, SceneError> {
    let v = ctx.color(c, key, at_most_one)?;
    Ok(rgb(xml_key, v.to_array(), c.span()))
}

//! `<texture>`: bitmap, checkerboard, mesh_attribute, rawconstant.

use super::Loader;
use crate::image_file::{filter_type_named, read_bitmap, wrap_mode_named};
use crate::xml::doc::Elem;
use crate::xml::props::{ColorUse, Plugin};
use crate::xml::resolve::Resolver;
use crate::SceneError;
use lt_core::math::Color;
use lt_core::texture::{Texture, UvTransform};
use std::sync::Arc;

/// The textures lt reads.
pub(super) const TEXTURES: [&str; 4] = ["bitmap", "checkerboard", "mesh_attribute", "rawconstant"];

impl<'a> Loader<'a> {
    /// A `<texture>`: Mitsuba's `bitmap` (`filename`, `filter_type` bilinear or nearest, `wrap_mode`
    /// repeat, mirror or clamp, `raw`, `to_uv`) or `checkerboard` (`color0` 0.4, `color1` 0.2,
    /// `to_uv`).
    pub(super) fn texture(&mut self, e: &'a Elem) -> Result<Texture, SceneError> {
        let p = self.plugin(e)?;
        let to_uv = match p.transform("to_uv")? {
            None => UvTransform::IDENTITY,
            Some((x, _)) => {
                let m = x.m;
                // A 2-D affine map given as a 4×4 (Mitsuba builds it with translate/scale/rotate
                // about z): its upper-left 2×2 and the translation's x, y.
                UvTransform {
                    m: [
                        [m.x_axis.x as f32, m.y_axis.x as f32],
                        [m.x_axis.y as f32, m.y_axis.y as f32],
                    ],
                    t: glam::Vec2::new(m.w_axis.x as f32, m.w_axis.y as f32),
                }
            }
        };
        let texture = match p.kind {
            "bitmap" => {
                let Some((file, fe)) = p.string("filename")? else {
                    return Err(p.err(e, "a bitmap texture needs a `filename`"));
                };
                let path = self.doc.resolver.resolve(file).map_err(|looked| {
                    p.err(fe, Resolver::not_found("texture file", file, &looked))
                })?;
                let raw = p.boolean("raw")?.unwrap_or(false);
                let filter = parse_named(&p, e, "filter_type", filter_type_named)?;
                let wrap = parse_named(&p, e, "wrap_mode", wrap_mode_named)?;
                let bitmap =
                    read_bitmap(&path, raw, filter, wrap, to_uv).map_err(|m| p.err(fe, m))?;
                self.meshes.push(path);
                p.finish(&["format"], &mut self.report)?;
                Texture::Bitmap(Arc::new(bitmap))
            }
            "checkerboard" => {
                let opts = self.opts;
                let color0 = p
                    .color("color0", ColorUse::Emission, opts, &mut self.report)?
                    .unwrap_or(Color::splat(0.4));
                let color1 = p
                    .color("color1", ColorUse::Emission, opts, &mut self.report)?
                    .unwrap_or(Color::splat(0.2));
                p.finish(&[], &mut self.report)?;
                Texture::Checkerboard {
                    color0,
                    color1,
                    to_uv,
                }
            }
            "mesh_attribute" => {
                let Some((name, ne)) = p.string("name")? else {
                    return Err(p.err(e, "a mesh_attribute texture needs a `name`"));
                };
                if !(name.starts_with("vertex_") || name.starts_with("face_")) {
                    return Err(p.err(
                        ne,
                        format!("mesh attribute `{name}`: its name must start with `vertex_` or `face_`"),
                    ));
                }
                p.finish(&[], &mut self.report)?;
                Texture::MeshAttribute { name: name.into() }
            }
            "rawconstant" => {
                // Mitsuba's `rawconstant`: `value`, a float or a 3-vector used as is (no colour
                // conversion: normal maps store directions in it).
                let is_float = e.children.iter().any(|c| {
                    c.attr("name") == Some("value") && matches!(c.tag.as_str(), "float" | "integer")
                });
                let value = if is_float {
                    p.float("value")?.map(|x| Color::splat(x as f32))
                } else {
                    p.vec3("value")?
                        .map(|v| Color::new(v[0] as f32, v[1] as f32, v[2] as f32))
                };
                let Some(value) = value else {
                    return Err(p.err(e, "a rawconstant texture needs a `value`"));
                };
                p.finish(&[], &mut self.report)?;
                Texture::Constant(value)
            }
            _ => return Err(super::kinds::unknown_type(self.doc, e)),
        };
        Ok(texture)
    }
}

/// A string parameter parsed by `parse`, its error placed at the parameter (or at the element
/// `e` when the parameter is absent).
pub(super) fn parse_named<T>(
    p: &Plugin,
    e: &Elem,
    key: &str,
    parse: fn(Option<&str>) -> Result<T, String>,
) -> Result<T, SceneError> {
    let given = p.string(key)?;
    parse(given.map(|(name, _)| name))
        .map_err(|m| p.err(given.map_or(e, |(_, ke)| ke), format!("`{key}` {m}")))
}

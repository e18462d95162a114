//! A TOML `[[shapes]]` entry as a `<shape>`: `quad` → `rectangle`, `cube` → `cube` and `mesh` →
//! `obj`, each with the exact `to_world` the TOML keys compose (`transform::shape_matrix`);
//! `sphere` → `sphere` (`center` in f64, `radius` as the f32 TOML reads it); `material` → a
//! `<ref>` to the BSDF; `emission` or `emission_texture` → an `area` emitter's `radiance`;
//! `interior`/`exterior` → named medium references. A TOML mesh without normals on every vertex
//! shades flat, where Mitsuba computes smooth normals: the tree says so with
//! `missing_normals = "flat"`, a property of lt's own, which `lt convert` prints as Mitsuba's
//! `face_normals` when the file has no normals (and drops otherwise).

use super::texture::texture;
use super::{elem, float64, matrix, plugin, point, reference, rgb, string};
use crate::error::Ctx;
use crate::toml_scene::schema::{ShapeDef, S};
use crate::transform::shape_matrix;
use crate::xml::doc::Elem;
use crate::SceneError;

/// The shape as a `<shape>` element; `materials` are the names the file defines (a name not
/// among them is reported here, in TOML's words).
pub(crate) fn shape(ctx: &Ctx, def: &S<ShapeDef>, materials: &[&str]) -> Result<Elem, SceneError> {
    let d = def.get_ref();
    let kind = d.kind.get_ref().as_str();
    let what = format!("a {kind} shape");
    let given = given!(d; file, center, radius, to_world, translate, rotate, scale);
    const PLACED: [&str; 4] = ["to_world", "translate", "rotate", "scale"];
    let placed = |mut e: Elem| -> Result<Elem, SceneError> {
        let (m, span) = shape_matrix(ctx, d)?;
        let rows: [[f64; 4]; 4] = std::array::from_fn(|r| m.row(r).to_array());
        e.children.push(matrix("to_world", rows, span));
        Ok(e)
    };
    let mut e = match kind {
        "sphere" => {
            ctx.only(&given, &["center", "radius"], &what)?;
            let c = ctx.need(&d.center, "center", &def.span(), &what)?;
            let r = ctx.need(&d.radius, "radius", &def.span(), &what)?;
            let mut e = plugin("shape", "sphere", def.span());
            e.children
                .push(point("center", ctx.dvec3(c, "center")?, c.span()));
            // TOML reads the radius in f32; written as that f32's exact f64.
            let radius = ctx.positive(r, "radius")?;
            e.children.push(float64("radius", radius.into(), r.span()));
            e
        }
        "quad" => {
            ctx.only(&given, &PLACED, &what)?;
            placed(plugin("shape", "rectangle", def.span()))?
        }
        "cube" => {
            ctx.only(&given, &PLACED, &what)?;
            placed(plugin("shape", "cube", def.span()))?
        }
        "mesh" => {
            ctx.only(
                &given,
                &["file", "to_world", "translate", "rotate", "scale"],
                &what,
            )?;
            let file = ctx.need(&d.file, "file", &def.span(), &what)?;
            let mut e = plugin("shape", "obj", def.span());
            e.children
                .push(string("filename", file.get_ref(), file.span()));
            e.children
                .push(string("missing_normals", "flat", def.span()));
            placed(e)?
        }
        other => {
            return Err(ctx.at(
                d.kind.span(),
                format!("unknown shape type `{other}` (expected mesh, quad, cube or sphere)"),
            ))
        }
    };
    if d.flip_normals {
        e.children
            .push(super::boolean("flip_normals", true, def.span()));
    }
    let name = d.material.get_ref();
    if !materials.contains(&name.as_str()) {
        let mut defined = materials.to_vec();
        defined.sort_unstable();
        let list = if defined.is_empty() {
            "no materials are defined".to_string()
        } else {
            format!("defined: {}", defined.join(", "))
        };
        return Err(ctx.at(
            d.material.span(),
            format!("material `{name}` is not defined ({list})"),
        ));
    }
    e.children
        .push(elem("ref", &[("id", name)], d.material.span()));
    let radiance = match (&d.emission, &d.emission_texture) {
        (Some(_), Some(t)) => {
            return Err(ctx.at(t.span(), "give `emission` or `emission_texture`, not both"))
        }
        // A black emission is no emitter.
        (Some(c), None) => {
            let v = ctx.color(c, "emission", false)?;
            (v.max_element() > 0.0).then(|| rgb("radiance", v.to_array(), c.span()))
        }
        (None, Some(t)) => Some(texture(ctx, t, "radiance")?),
        (None, None) => None,
    };
    if let Some(r) = radiance {
        let mut em = plugin("emitter", "area", r.range.clone());
        em.children.push(r);
        e.children.push(em);
    }
    for (side, m) in [("interior", &d.interior), ("exterior", &d.exterior)] {
        if let Some(m) = m {
            e.children.push(reference(side, m.get_ref(), m.span()));
        }
    }
    Ok(e)
}

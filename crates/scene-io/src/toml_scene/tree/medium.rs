//! A TOML `[media.NAME]` table as a `<medium id=NAME>`: the keys are Mitsuba's, except that a
//! grid is `sigma_t_volume` / `albedo_volume` (a `<volume type="gridvolume" name=…>`, whose
//! `file` is its `filename` and `wrap` its `wrap_mode`) and the phase function is a `phase`
//! table. A new medium type needs nothing here. Values are checked by the medium's builder
//! (`xml/build/medium.rs`), at the TOML line.

use super::texture::color;
use super::{boolean, float, matrix, plugin, string};
use crate::error::Ctx;
use crate::toml_scene::schema::{MediumDef, PhaseDef, VolumeDef, S};
use crate::xml::doc::Elem;
use crate::SceneError;

/// The medium as a `<medium>` element with `id` = its name.
pub(crate) fn medium(ctx: &Ctx, name: &str, def: &S<MediumDef>) -> Result<Elem, SceneError> {
    let d = def.get_ref();
    let kind = d.kind.get_ref().as_str();
    // The types are the builder's (`xml/build/medium.rs`); so are the keys a type takes: one it
    // does not take is refused there, at its TOML line, in the same (Mitsuba's) words.
    let types = crate::xml::build::MEDIA;
    if !types.contains(&kind) {
        let (last, rest) = types.split_last().expect("MEDIA is not empty");
        return Err(ctx.at(
            d.kind.span(),
            format!(
                "unknown medium type `{kind}` (expected {} or {last})",
                rest.join(", ")
            ),
        ));
    }
    let mut m = plugin("medium", kind, def.span());
    m.attrs.push(("id".into(), name.into()));
    for (c, key, at_most_one) in [
        (&d.sigma_t, "sigma_t", false),
        (&d.albedo, "albedo", true),
        (&d.sigma_a, "sigma_a", false),
        (&d.sigma_s, "sigma_s", false),
    ] {
        if let Some(c) = c {
            m.children.push(color(ctx, c, key, key, at_most_one)?);
        }
    }
    for (plain, grid, key) in [
        (&d.sigma_t, &d.sigma_t_volume, "sigma_t"),
        (&d.albedo, &d.albedo_volume, "albedo"),
    ] {
        if let Some(g) = grid {
            if plain.is_some() {
                return Err(ctx.at(
                    g.span(),
                    format!("give `{key}` or `{key}_volume`, not both"),
                ));
            }
            m.children.push(volume(g, key));
        }
    }
    if let Some(s) = &d.scale {
        m.children
            .push(float("scale", ctx.num(s, "scale")?, s.span()));
    }
    if let Some(p) = &d.phase {
        m.children.push(phase(ctx, p)?);
    }
    Ok(m)
}

fn phase(ctx: &Ctx, def: &S<PhaseDef>) -> Result<Elem, SceneError> {
    let d = def.get_ref();
    let kind = d.kind.get_ref().as_str();
    let mut p = plugin("phase", kind, def.span());
    match (kind, &d.g) {
        ("isotropic", None) => {}
        ("isotropic", Some(g)) => {
            return Err(ctx.at(g.span(), "`g` applies to the `hg` phase function"))
        }
        ("hg", g) => {
            if let Some(g) = g {
                p.children.push(float("g", ctx.num(g, "g")?, g.span()));
            }
        }
        (other, _) => {
            return Err(ctx.at(
                d.kind.span(),
                format!("unknown phase function `{other}` (expected isotropic or hg)"),
            ))
        }
    }
    Ok(p)
}

fn volume(def: &S<VolumeDef>, name: &str) -> Elem {
    let d = def.get_ref();
    let mut v = plugin("volume", "gridvolume", def.span());
    v.attrs.push(("name".into(), name.into()));
    v.children
        .push(string("filename", d.file.get_ref(), d.file.span()));
    if let Some(t) = &d.to_world {
        v.children.push(matrix("to_world", *t.get_ref(), t.span()));
    }
    if let Some(b) = &d.use_grid_bbox {
        v.children
            .push(boolean("use_grid_bbox", *b.get_ref(), b.span()));
    }
    if let Some(w) = &d.wrap {
        v.children.push(string("wrap_mode", w.get_ref(), w.span()));
    }
    v
}

//! TOML's `principled` and `principledthin` materials, with Mitsuba's parameter names and
//! defaults (docs/scene-format.md): `base_color` (0.5, or `base_color_texture`), `roughness`
//! (0.5), `anisotropic`, `spec_trans`, `spec_tint`, `sheen`, `sheen_tint`, `flatness` (0);
//! principled adds `metallic`, `clearcoat`, `clearcoat_gloss` (0) and `ior` or `specular`
//! (Mitsuba's `eta`/`specular`, specular 0.5); principledthin adds `diff_trans` (0, range 0–2)
//! and `ior` (1.5). Scalars are numbers here; Mitsuba XML also takes textures for them.

use crate::error::Ctx;
use crate::principled_keys::{principled_eta, scalar_in_range, thin_eta};
use crate::toml_scene::schema::{MaterialDef, S};
use crate::SceneError;
use lt_core::bsdf::{Material, Principled, PrincipledThin};
use lt_core::math::Color;
use std::ops::Range;

const SHARED: [&str; 10] = [
    "base_color",
    "base_color_texture",
    "roughness",
    "anisotropic",
    "spec_trans",
    "spec_tint",
    "sheen",
    "sheen_tint",
    "flatness",
    "ior",
];

/// The keys each of the two takes.
fn allowed(thin: bool) -> Vec<&'static str> {
    let own: &[&str] = if thin {
        &["diff_trans"]
    } else {
        &["metallic", "clearcoat", "clearcoat_gloss", "specular"]
    };
    SHARED.iter().chain(own).copied().collect()
}

pub fn principled(
    ctx: &Ctx,
    d: &MaterialDef,
    given: &[(&str, Option<Range<usize>>)],
    what: &str,
) -> Result<Material, SceneError> {
    let thin = d.kind.get_ref() == "principledthin";
    ctx.only(given, &allowed(thin), what)?;
    if let (Some(_), Some(t)) = (&d.base_color, &d.base_color_texture) {
        return Err(ctx.at(
            t.span(),
            "give `base_color` or `base_color_texture`, not both",
        ));
    }
    let base_color = match &d.base_color {
        Some(c) => ctx.color(c, "base_color", true)?,
        None => Color::splat(0.5),
    };
    let scalar = |v: &Option<S<f64>>, name: &str, default: f32, max: f32| match v {
        None => Ok(default),
        Some(x) => scalar_in_range(name, *x.get_ref(), max).map_err(|e| ctx.at(x.span(), e)),
    };
    let roughness = scalar(&d.roughness, "roughness", 0.5, 1.0)?;
    let anisotropic = scalar(&d.anisotropic, "anisotropic", 0.0, 1.0)?;
    let spec_trans = scalar(&d.spec_trans, "spec_trans", 0.0, 1.0)?;
    let spec_tint = scalar(&d.spec_tint, "spec_tint", 0.0, 1.0)?;
    let sheen = scalar(&d.sheen, "sheen", 0.0, 1.0)?;
    let sheen_tint = scalar(&d.sheen_tint, "sheen_tint", 0.0, 1.0)?;
    let flatness = scalar(&d.flatness, "flatness", 0.0, 1.0)?;
    let ior = d.ior.as_ref().map(|i| *i.get_ref());
    let ior_span = || d.ior.as_ref().map_or(d.kind.span(), |i| i.span());
    if thin {
        return Ok(Material::PrincipledThin(PrincipledThin {
            base_color,
            roughness,
            anisotropic,
            spec_trans,
            diff_trans: scalar(&d.diff_trans, "diff_trans", 0.0, 2.0)?,
            eta: thin_eta(ior, "ior").map_err(|e| ctx.at(ior_span(), e))?,
            spec_tint,
            sheen,
            sheen_tint,
            flatness,
            ..PrincipledThin::mitsuba_default()
        }));
    }
    let specular = d.specular.as_ref().map(|s| *s.get_ref());
    let eta_span = d.specular.as_ref().map_or_else(ior_span, |s| s.span());
    Ok(Material::Principled(Principled {
        base_color,
        roughness,
        anisotropic,
        metallic: scalar(&d.metallic, "metallic", 0.0, 1.0)?,
        spec_trans,
        eta: principled_eta(ior, specular, spec_trans != 0.0, "ior")
            .map_err(|e| ctx.at(eta_span, e))?,
        spec_tint,
        sheen,
        sheen_tint,
        flatness,
        clearcoat: scalar(&d.clearcoat, "clearcoat", 0.0, 1.0)?,
        clearcoat_gloss: scalar(&d.clearcoat_gloss, "clearcoat_gloss", 0.0, 1.0)?,
        has_spec_trans: spec_trans != 0.0,
        ..Principled::mitsuba_default()
    }))
}

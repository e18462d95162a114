//! A TOML `[materials.NAME]` table as a `<bsdf id=NAME>`. The renamed keys:
//!
//! | TOML | tree |
//! |---|---|
//! | `albedo` (diffuse, plastics) | `reflectance` / `diffuse_reflectance` |
//! | `reflectance` | `specular_reflectance` |
//! | `transmittance` | `specular_transmittance` |
//! | `ior` (dielectrics, plastics) | `int_ior` over `ext_ior` = 1 |
//! | `ior` (principled) | `eta` |
//! | `roughness` (glossy) | `alpha` of a GGX `roughconductor` of material `none` |
//! | `*_texture` | a `<texture>` named after the parameter it sets |
//! | `normal_map`, `bump_map` (+ `bump_scale`, `flip_invalid_normals`, `bump_shadowing`) | `normalmap` / `bumpmap` around the BSDF (`scale`, `use_shadowing_function`) |
//! | `opacity`, `opacity_texture` | `mask` around it |
//! | `twosided = true`, and every diffuse, mirror and glossy | `twosided` around the one-sided BSDF |
//!
//! Every other key keeps its name. The TOML types, the tree type each becomes and the groups of
//! keys it takes are rows of the builder's `BSDFS` (`xml/build/bsdf_toml.rs`), so a new material
//! needs no code here; each group is translated here, with what it needs and what may not be
//! given together checked in TOML's words.

use super::texture::{color, texture};
use super::{boolean, float, float64, plugin, string, wrap};
use crate::error::Ctx;
use crate::principled_keys::{principled_eta, scalar_in_range, thin_eta};
use crate::toml_scene::schema::{MaterialDef, TextureDef, S};
use crate::xml::build::{toml_material, toml_materials, Keys};
use crate::xml::doc::Elem;
use crate::SceneError;
use lt_core::bsdf::conductor_ior::{conductor_names, named_conductor};
use lt_core::bsdf::plastic::{AIR_IOR, POLYPROPYLENE_IOR};
use std::ops::Range;

/// GGX α below this is numerically a mirror; use `mirror` instead.
const MIN_ROUGHNESS: f32 = 1e-4;

/// The material as a BSDF element with `id` = its name.
pub(crate) fn material(ctx: &Ctx, name: &str, def: &S<MaterialDef>) -> Result<Elem, SceneError> {
    let e = plain(ctx, name, def)?;
    let e = perturbed(ctx, def, e)?;
    let mut e = masked(ctx, def, e)?;
    e.attrs.push(("id".into(), name.into()));
    Ok(e)
}

/// `e` inside Mitsuba's `mask` when the material has an `opacity` or `opacity_texture`.
fn masked(ctx: &Ctx, def: &S<MaterialDef>, e: Elem) -> Result<Elem, SceneError> {
    let d = def.get_ref();
    let opacity = match (&d.opacity, &d.opacity_texture) {
        (None, None) => return Ok(e),
        (Some(_), Some(t)) => {
            return Err(ctx.at(t.span(), "give `opacity` or `opacity_texture`, not both"));
        }
        (Some(a), None) => {
            let v: f32 = ctx.num(a, "opacity")?;
            if !(0.0..=1.0).contains(&v) {
                return Err(ctx.at(a.span(), format!("`opacity` must lie in [0, 1], got {v}")));
            }
            float("opacity", v, a.span())
        }
        (None, Some(t)) => texture(ctx, t, "opacity")?,
    };
    let mut m = wrap("bsdf", "mask", def.span(), e);
    m.children.insert(0, opacity);
    Ok(m)
}

/// `e` inside Mitsuba's `normalmap` or `bumpmap` when the material has one.
fn perturbed(ctx: &Ctx, def: &S<MaterialDef>, e: Elem) -> Result<Elem, SceneError> {
    let d = def.get_ref();
    let mut m = match (&d.normal_map, &d.bump_map) {
        (None, None) => {
            let stray = given!(d; bump_scale, flip_invalid_normals, bump_shadowing);
            if let Some((key, Some(span))) = stray.into_iter().find(|(_, s)| s.is_some()) {
                return Err(ctx.at(span, format!("`{key}` needs a `normal_map` or `bump_map`")));
            }
            return Ok(e);
        }
        (Some(_), Some(b)) => {
            return Err(ctx.at(b.span(), "give `normal_map` or `bump_map`, not both"));
        }
        (Some(n), None) => {
            if let Some(s) = &d.bump_scale {
                return Err(ctx.at(s.span(), "`bump_scale` applies to a `bump_map`"));
            }
            let mut m = plugin("bsdf", "normalmap", def.span());
            m.children.push(texture(ctx, n, "normalmap")?);
            m
        }
        (None, Some(b)) => {
            let mut m = plugin("bsdf", "bumpmap", def.span());
            m.children.push(texture(ctx, b, "height")?);
            if let Some(s) = &d.bump_scale {
                m.children
                    .push(float("scale", ctx.num(s, "bump_scale")?, s.span()));
            }
            m
        }
    };
    for (flag, key) in [
        (&d.flip_invalid_normals, "flip_invalid_normals"),
        (&d.bump_shadowing, "use_shadowing_function"),
    ] {
        if let Some(f) = flag {
            m.children.push(boolean(key, *f.get_ref(), f.span()));
        }
    }
    m.children.push(e);
    Ok(m)
}

/// The keys given, with their spans (serde knows only the union of every type's keys).
fn given(d: &MaterialDef) -> Vec<(&'static str, Option<Range<usize>>)> {
    given!(d; albedo, reflectance, ior, roughness, material, eta, k, distribution, alpha, alpha_u, alpha_v, transmittance, twosided, albedo_texture, reflectance_texture, alpha_texture, alpha_u_texture, alpha_v_texture, nonlinear, base_color, base_color_texture, anisotropic, metallic, spec_trans, specular, spec_tint, sheen, sheen_tint, flatness, clearcoat, clearcoat_gloss, diff_trans).to_vec()
}

/// The BSDF of a TOML type (its row of the builder's `BSDFS`: which tree type it becomes and
/// which groups of keys it takes), with its untextured and textured parameters, inside
/// `twosided` where ours reflect on both sides.
fn plain(ctx: &Ctx, name: &str, def: &S<MaterialDef>) -> Result<Elem, SceneError> {
    let d = def.get_ref();
    let kind = d.kind.get_ref().as_str();
    let Some((tree_type, toml)) = toml_material(kind) else {
        let types: Vec<&str> = toml_materials().collect();
        let (last, rest) = types.split_last().expect("BSDFS has TOML types");
        return Err(ctx.at(
            d.kind.span(),
            format!(
                "unknown material type `{kind}` (expected {} or {last})",
                rest.join(", ")
            ),
        ));
    };
    let what = format!("material `{name}` of type {kind}");
    let span = def.span();
    let allowed: Vec<&str> = toml
        .keys
        .iter()
        .flat_map(|k| k.toml_keys())
        .copied()
        .collect();
    ctx.only(&given(d), &allowed, &what)?;
    let mut b = plugin("bsdf", tree_type, span.clone());
    for (key, value) in toml.fixed {
        b.children.push(string(key, value, span.clone()));
    }
    for &group in toml.keys {
        keys(ctx, d, group, &span, &what, &mut b)?;
    }
    let twosided = d.twosided.as_ref().is_some_and(|t| *t.get_ref());
    Ok(if toml.always_twosided || twosided {
        wrap("bsdf", "twosided", span, b)
    } else {
        b
    })
}

/// One group of keys into the tree, in TOML's words (the renames are `Keys`' table).
fn keys(
    ctx: &Ctx,
    d: &MaterialDef,
    group: Keys,
    span: &Range<usize>,
    what: &str,
    b: &mut Elem,
) -> Result<(), SceneError> {
    match group {
        Keys::Albedo { to, required } => albedo(ctx, d, to, required, span, what, b),
        Keys::Reflectance { .. } => specular_reflectance(ctx, d, b),
        Keys::Transmittance => {
            if let Some(t) = &d.transmittance {
                let e = color(ctx, t, "transmittance", "specular_transmittance", true)?;
                b.children.push(e);
            }
            Ok(())
        }
        Keys::DielectricIor => ior(ctx, d, span, what, Some(b)).map(drop),
        Keys::PlasticIor { rough } => plastic_ior(ctx, d, rough, b),
        Keys::Roughness => {
            let r = ctx.need(&d.roughness, "roughness", span, what)?;
            let roughness = ctx.num(r, "roughness")?;
            if !(roughness >= MIN_ROUGHNESS) {
                return Err(ctx.at(r.span(), format!("`roughness` (GGX α) must be at least {MIN_ROUGHNESS}, got {roughness} (use a mirror for a perfectly smooth surface)")));
            }
            b.children.push(float("alpha", roughness, r.span()));
            Ok(())
        }
        Keys::Microfacet { .. } => microfacet(ctx, d, span, b),
        Keys::ComplexIor => complex_ior(ctx, d, span, b),
        Keys::Nonlinear => {
            if let Some(n) = &d.nonlinear {
                b.children
                    .push(boolean("nonlinear", *n.get_ref(), n.span()));
            }
            Ok(())
        }
        // `plain` wraps the BSDF.
        Keys::Twosided => Ok(()),
        Keys::Principled { thin } => principled(ctx, d, thin, b),
    }
}

/// `albedo` or `albedo_texture` as the reflectance `to`.
fn albedo(
    ctx: &Ctx,
    d: &MaterialDef,
    to: &str,
    required: bool,
    span: &Range<usize>,
    what: &str,
    b: &mut Elem,
) -> Result<(), SceneError> {
    match (&d.albedo, &d.albedo_texture) {
        (Some(_), Some(t)) => Err(ctx.at(t.span(), "give `albedo` or `albedo_texture`, not both")),
        (Some(a), None) => {
            b.children.push(color(ctx, a, "albedo", to, true)?);
            Ok(())
        }
        (None, Some(t)) => {
            b.children.push(texture(ctx, t, to)?);
            Ok(())
        }
        (None, None) if required => Err(ctx.at(
            span.clone(),
            format!("missing required key `albedo` (or `albedo_texture`) for {what}"),
        )),
        (None, None) => Ok(()),
    }
}

/// `reflectance` (or `reflectance_texture`) as `specular_reflectance`.
fn specular_reflectance(ctx: &Ctx, d: &MaterialDef, b: &mut Elem) -> Result<(), SceneError> {
    match (&d.reflectance, &d.reflectance_texture) {
        (Some(_), Some(t)) => Err(ctx.at(
            t.span(),
            "give `reflectance` or `reflectance_texture`, not both",
        )),
        (Some(r), None) => {
            let e = color(ctx, r, "reflectance", "specular_reflectance", true)?;
            b.children.push(e);
            Ok(())
        }
        (None, Some(t)) => {
            b.children.push(texture(ctx, t, "specular_reflectance")?);
            Ok(())
        }
        (None, None) => Ok(()),
    }
}

/// A dielectric's `ior` as `int_ior` in a vacuum (`ext_ior` = 1).
fn ior(
    ctx: &Ctx,
    d: &MaterialDef,
    span: &Range<usize>,
    what: &str,
    b: Option<&mut Elem>,
) -> Result<f32, SceneError> {
    let i = ctx.need(&d.ior, "ior", span, what)?;
    let ior = ctx.positive(i, "ior")?;
    if let Some(b) = b {
        b.children.push(float("int_ior", ior, i.span()));
        b.children.push(float("ext_ior", 1.0, span.clone()));
    }
    Ok(ior)
}

/// A plastic's `ior` as `int_ior` over `ext_ior` = 1, polypropylene in air when absent (as
/// Mitsuba's default); a rough one's must not be 1.
fn plastic_ior(ctx: &Ctx, d: &MaterialDef, rough: bool, b: &mut Elem) -> Result<(), SceneError> {
    let span = d.kind.span();
    let ior = match &d.ior {
        None => POLYPROPYLENE_IOR / AIR_IOR,
        Some(i) => ctx.positive(i, "ior")?,
    };
    if rough && ior == 1.0 {
        return Err(ctx.at(
            d.ior.as_ref().map_or(span.clone(), S::span),
            "a roughplastic needs `ior` ≠ 1 (as Mitsuba)",
        ));
    }
    let at = d.ior.as_ref().map_or(span.clone(), S::span);
    b.children.push(float("int_ior", ior, at));
    b.children.push(float("ext_ior", 1.0, span));
    Ok(())
}

/// A conductor's complex IOR: a `material` name Mitsuba knows (default "none": a perfect mirror)
/// or `eta` and `k` together.
fn complex_ior(
    ctx: &Ctx,
    d: &MaterialDef,
    span: &Range<usize>,
    b: &mut Elem,
) -> Result<(), SceneError> {
    match (&d.material, &d.eta, &d.k) {
        (None, None, None) => Ok(()),
        (Some(name), None, None) => {
            if named_conductor(name.get_ref()).is_none() {
                let names: Vec<&str> = conductor_names().collect();
                return Err(ctx.at(
                    name.span(),
                    format!(
                        "conductor material `{}` is not one Mitsuba knows (known: {})",
                        name.get_ref(),
                        names.join(", ")
                    ),
                ));
            }
            b.children
                .push(string("material", name.get_ref(), name.span()));
            Ok(())
        }
        (None, Some(eta), Some(k)) => {
            b.children.push(color(ctx, eta, "eta", "eta", false)?);
            b.children.push(color(ctx, k, "k", "k", false)?);
            Ok(())
        }
        (Some(name), _, _) => Err(ctx.at(
            name.span(),
            "give a conductor `material` or `eta` and `k`, not both",
        )),
        _ => Err(ctx.at(
            span.clone(),
            "a conductor's `eta` and `k` go together: give both",
        )),
    }
}

/// A microfacet distribution: `distribution` (beckmann, the default, or ggx) and `alpha`
/// (default 0.1, at least 1e-4) or `alpha_u` and `alpha_v`, each a number or a texture.
fn microfacet(
    ctx: &Ctx,
    d: &MaterialDef,
    at: &Range<usize>,
    b: &mut Elem,
) -> Result<(), SceneError> {
    if let Some(s) = &d.distribution {
        if !matches!(s.get_ref().as_str(), "beckmann" | "ggx") {
            return Err(ctx.at(
                s.span(),
                format!(
                    "`distribution` must be beckmann or ggx, got `{}`",
                    s.get_ref()
                ),
            ));
        }
        b.children
            .push(string("distribution", s.get_ref(), s.span()));
    }
    let given = |a: &Option<S<f64>>, t: &Option<S<TextureDef>>| a.is_some() || t.is_some();
    let (u_given, v_given) = (
        given(&d.alpha_u, &d.alpha_u_texture),
        given(&d.alpha_v, &d.alpha_v_texture),
    );
    if u_given != v_given || (u_given && given(&d.alpha, &d.alpha_texture)) {
        return Err(ctx.at(
            at.clone(),
            "give `alpha` (or `alpha_texture`), or both `alpha_u` and `alpha_v` (or their textures)",
        ));
    }
    for (a, t, key) in [
        (&d.alpha, &d.alpha_texture, "alpha"),
        (&d.alpha_u, &d.alpha_u_texture, "alpha_u"),
        (&d.alpha_v, &d.alpha_v_texture, "alpha_v"),
    ] {
        match (a, t) {
            (Some(_), Some(t)) => {
                return Err(ctx.at(
                    t.span(),
                    format!("give `{key}` or `{key}_texture`, not both"),
                ))
            }
            (Some(a), None) => {
                let x = ctx.num(a, key)?;
                if !(x >= MIN_ROUGHNESS) {
                    return Err(ctx.at(a.span(), format!("`{key}` must be at least {MIN_ROUGHNESS}, got {x} (use a conductor for a perfectly smooth surface)")));
                }
                b.children.push(float(key, x, a.span()));
            }
            (None, Some(t)) => b.children.push(texture(ctx, t, key)?),
            (None, None) => {}
        }
    }
    Ok(())
}

/// `principled` and `principledthin`: Mitsuba's names and defaults, except `ior` for its `eta`;
/// scalars are numbers here (Mitsuba XML also takes textures for them). η and `specular` go
/// into the tree in f64, as given: η = 1 exactly is moved off the index-matched interface.
fn principled(ctx: &Ctx, d: &MaterialDef, thin: bool, b: &mut Elem) -> Result<(), SceneError> {
    match (&d.base_color, &d.base_color_texture) {
        (Some(_), Some(t)) => {
            return Err(ctx.at(
                t.span(),
                "give `base_color` or `base_color_texture`, not both",
            ))
        }
        (Some(c), None) => b
            .children
            .push(color(ctx, c, "base_color", "base_color", true)?),
        (None, Some(t)) => b.children.push(texture(ctx, t, "base_color")?),
        (None, None) => {}
    }
    let mut spec_trans = 0.0;
    let scalars = [
        (&d.roughness, "roughness", 1.0),
        (&d.anisotropic, "anisotropic", 1.0),
        (&d.spec_trans, "spec_trans", 1.0),
        (&d.spec_tint, "spec_tint", 1.0),
        (&d.sheen, "sheen", 1.0),
        (&d.sheen_tint, "sheen_tint", 1.0),
        (&d.flatness, "flatness", 1.0),
        (&d.metallic, "metallic", 1.0),
        (&d.clearcoat, "clearcoat", 1.0),
        (&d.clearcoat_gloss, "clearcoat_gloss", 1.0),
        (&d.diff_trans, "diff_trans", 2.0),
    ];
    for (v, name, max) in scalars {
        let Some(x) = v else { continue };
        let value = scalar_in_range(name, *x.get_ref(), max).map_err(|e| ctx.at(x.span(), e))?;
        if name == "spec_trans" {
            spec_trans = value;
        }
        b.children.push(float(name, value, x.span()));
    }
    let ior = d.ior.as_ref().map(|i| *i.get_ref());
    let ior_span = || d.ior.as_ref().map_or(d.kind.span(), |i| i.span());
    if thin {
        thin_eta(ior, "ior").map_err(|e| ctx.at(ior_span(), e))?;
    } else {
        let specular = d.specular.as_ref().map(|s| *s.get_ref());
        let eta_span = d.specular.as_ref().map_or_else(ior_span, |s| s.span());
        principled_eta(ior, specular, spec_trans != 0.0, "ior").map_err(|e| ctx.at(eta_span, e))?;
        if let Some(s) = &d.specular {
            b.children.push(float64("specular", *s.get_ref(), s.span()));
        }
    }
    if let Some(i) = &d.ior {
        b.children.push(float64("eta", *i.get_ref(), i.span()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::xml::build::toml_materials;

    /// docs/scene-format.md's material table has a row for every TOML type of `BSDFS` (a type
    /// added to the table and not to the docs fails here), and no row for a type TOML lacks.
    #[test]
    fn toml_docs_list_every_material_type() {
        let docs = include_str!("../../../../../docs/scene-format.md");
        let section = docs
            .split("## `[materials.NAME]`")
            .nth(1)
            .and_then(|s| s.split("\n## ").next())
            .expect("docs/scene-format.md has a `[materials.NAME]` section");
        // The table's rows: after its header and `|---|` line.
        let rows: Vec<&str> = section
            .lines()
            .skip_while(|l| !l.starts_with("|---"))
            .filter_map(|l| l.strip_prefix("| `")?.split('`').next())
            .collect();
        let types: Vec<&str> = toml_materials().collect();
        for t in &types {
            assert!(
                rows.contains(t),
                "docs/scene-format.md has no row for `{t}`"
            );
        }
        for r in &rows {
            assert!(
                types.contains(r),
                "docs/scene-format.md documents `{r}`, not a TOML type"
            );
        }
    }
}

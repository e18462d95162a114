//! What several TOML materials share: plastics, conductors' complex IORs, microfacet
//! distributions.

use crate::error::Ctx;
use crate::toml_scene::schema::{MaterialDef, TextureDef, S};
use crate::SceneError;
use lt_core::bsdf::conductor_ior::{conductor_names, named_conductor, PERFECT_MIRROR};
use lt_core::bsdf::fresnel::ComplexIor;
use lt_core::bsdf::microfacet::{Microfacet, MicrofacetType};
use lt_core::bsdf::plastic::{channel_mean, specular_sampling_weight, AIR_IOR, POLYPROPYLENE_IOR};
use lt_core::bsdf::{Material, TextureSlot, TwoSided};
use lt_core::bsdf::{Plastic, RoughPlastic};
use lt_core::math::Color;

/// GGX α below this is numerically a mirror; use `mirror` instead.
pub(super) const MIN_ROUGHNESS: f32 = 1e-4;

/// Mitsuba's `plastic` / `roughplastic`: `albedo` (its `diffuse_reflectance`, default 0.5, or
/// `albedo_texture`), `reflectance` (`specular_reflectance`, default 1, or `reflectance_texture`),
/// `ior` (int_ior / ext_ior, default polypropylene in air), `nonlinear`, `twosided`; the rough one
/// adds `distribution` and `alpha`. A textured reflectance's mean sets the lobe-sampling weight
/// (`textured_material`).
pub(super) fn plastic(
    ctx: &Ctx,
    d: &MaterialDef,
    kind: &str,
    given: &[(&str, Option<std::ops::Range<usize>>)],
    what: &str,
) -> Result<Material, SceneError> {
    const SMOOTH: [&str; 7] = [
        "albedo",
        "albedo_texture",
        "reflectance",
        "reflectance_texture",
        "ior",
        "nonlinear",
        "twosided",
    ];
    const ROUGH: [&str; 9] = [
        "albedo",
        "albedo_texture",
        "reflectance",
        "reflectance_texture",
        "ior",
        "nonlinear",
        "twosided",
        "distribution",
        "alpha",
    ];
    ctx.only(
        given,
        if kind == "plastic" { &SMOOTH } else { &ROUGH },
        what,
    )?;
    for (plain, texture, key) in [
        (d.albedo.as_ref().map(S::span), &d.albedo_texture, "albedo"),
        (
            d.reflectance.as_ref().map(S::span),
            &d.reflectance_texture,
            "reflectance",
        ),
    ] {
        if let (Some(_), Some(t)) = (plain, texture) {
            return Err(ctx.at(
                t.span(),
                format!("give `{key}` or `{key}_texture`, not both"),
            ));
        }
    }
    let color = |c: &Option<S<crate::toml_scene::schema::ColorDef>>, key, default| {
        c.as_ref()
            .map(|c| ctx.color(c, key, true))
            .transpose()
            .map(|c| c.unwrap_or(Color::splat(default)))
    };
    let diffuse = color(&d.albedo, "albedo", 0.5)?;
    let specular = color(&d.reflectance, "reflectance", 1.0)?;
    let ior = match &d.ior {
        None => POLYPROPYLENE_IOR / AIR_IOR,
        Some(i) => ctx.positive(i, "ior")?,
    };
    if kind == "roughplastic" && ior == 1.0 {
        return Err(ctx.at(
            d.ior.as_ref().unwrap().span(),
            "a roughplastic needs `ior` ≠ 1 (as Mitsuba)",
        ));
    }
    let nonlinear = d.nonlinear.as_ref().is_some_and(|n| *n.get_ref());
    let one_sided = if kind == "plastic" {
        Material::Plastic(Plastic::new(ior, diffuse, specular, nonlinear))
    } else {
        Material::RoughPlastic(RoughPlastic::new(
            microfacet(ctx, d, d.kind.span())?,
            ior,
            diffuse,
            specular,
            nonlinear,
        ))
    };
    Ok(if d.twosided.as_ref().is_some_and(|t| *t.get_ref()) {
        Material::TwoSided(TwoSided {
            inner: Box::new(one_sided),
        })
    } else {
        one_sided
    })
}

/// Mitsuba's lobe-sampling weight of a plastic from the means of its textured reflectances.
pub(super) fn plastic_weight_from_textures(
    m: &mut Material,
    slots: &[(TextureSlot, lt_core::texture::Texture)],
) {
    let mean = |slot, plain: Color| {
        slots
            .iter()
            .rfind(|(s, _)| *s == slot)
            .map_or(plain, |(_, t)| t.mean())
    };
    let weight = |d: Color, s: Color| {
        specular_sampling_weight(
            channel_mean(mean(TextureSlot::Reflectance, d)),
            channel_mean(mean(TextureSlot::SpecularReflectance, s)),
        )
    };
    match m {
        Material::Plastic(p) => {
            p.specular_sampling_weight = weight(p.diffuse_reflectance, p.specular_reflectance)
        }
        Material::RoughPlastic(p) => {
            p.specular_sampling_weight = weight(p.diffuse_reflectance, p.specular_reflectance)
        }
        Material::TwoSided(t) => plastic_weight_from_textures(&mut t.inner, slots),
        _ => {}
    }
}

/// A conductor's complex IOR: a `material` name Mitsuba knows (default "none": a perfect mirror)
/// or `eta` and `k` together.
pub(super) fn complex_ior(
    ctx: &Ctx,
    d: &MaterialDef,
    def: &S<MaterialDef>,
) -> Result<ComplexIor, SceneError> {
    match (&d.material, &d.eta, &d.k) {
        (None, None, None) => Ok(PERFECT_MIRROR),
        (Some(name), None, None) => named_conductor(name.get_ref()).ok_or_else(|| {
            let names: Vec<&str> = conductor_names().collect();
            ctx.at(
                name.span(),
                format!(
                    "conductor material `{}` is not one Mitsuba knows (known: {})",
                    name.get_ref(),
                    names.join(", ")
                ),
            )
        }),
        (None, Some(eta), Some(k)) => Ok(ComplexIor {
            eta: ctx.color(eta, "eta", false)?,
            k: ctx.color(k, "k", false)?,
        }),
        (Some(name), _, _) => Err(ctx.at(
            name.span(),
            "give a conductor `material` or `eta` and `k`, not both",
        )),
        _ => Err(ctx.at(
            def.span(),
            "a conductor's `eta` and `k` go together: give both",
        )),
    }
}

/// A rough conductor's microfacet distribution: `distribution` (beckmann, the default, or ggx)
/// and `alpha` (default 0.1, at least 1e-4) or `alpha_u` and `alpha_v`, sampling visible normals
/// (Mitsuba's defaults).
pub(super) fn microfacet(
    ctx: &Ctx,
    d: &MaterialDef,
    at: std::ops::Range<usize>,
) -> Result<Microfacet, SceneError> {
    let kind = match &d.distribution {
        None => MicrofacetType::Beckmann,
        Some(s) => match s.get_ref().as_str() {
            "beckmann" => MicrofacetType::Beckmann,
            "ggx" => MicrofacetType::Ggx,
            other => {
                return Err(ctx.at(
                    s.span(),
                    format!("`distribution` must be beckmann or ggx, got `{other}`"),
                ))
            }
        },
    };
    let num = |a: &Option<S<f64>>, key: &str| -> Result<Option<f32>, SceneError> {
        let Some(a) = a else { return Ok(None) };
        let x = ctx.num(a, key)?;
        if !(x >= MIN_ROUGHNESS) {
            return Err(ctx.at(a.span(), format!("`{key}` must be at least {MIN_ROUGHNESS}, got {x} (use a conductor for a perfectly smooth surface)")));
        }
        Ok(Some(x))
    };
    // An axis given by a texture counts as given (its value here is a placeholder).
    let given = |a: &Option<S<f64>>, t: &Option<S<TextureDef>>| a.is_some() || t.is_some();
    let (u_given, v_given) = (
        given(&d.alpha_u, &d.alpha_u_texture),
        given(&d.alpha_v, &d.alpha_v_texture),
    );
    let iso_given = given(&d.alpha, &d.alpha_texture);
    if u_given != v_given || (u_given && iso_given) {
        return Err(ctx.at(
            at,
            "give `alpha` (or `alpha_texture`), or both `alpha_u` and `alpha_v` (or their textures)",
        ));
    }
    for (a, t, key) in [
        (&d.alpha, &d.alpha_texture, "alpha"),
        (&d.alpha_u, &d.alpha_u_texture, "alpha_u"),
        (&d.alpha_v, &d.alpha_v_texture, "alpha_v"),
    ] {
        if let (Some(_), Some(t)) = (a, t) {
            return Err(ctx.at(
                t.span(),
                format!("give `{key}` or `{key}_texture`, not both"),
            ));
        }
    }
    let alpha = num(&d.alpha, "alpha")?.unwrap_or(0.1);
    let au = num(&d.alpha_u, "alpha_u")?.unwrap_or(alpha);
    let av = num(&d.alpha_v, "alpha_v")?.unwrap_or(alpha);
    // α_u runs along ∂p/∂u made orthogonal to the normal (`SurfaceHit::tangent`), as in Mitsuba.
    Ok(Microfacet::new(kind, au, av, true))
}

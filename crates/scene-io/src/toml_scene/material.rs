//! A TOML `[materials.NAME]` table as a `Material`: its type's keys, its textured keys, and the
//! normal or bump map and mask around it.

use super::material_params::{
    complex_ior, microfacet, plastic, plastic_weight_from_textures, MIN_ROUGHNESS,
};
use crate::error::Ctx;
use crate::toml_scene::schema::{MaterialDef, S};
use crate::SceneError;
use lt_core::bsdf::textured::set_parameter;
use lt_core::bsdf::{
    Conductor, Dielectric, Diffuse, Glossy, Material, Mirror, NormalSource, Perturbed,
    RoughConductor, RoughDielectric, TextureSlot, Textured, ThinDielectric, TwoSided,
};
use lt_core::bsdf::{Mask, PrincipledParam};
use lt_core::math::Color;
use lt_core::texture::Texture;

pub(super) fn material(
    ctx: &Ctx,
    name: &str,
    def: &S<MaterialDef>,
) -> Result<Material, SceneError> {
    let m = textured_material(ctx, name, def)?;
    let m = perturbed(ctx, def, m)?;
    masked(ctx, def, m)
}

/// `m` under the material's `opacity` or `opacity_texture` (Mitsuba's `mask`), if it has one.
fn masked(ctx: &Ctx, def: &S<MaterialDef>, m: Material) -> Result<Material, SceneError> {
    let d = def.get_ref();
    let opacity = match (&d.opacity, &d.opacity_texture) {
        (None, None) => return Ok(m),
        (Some(_), Some(t)) => {
            return Err(ctx.at(t.span(), "give `opacity` or `opacity_texture`, not both"));
        }
        (Some(a), None) => {
            let v: f32 = ctx.num(a, "opacity")?;
            if !(0.0..=1.0).contains(&v) {
                return Err(ctx.at(a.span(), format!("`opacity` must lie in [0, 1], got {v}")));
            }
            Texture::Constant(Color::splat(v))
        }
        (None, Some(t)) => crate::toml_scene::texture::texture(ctx, t)?,
    };
    Ok(Material::Mask(Box::new(Mask { opacity, inner: m })))
}

/// `m` under the material's `normal_map` or `bump_map`, if it has one.
fn perturbed(ctx: &Ctx, def: &S<MaterialDef>, m: Material) -> Result<Material, SceneError> {
    let d = def.get_ref();
    let source = match (&d.normal_map, &d.bump_map) {
        (None, None) => {
            let stray = [
                ("bump_scale", d.bump_scale.as_ref().map(S::span)),
                (
                    "flip_invalid_normals",
                    d.flip_invalid_normals.as_ref().map(S::span),
                ),
                ("bump_shadowing", d.bump_shadowing.as_ref().map(S::span)),
            ];
            if let Some((key, Some(span))) = stray.into_iter().find(|(_, s)| s.is_some()) {
                return Err(ctx.at(span, format!("`{key}` needs a `normal_map` or `bump_map`")));
            }
            return Ok(m);
        }
        (Some(_), Some(b)) => {
            return Err(ctx.at(b.span(), "give `normal_map` or `bump_map`, not both"));
        }
        (Some(n), None) => {
            if let Some(s) = &d.bump_scale {
                return Err(ctx.at(s.span(), "`bump_scale` applies to a `bump_map`"));
            }
            NormalSource::NormalMap(crate::toml_scene::texture::texture(ctx, n)?)
        }
        (None, Some(b)) => NormalSource::BumpMap {
            height: crate::toml_scene::texture::texture(ctx, b)?,
            scale: match &d.bump_scale {
                None => 1.0,
                Some(s) => ctx.num(s, "bump_scale")?,
            },
        },
    };
    let flag = |v: &Option<S<bool>>| v.as_ref().is_none_or(|v| *v.get_ref());
    Ok(Material::Perturbed(Box::new(Perturbed {
        source,
        inner: m,
        flip_invalid_normals: flag(&d.flip_invalid_normals),
        shadowing: flag(&d.bump_shadowing),
    })))
}

/// The material with its textured parameters (`*_texture`).
fn textured_material(ctx: &Ctx, name: &str, def: &S<MaterialDef>) -> Result<Material, SceneError> {
    let d = def.get_ref();
    let base = plain_material(ctx, name, def)?;
    let mut slots = Vec::new();
    for (tex, slot, key) in [
        (
            &d.albedo_texture,
            TextureSlot::Reflectance,
            "albedo_texture",
        ),
        (
            &d.reflectance_texture,
            TextureSlot::SpecularReflectance,
            "reflectance_texture",
        ),
        (&d.alpha_texture, TextureSlot::Alpha, "alpha_texture"),
        (&d.alpha_u_texture, TextureSlot::AlphaU, "alpha_u_texture"),
        (&d.alpha_v_texture, TextureSlot::AlphaV, "alpha_v_texture"),
        (
            &d.base_color_texture,
            TextureSlot::Principled(PrincipledParam::BaseColor),
            "base_color_texture",
        ),
    ] {
        let Some(t) = tex else { continue };
        let texture = crate::toml_scene::texture::texture(ctx, t)?;
        if !slot.is_roughness() && texture.max_value() > 1.0 {
            return Err(ctx.at(
                t.span(),
                format!(
                    "`{key}` reaches {} (a reflectance must be at most 1)",
                    texture.max_value()
                ),
            ));
        }
        if !set_parameter(&mut base.clone(), slot, Color::ZERO) {
            return Err(ctx.at(
                t.span(),
                format!("`{key}` does not apply to a {} material", d.kind.get_ref()),
            ));
        }
        slots.push((slot, texture));
    }
    Ok(if slots.is_empty() {
        base
    } else {
        let mut base = base;
        plastic_weight_from_textures(&mut base, &slots);
        Material::Textured(Box::new(Textured { base, slots }))
    })
}

/// The material with its untextured parameters (a textured key leaves the default in place).
fn plain_material(ctx: &Ctx, name: &str, def: &S<MaterialDef>) -> Result<Material, SceneError> {
    let d = def.get_ref();
    let kind = d.kind.get_ref().as_str();
    let what = format!("material `{name}` of type {kind}");
    let given = [
        ("albedo", d.albedo.as_ref().map(S::span)),
        ("reflectance", d.reflectance.as_ref().map(S::span)),
        ("ior", d.ior.as_ref().map(S::span)),
        ("roughness", d.roughness.as_ref().map(S::span)),
        ("material", d.material.as_ref().map(S::span)),
        ("eta", d.eta.as_ref().map(S::span)),
        ("k", d.k.as_ref().map(S::span)),
        ("distribution", d.distribution.as_ref().map(S::span)),
        ("alpha", d.alpha.as_ref().map(S::span)),
        ("alpha_u", d.alpha_u.as_ref().map(S::span)),
        ("alpha_v", d.alpha_v.as_ref().map(S::span)),
        ("transmittance", d.transmittance.as_ref().map(S::span)),
        ("twosided", d.twosided.as_ref().map(S::span)),
        ("albedo_texture", d.albedo_texture.as_ref().map(S::span)),
        (
            "reflectance_texture",
            d.reflectance_texture.as_ref().map(S::span),
        ),
        ("alpha_texture", d.alpha_texture.as_ref().map(S::span)),
        ("alpha_u_texture", d.alpha_u_texture.as_ref().map(S::span)),
        ("alpha_v_texture", d.alpha_v_texture.as_ref().map(S::span)),
        ("nonlinear", d.nonlinear.as_ref().map(S::span)),
        ("base_color", d.base_color.as_ref().map(S::span)),
        (
            "base_color_texture",
            d.base_color_texture.as_ref().map(S::span),
        ),
        ("anisotropic", d.anisotropic.as_ref().map(S::span)),
        ("metallic", d.metallic.as_ref().map(S::span)),
        ("spec_trans", d.spec_trans.as_ref().map(S::span)),
        ("specular", d.specular.as_ref().map(S::span)),
        ("spec_tint", d.spec_tint.as_ref().map(S::span)),
        ("sheen", d.sheen.as_ref().map(S::span)),
        ("sheen_tint", d.sheen_tint.as_ref().map(S::span)),
        ("flatness", d.flatness.as_ref().map(S::span)),
        ("clearcoat", d.clearcoat.as_ref().map(S::span)),
        ("clearcoat_gloss", d.clearcoat_gloss.as_ref().map(S::span)),
        ("diff_trans", d.diff_trans.as_ref().map(S::span)),
    ];
    let reflectance = |default: f32| {
        d.reflectance
            .as_ref()
            .map(|r| ctx.color(r, "reflectance", true))
            .transpose()
            .map(|c| c.unwrap_or(Color::splat(default)))
    };
    Ok(match kind {
        "diffuse" => {
            ctx.only(&given, &["albedo", "albedo_texture"], &what)?;
            let albedo = match (&d.albedo, &d.albedo_texture) {
                (Some(a), None) => ctx.color(a, "albedo", true)?,
                (None, Some(_)) => Color::splat(0.5),
                (Some(_), Some(t)) => {
                    return Err(ctx.at(t.span(), "give `albedo` or `albedo_texture`, not both"))
                }
                (None, None) => {
                    return Err(ctx.at(def.span(), format!("missing required key `albedo` (or `albedo_texture`) for {what}")))
                }
            };
            Material::Diffuse(Diffuse { albedo })
        }
        "mirror" => {
            ctx.only(&given, &["reflectance"], &what)?;
            Material::Mirror(Mirror {
                reflectance: reflectance(1.0)?,
            })
        }
        "dielectric" => {
            ctx.only(&given, &["ior"], &what)?;
            Material::Dielectric(Dielectric {
                ior: ctx.positive(ctx.need(&d.ior, "ior", &def.span(), &what)?, "ior")?,
            })
        }
        "glossy" => {
            ctx.only(&given, &["reflectance", "roughness"], &what)?;
            let r = ctx.need(&d.roughness, "roughness", &def.span(), &what)?;
            let roughness = ctx.num(r, "roughness")?;
            if !(roughness >= MIN_ROUGHNESS) {
                return Err(ctx.at(r.span(), format!("`roughness` (GGX α) must be at least {MIN_ROUGHNESS}, got {roughness} (use a mirror for a perfectly smooth surface)")));
            }
            Material::Glossy(Glossy {
                reflectance: reflectance(1.0)?,
                roughness,
            })
        }
        "roughdielectric" | "thindielectric" => {
            const THIN: [&str; 4] = ["ior", "reflectance", "transmittance", "reflectance_texture"];
            const ROUGH: [&str; 11] = [
                "ior",
                "reflectance",
                "transmittance",
                "distribution",
                "alpha",
                "reflectance_texture",
                "alpha_texture",
                "alpha_u",
                "alpha_v",
                "alpha_u_texture",
                "alpha_v_texture",
            ];
            ctx.only(&given, if kind == "thindielectric" { &THIN } else { &ROUGH }, &what)?;
            let ior = ctx.positive(ctx.need(&d.ior, "ior", &def.span(), &what)?, "ior")?;
            let specular_reflectance = reflectance(1.0)?;
            let specular_transmittance = d
                .transmittance
                .as_ref()
                .map(|t| ctx.color(t, "transmittance", true))
                .transpose()?
                .unwrap_or(Color::ONE);
            if kind == "thindielectric" {
                Material::ThinDielectric(ThinDielectric {
                    ior,
                    specular_reflectance,
                    specular_transmittance,
                })
            } else {
                Material::RoughDielectric(RoughDielectric {
                    distribution: microfacet(ctx, d, def.span())?,
                    ior,
                    specular_reflectance,
                    specular_transmittance,
                })
            }
        }
        "conductor" | "roughconductor" => {
            const SMOOTH: [&str; 6] = [
                "reflectance",
                "material",
                "eta",
                "k",
                "twosided",
                "reflectance_texture",
            ];
            const ROUGH: [&str; 13] = [
                "reflectance",
                "material",
                "eta",
                "k",
                "twosided",
                "distribution",
                "alpha",
                "reflectance_texture",
                "alpha_texture",
                "alpha_u",
                "alpha_v",
                "alpha_u_texture",
                "alpha_v_texture",
            ];
            ctx.only(&given, if kind == "conductor" { &SMOOTH } else { &ROUGH }, &what)?;
            let ior = complex_ior(ctx, d, def)?;
            let specular_reflectance = reflectance(1.0)?;
            let one_sided = if kind == "conductor" {
                Material::Conductor(Conductor {
                    ior,
                    specular_reflectance,
                })
            } else {
                Material::RoughConductor(RoughConductor {
                    distribution: microfacet(ctx, d, def.span())?,
                    ior,
                    specular_reflectance,
                })
            };
            if d.twosided.as_ref().is_some_and(|t| *t.get_ref()) {
                Material::TwoSided(TwoSided {
                    inner: Box::new(one_sided),
                })
            } else {
                one_sided
            }
        }
        "plastic" | "roughplastic" => plastic(ctx, d, kind, &given, &what)?,
        "principled" | "principledthin" => {
            crate::toml_scene::principled::principled(ctx, d, &given, &what)?
        }
        other => {
            return Err(ctx.at(
                d.kind.span(),
                format!(
                "unknown material type `{other}` (expected diffuse, mirror, dielectric, roughdielectric, thindielectric, glossy, conductor, roughconductor, plastic, roughplastic, principled or principledthin)"
            ),
            ))
        }
    })
}

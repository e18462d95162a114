//! Turns the parsed file into a `Scene` through `SceneBuilder`, checking each value on the way.

use crate::error::Ctx;
use crate::format::{
    CameraDef, FilterDef, LightDef, MaterialDef, SceneFile, ShapeDef, TextureDef, S,
};
use crate::transform::{check_quad, check_solid, shape_matrix};
use crate::world::{out_of_range_message, LookAt, WorldBuilder, WorldGeometry, WorldMesh};
use crate::SceneError;
use glam::DVec3;
use lt_core::bsdf::conductor_ior::{conductor_names, named_conductor, PERFECT_MIRROR};
use lt_core::bsdf::fresnel::ComplexIor;
use lt_core::bsdf::microfacet::{Microfacet, MicrofacetType};
use lt_core::bsdf::plastic::{channel_mean, specular_sampling_weight, AIR_IOR, POLYPROPYLENE_IOR};
use lt_core::bsdf::textured::set_parameter;
use lt_core::bsdf::{
    Conductor, Dielectric, Diffuse, Glossy, Material, Mirror, NormalSource, Perturbed,
    RoughConductor, RoughDielectric, TextureSlot, Textured, ThinDielectric, TwoSided,
};
use lt_core::bsdf::{Mask, Plastic, PrincipledParam, RoughPlastic};
use lt_core::camera::{Camera, FilterShape, FovAxis, PixelFilter};
use lt_core::light::SunLight;
use lt_core::math::{Color, Vec2, PI};
use lt_core::scene::{LightDesc, RenderSettings, Scene, TriangleMesh};
use lt_core::texture::Texture;
use std::collections::HashMap;

/// GGX α below this is numerically a mirror; use `mirror` instead.
const MIN_ROUGHNESS: f32 = 1e-4;

pub fn assemble(ctx: &Ctx, file: &SceneFile) -> Result<Scene, SceneError> {
    // Checked here, at the origin, so that a degenerate camera is the error reported first.
    camera(ctx, &file.camera, DVec3::ZERO)?;
    let settings = render(ctx, file)?;
    let mut b = WorldBuilder::new(settings);
    let mut ids = HashMap::new();
    // In file order, so ids and the first error reported follow the file.
    let mut materials: Vec<_> = file.materials.iter().collect();
    materials.sort_by_key(|(_, def)| def.span().start);
    for (name, def) in materials {
        ids.insert(name.as_str(), b.add_material(material(ctx, name, def)?));
    }
    let mut emitters = 0;
    for def in &file.shapes {
        emitters += shape(ctx, def, &ids, &mut b)? as usize;
    }
    for def in &file.lights {
        match light(ctx, def)? {
            Some(Placed::At(position, l)) => b.add_light_at(l, position),
            Some(Placed::Anywhere(l)) => b.add_light(l),
            None => continue,
        }
        emitters += 1;
    }
    if emitters == 0 {
        return Err(ctx.whole(
            "the scene has no light: give a shape a non-zero `emission` or add a [[lights]] entry",
        ));
    }
    b.build(|origin| camera(ctx, &file.camera, origin))
}

/// The camera as the file places it, with its eye and target as world − `origin`.
fn camera(ctx: &Ctx, c: &S<CameraDef>, origin: DVec3) -> Result<Camera, SceneError> {
    let d = c.get_ref();
    let up =
        d.up.as_ref()
            .map(|u| ctx.dvec3(u, "up"))
            .transpose()?
            .unwrap_or(DVec3::Y);
    let [width, height] = *d.resolution.get_ref();
    let kind = d
        .kind
        .as_ref()
        .map_or("perspective", |k| k.get_ref().as_str());
    let kind_span = d.kind.as_ref().map_or(c.span(), |k| k.span());
    // Keys that belong to another camera type are refused, not ignored.
    let only = |key: &str, given: bool, types: &str| {
        if given {
            Err(ctx.at(
                c.span(),
                format!("`{key}` belongs to a {types} camera, not `{kind}`"),
            ))
        } else {
            Ok(())
        }
    };
    if kind != "thinlens" {
        only("aperture_radius", d.aperture_radius.is_some(), "thinlens")?;
        only("focus_distance", d.focus_distance.is_some(), "thinlens")?;
    }
    if kind != "orthographic" {
        only("half_width", d.half_width.is_some(), "orthographic")?;
    }
    let fov = match (&d.fov, kind) {
        (Some(f), _) => ctx.num(f, "fov")?,
        (None, "orthographic") => 90.0,
        (None, _) => return Err(ctx.at(c.span(), format!("a `{kind}` camera needs `fov`"))),
    };
    if kind == "orthographic" {
        only("fov", d.fov.is_some(), "perspective or thinlens")?;
    }
    let degenerate = |e: String| ctx.at(c.span(), format!("degenerate camera: {e}"));
    let mut camera = LookAt {
        eye: ctx.dvec3(&d.eye, "eye")?,
        target: ctx.dvec3(&d.target, "target")?,
        up,
        fov_deg: fov,
        fov_axis: d.fov_axis.map_or(FovAxis::X, FovAxis::from),
        width,
        height,
    }
    .at(origin)
    .map_err(degenerate)?;
    camera = match kind {
        "perspective" => camera,
        "thinlens" => {
            let (Some(r), Some(f)) = (&d.aperture_radius, &d.focus_distance) else {
                return Err(ctx.at(
                    c.span(),
                    "a `thinlens` camera needs `aperture_radius` and `focus_distance`",
                ));
            };
            let (r, f) = (
                ctx.positive(r, "aperture_radius")?,
                ctx.positive(f, "focus_distance")?,
            );
            camera.thin_lens(r, f).map_err(degenerate)?
        }
        "orthographic" => {
            let hw = match &d.half_width {
                Some(v) => ctx.positive(v, "half_width")?,
                None => 1.0,
            };
            camera.orthographic(hw).map_err(degenerate)?
        }
        other => {
            return Err(ctx.at(
                kind_span,
                format!(
                    "unknown camera type `{other}` (known: perspective, thinlens, orthographic)"
                ),
            ))
        }
    };
    if let Some(o) = &d.principal_point_offset {
        let [x, y] = *o.get_ref();
        camera = camera
            .with_principal_point_offset(Vec2::new(x as f32, y as f32))
            .map_err(|e| ctx.at(o.span(), e))?;
    }
    if let Some(f) = &d.filter {
        camera = camera.with_filter(filter(ctx, f)?);
    }
    Ok(camera)
}

/// `[camera.filter]` with Mitsuba's parameter names and defaults.
fn filter(ctx: &Ctx, f: &S<FilterDef>) -> Result<PixelFilter, SceneError> {
    let d = f.get_ref();
    let name = d.kind.get_ref().as_str();
    let allowed: &[&str] = match name {
        "box" | "tent" => &["radius"],
        "gaussian" => &["stddev"],
        "mitchell" => &["B", "C"],
        "catmullrom" => &[],
        "lanczos" => &["lobes"],
        other => {
            return Err(ctx.at(
                d.kind.span(),
                format!(
                    "unknown pixel filter `{other}` (known: box, tent, gaussian, mitchell, \
                     catmullrom, lanczos)"
                ),
            ))
        }
    };
    let given = [
        ("radius", d.radius.is_some()),
        ("stddev", d.stddev.is_some()),
        ("B", d.b.is_some()),
        ("C", d.c.is_some()),
        ("lobes", d.lobes.is_some()),
    ];
    if let Some((key, _)) = given.iter().find(|(k, g)| *g && !allowed.contains(k)) {
        return Err(ctx.at(f.span(), format!("the `{name}` filter takes no `{key}`")));
    }
    let num = |v: &Option<S<f64>>, key: &str, default: f32| -> Result<f32, SceneError> {
        v.as_ref().map_or(Ok(default), |v| ctx.num(v, key))
    };
    let shape = match name {
        "box" => FilterShape::Box {
            radius: num(&d.radius, "radius", 0.5)?,
        },
        "tent" => FilterShape::Tent {
            radius: num(&d.radius, "radius", 1.0)?,
        },
        "gaussian" => FilterShape::Gaussian {
            stddev: num(&d.stddev, "stddev", 0.5)?,
        },
        "mitchell" => FilterShape::Mitchell {
            b: num(&d.b, "B", 1.0 / 3.0)?,
            c: num(&d.c, "C", 1.0 / 3.0)?,
        },
        "catmullrom" => FilterShape::CatmullRom,
        _ => FilterShape::Lanczos {
            lobes: d.lobes.as_ref().map_or(3, |l| *l.get_ref()),
        },
    };
    PixelFilter::new(shape).map_err(|e| ctx.at(f.span(), e))
}

fn render(ctx: &Ctx, file: &SceneFile) -> Result<RenderSettings, SceneError> {
    let mut s = RenderSettings::default();
    let Some(r) = &file.render else { return Ok(s) };
    if let Some(m) = &r.max_depth {
        s.max_depth = *m.get_ref();
        if s.max_depth == 0 {
            return Err(ctx.at(
                m.span(),
                "`max_depth` must be at least 1 (1 = emitters seen directly)",
            ));
        }
    }
    if let Some(spp) = &r.spp {
        s.spp = *spp.get_ref();
        if s.spp == 0 {
            return Err(ctx.at(spp.span(), "`spp` must be at least 1"));
        }
    }
    s.rr_depth = r.rr_depth.unwrap_or(s.rr_depth);
    Ok(s)
}

fn material(ctx: &Ctx, name: &str, def: &S<MaterialDef>) -> Result<Material, SceneError> {
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
        (None, Some(t)) => crate::texture_def::texture(ctx, t)?,
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
            NormalSource::NormalMap(crate::texture_def::texture(ctx, n)?)
        }
        (None, Some(b)) => NormalSource::BumpMap {
            height: crate::texture_def::texture(ctx, b)?,
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
        let texture = crate::texture_def::texture(ctx, t)?;
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
            crate::principled_def::principled(ctx, d, &given, &what)?
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

/// Mitsuba's `plastic` / `roughplastic`: `albedo` (its `diffuse_reflectance`, default 0.5, or
/// `albedo_texture`), `reflectance` (`specular_reflectance`, default 1, or `reflectance_texture`),
/// `ior` (int_ior / ext_ior, default polypropylene in air), `nonlinear`, `twosided`; the rough one
/// adds `distribution` and `alpha`. A textured reflectance's mean sets the lobe-sampling weight
/// (`textured_material`).
fn plastic(
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
    let color = |c: &Option<S<crate::format::ColorDef>>, key, default| {
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
fn plastic_weight_from_textures(
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
fn complex_ior(ctx: &Ctx, d: &MaterialDef, def: &S<MaterialDef>) -> Result<ComplexIor, SceneError> {
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
fn microfacet(
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

/// Adds the shape; returns whether it emits.
fn shape(
    ctx: &Ctx,
    def: &S<ShapeDef>,
    ids: &HashMap<&str, u32>,
    b: &mut WorldBuilder,
) -> Result<bool, SceneError> {
    let d = def.get_ref();
    let kind = d.kind.get_ref().as_str();
    let what = format!("a {kind} shape");
    let given = [
        ("file", d.file.as_ref().map(S::span)),
        ("center", d.center.as_ref().map(S::span)),
        ("radius", d.radius.as_ref().map(S::span)),
        ("to_world", d.to_world.as_ref().map(S::span)),
        ("translate", d.translate.as_ref().map(S::span)),
        ("rotate", d.rotate.as_ref().map(S::span)),
        ("scale", d.scale.as_ref().map(S::span)),
    ];
    const PLACED: [&str; 4] = ["to_world", "translate", "rotate", "scale"];
    let geometry = match kind {
        "sphere" => {
            ctx.only(&given, &["center", "radius"], &what)?;
            let center = ctx.dvec3(ctx.need(&d.center, "center", &def.span(), &what)?, "center")?;
            let radius =
                ctx.positive(ctx.need(&d.radius, "radius", &def.span(), &what)?, "radius")?;
            WorldGeometry::Sphere {
                center,
                radius: radius.into(),
                rotation: None,
            }
        }
        "quad" | "cube" => {
            ctx.only(&given, &PLACED, &what)?;
            let (m, span) = shape_matrix(ctx, d)?;
            if kind == "quad" {
                check_quad(ctx, &m, span.clone())?;
                placed(
                    ctx,
                    span,
                    WorldMesh::place(&TriangleMesh::unit_rectangle(), &m),
                )?
            } else {
                check_solid(ctx, &m, span.clone(), "cube")?;
                placed(ctx, span, WorldMesh::place(&TriangleMesh::unit_cube(), &m))?
            }
        }
        "mesh" => {
            ctx.only(
                &given,
                &["file", "to_world", "translate", "rotate", "scale"],
                &what,
            )?;
            let file = ctx.need(&d.file, "file", &def.span(), &what)?;
            let (m, span) = shape_matrix(ctx, d)?;
            check_solid(ctx, &m, span.clone(), "mesh")?;
            let local = crate::mesh::obj::load_obj(ctx, file)?;
            let mesh = placed(ctx, span, WorldMesh::place(&local, &m))?;
            if !matches!(&mesh, WorldGeometry::Mesh(m) if m.area() > 0.0) {
                return Err(ctx.at(
                    file.span(),
                    "the mesh has zero area (every triangle is degenerate)",
                ));
            }
            mesh
        }
        other => {
            return Err(ctx.at(
                d.kind.span(),
                format!("unknown shape type `{other}` (expected mesh, quad, cube or sphere)"),
            ))
        }
    };
    let name = d.material.get_ref();
    let Some(&material) = ids.get(name.as_str()) else {
        let mut defined: Vec<&str> = ids.keys().copied().collect();
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
    };
    let radiance = match (&d.emission, &d.emission_texture) {
        (Some(_), Some(t)) => {
            return Err(ctx.at(t.span(), "give `emission` or `emission_texture`, not both"))
        }
        (Some(e), None) => Some(ctx.color(e, "emission", false)?)
            .filter(|e| e.max_element() > 0.0)
            .map(Texture::Constant),
        (None, Some(t)) => {
            Some(crate::texture_def::texture(ctx, t)?).filter(|t| t.max_value() > 0.0)
        }
        (None, None) => None,
    };
    let emits = radiance.is_some();
    b.add_shape(geometry, material, radiance, d.flip_normals);
    Ok(emits)
}

/// A mesh placed in the world whose every vertex is in range, else an error at `span`.
fn placed(
    ctx: &Ctx,
    span: std::ops::Range<usize>,
    mesh: WorldMesh,
) -> Result<WorldGeometry, SceneError> {
    match mesh.out_of_range() {
        Some(p) => Err(ctx.at(span, out_of_range_message("the transformed shape", p))),
        None => Ok(WorldGeometry::Mesh(mesh)),
    }
}

/// A light with a world position (kept in f64 until the one rounding) or without one.
enum Placed {
    At(DVec3, LightDesc),
    Anywhere(LightDesc),
}

/// The light, or None when it emits nothing.
fn light(ctx: &Ctx, def: &S<LightDef>) -> Result<Option<Placed>, SceneError> {
    let d = def.get_ref();
    let kind = d.kind.get_ref().as_str();
    let what = format!("a {kind} light");
    let given = [
        ("position", d.position.as_ref().map(S::span)),
        ("intensity", d.intensity.as_ref().map(S::span)),
        ("direction", d.direction.as_ref().map(S::span)),
        ("solid_angle", d.solid_angle.as_ref().map(S::span)),
        ("radiance", d.radiance.as_ref().map(S::span)),
        ("irradiance", d.irradiance.as_ref().map(S::span)),
        ("file", d.file.as_ref().map(S::span)),
        ("scale", d.scale.as_ref().map(S::span)),
        ("rotate", d.rotate.as_ref().map(S::span)),
        ("target", d.target.as_ref().map(S::span)),
        ("up", d.up.as_ref().map(S::span)),
        ("cutoff_angle", d.cutoff_angle.as_ref().map(S::span)),
        ("beam_width", d.beam_width.as_ref().map(S::span)),
        ("texture", d.texture.as_ref().map(S::span)),
        ("fov", d.fov.as_ref().map(S::span)),
    ];
    let span = def.span();
    let desc = match kind {
        "point" => {
            ctx.only(&given, &["position", "intensity"], &what)?;
            let position =
                ctx.dvec3(ctx.need(&d.position, "position", &span, &what)?, "position")?;
            let intensity = ctx.color(
                ctx.need(&d.intensity, "intensity", &span, &what)?,
                "intensity",
                false,
            )?;
            let desc = LightDesc::Point {
                position: glam::Vec3::ZERO,
                intensity,
            };
            return Ok((intensity.max_element() > 0.0).then_some(Placed::At(position, desc)));
        }
        "sun" => {
            ctx.only(
                &given,
                &["direction", "solid_angle", "radiance", "irradiance"],
                &what,
            )?;
            let dir = ctx.need(&d.direction, "direction", &span, &what)?;
            let direction = ctx.vec3(dir, "direction")?;
            if !(direction.length() > 0.0) {
                return Err(ctx.at(
                    dir.span(),
                    "`direction` (towards the sun) is the zero vector",
                ));
            }
            let sa = ctx.need(&d.solid_angle, "solid_angle", &span, &what)?;
            let solid_angle = ctx.positive(sa, "solid_angle")?;
            if !(solid_angle < 2.0 * PI) {
                return Err(ctx.at(
                    sa.span(),
                    format!("`solid_angle` must be below 2π sr (a hemisphere), got {solid_angle}"),
                ));
            }
            let radiance = match (&d.radiance, &d.irradiance) {
                (Some(r), None) => ctx.color(r, "radiance", false)?,
                (None, Some(e)) => {
                    let l = SunLight::radiance_from_irradiance(
                        ctx.color(e, "irradiance", false)?,
                        solid_angle,
                    );
                    if !l.is_finite() {
                        return Err(ctx.at(sa.span(), format!("`solid_angle` {solid_angle} is too small to turn the irradiance into a finite radiance")));
                    }
                    l
                }
                (Some(_), Some(e)) => {
                    return Err(ctx.at(
                        e.span(),
                        "give the sun `radiance` or `irradiance`, not both",
                    ))
                }
                (None, None) => {
                    return Err(ctx.at(
                        span,
                        "missing required key `radiance` or `irradiance` for a sun light",
                    ))
                }
            };
            LightDesc::Sun {
                direction: direction.normalize(),
                solid_angle,
                radiance,
            }
        }
        "directional" => {
            // A delta in direction has no solid angle, so no radiance: say so before the generic
            // "does not apply" check would.
            if let Some(r) = &d.radiance {
                return Err(ctx.at(
                    r.span(),
                    "a directional light takes `irradiance` (W/m² on a surface facing it), not \
                     `radiance`: it is a delta in direction, with no solid angle to spread a \
                     radiance over (for a light of finite angular size use type = \"sun\")",
                ));
            }
            ctx.only(&given, &["direction", "irradiance"], &what)?;
            let dir = ctx.need(&d.direction, "direction", &span, &what)?;
            let direction = ctx.vec3(dir, "direction")?;
            if !(direction.length() > 0.0) {
                return Err(ctx.at(
                    dir.span(),
                    "`direction` (towards the light) is the zero vector",
                ));
            }
            let irradiance = ctx.color(
                ctx.need(&d.irradiance, "irradiance", &span, &what)?,
                "irradiance",
                false,
            )?;
            LightDesc::Directional {
                direction: direction.normalize(),
                irradiance,
            }
        }
        "environment" => {
            ctx.only(&given, &["radiance"], &what)?;
            LightDesc::Environment {
                radiance: ctx.color(
                    ctx.need(&d.radiance, "radiance", &span, &what)?,
                    "radiance",
                    false,
                )?,
            }
        }
        "envmap" => {
            ctx.only(&given, &["file", "scale", "rotate"], &what)?;
            let file = ctx.need(&d.file, "file", &span, &what)?;
            let scale = match &d.scale {
                None => 1.0,
                Some(s) => ctx.num(s, "scale")?,
            };
            let to_world = match &d.rotate {
                None => glam::Mat3::IDENTITY,
                Some(r) => crate::transform::rotate_def(ctx, r)?.as_mat3(),
            };
            let path = ctx.base_dir.join(file.get_ref());
            let map = crate::image_file::read_environment_map(&path, scale, to_world)
                .map_err(|m| ctx.at(file.span(), m))?;
            LightDesc::EnvironmentMap {
                map: std::sync::Arc::new(map),
            }
        }
        "spot" => {
            ctx.only(
                &given,
                &["position", "target", "up", "intensity", "cutoff_angle", "beam_width", "texture"],
                &what,
            )?;
            let (position, to_world) = aimed(ctx, d, &span, &what)?;
            let intensity = ctx.color(
                ctx.need(&d.intensity, "intensity", &span, &what)?,
                "intensity",
                false,
            )?;
            let cutoff = match &d.cutoff_angle {
                None => 20.0,
                Some(c) => ctx.positive(c, "cutoff_angle")?,
            };
            let texture = match &d.texture {
                None => None,
                Some(t) => Some(crate::texture_def::texture(ctx, t)?),
            };
            let max = if texture.is_some() { 90.0 } else { 180.0 };
            if !(cutoff < max) {
                let at = d.cutoff_angle.as_ref().map_or(span.clone(), S::span);
                return Err(ctx.at(at, format!("`cutoff_angle` must be below {max}°{}, got {cutoff}", if texture.is_some() { " with a texture (it lies on a plane in front of the light)" } else { "" })));
            }
            let beam = match &d.beam_width {
                None => 0.75 * cutoff,
                Some(b) => {
                    let b = ctx.num(b, "beam_width")?;
                    if !(b >= 0.0) {
                        return Err(ctx.at(d.beam_width.as_ref().unwrap().span(), format!("`beam_width` must be a non-negative angle in degrees, got {b}")));
                    }
                    b
                }
            };
            let dark = intensity.max_element() <= 0.0
                || texture.as_ref().is_some_and(|t| t.max_value() <= 0.0);
            let desc = LightDesc::Spot {
                position: glam::Vec3::ZERO,
                to_world,
                intensity,
                texture,
                cutoff: cutoff.to_radians(),
                beam_width: beam.to_radians(),
            };
            return Ok((!dark).then_some(Placed::At(position, desc)));
        }
        "projector" => {
            ctx.only(
                &given,
                &["position", "target", "up", "irradiance", "texture", "scale", "fov"],
                &what,
            )?;
            let (position, to_world) = aimed(ctx, d, &span, &what)?;
            let (irradiance, aspect) = match (&d.texture, &d.irradiance) {
                (Some(_), Some(e)) => {
                    return Err(ctx.at(e.span(), "give the projector `irradiance` or `texture`, not both"))
                }
                (Some(t), None) => {
                    let tex = crate::texture_def::texture(ctx, t)?;
                    let aspect = match &tex {
                        lt_core::texture::Texture::Bitmap(b) => b.width as f64 / b.height as f64,
                        _ => 1.0,
                    };
                    (tex, aspect)
                }
                (None, Some(e)) => (lt_core::texture::Texture::Constant(ctx.color(e, "irradiance", false)?), 1.0),
                (None, None) => {
                    return Err(ctx.at(span, "missing required key `irradiance` or `texture` for a projector light"))
                }
            };
            let scale = match &d.scale {
                None => 1.0,
                Some(s) => ctx.num(s, "scale")?,
            };
            let fov_def = ctx.need(&d.fov, "fov", &span, &what)?;
            // In f64, as the XML loader computes it, so that a converted scene reads back exactly.
            let fov = *fov_def.get_ref();
            if !(fov > 0.0 && fov < 180.0 && scale >= 0.0) {
                return Err(ctx.at(fov_def.span(), format!("a projector needs 0 < `fov` < 180 (degrees) and `scale` ≥ 0, got {fov} and {scale}")));
            }
            let tan_x = (0.5 * fov).to_radians().tan();
            let dark = scale == 0.0 || irradiance.max_value() <= 0.0;
            let desc = LightDesc::Projector {
                position: glam::Vec3::ZERO,
                to_world,
                irradiance,
                scale,
                tan_half: glam::Vec2::new(tan_x as f32, (tan_x / aspect) as f32),
            };
            return Ok((!dark).then_some(Placed::At(position, desc)));
        }
        other => {
            return Err(ctx.at(
                d.kind.span(),
                format!(
                    "unknown light type `{other}` (expected point, spot, projector, sun, directional, environment or envmap)"
                ),
            ))
        }
    };
    let power = match &desc {
        LightDesc::Point { intensity: c, .. }
        | LightDesc::Sun { radiance: c, .. }
        | LightDesc::Directional { irradiance: c, .. }
        | LightDesc::Environment { radiance: c } => c.max_element(),
        LightDesc::EnvironmentMap { map } => map.integral(),
        LightDesc::Spot { .. } | LightDesc::Projector { .. } => {
            unreachable!("spot and projector return above")
        }
    };
    Ok((power > 0.0).then_some(Placed::Anywhere(desc)))
}

/// The world position and the rotation (Mitsuba's lookat) of a light aimed from `position` at
/// `target`, with `up` or its default (`transform::default_up`).
fn aimed(
    ctx: &Ctx,
    d: &LightDef,
    span: &std::ops::Range<usize>,
    what: &str,
) -> Result<(DVec3, glam::Mat3), SceneError> {
    let position = ctx.dvec3(ctx.need(&d.position, "position", span, what)?, "position")?;
    let target_def = ctx.need(&d.target, "target", span, what)?;
    let target = ctx.dvec3(target_def, "target")?;
    let up = match &d.up {
        Some(u) => ctx.dvec3(u, "up")?,
        None => crate::transform::default_up(target - position),
    };
    let at = d.up.as_ref().map_or(target_def.span(), S::span);
    let r = crate::transform::look_at_rotation(position, target, up).map_err(|m| ctx.at(at, m))?;
    Ok((position, r.as_mat3()))
}

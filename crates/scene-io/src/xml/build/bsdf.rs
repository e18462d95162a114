//! `<bsdf>`: every BSDF type lt reads, each one entry of `BSDFS`.

use super::bsdf_toml::Keys::{self, *};
use super::bsdf_toml::{same_name, TomlType};
use super::Loader;
use crate::world::WorldBuilder;
use crate::xml::doc::Elem;
use crate::xml::props::{ColorUse, Plugin};
use crate::SceneError;
use lt_core::bsdf::conductor_ior::PERFECT_MIRROR;
use lt_core::bsdf::microfacet::MicrofacetType;
use lt_core::bsdf::{Blend, Mask, NormalSource, Perturbed, TextureSlot, Textured};
use lt_core::bsdf::{
    Conductor, Dielectric, Diffuse, FrontDiffuse, Glossy, Material, Mirror, RoughConductor,
    RoughDielectric, ThinDielectric, TwoSided,
};
use lt_core::math::Color;
use lt_core::texture::Texture;

impl<'a> Loader<'a> {
    /// The material id of a BSDF element (converted once, however often it is referenced).
    pub(super) fn material(
        &mut self,
        e: &'a Elem,
        b: &mut WorldBuilder,
    ) -> Result<u32, SceneError> {
        let key = e as *const Elem;
        if let Some(&id) = self.materials.get(&key) {
            return Ok(id);
        }
        let m = self.bsdf(e, false)?;
        let id = b.add_material(m);
        self.materials.insert(key, id);
        Ok(id)
    }

    /// A BSDF element as a material: its type's entry of `BSDFS` builds it, every parameter it
    /// leaves is an error, and parameters given as textures wrap it in `Textured`.
    pub(super) fn bsdf(&mut self, e: &'a Elem, in_twosided: bool) -> Result<Material, SceneError> {
        let p = self.plugin(e)?;
        let Some(&(_, build, _)) = BSDFS.iter().find(|(name, ..)| *name == p.kind) else {
            return Err(super::kinds::unknown_type(self.doc, e));
        };
        // Parameters given as textures: the material is built with their defaults and the
        // textures set them at each shading point.
        let mut slots: Slots = Vec::new();
        let m = build(self, &p, in_twosided, &mut slots)?;
        p.finish(&[], &mut self.report)?;
        Ok(if slots.is_empty() {
            m
        } else {
            Material::Textured(Box::new(Textured { base: m, slots }))
        })
    }

    /// A colour parameter that may be a texture: a texture goes to `slots` (and None is returned,
    /// so the material keeps its default there); a plain colour is returned.
    pub(super) fn color_or_texture(
        &mut self,
        p: &Plugin<'a>,
        name: &str,
        slot: TextureSlot,
        slots: &mut Vec<(TextureSlot, Texture)>,
    ) -> Result<Option<Color>, SceneError> {
        if let Some(t) = p.texture(name) {
            let texture = self.texture(t)?;
            if !slot.is_scalar() && texture.max_value() > 1.0 {
                return Err(p.err(
                    t,
                    format!(
                        "the texture of `{name}` reaches {} (a reflectance must be at most 1)",
                        texture.max_value()
                    ),
                ));
            }
            slots.push((slot, texture));
            return Ok(None);
        }
        let usage = if slot.is_scalar() {
            ColorUse::Emission
        } else {
            ColorUse::Reflectance
        };
        p.color(name, usage, self.opts, &mut self.report)
    }
}

/// The textured parameters a BSDF builder found: each slot's texture, set at every shading point.
pub(super) type Slots = Vec<(TextureSlot, Texture)>;

/// A BSDF builder: the loader, the plugin, whether a `twosided` wraps it, the slots it fills.
type BsdfBuilder = for<'a, 'p> fn(
    &mut Loader<'a>,
    &'p Plugin<'a>,
    bool,
    &mut Slots,
) -> Result<Material, SceneError>;

/// Every BSDF type lt reads, with its builder and the TOML types that become it: a new material
/// is one entry here (plus its file in lt-core). The list of known types in errors and
/// docs/xml.md is this table's, and so are TOML's material types and their keys.
#[rustfmt::skip] // a table: one row a line
pub(super) const BSDFS: &[(&str, BsdfBuilder, &[TomlType])] = &[
    ("diffuse", diffuse, &[DIFFUSE]),
    ("dielectric", dielectric, &[same_name("dielectric", &[DielectricIor])]),
    ("roughdielectric", rough_or_thin_dielectric, &[same_name("roughdielectric", ROUGH_GLASS)]),
    ("thindielectric", rough_or_thin_dielectric, &[same_name("thindielectric", PANE)]),
    ("conductor", conductor, &[MIRROR, same_name("conductor", METAL)]),
    ("roughconductor", conductor, &[GLOSSY, same_name("roughconductor", ROUGH_METAL)]),
    ("plastic", plastic, &[same_name("plastic", PLASTIC)]),
    ("roughplastic", plastic, &[same_name("roughplastic", ROUGH_PLASTIC)]),
    ("principled", principled, &[same_name("principled", &[Principled { thin: false }])]),
    ("principledthin", principled, &[same_name("principledthin", &[Principled { thin: true }])]),
    ("twosided", twosided, &[]),
    ("normalmap", perturbed, &[]),
    ("bumpmap", perturbed, &[]),
    ("mask", mask, &[]),
    ("blendbsdf", blend, &[]),
    ("null", null, &[same_name("null", &[])]),
];

// TOML's keys of the types whose rows would not fit a line, and TOML's own types.
const ROUGH_GLASS: &[Keys] = &[DielectricIor, ANISOTROPIC, TEXTURED, Transmittance];
const PANE: &[Keys] = &[DielectricIor, TEXTURED, Transmittance];
const METAL: &[Keys] = &[ComplexIor, TEXTURED, Twosided];
const ROUGH_METAL: &[Keys] = &[ComplexIor, ANISOTROPIC, TEXTURED, Twosided];
const PLASTIC: &[Keys] = &[PLASTIC_IOR, BASE, TEXTURED, Nonlinear, Twosided];
const ROUGH_PLASTIC: &[Keys] = &[ROUGH_IOR, BASE, TEXTURED, Nonlinear, ISOTROPIC, Twosided];
const TEXTURED: Keys = Reflectance { textured: true };
const ANISOTROPIC: Keys = Microfacet { anisotropic: true };
const ISOTROPIC: Keys = Microfacet { anisotropic: false };
const PLASTIC_IOR: Keys = PlasticIor { rough: false };
const ROUGH_IOR: Keys = PlasticIor { rough: true };
const BASE: Keys = Albedo {
    to: "diffuse_reflectance",
    required: false,
};
/// lt's diffuse: reflects on both sides.
const DIFFUSE: TomlType = TomlType {
    name: "diffuse",
    fixed: &[],
    keys: &[Albedo {
        to: "reflectance",
        required: true,
    }],
    always_twosided: true,
};
/// lt's mirror: a two-sided conductor of material `none`.
const MIRROR: TomlType = TomlType {
    name: "mirror",
    fixed: &[("material", "none")],
    keys: &[Reflectance { textured: false }],
    always_twosided: true,
};
/// lt's glossy: a two-sided GGX conductor of material `none`, `roughness` its α.
const GLOSSY: TomlType = TomlType {
    name: "glossy",
    fixed: &[("material", "none"), ("distribution", "ggx")],
    keys: &[Roughness, Reflectance { textured: false }],
    always_twosided: true,
};

/// The BSDF type a TOML material `type` becomes, and how TOML spells it.
pub(crate) fn toml_material(name: &str) -> Option<(&'static str, &'static TomlType)> {
    BSDFS
        .iter()
        .find_map(|(xml, _, toml)| toml.iter().find(|t| t.name == name).map(|t| (*xml, t)))
}

/// TOML's material types, in the table's order.
pub(crate) fn toml_materials() -> impl Iterator<Item = &'static str> {
    BSDFS
        .iter()
        .flat_map(|(_, _, toml)| toml.iter().map(|t| t.name))
}

/// Mitsuba's `null`: a boundary between media that light passes straight through.
fn null<'a>(
    _: &mut Loader<'a>,
    p: &Plugin<'a>,
    in_twosided: bool,
    _: &mut Slots,
) -> Result<Material, SceneError> {
    if in_twosided {
        return Err(p.err(
            p.elem,
            "a `null` BSDF inside `twosided`: give it to the shape alone",
        ));
    }
    Ok(Material::Null(lt_core::bsdf::Null))
}

fn diffuse<'a>(
    l: &mut Loader<'a>,
    p: &Plugin<'a>,
    in_twosided: bool,
    slots: &mut Slots,
) -> Result<Material, SceneError> {
    let albedo = l
        .color_or_texture(p, "reflectance", TextureSlot::Reflectance, slots)?
        .unwrap_or(Color::splat(0.5));
    // Mitsuba's BSDFs reflect on the front only unless `twosided` wraps them.
    Ok(if in_twosided {
        Material::Diffuse(Diffuse { albedo })
    } else {
        Material::FrontDiffuse(FrontDiffuse { albedo })
    })
}

fn twosided<'a>(
    l: &mut Loader<'a>,
    p: &Plugin<'a>,
    in_twosided: bool,
    _: &mut Slots,
) -> Result<Material, SceneError> {
    let e = p.elem;
    if in_twosided {
        return Err(p.err(e, "a twosided BSDF inside a twosided BSDF"));
    }
    match p.nested(&["bsdf"])[..] {
        [one] => {
            let m = l.bsdf(one, true)?;
            if matches!(
                m,
                Material::Dielectric(_) | Material::RoughDielectric(_) | Material::ThinDielectric(_)
            ) {
                return Err(p.err(one, "twosided cannot wrap a dielectric (it transmits)"));
            }
            Ok(m)
        }
        [] => Err(p.err(e, "twosided needs a nested BSDF")),
        [_, second, ..] => Err(p.err(
            second,
            "twosided with different front and back BSDFs is not supported (lt's materials reflect alike on both sides)",
        )),
    }
}

fn dielectric<'a>(
    l: &mut Loader<'a>,
    p: &Plugin<'a>,
    _: bool,
    _: &mut Slots,
) -> Result<Material, SceneError> {
    for k in ["specular_reflectance", "specular_transmittance"] {
        if let Some(c) = p.color(k, ColorUse::Reflectance, l.opts, &mut l.report)? {
            if c != Color::ONE {
                return Err(p.err(p.elem, format!("`{k}` ≠ 1 on a dielectric is not supported (lt's glass has exact Fresnel only)")));
            }
        }
    }
    Ok(Material::Dielectric(Dielectric {
        ior: l.relative_ior(p)?,
    }))
}

fn rough_or_thin_dielectric<'a>(
    l: &mut Loader<'a>,
    p: &Plugin<'a>,
    _: bool,
    slots: &mut Slots,
) -> Result<Material, SceneError> {
    let ior = l.relative_ior(p)?;
    let specular_reflectance = l
        .color_or_texture(
            p,
            "specular_reflectance",
            TextureSlot::SpecularReflectance,
            slots,
        )?
        .unwrap_or(Color::ONE);
    let specular_transmittance = p
        .color(
            "specular_transmittance",
            ColorUse::Reflectance,
            l.opts,
            &mut l.report,
        )?
        .unwrap_or(Color::ONE);
    Ok(if p.kind == "thindielectric" {
        Material::ThinDielectric(ThinDielectric {
            ior,
            specular_reflectance,
            specular_transmittance,
        })
    } else {
        Material::RoughDielectric(RoughDielectric {
            distribution: l.microfacet(p, slots)?,
            ior,
            specular_reflectance,
            specular_transmittance,
        })
    })
}

fn conductor<'a>(
    l: &mut Loader<'a>,
    p: &Plugin<'a>,
    in_twosided: bool,
    slots: &mut Slots,
) -> Result<Material, SceneError> {
    let ior = l.complex_ior(p)?;
    let specular_reflectance = l
        .color_or_texture(
            p,
            "specular_reflectance",
            TextureSlot::SpecularReflectance,
            slots,
        )?
        .unwrap_or(Color::ONE);
    let one_sided = if p.kind == "conductor" {
        Material::Conductor(Conductor {
            ior,
            specular_reflectance,
        })
    } else {
        Material::RoughConductor(RoughConductor {
            distribution: l.microfacet(p, slots)?,
            ior,
            specular_reflectance,
        })
    };
    // Mitsuba's conductors reflect on the front only; `twosided` gives them a back.
    // Two-sided and with material "none" (Fresnel = 1), a smooth conductor is lt's
    // mirror and an isotropic GGX one sampling visible normals is lt's glossy: the
    // same BSDFs, kept as those so scenes written by `lt convert` read back exactly.
    let ideal = in_twosided && ior == PERFECT_MIRROR;
    Ok(match one_sided {
        Material::Conductor(_) if ideal => Material::Mirror(Mirror {
            reflectance: specular_reflectance,
        }),
        Material::RoughConductor(r)
            if ideal
                && r.distribution.kind == MicrofacetType::Ggx
                && !r.distribution.is_anisotropic()
                && !slots
                    .iter()
                    .any(|(s, _)| matches!(s, TextureSlot::AlphaU | TextureSlot::AlphaV))
                && r.distribution.sample_visible =>
        {
            Material::Glossy(Glossy {
                reflectance: specular_reflectance,
                roughness: r.distribution.alpha_u,
            })
        }
        one_sided => two_sided_if(in_twosided, one_sided),
    })
}

/// `m` given a back side when a `twosided` wraps it.
fn two_sided_if(in_twosided: bool, m: Material) -> Material {
    if in_twosided {
        Material::TwoSided(TwoSided { inner: Box::new(m) })
    } else {
        m
    }
}

fn plastic<'a>(
    l: &mut Loader<'a>,
    p: &Plugin<'a>,
    in_twosided: bool,
    slots: &mut Slots,
) -> Result<Material, SceneError> {
    let one_sided = l.plastic(p, slots)?;
    Ok(two_sided_if(in_twosided, one_sided))
}

fn principled<'a>(
    l: &mut Loader<'a>,
    p: &Plugin<'a>,
    in_twosided: bool,
    slots: &mut Slots,
) -> Result<Material, SceneError> {
    let m = l.principled(p, slots)?;
    if in_twosided {
        return Err(p.err(
            p.elem,
            format!(
                "twosided cannot wrap {} (it transmits, and its back side is its own)",
                p.kind
            ),
        ));
    }
    Ok(m)
}

/// The one nested BSDF of a wrapper (`normalmap`, `bumpmap`, `mask`).
fn one_inner<'a>(
    l: &mut Loader<'a>,
    p: &Plugin<'a>,
    in_twosided: bool,
) -> Result<Material, SceneError> {
    match p.nested(&["bsdf"])[..] {
        [one] => l.bsdf(one, in_twosided),
        [] => Err(p.err(p.elem, format!("{} needs a nested BSDF", p.kind))),
        [_, second, ..] => Err(p.err(
            second,
            format!("{} takes one nested BSDF, this is a second one", p.kind),
        )),
    }
}

fn perturbed<'a>(
    l: &mut Loader<'a>,
    p: &Plugin<'a>,
    in_twosided: bool,
    _: &mut Slots,
) -> Result<Material, SceneError> {
    let e = p.elem;
    let inner = one_inner(l, p, in_twosided)?;
    let source = if p.kind == "normalmap" {
        let Some(t) = p.texture("normalmap") else {
            return Err(p.err(e, "normalmap needs a texture named `normalmap`"));
        };
        NormalSource::NormalMap(l.texture(t)?)
    } else {
        let height = match p.any_textures()[..] {
            [one] => l.texture(one)?,
            [] => return Err(p.err(e, "bumpmap needs a nested height texture")),
            [_, second, ..] => {
                return Err(p.err(second, "bumpmap takes one texture, this is a second one"))
            }
        };
        let scale = p.float("scale")?.unwrap_or(1.0) as f32;
        if !scale.is_finite() {
            return Err(p.err(
                e,
                format!("bumpmap `scale` = {scale} is not a finite number"),
            ));
        }
        NormalSource::BumpMap { height, scale }
    };
    Ok(Material::Perturbed(Box::new(Perturbed {
        source,
        inner,
        flip_invalid_normals: p.boolean("flip_invalid_normals")?.unwrap_or(true),
        shadowing: p.boolean("use_shadowing_function")?.unwrap_or(true),
    })))
}

/// A texture or colour parameter in [0, 1] (`opacity`, `weight`), 0.5 when absent.
fn unit_texture<'a>(l: &mut Loader<'a>, p: &Plugin<'a>, name: &str) -> Result<Texture, SceneError> {
    Ok(match p.texture(name) {
        Some(t) => l.texture(t)?,
        None => Texture::Constant(
            p.color(name, ColorUse::Reflectance, l.opts, &mut l.report)?
                .unwrap_or(Color::splat(0.5)),
        ),
    })
}

fn mask<'a>(
    l: &mut Loader<'a>,
    p: &Plugin<'a>,
    in_twosided: bool,
    _: &mut Slots,
) -> Result<Material, SceneError> {
    let inner = one_inner(l, p, in_twosided)?;
    let opacity = unit_texture(l, p, "opacity")?;
    Ok(Material::Mask(Box::new(Mask { opacity, inner })))
}

fn blend<'a>(
    l: &mut Loader<'a>,
    p: &Plugin<'a>,
    in_twosided: bool,
    _: &mut Slots,
) -> Result<Material, SceneError> {
    let e = p.elem;
    let (first, second) = match p.nested(&["bsdf"])[..] {
        [a, b] => (l.bsdf(a, in_twosided)?, l.bsdf(b, in_twosided)?),
        [_, _, third, ..] => {
            return Err(p.err(
                third,
                "blendbsdf takes two nested BSDFs, this is a third one",
            ))
        }
        _ => return Err(p.err(e, "blendbsdf needs two nested BSDFs")),
    };
    for m in [&first, &second] {
        if m.refraction_ior().is_some() || m.perturbation().is_some() {
            return Err(p.err(
                e,
                "blendbsdf of a refracting or normal/bump-mapped BSDF is not supported (its η² scaling and shading normal belong to one material)",
            ));
        }
    }
    let weight = unit_texture(l, p, "weight")?;
    Ok(Material::Blend(Box::new(Blend {
        weight,
        first,
        second,
    })))
}

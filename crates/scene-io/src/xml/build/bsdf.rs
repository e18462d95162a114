//! `<bsdf>`: every BSDF type lt reads, each one entry of `BSDFS`.

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

    pub(super) fn bsdf(&mut self, e: &'a Elem, in_twosided: bool) -> Result<Material, SceneError> {
        let p = self.plugin(e)?;
        let opts = self.opts;
        // Parameters given as textures: the material is built with their defaults and the
        // textures set them at each shading point.
        let mut slots: Vec<(TextureSlot, Texture)> = Vec::new();
        let m = match p.kind {
            "diffuse" => {
                let albedo = self
                    .color_or_texture(&p, "reflectance", TextureSlot::Reflectance, &mut slots)?
                    .unwrap_or(Color::splat(0.5));
                // Mitsuba's BSDFs reflect on the front only unless `twosided` wraps them.
                if in_twosided {
                    Material::Diffuse(Diffuse { albedo })
                } else {
                    Material::FrontDiffuse(FrontDiffuse { albedo })
                }
            }
            "twosided" => {
                if in_twosided {
                    return Err(p.err(e, "a twosided BSDF inside a twosided BSDF"));
                }
                let inner = p.nested(&["bsdf"]);
                match inner[..] {
                    [one] => {
                        let m = self.bsdf(one, true)?;
                        if matches!(m, Material::Dielectric(_) | Material::RoughDielectric(_) | Material::ThinDielectric(_)) {
                            return Err(p.err(one, "twosided cannot wrap a dielectric (it transmits)"));
                        }
                        m
                    }
                    [] => return Err(p.err(e, "twosided needs a nested BSDF")),
                    [_, second, ..] => {
                        return Err(p.err(
                            second,
                            "twosided with different front and back BSDFs is not supported (lt's materials reflect alike on both sides)",
                        ))
                    }
                }
            }
            "dielectric" => {
                for k in ["specular_reflectance", "specular_transmittance"] {
                    if let Some(c) = p.color(k, ColorUse::Reflectance, opts, &mut self.report)? {
                        if c != Color::ONE {
                            return Err(p.err(e, format!("`{k}` ≠ 1 on a dielectric is not supported (lt's glass has exact Fresnel only)")));
                        }
                    }
                }
                Material::Dielectric(Dielectric {
                    ior: self.relative_ior(&p)?,
                })
            }
            "roughdielectric" | "thindielectric" => {
                let ior = self.relative_ior(&p)?;
                let specular_reflectance = self
                    .color_or_texture(&p, "specular_reflectance", TextureSlot::SpecularReflectance, &mut slots)?
                    .unwrap_or(Color::ONE);
                let specular_transmittance = p
                    .color("specular_transmittance", ColorUse::Reflectance, opts, &mut self.report)?
                    .unwrap_or(Color::ONE);
                if p.kind == "thindielectric" {
                    Material::ThinDielectric(ThinDielectric {
                        ior,
                        specular_reflectance,
                        specular_transmittance,
                    })
                } else {
                    Material::RoughDielectric(RoughDielectric {
                        distribution: self.microfacet(&p, &mut slots)?,
                        ior,
                        specular_reflectance,
                        specular_transmittance,
                    })
                }
            }
            "conductor" | "roughconductor" => {
                let ior = self.complex_ior(&p)?;
                let specular_reflectance = self
                    .color_or_texture(&p, "specular_reflectance", TextureSlot::SpecularReflectance, &mut slots)?
                    .unwrap_or(Color::ONE);
                let one_sided = if p.kind == "conductor" {
                    Material::Conductor(Conductor {
                        ior,
                        specular_reflectance,
                    })
                } else {
                    Material::RoughConductor(RoughConductor {
                        distribution: self.microfacet(&p, &mut slots)?,
                        ior,
                        specular_reflectance,
                    })
                };
                // Mitsuba's conductors reflect on the front only; `twosided` gives them a back.
                // Two-sided and with material "none" (Fresnel = 1), a smooth conductor is lt's
                // mirror and an isotropic GGX one sampling visible normals is lt's glossy: the
                // same BSDFs, kept as those so scenes written by `lt convert` read back exactly.
                let ideal = in_twosided && ior == PERFECT_MIRROR;
                match one_sided {
                    Material::Conductor(_) if ideal => Material::Mirror(Mirror {
                        reflectance: specular_reflectance,
                    }),
                    Material::RoughConductor(r)
                        if ideal
                            && r.distribution.kind == MicrofacetType::Ggx
                            && !r.distribution.is_anisotropic()
                            && !slots.iter().any(|(s, _)| {
                                matches!(s, TextureSlot::AlphaU | TextureSlot::AlphaV)
                            })
                            && r.distribution.sample_visible =>
                    {
                        Material::Glossy(Glossy {
                            reflectance: specular_reflectance,
                            roughness: r.distribution.alpha_u,
                        })
                    }
                    one_sided if in_twosided => Material::TwoSided(TwoSided {
                        inner: Box::new(one_sided),
                    }),
                    one_sided => one_sided,
                }
            }
            "plastic" | "roughplastic" => {
                let one_sided = self.plastic(&p, &mut slots)?;
                if in_twosided {
                    Material::TwoSided(TwoSided {
                        inner: Box::new(one_sided),
                    })
                } else {
                    one_sided
                }
            }
            "principled" | "principledthin" => {
                let m = self.principled(&p, &mut slots)?;
                if in_twosided {
                    return Err(p.err(e, format!("twosided cannot wrap {} (it transmits, and its back side is its own)", p.kind)));
                }
                m
            }
            "normalmap" | "bumpmap" => {
                let inner = match p.nested(&["bsdf"])[..] {
                    [one] => self.bsdf(one, in_twosided)?,
                    [] => return Err(p.err(e, format!("{} needs a nested BSDF", p.kind))),
                    [_, second, ..] => {
                        return Err(p.err(second, format!("{} takes one nested BSDF, this is a second one", p.kind)))
                    }
                };
                let source = if p.kind == "normalmap" {
                    let Some(t) = p.texture("normalmap") else {
                        return Err(p.err(e, "normalmap needs a texture named `normalmap`"));
                    };
                    NormalSource::NormalMap(self.texture(t)?)
                } else {
                    let height = match p.any_textures()[..] {
                        [one] => self.texture(one)?,
                        [] => return Err(p.err(e, "bumpmap needs a nested height texture")),
                        [_, second, ..] => {
                            return Err(p.err(second, "bumpmap takes one texture, this is a second one"))
                        }
                    };
                    let scale = p.float("scale")?.unwrap_or(1.0) as f32;
                    if !scale.is_finite() {
                        return Err(p.err(e, format!("bumpmap `scale` = {scale} is not a finite number")));
                    }
                    NormalSource::BumpMap { height, scale }
                };
                Material::Perturbed(Box::new(Perturbed {
                    source,
                    inner,
                    flip_invalid_normals: p.boolean("flip_invalid_normals")?.unwrap_or(true),
                    shadowing: p.boolean("use_shadowing_function")?.unwrap_or(true),
                }))
            }
            "mask" => {
                let inner = match p.nested(&["bsdf"])[..] {
                    [one] => self.bsdf(one, in_twosided)?,
                    [] => return Err(p.err(e, "mask needs a nested BSDF")),
                    [_, second, ..] => {
                        return Err(p.err(second, "mask takes one nested BSDF, this is a second one"))
                    }
                };
                let opacity = match p.texture("opacity") {
                    Some(t) => self.texture(t)?,
                    None => Texture::Constant(
                        p.color("opacity", ColorUse::Reflectance, opts, &mut self.report)?
                            .unwrap_or(Color::splat(0.5)),
                    ),
                };
                Material::Mask(Box::new(Mask { opacity, inner }))
            }
            "blendbsdf" => {
                let (first, second) = match p.nested(&["bsdf"])[..] {
                    [a, b] => (self.bsdf(a, in_twosided)?, self.bsdf(b, in_twosided)?),
                    [_, _, third, ..] => {
                        return Err(p.err(third, "blendbsdf takes two nested BSDFs, this is a third one"))
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
                let weight = match p.texture("weight") {
                    Some(t) => self.texture(t)?,
                    None => Texture::Constant(
                        p.color("weight", ColorUse::Reflectance, opts, &mut self.report)?
                            .unwrap_or(Color::splat(0.5)),
                    ),
                };
                Material::Blend(Box::new(Blend { weight, first, second }))
            }
            other => {
                return Err(p.err(
                    e,
                    format!("BSDF `{other}` is not supported (lt reads diffuse, dielectric, roughdielectric, thindielectric, conductor, roughconductor, plastic, roughplastic, principled, principledthin, twosided, normalmap, bumpmap, mask and blendbsdf)"),
                ))
            }
        };
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

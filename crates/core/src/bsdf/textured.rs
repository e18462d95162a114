//! A material some of whose parameters vary over the surface (Mitsuba's nested `<texture>`s):
//! resolved at the point's texture coordinates into the plain material, which is then sampled or
//! evaluated as usual. Untextured materials never come here, so they keep their bits and speed.

use super::microfacet::Microfacet;
use super::principled_common::PrincipledParam;
use super::two_sided::FrontFacing;
use super::{LocalBsdf, Material};
use crate::math::Color;
use crate::texture::{TexPoint, Texture};

/// Which parameter a texture drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureSlot {
    /// Diffuse albedo (Mitsuba's `reflectance` of `diffuse`, `diffuse_reflectance` of plastics).
    Reflectance,
    /// The colour factor of mirrors, conductors and plastics' coatings (`specular_reflectance`).
    SpecularReflectance,
    /// Microfacet roughness α (`alpha`), read as a scalar (`Texture::eval_scalar`).
    Alpha,
    /// Roughness along the shading frame's x axis alone (`alpha_u`; x follows ∂p/∂u).
    AlphaU,
    /// Roughness along y alone (`alpha_v`).
    AlphaV,
    /// A parameter of `principled` or `principledthin`.
    Principled(PrincipledParam),
}

impl TextureSlot {
    /// A roughness, not a reflectance (no upper bound of 1).
    pub fn is_roughness(self) -> bool {
        matches!(
            self,
            TextureSlot::Alpha | TextureSlot::AlphaU | TextureSlot::AlphaV
        )
    }

    /// A scalar parameter, read as Mitsuba's `eval_1` reads it (`Texture::eval_scalar`) and not
    /// bounded by 1 as a reflectance is: the roughnesses and every principled parameter but
    /// `base_color`.
    pub fn is_scalar(self) -> bool {
        self.is_roughness()
            || matches!(self, TextureSlot::Principled(p) if p != PrincipledParam::BaseColor)
    }
}

#[derive(Clone, Debug)]
pub struct Textured {
    /// The material with its untextured parameters (used where no point is known: `is_delta`).
    pub base: Material,
    pub slots: Vec<(TextureSlot, Texture)>,
}

impl Textured {
    /// True when a texture drives one roughness axis alone: the frame must then follow ∂p/∂u.
    pub fn is_anisotropic(&self) -> bool {
        self.slots.iter().any(|(s, _)| {
            matches!(
                s,
                TextureSlot::AlphaU
                    | TextureSlot::AlphaV
                    | TextureSlot::Principled(PrincipledParam::Anisotropic)
            )
        })
    }

    /// Calls `f` with the plain local BSDF at texture coordinates `uv`. The resolved material
    /// lives on the stack: a two-sided base is resolved as its inner material (no `Box` cloned
    /// per shading query) and seen from both sides through `FrontFacing`.
    #[inline]
    pub(super) fn with_local<R>(&self, uv: TexPoint, f: impl FnOnce(&dyn LocalBsdf) -> R) -> R {
        match &self.base {
            Material::TwoSided(t) => {
                let inner = self.resolved((*t.inner).clone(), uv);
                f(&FrontFacing(inner.local()))
            }
            base => f(self.resolved(base.clone(), uv).local()),
        }
    }

    /// `m` with every textured parameter set from its texture at `uv`.
    fn resolved(&self, mut m: Material, uv: TexPoint) -> Material {
        for (slot, texture) in &self.slots {
            // A roughness (any scalar parameter) is read with Mitsuba's `eval_1`.
            let value = if slot.is_scalar() {
                Color::splat(texture.eval_scalar(uv))
            } else {
                texture.eval(uv)
            };
            set_parameter(&mut m, *slot, value);
        }
        m
    }
}

/// Sets one parameter of `m`; false when `m` has no such parameter (the loader asks first).
pub fn set_parameter(m: &mut Material, slot: TextureSlot, value: Color) -> bool {
    use TextureSlot::*;
    match (m, slot) {
        (Material::Diffuse(d), Reflectance) => d.albedo = value,
        (Material::FrontDiffuse(d), Reflectance) => d.albedo = value,
        (Material::Mirror(x), SpecularReflectance) => x.reflectance = value,
        (Material::Glossy(g), SpecularReflectance) => g.reflectance = value,
        (Material::Glossy(g), Alpha) => g.roughness = value.x.max(super::microfacet::MIN_ALPHA),
        (Material::Conductor(c), SpecularReflectance) => c.specular_reflectance = value,
        (Material::RoughConductor(r), SpecularReflectance) => r.specular_reflectance = value,
        (Material::RoughConductor(r), Alpha | AlphaU | AlphaV) => {
            r.distribution = with_alpha(r.distribution, slot, value.x)
        }
        (Material::Plastic(p), Reflectance) => p.diffuse_reflectance = value,
        (Material::Plastic(p), SpecularReflectance) => p.specular_reflectance = value,
        (Material::RoughPlastic(p), Reflectance) => p.diffuse_reflectance = value,
        (Material::RoughPlastic(p), SpecularReflectance) => p.specular_reflectance = value,
        (Material::RoughDielectric(r), SpecularReflectance) => r.specular_reflectance = value,
        (Material::RoughDielectric(r), Alpha | AlphaU | AlphaV) => {
            r.distribution = with_alpha(r.distribution, slot, value.x)
        }
        (Material::ThinDielectric(t), SpecularReflectance) => t.specular_reflectance = value,
        (Material::Principled(p), Principled(param)) => return p.set(param, value),
        (Material::PrincipledThin(p), Principled(param)) => return p.set(param, value),
        (Material::TwoSided(t), slot) => return set_parameter(&mut t.inner, slot, value),
        _ => return false,
    }
    true
}

/// `d` with the roughness of `slot` (both axes, x or y) set to `a`.
fn with_alpha(d: Microfacet, slot: TextureSlot, a: f32) -> Microfacet {
    let (au, av) = match slot {
        TextureSlot::AlphaU => (a, d.alpha_v),
        TextureSlot::AlphaV => (d.alpha_u, a),
        _ => (a, a),
    };
    Microfacet::new(d.kind, au, av, d.sample_visible)
}

/// The sampling tests' textured materials (`test_registry`).
#[cfg(feature = "test-support")]
impl super::test_registry::Fixtures for Textured {
    fn fixtures() -> Vec<super::test_registry::Fixture> {
        use super::test_registry::*;
        let textured = |base| {
            Material::Textured(Box::new(Textured {
                base,
                slots: vec![(
                    super::TextureSlot::Reflectance,
                    Texture::Constant(TEXTURE_COLOR),
                )],
            }))
        };
        vec![
            (
                "textured-diffuse",
                textured(Material::Diffuse(super::Diffuse { albedo: COLOR })),
            ),
            ("textured-plastic", textured(plastic(COLOR, false))),
        ]
    }
}

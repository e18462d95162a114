//! The test fixture: representative materials the sampling tests sweep. Each material's file
//! gives its own (`impl Fixtures`), and `bsdf/mod.rs`'s list of variants gathers them, so a new
//! material joins the sampling tests with its file; this one holds the parts several files share.
//! Built only with the `test-support` feature, which the crates' dev-dependencies enable; the
//! library's public API does not carry it.

use super::microfacet::{Microfacet, MicrofacetType};
use super::*;

/// A named material the sampling tests sweep.
pub type Fixture = (&'static str, Material);

/// The sampling-test materials of one variant's type: every one a material can be in (GGX
/// roughness from near-specular to very rough, IORs seen from both sides of the interface, each
/// lobe switched on); empty only where the sampling tests cannot reach it, with the reason.
pub trait Fixtures {
    fn fixtures() -> Vec<Fixture>;
}

/// Representative materials that the sampling tests sweep (name, material): every variant's
/// fixtures, in the order `bsdf/mod.rs` lists the variants.
pub fn test_registry() -> Vec<Fixture> {
    every_fixture()
}

/// The colour most fixtures reflect with.
pub(super) const COLOR: Color = Color::new(0.9, 0.6, 0.3);
/// A texture's constant colour, different from `COLOR`.
pub(super) const TEXTURE_COLOR: Color = Color::new(0.2, 0.7, 0.4);
/// A conductor's colour factor.
pub(super) const CONDUCTOR_TINT: Color = Color::new(1.0, 0.8, 0.9);

pub(super) fn glossy(roughness: f32) -> Material {
    Material::Glossy(Glossy {
        reflectance: COLOR,
        roughness,
    })
}

pub(super) fn gold() -> fresnel::ComplexIor {
    conductor_ior::named_conductor("Au").expect("Mitsuba names gold Au")
}

pub(super) fn rough_gold(
    kind: MicrofacetType,
    alpha_u: f32,
    alpha_v: f32,
    sample_visible: bool,
) -> Material {
    Material::RoughConductor(RoughConductor {
        distribution: Microfacet::new(kind, alpha_u, alpha_v, sample_visible),
        ior: gold(),
        specular_reflectance: CONDUCTOR_TINT,
    })
}

/// Polypropylene in air, Mitsuba's default plastic.
pub(super) fn polypropylene() -> f32 {
    plastic::POLYPROPYLENE_IOR / plastic::AIR_IOR
}

pub(super) fn plastic(diffuse: Color, nonlinear: bool) -> Material {
    Material::Plastic(Plastic::new(
        polypropylene(),
        diffuse,
        Color::new(1.0, 0.9, 0.8),
        nonlinear,
    ))
}

pub(super) fn rough_plastic(
    kind: MicrofacetType,
    alpha: f32,
    sample_visible: bool,
    nonlinear: bool,
) -> Material {
    Material::RoughPlastic(RoughPlastic::new(
        Microfacet::new(kind, alpha, alpha, sample_visible),
        polypropylene(),
        COLOR,
        Color::ONE,
        nonlinear,
    ))
}

/// A constant texture of `value` in every channel.
pub(super) fn constant(value: f32) -> crate::texture::Texture {
    crate::texture::Texture::Constant(Color::splat(value))
}

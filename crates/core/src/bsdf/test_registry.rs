//! The test fixture: representative materials the sampling tests sweep. Built only with the
//! `test-support` feature, which the crates' dev-dependencies enable; the library's public API
//! does not carry it.

use super::*;

/// Representative materials that the sampling tests sweep (name, material): every kind, GGX
/// roughness from near-specular to very rough, and IORs seen from both sides of the interface.
pub fn test_registry() -> Vec<(&'static str, Material)> {
    let c = Color::new(0.9, 0.6, 0.3);
    let glossy = |roughness| {
        Material::Glossy(Glossy {
            reflectance: c,
            roughness,
        })
    };
    let glass = |ior| Material::Dielectric(Dielectric { ior });
    let gold = conductor_ior::named_conductor("Au").expect("Mitsuba names gold Au");
    let rough_gold = |kind, alpha_u, alpha_v, sample_visible| {
        Material::RoughConductor(RoughConductor {
            distribution: microfacet::Microfacet::new(kind, alpha_u, alpha_v, sample_visible),
            ior: gold,
            specular_reflectance: Color::new(1.0, 0.8, 0.9),
        })
    };
    let rough_glass = |kind, alpha_u, alpha_v, sample_visible, ior, tinted: bool| {
        let (r, t) = if tinted {
            (Color::new(0.9, 1.0, 0.7), Color::new(1.0, 0.6, 0.8))
        } else {
            (Color::ONE, Color::ONE)
        };
        Material::RoughDielectric(RoughDielectric {
            distribution: microfacet::Microfacet::new(kind, alpha_u, alpha_v, sample_visible),
            ior,
            specular_reflectance: r,
            specular_transmittance: t,
        })
    };
    let pane = |ior, specular_reflectance, specular_transmittance| {
        Material::ThinDielectric(ThinDielectric {
            ior,
            specular_reflectance,
            specular_transmittance,
        })
    };
    use microfacet::MicrofacetType::{Beckmann, Ggx};
    let polypropylene = plastic::POLYPROPYLENE_IOR / plastic::AIR_IOR;
    let plastic = |diffuse, nonlinear| {
        Material::Plastic(Plastic::new(
            polypropylene,
            diffuse,
            Color::new(1.0, 0.9, 0.8),
            nonlinear,
        ))
    };
    let rough_plastic = |kind, alpha, sample_visible, nonlinear| {
        Material::RoughPlastic(RoughPlastic::new(
            microfacet::Microfacet::new(kind, alpha, alpha, sample_visible),
            polypropylene,
            c,
            Color::ONE,
            nonlinear,
        ))
    };
    let principled = |set: fn(&mut Principled)| {
        let mut p = Principled {
            base_color: Color::new(0.5, 0.35, 0.2),
            ..Principled::mitsuba_default()
        };
        set(&mut p);
        Material::Principled(p)
    };
    let thin = |set: fn(&mut PrincipledThin)| {
        let mut p = PrincipledThin {
            base_color: Color::new(0.5, 0.35, 0.2),
            ..PrincipledThin::mitsuba_default()
        };
        set(&mut p);
        Material::PrincipledThin(p)
    };
    vec![
        ("diffuse", Material::Diffuse(Diffuse { albedo: c })),
        (
            "diffuse-front",
            Material::FrontDiffuse(FrontDiffuse { albedo: c }),
        ),
        ("mirror", Material::Mirror(Mirror { reflectance: c })),
        ("glossy-0.05", glossy(0.05)),
        ("glossy-0.2", glossy(0.2)),
        ("glossy-0.5", glossy(0.5)),
        ("glossy-1.0", glossy(1.0)),
        ("glass-1.5", glass(1.5)),
        ("glass-1/1.5", glass(1.0 / 1.5)),
        ("glass-2.4", glass(2.4)),
        (
            "conductor-Au",
            Material::Conductor(Conductor {
                ior: gold,
                specular_reflectance: Color::new(1.0, 0.8, 0.9),
            }),
        ),
        (
            "roughconductor-beckmann-0.05",
            rough_gold(Beckmann, 0.05, 0.05, true),
        ),
        (
            "roughconductor-beckmann-0.3",
            rough_gold(Beckmann, 0.3, 0.3, true),
        ),
        (
            "roughconductor-beckmann-0.1x0.4",
            rough_gold(Beckmann, 0.1, 0.4, true),
        ),
        (
            "roughconductor-beckmann-0.3-all",
            rough_gold(Beckmann, 0.3, 0.3, false),
        ),
        ("roughconductor-ggx-0.05", rough_gold(Ggx, 0.05, 0.05, true)),
        ("roughconductor-ggx-0.3", rough_gold(Ggx, 0.3, 0.3, true)),
        (
            "roughconductor-ggx-0.4x0.1",
            rough_gold(Ggx, 0.4, 0.1, true),
        ),
        (
            "roughconductor-ggx-0.2x0.5-all",
            rough_gold(Ggx, 0.2, 0.5, false),
        ),
        (
            "roughdielectric-beckmann-0.1-1.5",
            rough_glass(Beckmann, 0.1, 0.1, true, 1.5, false),
        ),
        (
            "roughdielectric-beckmann-0.3-1/1.5",
            rough_glass(Beckmann, 0.3, 0.3, true, 1.0 / 1.5, true),
        ),
        (
            "roughdielectric-beckmann-0.4x0.1-all-1.33",
            rough_glass(Beckmann, 0.4, 0.1, false, 1.33, false),
        ),
        (
            "roughdielectric-ggx-0.05-1.5",
            rough_glass(Ggx, 0.05, 0.05, true, 1.5, false),
        ),
        (
            "roughdielectric-ggx-0.3-2.4",
            rough_glass(Ggx, 0.3, 0.3, true, 2.4, true),
        ),
        (
            "roughdielectric-ggx-0.2x0.5-1.5",
            rough_glass(Ggx, 0.2, 0.5, true, 1.5, false),
        ),
        (
            "roughdielectric-ggx-0.6-all-1/1.33",
            rough_glass(Ggx, 0.6, 0.6, false, 1.0 / 1.33, false),
        ),
        ("thindielectric-1.5", pane(1.5, Color::ONE, Color::ONE)),
        (
            "thindielectric-1.33-tinted",
            pane(1.33, Color::new(0.9, 1.0, 0.7), Color::new(1.0, 0.6, 0.8)),
        ),
        (
            "textured-diffuse",
            Material::Textured(Box::new(Textured {
                base: Material::Diffuse(Diffuse { albedo: c }),
                slots: vec![(
                    TextureSlot::Reflectance,
                    crate::texture::Texture::Constant(Color::new(0.2, 0.7, 0.4)),
                )],
            })),
        ),
        ("plastic", plastic(c, false)),
        ("plastic-nonlinear", plastic(c, true)),
        (
            "plastic-ior-2.4-dark",
            Material::Plastic(Plastic::new(
                2.4,
                Color::new(0.05, 0.1, 0.02),
                Color::ONE,
                false,
            )),
        ),
        (
            "roughplastic-beckmann-0.05",
            rough_plastic(Beckmann, 0.05, true, false),
        ),
        (
            "roughplastic-beckmann-0.3-nonlinear",
            rough_plastic(Beckmann, 0.3, true, true),
        ),
        (
            "roughplastic-beckmann-0.3-all",
            rough_plastic(Beckmann, 0.3, false, false),
        ),
        (
            "roughplastic-ggx-0.1-nonlinear",
            rough_plastic(Ggx, 0.1, true, true),
        ),
        ("roughplastic-ggx-0.5", rough_plastic(Ggx, 0.5, true, false)),
        (
            "roughplastic-ggx-0.2-all",
            rough_plastic(Ggx, 0.2, false, false),
        ),
        (
            "textured-plastic",
            Material::Textured(Box::new(Textured {
                base: plastic(c, false),
                slots: vec![(
                    TextureSlot::Reflectance,
                    crate::texture::Texture::Constant(Color::new(0.2, 0.7, 0.4)),
                )],
            })),
        ),
        (
            "twosided-roughplastic-ggx-0.3",
            Material::TwoSided(TwoSided {
                inner: Box::new(rough_plastic(Ggx, 0.3, true, false)),
            }),
        ),
        (
            "mask-0.4-diffuse",
            Material::Mask(Box::new(Mask {
                opacity: crate::texture::Texture::Constant(Color::splat(0.4)),
                inner: Material::Diffuse(Diffuse { albedo: c }),
            })),
        ),
        (
            "mask-0.7-twosided-plastic",
            Material::Mask(Box::new(Mask {
                opacity: crate::texture::Texture::Constant(Color::splat(0.7)),
                inner: Material::TwoSided(TwoSided {
                    inner: Box::new(plastic(c, false)),
                }),
            })),
        ),
        (
            "blend-0.3-diffuse-roughconductor",
            Material::Blend(Box::new(Blend {
                weight: crate::texture::Texture::Constant(Color::splat(0.3)),
                first: Material::Diffuse(Diffuse { albedo: c }),
                second: rough_gold(Ggx, 0.2, 0.2, true),
            })),
        ),
        (
            "blend-0.6-plastic-glossy",
            Material::Blend(Box::new(Blend {
                weight: crate::texture::Texture::Constant(Color::splat(0.6)),
                first: plastic(c, false),
                second: glossy(0.3),
            })),
        ),
        (
            "twosided-roughconductor-ggx-0.3",
            Material::TwoSided(TwoSided {
                inner: Box::new(rough_gold(Ggx, 0.3, 0.3, true)),
            }),
        ),
        // Base colours stay ≤ 0.5: Mitsuba's principled adds its specular, sheen and clearcoat
        // lobes on top of a diffuse whose retro-reflection alone can exceed 1 (Burley 2012,
        // §5.3), so a bright one would break the furnace test by design, not by a bug.
        ("principled-diffuse", principled(|_| {})),
        (
            "principled-metallic-anisotropic",
            principled(|p| {
                p.metallic = 0.7;
                p.anisotropic = 0.6;
                p.roughness = 0.3;
                p.spec_tint = 0.5;
            }),
        ),
        (
            "principled-clearcoat-sheen-flatness",
            principled(|p| {
                p.clearcoat = 0.8;
                p.clearcoat_gloss = 0.5;
                p.sheen = 0.6;
                p.sheen_tint = 0.5;
                p.flatness = 0.4;
                p.roughness = 0.6;
            }),
        ),
        (
            "principled-spec-trans-0.6",
            principled(|p| {
                p.spec_trans = 0.6;
                p.has_spec_trans = true;
                p.roughness = 0.3;
                p.clearcoat = 0.3;
                p.sheen = 0.3;
                p.eta = Principled::eta_from_specular(0.4);
            }),
        ),
        (
            "principled-glass-anisotropic",
            principled(|p| {
                p.spec_trans = 1.0;
                p.has_spec_trans = true;
                p.roughness = 0.4;
                p.anisotropic = 0.5;
                p.eta = 1.33;
            }),
        ),
        (
            "principledthin-diff-trans",
            thin(|p| {
                p.diff_trans = 1.2;
                p.sheen = 0.5;
                p.roughness = 0.4;
            }),
        ),
        // spec_trans stays small: Mitsuba's side test cuts the transmission lobe's pdf along a
        // curve no bin edge follows, and a large jump there keeps the χ² test's cubature from
        // converging at grazing incidence (it did at spec_trans 0.5).
        (
            "principledthin-spec-trans-anisotropic",
            thin(|p| {
                p.spec_trans = 0.25;
                p.diff_trans = 0.6;
                p.eta = 1.33;
                p.anisotropic = 0.5;
                p.spec_tint = 0.4;
                p.roughness = 0.6;
            }),
        ),
    ]
}

//! The parameters several BSDFs share (IORs, microfacet distributions, complex IORs) and the
//! two families with many (plastics, principled).

use super::Loader;
use crate::principled_keys::{principled_eta, scalar_in_range, thin_eta};
use crate::xml::props::{ColorUse, Plugin};
use crate::SceneError;
use lt_core::bsdf::conductor_ior::{conductor_names, named_conductor};
use lt_core::bsdf::fresnel::ComplexIor;
use lt_core::bsdf::microfacet::{Microfacet, MicrofacetType};
use lt_core::bsdf::plastic::{channel_mean, specular_sampling_weight};
use lt_core::bsdf::Material;
use lt_core::bsdf::TextureSlot;
use lt_core::bsdf::{Plastic, Principled, PrincipledParam, PrincipledThin, RoughPlastic};
use lt_core::math::Color;
use lt_core::texture::Texture;

/// GGX α below this is numerically a mirror (the TOML loader's bound).
const MIN_ROUGHNESS: f64 = 1e-4;

/// IORs Mitsuba knows by name (its `int_ior`/`ext_ior` strings).
const NAMED_IORS: [(&str, f64); 23] = [
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.333),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.575),
    ("diamond", 2.419),
];

impl<'a> Loader<'a> {
    /// Mitsuba's `plastic` and `roughplastic` (one-sided): `int_ior` (polypropylene), `ext_ior`
    /// (air), `diffuse_reflectance` (0.5) and `specular_reflectance` (1), either a texture,
    /// `nonlinear` (false); `roughplastic` adds the microfacet parameters (isotropic, α a
    /// number). The lobe-sampling weight reads a textured reflectance's mean, as Mitsuba does.
    pub(super) fn plastic(
        &mut self,
        p: &Plugin<'a>,
        slots: &mut Vec<(TextureSlot, Texture)>,
    ) -> Result<Material, SceneError> {
        let e = p.elem;
        let int = self.ior(p, "int_ior", 1.49)?;
        let ext = self.ior(p, "ext_ior", 1.000277)?;
        let eta = (int / ext) as f32;
        if !(eta.is_finite() && eta > 0.0) {
            return Err(p.err(
                e,
                format!("the relative IOR {int}/{ext} is not a positive number"),
            ));
        }
        if p.kind == "roughplastic" && int == ext {
            return Err(p.err(e, "roughplastic needs `int_ior` ≠ `ext_ior` (as Mitsuba)"));
        }
        let mut reflectance = |this: &mut Self, name, slot, default| {
            let c = this.color_or_texture(p, name, slot, slots)?;
            let mean = match c {
                Some(c) => c,
                None => slots
                    .iter()
                    .rfind(|(s, _)| *s == slot)
                    .map_or(default, |(_, t)| t.mean()),
            };
            Ok::<_, SceneError>((c.unwrap_or(default), mean))
        };
        let (diffuse, diffuse_mean) = reflectance(
            self,
            "diffuse_reflectance",
            TextureSlot::Reflectance,
            Color::splat(0.5),
        )?;
        let (specular, specular_mean) = reflectance(
            self,
            "specular_reflectance",
            TextureSlot::SpecularReflectance,
            Color::ONE,
        )?;
        let nonlinear = p.boolean("nonlinear")?.unwrap_or(false);
        let weight =
            specular_sampling_weight(channel_mean(diffuse_mean), channel_mean(specular_mean));
        Ok(if p.kind == "plastic" {
            let mut m = Plastic::new(eta, diffuse, specular, nonlinear);
            m.specular_sampling_weight = weight;
            Material::Plastic(m)
        } else {
            let distribution = self.microfacet(p, slots)?;
            if slots.iter().any(|(s, _)| s.is_roughness()) {
                return Err(p.err(
                    e,
                    "roughplastic's `alpha` must be a number (Mitsuba takes no texture there)",
                ));
            }
            if distribution.is_anisotropic() {
                return Err(p.err(
                    e,
                    "roughplastic is isotropic in Mitsuba: give `alpha`, not `alpha_u` ≠ `alpha_v`",
                ));
            }
            let mut m = RoughPlastic::new(distribution, eta, diffuse, specular, nonlinear);
            m.specular_sampling_weight = weight;
            Material::RoughPlastic(m)
        })
    }

    /// Mitsuba's `principled` and `principledthin`: `base_color` (0.5) and the scalars
    /// `roughness` (0.5), `anisotropic`, `metallic`*, `spec_trans`, `spec_tint`, `sheen`,
    /// `sheen_tint`, `flatness`, `clearcoat`*, `clearcoat_gloss`* (0), `diff_trans`† (0, range
    /// 0–2), each a number or a texture; principled's `eta` or `specular` (0.5, one of the two;
    /// numbers), principledthin's `eta` (1.5, a number or a texture); the sampling rates (1).
    /// (* principled only, † principledthin only.)
    pub(super) fn principled(
        &mut self,
        p: &Plugin<'a>,
        slots: &mut Vec<(TextureSlot, Texture)>,
    ) -> Result<Material, SceneError> {
        use PrincipledParam::*;
        let e = p.elem;
        let thin = p.kind == "principledthin";
        let base_color = self
            .color_or_texture(p, "base_color", TextureSlot::Principled(BaseColor), slots)?
            .unwrap_or(Color::splat(0.5));
        // A scalar: a number in [0, max], or a texture whose values stay there.
        let mut scalar = |this: &mut Self, name: &str, param, default: f32, max: f32| {
            if let Some(t) = p.texture(name) {
                let texture = this.texture(t)?;
                let top = texture.max_value();
                if !(top <= max) {
                    return Err(p.err(
                        t,
                        format!("the texture of `{name}` reaches {top} (at most {max})"),
                    ));
                }
                slots.push((TextureSlot::Principled(param), texture));
                return Ok((default, true));
            }
            match p.float(name)? {
                None => Ok((default, false)),
                Some(x) => scalar_in_range(name, x, max)
                    .map(|v| (v, x != 0.0))
                    .map_err(|m| p.err(e, m)),
            }
        };
        let (roughness, _) = scalar(self, "roughness", Roughness, 0.5, 1.0)?;
        let (anisotropic, _) = scalar(self, "anisotropic", Anisotropic, 0.0, 1.0)?;
        let (spec_trans, has_spec_trans) = scalar(self, "spec_trans", SpecTrans, 0.0, 1.0)?;
        let (spec_tint, _) = scalar(self, "spec_tint", SpecTint, 0.0, 1.0)?;
        let (sheen, _) = scalar(self, "sheen", Sheen, 0.0, 1.0)?;
        let (sheen_tint, _) = scalar(self, "sheen_tint", SheenTint, 0.0, 1.0)?;
        let (flatness, _) = scalar(self, "flatness", Flatness, 0.0, 1.0)?;
        let rate = |name: &str| -> Result<f32, SceneError> {
            match p.float(name)? {
                None => Ok(1.0),
                Some(x) if x >= 0.0 && x.is_finite() => Ok(x as f32),
                Some(x) => Err(p.err(
                    e,
                    format!("`{name}` must be a non-negative number, got {x}"),
                )),
            }
        };
        if thin {
            let (diff_trans, _) = scalar(self, "diff_trans", DiffTrans, 0.0, 2.0)?;
            let eta = match p.texture("eta") {
                Some(t) => {
                    let texture = self.texture(t)?;
                    slots.push((TextureSlot::Principled(Eta), texture));
                    1.5
                }
                None => thin_eta(p.float("eta")?, "eta").map_err(|m| p.err(e, m))?,
            };
            let sampling_rates = [
                rate("specular_reflectance_sampling_rate")?,
                rate("specular_transmittance_sampling_rate")?,
                rate("diffuse_reflectance_sampling_rate")?,
                rate("diffuse_transmittance_sampling_rate")?,
            ];
            return Ok(Material::PrincipledThin(PrincipledThin {
                base_color,
                roughness,
                anisotropic,
                spec_trans,
                diff_trans,
                eta,
                spec_tint,
                sheen,
                sheen_tint,
                flatness,
                sampling_rates,
            }));
        }
        let (metallic, _) = scalar(self, "metallic", Metallic, 0.0, 1.0)?;
        let (clearcoat, _) = scalar(self, "clearcoat", Clearcoat, 0.0, 1.0)?;
        let (clearcoat_gloss, _) = scalar(self, "clearcoat_gloss", ClearcoatGloss, 0.0, 1.0)?;
        let eta = principled_eta(p.float("eta")?, p.float("specular")?, has_spec_trans, "eta")
            .map_err(|m| p.err(e, m))?;
        let sampling_rates = [
            rate("diffuse_reflectance_sampling_rate")?,
            rate("clearcoat_sampling_rate")?,
            rate("main_specular_sampling_rate")?,
        ];
        Ok(Material::Principled(Principled {
            base_color,
            roughness,
            anisotropic,
            metallic,
            spec_trans,
            eta,
            spec_tint,
            sheen,
            sheen_tint,
            flatness,
            clearcoat,
            clearcoat_gloss,
            sampling_rates,
            has_spec_trans,
        }))
    }

    /// An IOR given as a number or by one of Mitsuba's names.
    pub(super) fn ior(&self, p: &Plugin<'a>, key: &str, default: f64) -> Result<f64, SceneError> {
        let Some(e) = p.take_elem(key) else {
            return Ok(default);
        };
        let v = e.attr("value").unwrap_or("");
        let x = match e.tag.as_str() {
            "float" | "integer" => crate::xml::values::number(self.doc, e, v, key)?,
            "string" => match NAMED_IORS
                .iter()
                .find(|(n, _)| *n == v.trim().to_ascii_lowercase())
            {
                Some(&(_, x)) => x,
                None => {
                    return Err(p.err(
                        e,
                        format!("`{key}`: `{v}` is not an IOR Mitsuba knows by name"),
                    ))
                }
            },
            _ => {
                return Err(p.err(
                    e,
                    format!("`{key}` must be a <float> or a <string> naming a material"),
                ))
            }
        };
        if !(x > 0.0) {
            return Err(p.err(e, format!("`{key}` must be positive, got {x}")));
        }
        Ok(x)
    }

    /// A dielectric's `int_ior / ext_ior` (Mitsuba's defaults: bk7 = 1.5046 inside, air =
    /// 1.000277 outside; either a number or a name Mitsuba knows).
    pub(super) fn relative_ior(&self, p: &Plugin<'a>) -> Result<f32, SceneError> {
        let int = self.ior(p, "int_ior", 1.5046)?;
        let ext = self.ior(p, "ext_ior", 1.000277)?;
        let ior = int / ext;
        if !(ior > 0.0) || !(ior as f32).is_finite() {
            return Err(p.err(
                p.elem,
                format!("the relative IOR {int}/{ext} is not a positive number"),
            ));
        }
        Ok(ior as f32)
    }

    /// Mitsuba's microfacet parameters: `distribution` (beckmann, the default, or ggx), `alpha` or
    /// `alpha_u` and `alpha_v` (default 0.1), `sample_visible` (default true).
    pub(super) fn microfacet(
        &mut self,
        p: &Plugin<'a>,
        slots: &mut Vec<(TextureSlot, Texture)>,
    ) -> Result<Microfacet, SceneError> {
        let e = p.elem;
        let kind = match p.string("distribution")? {
            None | Some(("beckmann", _)) => MicrofacetType::Beckmann,
            Some(("ggx", _)) => MicrofacetType::Ggx,
            Some((other, de)) => {
                return Err(p.err(
                    de,
                    format!("`distribution` must be ggx or beckmann, got `{other}`"),
                ))
            }
        };
        // A texture of α (or of α_u, α_v): the distribution keeps the default 0.1 there until a
        // point sets it (`TextureSlot::Alpha`, `AlphaU`, `AlphaV`).
        let mut roughness = |name: &str, slot| -> Result<Option<Option<f64>>, SceneError> {
            match p.texture(name) {
                Some(t) => {
                    let texture = self.texture(t)?;
                    slots.push((slot, texture));
                    Ok(Some(None))
                }
                None => Ok(p.float(name)?.map(Some)),
            }
        };
        let alpha = roughness("alpha", TextureSlot::Alpha)?;
        let au = roughness("alpha_u", TextureSlot::AlphaU)?;
        let av = roughness("alpha_v", TextureSlot::AlphaV)?;
        // α_u runs along the shading frame's x axis, ∂p/∂u made orthogonal to the normal
        // (`SurfaceHit::tangent`), as in Mitsuba.
        let (u, v) = match (alpha, au, av) {
            (Some(a), None, None) => (a, a),
            (None, None, None) => (Some(0.1), Some(0.1)),
            (None, Some(u), Some(v)) => (u, v),
            _ => return Err(p.err(e, "give `alpha`, or both `alpha_u` and `alpha_v`")),
        };
        for a in [u, v].into_iter().flatten() {
            if !(a >= MIN_ROUGHNESS) || !(a.is_finite()) {
                return Err(p.err(e, format!("`alpha` must be at least {MIN_ROUGHNESS}, got {a} (use a conductor for a mirror)")));
            }
        }
        let sample_visible = p.boolean("sample_visible")?.unwrap_or(true);
        let (u, v) = (u.unwrap_or(0.1) as f32, v.unwrap_or(0.1) as f32);
        Ok(Microfacet::new(kind, u, v, sample_visible))
    }

    /// A conductor's complex IOR: Mitsuba's `material` name (default "none", a perfect mirror), or
    /// `eta` and `k` given together (RGB, spectrum or float).
    pub(super) fn complex_ior(&mut self, p: &Plugin<'a>) -> Result<ComplexIor, SceneError> {
        let opts = self.opts;
        let eta = p.color("eta", ColorUse::Unbounded, opts, &mut self.report)?;
        let k = p.color("k", ColorUse::Unbounded, opts, &mut self.report)?;
        let named = p.string("material")?;
        match (named, eta, k) {
            (None, None, None) => Ok(named_conductor("none").expect("none is a conductor")),
            (Some((name, me)), None, None) => named_conductor(name).ok_or_else(|| {
                let names: Vec<&str> = conductor_names().collect();
                p.err(
                    me,
                    format!(
                        "conductor material `{name}` is not one Mitsuba knows (known: {})",
                        names.join(", ")
                    ),
                )
            }),
            (None, Some(eta), Some(k)) => Ok(ComplexIor { eta, k }),
            (Some((_, me)), _, _) => {
                Err(p.err(me, "give a conductor `material` or `eta` and `k`, not both"))
            }
            _ => Err(p.err(p.elem, "a conductor's `eta` and `k` go together: give both")),
        }
    }
}

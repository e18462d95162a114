//! The scene file as serde sees it (reference: docs/scene-format.md). Every table denies unknown
//! keys; values that are checked after parsing keep their byte span (`Spanned`) so the error can
//! name the line. Shapes, materials and lights are flat structs with a `type` key rather than
//! tagged enums: serde buffers tagged enums, which would lose the spans.

use lt_core::camera::FovAxis;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt;
use toml::Spanned;

pub type S<T> = Spanned<T>;
pub type V3 = [f64; 3];

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    pub camera: S<CameraDef>,
    pub render: Option<S<RenderDef>>,
    #[serde(default)]
    pub materials: BTreeMap<String, S<MaterialDef>>,
    #[serde(default)]
    pub shapes: Vec<S<ShapeDef>>,
    #[serde(default)]
    pub lights: Vec<S<LightDef>>,
    /// Participating media by name, referenced by shapes' `interior`/`exterior` and by the
    /// camera's and lights' `medium`.
    #[serde(default)]
    pub media: BTreeMap<String, S<MediumDef>>,
}

/// `[media.NAME]`: Mitsuba's `homogeneous` (`sigma_t` and `albedo`, or `sigma_a` and `sigma_s`)
/// and `heterogeneous` (`sigma_t` and `albedo` as colours or as `*_volume` grids) media, both
/// with `scale` and a `phase` function.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MediumDef {
    #[serde(rename = "type")]
    pub kind: S<String>,
    pub sigma_t: Option<S<ColorDef>>,
    pub albedo: Option<S<ColorDef>>,
    pub sigma_a: Option<S<ColorDef>>,
    pub sigma_s: Option<S<ColorDef>>,
    pub scale: Option<S<f64>>,
    pub sigma_t_volume: Option<S<VolumeDef>>,
    pub albedo_volume: Option<S<VolumeDef>>,
    pub phase: Option<S<PhaseDef>>,
}

/// `phase = { type = "isotropic" }` or `{ type = "hg", g = 0.7 }`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhaseDef {
    #[serde(rename = "type")]
    pub kind: S<String>,
    pub g: Option<S<f64>>,
}

/// A grid volume (Mitsuba's `gridvolume`): a `.vol` `file` (relative to the scene file), its
/// `to_world` (row by row), `use_grid_bbox` and `wrap` ("clamp", "repeat" or "mirror").
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VolumeDef {
    pub file: S<String>,
    pub to_world: Option<S<[[f64; 4]; 4]>>,
    pub use_grid_bbox: Option<S<bool>>,
    pub wrap: Option<S<String>>,
}

/// `fov_axis` as the file spells it (the core's `FovAxis` knows no file format).
#[derive(Clone, Copy, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FovAxisName {
    X,
    Y,
    Smaller,
    Larger,
}

impl From<FovAxisName> for FovAxis {
    fn from(n: FovAxisName) -> FovAxis {
        match n {
            FovAxisName::X => FovAxis::X,
            FovAxisName::Y => FovAxis::Y,
            FovAxisName::Smaller => FovAxis::Smaller,
            FovAxisName::Larger => FovAxis::Larger,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDef {
    /// Mitsuba's sensor type: `perspective` (default), `thinlens`, `orthographic`.
    #[serde(rename = "type")]
    pub kind: Option<S<String>>,
    pub eye: S<V3>,
    pub target: S<V3>,
    pub up: Option<S<V3>>,
    /// Required by `perspective` and `thinlens`.
    pub fov: Option<S<f64>>,
    pub fov_axis: Option<FovAxisName>,
    pub resolution: S<[u32; 2]>,
    /// `thinlens`.
    pub aperture_radius: Option<S<f64>>,
    pub focus_distance: Option<S<f64>>,
    /// `orthographic`: half the film rectangle's width in world units (Mitsuba's `to_world` x
    /// scale; default 1).
    pub half_width: Option<S<f64>>,
    /// Mitsuba's `principal_point_offset_x/y`, in fractions of the film's width and height.
    pub principal_point_offset: Option<S<[f64; 2]>>,
    /// The pixel filter (Mitsuba's `<rfilter>`); the box of one pixel when absent.
    pub filter: Option<S<FilterDef>>,
    /// The medium the camera sits in (a `[media]` name).
    pub medium: Option<S<String>>,
}

/// `[camera.filter]`: Mitsuba's reconstruction filters and their parameters.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilterDef {
    /// `box`, `tent`, `gaussian`, `mitchell`, `catmullrom`, `lanczos`.
    #[serde(rename = "type")]
    pub kind: S<String>,
    pub radius: Option<S<f64>>,
    pub stddev: Option<S<f64>>,
    #[serde(rename = "B")]
    pub b: Option<S<f64>>,
    #[serde(rename = "C")]
    pub c: Option<S<f64>>,
    pub lobes: Option<S<u32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderDef {
    pub max_depth: Option<S<u32>>,
    pub rr_depth: Option<u32>,
    pub spp: Option<S<u32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialDef {
    #[serde(rename = "type")]
    pub kind: S<String>,
    pub albedo: Option<S<ColorDef>>,
    pub reflectance: Option<S<ColorDef>>,
    pub ior: Option<S<f64>>,
    pub roughness: Option<S<f64>>,
    /// Conductors: Mitsuba's named complex IOR ("Au", "Cu", …, "none").
    pub material: Option<S<String>>,
    pub eta: Option<S<ColorDef>>,
    pub k: Option<S<ColorDef>>,
    /// Rough conductors: "beckmann" (default) or "ggx", and α.
    pub distribution: Option<S<String>>,
    pub alpha: Option<S<f64>>,
    /// Rough conductors and dielectrics: anisotropic α along ∂p/∂u and along ∂p/∂v (Mitsuba's
    /// `alpha_u`, `alpha_v`; both or neither, in place of `alpha`).
    pub alpha_u: Option<S<f64>>,
    pub alpha_v: Option<S<f64>>,
    /// Rough and thin dielectrics: the colour factor of transmission (Mitsuba's
    /// `specular_transmittance`; `reflectance` is their `specular_reflectance`).
    pub transmittance: Option<S<ColorDef>>,
    /// One-sided materials (conductors, plastics) reflect on both sides when true.
    pub twosided: Option<S<bool>>,
    /// Plastics: Mitsuba's `nonlinear` (the base's albedo takes part in the internal reflections).
    pub nonlinear: Option<S<bool>>,
    /// Textures in place of `albedo`, `reflectance` (the colour factor) and `alpha`.
    pub albedo_texture: Option<S<TextureDef>>,
    pub reflectance_texture: Option<S<TextureDef>>,
    pub alpha_texture: Option<S<TextureDef>>,
    pub alpha_u_texture: Option<S<TextureDef>>,
    pub alpha_v_texture: Option<S<TextureDef>>,
    /// Mitsuba's `normalmap` around the material: a texture of tangent-space normals ((x+1)/2;
    /// give `raw = true` for 8-bit files), or `bumpmap`: a height texture times `bump_scale`
    /// (default 1). `flip_invalid_normals` and `bump_shadowing` (Mitsuba's
    /// `use_shadowing_function`) default to true, as in Mitsuba.
    pub normal_map: Option<S<TextureDef>>,
    pub bump_map: Option<S<TextureDef>>,
    pub bump_scale: Option<S<f64>>,
    pub flip_invalid_normals: Option<S<bool>>,
    pub bump_shadowing: Option<S<bool>>,
    /// Mitsuba's `mask` around the material: its opacity α (1 opaque; light passes straight
    /// through with probability 1 − α), a number in [0, 1] or a texture (its luminance).
    pub opacity: Option<S<f64>>,
    pub opacity_texture: Option<S<TextureDef>>,
    /// `principled` and `principledthin` (Mitsuba's names, `tree/material.rs`): `base_color`
    /// or `base_color_texture`, `roughness` and `ior` as above, and these scalars.
    pub base_color: Option<S<ColorDef>>,
    pub base_color_texture: Option<S<TextureDef>>,
    pub anisotropic: Option<S<f64>>,
    pub metallic: Option<S<f64>>,
    pub spec_trans: Option<S<f64>>,
    pub specular: Option<S<f64>>,
    pub spec_tint: Option<S<f64>>,
    pub sheen: Option<S<f64>>,
    pub sheen_tint: Option<S<f64>>,
    pub flatness: Option<S<f64>>,
    pub clearcoat: Option<S<f64>>,
    pub clearcoat_gloss: Option<S<f64>>,
    pub diff_trans: Option<S<f64>>,
}

/// A texture: `type = "bitmap"` with `file` (PNG, JPEG, BMP, HDR or EXR, relative to the scene
/// file), `filter` ("bilinear" or "nearest"), `wrap` ("repeat", "mirror" or "clamp") and `raw`
/// (keep 8-bit values as they are instead of decoding sRGB); or `type = "checkerboard"` with
/// `color0`, `color1`. Both take `scale` (uv multiplied by it first, default 1).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TextureDef {
    #[serde(rename = "type")]
    pub kind: S<String>,
    pub file: Option<S<String>>,
    pub filter: Option<S<String>>,
    pub wrap: Option<S<String>>,
    pub raw: Option<S<bool>>,
    pub color0: Option<S<ColorDef>>,
    pub color1: Option<S<ColorDef>>,
    pub scale: Option<S<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShapeDef {
    #[serde(rename = "type")]
    pub kind: S<String>,
    pub material: S<String>,
    pub emission: Option<S<ColorDef>>,
    /// The emitted radiance as a texture over the shape's uv (instead of `emission`).
    pub emission_texture: Option<S<TextureDef>>,
    #[serde(default)]
    pub flip_normals: bool,
    // mesh
    pub file: Option<S<String>>,
    // sphere
    pub center: Option<S<V3>>,
    pub radius: Option<S<f64>>,
    // mesh, quad, cube
    pub to_world: Option<S<[[f64; 4]; 4]>>,
    pub translate: Option<S<V3>>,
    pub rotate: Option<S<RotateDef>>,
    pub scale: Option<S<ScaleDef>>,
    /// The media inside and outside the surface (`[media]` names; an interior needs a closed
    /// surface).
    pub interior: Option<S<String>>,
    pub exterior: Option<S<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotateDef {
    pub axis: V3,
    /// Degrees, counter-clockwise looking down the axis (right-handed).
    pub angle: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightDef {
    #[serde(rename = "type")]
    pub kind: S<String>,
    pub position: Option<S<V3>>,
    pub intensity: Option<S<ColorDef>>,
    pub direction: Option<S<V3>>,
    pub solid_angle: Option<S<f64>>,
    pub radiance: Option<S<ColorDef>>,
    pub irradiance: Option<S<ColorDef>>,
    /// `envmap`: a latitude–longitude image (relative to the scene file), its `scale` (default
    /// 1) and a `rotate` of its local frame (Mitsuba's convention: +y is the image's top row).
    pub file: Option<S<String>>,
    pub scale: Option<S<f64>>,
    pub rotate: Option<S<RotateDef>>,
    /// `spot` and `projector`: at `position`, aimed at `target`, the image's vertical towards
    /// `up` (Mitsuba's lookat; default +y, or +z when the axis is vertical).
    pub target: Option<S<V3>>,
    pub up: Option<S<V3>>,
    /// `spot`: angles from the axis in degrees (defaults 20 and ¾ of the cutoff), and an optional
    /// `texture` over the cone (`intensity` multiplies it).
    pub cutoff_angle: Option<S<f64>>,
    pub beam_width: Option<S<f64>>,
    /// `projector`: the projected image (else the constant `irradiance`), and the full field
    /// of view across the image's width in degrees.
    pub texture: Option<S<TextureDef>>,
    pub fov: Option<S<f64>>,
    /// The medium the light sits in (a `[media]` name).
    pub medium: Option<S<String>>,
}

/// An RGB triple written as `[r, g, b]` or as one number for grey.
#[derive(Clone, Copy, Debug)]
pub struct ColorDef(pub V3);

/// A scale written as `[x, y, z]` or as one number for a uniform scale.
#[derive(Clone, Copy, Debug)]
pub struct ScaleDef(pub V3);

/// Accepts one number (repeated three times) or an array of exactly three numbers.
struct TripleVisitor(&'static str);

impl<'de> Visitor<'de> for TripleVisitor {
    type Value = V3;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "{}: a number or an array of 3 numbers", self.0)
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> Result<V3, E> {
        Ok([v; 3])
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<V3, E> {
        Ok([v as f64; 3])
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<V3, E> {
        Ok([v as f64; 3])
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<V3, A::Error> {
        let mut out = [0.0; 3];
        for (i, slot) in out.iter_mut().enumerate() {
            *slot = seq
                .next_element()?
                .ok_or_else(|| de::Error::invalid_length(i, &self))?;
        }
        if seq.next_element::<de::IgnoredAny>()?.is_some() {
            return Err(de::Error::invalid_length(4, &self));
        }
        Ok(out)
    }
}

impl<'de> Deserialize<'de> for ColorDef {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(TripleVisitor("a colour")).map(ColorDef)
    }
}

impl<'de> Deserialize<'de> for ScaleDef {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(TripleVisitor("a scale")).map(ScaleDef)
    }
}

//! Image files for textures and environment maps: PNG, JPEG and BMP through the `image` crate,
//! Radiance HDR through it too, OpenEXR through `exr`. Returns texels row by row from the top and
//! says whether they are display-encoded (8- or 16-bit sRGB files) or linear (HDR, EXR), so the
//! caller can decode sRGB unless the scene asks for the raw values.

use lt_core::math::Color;
use lt_core::texture::{Bitmap, FilterType, UvTransform, WrapMode};
use std::path::Path;

pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<Color>,
    /// The values are sRGB-encoded display values in [0, 1] (else linear radiometric values).
    pub srgb_encoded: bool,
}

/// Reads `path` by its extension; the error names the file and what went wrong.
pub fn read_rgb(path: &Path) -> Result<RgbImage, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    if ext == "exr" {
        return read_exr(path);
    }
    let img =
        image::open(path).map_err(|e| format!("cannot read image {}: {e}", path.display()))?;
    let (width, height) = (img.width() as usize, img.height() as usize);
    let linear = matches!(ext.as_str(), "hdr");
    let rgb = img.into_rgb32f();
    let texels = rgb
        .pixels()
        .map(|p| Color::new(p.0[0], p.0[1], p.0[2]))
        .collect();
    Ok(RgbImage {
        width,
        height,
        texels,
        srgb_encoded: !linear,
    })
}

fn read_exr(path: &Path) -> Result<RgbImage, String> {
    use exr::prelude::read_first_rgba_layer_from_file;
    let img = read_first_rgba_layer_from_file(
        path,
        |size, _| {
            (
                size.width(),
                vec![Color::ZERO; size.width() * size.height()],
            )
        },
        |(w, texels): &mut (usize, Vec<Color>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            texels[pos.y() * *w + pos.x()] = Color::new(r, g, b);
        },
    )
    .map_err(|e| format!("cannot read EXR {}: {e}", path.display()))?;
    let (width, texels) = img.layer_data.channel_data.pixels;
    Ok(RgbImage {
        width,
        height: texels.len() / width.max(1),
        texels,
        srgb_encoded: false,
    })
}

/// An environment map from an image file (Mitsuba's `envmap`): linear RGB texels (8-bit files
/// sRGB-decoded, as Mitsuba converts them), times `scale`, rotated by `to_world`.
pub fn read_environment_map(
    path: &Path,
    scale: f32,
    to_world: glam::Mat3,
) -> Result<lt_core::light::EnvironmentMap, String> {
    let img = read_rgb(path)?;
    let texels = if img.srgb_encoded {
        img.texels.iter().map(|c| c.map(srgb_to_linear)).collect()
    } else {
        img.texels
    };
    lt_core::light::EnvironmentMap::new(img.width, img.height, texels, scale, to_world)
        .map_err(|m| format!("{}: {m}", path.display()))
}

/// The sRGB transfer function inverted (IEC 61966-2-1): display value → linear.
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Mitsuba's `filter_type` by name (absent: bilinear); the error says what is accepted.
pub fn filter_type_named(name: Option<&str>) -> Result<FilterType, String> {
    match name {
        None | Some("bilinear") => Ok(FilterType::Bilinear),
        Some("nearest") => Ok(FilterType::Nearest),
        Some(other) => Err(format!("must be bilinear or nearest, got `{other}`")),
    }
}

/// Mitsuba's `wrap_mode` by name (absent: repeat); the error says what is accepted.
pub fn wrap_mode_named(name: Option<&str>) -> Result<WrapMode, String> {
    match name {
        None | Some("repeat") => Ok(WrapMode::Repeat),
        Some("mirror") => Ok(WrapMode::Mirror),
        Some("clamp") => Ok(WrapMode::Clamp),
        Some(other) => Err(format!("must be repeat, mirror or clamp, got `{other}`")),
    }
}

/// A bitmap texture from an image file: sRGB-encoded files are decoded to linear unless `raw`.
pub fn read_bitmap(
    path: &Path,
    raw: bool,
    filter: FilterType,
    wrap: WrapMode,
    to_uv: UvTransform,
) -> Result<Bitmap, String> {
    let img = read_rgb(path)?;
    let decode = img.srgb_encoded && !raw;
    let texels = img
        .texels
        .iter()
        .map(|c| if decode { c.map(srgb_to_linear) } else { *c })
        .collect();
    Ok(Bitmap {
        width: img.width,
        height: img.height,
        texels,
        filter,
        wrap,
        to_uv,
    })
}

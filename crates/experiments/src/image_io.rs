//! Image files: EXR in and out (linear RGB), PNG previews, and atomic writes so an interrupted
//! run never leaves a truncated file where a good one was expected.

use lt_estimators::Image;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

/// A temporary path next to `path` (same directory, so the final rename stays atomic).
fn temp_sibling(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    path.with_file_name(format!(".{name}.tmp-{}", std::process::id()))
}

/// Runs `write` on a temporary sibling of `path`, then renames it over `path`. On error the
/// temporary file is removed and `path` is left untouched.
pub fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), String> {
    let tmp = temp_sibling(path);
    let result = write(&tmp).and_then(|()| {
        fs::rename(&tmp, path)
            .map_err(|e| format!("cannot move {} to {}: {e}", tmp.display(), path.display()))
    });
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Writes `bytes` to `path` atomically (temp file in the same directory, synced, renamed).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), String> {
    write_atomic_with(path, |tmp| {
        let mut f =
            fs::File::create(tmp).map_err(|e| format!("cannot create {}: {e}", tmp.display()))?;
        f.write_all(bytes)
            .and_then(|()| f.sync_all())
            .map_err(|e| format!("cannot write {}: {e}", tmp.display()))
    })
}

/// An EXR's first RGB(A) layer; `has_alpha` says whether an A channel was present (ignored).
pub fn read_exr_with_alpha(path: &Path) -> Result<(Image, bool), String> {
    use exr::prelude::read_first_rgba_layer_from_file;
    let img = read_first_rgba_layer_from_file(
        path,
        |size, channels| {
            (
                Image::new(size.width(), size.height()),
                channels.3.is_some(),
            )
        },
        |(img, _): &mut (Image, bool), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            let w = img.width;
            img.data[pos.y() * w + pos.x()] = [r as f64, g as f64, b as f64];
        },
    )
    .map_err(|e| format!("cannot read EXR {}: {e}", path.display()))?;
    Ok(img.layer_data.channel_data.pixels)
}

/// Reads the first RGB or RGBA layer of an EXR (half, float or uint samples) as linear RGB.
pub fn read_exr(path: &Path) -> Result<Image, String> {
    read_exr_with_alpha(path).map(|(img, _)| img)
}

/// Writes linear RGB as 32-bit float EXR (ZIP, lossless), atomically.
pub fn write_exr(path: &Path, img: &Image) -> Result<(), String> {
    use exr::prelude::{Encoding, SpecificChannels, Vec2, WritableImage};
    check_size(path, img)?;
    write_atomic_with(path, |tmp| {
        let channels = SpecificChannels::rgb(|Vec2(x, y)| {
            let p = img.get(x, y);
            (p[0] as f32, p[1] as f32, p[2] as f32)
        });
        exr::image::Image::from_encoded_channels(
            (img.width, img.height),
            Encoding::SMALL_LOSSLESS,
            channels,
        )
        .write()
        .to_file(tmp)
        .map_err(|e| format!("cannot write EXR {}: {e}", path.display()))
    })
}

/// The sRGB transfer curve on a linear value, clamped to [0, 1] (NaN maps to 0).
pub fn srgb_encode(v: f64) -> f64 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    if v <= 0.0031308 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// Writes an 8-bit sRGB PNG preview (clamped, no tone mapping), atomically.
pub fn write_png_preview(path: &Path, img: &Image) -> Result<(), String> {
    check_size(path, img)?;
    let bytes: Vec<u8> = img
        .data
        .iter()
        .flat_map(|p| p.map(|v| (srgb_encode(v) * 255.0).round() as u8))
        .collect();
    let buf = image::RgbImage::from_raw(img.width as u32, img.height as u32, bytes)
        .expect("buffer matches size");
    write_atomic_with(path, |tmp| {
        buf.save_with_format(tmp, image::ImageFormat::Png)
            .map_err(|e| format!("cannot write PNG {}: {e}", path.display()))
    })
}

fn check_size(path: &Path, img: &Image) -> Result<(), String> {
    if img.width == 0 || img.height == 0 || img.data.len() != img.width * img.height {
        return Err(format!(
            "cannot write {}: image is {}x{} with {} pixels",
            path.display(),
            img.width,
            img.height,
            img.data.len()
        ));
    }
    Ok(())
}

/// Paths of everything written beside the main EXR.
pub fn sibling(out: &Path, suffix: &str) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    out.with_file_name(format!("{stem}{suffix}"))
}

/// Writes the image, its preview and, when there is an honest one, its standard error. Where
/// there is none (one run of a consistent estimator) a stale `.stderr.exr` from an earlier render
/// is removed, so no file beside the image claims an error bar it does not have.
pub fn write_outputs(out: &Path, mean: &Image, std_error: Option<&Image>) -> Result<(), String> {
    write_exr(out, mean)?;
    write_png_preview(&sibling(out, ".png"), mean)?;
    let se_path = sibling(out, ".stderr.exr");
    match std_error {
        Some(se) => write_exr(&se_path, se),
        None => match std::fs::remove_file(&se_path) {
            Ok(()) => Ok(()),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
            Err(e) => Err(format!("cannot remove stale {}: {e}", se_path.display())),
        },
    }
}

/// The mean over pixels and channels of a standard-error image (NaN-free pixels only).
pub fn mean_of(img: &Image) -> f64 {
    let (sum, n) = img
        .data
        .iter()
        .flatten()
        .filter(|v| v.is_finite())
        .fold((0.0, 0u64), |(s, n), v| (s + v, n + 1));
    sum / n.max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("lt-image-io-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        dir.join(name)
    }

    #[test]
    fn exr_round_trip_is_f32_exact() {
        let img = Image::from_fn(5, 3, |x, y| {
            [x as f64 * 0.1, y as f64 / 3.0, 1e-7 + x as f64 * 1e5]
        });
        let path = scratch("rt.exr");
        write_exr(&path, &img).unwrap();
        let back = read_exr(&path).unwrap();
        assert_eq!((back.width, back.height), (5, 3));
        for (a, b) in img.data.iter().zip(&back.data) {
            assert_eq!(a.map(|v| v as f32 as f64), *b);
        }
        // No temporary file left behind.
        let left: Vec<_> = fs::read_dir(path.parent().unwrap())
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().starts_with(".rt.exr.tmp-"))
            .collect();
        assert!(left.is_empty());
    }

    #[test]
    fn reads_half_rgba() {
        use exr::prelude::*;
        let path = scratch("half.exr");
        write_rgba_file(&path, 4, 2, |x, y| {
            (
                f16::from_f32(x as f32 * 0.5),
                f16::from_f32(y as f32),
                f16::from_f32(0.25),
                f16::from_f32(1.0),
            )
        })
        .unwrap();
        let (img, alpha) = read_exr_with_alpha(&path).unwrap();
        assert!(alpha);
        assert_eq!(img.get(3, 1), [1.5, 1.0, 0.25]);
    }

    #[test]
    fn errors_name_the_file() {
        let path = scratch("missing.exr");
        let e = read_exr(&path).unwrap_err();
        assert!(e.contains("missing.exr"), "{e}");
    }

    #[test]
    fn png_uses_srgb_curve() {
        assert_eq!(srgb_encode(0.0), 0.0);
        assert!((srgb_encode(0.5) - 0.7353569830524495).abs() < 1e-12);
        assert!((srgb_encode(7.0) - 1.0).abs() <= f64::EPSILON); // clamped to 1 (1.055 − 0.055 rounds)
        let path = scratch("p.png");
        write_png_preview(
            &path,
            &Image::from_fn(2, 1, |x, _| [x as f64 * 0.5, f64::NAN, 2.0]),
        )
        .unwrap();
        let back = image::open(&path).unwrap().to_rgb8();
        assert_eq!(back.get_pixel(1, 0).0, [188, 0, 255]);
    }
}

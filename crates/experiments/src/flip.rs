//! NVIDIA's FLIP (Andersson et al. 2020, the `nv-flip` crate) between a reference and a test
//! image, for the studies' "how different does it look" column beside MSE and relMSE.

use crate::image_io::srgb_encode;
use lt_estimators::Image;

/// FLIP's default observer: 67 pixels per degree of visual angle (a 0.7 m distance from a
/// 24-inch 4K monitor, the FLIP paper's setting).
pub const PIXELS_PER_DEGREE: f32 = 67.0;

/// The tone mapping FLIP sees: linear RGB clamped to [0, 1] and sRGB-encoded
/// (`image_io::srgb_encode`, as the PNG previews), rounded to 8 bits. No exposure or curve:
/// the same bytes as `lt render`'s `.png`.
fn to_ldr(img: &Image) -> Vec<u8> {
    img.data
        .iter()
        .flat_map(|p| p.map(|v| (srgb_encode(v) * 255.0).round() as u8))
        .collect()
}

/// The mean of LDR-FLIP's per-pixel error map (0 = identical, 1 = as different as can be)
/// between `reference` and `test`, both tone-mapped by clamping to [0, 1] and sRGB encoding
/// (8 bits), at FLIP's default 67 pixels per degree. Errors when the sizes differ or an image
/// is empty.
pub fn flip_mean(reference: &Image, test: &Image) -> Result<f64, String> {
    if !reference.same_size(test) {
        return Err(format!(
            "FLIP: reference is {}x{}, test is {}x{}",
            reference.width, reference.height, test.width, test.height
        ));
    }
    if reference.width == 0 || reference.height == 0 {
        return Err("FLIP: empty image".into());
    }
    let (w, h) = (reference.width as u32, reference.height as u32);
    let r = nv_flip::FlipImageRgb8::with_data(w, h, &to_ldr(reference));
    let t = nv_flip::FlipImageRgb8::with_data(w, h, &to_ldr(test));
    let map = nv_flip::flip(r, t, PIXELS_PER_DEGREE).to_vec();
    let sum: f64 = map.iter().map(|&v| v as f64).sum();
    Ok(sum / map.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth image with some structure (gradients and a bright square).
    fn scene(w: usize, h: usize) -> Image {
        Image::from_fn(w, h, |x, y| {
            let u = x as f64 / w as f64;
            let v = y as f64 / h as f64;
            let lit = if (20..40).contains(&x) && (20..40).contains(&y) {
                0.6
            } else {
                0.0
            };
            [0.2 + 0.5 * u + lit, 0.1 + 0.4 * v, 0.3 * (u + v) + lit]
        })
    }

    /// `img` plus deterministic ±amplitude noise per channel.
    fn noisy(img: &Image, amplitude: f64) -> Image {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut out = img.clone();
        for p in &mut out.data {
            for c in p.iter_mut() {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let u = (state >> 11) as f64 / (1u64 << 53) as f64;
                *c += amplitude * (2.0 * u - 1.0);
            }
        }
        out
    }

    #[test]
    fn identical_is_zero_and_error_grows_with_noise() {
        let r = scene(64, 48);
        assert_eq!(flip_mean(&r, &r).unwrap(), 0.0);
        let mut last = 0.0;
        for amp in [0.02, 0.05, 0.1, 0.2, 0.4] {
            let f = flip_mean(&r, &noisy(&r, amp)).unwrap();
            assert!(f > last, "FLIP {f} at noise {amp} not above {last}");
            assert!(f <= 1.0, "FLIP {f} above 1");
            last = f;
        }
    }

    #[test]
    fn tone_mapping_clamps_and_sizes_must_match() {
        let r = scene(32, 32);
        // Above 1 everywhere: both clamp to white, so FLIP sees no difference.
        let a = Image::from_fn(32, 32, |_, _| [2.0, 3.0, 4.0]);
        let b = Image::from_fn(32, 32, |_, _| [5.0, 1.5, 9.0]);
        assert_eq!(flip_mean(&a, &b).unwrap(), 0.0);
        let e = flip_mean(&r, &scene(32, 16)).unwrap_err();
        assert!(e.contains("32x16"), "{e}");
    }
}

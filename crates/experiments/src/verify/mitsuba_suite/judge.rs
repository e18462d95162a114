//! Mitsuba's render-test rule with lt's own error bars (../shared/mitsuba-render-tests/README.md):
//! per pixel value z = |mean − ref| / sqrt(max(se², 1e-4/spp) + max(var, 1e-4)/32000) — lt's
//! standard error from independent passes plus the reference's own 32,000-sample noise, with
//! Mitsuba's 1e-4 variance floor on both sides (without it, zero-variance pixels such as a
//! constant background fail on rounding alone) —, each value passing when its two-sided p-value
//! is above the Šidák level 1 − 0.99^(1/pixels), the image passing when at least 99.75 % of its
//! pixel values pass.

use lt_estimators::agreement::sidak_threshold;
use lt_estimators::Image;

/// Samples per pixel of Mitsuba's reference renders.
pub const REFERENCE_SPP: f64 = 32_000.0;
/// Mitsuba's floor on per-sample variances.
pub const VARIANCE_FLOOR: f64 = 1e-4;
/// Family-wise false-alarm rate over an image's pixels.
pub const FAMILY_ALPHA: f64 = 0.01;
/// Fraction of pixel values that must pass.
pub const PASS_FRACTION: f64 = 0.9975;

/// One image judged.
#[derive(Clone, Debug)]
pub struct Judgement {
    /// Pixel values whose p-value is above the Šidák level.
    pub passed_fraction: f64,
    /// The |z| the Šidák level corresponds to.
    pub z_threshold: f64,
    /// Largest |z| (NaN counts as infinite).
    pub max_z: f64,
    /// Mean of our image over the reference's (a bias shows here first).
    pub mean_ratio: f64,
}

impl Judgement {
    pub fn passes(&self) -> bool {
        self.passed_fraction >= PASS_FRACTION
    }
}

/// Judges `mean` (with per-pixel standard error `se`, from `spp` samples per pixel) against the
/// reference mean and per-sample variance.
pub fn judge(
    mean: &Image,
    se: &Image,
    spp: f64,
    reference: &Image,
    reference_var: &Image,
) -> Result<Judgement, String> {
    for (what, img) in [
        ("standard error", se),
        ("reference", reference),
        ("reference variance", reference_var),
    ] {
        if !img.same_size(mean) {
            return Err(format!(
                "the {what} image is {}×{}, the render {}×{}",
                img.width, img.height, mean.width, mean.height
            ));
        }
    }
    let pixels = mean.data.len();
    let z_threshold = sidak_threshold(FAMILY_ALPHA, pixels);
    let signed = signed_z(mean, se, spp, reference, reference_var);
    let (mut passed, mut max_z, mut ours, mut theirs) = (0usize, 0.0f64, 0.0, 0.0);
    for i in 0..pixels {
        for c in 0..3 {
            let z = signed.data[i][c].abs();
            let z = if z.is_nan() { f64::INFINITY } else { z };
            passed += (z < z_threshold) as usize;
            max_z = max_z.max(z);
            ours += mean.data[i][c];
            theirs += reference.data[i][c];
        }
    }
    Ok(Judgement {
        passed_fraction: passed as f64 / (3 * pixels) as f64,
        z_threshold,
        max_z,
        mean_ratio: ours / theirs,
    })
}

/// Per pixel value, (mean − ref) / σ with σ as the rule forms it (the sizes already checked): the
/// map `--diagnostics` writes, where a bias shows as a region of one sign and noise as speckle.
pub fn signed_z(
    mean: &Image,
    se: &Image,
    spp: f64,
    reference: &Image,
    reference_var: &Image,
) -> Image {
    let mut z = Image::new(mean.width, mean.height);
    for (i, out) in z.data.iter_mut().enumerate() {
        for (c, z_c) in out.iter_mut().enumerate() {
            let ours_var = (se.data[i][c].powi(2)).max(VARIANCE_FLOOR / spp);
            let ref_var = reference_var.data[i][c].max(VARIANCE_FLOOR) / REFERENCE_SPP;
            *z_c = (mean.data[i][c] - reference.data[i][c]) / (ours_var + ref_var).sqrt();
        }
    }
    z
}

#[cfg(test)]
mod tests {
    use super::*;
    use lt_core::sampling::Sampler;

    /// A render of `reference` with Gaussian noise of standard error `se` per value.
    fn noisy(reference: &Image, se: f64, seed: u64) -> Image {
        let mut s = Sampler::new(seed, 0, 0);
        let mut out = reference.clone();
        for p in &mut out.data {
            for v in p.iter_mut() {
                // Box–Muller.
                let (u1, u2) = (1.0 - s.next_f32() as f64, s.next_f32() as f64);
                *v += se * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
            }
        }
        out
    }

    #[test]
    fn judge_passes_an_honest_render_and_fails_a_five_percent_bias() {
        let reference = Image::from_fn(48, 48, |x, y| {
            [0.2 + 0.01 * x as f64, 0.5, 0.1 + 0.01 * y as f64]
        });
        let var = Image::from_fn(48, 48, |_, _| [0.05; 3]);
        let se_value = 0.004;
        let se = Image::from_fn(48, 48, |_, _| [se_value; 3]);
        let honest = noisy(&reference, se_value, 1);
        let j = judge(&honest, &se, 256.0, &reference, &var).unwrap();
        assert!(j.passes(), "{j:?}");
        // The planted error of the suite's demonstration: a reference 5 % too bright.
        let bright = Image {
            data: reference.data.iter().map(|p| p.map(|v| v * 1.05)).collect(),
            ..reference.clone()
        };
        let j = judge(&honest, &se, 256.0, &bright, &var).unwrap();
        assert!(!j.passes(), "{j:?}");
        assert!(judge(&honest, &se, 256.0, &Image::new(4, 4), &var).is_err());
    }
}

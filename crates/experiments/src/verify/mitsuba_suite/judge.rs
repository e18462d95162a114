//! Mitsuba's render-test rule with lt's own error bars (../shared/mitsuba-render-tests/README.md):
//! per pixel value z = |mean − ref| / sqrt(max(se², 1e-4/n) + max(var, 1e-4)/32000) — lt's
//! standard error from independent passes plus the reference's own 32,000-sample noise, with
//! Mitsuba's 1e-4 variance floor on both sides (without it, zero-variance pixels such as a
//! constant background fail on rounding alone) —, each value passing when its two-sided p-value
//! is above the Šidák level 1 − 0.99^(1/pixels), the image passing when at least 99.75 % of its
//! pixel values pass. n is lt's samples per pixel, but at most the 2·10⁶/pixels Mitsuba's own
//! test renders: the floor stands for what Mitsuba's test cannot resolve, and a longer lt run
//! must not make a zero-variance pixel stricter than Mitsuba judges itself (its references'
//! backgrounds carry ~0.1 % of noise their variance images record as 0: test_constant's sky reads
//! 1.0011 / 0.9997 where the emitter is 1, which fails at 2048 spp under a 1e-4/2048 floor).
//!
//! The references are also no more precise than their f32 accumulation of 32,000 samples: where a
//! pixel is nearly deterministic their red channel sits 0.10–0.15 % above green and blue and above
//! the analytic value (projector_constant: a white plane under a projector of irradiance 1 reads
//! 1.0014 / 0.9998 / 1.0002 in the reference, 0.9999–1.0002 in lt's pt and bdpt, in every
//! channel), and their variance images go negative there (E[x²] − E[x]² cancelling: −1.6e-3 at
//! x ≈ 1). So the reference's σ also holds a relative precision term, `REFERENCE_PRECISION` · ref:
//! it decides only where both renders' noise is below it, and a 1 % bias still fails there.

use lt_estimators::agreement::sidak_threshold;
use lt_estimators::Image;

/// Samples per pixel of Mitsuba's reference renders.
pub const REFERENCE_SPP: f64 = 32_000.0;
/// Mitsuba's floor on per-sample variances.
pub const VARIANCE_FLOOR: f64 = 1e-4;
/// Relative precision of a reference value (its f32 accumulation; see the module's doc).
pub const REFERENCE_PRECISION: f64 = 1e-3;
/// Samples Mitsuba's own test renders per image (per pixel: this over the pixel count).
pub const MITSUBA_TEST_SAMPLES: f64 = 2e6;
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
    let floor_spp = spp.min(MITSUBA_TEST_SAMPLES / mean.data.len() as f64);
    for (i, out) in z.data.iter_mut().enumerate() {
        for (c, z_c) in out.iter_mut().enumerate() {
            let ours_var = (se.data[i][c].powi(2)).max(VARIANCE_FLOOR / floor_spp);
            let ref_var = reference_var.data[i][c].max(VARIANCE_FLOOR) / REFERENCE_SPP
                + (REFERENCE_PRECISION * reference.data[i][c]).powi(2);
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

    /// A zero-variance background off by Mitsuba's reference noise (test_constant's sky: 1.0011
    /// where the emitter is 1, variance recorded as 0) passes at any lt budget, as it passes
    /// Mitsuba's own test; a 1 % offset still fails.
    #[test]
    fn a_longer_render_is_not_judged_stricter_than_mitsuba_judges_itself() {
        let reference = Image::from_fn(48, 48, |_, _| [1.0011, 0.9997, 0.9997]);
        let var = Image::new(48, 48);
        let exact = Image::from_fn(48, 48, |_, _| [1.0; 3]);
        let se = Image::new(48, 48);
        for spp in [256.0, 2048.0, 65536.0] {
            let j = judge(&exact, &se, spp, &reference, &var).unwrap();
            assert!(j.passes(), "{spp} spp: {j:?}");
        }
        let off = Image::from_fn(48, 48, |_, _| [1.01; 3]);
        let j = judge(&off, &se, 65536.0, &exact, &var).unwrap();
        assert!(!j.passes(), "{j:?}");
    }

    /// projector_constant's reference against its analytic value 1: red 0.14 % high with a
    /// negative variance (f32 accumulation) passes; a 1 % bias still fails on such pixels.
    #[test]
    fn a_reference_is_trusted_to_its_accumulation_precision() {
        let reference = Image::from_fn(48, 48, |_, _| [1.0014, 0.9998, 1.0002]);
        let var = Image::from_fn(48, 48, |_, _| [-1.6e-3, 3e-4, -2e-4]);
        let se = Image::from_fn(48, 48, |_, _| [2e-5; 3]);
        let exact = Image::from_fn(48, 48, |_, _| [1.0; 3]);
        assert!(judge(&exact, &se, 2048.0, &reference, &var)
            .unwrap()
            .passes());
        let biased = Image::from_fn(48, 48, |_, _| [0.99; 3]);
        let j = judge(&biased, &se, 2048.0, &reference, &var).unwrap();
        assert!(!j.passes(), "{j:?}");
    }
}

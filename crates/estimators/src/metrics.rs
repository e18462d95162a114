//! Error metrics of an image against a reference, per channel and over all three channels.
//!
//! Relative MSE follows pbrt-v4: mean over pixels of (v − r)² / (r + 0.01)². The 0.01 guard keeps
//! near-black reference pixels from dominating; it assumes non-negative references (radiance).

use crate::image::Image;

/// The small-denominator guard in relative MSE (pbrt-v4's value).
pub const REL_MSE_GUARD: f64 = 0.01;

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ChannelMetrics {
    pub mse: f64,
    /// mean((v − r)² / (r + 0.01)²)
    pub rel_mse: f64,
    pub rmse: f64,
    /// Mean absolute error.
    pub mae: f64,
    /// Largest absolute error.
    pub max_abs: f64,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageMetrics {
    /// R, G, B.
    pub channels: [ChannelMetrics; 3],
    /// Over all pixels and channels (so `overall.mse` is the mean of the channel MSEs).
    pub overall: ChannelMetrics,
    /// (x, y, channel) of `overall.max_abs`.
    pub max_at: (usize, usize, usize),
    /// Pixels of the image (not the reference) with a NaN or infinite channel; they make the
    /// metrics non-finite rather than being silently skipped.
    pub nonfinite_pixels: usize,
}

impl ImageMetrics {
    /// PSNR of the overall MSE for signal peak `peak`.
    pub fn psnr(&self, peak: f64) -> f64 {
        psnr(self.overall.mse, peak)
    }
}

/// 10·log10(peak² / mse) in dB; +inf for identical images.
pub fn psnr(mse: f64, peak: f64) -> f64 {
    10.0 * (peak * peak / mse).log10()
}

/// Metrics of `img` against `reference`. Panics if the sizes differ.
pub fn image_metrics(img: &Image, reference: &Image) -> ImageMetrics {
    assert!(
        img.same_size(reference),
        "image_metrics: image is {}x{}, reference {}x{}",
        img.width,
        img.height,
        reference.width,
        reference.height
    );
    let mut sums = [[0.0f64; 3]; 3]; // per channel: Σd², Σ rel d², Σ|d|
    let mut max = [0.0f64; 3];
    let (mut max_at, mut max_all, mut nonfinite) = ((0, 0, 0), 0.0f64, 0);
    for (i, (v, r)) in img.data.iter().zip(&reference.data).enumerate() {
        nonfinite += v.iter().any(|x| !x.is_finite()) as usize;
        for c in 0..3 {
            let d = v[c] - r[c];
            let a = d.abs();
            sums[c][0] += d * d;
            sums[c][1] += d * d / ((r[c] + REL_MSE_GUARD) * (r[c] + REL_MSE_GUARD));
            sums[c][2] += a;
            // NaN fails every comparison; record it explicitly so max_abs is not silently finite.
            if a > max[c] || a.is_nan() {
                max[c] = if max[c].is_nan() { max[c] } else { a };
            }
            if a > max_all || (a.is_nan() && !max_all.is_nan()) {
                (max_all, max_at) = (a, (i % img.width, i / img.width, c));
            }
        }
    }
    let n = img.data.len().max(1) as f64;
    let channel = |s: [f64; 3], m: f64| ChannelMetrics {
        mse: s[0] / n,
        rel_mse: s[1] / n,
        rmse: (s[0] / n).sqrt(),
        mae: s[2] / n,
        max_abs: m,
    };
    let channels = [0, 1, 2].map(|c| channel(sums[c], max[c]));
    let tot = [0, 1, 2].map(|k| (sums[0][k] + sums[1][k] + sums[2][k]) / 3.0);
    ImageMetrics {
        channels,
        overall: channel(tot, max_all),
        max_at,
        nonfinite_pixels: nonfinite,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // A 2×1 image with hand-computed answers.
    #[test]
    fn hand_computed() {
        let r = Image {
            width: 2,
            height: 1,
            data: vec![[1.0, 0.0, 2.0], [0.0, 0.0, 2.0]],
        };
        let v = Image {
            width: 2,
            height: 1,
            data: vec![[1.5, 0.0, 2.0], [-1.0, 0.0, 5.0]],
        };
        let m = image_metrics(&v, &r);
        let red = m.channels[0];
        assert_eq!(red.mse, (0.25 + 1.0) / 2.0);
        assert_eq!(red.mae, 0.75);
        assert_eq!(red.max_abs, 1.0);
        let rel = (0.25 / 1.01f64.powi(2) + 1.0 / 0.01f64.powi(2)) / 2.0;
        assert!((red.rel_mse - rel).abs() <= 1e-15 * rel);
        assert_eq!(m.channels[1], ChannelMetrics::default());
        assert_eq!(m.overall.mse, (0.25 + 1.0 + 9.0) / 6.0);
        assert_eq!(m.overall.max_abs, 3.0);
        assert_eq!(m.max_at, (1, 0, 2));
        assert!((m.psnr(1.0) - 10.0 * (6.0f64 / 10.25).log10()).abs() < 1e-14);
        assert_eq!(psnr(0.0, 1.0), f64::INFINITY);
    }

    #[test]
    fn nan_is_reported_not_hidden() {
        let r = Image::new(2, 1);
        let mut v = Image::new(2, 1);
        v.data[1][2] = f64::NAN;
        let m = image_metrics(&v, &r);
        assert_eq!(m.nonfinite_pixels, 1);
        assert!(
            m.overall.mse.is_nan() && m.overall.max_abs.is_nan() && m.channels[2].max_abs.is_nan()
        );
        assert_eq!(m.max_at, (1, 0, 2));
    }
}

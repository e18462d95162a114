//! Welford running mean and variance, scalar and per pixel, with exact merging (Chan et al.) so
//! parallel or resumed runs combine into the same numbers a single sequential run would give.

use crate::image::Image;

/// Scalar running mean/variance.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RunningStat {
    n: u64,
    mean: f64,
    m2: f64,
}

impl RunningStat {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn from_slice(xs: &[f64]) -> Self {
        let mut s = Self::new();
        xs.iter().for_each(|&x| s.add(x));
        s
    }

    pub fn add(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
    }

    pub fn merge(&mut self, o: &RunningStat) {
        (self.n, self.mean, self.m2) = chan(self.n, self.mean, self.m2, o.n, o.mean, o.m2);
    }

    pub fn count(&self) -> u64 {
        self.n
    }

    pub fn mean(&self) -> f64 {
        self.mean
    }

    /// Unbiased sample variance; NaN below two samples (unknown, not zero).
    pub fn sample_variance(&self) -> f64 {
        if self.n < 2 {
            f64::NAN
        } else {
            self.m2 / (self.n - 1) as f64
        }
    }

    /// Standard error of the mean, sqrt(s²/n).
    pub fn std_error(&self) -> f64 {
        (self.sample_variance() / self.n as f64).sqrt()
    }
}

/// Chan et al.'s pairwise combination of (count, mean, M2).
#[inline]
pub(crate) fn chan(na: u64, ma: f64, m2a: f64, nb: u64, mb: f64, m2b: f64) -> (u64, f64, f64) {
    if nb == 0 {
        return (na, ma, m2a);
    }
    if na == 0 {
        return (nb, mb, m2b);
    }
    let n = na + nb;
    let d = mb - ma;
    let fb = nb as f64 / n as f64;
    (n, ma + d * fb, m2a + m2b + d * d * na as f64 * fb)
}

/// Per-pixel, per-channel running mean/variance over passes (each pass one independent image).
#[derive(Clone, Debug, PartialEq)]
pub struct RunningImage {
    width: usize,
    height: usize,
    n: u64,
    mean: Vec<[f64; 3]>,
    m2: Vec<[f64; 3]>,
}

impl RunningImage {
    pub fn new(width: usize, height: usize) -> Self {
        let z = vec![[0.0; 3]; width * height];
        RunningImage {
            width,
            height,
            n: 0,
            mean: z.clone(),
            m2: z,
        }
    }

    pub fn add(&mut self, pass: &Image) {
        assert!(
            pass.width == self.width && pass.height == self.height,
            "RunningImage::add: pass is {}x{}, accumulator {}x{}",
            pass.width,
            pass.height,
            self.width,
            self.height
        );
        self.n += 1;
        let inv = 1.0 / self.n as f64;
        for ((m, m2), p) in self.mean.iter_mut().zip(&mut self.m2).zip(&pass.data) {
            for c in 0..3 {
                let d = p[c] - m[c];
                m[c] += d * inv;
                m2[c] += d * (p[c] - m[c]);
            }
        }
    }

    pub fn merge(&mut self, other: &RunningImage) {
        assert!(
            other.width == self.width && other.height == self.height,
            "RunningImage::merge: sizes differ ({}x{} vs {}x{})",
            other.width,
            other.height,
            self.width,
            self.height
        );
        let n = self.n;
        for i in 0..self.mean.len() {
            for c in 0..3 {
                let (_, m, m2) = chan(
                    n,
                    self.mean[i][c],
                    self.m2[i][c],
                    other.n,
                    other.mean[i][c],
                    other.m2[i][c],
                );
                self.mean[i][c] = m;
                self.m2[i][c] = m2;
            }
        }
        self.n += other.n;
    }

    /// An accumulator from its stored state: `count` passes, per-pixel mean and sum of squared
    /// deviations (M2), row-major — what a partial render keeps so that it can be merged exactly.
    pub fn from_parts(
        width: usize,
        height: usize,
        count: u64,
        mean: Vec<[f64; 3]>,
        m2: Vec<[f64; 3]>,
    ) -> Result<Self, String> {
        let n = width * height;
        if mean.len() != n || m2.len() != n {
            return Err(format!(
                "a {width}x{height} accumulator needs {n} pixels of mean and of M2, got {} and {}",
                mean.len(),
                m2.len()
            ));
        }
        if count == 0 && (mean.iter().chain(&m2).flatten().any(|&v| v != 0.0)) {
            return Err("an accumulator of no passes must be all zeros".into());
        }
        if m2.iter().flatten().any(|&v| v < 0.0) {
            return Err("a sum of squared deviations (M2) is negative".into());
        }
        Ok(RunningImage {
            width,
            height,
            n: count,
            mean,
            m2,
        })
    }

    /// The stored state: per-pixel mean and M2, row-major (see `from_parts`).
    pub fn parts(&self) -> (&[[f64; 3]], &[[f64; 3]]) {
        (&self.mean, &self.m2)
    }

    pub fn count(&self) -> u64 {
        self.n
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    pub fn mean(&self) -> Image {
        Image {
            width: self.width,
            height: self.height,
            data: self.mean.clone(),
        }
    }

    /// Unbiased per-pixel variance of one pass; NaN below two passes.
    pub fn sample_variance(&self) -> Image {
        let k = if self.n < 2 {
            f64::NAN
        } else {
            1.0 / (self.n - 1) as f64
        };
        self.map_m2(|m2| m2 * k)
    }

    /// Per-pixel standard error of the mean, sqrt(sample_variance / count).
    pub fn std_error(&self) -> Image {
        let k = if self.n < 2 {
            f64::NAN
        } else {
            1.0 / ((self.n - 1) as f64 * self.n as f64)
        };
        self.map_m2(|m2| (m2 * k).sqrt())
    }

    fn map_m2(&self, f: impl Fn(f64) -> f64) -> Image {
        let data = self
            .m2
            .iter()
            .map(|m| [f(m[0]), f(m[1]), f(m[2])])
            .collect();
        Image {
            width: self.width,
            height: self.height,
            data,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::Rng;

    fn random_image(rng: &mut Rng, w: usize, h: usize) -> Image {
        Image::from_fn(w, h, |x, _| {
            let s = 1.0 + x as f64;
            [rng.normal() * s + 5.0, rng.uniform() * 1e3, rng.exp()]
        })
    }

    // Two-pass textbook variance, the reference Welford must reproduce.
    fn two_pass(xs: &[f64]) -> (f64, f64) {
        let m = xs.iter().sum::<f64>() / xs.len() as f64;
        (
            m,
            xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (xs.len() - 1) as f64,
        )
    }

    #[test]
    fn welford_matches_two_pass() {
        let mut rng = Rng::new(1);
        let xs: Vec<f64> = (0..1000).map(|_| 1e6 + rng.normal()).collect();
        let s = RunningStat::from_slice(&xs);
        let (m, v) = two_pass(&xs);
        // Rounding bound: each step's deviation d carries an error of a few ulps of |x|, so the
        // mean errs by ~n·eps·|x| and M2 by ~n·eps·|x|·|d|.
        let n = xs.len() as f64;
        let xmax = xs.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let dmax = xs.iter().fold(0.0f64, |a, x| a.max((x - m).abs()));
        assert!(
            (s.mean() - m).abs() <= 4.0 * n * f64::EPSILON * xmax,
            "{} vs {m}",
            s.mean()
        );
        let tol_v = 4.0 * n * f64::EPSILON * xmax * dmax / (n - 1.0);
        assert!(
            (s.sample_variance() - v).abs() <= tol_v,
            "{} vs {v}",
            s.sample_variance()
        );
        // And it is not vacuous: the bound is far below the variance itself.
        assert!(tol_v < 1e-3 * v);
    }

    #[test]
    fn image_merge_equals_sequential() {
        let mut rng = Rng::new(7);
        let passes: Vec<Image> = (0..37).map(|_| random_image(&mut rng, 4, 3)).collect();
        let mut seq = RunningImage::new(4, 3);
        passes.iter().for_each(|p| seq.add(p));
        // Uneven split into three parts, including merging into and from an empty accumulator.
        let mut parts = [
            RunningImage::new(4, 3),
            RunningImage::new(4, 3),
            RunningImage::new(4, 3),
        ];
        for (i, p) in passes.iter().enumerate() {
            parts[if i < 5 {
                0
            } else if i < 30 {
                1
            } else {
                2
            }]
            .add(p);
        }
        let mut merged = RunningImage::new(4, 3);
        for p in &parts {
            merged.merge(p);
        }
        merged.merge(&RunningImage::new(4, 3));
        assert_eq!(merged.count(), seq.count());
        let (a, b) = (merged.sample_variance(), seq.sample_variance());
        let (ma, mb) = (merged.mean(), seq.mean());
        let n = passes.len() as f64;
        for i in 0..a.data.len() {
            for c in 0..3 {
                // Same rounding bound as welford_matches_two_pass, doubled: both sides err.
                let xs: Vec<f64> = passes.iter().map(|p| p.data[i][c]).collect();
                let xmax = xs.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                let dmax = xs
                    .iter()
                    .fold(0.0f64, |m, x| m.max((x - mb.data[i][c]).abs()));
                let tol_m = 8.0 * n * f64::EPSILON * xmax;
                let tol_v = 8.0 * n * f64::EPSILON * xmax * dmax / (n - 1.0);
                assert!((ma.data[i][c] - mb.data[i][c]).abs() <= tol_m);
                assert!(
                    (a.data[i][c] - b.data[i][c]).abs() <= tol_v,
                    "{} vs {}",
                    a.data[i][c],
                    b.data[i][c]
                );
            }
        }
    }

    #[test]
    fn parts_round_trip_and_bad_parts_are_refused() {
        let mut rng = Rng::new(11);
        let mut r = RunningImage::new(3, 2);
        (0..5).for_each(|_| r.add(&random_image(&mut rng, 3, 2)));
        let (m, m2) = r.parts();
        let back = RunningImage::from_parts(3, 2, r.count(), m.to_vec(), m2.to_vec()).unwrap();
        assert_eq!(back, r);
        assert!(RunningImage::from_parts(3, 2, 5, m[..5].to_vec(), m2.to_vec()).is_err());
        let mut neg = m2.to_vec();
        neg[2][1] = -1.0;
        assert!(RunningImage::from_parts(3, 2, 5, m.to_vec(), neg).is_err());
        assert!(RunningImage::from_parts(3, 2, 0, m.to_vec(), m2.to_vec()).is_err());
    }

    #[test]
    fn scalar_merge_equals_sequential() {
        let mut rng = Rng::new(3);
        let xs: Vec<f64> = (0..101).map(|_| rng.exp()).collect();
        let mut a = RunningStat::from_slice(&xs[..40]);
        a.merge(&RunningStat::from_slice(&xs[40..]));
        let s = RunningStat::from_slice(&xs);
        assert_eq!(a.count(), 101);
        assert!((a.mean() - s.mean()).abs() <= 1e-14 * s.mean());
        assert!((a.sample_variance() - s.sample_variance()).abs() <= 1e-13 * s.sample_variance());
    }

    #[test]
    fn std_error_is_sqrt_var_over_n() {
        let mut r = RunningImage::new(1, 1);
        for v in [1.0, 2.0, 4.0] {
            r.add(&Image {
                width: 1,
                height: 1,
                data: vec![[v, 0.0, -v]],
            });
        }
        // Hand-computed: mean 7/3, s² = 7/3.
        let v = r.sample_variance().data[0];
        assert!((v[0] - 7.0 / 3.0).abs() < 1e-15 && v[1] == 0.0);
        assert!((r.std_error().data[0][2] - (7.0f64 / 9.0).sqrt()).abs() < 1e-15);
        assert!(RunningImage::new(1, 1).sample_variance().data[0][0].is_nan());
    }
}

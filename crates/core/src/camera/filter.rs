//! Pixel (reconstruction) filters with Mitsuba 3's definitions and parameters, and what the film
//! does with them.
//!
//! A filter is a 1-D profile f₁ applied separably, f(x, y) = f₁(x) f₁(y), in raster units
//! (Mitsuba 3, `src/rfilters/*.cpp`). Pixel j, centred at c_j, estimates
//!
//! ```text
//!     I_j = ∫_film f(x − c_j) I(x) dx / Z_j,      Z_j = ∫_film f(x − c_j) dx,
//! ```
//!
//! x over the film only: Mitsuba's default `sample_border = false` samples positions on the film
//! and normalises each pixel by the filter weights it received, which converges to the same
//! ratio. Z_j = Z_x(column) · Z_y(row) is computed once per column and row (`FilmFilter`).
//!
//! Two estimators of I_j, unbiased for the same number, so light tracing, path tracing and BDPT
//! still agree pixel by pixel:
//! - **camera rays** (filter importance sampling): the offset x − c_j is drawn from a tabulated
//!   density p ∝ |f₁| per axis (piecewise constant over `BINS` bins, so p is known exactly) and
//!   the sample is weighted f(x − c_j) / (p(x − c_j) Z_j) — negative lobes give negative weights,
//!   honestly; an offset that leaves the film contributes nothing;
//! - **splats** (light tracing, BDPT's t = 1): a contribution landing at x is added to every pixel
//!   whose support covers x with weight f(x − c_j) / Z_j.
//!
//! The default, `box` of radius ½, is today's film bit for bit: one uniform position in the pixel
//! (`x + u`, no weight) and one pixel per splat.
//!
//! Neighbouring pixels of a filtered image share samples, so they are correlated; each pixel's
//! standard error over independent passes is still honest, and tests over groups of pixels must
//! use per-pass block means (`lt_estimators::blocks`), never treat pixels as independent.

use crate::sampling::Distribution1D;

/// The 1-D profile of a pixel filter, with Mitsuba 3's parameters (in pixels).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FilterShape {
    /// 1 on [−radius, radius) (Mitsuba: `radius`, default 0.5).
    Box { radius: f32 },
    /// max(0, 1 − |x| / radius) (Mitsuba: `radius`, default 1).
    Tent { radius: f32 },
    /// max(0, exp(−x²/2σ²) − exp(−r²/2σ²)) with r = 4σ: the Gaussian minus its value at the
    /// truncation radius, so it reaches zero there (Mitsuba: `stddev`, default 0.5).
    Gaussian { stddev: f32 },
    /// Mitchell & Netravali's cubic of radius 2 (Mitsuba: `B`, `C`, default ⅓ each).
    Mitchell { b: f32, c: f32 },
    /// The Mitchell–Netravali cubic with B = 0, C = ½.
    CatmullRom,
    /// sinc(x) sinc(x / lobes) on |x| ≤ lobes (Mitsuba: `lobes`, default 3).
    Lanczos { lobes: u32 },
}

impl Default for FilterShape {
    fn default() -> FilterShape {
        FilterShape::Box { radius: 0.5 }
    }
}

impl FilterShape {
    /// Mitsuba's name of the filter.
    pub fn name(&self) -> &'static str {
        match self {
            FilterShape::Box { .. } => "box",
            FilterShape::Tent { .. } => "tent",
            FilterShape::Gaussian { .. } => "gaussian",
            FilterShape::Mitchell { .. } => "mitchell",
            FilterShape::CatmullRom => "catmullrom",
            FilterShape::Lanczos { .. } => "lanczos",
        }
    }

    /// Half-width of the support in pixels.
    pub fn radius(&self) -> f32 {
        match *self {
            FilterShape::Box { radius } | FilterShape::Tent { radius } => radius,
            FilterShape::Gaussian { stddev } => 4.0 * stddev,
            FilterShape::Mitchell { .. } | FilterShape::CatmullRom => 2.0,
            FilterShape::Lanczos { lobes } => lobes as f32,
        }
    }

    /// f₁(x), in f64 (tables and normalisers are built from it).
    pub fn eval(&self, x: f64) -> f64 {
        let a = x.abs();
        match *self {
            FilterShape::Box { radius } => {
                let r = radius as f64;
                if x >= -r && x < r {
                    1.0
                } else {
                    0.0
                }
            }
            FilterShape::Tent { radius } => (1.0 - a / radius as f64).max(0.0),
            FilterShape::Gaussian { stddev } => {
                let alpha = -1.0 / (2.0 * (stddev as f64).powi(2));
                let r = 4.0 * stddev as f64;
                ((alpha * x * x).exp() - (alpha * r * r).exp()).max(0.0)
            }
            FilterShape::Mitchell { b, c } => mitchell_netravali(a, b as f64, c as f64),
            FilterShape::CatmullRom => mitchell_netravali(a, 0.0, 0.5),
            FilterShape::Lanczos { lobes } => {
                let r = lobes as f64;
                if a > r {
                    0.0
                } else if a < 1e-7 {
                    1.0
                } else {
                    let x1 = std::f64::consts::PI * a;
                    let x2 = x1 / r;
                    (x1.sin() * x2.sin()) / (x1 * x2)
                }
            }
        }
    }

    /// Refuses parameters Mitsuba would not render sensibly (non-positive sizes).
    pub fn validate(&self) -> Result<(), String> {
        let bad = |what: &str, v: f32| {
            Err(format!(
                "pixel filter {}: {what} must be positive and finite, got {v}",
                self.name()
            ))
        };
        match *self {
            FilterShape::Box { radius } | FilterShape::Tent { radius }
                if !(radius > 0.0 && radius.is_finite()) =>
            {
                bad("radius", radius)
            }
            FilterShape::Gaussian { stddev } if !(stddev > 0.0 && stddev.is_finite()) => {
                bad("stddev", stddev)
            }
            FilterShape::Mitchell { b, c } if !(b.is_finite() && c.is_finite()) => Err(format!(
                "pixel filter mitchell: B and C must be finite, got {b}, {c}"
            )),
            FilterShape::Lanczos { lobes: 0 } => bad("lobes", 0.0),
            _ => Ok(()),
        }
    }
}

/// Mitchell & Netravali (1988), eq. 8, for |x| = `a`.
fn mitchell_netravali(a: f64, b: f64, c: f64) -> f64 {
    let (a2, a3) = (a * a, a * a * a);
    let v = if a < 1.0 {
        (12.0 - 9.0 * b - 6.0 * c) * a3 + (-18.0 + 12.0 * b + 6.0 * c) * a2 + (6.0 - 2.0 * b)
    } else if a < 2.0 {
        (-b - 6.0 * c) * a3
            + (6.0 * b + 30.0 * c) * a2
            + (-12.0 * b - 48.0 * c) * a
            + (8.0 * b + 24.0 * c)
    } else {
        0.0
    };
    v / 6.0
}

/// Bins of the sampling table over [−r, r).
const BINS: usize = 512;
/// Simpson sub-intervals per bin (and per pixel width for the normalisers): the integrals are
/// accurate to ~1e-9 relative for the smooth pieces; kinks cost O(h²) locally.
const SUBSTEPS: usize = 16;

/// ∫_a^b f₁ by composite Simpson with `n` (even) intervals; `abs` integrates |f₁|.
fn integrate(shape: &FilterShape, a: f64, b: f64, n: usize, abs: bool) -> f64 {
    if !(b > a) {
        return 0.0;
    }
    let h = (b - a) / n as f64;
    let f = |x: f64| {
        let v = shape.eval(x);
        if abs {
            v.abs()
        } else {
            v
        }
    };
    let mut sum = f(a) + f(b);
    for i in 1..n {
        sum += f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    sum * h / 3.0
}

/// A filter ready for the film: its shape and the table camera rays sample offsets from.
#[derive(Clone, Debug)]
pub struct PixelFilter {
    shape: FilterShape,
    radius: f32,
    /// Bin masses of |f₁| over [−r, r) (empty for a box, sampled analytically).
    table: Distribution1D,
}

impl Default for PixelFilter {
    fn default() -> PixelFilter {
        PixelFilter::new(FilterShape::default()).expect("the default box is valid")
    }
}

impl PixelFilter {
    pub fn new(shape: FilterShape) -> Result<PixelFilter, String> {
        shape.validate()?;
        let radius = shape.radius();
        let table = if matches!(shape, FilterShape::Box { .. }) {
            Distribution1D::new(&[])
        } else {
            let r = radius as f64;
            let h = 2.0 * r / BINS as f64;
            let masses: Vec<f32> = (0..BINS)
                .map(|i| {
                    let a = -r + i as f64 * h;
                    integrate(&shape, a, a + h, SUBSTEPS, true) as f32
                })
                .collect();
            Distribution1D::new(&masses)
        };
        Ok(PixelFilter {
            shape,
            radius,
            table,
        })
    }

    pub fn shape(&self) -> FilterShape {
        self.shape
    }

    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// The box of radius ½: one uniform position per pixel and one pixel per splat, exactly the
    /// film this project had before filters.
    pub fn is_pixel_box(&self) -> bool {
        self.shape == FilterShape::Box { radius: 0.5 }
    }

    #[inline]
    pub fn eval(&self, x: f32) -> f32 {
        self.shape.eval(x as f64) as f32
    }

    /// An offset in [−r, r) from one uniform number, with f₁(offset) / p(offset): the 1-D filter
    /// importance sample (p ∝ |f₁| up to the table's resolution, and exactly the table's density).
    pub fn sample(&self, u: f32) -> (f32, f32) {
        let r = self.radius;
        if let FilterShape::Box { .. } = self.shape {
            // Uniform: p = 1 / 2r, f₁ = 1.
            return (-r + 2.0 * r * u, 2.0 * r);
        }
        let h = 2.0 * r / BINS as f32;
        let (i, pmf, v) = self.table.sample(u);
        let x = -r + (i as f32 + v) * h;
        let pdf = pmf / h;
        (x, self.eval(x) / pdf)
    }

    /// The density `sample` draws offsets with.
    pub fn pdf(&self, x: f32) -> f32 {
        let r = self.radius;
        if !(x >= -r && x < r) {
            return 0.0;
        }
        if let FilterShape::Box { .. } = self.shape {
            return 1.0 / (2.0 * r);
        }
        let h = 2.0 * r / BINS as f32;
        let i = (((x + r) / h) as usize).min(BINS - 1);
        self.table.pmf(i) / h
    }

    /// ∫ f₁ over [lo, hi] ∩ support (the film-clipped normaliser of one axis).
    pub fn integral(&self, lo: f64, hi: f64) -> f64 {
        let r = self.radius as f64;
        let (lo, hi) = (lo.max(-r), hi.min(r));
        if !(hi > lo) {
            return 0.0;
        }
        if let FilterShape::Box { .. } = self.shape {
            return hi - lo;
        }
        // Split at the integers inside (every kink of these filters sits on one: 0, ±1, ±2 …
        // in units of the radius for tent, which `SUBSTEPS` per unit covers closely enough).
        let mut sum = 0.0;
        let mut a = lo;
        while a < hi {
            let b = (a.floor() + 1.0).min(hi);
            let n = (SUBSTEPS * 8).max(2);
            sum += integrate(&self.shape, a, b, n, false);
            a = b;
        }
        sum
    }
}

/// A filter on a film of `width` × `height` pixels: the per-column and per-row normalisers Z.
#[derive(Clone, Debug, Default)]
pub struct FilmFilter {
    pub filter: PixelFilter,
    /// Z_x of each column and Z_y of each row: ∫ f₁ over the film around its centre.
    norm_x: Vec<f32>,
    norm_y: Vec<f32>,
}

/// Where a camera sample of a pixel went, and its weight f / (p Z).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilmSample {
    pub raster: crate::math::Vec2,
    pub weight: f32,
}

impl FilmFilter {
    pub fn new(filter: PixelFilter, width: u32, height: u32) -> FilmFilter {
        let norms = |n: u32| -> Vec<f32> {
            if filter.is_pixel_box() {
                return vec![1.0; n as usize];
            }
            (0..n)
                .map(|j| {
                    let c = j as f64 + 0.5;
                    filter.integral(-c, n as f64 - c) as f32
                })
                .collect()
        };
        FilmFilter {
            norm_x: norms(width),
            norm_y: norms(height),
            filter,
        }
    }

    pub fn width(&self) -> u32 {
        self.norm_x.len() as u32
    }

    pub fn height(&self) -> u32 {
        self.norm_y.len() as u32
    }

    /// The camera sample of pixel (x, y) from two uniform numbers; `None` when the offset left
    /// the film (the sample then contributes nothing). The box of radius ½ gives `x + u` with
    /// weight 1, bit for bit the unfiltered film.
    #[inline]
    pub fn sample_pixel(&self, x: u32, y: u32, u: crate::math::Vec2) -> Option<FilmSample> {
        use crate::math::Vec2;
        if self.filter.is_pixel_box() {
            return Some(FilmSample {
                raster: Vec2::new(x as f32 + u.x, y as f32 + u.y),
                weight: 1.0,
            });
        }
        let (dx, wx) = self.filter.sample(u.x);
        let (dy, wy) = self.filter.sample(u.y);
        let raster = Vec2::new(x as f32 + 0.5 + dx, y as f32 + 0.5 + dy);
        let (w, h) = (self.width() as f32, self.height() as f32);
        if !(raster.x >= 0.0 && raster.y >= 0.0 && raster.x < w && raster.y < h) {
            return None;
        }
        let weight = (wx / self.norm_x[x as usize]) * (wy / self.norm_y[y as usize]);
        Some(FilmSample { raster, weight })
    }

    /// Every pixel whose support covers raster point `p` (on the film), with weight
    /// f(p − c_j) / Z_j, in row-major order (a fixed order: splats stay deterministic).
    #[inline]
    pub fn for_each_splat(&self, p: crate::math::Vec2, mut add: impl FnMut(u32, f32)) {
        let (w, h) = (self.width(), self.height());
        if self.filter.is_pixel_box() {
            let x = (p.x as u32).min(w - 1);
            let y = (p.y as u32).min(h - 1);
            add(y * w + x, 1.0);
            return;
        }
        let r = self.filter.radius();
        // Pixels j with p − c_j ∈ [−r, r], i.e. j + ½ ∈ [p − r, p + r].
        let range = |c: f32, n: u32| {
            let lo = (c - r - 0.5).ceil().max(0.0) as u32;
            let hi = ((c + r - 0.5).floor() as i64).min(n as i64 - 1);
            (lo, hi)
        };
        let (x0, x1) = range(p.x, w);
        let (y0, y1) = range(p.y, h);
        if x1 < x0 as i64 || y1 < y0 as i64 {
            return;
        }
        for y in y0..=y1 as u32 {
            let fy = self.filter.eval(p.y - (y as f32 + 0.5)) / self.norm_y[y as usize];
            if fy == 0.0 {
                continue;
            }
            for x in x0..=x1 as u32 {
                let fx = self.filter.eval(p.x - (x as f32 + 0.5)) / self.norm_x[x as usize];
                if fx != 0.0 {
                    add(y * w + x, fx * fy);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec2;
    use crate::sampling::Sampler;

    type TestFn = Box<dyn Fn(f64) -> f64>;

    fn all_shapes() -> Vec<FilterShape> {
        vec![
            FilterShape::Box { radius: 0.5 },
            FilterShape::Box { radius: 1.3 },
            FilterShape::Tent { radius: 1.0 },
            FilterShape::Gaussian { stddev: 0.5 },
            FilterShape::Mitchell {
                b: 1.0 / 3.0,
                c: 1.0 / 3.0,
            },
            FilterShape::CatmullRom,
            FilterShape::Lanczos { lobes: 3 },
        ]
    }

    #[test]
    fn mitsuba_values() {
        // Spot values of Mitsuba 3's formulas.
        let g = FilterShape::Gaussian { stddev: 0.5 };
        let bias = (-8.0f64).exp();
        assert!((g.eval(0.0) - (1.0 - bias)).abs() < 1e-12);
        assert!((g.eval(0.5) - ((-0.5f64).exp() - bias)).abs() < 1e-12);
        assert_eq!(g.eval(2.0), 0.0);
        let m = FilterShape::Mitchell {
            b: 1.0 / 3.0,
            c: 1.0 / 3.0,
        };
        assert!((m.eval(0.0) - 8.0 / 9.0).abs() < 1e-7);
        assert!((m.eval(1.0) - 1.0 / 18.0).abs() < 1e-7);
        assert_eq!(m.eval(2.0), 0.0);
        assert!((FilterShape::CatmullRom.eval(0.0) - 1.0).abs() < 1e-12);
        assert!(FilterShape::CatmullRom.eval(1.0).abs() < 1e-12);
        let l = FilterShape::Lanczos { lobes: 3 };
        assert_eq!(l.eval(0.0), 1.0);
        assert!(l.eval(1.0).abs() < 1e-12 && l.eval(2.0).abs() < 1e-12);
        assert!(l.eval(1.5) < 0.0, "a negative lobe");
        assert_eq!(FilterShape::Tent { radius: 1.0 }.eval(0.25), 0.75);
    }

    /// The filter importance sample: E[w · g(X)] = ∫ f₁ g for test functions g (moments 0, 1, 2
    /// and an indicator), z-tested against the integral (Šidák over the 4 × 7 checks).
    #[test]
    fn sampled_offsets_integrate_the_filter() {
        let n = 200_000;
        // Two-sided tail 1e-3 / 28 per check.
        let z_max = 4.1;
        for shape in all_shapes() {
            let f = PixelFilter::new(shape).unwrap();
            let r = f.radius() as f64;
            let tests: [(&str, TestFn); 4] = [
                ("1", Box::new(|_| 1.0)),
                ("x", Box::new(|x| x)),
                ("x²", Box::new(|x| x * x)),
                (
                    "[0.2, 0.9)",
                    Box::new(|x| (0.2..0.9).contains(&x) as u8 as f64),
                ),
            ];
            for (name, g) in tests.iter() {
                // ∫ f₁ g by fine Simpson, split at the integers.
                let m = 20_000;
                let h = 2.0 * r / m as f64;
                let mut exact = 0.0;
                for i in 0..m {
                    let x = -r + (i as f64 + 0.5) * h;
                    exact += shape.eval(x) * g(x) * h;
                }
                let mut s = Sampler::new(11, 0, 0);
                let (mut sum, mut sum2) = (0.0f64, 0.0f64);
                for _ in 0..n {
                    let (x, w) = f.sample(s.next_f32());
                    assert!(x >= -r as f32 && x < r as f32);
                    let v = w as f64 * g(x as f64);
                    sum += v;
                    sum2 += v * v;
                }
                let mean = sum / n as f64;
                let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
                let z = (mean - exact) / se.max(1e-12);
                assert!(
                    z.abs() < z_max || (mean - exact).abs() < 1e-6,
                    "{shape:?} E[w {name}] = {mean} ± {se}, ∫ f₁ {name} = {exact} (z = {z:.2})"
                );
            }
        }
    }

    #[test]
    fn the_sampling_density_is_normalised() {
        for shape in all_shapes() {
            let f = PixelFilter::new(shape).unwrap();
            let r = f.radius();
            let m = 100_000;
            let h = 2.0 * r / m as f32;
            let total: f64 = (0..m)
                .map(|i| f.pdf(-r + (i as f32 + 0.5) * h) as f64 * h as f64)
                .sum();
            assert!((total - 1.0).abs() < 1e-3, "{shape:?}: ∫ p = {total}");
        }
    }

    #[test]
    fn the_pixel_box_is_the_unfiltered_film() {
        let film = FilmFilter::new(PixelFilter::default(), 7, 5);
        let u = Vec2::new(0.123_456_7, 0.999_999_9);
        let s = film.sample_pixel(3, 4, u).unwrap();
        assert_eq!(s.raster, Vec2::new(3.0 + u.x, 4.0 + u.y));
        assert_eq!(s.weight, 1.0);
        let mut got = vec![];
        film.for_each_splat(Vec2::new(6.99, 0.0), |i, w| got.push((i, w)));
        assert_eq!(got, vec![(6, 1.0)]);
    }

    /// A splat's weights over the pixels it reaches, summed against each pixel's Z, give back
    /// ∫ f over the film: Σ_j w_j Z_j = Σ_j f(p − c_j) for a point well inside.
    #[test]
    fn splat_weights_are_the_filter_over_the_normaliser() {
        for shape in all_shapes() {
            let film = FilmFilter::new(PixelFilter::new(shape).unwrap(), 16, 12);
            let p = Vec2::new(7.3, 5.8);
            let mut total = 0.0f64;
            film.for_each_splat(p, |i, w| {
                let (x, y) = (i % 16, i / 16);
                let z = film.norm_x[x as usize] as f64 * film.norm_y[y as usize] as f64;
                let f = shape.eval((p.x - (x as f32 + 0.5)) as f64)
                    * shape.eval((p.y - (y as f32 + 0.5)) as f64);
                assert!((w as f64 * z - f).abs() < 1e-5, "{shape:?} pixel {x},{y}");
                total += w as f64 * z;
            });
            assert!(total.is_finite());
        }
    }
}

//! An environment map (Mitsuba 3's `envmap`): radiance at infinity read from a latitude–longitude
//! image, sampled in proportion to its luminance.
//!
//! Conventions (Mitsuba 3.9's, so its scenes and reference images carry over): a local direction
//! d = (sin φ sin θ, cos θ, −cos φ sin θ) has image coordinates (u, v) = (φ / 2π, θ / π), +y is
//! the pole of row 0, and `to_world` rotates local directions into the scene. The lookup is
//! bilinear, texel-centred and periodic in u (column j's centre at u = (j + ½)/W) and
//! corner-aligned and clamped in v (row r at v = r / (H − 1), so the first and last rows are the
//! poles). Values are linear RGB times `scale`.
//!
//! Sampling (our own; only the variance depends on it): a piecewise-constant density over the
//! W × H cells of (u, v), each weighted by the largest luminance of its four bilinear corners
//! (the interpolant's maximum over the cell, so no cell where the map is non-zero gets density
//! zero) times the largest sin θ over the cell; uniform within a cell. With the cell's
//! probability P, pdf(u, v) = P · W · H and the solid-angle density is
//! pdf_ω = pdf(u, v) / (2π² sin θ) (dω = 2π² sin θ du dv). The row, then the column within it,
//! is drawn by inverting its CDF through a guide table (`guided_cdf`: O(1), the same texel as a
//! binary search), and a direction's (u, v) is computed once for both its pdf and its radiance
//! (`local_uv`).

mod guided_cdf;

use super::environment::{disk_pdf, distant_le};
use super::{LightLeSample, LightLiSample};
use crate::math::{luminance, Color, Vec2, Vec3, PI};
use crate::texture::TexPoint;
use glam::Mat3;
use guided_cdf::GuidedCdf;
use std::sync::Arc;

/// The image and its sampling distribution (shared by clones of the light).
#[derive(Debug)]
pub struct EnvironmentMap {
    width: usize,
    height: usize,
    /// Linear RGB texels, row by row from v = 0, already times `scale`.
    texels: Vec<Color>,
    /// Rotation from the map's local frame to the world, and back.
    to_world: Mat3,
    to_local: Mat3,
    /// Row choice, then the column within the row.
    rows: GuidedCdf,
    columns: Vec<GuidedCdf>,
}

impl EnvironmentMap {
    /// A map of `width` × `height` linear RGB texels (rows from the +y pole down) times `scale`,
    /// rotated by `to_world` (a rotation: its scale and shear are the caller's to refuse).
    pub fn new(
        width: usize,
        height: usize,
        texels: Vec<Color>,
        scale: f32,
        to_world: Mat3,
    ) -> Result<EnvironmentMap, String> {
        if width < 1 || height < 2 || texels.len() != width * height {
            return Err(format!(
                "an environment map needs at least 1 × 2 texels and one per pixel, got {width} × {height} with {}",
                texels.len()
            ));
        }
        if !(scale >= 0.0 && scale.is_finite()) {
            return Err(format!(
                "environment map scale must be finite and non-negative, got {scale}"
            ));
        }
        if let Some(bad) = texels
            .iter()
            .find(|c| !(c.min_element() >= 0.0 && c.is_finite()))
        {
            return Err(format!(
                "environment map texels must be finite and non-negative, found {bad}"
            ));
        }
        let texels: Vec<Color> = texels.into_iter().map(|c| c * scale).collect();
        let lum = |x: usize, y: usize| luminance(texels[y * width + x % width]);
        // Cell (i, j) spans columns' centres i−½ … i+½ (periodic) and rows j … j+1 of the
        // corner-aligned v grid scaled to H cells: its bilinear corners are the texels around it.
        let mut row_weights = Vec::with_capacity(height);
        let mut columns = Vec::with_capacity(height);
        for j in 0..height {
            // v range of cell row j: [j/H, (j+1)/H]; texel rows it interpolates between.
            let (v0, v1) = (j as f32 / height as f32, (j + 1) as f32 / height as f32);
            let r0 = (v0 * (height - 1) as f32).floor() as usize;
            let r1 = ((v1 * (height - 1) as f32).ceil() as usize).min(height - 1);
            let sin_max = if v0 <= 0.5 && v1 >= 0.5 {
                1.0
            } else {
                (PI * v0).sin().max((PI * v1).sin())
            };
            let weights: Vec<f32> = (0..width)
                .map(|i| {
                    // Columns i−1, i, i+1 cover the cell's u range [i/W, (i+1)/W] with
                    // texel-centred interpolation (centres at (k+½)/W).
                    let mut m = 0.0f32;
                    for x in [i + width - 1, i, i + 1] {
                        for y in r0..=r1 {
                            m = m.max(lum(x, y));
                        }
                    }
                    m * sin_max
                })
                .collect();
            let d = GuidedCdf::new(&weights);
            row_weights.push(d.total());
            columns.push(d);
        }
        let to_local = to_world.transpose();
        Ok(EnvironmentMap {
            width,
            height,
            texels,
            to_world,
            to_local,
            rows: GuidedCdf::new(&row_weights),
            columns,
        })
    }

    /// Texel (x, y) with x wrapped into the row; x ∈ [−1, W] (the lookup's corners): a compare
    /// instead of `rem_euclid`'s division.
    #[inline]
    fn texel(&self, x: i64, y: usize) -> Color {
        let w = self.width as i64;
        let x = if x < 0 {
            x + w
        } else if x >= w {
            x - w
        } else {
            x
        };
        self.texels[y * self.width + x as usize]
    }

    /// Radiance arriving from world direction `w` (pointing away from the scene).
    pub fn eval(&self, w: Vec3) -> Color {
        self.lookup(self.local_uv(w).uv)
    }

    /// (u, v) and sin θ of world direction `w` in the map's frame: the one conversion (two
    /// `atan2`) that `pdf` and `eval` of the same direction share.
    #[inline]
    fn local_uv(&self, w: Vec3) -> LocalUv {
        let d = (self.to_local * w).normalize();
        LocalUv {
            uv: unit_direction_to_uv(d),
            // sin θ from the direction itself: sin(π v) after atan2 would lose it near the poles.
            sin_theta: (d.x * d.x + d.z * d.z).sqrt(),
        }
    }

    /// Bilinear lookup: texel-centred and periodic in u, corner-aligned and clamped in v.
    fn lookup(&self, uv: Vec2) -> Color {
        let (w, h) = (self.width as f64, self.height as f64);
        let x = (uv.x as f64 - floor(uv.x as f64)) * w - 0.5;
        let y = (uv.y as f64).clamp(0.0, 1.0) * (h - 1.0);
        let (x0, y0) = (floor(x), floor(y).min(h - 2.0));
        let (tx, ty) = ((x - x0) as f32, (y - y0) as f32);
        let (x0, y0) = (x0 as i64, y0 as usize);
        let top = self.texel(x0, y0) * (1.0 - tx) + self.texel(x0 + 1, y0) * tx;
        let bottom = self.texel(x0, y0 + 1) * (1.0 - tx) + self.texel(x0 + 1, y0 + 1) * tx;
        top * (1.0 - ty) + bottom * ty
    }

    /// A world direction (away from the scene) with its solid-angle pdf, or None for a black map.
    pub fn sample(&self, u: Vec2) -> Option<(Vec3, f32)> {
        self.sample_with_radiance(u).map(|(w, pdf, _)| (w, pdf))
    }

    /// `sample`, with the radiance from the sampled direction (`eval`), both read from one
    /// (u, v) of the direction.
    pub fn sample_with_radiance(&self, u: Vec2) -> Option<(Vec3, f32, Color)> {
        if self.rows.is_empty() {
            return None;
        }
        let (j, p_row, uy) = self.rows.sample(u.y);
        // A row of zero weight is drawn only where rounding leaves a sliver of the CDF to it
        // (u.y just below 1 before a trailing black row): no direction of density there, and
        // its column distribution is empty.
        if !(p_row > 0.0) {
            return None;
        }
        let (i, _, ux) = self.columns[j].sample(u.x);
        let uv = Vec2::new(
            (i as f32 + ux) / self.width as f32,
            (j as f32 + uy) / self.height as f32,
        );
        let (local, sin_theta) = uv_to_direction_and_sin(uv);
        if !(sin_theta > 0.0) {
            return None;
        }
        // The density is `pdf` of the direction (p_row · p_col · W · H / (2π² sin θ) with sin θ
        // from the direction, computed as `pdf` computes it, bit for bit), not that product with
        // sin(π v): next-event estimation and a BSDF sample reaching the same direction must weigh
        // it with the same number (the two differed by 3e-7 relative). Only where rounding moves a
        // sample across a cell edge is that the neighbour cell's density.
        let w = self.to_world * local;
        let at = self.local_uv(w);
        let pdf = self.pdf_at(at);
        (pdf > 0.0 && pdf.is_finite()).then(|| (w, pdf, self.lookup(at.uv)))
    }

    /// Solid-angle pdf of `sample` returning world direction `w`.
    pub fn pdf(&self, w: Vec3) -> f32 {
        if self.rows.is_empty() {
            return 0.0;
        }
        self.pdf_at(self.local_uv(w))
    }

    /// `pdf` of the direction at `at` (a non-empty map).
    #[inline]
    fn pdf_at(&self, at: LocalUv) -> f32 {
        let LocalUv { uv, sin_theta } = at;
        if !(sin_theta > 0.0) {
            return 0.0;
        }
        let i = ((uv.x * self.width as f32) as usize).min(self.width - 1);
        let j = ((uv.y * self.height as f32) as usize).min(self.height - 1);
        let pdf_uv = self.rows.pmf(j) * self.columns[j].pmf(i) * (self.width * self.height) as f32;
        pdf_uv / (2.0 * PI * PI * sin_theta)
    }

    /// ∫ luminance(L(ω)) dω over the sphere, by the midpoint rule on a grid twice as fine as the
    /// texels (the light's power: what light selection weighs it by; its accuracy only moves
    /// the selection probabilities).
    pub fn integral(&self) -> f32 {
        self.integral_on_grid(2)
    }

    /// `integral` on a grid `k` times as fine as the texels in each direction.
    fn integral_on_grid(&self, k: usize) -> f32 {
        let (nu, nv) = (k * self.width, k * self.height);
        let mut sum = 0.0f64;
        for j in 0..nv {
            let v = (j as f32 + 0.5) / nv as f32;
            let sin_theta = (PI * v).sin() as f64;
            for i in 0..nu {
                let u = (i as f32 + 0.5) / nu as f32;
                sum += luminance(self.lookup(Vec2::new(u, v))) as f64 * sin_theta;
            }
        }
        (sum * 2.0 * (PI as f64) * (PI as f64) / (nu * nv) as f64) as f32
    }
}

/// A direction's map coordinates and sin θ (`EnvironmentMap::local_uv`).
#[derive(Clone, Copy)]
struct LocalUv {
    uv: Vec2,
    sin_theta: f32,
}

/// (u, v) of a local direction (Mitsuba's latitude–longitude convention, module docs).
#[cfg(test)]
fn direction_to_uv(d: Vec3) -> Vec2 {
    unit_direction_to_uv(d.normalize())
}

/// `direction_to_uv` of a unit direction.
#[inline]
fn unit_direction_to_uv(d: Vec3) -> Vec2 {
    // atan2 ∈ [−π, π], so u ∈ [−½, ½] before the wrap: u − ⌊u⌋ is u + 1 below zero, else u + 0
    // (which also turns −0 into +0, as u − ⌊u⌋ does) — the same bits without a libm floor.
    let u = d.x.atan2(-d.z) * (0.5 / PI);
    let u = if u < 0.0 { u + 1.0 } else { u + 0.0 };
    // θ by atan2, well conditioned at the poles where acos(y) is not.
    let theta = (d.x * d.x + d.z * d.z).sqrt().atan2(d.y);
    Vec2::new(u, theta / PI)
}

/// ⌊x⌋ for |x| < 2⁶³ by truncation (a libm call otherwise, without SSE4.1's `roundsd`): the
/// lookup's texel corners, the same values as `f64::floor`.
#[inline]
fn floor(x: f64) -> f64 {
    let t = x as i64 as f64;
    if t > x {
        t - 1.0
    } else {
        t
    }
}

#[cfg(test)]
fn uv_to_direction(uv: Vec2) -> Vec3 {
    uv_to_direction_and_sin(uv).0
}

/// The local direction at (u, v), and sin θ = sin(π v).
#[inline]
fn uv_to_direction_and_sin(uv: Vec2) -> (Vec3, f32) {
    let (sin_t, cos_t) = (PI * uv.y).sin_cos();
    let (sin_p, cos_p) = (2.0 * PI * uv.x).sin_cos();
    (Vec3::new(sin_p * sin_t, cos_t, -cos_p * sin_t), sin_t)
}

/// The light: an `EnvironmentMap` shared by clones.
#[derive(Clone, Debug)]
pub struct EnvironmentMapLight {
    pub map: Arc<EnvironmentMap>,
}

impl EnvironmentMapLight {
    pub fn sample_li(&self, u: Vec2) -> Option<LightLiSample> {
        let (wi, pdf_w, radiance) = self.map.sample_with_radiance(u)?;
        Some(LightLiSample {
            uv: TexPoint::default(),
            p_err: Vec3::ZERO,
            wi,
            p: wi,
            n: -wi,
            distance: f32::INFINITY,
            radiance,
            pdf_w,
            delta: false,
        })
    }

    pub fn pdf_li(&self, wi: Vec3) -> f32 {
        self.map.pdf(wi)
    }

    pub fn escaped(&self, dir: Vec3) -> Color {
        self.map.eval(dir)
    }

    pub fn sample_le(
        &self,
        u_pos: Vec2,
        u_dir: Vec2,
        bounds: (Vec3, f32),
    ) -> Option<LightLeSample> {
        let (w, pdf_dir, radiance) = self.map.sample_with_radiance(u_dir)?;
        Some(distant_le(-w, u_pos, bounds, radiance, pdf_dir))
    }

    /// (area pdf on the bounding disk, solid-angle pdf) of light travelling in direction `dir`.
    pub fn pdf_le(&self, dir: Vec3, bounds: (Vec3, f32)) -> (f32, f32) {
        (disk_pdf(bounds), self.map.pdf(-dir))
    }

    pub fn power(&self, bounds: (Vec3, f32)) -> f32 {
        PI * bounds.1 * bounds.1 * self.map.integral()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Sampler;

    fn map(scale: f32, to_world: Mat3) -> EnvironmentMap {
        // 8 × 5 texels: a dim sky with one bright texel and a black row.
        let (w, h) = (8, 5);
        let texels = (0..w * h)
            .map(|k| match k {
                11 => Color::new(40.0, 30.0, 10.0),
                k if k / w == 3 => Color::ZERO,
                k => Color::new(0.2 + 0.05 * (k % w) as f32, 0.3, 0.25),
            })
            .collect();
        EnvironmentMap::new(w, h, texels, scale, to_world).unwrap()
    }

    #[test]
    fn uv_and_direction_are_inverse_and_mitsubas() {
        // Mitsuba: u = 0.25 is +x at the horizon, v = 0 is +y, u = 0 is −z.
        assert!((uv_to_direction(Vec2::new(0.25, 0.5)) - Vec3::X).length() < 1e-6);
        assert!((uv_to_direction(Vec2::new(0.0, 0.0)) - Vec3::Y).length() < 1e-6);
        assert!((uv_to_direction(Vec2::new(0.0, 0.5)) + Vec3::Z).length() < 1e-6);
        for uv in [
            Vec2::new(0.1, 0.3),
            Vec2::new(0.8, 0.9),
            Vec2::new(0.55, 0.02),
        ] {
            let back = direction_to_uv(uv_to_direction(uv));
            assert!((back - uv).length() < 1e-5, "{uv} -> {back}");
        }
    }

    #[test]
    fn lookup_is_texel_centred_in_u_and_corner_aligned_in_v() {
        let m = map(1.0, Mat3::IDENTITY);
        // Texel (3, 1): u centre (3.5)/8, v = 1/4.
        let c = m.lookup(Vec2::new(3.5 / 8.0, 0.25));
        assert!((c - m.texels[8 + 3]).length() < 1e-6, "{c}");
        // Periodic between the last and the first column (u = 0 is halfway).
        let wrap = m.lookup(Vec2::new(0.0, 0.0));
        assert!((wrap - (m.texels[0] + m.texels[7]) * 0.5).length() < 1e-6);
        // The last row sits at v = 1.
        assert!((m.lookup(Vec2::new(0.5 / 8.0, 1.0)) - m.texels[32]).length() < 1e-6);
    }

    /// Mitsuba 3.9.1's `envmap` itself: an 8 × 5 bitmap whose texel (x, y) is
    /// (x + 1 + y/10, 10 (y + 1), 100 + (7x + 3y) mod 11), `to_world` a rotation by 37° about
    /// (0.3, 1, −0.2) normalised, evaluated with `emitter.eval(si)` (si.wi = −w) by its Python
    /// package for six world directions w (one 0.0057° from the pole): our lookup, to_world and
    /// axis conventions give the same radiance.
    #[test]
    fn eval_is_mitsubas() {
        let (w, h) = (8, 5);
        let texels = (0..w * h)
            .map(|k| {
                let (x, y) = ((k % w) as f32, (k / w) as f32);
                Color::new(
                    x + 1.0 + 0.1 * y,
                    10.0 * (y + 1.0),
                    100.0 + ((7 * (k % w) + 3 * (k / w)) % 11) as f32,
                )
            })
            .collect();
        // Mitsuba's matrix, rows.
        let rows = [
            [0.814_673_4, 0.166_687_6, 0.555_448],
            [-0.059_768_38, 0.976_834_2, -0.205_481_7],
            [-0.576_831_9, 0.134_202_24, 0.805_763_4],
        ];
        let to_world = Mat3::from_cols_array_2d(&rows).transpose();
        let m = EnvironmentMap::new(w, h, texels, 1.0, to_world).unwrap();
        for (d, mitsuba) in [
            (
                Vec3::new(0.303_045_77, 0.505_076_3, -0.808_122),
                Color::new(1.738_972_8, 24.263_742, 105.656_6),
            ),
            (
                Vec3::new(-0.952_579_3, 0.136_082_77, 0.272_165_5),
                Color::new(7.137_357, 29.864_11, 104.204_37),
            ),
            (
                Vec3::new(0.050_186_03, -0.993_683_4, 0.100_372_07),
                Color::new(4.687_71, 45.909_19, 104.094_22),
            ),
            (
                Vec3::new(0.904_534, 0.301_511_35, 0.301_511_35),
                Color::new(3.778_326_7, 23.541_647, 104.490_85),
            ),
            (
                Vec3::new(0.0, 1.0, 1e-4),
                Color::new(7.053_517, 12.745_141, 105.127_87),
            ),
            (
                Vec3::new(-0.199_007_44, -0.398_014_87, -0.895_533_5),
                Color::new(1.367_442_6, 37.295_567, 107.810_72),
            ),
        ] {
            let ours = m.eval(d);
            assert!(
                ((ours - mitsuba) / mitsuba).abs().max_element() < 2e-4,
                "{d}: {ours} vs Mitsuba {mitsuba}"
            );
        }
    }

    /// The solid-angle pdf integrates to one, `sample` reports it (its pdf and radiance are `pdf`
    /// and `eval` at the sampled direction, bit for bit), and every direction where the map is
    /// non-zero has density: the estimate ∫ L dω ≈ mean(L / pdf) agrees with the quadrature
    /// within its standard error. (`sample` draws from that pdf: `sampling_passes_chi2`.)
    #[test]
    fn sampling_density_is_the_pdf_and_covers_the_map() {
        let rot = Mat3::from_rotation_y(0.7) * Mat3::from_rotation_x(-0.4);
        let m = map(2.0, rot);
        let mut s = Sampler::new(17, 0, 0);
        let n = 400_000;
        let (mut sum_pdf, mut sum_pdf2, mut est, mut est2) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for _ in 0..n {
            // Uniform sphere directions: ∫ pdf dω = 4π · mean(pdf).
            let w = crate::sampling::sample_uniform_sphere(s.next_2d());
            let p = 4.0 * std::f64::consts::PI * m.pdf(w) as f64;
            sum_pdf += p;
            sum_pdf2 += p * p;
            let (d, pdf, radiance) = m.sample_with_radiance(s.next_2d()).unwrap();
            assert_eq!(pdf.to_bits(), m.pdf(d).to_bits(), "pdf at {d}");
            assert_eq!(radiance, m.eval(d), "radiance at {d}");
            let x = luminance(radiance) as f64 / pdf as f64;
            est += x;
            est2 += x * x;
        }
        // Two comparisons at a family-wise 1e-4 (Šidák): |z| < 3.89 each.
        let z_max = 3.89;
        let mean_pdf = sum_pdf / n as f64;
        let se_pdf = ((sum_pdf2 / n as f64 - mean_pdf * mean_pdf) / n as f64).sqrt();
        assert!(
            (mean_pdf - 1.0).abs() < z_max * se_pdf,
            "∫ pdf dω = {mean_pdf} ± {se_pdf}"
        );
        let mean = est / n as f64;
        let se = ((est2 / n as f64 - mean * mean) / n as f64).sqrt();
        // A quadrature 32 times finer than the texels: its error is far below the sampling's.
        let exact = m.integral_on_grid(32) as f64;
        assert!(
            (mean - exact).abs() < z_max * se,
            "∫ L dω: sampled {mean} ± {se}, quadrature {exact}"
        );
    }

    /// Directions charted by the map's own (u, v), two bins per cell edge each way, so the
    /// sampling density (constant per cell in (u, v)) has its jumps on bin edges and each cell's
    /// uniform remap is tested too: dω = 2π² sin(π v) du dv.
    struct UvChart {
        to_world: Mat3,
        u_edges: Vec<f64>,
        v_edges: Vec<f64>,
    }

    impl crate::testing::chi2::Chart for UvChart {
        fn a_edges(&self) -> &[f64] {
            &self.u_edges
        }
        fn b_edges(&self) -> &[f64] {
            &self.v_edges
        }
        fn direction(&self, u: f64, v: f64) -> (Vec3, f64) {
            let w = self.to_world * uv_to_direction(Vec2::new(u as f32, v as f32));
            let pi = std::f64::consts::PI;
            (w, 2.0 * pi * pi * (pi * v).sin())
        }
        fn coords(&self, w: Vec3) -> Option<(f64, f64)> {
            let uv = direction_to_uv(self.to_world.transpose() * w);
            Some((uv.x as f64, uv.y as f64))
        }
        fn covers_sphere(&self) -> bool {
            true
        }
    }

    /// Pearson's χ² of `sample`'s directions against `pdf` on the rotated 8 × 5 map (a black
    /// row, one bright texel), binned half a cell wide: the texel each draw picks (the guide
    /// tables' inversion) and where within it. Planted errors it rejects (p < 1e-12): the guide
    /// walk that never steps up from its slice's start; every draw put at its cell's centre.
    #[test]
    fn sampling_passes_chi2() {
        use crate::testing::chi2;
        let rot = Mat3::from_rotation_y(0.7) * Mat3::from_rotation_x(-0.4);
        let m = map(2.0, rot);
        let edges = |n: usize| (0..=2 * n).map(|k| k as f64 / (2 * n) as f64).collect();
        let chart = UvChart {
            to_world: rot,
            u_edges: edges(m.width),
            v_edges: edges(m.height),
        };
        let cfg = chi2::Chi2Test {
            samples: 200_000,
            seed: 11,
        };
        let outcome = chi2::run(
            "envmap",
            cfg,
            &chart,
            |s| m.sample(s.next_2d()).map(|(w, _)| w),
            |w| m.pdf(w),
        );
        outcome.check(1e-4).unwrap();
        outcome.check_mass().unwrap();
    }
}

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
//! pdf_ω = pdf(u, v) / (2π² sin θ) (dω = 2π² sin θ du dv).

use super::environment::{disk_pdf, distant_le};
use super::{LightLeSample, LightLiSample};
use crate::math::{luminance, Color, Vec2, Vec3, PI};
use crate::sampling::Distribution1D;
use crate::texture::TexPoint;
use glam::Mat3;
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
    rows: Distribution1D,
    columns: Vec<Distribution1D>,
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
            let d = Distribution1D::new(&weights);
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
            rows: Distribution1D::new(&row_weights),
            columns,
        })
    }

    #[inline]
    fn texel(&self, x: i64, y: usize) -> Color {
        self.texels[y * self.width + x.rem_euclid(self.width as i64) as usize]
    }

    /// Radiance arriving from world direction `w` (pointing away from the scene).
    pub fn eval(&self, w: Vec3) -> Color {
        let uv = direction_to_uv(self.to_local * w);
        self.lookup(uv)
    }

    /// Bilinear lookup: texel-centred and periodic in u, corner-aligned and clamped in v.
    fn lookup(&self, uv: Vec2) -> Color {
        let (w, h) = (self.width as f64, self.height as f64);
        let x = (uv.x as f64 - (uv.x as f64).floor()) * w - 0.5;
        let y = (uv.y as f64).clamp(0.0, 1.0) * (h - 1.0);
        let (x0, y0) = (x.floor(), y.floor().min(h - 2.0));
        let (tx, ty) = ((x - x0) as f32, (y - y0) as f32);
        let (x0, y0) = (x0 as i64, y0 as usize);
        let top = self.texel(x0, y0) * (1.0 - tx) + self.texel(x0 + 1, y0) * tx;
        let bottom = self.texel(x0, y0 + 1) * (1.0 - tx) + self.texel(x0 + 1, y0 + 1) * tx;
        top * (1.0 - ty) + bottom * ty
    }

    /// A world direction (away from the scene) with its solid-angle pdf, or None for a black map.
    pub fn sample(&self, u: Vec2) -> Option<(Vec3, f32)> {
        if self.rows.is_empty() {
            return None;
        }
        let (j, _, uy) = self.rows.sample(u.y);
        let (i, _, ux) = self.columns[j].sample(u.x);
        let uv = Vec2::new(
            (i as f32 + ux) / self.width as f32,
            (j as f32 + uy) / self.height as f32,
        );
        if !((PI * uv.y).sin() > 0.0) {
            return None;
        }
        // The density is `pdf` of the direction (p_row · p_col · W · H / (2π² sin θ) with sin θ
        // from the direction), not that product with sin(π v): next-event estimation and a BSDF
        // sample reaching the same direction must weigh it with the same number (the two differed
        // by 3e-7 relative). Only where rounding moves a sample across a cell edge does it report
        // the neighbour's density (the unit test below counts those).
        let w = self.to_world * uv_to_direction(uv);
        let pdf = self.pdf(w);
        (pdf > 0.0 && pdf.is_finite()).then_some((w, pdf))
    }

    /// Solid-angle pdf of `sample` returning world direction `w`.
    pub fn pdf(&self, w: Vec3) -> f32 {
        if self.rows.is_empty() {
            return 0.0;
        }
        let d = (self.to_local * w).normalize();
        let uv = direction_to_uv(d);
        // sin θ from the direction itself: sin(π v) after acos would lose it near the poles.
        let sin_theta = (d.x * d.x + d.z * d.z).sqrt();
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

/// (u, v) of a local direction (Mitsuba's latitude–longitude convention, module docs).
#[inline]
fn direction_to_uv(d: Vec3) -> Vec2 {
    let d = d.normalize();
    let u = d.x.atan2(-d.z) * (0.5 / PI);
    // θ by atan2, well conditioned at the poles where acos(y) is not.
    let theta = (d.x * d.x + d.z * d.z).sqrt().atan2(d.y);
    Vec2::new(u - u.floor(), theta / PI)
}

#[inline]
fn uv_to_direction(uv: Vec2) -> Vec3 {
    let (sin_t, cos_t) = (PI * uv.y).sin_cos();
    let (sin_p, cos_p) = (2.0 * PI * uv.x).sin_cos();
    Vec3::new(sin_p * sin_t, cos_t, -cos_p * sin_t)
}

/// The light: an `EnvironmentMap` shared by clones.
#[derive(Clone, Debug)]
pub struct EnvironmentMapLight {
    pub map: Arc<EnvironmentMap>,
}

impl EnvironmentMapLight {
    pub fn sample_li(&self, u: Vec2) -> Option<LightLiSample> {
        let (wi, pdf_w) = self.map.sample(u)?;
        let radiance = self.map.eval(wi);
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
        let (w, pdf_dir) = self.map.sample(u_dir)?;
        Some(distant_le(-w, u_pos, bounds, self.map.eval(w), pdf_dir))
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

    /// The solid-angle pdf integrates to one, `sample` draws from it (its pdf is `pdf` at the
    /// sampled direction), and every direction where the map is non-zero has density: the
    /// estimate ∫ L dω ≈ mean(L / pdf) agrees with the quadrature within its standard error.
    #[test]
    fn sampling_density_is_the_pdf_and_covers_the_map() {
        let rot = Mat3::from_rotation_y(0.7) * Mat3::from_rotation_x(-0.4);
        let m = map(2.0, rot);
        let mut s = Sampler::new(17, 0, 0);
        let n = 400_000;
        let (mut sum_pdf, mut sum_pdf2, mut est, mut est2) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        let mut other_cell = 0;
        for _ in 0..n {
            // Uniform sphere directions: ∫ pdf dω = 4π · mean(pdf).
            let w = crate::sampling::sample_uniform_sphere(s.next_2d());
            let p = 4.0 * std::f64::consts::PI * m.pdf(w) as f64;
            sum_pdf += p;
            sum_pdf2 += p * p;
            let (d, pdf) = m.sample(s.next_2d()).unwrap();
            // The direction's own cell gives the same pdf, bar rounding; at a cell's edge the
            // round trip uv → direction → uv may land in the neighbour (counted, must be rare).
            if (pdf / m.pdf(d) - 1.0).abs() > 1e-3 {
                other_cell += 1;
            }
            let x = luminance(m.eval(d)) as f64 / pdf as f64;
            est += x;
            est2 += x * x;
        }
        assert!(
            other_cell * 10_000 < n,
            "{other_cell} of {n} samples disagree with pdf()"
        );
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
}

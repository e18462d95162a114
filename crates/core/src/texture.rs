//! Textures: a colour (or a scalar, read from the first channel) that varies over a surface with
//! its (u, v) parameterisation, as Mitsuba 3 defines them: `bitmap` (an image, linear RGB texels,
//! looked up with `filter_type` nearest or bilinear and a `wrap_mode`), `checkerboard`, and the
//! constant case every untextured parameter is. Decoding image files is not the core's job
//! (`lt-scene-io` hands a `Bitmap` its texels).
//!
//! Conventions (Mitsuba 3's): `to_uv` maps the surface's uv first; uv (0, 0) is the top-left
//! corner of the image's first row of texels and v grows downwards through the rows; texel
//! centres sit at half-integer positions of uv · (width, height).

use crate::math::{luminance, Color, Vec2};
use std::sync::Arc;

/// How coordinates outside [0, 1) are brought back (Mitsuba's `wrap_mode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WrapMode {
    Repeat,
    Mirror,
    Clamp,
}

/// How a bitmap is read between texel centres (Mitsuba's `filter_type`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FilterType {
    Nearest,
    Bilinear,
}

/// A 2-D affine map of texture coordinates (Mitsuba's `to_uv`): uv' = m · uv + t.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    /// Rows of the 2 × 2 linear part.
    pub m: [[f32; 2]; 2],
    pub t: Vec2,
}

impl UvTransform {
    pub const IDENTITY: UvTransform = UvTransform {
        m: [[1.0, 0.0], [0.0, 1.0]],
        t: Vec2::ZERO,
    };

    #[inline]
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        Vec2::new(
            self.m[0][0] * uv.x + self.m[0][1] * uv.y + self.t.x,
            self.m[1][0] * uv.x + self.m[1][1] * uv.y + self.t.y,
        )
    }
}

/// An image of linear RGB texels, row by row from the top.
#[derive(Clone, Debug)]
pub struct Bitmap {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<Color>,
    pub filter: FilterType,
    pub wrap: WrapMode,
    pub to_uv: UvTransform,
}

impl Bitmap {
    /// The texel at integer coordinates, wrapped into the image.
    #[inline]
    fn texel(&self, x: i64, y: i64) -> Color {
        let x = wrap_index(x, self.width, self.wrap);
        let y = wrap_index(y, self.height, self.wrap);
        self.texels[y * self.width + x]
    }

    pub fn eval(&self, uv: Vec2) -> Color {
        let uv = self.to_uv.apply(uv);
        // Continuous texel coordinates whose integer + ½ points are texel centres.
        let (x, y) = (
            uv.x as f64 * self.width as f64,
            uv.y as f64 * self.height as f64,
        );
        match self.filter {
            FilterType::Nearest => self.texel(x.floor() as i64, y.floor() as i64),
            FilterType::Bilinear => {
                let (fx, fy) = (x - 0.5, y - 0.5);
                let (x0, y0) = (fx.floor(), fy.floor());
                let (tx, ty) = ((fx - x0) as f32, (fy - y0) as f32);
                let (x0, y0) = (x0 as i64, y0 as i64);
                let top = self.texel(x0, y0) * (1.0 - tx) + self.texel(x0 + 1, y0) * tx;
                let bottom = self.texel(x0, y0 + 1) * (1.0 - tx) + self.texel(x0 + 1, y0 + 1) * tx;
                top * (1.0 - ty) + bottom * ty
            }
        }
    }

    /// Gradient of the texture's scalar value (luminance, as Mitsuba's `eval_1_grad` reads an RGB
    /// bitmap) with respect to the surface's (u, v): the exact derivative of the bilinear
    /// interpolant in texel units, carried back through `to_uv` by its transpose and then scaled
    /// by the resolution, in Mitsuba 3.9's order (the exact chain rule scales before the
    /// transpose; the two agree for square images or a diagonal `to_uv`); zero for nearest
    /// lookups (their gradient is zero almost everywhere). Bump mapping reads it.
    pub fn grad(&self, uv: Vec2) -> Vec2 {
        if self.filter == FilterType::Nearest {
            return Vec2::ZERO;
        }
        let uv = self.to_uv.apply(uv);
        let (fx, fy) = (
            uv.x as f64 * self.width as f64 - 0.5,
            uv.y as f64 * self.height as f64 - 0.5,
        );
        let (x0, y0) = (fx.floor(), fy.floor());
        let (tx, ty) = ((fx - x0) as f32, (fy - y0) as f32);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let l = |x, y| luminance(self.texel(x, y));
        let (f00, f10, f01, f11) = (l(x0, y0), l(x0 + 1, y0), l(x0, y0 + 1), l(x0 + 1, y0 + 1));
        // ∂f/∂x and ∂f/∂y of f = (1−ty)((1−tx) f00 + tx f10) + ty((1−tx) f01 + tx f11).
        let dx = (1.0 - ty) * (f10 - f00) + ty * (f11 - f01);
        let dy = (1.0 - tx) * (f01 - f00) + tx * (f11 - f10);
        let m = &self.to_uv.m;
        Vec2::new(
            (m[0][0] * dx + m[1][0] * dy) * self.width as f32,
            (m[0][1] * dx + m[1][1] * dy) * self.height as f32,
        )
    }

    /// Mean of the texels (a light's power, a material's average albedo).
    pub fn mean(&self) -> Color {
        let sum: glam::DVec3 = self.texels.iter().map(|c| c.as_dvec3()).sum();
        (sum / self.texels.len().max(1) as f64).as_vec3()
    }
}

/// An integer coordinate brought into [0, n) by the wrap mode.
#[inline]
fn wrap_index(i: i64, n: usize, wrap: WrapMode) -> usize {
    let n = n as i64;
    let j = match wrap {
        WrapMode::Repeat => i.rem_euclid(n),
        WrapMode::Clamp => i.clamp(0, n - 1),
        WrapMode::Mirror => {
            let k = i.rem_euclid(2 * n);
            if k < n {
                k
            } else {
                2 * n - 1 - k
            }
        }
    };
    j as usize
}

/// Where a texture is read: the point's texture coordinates and, when its material reads a mesh
/// attribute, that attribute's value there (zero otherwise). The hit fills `attr` only for
/// materials that ask (`Material::mesh_attribute`), so other scenes pay nothing for it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TexPoint {
    pub uv: Vec2,
    pub attr: Color,
}

impl TexPoint {
    /// A point known by its texture coordinates only.
    #[inline]
    pub fn at(uv: Vec2) -> TexPoint {
        TexPoint {
            uv,
            attr: Color::ZERO,
        }
    }
}

/// True on a checkerboard's `color0` squares as `eval` reads it: ⌊2u⌋ + ⌊2v⌋ even (uv after
/// `to_uv`).
#[inline]
fn checker_parity(uv: Vec2) -> bool {
    let (a, b) = ((uv.x * 2.0).floor() as i64, (uv.y * 2.0).floor() as i64);
    (a + b).rem_euclid(2) == 0
}

#[derive(Clone, Debug)]
pub enum Texture {
    Constant(Color),
    Bitmap(Arc<Bitmap>),
    /// Mitsuba's `checkerboard`: `color0` where ⌊2u⌋ + ⌊2v⌋ is even (after `to_uv`), else
    /// `color1` — read as a colour; read as a scalar the squares swap (see `eval_scalar`).
    Checkerboard {
        color0: Color,
        color1: Color,
        to_uv: UvTransform,
    },
    /// Mitsuba's `mesh_attribute`: a per-vertex (`vertex_<name>`, interpolated barycentrically)
    /// or per-face (`face_<name>`, constant over the face) quantity the mesh file carries. The
    /// value arrives in `TexPoint::attr`; a material reads at most one attribute.
    MeshAttribute {
        name: Arc<str>,
    },
}

impl Texture {
    #[inline]
    pub fn eval(&self, at: TexPoint) -> Color {
        let uv = at.uv;
        match self {
            Texture::Constant(c) => *c,
            Texture::MeshAttribute { .. } => at.attr,
            Texture::Bitmap(b) => b.eval(uv),
            Texture::Checkerboard {
                color0,
                color1,
                to_uv,
            } => {
                if checker_parity(to_uv.apply(uv)) {
                    *color0
                } else {
                    *color1
                }
            }
        }
    }

    /// The value as one number, as Mitsuba's `eval_1` reads it wherever a parameter is a scalar
    /// (roughness, opacity, a blend's weight): a colour's luminance, except that a checkerboard
    /// read this way puts `color1` where `eval` puts `color0` — Mitsuba keeps that "legacy scalar
    /// checkerboard convention" in `eval_1`, and its reference images depend on it
    /// (`textured_roughconductor`: 83.8 % of pixels pass with one phase, ≥ 99.6 % with the other).
    #[inline]
    pub fn eval_scalar(&self, at: TexPoint) -> f32 {
        match self {
            Texture::Checkerboard {
                color0,
                color1,
                to_uv,
            } => luminance(if checker_parity(to_uv.apply(at.uv)) {
                *color1
            } else {
                *color0
            }),
            _ => luminance(self.eval(at)),
        }
    }

    /// Gradient of the scalar value with respect to (u, v) (see `Bitmap::grad`); zero where the
    /// texture is piecewise constant.
    pub fn grad(&self, uv: Vec2) -> Vec2 {
        match self {
            Texture::Bitmap(b) => b.grad(uv),
            Texture::Constant(_) | Texture::Checkerboard { .. } | Texture::MeshAttribute { .. } => {
                Vec2::ZERO
            }
        }
    }

    /// The mean value (Mitsuba's `Texture::mean`: a checkerboard's two colours weigh equally).
    pub fn mean(&self) -> Color {
        match self {
            Texture::Constant(c) => *c,
            Texture::Bitmap(b) => b.mean(),
            Texture::Checkerboard { color0, color1, .. } => 0.5 * (*color0 + *color1),
            // Unknown before a mesh is at hand: the middle of [0, 1].
            Texture::MeshAttribute { .. } => Color::splat(0.5),
        }
    }

    /// The value at `at` as a fraction: `eval_scalar` clamped to [0, 1] (how Mitsuba reads a
    /// mask's opacity and a blend's weight).
    #[inline]
    pub fn fraction(&self, at: TexPoint) -> f32 {
        self.eval_scalar(at).clamp(0.0, 1.0)
    }

    /// The mesh attribute the texture reads, if it is one.
    pub fn mesh_attribute(&self) -> Option<&str> {
        match self {
            Texture::MeshAttribute { name } => Some(name),
            _ => None,
        }
    }

    /// The largest value the texture takes (for checks such as reflectance ≤ 1).
    pub fn max_value(&self) -> f32 {
        match self {
            Texture::Constant(c) => c.max_element(),
            Texture::Bitmap(b) => b.texels.iter().map(|c| c.max_element()).fold(0.0, f32::max),
            Texture::Checkerboard { color0, color1, .. } => {
                color0.max_element().max(color1.max_element())
            }
            // Checked against the mesh's values where the shape is read.
            Texture::MeshAttribute { .. } => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bitmap(filter: FilterType, wrap: WrapMode) -> Bitmap {
        // 2 × 2: top row red, green; bottom row blue, white.
        Bitmap {
            width: 2,
            height: 2,
            texels: vec![Color::X, Color::Y, Color::Z, Color::ONE],
            filter,
            wrap,
            to_uv: UvTransform::IDENTITY,
        }
    }

    #[test]
    fn nearest_reads_the_texel_under_uv_from_the_top_row() {
        let b = bitmap(FilterType::Nearest, WrapMode::Repeat);
        assert_eq!(b.eval(Vec2::new(0.25, 0.25)), Color::X);
        assert_eq!(b.eval(Vec2::new(0.75, 0.25)), Color::Y);
        assert_eq!(b.eval(Vec2::new(0.25, 0.75)), Color::Z);
        assert_eq!(b.eval(Vec2::new(1.25, -0.25)), Color::Z); // repeat
    }

    #[test]
    fn bilinear_is_exact_at_centres_and_halfway_between() {
        let b = bitmap(FilterType::Bilinear, WrapMode::Clamp);
        assert_eq!(b.eval(Vec2::new(0.25, 0.25)), Color::X);
        assert_eq!(b.eval(Vec2::new(0.5, 0.25)), Color::new(0.5, 0.5, 0.0));
        assert_eq!(b.eval(Vec2::new(0.0, 0.25)), Color::X); // clamped edge
        let m = bitmap(FilterType::Nearest, WrapMode::Mirror);
        assert_eq!(m.eval(Vec2::new(1.25, 0.25)), Color::Y); // mirrored back into the last column
    }

    /// The gradient is the derivative of `eval`'s bilinear interpolant: compared with central
    /// differences of `eval` inside a texel cell, through a rotating, scaling `to_uv`.
    #[test]
    fn bilinear_gradient_is_the_derivative_of_the_lookup() {
        let mut b = bitmap(FilterType::Bilinear, WrapMode::Repeat);
        b.texels = vec![
            Color::splat(0.1),
            Color::new(0.9, 0.2, 0.4),
            Color::splat(0.7),
            Color::new(0.3, 0.8, 0.05),
        ];
        b.to_uv = UvTransform {
            m: [[0.8, -0.6], [0.3, 1.2]],
            t: Vec2::new(0.05, 0.1),
        };
        let f = |uv: Vec2| luminance(b.eval(uv)) as f64;
        for uv in [
            Vec2::new(0.3, 0.2),
            Vec2::new(0.61, 0.47),
            Vec2::new(1.3, -0.17),
        ] {
            let h = 1e-3f32;
            let numeric = [
                (f(uv + Vec2::new(h, 0.0)) - f(uv - Vec2::new(h, 0.0))) / (2.0 * h as f64),
                (f(uv + Vec2::new(0.0, h)) - f(uv - Vec2::new(0.0, h))) / (2.0 * h as f64),
            ];
            let g = b.grad(uv);
            for (a, n) in [g.x as f64, g.y as f64].into_iter().zip(numeric) {
                // f32 lookups differenced over 2h: rounding of about 1e-7/1e-3 per unit slope.
                assert!(
                    (a - n).abs() < 1e-3 * (1.0 + n.abs()),
                    "{uv}: {g} vs {numeric:?}"
                );
            }
        }
    }

    #[test]
    fn checkerboard_alternates_in_quarters() {
        let t = Texture::Checkerboard {
            color0: Color::ZERO,
            color1: Color::ONE,
            to_uv: UvTransform::IDENTITY,
        };
        assert_eq!(t.eval(TexPoint::at(Vec2::new(0.1, 0.1))), Color::ZERO);
        assert_eq!(t.eval(TexPoint::at(Vec2::new(0.6, 0.1))), Color::ONE);
        assert_eq!(t.eval(TexPoint::at(Vec2::new(0.6, 0.6))), Color::ZERO);
        // Read as a scalar (Mitsuba's `eval_1`) the squares swap.
        assert_eq!(t.eval_scalar(TexPoint::at(Vec2::new(0.1, 0.1))), 1.0);
        assert_eq!(t.eval_scalar(TexPoint::at(Vec2::new(0.6, 0.1))), 0.0);
        assert_eq!(t.fraction(TexPoint::at(Vec2::new(0.6, 0.6))), 1.0);
    }
}

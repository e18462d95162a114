//! Small vector helpers shared by every module: colours, orthonormal frames, float error bounds.

pub use glam::{Mat4, Vec2, Vec3};

/// Linear RGB radiance, importance or throughput.
pub type Color = Vec3;

pub const PI: f32 = std::f32::consts::PI;
pub const INV_PI: f32 = std::f32::consts::FRAC_1_PI;

/// Luminance of linear sRGB primaries (Rec. 709 weights).
#[inline]
pub fn luminance(c: Color) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Bound on the relative rounding error of `n` chained f32 operations (pbrt's γ_n).
#[inline]
pub const fn gamma(n: i32) -> f32 {
    let e = f32::EPSILON * 0.5;
    (n as f32 * e) / (1.0 - n as f32 * e)
}

/// Orthonormal basis around a unit normal; `z` is the normal.
/// Built with the branchless construction of Duff et al. 2017 so it is continuous almost everywhere.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub x: Vec3,
    pub y: Vec3,
    pub z: Vec3,
}

impl Frame {
    pub fn from_z(n: Vec3) -> Frame {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let x = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let y = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { x, y, z: n }
    }
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.x), v.dot(self.y), v.dot(self.z))
    }
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.x * v.x + self.y * v.y + self.z * v.z
    }
}

/// True when every component is finite and non-negative (a valid radiance or weight).
#[inline]
pub fn is_valid_color(c: Color) -> bool {
    c.is_finite() && c.min_element() >= 0.0
}

/// Reflect `w` about `n` (both pointing away from the surface).
#[inline]
pub fn reflect(w: Vec3, n: Vec3) -> Vec3 {
    2.0 * w.dot(n) * n - w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_for_awkward_normals() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(1e-7, -1e-7, -1.0).normalize(),
            Vec3::new(0.3, -0.8, 0.1).normalize(),
        ] {
            let f = Frame::from_z(n);
            assert!((f.x.length() - 1.0).abs() < 1e-5 && (f.y.length() - 1.0).abs() < 1e-5);
            assert!(
                f.x.dot(f.y).abs() < 1e-5 && f.x.dot(f.z).abs() < 1e-5 && f.y.dot(f.z).abs() < 1e-5
            );
            let v = Vec3::new(0.2, -0.5, 0.7);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
        }
    }
}

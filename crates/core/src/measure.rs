//! The one place that converts densities between measures. Every pdf in the code base is either
//! solid angle (`*_w`, per steradian at the point the direction leaves) or area (`*_a`, per unit
//! area at the point that was reached). A path vertex stores area measure; see `path::vertex`.

use crate::math::Vec3;

/// Converts a solid-angle density at `from` into an area density at the point `to` whose normal
/// is `n_to`: p_A = p_ω · |cos θ_to| / ‖to − from‖² (dω = |cos θ| / r² dA).
#[inline]
pub fn solid_angle_to_area(pdf_w: f32, from: Vec3, to: Vec3, n_to: Vec3) -> f32 {
    let d = to - from;
    let d2 = d.length_squared();
    if d2 == 0.0 {
        return 0.0;
    }
    let cos = n_to.dot(d).abs() / d2.sqrt();
    pdf_w * cos / d2
}

/// The geometry term G(x ↔ y) = |cos θx| |cos θy| / ‖x − y‖², visibility excluded.
#[inline]
pub fn geometry_term(x: Vec3, nx: Vec3, y: Vec3, ny: Vec3) -> f32 {
    let d = y - x;
    let d2 = d.length_squared();
    if d2 == 0.0 {
        return 0.0;
    }
    let inv = 1.0 / d2.sqrt();
    (nx.dot(d) * inv).abs() * (ny.dot(d) * inv).abs() / d2
}

/// Converts a density over the plane perpendicular to `dir` (the disk a light at infinity emits
/// over, so the density of where a parallel ray starts) into an area density at a surface point
/// with normal `n_to` that the ray reaches: p_A = p_⊥ · |cos θ_to| (dA_⊥ = |cos θ| dA).
#[inline]
pub fn perpendicular_to_area(pdf_perp: f32, dir: Vec3, n_to: Vec3) -> f32 {
    pdf_perp * n_to.dot(dir).abs()
}

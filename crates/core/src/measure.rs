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

/// Converts a solid-angle density at `from` into a volume density at the point `to` inside a
/// medium, per unit length of free flight: p_V = p_ω · p_ff / ‖to − from‖², because a volume
/// element seen from `from` is dV = r² dr dω (Pauly et al. 2000, §3). There is no cosine: a
/// point in a medium has no surface facing the ray. `pdf_len` is the free-flight density per
/// unit length with which the walk stopped at `to` (`Medium::free_flight_density`, scattered);
/// a surface reached through media instead takes `solid_angle_to_area` times the probability of
/// passing every medium on the way, which is a probability, not a density, so no measure changes.
#[inline]
pub fn solid_angle_to_volume(pdf_w: f32, pdf_len: f32, from: Vec3, to: Vec3) -> f32 {
    let d2 = (to - from).length_squared();
    if d2 == 0.0 {
        return 0.0;
    }
    pdf_w * pdf_len / d2
}

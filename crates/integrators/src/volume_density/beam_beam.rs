//! `bb1d`'s query: photon beams gathered along a camera beam with the 1-D kernel (Jarosz,
//! Nowrouzezahrai, Sadeghi & Jensen 2011, "A comprehensive theory of volumetric radiance
//! estimation using photon points and beams", the beam × beam 1-D estimate).
//!
//! The camera walk's flight from o_c along ω_c (unit) in medium m up to t_c (a long camera beam,
//! as `pb2d`'s) counts every path whose first medium vertex from the camera lies on it:
//! β ∫₀^t_c T_c(s) σs(y_s) L_i(y_s, −ω_c) ds. A photon beam b (origin o_b, unit direction ω_b,
//! length t_b, power Φ_b: `photon_beams.rs`) carries the radiance Φ_b T_b(t) along itself, so
//! the joint integral over s and t is estimated with a 3-D kernel that is a delta in the plane
//! of the two directions and a 1-D kernel k(u) across it (u: the distance between the lines).
//! The delta integrates over (s, t) to 1 / sin θ (the Jacobian of (s, t) → the plane, θ the
//! angle between the beams), so
//!
//!   Σ_b k(u_b) Φ_b T_c(s_b) σs(y_{s_b}) T_b(t_b) f_p(−ω_c, −ω_b) / sin θ_b,
//!
//! s_b, t_b the closest points (counted when 0 ≤ s_b < t_c and 0 ≤ t_b < the beam's length),
//! k(u) = 1/(2r) for |u| ≤ r (the box kernel normalised over the line, ∫_{−r}^{r} k = 1).
//! T on both beams is `Medium::transmittance` (deterministic; a ray march on grid media). The
//! 1/sin θ is integrable: near-parallel beams meet within their lengths with probability
//! ∝ sin θ.

use super::photon_beams::BeamQuery;
use lt_core::geometry::Ray;
use lt_core::math::{Color, Vec3};
use lt_core::medium::MediumId;

/// Beams closer to parallel than this (sin θ) are not counted: their closest points are
/// ill-conditioned, and they meet within finite lengths with probability ∝ sin θ (a bias of
/// that order, ~1e-4 of the beams that pass the distance test).
const MIN_SIN: f32 = 1e-4;

/// The closest points of two lines o_c + s ω_c and o_b + t ω_b (unit directions): (s, t, the
/// distance between them, sin θ); `None` when (nearly) parallel.
pub fn closest_points(oc: Vec3, wc: Vec3, ob: Vec3, wb: Vec3) -> Option<(f32, f32, f32, f32)> {
    let cos = wc.dot(wb);
    let sin2 = 1.0 - cos * cos;
    if !(sin2 > MIN_SIN * MIN_SIN) {
        return None;
    }
    let w = oc - ob;
    let (d, e) = (wc.dot(w), wb.dot(w));
    let s = (cos * e - d) / sin2;
    let t = (e - cos * d) / sin2;
    let u = ((oc + wc * s) - (ob + wb * t)).length();
    Some((s, t, u, sin2.sqrt()))
}

/// The estimate along the camera flight `ray` up to `t_max` (`BeamQuery` with
/// `BeamKernel::Line1d`).
pub fn along_camera_beam(
    q: &BeamQuery,
    ray: &Ray,
    t_max: f32,
    m: MediumId,
    depth: u32,
) -> Option<Color> {
    let index = q.index.as_ref()?;
    let longest = q.max_depth.saturating_sub(depth);
    if longest == 0 {
        return None;
    }
    let medium = &q.scene.media[m as usize];
    let phase = medium.phase();
    let wo = -ray.d;
    let mut sum = Color::ZERO;
    index
        .lists
        .frame
        .for_cells_along(ray, t_max, |cell, _, t_lo, t_hi| {
            for &i in index.lists.items(cell) {
                let b = &q.beams.beams[i as usize];
                if b.medium != m || b.segments > longest {
                    continue;
                }
                let Some((s, t, u, sin)) = closest_points(ray.o, ray.d, b.origin, b.dir) else {
                    continue;
                };
                // Counted in the one cell whose interval holds s (each beam once).
                if !(s >= t_lo && s < t_hi && s < t_max && t >= 0.0 && t < b.length) {
                    continue;
                }
                if u > q.r {
                    continue;
                }
                let y = ray.o + ray.d * s;
                let x = b.origin + b.dir * t;
                let tc = medium.transmittance(ray.o, y);
                let tb = medium.transmittance(b.origin, x);
                sum += tc * tb * medium.sigma_s(y) * b.power * (phase.eval(wo, -b.dir) / sin);
            }
        });
    Some(sum * q.norm)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_points_of_skew_lines() {
        // x axis at z = 0 against the y axis at z = 1, shifted: closest at s = 2, t = 3, u = 1.
        let (s, t, u, sin) = closest_points(
            Vec3::new(-2.0, 0.0, 0.0),
            Vec3::X,
            Vec3::new(0.0, -3.0, 1.0),
            Vec3::Y,
        )
        .unwrap();
        assert!((s - 2.0).abs() < 1e-6 && (t - 3.0).abs() < 1e-6, "{s} {t}");
        assert!(
            (u - 1.0).abs() < 1e-6 && (sin - 1.0).abs() < 1e-6,
            "{u} {sin}"
        );
        assert!(closest_points(Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::X).is_none());
    }
}

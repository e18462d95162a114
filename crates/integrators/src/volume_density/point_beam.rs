//! `bp2d`'s query: photon beams gathered at a camera point with the 2-D kernel — Jarosz,
//! Nowrouzezahrai, Sadeghi & Jensen 2011's "beam × point 2-D" (their BP2D; SmallUPBP's `bp2d`).
//! Naming: this is the other 2-D estimator beside `pb2d` (photon *points* × camera *beam*, the
//! beam radiance estimate); here the photons are *beams* and the query a *point*.
//!
//! At the camera walk's first medium vertex x (sampled by free flight, as `pp3d`'s; β holding
//! σs(x)), a photon beam b (origin o_b, unit direction ω_b, length ℓ_b, power Φ_b:
//! `photon_beams.rs`) carries the radiance Φ_b T_b(t) at o_b + t ω_b. The photon points its
//! flight would have left give, through pp3d's 3-D kernel, β ∫ T_b(t) K₃(x_t − x) dt f_p; a
//! kernel that is a delta along the beam and a disk of radius r across it gives instead
//!
//!   L_i(x, ω_o) ≈ Σ_b Φ_b T_b(t_b) f_p(ω_o, −ω_b) / (π r²),   u_b ≤ r, 0 ≤ t_b < ℓ_b,
//!
//! t_b = (x − o_b)·ω_b the projection of x on the beam and u_b its distance from the beam's
//! line (the 2-D kernel 1/(πr²) normalised over the disk across the beam). T_b is
//! `Medium::transmittance` (deterministic). `power` carries 1/N (`photons.rs`).

use super::photon_beams::BeamQuery;
use lt_core::math::{Color, Vec3};
use lt_core::medium::MediumId;

/// The estimate at the camera point `x` (`BeamQuery` with `BeamKernel::Point2d`).
pub fn at_camera_point(q: &BeamQuery, x: Vec3, wo: Vec3, m: MediumId, depth: u32) -> Option<Color> {
    let Some(index) = &q.index else {
        return Some(Color::ZERO);
    };
    let medium = &q.scene.media[m as usize];
    let phase = medium.phase();
    let longest = q.max_depth.saturating_sub(depth);
    let frame = &index.lists.frame;
    // Every beam within r of x is listed in x's cell (`BeamIndex::build`).
    let cell = frame.index(frame.cell_of(x));
    let r2 = q.r * q.r;
    let mut sum = Color::ZERO;
    for &i in index.lists.items(cell) {
        let b = &q.beams.beams[i as usize];
        if b.medium != m || b.segments > longest {
            continue;
        }
        let t = (x - b.origin).dot(b.dir);
        if !(t >= 0.0 && t < b.length) {
            continue;
        }
        let on_beam = b.origin + b.dir * t;
        if (x - on_beam).length_squared() > r2 {
            continue;
        }
        let tb = medium.transmittance(b.origin, on_beam);
        sum += tb * b.power * phase.eval(wo, -b.dir);
    }
    Some(sum * q.norm)
}

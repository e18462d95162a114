//! The light side of a BB1D or BP2D merge: a photon beam's value, rates and flights at the point
//! where a camera beam or camera point meets it (used by `camera_beams` and `policy`).

use super::light_beams::LightBeams;
use super::light_store::LightStore;
use super::weights::VertexRate;
use crate::subpath::connect::nee_density;
use lt_core::math::Color;
use lt_core::path::PathVertex;
use lt_core::Scene;

/// The light side of a merge with a photon beam at its point x' = o_b + t ω_b (BB1D, BP2D):
/// the beam's value there (Φ_b T_b / P_pass,b, or Φ_b T_b for a long beam), σ̂ᴸ of its flight at
/// x' (the short beam's ratio, or a long beam's whole scattering density), the flight from x'
/// back to y_{i−1} with σ̂ there, and next-event estimation's density of y_0.
pub(super) struct BeamEnd<'s> {
    pub value: Color,
    pub back: f64,
    pub near_rate: f64,
    pub end_rate: f64,
    pub nee: f64,
    /// The light subpath's stored rates (its vertices before x').
    pub rates: &'s [VertexRate],
}

impl<'s> BeamEnd<'s> {
    /// Beam `bi` of `lb` at distance `tb` along it: `light_buf` gets y_0 … y_{i−1}, x' (`None`
    /// where the beam's flight cannot pass or scatter there).
    pub fn at(
        scene: &Scene,
        lb: &'s LightBeams,
        store: &'s LightStore,
        (bi, tb): (u32, f32),
        light_buf: &mut Vec<PathVertex>,
    ) -> Option<BeamEnd<'s>> {
        let b = &lb.beams[bi as usize];
        let src = lb.refs[bi as usize];
        let i = src.vertex as usize;
        let mm = &scene.media[b.medium as usize];
        let xl = b.origin + b.dir * tb;
        let pass_l = src.p_before * mm.free_flight_density(b.origin, xl, false);
        let scatter_l = src.p_before * mm.free_flight_density(b.origin, xl, true);
        if !(pass_l > 0.0 && scatter_l > 0.0) {
            return None;
        }
        let tr = b.power * mm.transmittance(b.origin, xl);
        let (value, end_rate) = if lb.long {
            (tr, scatter_l as f64)
        } else {
            (tr * (src.p_before / pass_l), (scatter_l / pass_l) as f64)
        };
        let y = store.path(src.path as usize);
        let yp = &y.vertices[i - 1];
        let xlv = PathVertex::medium(b.medium, xl, -b.dir, value, src.pdf_w, scatter_l, yp);
        light_buf.clear();
        light_buf.extend_from_slice(&y.vertices[..i]);
        light_buf.push(xlv);
        // The camera direction's σ̂ at y_{i−1}: camera beams are short whatever the photon beams.
        let (back, near_rate) = src.back.at(mm, xl, b.origin, false);
        // y_1 is the beam's point when the beam leaves the light.
        let nee = if i == 1 {
            nee_density(scene, &light_buf[0], &xlv)
        } else {
            y.nee
        };
        Some(BeamEnd {
            value,
            back,
            near_rate,
            end_rate,
            nee,
            rates: y.rates,
        })
    }
}

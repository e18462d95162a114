//! `lt mis-check`: samples paths with an integrator's own code (through its `Recorder` hooks) and
//! holds the MIS weights it applied to the from-scratch oracle of `lt_core::path`.
//!
//! - `pt_bdpt`: pt's, bdpt's and lvc-bdpt's weights (connection techniques; lvc-bdpt's counted
//!   n_conn = N / L̄ times, `connection_count`), and bdpt's (lvc-bdpt's) replayed for every
//!   technique of the path.
//! - `vcm_bpm`: vcm's and bpm's (connections and merges), and their recursion replayed.
//! - `upbp`: upbp's (connections, PP3D, PB2D and BB1D through media), and its routine replayed.
//! - `quota`: how many recorded paths the vcm and upbp checkers keep per (length, technique).
//! - `tolerance`: how far a weight may stray from the oracle's.
//! - `report`: the one report both checkers fill, a row per path length.

use lt_core::Scene;

pub mod pt_bdpt;
pub mod quota;
pub mod report;
pub mod tolerance;
pub mod upbp;
pub mod vcm_bpm;

/// One clear line when `integrator`'s weights cannot be held to the oracle on `scene` because
/// of its media. bdpt's can (its walks, joins and weights take media, and the oracle covers
/// medium vertices). pt's through media are Mitsuba volpath's, next-event estimation against
/// phase or BSDF sampling by the two direction densities alone: a partition of unity, so
/// unbiased, but not the path-space weights, whose BSDF-sampling density also carries the
/// probability of passing the media to the light. The others refuse media scenes outright.
pub fn refuse_media(scene: &Scene, integrator: &str) -> Result<(), String> {
    if !scene.has_media || integrator == "bdpt" || integrator == "upbp" {
        return Ok(());
    }
    if integrator == "pt" {
        return Err(
            "mis-check: pt through media weighs by direction densities alone (Mitsuba's \
                    volpath), not by the path-space densities the oracle holds; check bdpt on \
                    this scene"
                .into(),
        );
    }
    Err(format!(
        "mis-check: integrator {integrator} does not handle participating media yet; the scene \
         has {} media",
        scene.media.len()
    ))
}

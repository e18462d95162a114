//! `upbp`'s MIS weights from the full path's densities: bdpt's connection techniques (through
//! `lt_core::path::Chain`, from the walks' stored densities) and the volumetric merges PP3D and
//! PB2D at every medium vertex (`lt_core::path::volume_merging` states their densities). One
//! routine weighs every technique, so `lt mis-check` replays it on the oracle's densities.
//!
//! Measures: l_j, c_j per unit volume at a medium vertex (no cosine), per unit area at a surface
//! (the walks' `pdf_fwd`/`pdf_rev`). PP3D at x_i counts η_P = N·(4/3)πr_P³ times
//! ∏_{j≤i} l_j ∏_{j≥i} c_j; PB2D counts η_B = N·πr_B² times the same product with c_i divided
//! by σ̂_i (`VertexRate::rate`), the flight's scattering density over its pass probability at x_i:
//! the beam covers x_i with the pass probability where the walk stopped there with the
//! scattering density. BB1D counts η_BB = N·2r times sin θ_i and the product with both l_i and
//! c_i divided by their σ̂'s (`light_rate`, `rate`): both walks' segments are beams. A surface
//! merge (vcm's) at a non-delta surface vertex counts η_S = N·πr_S² times ∏_{j≤i} l_j ∏_{j≥i} c_j.
//! Under SmallUPBP's compatible/previous modes (`lt_core::path::UpbpMode`) the techniques the
//! mode does not count are zero, as in the oracle. BP2D counts η_BP = N_B·πr² times the product with l_i divided by σ̂ᴸ_i (the light's segment
//! is the beam, the camera's x_i a sampled point). With long photon beams (`VolumeSet::long_beams`)
//! BB1D's and BP2D's σ̂ᴸ_i is the light flight's whole scattering density (`light_flight`).

use lt_core::path::volume_merging::first_medium_from_camera;
use lt_core::path::{Chain, Heuristic, UpbpMode, VolumeSet, VolumeTechnique};

/// Per path vertex x_j: in a medium, σ̂_j of the camera direction's flight into it, σ̂ᴸ_j of the
/// light direction's, and sin θ_j between the two flights (`lt_core::path::VolumeRates`).
#[derive(Clone, Copy, Debug, Default)]
pub struct VertexRate {
    pub medium: bool,
    /// σ̂_j (0 where no flight scatters into x_j).
    pub rate: f64,
    /// σ̂ᴸ_j of the flight x_{j−1} → x_j (0 where none scatters), as the pass's photon beams
    /// read it: with long beams the flight's whole scattering density (`rates::Needs::long`,
    /// `VolumeRates::light_side`).
    pub light_rate: f64,
    /// sin θ_j between the flights x_{j−1} → x_j and x_{j+1} → x_j.
    pub sin: f64,
}

/// Longest path (segments) weighed on the stack.
const STACK_K: usize = 24;

/// The weight of `technique` on the path whose densities `chain` holds (`vol[j]` for each x_j),
/// under `h` over every technique of `set`.
pub fn weight(
    chain: &Chain,
    vol: &[VertexRate],
    set: &VolumeSet,
    technique: VolumeTechnique,
    h: Heuristic,
) -> f64 {
    let k = chain.k();
    let n = BLOCKS * (k + 2);
    let mut stack = [0.0f64; BLOCKS * (STACK_K + 2)];
    let mut heap = Vec::new();
    let p: &mut [f64] = if k <= STACK_K {
        &mut stack[..n]
    } else {
        heap.resize(n, 0.0);
        &mut heap
    };
    effective(chain, vol, set, p);
    let own = match technique {
        VolumeTechnique::Connect(s) => p[s],
        VolumeTechnique::Point(i) => p[k + 2 + i],
        VolumeTechnique::Beam(i) => p[2 * (k + 2) + i],
        VolumeTechnique::BeamBeam(i) => p[3 * (k + 2) + i],
        VolumeTechnique::Surface(i) => p[4 * (k + 2) + i],
        VolumeTechnique::BeamPoint(i) => p[5 * (k + 2) + i],
    };
    if !(own > 0.0) {
        return 0.0;
    }
    for x in p.iter_mut() {
        *x /= own;
    }
    h.weight_from_ratios(p)
}

/// Technique families: connections, PP3D, PB2D, BB1D, surface merges, BP2D.
const BLOCKS: usize = 6;

/// n·p of every technique into `out` (6 (k + 2) entries): connections s = 0 … k+1, PP3D, PB2D,
/// BB1D, surface merges and BP2D at x_0 … x_{k+1} (the last of each never valid).
fn effective(chain: &Chain, vol: &[VertexRate], set: &VolumeSet, out: &mut [f64]) {
    let k = chain.k();
    for s in 0..=k + 1 {
        out[s] = if s == 0 || set.connections {
            chain.sample_count(s) * chain.technique(s)
        } else {
            0.0
        };
    }
    // Prefix products of the light side and suffix products of the camera side.
    let (l, c) = (chain.light, chain.camera);
    let mut light_to = 1.0;
    for i in 0..=k + 1 {
        let (point, beam, beam_beam, surface) = (&mut 0.0, &mut 0.0, &mut 0.0, &mut 0.0);
        let beam_point = &mut 0.0;
        if i <= k {
            light_to *= l[i];
        }
        if i >= 1 && i < k && vol[i].medium {
            let camera_from: f64 = c[i..].iter().product();
            *point = set.points_eta * light_to * camera_from;
            let v = vol[i];
            let light_rate = v.light_rate;
            if v.rate > 0.0 {
                *beam = set.beams_eta * light_to * camera_from / v.rate;
                if light_rate > 0.0 {
                    *beam_beam = set.beam_beams_eta
                        * v.sin
                        * (light_to / light_rate)
                        * (camera_from / v.rate);
                }
            }
            if light_rate > 0.0 {
                *beam_point = set.beam_points_eta * (light_to / light_rate) * camera_from;
            }
        } else if i >= 1 && i < k && chain.connectable[i] {
            // vcm's vertex merging at a non-delta surface vertex (`Densities::merging`).
            *surface = set.surface_eta * light_to * c[i..].iter().product::<f64>();
        }
        out[k + 2 + i] = *point;
        out[2 * (k + 2) + i] = *beam;
        out[3 * (k + 2) + i] = *beam_beam;
        out[4 * (k + 2) + i] = *surface;
        out[5 * (k + 2) + i] = *beam_point;
    }
    // SmallUPBP's compatible/previous modes: the techniques the mode does not count are zero.
    if set.mode != UpbpMode::Full {
        let m = first_medium_from_camera(k, |j| vol[j].medium, chain.connectable);
        for (s, p) in out[..=k + 1].iter_mut().enumerate() {
            if !set.mode.counts(m, VolumeTechnique::Connect(s)) {
                *p = 0.0;
            }
        }
        for i in 0..=k + 1 {
            if !set.mode.counts(m, VolumeTechnique::Point(i)) {
                for b in 1..BLOCKS {
                    out[b * (k + 2) + i] = 0.0;
                }
            }
        }
    }
}

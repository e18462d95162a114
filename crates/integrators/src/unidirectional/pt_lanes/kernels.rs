//! Lane kernels: each performs, lane by lane, the IEEE operations of the scalar code it names in
//! the same order (plain `*`, `+`, `/`; no fused multiply-add), so every lane's result is the
//! scalar result's bits. The loops are over fixed-size arrays with no early exit, so the compiler
//! may vectorise them; a masked-off lane's slot is computed and discarded, never stored.

use super::state::{ColorLanes, Mask, LANES};
use crate::pt::{Pt, Techniques};
use lt_core::path::Heuristic;

/// `Pt::weight(a, b)` per lane: the MIS weight of technique a against b (solid-angle pdfs).
/// The power heuristic mirrors `lt_core::sampling::power_heuristic` (Veach 1997, eq. 9.13, β = 2);
/// the balance heuristic goes through the scalar `Pt::weight` per lane.
pub fn mis_weight(pt: &Pt, a: &[f32; LANES], b: &[f32; LANES]) -> [f32; LANES] {
    let mut w = [0.0f32; LANES];
    if pt.params.mis == Heuristic::Balance {
        for i in 0..LANES {
            w[i] = pt.weight(a[i], b[i]);
        }
        return w;
    }
    for i in 0..LANES {
        let a2 = a[i] * a[i];
        let b2 = b[i] * b[i];
        let sum = a2 + b2;
        // Branch-free selects of power_heuristic's three cases, in its order of precedence.
        let ratio = a2 / sum;
        w[i] = if a2.is_infinite() {
            1.0
        } else if sum == 0.0 {
            0.0
        } else {
            ratio
        };
    }
    w
}

/// `Pt::hit_weights(prev_delta, prev_pdf_w, light_pdf).0` per lane: the weight of an emitter
/// reached by BSDF sampling, against next-event estimation of the same direction.
pub fn hit_weight(
    pt: &Pt,
    prev_delta: &Mask,
    prev_pdf_w: &[f32; LANES],
    light_pdf: &[f32; LANES],
) -> [f32; LANES] {
    let both = mis_weight(pt, prev_pdf_w, light_pdf);
    let mut w = [0.0f32; LANES];
    for i in 0..LANES {
        w[i] = if prev_delta[i] {
            1.0
        } else {
            match pt.params.techniques {
                Techniques::Both => both[i],
                Techniques::Light => 0.0,
                Techniques::Bsdf => 1.0,
            }
        };
    }
    w
}

/// `l += beta * le * w` of `Pt::radiance_recorded` (an emitter hit) on the lanes of `mask`.
pub fn add_emitted(
    l: &mut ColorLanes,
    mask: &Mask,
    beta: &ColorLanes,
    le: &ColorLanes,
    w: &[f32; LANES],
) {
    for i in 0..LANES {
        if mask[i] {
            l.r[i] += beta.r[i] * le.r[i] * w[i];
            l.g[i] += beta.g[i] * le.g[i] * w[i];
            l.b[i] += beta.b[i] * le.b[i] * w[i];
        }
    }
}

/// What next-event estimation found per lane before its weight: `ev.f_cos`, `ls.radiance`, the
/// light's solid-angle pdf `pmf · ls.pdf_w`, the BSDF's `ev.pdf_w`, and whether the light is a
/// delta (or the BSDF technique is off: weight one).
#[derive(Default)]
pub struct NextEventLanes {
    /// Lanes where the light sample survived every check of `Pt::direct_light` (the rest add zero).
    pub found: Mask,
    pub f_cos: ColorLanes,
    pub radiance: ColorLanes,
    pub light_pdf: [f32; LANES],
    pub bsdf_pdf: [f32; LANES],
    pub weight_one: Mask,
}

/// The end of `Pt::direct_light` and the `l += beta * direct_light(…)` after it, on the lanes of
/// `ran` (those where next-event estimation ran; it returned zero where nothing was `found`):
/// `w = weight(light_pdf, ev.pdf_w)`, `l += beta * (ev.f_cos * ls.radiance * (w / light_pdf))`.
pub fn add_next_event(
    pt: &Pt,
    l: &mut ColorLanes,
    ran: &Mask,
    beta: &ColorLanes,
    ne: &NextEventLanes,
) {
    let mis = mis_weight(pt, &ne.light_pdf, &ne.bsdf_pdf);
    for i in 0..LANES {
        if !ran[i] {
            continue;
        }
        let (r, g, b) = if ne.found[i] {
            let w = if ne.weight_one[i] { 1.0 } else { mis[i] };
            let s = w / ne.light_pdf[i];
            (
                ne.f_cos.r[i] * ne.radiance.r[i] * s,
                ne.f_cos.g[i] * ne.radiance.g[i] * s,
                ne.f_cos.b[i] * ne.radiance.b[i] * s,
            )
        } else {
            (0.0, 0.0, 0.0)
        };
        l.r[i] += beta.r[i] * r;
        l.g[i] += beta.g[i] * g;
        l.b[i] += beta.b[i] * b;
    }
}

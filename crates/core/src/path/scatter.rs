//! The BSDF factor and the directional density at one surface vertex of a fixed path, including
//! delta lobes, which `Material::eval`/`pdf` report as zero.
//!
//! Delta vertices are represented delta-stripped (Veach 1997, ch. 8, on paths through specular surfaces): a
//! mirror's f = R δ(ω − ω_r) / |cos θ| and its sampling density p = 1 · δ(ω − ω_r) share the same
//! Dirac, so we keep the lobe value (f_cos of the lobe) and the lobe's selection probability. Their
//! ratio is exactly the sample weight, and no technique ever connects at such a vertex (its
//! density of being reached by a connection is zero), so the Diracs never have to be compared.

use crate::bsdf::TransportMode;
use crate::math::{Color, Vec2, Vec3};
use crate::path::vertex::{PathVertex, VertexKind};
use crate::scene::Scene;

/// Two unit directions closer than this (chord length, ≈ angle in radians) are the same delta
/// lobe, on top of what the positions' rounding errors allow (`delta_tolerance`): f32 direction
/// arithmetic alone is good to a few 1e-7, and no two distinct lobes of a smooth surface come
/// this close.
pub const DELTA_MATCH_TOL: f32 = 1e-4;

/// Bound on the angle between the direction a walk sampled from `a` and the one rebuilt from the
/// stored positions of `a` and `b`: each position is within its `p_err` box of the exact point
/// (the walk's ray started on the offset origin, which is as close), so the chord is at most
/// (|err_a| + |err_b|) / distance. Zero towards infinity.
pub fn direction_error(a: &PathVertex, b: &PathVertex) -> f32 {
    if a.is_infinite() || b.is_infinite() {
        return 0.0;
    }
    (a.p_err.length() + b.p_err.length()) / (b.p - a.p).length()
}

/// The match tolerance at a delta vertex `v` between neighbours `a` and `b`: both directions
/// may be off by their error bound (twice, for safety), plus `DELTA_MATCH_TOL`.
pub fn delta_tolerance(v: &PathVertex, a: &PathVertex, b: &PathVertex) -> f32 {
    DELTA_MATCH_TOL + 2.0 * (direction_error(v, a) + direction_error(v, b))
}

/// Lobe-choice variates tried to find which delta lobe produced `wi`: every material here picks
/// its lobe by comparing `u_lobe` with a cumulative probability, so the extremes reach the first
/// and the last lobe (reflection and transmission of a dielectric) and the middle any third one.
const LOBE_PROBES: [f32; 3] = [0.0, 0.5, 1.0 - f32::EPSILON];

/// Factor and density of scattering at a surface vertex `v` between `wo` (towards where the walk
/// came from) and `wi` (where it goes), both unit and pointing away from `v`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Scatter {
    /// f_cos / |ng·wi|: the BSDF factor of f(x̄) (bsdf/mod.rs conventions), delta-stripped.
    pub f: Color,
    /// Solid-angle density of sampling `wi` given `wo`; for a delta lobe its selection probability.
    pub pdf_w: f32,
    /// The path scatters through a delta lobe here: no technique joins the path at this vertex
    /// (for a material with smooth lobes beside the delta, `connectable` alone does not say so).
    pub delta: bool,
}

/// Evaluates the vertex's material, or at a `Medium` vertex its phase function
/// (`scatter_in_medium`); an endpoint scatters nothing.
/// A delta lobe matches `wi` when the lobe's direction is within `tol` (see `delta_tolerance`).
pub fn scatter(
    scene: &Scene,
    v: &PathVertex,
    wo: Vec3,
    wi: Vec3,
    mode: TransportMode,
    tol: f32,
) -> Scatter {
    let material = match v.kind {
        VertexKind::Surface { material } => material,
        VertexKind::Medium { medium } => return scatter_in_medium(scene, v, medium, wo, wi),
        _ => return Scatter::default(),
    };
    let m = scene.material(material);
    let sf = v.shading_frame();
    let cos_g = v.ng.dot(wi).abs();
    if cos_g == 0.0 {
        return Scatter::default();
    }
    let smooth = || {
        let e = m.eval(&sf, wo, wi, mode);
        Scatter {
            f: e.f_cos / cos_g,
            pdf_w: e.pdf_w,
            delta: false,
        }
    };
    if !m.has_delta_lobe() {
        return smooth();
    }
    // The lobe whose direction is closest to `wi`, and how far the nearest other lobe is.
    let mut best: Option<(f32, Scatter, Vec3)> = None;
    let mut candidates = [None; LOBE_PROBES.len()];
    for (slot, u_lobe) in candidates.iter_mut().zip(LOBE_PROBES) {
        if let Some(s) = m.sample(&sf, wo, u_lobe, Vec2::splat(0.5), mode) {
            if s.delta {
                let dist = (s.wi - wi).length();
                // weight = f_cos / pdf for the lobe, so weight · pdf is the lobe's f_cos.
                let sc = Scatter {
                    f: s.weight * s.pdf_w / cos_g,
                    pdf_w: s.pdf_w,
                    delta: true,
                };
                *slot = Some(s.wi);
                if best.is_none_or(|b| dist < b.0) {
                    best = Some((dist, sc, s.wi));
                }
            }
        }
    }
    // Beside smooth lobes (plastic), a direction off every delta lobe scatters smoothly.
    let missed = || {
        if m.is_delta() {
            Scatter::default()
        } else {
            smooth()
        }
    };
    let Some((dist, sc, dir)) = best else {
        return missed();
    };
    let other = candidates
        .iter()
        .flatten()
        .filter(|w| (**w - dir).length() > tol)
        .map(|w| (*w - wi).length())
        .fold(f32::INFINITY, f32::min);
    // Refraction near grazing exit magnifies the positions' angular error by η·cos θt / cos θi,
    // beyond `tol`; the match still stands when it is unambiguous (the other lobe is far further
    // away) and the direction is within MAGNIFIED_TOL of the lobe.
    // Beside smooth lobes the magnified match is off: a smooth direction may fall that close.
    let unambiguous = m.is_delta() && dist < UNAMBIGUOUS_RATIO * other && dist < MAGNIFIED_TOL;
    if dist < tol || unambiguous {
        sc
    } else {
        missed()
    }
}

/// Scattering at a medium vertex (Pauly et al. 2000): the factor of f(x̄) is σs(x) · p(ω_o, ω_i),
/// the phase function per steradian times the scattering coefficient per unit length — the
/// volume measure's dV has one more length than a surface's dA, and σs carries it. No cosine: a
/// point in a medium has no surface (its G has none either). The phase function is reciprocal,
/// so neither transport mode nor which side `wo` is changes it, and it is never a delta. Its
/// sampling density is the phase function itself (isotropic and Henyey–Greenstein are sampled
/// exactly, `medium::phase`).
fn scatter_in_medium(
    scene: &Scene,
    v: &PathVertex,
    medium: crate::medium::MediumId,
    wo: Vec3,
    wi: Vec3,
) -> Scatter {
    let m = &scene.media[medium as usize];
    let phase = m.phase().eval(wo, wi);
    Scatter {
        f: m.sigma_s(v.p) * phase,
        pdf_w: phase,
        delta: false,
    }
}

/// Largest mismatch (chord) accepted for an unambiguous lobe: 20× magnification of 5e-4.
const MAGNIFIED_TOL: f32 = 1e-2;

/// A lobe closer to `wi` than this fraction of the distance to any other lobe is the one taken.
const UNAMBIGUOUS_RATIO: f32 = 0.05;

/// True when `v`, an inner vertex of a path (not the end of a subpath that a connection or a
/// merge joins), lets a technique join the path there: `connectable`, and the walk did not
/// scatter through a delta lobe at `v` (`PathVertex::delta`). The two differ only for a material
/// with a delta lobe beside smooth ones (plastic): a path through its delta lobe is sampled by
/// walking alone, while a connection at `v` evaluates the smooth lobes (pbrt-v3 and SmallVCM
/// decide per sampled lobe too). The end vertices of a connection scatter by evaluation, hence
/// smoothly, whatever their own walk did next: they take `connectable`.
#[inline]
pub fn connectable_inside(scene: &Scene, v: &PathVertex) -> bool {
    connectable(scene, v) && !v.delta
}

/// True when a connection (a deterministic edge between two subpaths) may end at `v`: never at a
/// delta surface, nor at a light delta in direction (a directional light: the edge would have to
/// match its Dirac); always at the camera and at other lights (a point light's delta is in
/// position, which an edge to it matches by construction). Next-event estimation is not a
/// deterministic edge — the light samples its own Dirac — and `Chain::valid` lets technique 1
/// through whatever x0 is.
#[inline]
pub fn connectable(scene: &Scene, v: &PathVertex) -> bool {
    match v.kind {
        VertexKind::Surface { material } => !scene.material_is_delta(material),
        VertexKind::Light { light, .. } => !scene.lights[light as usize].delta_direction(),
        // An orthographic camera is a delta in direction (`PathVertex::camera_at`).
        VertexKind::Camera => !v.delta,
        // A phase function has no delta: a medium vertex joins every technique.
        VertexKind::Medium { .. } => true,
    }
}

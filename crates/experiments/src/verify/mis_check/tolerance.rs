//! How far an integrator's MIS weight may stray from the oracle's, for `lt mis-check`: a bound
//! derived for each path from what the walks round — their stored f32 densities (`arithmetic_bound`)
//! and their vertices' positions, from which the oracle rebuilds every direction
//! (`geometric_bound`) — instead of a fixed floor. Measured on every shipped scene, the largest
//! mismatch stays below a quarter of it (0.22 in 21 million paths: results/mis-check-scale.md), while a weight off by 1e-4 on
//! a well-conditioned path exceeds it.

/// Tolerance of check (b), absolute on Σ w − 1 (f64 arithmetic on consistent densities for bdpt;
/// two complementary f32 weights for pt).
pub const SUM_TOLERANCE: f64 = 1e-6;
/// Stricter levels of (a) whose exceedances the table counts, for the record.
pub const STRICT_LEVELS: [f64; 3] = [1e-4, 1e-5, 1e-6];
/// `--slack` by default: the derived tolerance as it is.
pub const DEFAULT_SLACK: f64 = 1.0;

use lt_core::path::{Densities, PathVertex};

/// Relative difference |a − b| / max(|a|, |b|) (0 when both are 0; NaN counts as 1).
pub fn relative(a: f64, b: f64) -> f64 {
    if a == b {
        return 0.0;
    }
    let r = (a - b).abs() / a.abs().max(b.abs());
    if r.is_nan() {
        1.0
    } else {
        r
    }
}

/// Unit roundoff of f32, the precision the walks store densities in.
const UNIT_ROUNDOFF_F32: f64 = f32::EPSILON as f64 / 2.0;

/// Operations in f32 behind one stored density (a BSDF or light pdf, then the solid-angle to area
/// conversion: distance², a cosine, a quotient): a generous count, since γ only grows linearly.
const DENSITY_OPS: f64 = 32.0;

/// Operations in f32 of a weight computed from its densities (pt's two-technique weights).
const WEIGHT_OPS: f64 = 16.0;

/// Higham's γ_n = n·u / (1 − n·u): the relative error bound of n rounded f32 operations.
fn gamma_f32(n: f64) -> f64 {
    n * UNIT_ROUNDOFF_F32 / (1.0 - n * UNIT_ROUNDOFF_F32)
}

fn density_at(d: &Densities, i: usize) -> f64 {
    let (nl, nc) = (d.light.len(), d.camera.len());
    if i < nl {
        d.light[i]
    } else if i < nl + nc {
        d.camera[i - nl]
    } else {
        d.nee
    }
}

/// The density at position `i` of the list light ++ camera ++ [nee].
fn density_mut(d: &mut Densities, i: usize) -> &mut f64 {
    let (nl, nc) = (d.light.len(), d.camera.len());
    if i < nl {
        &mut d.light[i]
    } else if i < nl + nc {
        &mut d.camera[i - nl]
    } else {
        &mut d.nee
    }
}

/// Absolute error per axis of a stored direction to a light at infinity (the vertex's `p`): the
/// walk sampled it in a local frame and took its pdf there, the oracle dots the world direction
/// with the normal; one frame change apart, ≈ √3·(γ(3) + 4ε) ≈ 10ε, rounded up. It matters at
/// grazing angles, where a density ∝ cos θ changes by this over cos θ (cornell-env: cos 1.9e-3,
/// 1 path in 2·10⁵ off by 2e-5 before this term).
const INFINITE_DIRECTION_ERROR: f32 = 16.0 * f32::EPSILON;

/// A first-order bound on a weight's relative error from what the walks round. Each density ρ of
/// the path (light side, camera side, NEE) gets ε_ρ: γ(DENSITY_OPS) for its f32 arithmetic, plus
/// its relative change when each finite vertex moves
/// within twice its rounding box `p_err` (a vertex at infinity: its direction by
/// `INFINITE_DIRECTION_ERROR`) (the walks traced from points within it, or from the
/// spawn offset, within |p_err|₁ along the normal): first order, by finite differences of the
/// oracle's own densities, summed over vertices and axes. Glossy lobes, grazing cosines and
/// short segments enter exactly as they amplify the walks' errors. The densities are then treated
/// as independent — a walk computes a segment's forward density from the traced distance and the
/// reverse one from stored positions, so their errors need not cancel as the oracle's do — and
/// the weight's change is summed over them, each ρ scaled by 1 ± ε_ρ alone: factors that every
/// technique shares (pt's whole path but the last vertex) cancel in the weight and cost nothing.
pub fn weight_error_bound(
    vertices: &[PathVertex],
    densities: impl Fn(&[PathVertex]) -> Densities,
    weight: impl Fn(&Densities) -> f64,
) -> f64 {
    let base = densities(vertices);
    let n = base.light.len() + base.camera.len() + 1;
    let arithmetic = gamma_f32(DENSITY_OPS);
    let mut eps = vec![arithmetic; n];
    let mut moved = vertices.to_vec();
    for j in 0..vertices.len() {
        for axis in 0..3 {
            let e = if vertices[j].is_infinite() {
                INFINITE_DIRECTION_ERROR
            } else {
                2.0 * vertices[j].p_err[axis]
            };
            if !(e > 0.0) {
                continue;
            }
            let mut worst = vec![0.0f64; n];
            for sign in [-1.0f32, 1.0] {
                moved[j].p[axis] = vertices[j].p[axis] + sign * e;
                let d = densities(&moved);
                for (i, w) in worst.iter_mut().enumerate() {
                    let (a, b) = (density_at(&d, i), density_at(&base, i));
                    if b.is_finite() && b > 0.0 {
                        *w = w.max(relative(a, b));
                    }
                }
            }
            moved[j].p[axis] = vertices[j].p[axis];
            for (e, w) in eps.iter_mut().zip(&worst) {
                *e += w;
            }
        }
    }
    let w0 = weight(&base);
    let mut total = 0.0;
    for (i, &e) in eps.iter().enumerate() {
        let b = density_at(&base, i);
        if !(b.is_finite() && b > 0.0) {
            continue;
        }
        let mut worst = 0.0f64;
        for sign in [-1.0, 1.0] {
            let mut d = base.clone();
            *density_mut(&mut d, i) *= 1.0 + sign * e;
            worst = worst.max(relative(weight(&d), w0));
        }
        total += worst;
    }
    total
}

/// Safety factor on the first-order bound (second-order terms; probes along one axis at a time).
const FIRST_ORDER_SAFETY: f64 = 2.0;

/// The tolerance of (a): slack × (2 × `weight_error_bound` + γ(WEIGHT_OPS)).
pub fn derived_tolerance(bound: f64, slack: f64) -> f64 {
    slack * (FIRST_ORDER_SAFETY * bound + gamma_f32(WEIGHT_OPS))
}

//! Multiple importance sampling weights over the techniques s = 0 … k+1 of one path (Veach &
//! Guibas 1995; Veach 1997, ch. 9 and 10). Pure functions of the densities: they copy, never
//! mutate vertices (Tungsten's `misWeight`, not pbrt's scoped assignments).
//!
//! No sample-count factor n_s appears: with one light subpath per camera sample, every technique
//! is taken once per camera sample, so all n_s are equal (see the module docs of `path`).
//!
//! The densities are delta-stripped (`path::scatter`). For mirrors and every non-delta vertex the
//! stripped p_s are the true densities in one common measure, so these are exactly the balance and
//! power heuristics. A refraction sampled from the light side by one technique and from the camera
//! side by another carries its Dirac in different solid angles (`Path::contribution_for`): the
//! stripped p_s then differ from common-measure densities by the Jacobian η_L² cos θ_L /
//! (η_C² cos θ_C) per such refraction. The weights still sum to one and vanish where p_s = 0, so
//! every estimator stays unbiased; they are just not the exact heuristic there (nor are pbrt's,
//! which make the same choice). Exact ones would use p̂_s = p_s · f_0 / f_s with f_s =
//! `contribution_for(s)`.

use super::path::Densities;

/// Balance heuristic w_s = p_s / Σ_i p_i. Zero when p_s = 0 (the technique cannot make the path).
pub fn balance_weight(pdfs: &[f64], s: usize) -> f64 {
    power_weight(pdfs, s, 1.0)
}

/// Power heuristic w_s = p_s^β / Σ_i p_i^β. Evaluated as 1 / Σ_i (p_i / p_s)^β so that densities
/// far outside f64's range of squares (β = 2 squares area densities) cannot overflow.
pub fn power_weight(pdfs: &[f64], s: usize, beta: f64) -> f64 {
    let ps = pdfs[s];
    if ps.is_nan() || ps <= 0.0 {
        return 0.0;
    }
    let sum: f64 = pdfs.iter().map(|&p| (p / ps).powf(beta)).sum();
    1.0 / sum
}

/// The ratios p_i / p_s for every i (p_s > 0), by Veach's recursion (1997, ch. 10) instead of
/// products. With l = `Densities::light` and c = `Densities::camera`, moving x_i from the camera
/// subpath to the light subpath gives p_{i+1} / p_i = l_i / c_i. Technique 1 draws x0 by
/// next-event estimation instead of l_0, so the chain steps from 0 straight to 2 (ratio
/// l_0·l_1 / (c_0·c_1)) and p_1 hangs off a neighbour (p_1 / p_0 = nee / c_0). Every divisor is a
/// density of p_s itself, hence non-zero: no remap0 (pbrt) is needed, and a delta light's
/// c_0 = 0 zeroes p_0 by itself. Delta-stripped densities keep the chain finite through delta
/// vertices; techniques that connect there are zeroed at the end.
/// This is the form BDPT and VCM evaluate incrementally; `power_weight` on `Densities::all` is
/// the brute-force oracle it must match.
pub fn relative_pdfs(d: &Densities, s: usize) -> Vec<f64> {
    let k = d.k();
    let (l, c) = (&d.light, &d.camera);
    let mut r = vec![0.0; k + 2];
    r[s] = 1.0;
    if s == 1 {
        r[0] = c[0] / d.nee;
        r[2] = l[0] * l[1] / (d.nee * c[1]);
    }
    let lo = if s == 1 { 2 } else { s };
    // Up the chain: techniques lo+1 … k+1 (from 0, the step skips 1).
    let mut i = lo;
    while i <= k {
        let (next, ratio) = if i == 0 {
            (2, l[0] * l[1] / (c[0] * c[1]))
        } else {
            (i + 1, l[i] / c[i])
        };
        r[next] = r[i] * ratio;
        i = next;
    }
    // Down the chain: techniques lo−1 … 2, then 0.
    for i in (2..lo).rev() {
        r[i] = r[i + 1] * c[i] / l[i];
    }
    if lo >= 2 && s != 1 {
        r[0] = r[2] * c[0] * c[1] / (l[0] * l[1]);
    }
    if s != 1 {
        r[1] = if c[0] > 0.0 {
            r[0] * d.nee / c[0]
        } else {
            r[2] * d.nee * c[1] / (l[0] * l[1])
        };
    }
    for (i, ri) in r.iter_mut().enumerate() {
        if !d.valid(i) {
            *ri = 0.0;
        }
    }
    r
}

/// The power-heuristic weight of technique s computed from `relative_pdfs` (β = 1: balance).
pub fn power_weight_by_ratios(d: &Densities, s: usize, beta: f64) -> f64 {
    if !d.valid(s) || d.technique(s) == 0.0 {
        return 0.0;
    }
    let sum: f64 = relative_pdfs(d, s).iter().map(|&r| r.powf(beta)).sum();
    1.0 / sum
}

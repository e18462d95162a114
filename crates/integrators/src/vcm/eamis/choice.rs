//! The prediction from the pilot's sums and the choice of least predicted inefficiency: the
//! direct variance, κ (the pilot's merge correlation), merging's bias over the horizon, the
//! windows and relative weights, the merge mask (results/eamis.md, "How eamis predicts").

use super::probe::{globals, Probe, PILOT};
use super::{
    label, Choice, COST_CAMERA, COST_LIGHT, COST_MERGE, COST_QUERY, COST_VERTEX_CONNECTION,
};
use lt_core::path::efficiency::Counts;
use lt_estimators::metrics::REL_MSE_GUARD;
use lt_estimators::Image;
use std::sync::Arc;

/// Per pixel and candidate, the variance per pass of the value the candidate would get, from
/// the pilot's own samples (`Probe::direct`): each pixel's square less its value times its 8
/// neighbours' mean, averaged over the pixel's window as relative values (`relative_window`),
/// clamped at 0.
///
/// The independent-sample model, M(c) = ∫ f²/q_c, drops the cross terms between techniques: it
/// is Var + Σ_u μ_u²/n_u, not Var + μ², and on cornell-box it fell below μ² altogether. How the
/// mean is split between techniques changes with the configuration, so second moment × cost
/// ranked configurations by that split and by cost as much as by their variance (caustic-sds,
/// where μ² is most of every candidate's second moment; results/eamis.md). Merges around one
/// camera vertex share its prefix and the techniques of one camera path are correlated: summing
/// a camera sample's values before squaring keeps both.
fn direct_variance(probe: &Probe, per_pass: f64, rel: &[f64]) -> Vec<f64> {
    let (w, h) = (probe.width as usize, probe.height as usize);
    let nc = probe.candidates.len();
    let mean = |p: usize, c: usize| probe.direct_sum[p * nc + c] * per_pass;
    // x_p² − x_p x̄_q, x̄_q the mean of the 8 neighbours' (independent) samples: an estimate of
    // E[x²] − μ_p μ_q that a pixel's single sample cannot give of μ_p²; only the local gradient
    // of μ is left in it, not the window's spread of μ (the lamp's edge on cornell-box).
    let mut raw = vec![0.0; w * h * nc];
    let mut around = vec![0.0; nc];
    for y in 0..h {
        for x in 0..w {
            let p = y * w + x;
            around.fill(0.0);
            let mut count = 0usize;
            for ny in span(y, h, 1) {
                for nx in span(x, w, 1) {
                    let q = ny * w + nx;
                    if q != p {
                        count += 1;
                        around
                            .iter_mut()
                            .enumerate()
                            .for_each(|(c, a)| *a += mean(q, c));
                    }
                }
            }
            let k = 1.0 / count.max(1) as f64;
            for (c, a) in around.iter().enumerate() {
                raw[p * nc + c] = probe.direct[p * nc + c] * per_pass - mean(p, c) * (a * k);
            }
        }
    }
    let mut out = relative_window(&raw, nc, w, h, rel);
    out.iter_mut().for_each(|v| *v = v.max(0.0));
    out
}

/// κ = Σ_p rel_p · measured_p / Σ_p rel_p · predicted_p for the pilot's own configuration
/// (candidate `own`, which merges everywhere): the pilot's second moment as measured (each camera
/// sample's contributions summed before squaring, `Probe::direct`) over the independent-sample
/// model's (`Probe::moments`). Merges around one camera vertex share its prefix, which the model
/// does not see and the measurement does.
fn merge_correlation(probe: &Probe, rel: &[f64], own: usize) -> f64 {
    let nc = probe.candidates.len();
    let (mut measured, mut predicted) = (0.0, 0.0);
    for (p, r) in rel.iter().enumerate() {
        measured += r * probe.direct[p * nc + own];
        predicted += r * probe.moments[p * nc + own];
    }
    if predicted > 0.0 && measured > 0.0 {
        measured / predicted
    } else {
        1.0
    }
}

/// κ per pixel: `merge_correlation`'s ratio over the pixel's (2 `KAPPA_REACH` + 1)²
/// neighbourhood, never below the image's κ (`kappa`). Every merging candidate's variance is
/// multiplied by it. The direct variance already holds the correlation the pilot saw, so this
/// is a guard, not a correction: where one camera sample's merges are strongly correlated, one
/// pilot pass sees few of the clumps that make merging's tail, and its variance is unreliable.
/// Without it, veach-bidir merged 8–17 % of its pixels again, on the glass egg where merging's
/// caustic is heavy-tailed; with it, 1 % (results/eamis.md). The image's κ alone, a ratio of
/// sums, is set by the few pixels a rare pilot sample inflated (veach-bidir: 1.4, where the
/// pixels' own ratios have median 8.8).
fn local_merge_correlation(probe: &Probe, kappa: f64, own: usize) -> Vec<f64> {
    let (w, h) = (probe.width as usize, probe.height as usize);
    let nc = probe.candidates.len();
    // Sums over the pilot passes: the ratio needs no per-pass scale.
    let measured: Vec<f64> = (0..w * h).map(|p| probe.direct[p * nc + own]).collect();
    let predicted: Vec<f64> = (0..w * h).map(|p| probe.moments[p * nc + own]).collect();
    let measured = box_filter(&measured, 1, w, h, KAPPA_REACH);
    let predicted = box_filter(&predicted, 1, w, h, KAPPA_REACH);
    measured
        .iter()
        .zip(&predicted)
        .map(|(&m, &q)| if q > 0.0 { (m / q).max(kappa) } else { kappa })
        .collect()
}

/// The window of the per-pixel κ reaches this many pixels each way: wider than the moments'
/// (`FILTER_REACH`), since κ is a ratio that changes slowly across the image and one pilot pass
/// gives one sample per pixel (veach-bidir, 4 seeds: reach 3 left one seed at 3.9× the relMSE of
/// m2_vc1_nomerge, reach 7 at 1.8×).
pub const KAPPA_REACH: usize = 7;

/// How much lower than merging everywhere or nowhere a per-pixel mask's predicted inefficiency
/// must be for eamis to use it. A one-pass pilot misjudges the pixels at a mask's edge both ways:
/// on caustic-sds it under-predicted heavy-tailed light where it turned merging off (relMSE 317
/// at a margin of 1), on veach-bidir merging's rare fireflies where it turned it on (a mask
/// predicted 1.3× better than merging nowhere measured 5× worse; results/eamis.md).
pub const MASK_MARGIN: f64 = 2.0;

/// The moments' box filter reaches this many pixels each way.
pub const FILTER_REACH: usize = 3;

/// Pixels within this many of one where the pilot found light only merging makes merge too.
pub const MUST_MERGE_REACH: usize = 4;

/// `mask` grown by `reach` pixels in x and y.
fn dilate(mask: &[bool], w: usize, h: usize, reach: usize) -> Vec<bool> {
    let mut out = vec![false; mask.len()];
    for y in 0..h {
        for x in 0..w {
            if !mask[y * w + x] {
                continue;
            }
            for ny in span(y, h, reach) {
                for nx in span(x, w, reach) {
                    out[ny * w + nx] = true;
                }
            }
        }
    }
    out
}

/// Indices within `reach` of `i` on an axis of `len`, clamped at its ends.
fn span(i: usize, len: usize, reach: usize) -> std::ops::Range<usize> {
    i.saturating_sub(reach)..(i + reach + 1).min(len)
}

/// Per-pixel rows of `nc` values averaged over each pixel's (2 `reach` + 1)² neighbourhood
/// (clamped at the film's edges), as two passes of 2 `reach` + 1 taps: along x, then along y.
fn box_filter(values: &[f64], nc: usize, w: usize, h: usize, reach: usize) -> Vec<f64> {
    let along_x = window_sums(values, nc, w, h, reach, true);
    let mut out = window_sums(&along_x, nc, w, h, reach, false);
    for y in 0..h {
        for x in 0..w {
            let count = (span(x, w, reach).len() * span(y, h, reach).len()) as f64;
            out[(y * w + x) * nc..(y * w + x + 1) * nc]
                .iter_mut()
                .for_each(|a| *a /= count);
        }
    }
    out
}

/// Per-pixel rows of `nc` values summed over the 2 `reach` + 1 pixels around each along one
/// axis (x when `along_x`, else y), clamped at the film's edges.
fn window_sums(
    values: &[f64],
    nc: usize,
    w: usize,
    h: usize,
    reach: usize,
    along_x: bool,
) -> Vec<f64> {
    let mut out = vec![0.0; values.len()];
    for y in 0..h {
        for x in 0..w {
            let row = &mut out[(y * w + x) * nc..(y * w + x + 1) * nc];
            let taps = if along_x {
                span(x, w, reach)
            } else {
                span(y, h, reach)
            };
            for t in taps {
                let q = if along_x { y * w + t } else { t * w + x };
                let src = &values[q * nc..(q + 1) * nc];
                row.iter_mut().zip(src).for_each(|(a, b)| *a += b);
            }
        }
    }
    out
}

/// Rows of `nc` per-pixel values averaged over each pixel's (2 `FILTER_REACH` + 1)² window as
/// relative values (each weighed by its own pixel's `rel`), then divided by the pixel's `rel`:
/// times `rel` again, a pixel gets its window's mean relative value. Averaging absolute values
/// instead weighed a bright pixel's μ² as its dark neighbours' (cornell-box: the lamp's edge
/// made the whole prediction; results/eamis.md).
fn relative_window(values: &[f64], nc: usize, w: usize, h: usize, rel: &[f64]) -> Vec<f64> {
    let scaled: Vec<f64> = values
        .iter()
        .enumerate()
        .map(|(i, v)| v * rel[i / nc])
        .collect();
    let mut out = box_filter(&scaled, nc, w, h, FILTER_REACH);
    out.iter_mut()
        .enumerate()
        .for_each(|(i, v)| *v /= rel[i / nc]);
    out
}

/// 1/(μ̃ + 0.01)² per pixel (pbrt's relMSE guard), μ̃ the median of the pilot's estimate over
/// the pixel and its 8 neighbours: one pilot sample per pixel is no estimate of the pixel's
/// value where rare light lands (caustic-sds: a pixel whose one sample found the caustic would
/// weigh its own moment by its firefly and call it small).
fn relative_weights(estimate: &Image, w: usize, h: usize) -> Vec<f64> {
    let mean = |p: usize| {
        let c = estimate.data[p];
        (c[0] + c[1] + c[2]) / 3.0
    };
    (0..w * h)
        .map(|p| {
            let (x, y) = (p % w, p / w);
            let (mut around, mut len) = ([0.0; 9], 0);
            for ny in span(y, h, 1) {
                for nx in span(x, w, 1) {
                    around[len] = mean(ny * w + nx);
                    len += 1;
                }
            }
            let around = &mut around[..len];
            around.sort_by(f64::total_cmp);
            let mu = around[len / 2];
            1.0 / (mu.max(0.0) + REL_MSE_GUARD).powi(2)
        })
        .collect()
}

/// The render the choice is made for: merging's bias weighs in over `passes`.
pub(super) struct Horizon {
    pub(super) passes: u32,
    pub(super) alpha: f64,
    pub(super) pilot_passes: u32,
}

impl Horizon {
    /// P s(P)², s(P) = (1/P) Σ_{i=1}^{P} i^(α−1): what b₀² adds to a merging pixel's per-pass
    /// moment when relMSE × time is divided by P (the module's doc).
    fn bias_factor(&self) -> f64 {
        let p = self.passes.max(1);
        let s = (1..=p)
            .map(|i| (i as f64).powf(self.alpha - 1.0))
            .sum::<f64>()
            / p as f64;
        p as f64 * s * s
    }
}

/// Per pixel and global candidate g, b₀² of merging at r₀: 4 × (the pilot's mean difference
/// squared less its sampling variance), averaged over the pixel's (2 `FILTER_REACH` + 1)²
/// neighbourhood and clamped at 0. Laid out as `Probe::bias_diff`.
fn merge_bias_squared(probe: &Probe, pilot_passes: u32, rel: &[f64]) -> Vec<f64> {
    let g_count = probe.candidates.len() / 2;
    let (w, h) = (probe.width as usize, probe.height as usize);
    let k = 1.0 / pilot_passes.max(1) as f64;
    let raw: Vec<f64> = probe
        .bias_diff
        .iter()
        .zip(&probe.bias_terms_sq)
        .map(|(d, sq)| 4.0 * ((d * k).powi(2) - sq * k * k))
        .collect();
    let mut out = relative_window(&raw, g_count, w, h, rel);
    out.iter_mut().for_each(|b| *b = b.max(0.0));
    out
}

/// The configuration of least predicted inefficiency from the pilot's `probe` and estimate.
pub(super) fn choose(probe: &Probe, estimate: &Image, horizon: &Horizon) -> Choice {
    let n = estimate.data.len();
    let nc = probe.candidates.len();
    let (w, h) = (probe.width as usize, probe.height as usize);
    let rel = relative_weights(estimate, w, h);
    let fixed_work = COST_CAMERA * (probe.camera_samples + 2 * probe.shadow_rays_fixed) as f64;
    // Light a candidate makes no path for is a bias no pass removes: over the horizon's P passes
    // it adds P b² to the per-pass moment (b the light missed per pass). One pilot pass is one
    // sample per pixel: each pixel's moments are averaged over its 7 × 7 neighbourhood, which
    // keeps the total a rare path the pilot saw once adds and spreads it to the pixels around.
    // The probe's sums run over every pilot pass; the bias terms below are per pass, so the
    // moments are too.
    let per_pass = 1.0 / horizon.pilot_passes.max(1) as f64;
    // P b² of candidate c in pixel p.
    let missed_bias =
        |p: usize, c: usize| horizon.passes as f64 * (probe.missed[p * nc + c] * per_pass).powi(2);
    let missed: Vec<f64> = (0..n * nc).map(|i| missed_bias(i / nc, i % nc)).collect();
    let missed = relative_window(&missed, nc, w, h, &rel);
    let variance = direct_variance(probe, per_pass, &rel);
    // The independent-sample model's moments, from every pilot sample and (without merging,
    // global g's candidate 2g + 1) from the samples that are not merges: where merging is
    // unbiased, their difference is light the merges witness that the other techniques find
    // rarely — a heavy tail one pilot pass does not show in the techniques' own samples
    // (caustic-sds).
    let per_pass_sums = |v: &[f64], k: usize| {
        let scaled: Vec<f64> = v.iter().map(|m| m * per_pass).collect();
        relative_window(&scaled, k, w, h, &rel)
    };
    let independent = per_pass_sums(&probe.moments, nc);
    let independent_unmerged = per_pass_sums(&probe.moments_unmerged, nc / 2);
    // Light only merging reaches, seen by the pilot in one pixel, is likely in the pixels around
    // it that one pass did not sample (caustic-sds: a mask of the pixels the pilot saw it in
    // merged 7–10 % of the image and was 97× the best fixed configuration's inefficiency): every
    // pixel within `MUST_MERGE_REACH` of one merges, and merging nowhere is not an option.
    let only_merging: Vec<bool> = (0..n)
        .map(|p| (0..nc / 2).any(|g| probe.missed[p * nc + 2 * g + 1] != 0.0))
        .collect();
    let must_merge = dilate(&only_merging, w, h, MUST_MERGE_REACH);
    let any_must = must_merge.iter().any(|&m| m);
    let must_share = must_merge.iter().filter(|&&m| m).count() as f64 / n.max(1) as f64;
    let g_count = nc / 2;
    let bias2 = merge_bias_squared(probe, horizon.pilot_passes, &rel);
    let bias_factor = horizon.bias_factor();
    let pilot_g = globals()
        .iter()
        .position(|&(r, vc)| r == PILOT.light_ratio && vc == PILOT.vertex_connections)
        .unwrap_or(0);
    // The pilot's own candidate: global `pilot_g` with merging.
    let own = 2 * pilot_g;
    // Pixels where merging's predicted bias outweighs its variance: their merges witness a
    // blurred integrand, so they witness nothing for the configurations without merging.
    let bias_dominated: Vec<bool> = (0..n)
        .map(|p| bias_factor * bias2[p * g_count + pilot_g] > variance[p * nc + own])
        .collect();
    let bias_share = {
        let g = pilot_g;
        let bias: f64 = (0..n)
            .map(|p| bias_factor * bias2[p * g_count + g] * rel[p])
            .sum();
        let var: f64 = (0..n).map(|p| variance[p * nc + own] * rel[p]).sum();
        if bias + var > 0.0 {
            bias / (bias + var)
        } else {
            0.0
        }
    };
    let direct_over_independent = {
        let d: f64 = (0..n).map(|p| variance[p * nc + own] * rel[p]).sum();
        let i: f64 = (0..n).map(|p| independent[p * nc + own] * rel[p]).sum();
        d / i
    };
    // Merging's variance is floored by κ per pixel (`local_merge_correlation`), after the
    // comparisons above, which weigh the bias against the variance as the pilot measured it.
    let kappa = merge_correlation(probe, &rel, own);
    let kappa_at = local_merge_correlation(probe, kappa, own);
    let kappa_median = {
        let mut sorted = kappa_at.clone();
        sorted.sort_by(f64::total_cmp);
        sorted.get(sorted.len() / 2).copied().unwrap_or(kappa)
    };
    let mut variance = variance;
    for (p, k) in kappa_at.iter().enumerate() {
        for g in 0..g_count {
            variance[p * nc + 2 * g] *= k;
        }
    }
    // Index of candidate c in pixel p.
    let p_c = |c: usize| move |p: usize| p * nc + c;
    let mut best: Option<Choice> = None;
    let mut fixed = Vec::new();
    for (g, (ratio, vc)) in globals().into_iter().enumerate() {
        let cost0 = fixed_work
            + COST_LIGHT * ratio * (probe.light_vertices + probe.light_tracing) as f64
            + if vc {
                COST_VERTEX_CONNECTION * probe.vertex_connections as f64
            } else {
                0.0
            };
        let (on_c, off_c) = (p_c(2 * g), p_c(2 * g + 1));
        let on = |p: usize| {
            (variance[on_c(p)] + missed[on_c(p)] + bias_factor * bias2[p * g_count + g]) * rel[p]
        };
        let off = |p: usize| {
            let witnessed = if bias_dominated[p] {
                0.0
            } else {
                (independent[off_c(p)] - independent_unmerged[p * g_count + g]).max(0.0)
            };
            (variance[off_c(p)] + missed[off_c(p)] + witnessed) * rel[p]
        };
        let merge_cost = |p: usize| {
            COST_QUERY * probe.merge_queries[p] as f64
                + COST_MERGE * ratio * probe.merges_found[p] as f64
        };
        let all_on: f64 =
            (0..n).map(on).sum::<f64>() * (cost0 + (0..n).map(merge_cost).sum::<f64>());
        let all_off: f64 = (0..n).map(off).sum::<f64>() * cost0;
        fixed.push((label(&probe.candidates[2 * g]), all_on / n as f64));
        fixed.push((label(&probe.candidates[2 * g + 1]), all_off / n as f64));
        let mut v: f64 = (0..n)
            .map(|p| if must_merge[p] { on(p) } else { off(p) })
            .sum();
        let mut c = cost0
            + (0..n)
                .filter(|&p| must_merge[p])
                .map(merge_cost)
                .sum::<f64>();
        // Pixels where merging lowers the moment, by moment saved per cost added.
        let mut gain: Vec<(f64, usize)> = (0..n)
            .filter(|&p| !must_merge[p] && on(p) < off(p))
            .map(|p| ((off(p) - on(p)) / merge_cost(p).max(1e-9), p))
            .collect();
        gain.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let (mut best_j, mut best_len) = (v * c, 0);
        for (i, &(_, p)) in gain.iter().enumerate() {
            v -= off(p) - on(p);
            c += merge_cost(p);
            if v * c < best_j {
                best_j = v * c;
                best_len = i + 1;
            }
        }
        // The per-pixel mask must beat merging everywhere and nowhere by `MASK_MARGIN`: one pilot
        // pass misses rare, heavy-tailed light on either side of the mask's edge.
        let uniform = if any_must {
            all_on
        } else {
            all_on.min(all_off)
        };
        let use_mask = best_j * MASK_MARGIN < uniform;
        let (predicted, everywhere) = if use_mask {
            (best_j / n as f64, false)
        } else {
            (uniform / n as f64, any_must || all_on <= all_off)
        };
        if predicted.is_finite() && best.as_ref().is_none_or(|b| predicted < b.predicted) {
            let mut mask = vec![everywhere; n];
            if use_mask {
                for &(_, p) in &gain[..best_len] {
                    mask[p] = true;
                }
                for (m, &must) in mask.iter_mut().zip(&must_merge) {
                    *m |= must;
                }
            }
            let best_len = mask.iter().filter(|&&m| m).count();
            best = Some(Choice {
                counts: Counts {
                    light_ratio: ratio,
                    vertex_connections: vc,
                    merging: best_len > 0,
                },
                merge_mask: Arc::from(mask),
                predicted,
                fixed: Vec::new(),
                direct_over_independent,
                merge_correlation: kappa,
                merge_correlation_median: kappa_median,
                bias_share,
                must_merge: must_share,
            });
        }
    }
    // Every global candidate ruled out (light no candidate samples, e.g. a path only vertex
    // connections make): the pilot's own configuration, which runs every technique.
    let mut choice = best.unwrap_or_else(|| Choice {
        counts: PILOT,
        merge_mask: Arc::from(vec![true; n]),
        predicted: f64::INFINITY,
        fixed: Vec::new(),
        direct_over_independent,
        merge_correlation: kappa,
        merge_correlation_median: kappa_median,
        bias_share,
        must_merge: must_share,
    });
    choice.fixed = fixed;
    choice
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The separable filter against the window's mean summed directly; the tolerance is f64
    /// rounding of sums taken in another order, not a statistical one.
    #[test]
    fn box_filter_is_the_mean_over_the_clamped_window() {
        let (w, h, nc, reach) = (9, 7, 3, 2);
        let values: Vec<f64> = (0..w * h * nc)
            .map(|i| ((i * 7919) % 101) as f64 - 50.0)
            .collect();
        let got = box_filter(&values, nc, w, h, reach);
        for y in 0..h {
            for x in 0..w {
                for c in 0..nc {
                    let (mut sum, mut count) = (0.0, 0.0);
                    for ny in y.saturating_sub(reach)..(y + reach + 1).min(h) {
                        for nx in x.saturating_sub(reach)..(x + reach + 1).min(w) {
                            sum += values[(ny * w + nx) * nc + c];
                            count += 1.0;
                        }
                    }
                    let want = sum / count;
                    let have = got[(y * w + x) * nc + c];
                    assert!(
                        (have - want).abs() <= 1e-12 * want.abs().max(1.0),
                        "({x}, {y}) channel {c}: {have} against {want}"
                    );
                }
            }
        }
    }

    /// A pixel whose one pilot sample found a firefly keeps the relative weight of the value
    /// around it: the median of its 3 × 3 neighbourhood, not its own estimate.
    #[test]
    fn a_lone_firefly_does_not_set_its_pixels_relative_weight() {
        let (w, h) = (5, 4);
        let mut img = Image::new(w, h);
        img.data.iter_mut().for_each(|p| *p = [0.1; 3]);
        img.data[2 * w + 2] = [1000.0; 3];
        let rel = relative_weights(&img, w, h);
        let want = 1.0 / (0.1 + REL_MSE_GUARD).powi(2);
        for (p, r) in rel.iter().enumerate() {
            assert!(
                (r - want).abs() <= 1e-9 * want,
                "pixel {p}: {r} against {want}"
            );
        }
    }
}

//! Correlation-aware MIS for merging (Grittmann, Georgiev & Slusallek, "Correlation-Aware
//! Multiple Importance Sampling for Bidirectional Rendering Algorithms", EG 2021): the merges
//! around one camera vertex share one set of N_VM light subpaths, so they are not N_VM independent
//! samples. Merging at x_i is given the effective count N_VM ρ_i, i.e. η_i = N_VM π r² ρ_i in the
//! heuristics in place of η, for that merge technique only (every other technique's weight changes
//! only through the denominator):
//!
//!   ρ_i = P_c,i / (P_c,i + P_l,i − P_c,i P_l,i),   clamped to ≥ 1 / N_VM,   ρ = 1 at x_{k−1},
//!
//! with P_c,i = ∏_{i ≤ j ≤ k−1} min(1, A c_j) (the camera prefix reaching x_i, each area density
//! turned into the probability of landing in a footprint of area A) and P_l,i = ∏_{j ≤ i}
//! min(1, A l_j) (the light prefix reaching x_i), A = π r_c², r_c = |x_k − x_{k−1}| tan 1° (a
//! footprint at the primary hit's distance). This is the form of the authors' public VCM
//! re-implementation (pgrit/EfficiencyAwareMIS, `CorrelAwareVcm`), which the brief of this change
//! states; the paper derives the correlation factor from the same prefix/suffix probabilities
//! (§4–5). Whether a product includes x_i itself on both sides, and the primary hit's ρ = 1, follow
//! that implementation: the paper's text could not be consulted from this machine, so no equation
//! number is claimed here.
//!
//! ρ_i depends on both subpaths' products, which VCM's per-vertex recursion (`SubpathMis`) cannot
//! carry: with the option on, integrators weigh every technique from the full path's per-vertex
//! densities ([`weight`], O(k) per technique from prefix and suffix products). The oracle
//! (`Densities::vcm_weight_with`, `Densities::correlation_ratio`) builds each technique's density
//! from scratch, one product per technique, and is what [`weight`] is held to.

use super::correlation::Correlation;
use super::merging::{Technique, TechniqueSet};
use super::mis::{Chain, Heuristic};

/// Paths up to this many vertices (k ≤ 24) weigh without allocating.
const STACK: usize = 26;

/// The effective densities n_u·p_u of one path's techniques, summed by how their sample counts
/// scale with a configuration's choices (efficiency-aware MIS, `path::efficiency`): what is
/// fixed per camera sample, what scales with the light subpath count M, what a vertex
/// connection adds, what merging adds. Their sum is the balance heuristic's denominator.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Mixture {
    /// n·p of the technique that made the path.
    pub own: f64,
    /// s = 0 (the camera walk reached the light) and s = 1 (next-event estimation): once per
    /// camera sample whatever the configuration.
    pub fixed: f64,
    /// s = k, light tracing: M/N per camera sample.
    pub light_tracing: f64,
    /// s = 2 … k−1, vertex connections: once per camera sample when on.
    pub vertex_connections: f64,
    /// Merging at every x_i as the weights counted it: η each, or η ρ_i with correlation-aware
    /// weights; η = M π r².
    pub merges: f64,
    /// Merging at every x_i counted η ρ_i (correlation-aware MIS's effective count) whenever a
    /// `Correlation` was given, whatever the weights counted: what efficiency-aware MIS predicts
    /// merging's second moment with, since the merges of one camera vertex share its prefix.
    pub merges_correlated: f64,
}

impl Mixture {
    /// Σ_u n_u p_u.
    pub fn total(&self) -> f64 {
        self.fixed + self.light_tracing + self.vertex_connections + self.merges
    }
}

/// A technique's weight and the effective densities it was computed from.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Weighed {
    pub weight: f64,
    pub mixture: Mixture,
}

/// The weight of `technique` under `h` over every technique of `set` from the full path's
/// per-vertex densities in `chain`, merging at x_i counted η ρ_i times with `corr`
/// (correlation-aware) and η times without: O(k) through prefix products ∏_{j<s} l_j and suffix
/// products ∏_{j≥s} c_j (what the integrators run; the oracle is `Densities::vcm_weight_with`).
pub fn weight(
    chain: &Chain,
    set: TechniqueSet,
    corr: Option<&Correlation>,
    technique: Technique,
    h: Heuristic,
) -> f64 {
    weigh(chain, set, corr, technique, h).weight
}

/// [`weight`] with the effective densities grouped as [`Mixture`] (balance-heuristic sums,
/// whatever `h`).
pub fn weigh(
    chain: &Chain,
    set: TechniqueSet,
    corr: Option<&Correlation>,
    technique: Technique,
    h: Heuristic,
) -> Weighed {
    weigh_full(chain, set, corr, corr.is_some(), technique, h)
}

/// [`weigh`] with ρ_i computed from `corr` for `Mixture::merges_correlated` and applied to the
/// weights only when `correlated_weights`.
pub fn weigh_full(
    chain: &Chain,
    set: TechniqueSet,
    corr: Option<&Correlation>,
    correlated_weights: bool,
    technique: Technique,
    h: Heuristic,
) -> Weighed {
    let k = chain.k();
    let (mut la, mut ca, mut pa) = ([0.0f64; STACK], [0.0f64; STACK], [0.0f64; STACK]);
    let (mut lv, mut cv, mut pv) = (Vec::new(), Vec::new(), Vec::new());
    let (lpre, csuf, p): (&mut [f64], &mut [f64], &mut [f64]) = if 2 * k + 3 <= STACK {
        (&mut la, &mut ca, &mut pa)
    } else {
        lv.resize(k + 2, 0.0);
        cv.resize(k + 2, 0.0);
        pv.resize(2 * k + 3, 0.0);
        (&mut lv, &mut cv, &mut pv)
    };
    // lpre[s] = ∏_{j<s} l_j, csuf[s] = ∏_{j≥s} c_j, s = 0 … k+1.
    lpre[0] = 1.0;
    for j in 0..=k {
        lpre[j + 1] = lpre[j] * chain.light[j];
    }
    csuf[k + 1] = 1.0;
    for j in (0..=k).rev() {
        csuf[j] = csuf[j + 1] * chain.camera[j];
    }
    // Connection techniques s = 0 … k+1 at p[s], merges i = 0 … k at p[k + 2 + i].
    for s in 0..=k + 1 {
        let vertex_connection = s >= 2 && s < k;
        p[s] = if !chain.valid(s)
            || (s >= 1 && !set.connections)
            || (vertex_connection && !set.vertex_connections)
        {
            0.0
        } else {
            let prefix = if s == 1 && chain.one_is_nee() {
                chain.nee
            } else {
                lpre[s]
            };
            chain.sample_count(s) * prefix * csuf[s]
        };
    }
    let eta = set.merging_eta;
    // P_c,i as a running suffix product from x_{k−1} down, P_l,i as a prefix product.
    let mut p_camera = 1.0;
    let mut p_light_below = 1.0;
    let a = corr.map_or(0.0, |c| c.footprint);
    let mut p_light = [0.0f64; STACK];
    let mut p_light_v = Vec::new();
    let pl: &mut [f64] = if k < STACK {
        &mut p_light[..=k]
    } else {
        p_light_v.resize(k + 1, 0.0);
        &mut p_light_v
    };
    for (p_l, &l) in pl.iter_mut().zip(chain.light) {
        p_light_below *= (a * l).min(1.0);
        *p_l = p_light_below;
    }
    p[k + 2] = 0.0;
    p[2 * k + 2] = 0.0;
    let mut merges_correlated = 0.0;
    for i in (1..k).rev() {
        p_camera *= (a * chain.camera[i]).min(1.0);
        let rho = match corr {
            Some(corr) if i + 1 < k => corr.ratio(p_camera, pl[i]),
            _ => 1.0,
        };
        let independent = if eta > 0.0 && chain.connectable[i] {
            eta * lpre[i + 1] * csuf[i]
        } else {
            0.0
        };
        merges_correlated += independent * rho;
        p[k + 2 + i] = if correlated_weights {
            independent * rho
        } else {
            independent
        };
    }
    let own = match technique {
        Technique::Connect(s) => p[s],
        Technique::Merge(i) => p[k + 2 + i],
    };
    if own.is_nan() || own <= 0.0 {
        return Weighed::default();
    }
    let all = &p[..2 * k + 3];
    let sum: f64 = match h {
        Heuristic::Balance => all.iter().map(|&x| x / own).sum(),
        Heuristic::Power => all.iter().map(|&x| (x / own) * (x / own)).sum(),
        Heuristic::Uniform => all.iter().filter(|&&x| x > 0.0).count() as f64,
    };
    let w = 1.0 / sum;
    let fixed = p[0] + if k >= 2 { p[1] } else { 0.0 } + p[k + 1];
    let mixture = Mixture {
        own,
        fixed,
        light_tracing: p[k],
        vertex_connections: if k >= 3 { p[2..k].iter().sum() } else { 0.0 },
        merges: p[k + 2..2 * k + 3].iter().sum(),
        merges_correlated,
    };
    Weighed {
        weight: if w.is_finite() { w } else { 0.0 },
        mixture,
    }
}

//! Efficiency-aware MIS (Grittmann, Yazici, Georgiev & Slusallek, "Efficiency-aware multiple
//! importance sampling for bidirectional rendering algorithms", SIGGRAPH 2022): predict, from
//! the samples of a pilot configuration, the second moment every other configuration of the
//! same techniques would have, so that sample counts can be chosen by predicted efficiency.
//!
//! **The prediction.** A multi-sample MIS estimator with counts n_u and the balance heuristic
//! has the per-camera-sample second moment (cross terms of independent samples dropped)
//!
//!   M(c) = ∫ f(x̄)² / q_c(x̄) dx̄,   q_c = Σ_u n_u^c p_u   (Veach 1997, §9.2.2).
//!
//! Any MIS estimator of the pilot estimates an integral ∫ g as Σ w_u g / (n_u p_u) over its
//! samples. With g = f²/q_c and a sample's unweighted value V = f/(n_u p_u), one sample of
//! technique u adds
//!
//!   w_u · V² · n_u p_u / q_c                                  ([`Counts::second_moment_term`])
//!
//! whatever heuristic gave w_u: an unbiased estimate of M(c) for every c whose techniques the
//! pilot runs. q_c follows from the pilot's effective densities grouped by how their counts scale
//! ([`Mixture`]): light tracing and merging (η = M π r²) with the light subpath count M, vertex
//! connections on or off, the rest fixed per camera sample.
//!
//! **Merges are not independent samples.** The merges around one camera vertex share its camera
//! prefix (Grittmann et al., EG 2021), so counting them η = M π r² times overstates what merging
//! buys: on cornell-box (64 px) the η-count prediction chose merging in 85 % of the pixels, and the
//! measured inefficiency of that choice was 2.8× the best fixed configuration's (no merging).
//! q_c therefore counts merging η ρ_i (`Mixture::merges_correlated`, correlation-aware MIS's
//! effective count) while the pilot's weights keep η; the identity above then estimates the
//! second moment of that model, not of the exact correlated estimator.
//!
//! The paper's own derivation and its cost model could not be read from this machine; this is
//! the second-moment identity above, which the paper builds on, not its text.

use super::camis::Mixture;

/// How a technique's sample count scales between configurations of the VCM family: the groups
/// of `Mixture`'s fields.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scaling {
    /// s = 0, s = 1 (next-event estimation) and t = 0: once per camera sample (`Mixture::fixed`).
    PerCameraSample,
    /// t = 1: M/N per camera sample.
    LightTracing,
    /// s ≥ 2, t ≥ 2: once per camera sample when on.
    VertexConnection,
    /// η = M π r² per camera vertex when on.
    Merge,
}

impl Scaling {
    /// The scaling of technique (s, t) (s light vertices, t camera vertices), or of a merge.
    pub fn of(s: usize, t: usize, merge: bool) -> Scaling {
        if merge {
            Scaling::Merge
        } else if t == 1 {
            Scaling::LightTracing
        } else if s >= 2 && t >= 2 {
            Scaling::VertexConnection
        } else {
            Scaling::PerCameraSample
        }
    }
}

/// The sample counts of one configuration of the VCM family, per camera sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Counts {
    /// M/N: light subpaths per camera sample.
    pub light_ratio: f64,
    /// Vertex connections s ≥ 2, t ≥ 2 (one light subpath per camera vertex).
    pub vertex_connections: bool,
    /// Merging, counted η = M π r² (so it scales with M at a fixed radius).
    pub merging: bool,
}

impl Counts {
    /// Σ_u n_u p_u of a path under `self`, from its `mixture` as `pilot` weighed it. The pilot
    /// must run every technique `self` does (vertex connections, merging).
    pub fn total(&self, mixture: &Mixture, pilot: &Counts) -> f64 {
        self.total_with_merges(mixture, pilot, mixture.merges_correlated)
    }

    /// `total` with merging at the pilot's light-path count counted `merges` (η ρ for the
    /// second-moment model, η as the weights count it).
    fn total_with_merges(&self, mixture: &Mixture, pilot: &Counts, merges: f64) -> f64 {
        let r = self.light_ratio / pilot.light_ratio;
        let vc = if self.vertex_connections {
            mixture.vertex_connections
        } else {
            0.0
        };
        let vm = if self.merging { r * merges } else { 0.0 };
        mixture.fixed + r * mixture.light_tracing + vc + vm
    }

    /// The balance weight `self` would give a merge the pilot weighed with `mixture`:
    /// n_u p_u / Σ_v n_v p_v with merging counted η (as the weights count it, not η ρ), the
    /// merge's own count scaling with M. 0 where `self` does not merge.
    pub fn merge_weight(&self, mixture: &Mixture, pilot: &Counts) -> f64 {
        if !self.merging {
            return 0.0;
        }
        let r = self.light_ratio / pilot.light_ratio;
        let total = self.total_with_merges(mixture, pilot, mixture.merges);
        if total > 0.0 {
            r * mixture.own / total
        } else {
            0.0
        }
    }

    /// The weighted value `self` gives the pilot's sample of a technique scaling as `scaling`,
    /// with unweighted value `value` = f/(n_u p_u) under the pilot: the balance heuristic's
    /// f/q_c = value · n_u p_u / q_c, merging counted η as the weights count it (the count of
    /// light tracing and merging scales with M, so their n_u^c p_u/n_u^c cancels). The camera
    /// walk, next-event estimation and the connections draw their paths alike in every
    /// configuration, so summing these over one camera sample gives the value `self` would
    /// have got from it. 0 where `self` does not run the technique or makes no path.
    pub fn contribution(
        &self,
        value: f64,
        mixture: &Mixture,
        pilot: &Counts,
        scaling: Scaling,
    ) -> f64 {
        let runs = match scaling {
            Scaling::VertexConnection => self.vertex_connections,
            Scaling::Merge => self.merging,
            Scaling::PerCameraSample | Scaling::LightTracing => true,
        };
        let q = self.total_with_merges(mixture, pilot, mixture.merges);
        if !runs || !(mixture.own > 0.0) || !(q > 0.0) {
            return 0.0;
        }
        value * mixture.own / q
    }

    /// One pilot sample's share of the second moment M(`self`): w · v² · n_u p_u / q_c, for a
    /// sample of weight `weight` and unweighted value `value` whose effective densities under
    /// `pilot` are `mixture`. Infinite where the sample carries light but no technique of `self`
    /// makes its path (q_c = 0): `self` would miss that light, an error no number of samples
    /// removes.
    pub fn second_moment_term(
        &self,
        weight: f64,
        value: f64,
        mixture: &Mixture,
        pilot: &Counts,
    ) -> f64 {
        let q = self.total(mixture, pilot);
        let term = weight * value * value;
        if !(mixture.own > 0.0) || term == 0.0 {
            0.0
        } else if q > 0.0 {
            term * mixture.own / q
        } else {
            f64::INFINITY
        }
    }

    /// The same for a configuration without merging, from the pilot's samples that are not
    /// merges (`merge` false) alone, each reweighted by the balance heuristic over the
    /// techniques that are not merges: weights summing to one over techniques that cover the
    /// integrand keep the estimate unbiased. A merge's value is the blurred integrand; where
    /// merging is biased it is not the f² a configuration without merging would see, and on
    /// veach-bidir [`second_moment_term`](Self::second_moment_term) inflated such a
    /// configuration's predicted moment 25× past merging everywhere, whose measured
    /// inefficiency was 50× worse (results/eamis.md). Where merging is unbiased the merges are
    /// the better witnesses of light the other techniques find rarely (caustic-sds), so eamis
    /// uses this estimate only where it predicts merging's bias to dominate.
    pub fn second_moment_term_without_merges(
        &self,
        value: f64,
        mixture: &Mixture,
        pilot: &Counts,
        merge: bool,
    ) -> f64 {
        debug_assert!(!self.merging);
        let q = self.total(mixture, pilot);
        let own = mixture.own;
        if merge || !(own > 0.0) || value == 0.0 {
            return 0.0;
        }
        if !(q > 0.0) {
            return f64::INFINITY;
        }
        let without_merges = Counts {
            merging: false,
            ..*pilot
        }
        .total(mixture, pilot);
        (own / without_merges) * value * value * own / q
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::path::camis::weigh;
    use crate::path::{Densities, Heuristic, Technique, TechniqueSet};
    use rand_pcg::rand_core::Rng as _;
    use rand_pcg::Pcg32;

    struct Pcg64(Pcg32);

    impl Pcg64 {
        fn seed_from_u64(seed: u64) -> Pcg64 {
            Pcg64(Pcg32::new(seed, 0x5bd1_e995_2022_0001))
        }

        fn gen_range(&mut self, r: std::ops::Range<f64>) -> f64 {
            let u = (self.0.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
            r.start + (r.end - r.start) * u
        }

        fn gen_bool(&mut self, p: f64) -> bool {
            self.gen_range(0.0..1.0) < p
        }
    }

    fn random_path(rng: &mut Pcg64, k: usize) -> Densities {
        let mut pick = || 10f64.powf(rng.gen_range(-3.0..3.0));
        let light: Vec<f64> = (0..=k).map(|_| pick()).collect();
        let camera: Vec<f64> = (0..=k).map(|_| pick()).collect();
        let nee = pick();
        let connectable = (0..=k).map(|_| rng.gen_bool(0.85)).collect();
        let mut d = Densities {
            light,
            camera,
            nee,
            connectable,
            light_tracing_ratio: 10f64.powf(rng.gen_range(-1.0..1.0)),
        };
        d.light[k] = 0.0;
        d.camera[k] = 1.0;
        d
    }

    /// q_c predicted from the pilot's grouped densities equals the oracle's Σ n_u p_u of `c`
    /// built from scratch (`Densities::effective_vcm`) — for every technique a pilot sample may
    /// come from, every path length and every configuration.
    #[test]
    fn predicted_mixture_totals_match_the_oracle_for_every_configuration() {
        let mut rng = Pcg64::seed_from_u64(2022);
        let mut checked = 0;
        for trial in 0..4000 {
            let k = 1 + trial % 7;
            let d = random_path(&mut rng, k);
            let eta = 10f64.powf(rng.gen_range(-3.0..3.0));
            let pilot = Counts {
                light_ratio: d.light_tracing_ratio,
                vertex_connections: true,
                merging: true,
            };
            let set = TechniqueSet::new(true, eta);
            // Per configuration: Σ over techniques of n_u p_u × share, and q_c; then the same
            // for the configurations without merging, from the samples that are not merges.
            let mut integrand = [(0.0, 0.0); 8];
            for own in d.vcm_techniques(set) {
                let w = weigh(&d.chain(), set, None, own, Heuristic::Balance);
                for (ci, (r, vc, vm)) in
                    [(0.25, true, true), (2.0, false, true), (1.0, true, false)]
                        .into_iter()
                        .chain([(0.5, false, false)])
                        .enumerate()
                {
                    let c = Counts {
                        light_ratio: pilot.light_ratio * r,
                        vertex_connections: vc,
                        merging: vm,
                    };
                    let mut dc = d.clone();
                    dc.light_tracing_ratio = c.light_ratio;
                    let set_c = TechniqueSet {
                        vertex_connections: vc,
                        ..TechniqueSet::new(true, if vm { eta * r } else { 0.0 })
                    };
                    let (vcs, vms) = dc.effective_vcm(set_c);
                    let want: f64 = vcs.iter().chain(&vms).sum();
                    let got = c.total(&w.mixture, &pilot);
                    assert!(
                        (got - want).abs() <= 1e-12 * want.max(1e-300),
                        "k {k}, {own:?}, ratio ×{r}, vc {vc}, vm {vm}: predicted {got}, oracle {want}"
                    );
                    // Σ_u n_u p_u × (one sample of u's share of M(c)) = f²/q_c, the integrand of
                    // M(c), whatever u (value f/(n_u p_u) with f = 1); merges add nothing
                    // without merging.
                    {
                        let total_c = c.total(&w.mixture, &pilot);
                        let is_merge = matches!(own, Technique::Merge(_));
                        let v = 1.0 / w.mixture.own;
                        let share =
                            c.second_moment_term(w.weight, v, &w.mixture, &pilot) * w.mixture.own;
                        integrand[ci].0 += share;
                        integrand[ci].1 = total_c;
                        if !vm {
                            let share = c
                                .second_moment_term_without_merges(v, &w.mixture, &pilot, is_merge)
                                * w.mixture.own;
                            integrand[4 + ci].0 += share;
                            integrand[4 + ci].1 = total_c;
                        }
                    }
                    // The value `c` gives the sample (f = 1): its oracle balance weight over
                    // n_u^c p_u, 0 where `c` does not run the technique.
                    {
                        let (scaling, n_c) = match own {
                            Technique::Merge(_) => (Scaling::Merge, w.mixture.own * r),
                            Technique::Connect(s) => {
                                let sc = Scaling::of(s, k + 1 - s, false);
                                let n = if sc == Scaling::LightTracing { r } else { 1.0 };
                                (sc, w.mixture.own * n)
                            }
                        };
                        let runs = match scaling {
                            Scaling::VertexConnection => vc,
                            Scaling::Merge => vm,
                            _ => true,
                        };
                        let got = c.contribution(1.0 / w.mixture.own, &w.mixture, &pilot, scaling);
                        let want = if runs {
                            weigh(&dc.chain(), set_c, None, own, Heuristic::Balance).weight / n_c
                        } else {
                            0.0
                        };
                        assert!(
                            (got - want).abs() <= 1e-9 * want.abs().max(1e-300),
                            "k {k}, {own:?}, ratio ×{r}, vc {vc}, vm {vm}: value {got}, oracle {want}"
                        );
                    }
                    // A merge's balance weight under `c`, against the oracle's weights of `c`.
                    if let Technique::Merge(_) = own {
                        let got = c.merge_weight(&w.mixture, &pilot);
                        let want = if vm {
                            weigh(&dc.chain(), set_c, None, own, Heuristic::Balance).weight
                        } else {
                            0.0
                        };
                        assert!(
                            (got - want).abs() <= 1e-12,
                            "k {k}, {own:?}, ratio ×{r}, vc {vc}: merge weight {got}, oracle {want}"
                        );
                    }
                    checked += 1;
                }
                // The pilot's own total is its balance weight's denominator.
                let own_p = w.mixture.own;
                assert!((own_p / w.mixture.total() - w.weight).abs() <= 1e-12);
                if let Technique::Merge(_) = own {
                    assert!(w.mixture.merges >= own_p);
                }
            }
            for (ci, (sum, q)) in integrand.iter().enumerate() {
                if ci >= 4 && [2, 3].binary_search(&(ci - 4)).is_err() {
                    continue; // merging configurations have no estimate without merges
                }
                if *q == 0.0 {
                    // No technique of the configuration makes the path: infinite where the
                    // pilot's do.
                    let pilot_makes_it = d
                        .vcm_techniques(set)
                        .iter()
                        .any(|t| ci < 4 || !matches!(t, Technique::Merge(_)));
                    assert_eq!(
                        sum.is_infinite(),
                        pilot_makes_it,
                        "k {k}, configuration {ci}"
                    );
                    continue;
                }
                let want = 1.0 / q;
                assert!(
                    (sum - want).abs() <= 1e-9 * want,
                    "k {k}, configuration {ci}: Σ_u n_u p_u × share {sum}, f²/q_c {want}"
                );
            }
        }
        assert!(checked > 10_000, "{checked}");
    }
}

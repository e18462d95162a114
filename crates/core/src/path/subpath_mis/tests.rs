//! The recursive weights against the from-scratch ones on random chains: every technique of
//! every path, under every heuristic, with and without connections and merging.

use super::*;
use crate::path::merging::{Technique, TechniqueSet};
use crate::path::Densities;
use rand_pcg::rand_core::Rng as _;
use rand_pcg::Pcg32;

struct Pcg64(Pcg32);

impl Pcg64 {
    fn seed_from_u64(seed: u64) -> Pcg64 {
        Pcg64(Pcg32::new(seed, 0xa02b_dbf7_bb3c_0a7f))
    }

    fn uniform(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    fn gen_range(&mut self, r: std::ops::Range<f64>) -> f64 {
        r.start + (r.end - r.start) * self.uniform()
    }

    fn gen_bool(&mut self, p: f64) -> bool {
        self.uniform() < p
    }
}

/// A random path of k segments: densities log-uniform over 12 decades (what sharp lobes, grazing
/// angles and scene scales produce), interior vertices delta one time in four, sometimes a delta
/// light (c_0 = 0).
fn random_densities(rng: &mut Pcg64, k: usize) -> Densities {
    let mut d = || 10f64.powf(rng.gen_range(-6.0..6.0));
    let mut light: Vec<f64> = (0..=k).map(|_| d()).collect();
    let mut camera: Vec<f64> = (0..=k).map(|_| d()).collect();
    let nee = d();
    light[k] = 0.0;
    camera[k] = 1.0;
    let mut connectable = vec![true; k + 1];
    for c in connectable.iter_mut().take(k).skip(1) {
        *c = rng.gen_bool(0.75);
    }
    if rng.gen_bool(0.2) {
        // A delta light: a point light (x0 connectable) or a directional one (not).
        camera[0] = 0.0;
        connectable[0] = rng.gen_bool(0.5);
    }
    Densities {
        light,
        camera,
        nee,
        connectable,
        light_tracing_ratio: 10f64.powf(rng.gen_range(-1.0..1.0)),
    }
}

#[test]
fn recursive_weights_equal_the_oracle_on_random_chains() {
    let mut rng = Pcg64::seed_from_u64(12);
    let mut checked = 0usize;
    let mut worst = 0.0f64;
    for trial in 0..20_000 {
        let k = 1 + trial % 8;
        let d = random_densities(&mut rng, k);
        let set = TechniqueSet::new(
            rng.gen_bool(0.8),
            if rng.gen_bool(0.7) {
                10f64.powf(rng.gen_range(-4.0..4.0))
            } else {
                0.0
            },
        );
        for h in [Heuristic::Power, Heuristic::Balance, Heuristic::Uniform] {
            let mis = SubpathMis::new(h, set, d.light_tracing_ratio);
            for t in d.vcm_techniques(set) {
                let want = d.vcm_weight(set, t, h);
                let got = mis.replay(&d, t);
                let err = (got - want).abs() / want.max(1e-300);
                worst = worst.max(err.min(1.0));
                assert!(
                    err < 1e-9 || (got - want).abs() < 1e-12,
                    "k {k} {t:?} {h:?} {set:?}: recursive {got} oracle {want}\n{d:?}"
                );
                checked += 1;
            }
        }
    }
    eprintln!("{checked} weights, worst relative difference {worst:.2e}");
    assert!(checked > 100_000);
}

#[test]
fn without_merging_the_recursion_is_bdpts_chain() {
    let mut rng = Pcg64::seed_from_u64(13);
    let set = TechniqueSet::new(true, 0.0);
    for trial in 0..5_000 {
        let d = random_densities(&mut rng, 1 + trial % 8);
        let chain = d.chain();
        let mis = SubpathMis::new(Heuristic::Power, set, d.light_tracing_ratio);
        for s in 0..=d.k() {
            let want = chain.weight(s, Heuristic::Power);
            if want == 0.0 {
                continue;
            }
            let got = mis.replay(&d, Technique::Connect(s));
            assert!(
                (got - want).abs() <= 1e-9 * want,
                "s {s}: recursive {got} chain {want}\n{d:?}"
            );
        }
    }
}

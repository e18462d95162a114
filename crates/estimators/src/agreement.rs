//! The agreement test behind every "agrees within N standard errors" claim: a z-score per region
//! and channel, and a Šidák correction so a test over hundreds of regions keeps the stated
//! false-alarm rate for the whole image rather than for each region.
//!
//! [`agreement`] treats z as standard normal. With standard errors estimated from n passes it is
//! closer to Student t, so its real false-alarm rate is higher than stated for small n (1.44× at
//! n = 64 per side over 192 tests, approaching the stated rate as n grows). [`agreement_t`] takes
//! the accumulators instead and corrects for this; what no correction fixes is strongly skewed
//! per-pass block means with only a handful of passes (tails of t then are not the tails of z).

use crate::blocks::{BlockEstimate, RunningBlocks};
use statrs::distribution::{ContinuousCDF, Normal, StudentsT};
use std::fmt;

#[derive(Clone, Debug, PartialEq)]
pub struct Agreement {
    pub regions: usize,
    /// Blocks per row, to name the worst region by block coordinates.
    pub blocks_x: usize,
    /// Mean of z² over regions×channels; ≈ 1 when the standard errors are right and both agree.
    pub mean_z2: f64,
    /// Largest |z|; NaN if any z is NaN (e.g. a standard error from fewer than two passes).
    pub max_abs_z: f64,
    pub worst_region: usize,
    pub worst_channel: usize,
    /// Šidák-corrected two-sided |z| threshold for `regions × 3` tests.
    pub threshold: f64,
    pub false_alarm_rate: f64,
    /// Per region and channel.
    pub z: Vec<[f64; 3]>,
}

impl Agreement {
    /// True when max |z| is below the threshold (false on NaN).
    pub fn passed(&self) -> bool {
        self.max_abs_z < self.threshold
    }

    /// Number of region-channels with |z| at or above `k` (NaN counts).
    pub fn count_above(&self, k: f64) -> usize {
        self.z.iter().flatten().filter(|z| !(z.abs() < k)).count()
    }
}

/// Two-sided |z| threshold keeping the family-wise false-alarm rate at `alpha` over `tests`
/// independent tests (Šidák): each test runs at 1 − (1 − alpha)^(1/tests).
pub fn sidak_threshold(alpha: f64, tests: usize) -> f64 {
    assert!(
        alpha > 0.0 && alpha < 1.0,
        "false-alarm rate must be in (0, 1), got {alpha}"
    );
    // expm1/ln_1p keep the per-test rate accurate when it is tiny.
    let per_test = -(((-alpha).ln_1p()) / tests.max(1) as f64).exp_m1();
    -Normal::standard().inverse_cdf(per_test / 2.0)
}

/// Two-sample test of two estimates of the same image: z = (ma − mb)/sqrt(sea² + seb²).
/// Where both standard errors are 0, equal means give z = 0 and different means z = ±inf.
pub fn agreement(a: &BlockEstimate, b: &BlockEstimate, false_alarm_rate: f64) -> Agreement {
    assert!(
        (a.blocks_x, a.blocks_y) == (b.blocks_x, b.blocks_y),
        "agreement: block grids differ ({}x{} vs {}x{})",
        a.blocks_x,
        a.blocks_y,
        b.blocks_x,
        b.blocks_y
    );
    let z = (0..a.regions())
        .map(|i| {
            [0, 1, 2].map(|c| {
                z_score(
                    a.mean[i][c] - b.mean[i][c],
                    a.std_error[i][c].hypot(b.std_error[i][c]),
                )
            })
        })
        .collect();
    summarize(z, a.blocks_x, false_alarm_rate)
}

/// One estimate against a reference taken as exact (block means, e.g. from [`crate::block_means`]).
pub fn agreement_with_reference(
    a: &BlockEstimate,
    reference: &[[f64; 3]],
    false_alarm_rate: f64,
) -> Agreement {
    assert_eq!(
        a.regions(),
        reference.len(),
        "agreement_with_reference: region counts differ"
    );
    let z = (0..a.regions())
        .map(|i| [0, 1, 2].map(|c| z_score(a.mean[i][c] - reference[i][c], a.std_error[i][c])))
        .collect();
    summarize(z, a.blocks_x, false_alarm_rate)
}

/// Like [`agreement`], but for estimates whose standard errors come from few passes: each
/// difference is a Welch t statistic (Welch–Satterthwaite dof) and is mapped to the normal z with
/// the same tail probability, so the stated false-alarm rate holds for any pass count ≥ 2.
pub fn agreement_t(a: &RunningBlocks, b: &RunningBlocks, false_alarm_rate: f64) -> Agreement {
    let eb = b.estimate();
    agreement_t_with_estimate(a, &eb, b.count() as f64 - 1.0, false_alarm_rate)
}

/// [`agreement_t`] against an estimate known only by its block means and standard errors (a
/// peer's render, from its per-pixel mean and standard-error images), whose variances have
/// `b_dof` degrees of freedom (seeds − 1 for errors taken across seeds: the conservative choice).
pub fn agreement_t_with_estimate(
    a: &RunningBlocks,
    eb: &BlockEstimate,
    b_dof: f64,
    false_alarm_rate: f64,
) -> Agreement {
    let ea = a.estimate();
    assert!(
        (ea.blocks_x, ea.blocks_y) == (eb.blocks_x, eb.blocks_y),
        "agreement_t: block grids differ"
    );
    let (da, db) = (a.count() as f64 - 1.0, b_dof);
    let z = (0..ea.regions())
        .map(|i| {
            [0, 1, 2].map(|c| {
                let (sa, sb) = (ea.std_error[i][c].powi(2), eb.std_error[i][c].powi(2));
                let dof = (sa + sb).powi(2) / (sa * sa / da + sb * sb / db);
                t_to_z(
                    z_score(ea.mean[i][c] - eb.mean[i][c], (sa + sb).sqrt()),
                    dof,
                )
            })
        })
        .collect();
    summarize(z, ea.blocks_x, false_alarm_rate)
}

/// [`agreement_with_reference`] with the same t-to-z mapping as [`agreement_t`] (dof n − 1).
pub fn agreement_with_reference_t(
    a: &RunningBlocks,
    reference: &[[f64; 3]],
    false_alarm_rate: f64,
) -> Agreement {
    let e = a.estimate();
    assert_eq!(
        e.regions(),
        reference.len(),
        "agreement_with_reference_t: region counts differ"
    );
    let dof = a.count() as f64 - 1.0;
    let z = (0..e.regions())
        .map(|i| {
            [0, 1, 2].map(|c| {
                t_to_z(
                    z_score(e.mean[i][c] - reference[i][c], e.std_error[i][c]),
                    dof,
                )
            })
        })
        .collect();
    summarize(z, e.blocks_x, false_alarm_rate)
}

/// The standard normal quantile with the same two-sided tail as Student t with `dof`.
fn t_to_z(t: f64, dof: f64) -> f64 {
    if !t.is_finite() || t == 0.0 || dof.is_nan() {
        // ±inf, NaN and 0 map to themselves; NaN dof means both errors are 0 (z is 0 or inf).
        return t;
    }
    if dof > 1e6 {
        // First-order inverse Cornish–Fisher; statrs' t tail degrades for huge dof.
        return t * (1.0 - (t * t + 1.0) / (4.0 * dof));
    }
    let tail = StudentsT::new(0.0, 1.0, dof).expect("dof > 0").sf(t.abs());
    -Normal::standard().inverse_cdf(tail) * t.signum()
}

fn z_score(diff: f64, se: f64) -> f64 {
    if se == 0.0 {
        if diff == 0.0 {
            0.0
        } else {
            diff.signum() * f64::INFINITY
        }
    } else {
        diff / se
    }
}

fn summarize(z: Vec<[f64; 3]>, blocks_x: usize, false_alarm_rate: f64) -> Agreement {
    let (mut max, mut worst_region, mut worst_channel, mut sum2) = (0.0f64, 0, 0, 0.0);
    for (i, zi) in z.iter().enumerate() {
        for (c, &v) in zi.iter().enumerate() {
            sum2 += v * v;
            let a = v.abs();
            // The first NaN sticks, so a missing standard error cannot hide behind a larger z.
            if !max.is_nan() && (a.is_nan() || a > max) {
                (max, worst_region, worst_channel) = (a, i, c);
            }
        }
    }
    let tests = z.len() * 3;
    Agreement {
        regions: z.len(),
        blocks_x: blocks_x.max(1),
        mean_z2: sum2 / tests.max(1) as f64,
        max_abs_z: max,
        worst_region,
        worst_channel,
        threshold: sidak_threshold(false_alarm_rate, tests),
        false_alarm_rate,
        z,
    }
}

impl fmt::Display for Agreement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (bx, by) = (
            self.worst_region % self.blocks_x,
            self.worst_region / self.blocks_x,
        );
        write!(
            f,
            "{}: max |z| {:.3} at region {} (block {bx},{by}) channel {}, threshold {:.3} \
             (Šidák over {} regions × 3 channels, false-alarm rate {}); mean z² {:.3} (≈1 expected)",
            if self.passed() { "agree" } else { "DISAGREE" },
            self.max_abs_z,
            self.worst_region,
            ["R", "G", "B"][self.worst_channel],
            self.threshold,
            self.regions,
            self.false_alarm_rate,
            self.mean_z2
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::binomial::binomial_test;
    use crate::blocks::block_means;
    use crate::image::Image;
    use crate::test_rng::Rng;

    // Alpha for the tests *about* the test: a failed binomial test here is a 1-in-1000 event.
    const META_ALPHA: f64 = 1e-3;

    #[test]
    fn sidak_threshold_known_values() {
        // One test at 5 %: the familiar 1.959964; Šidák over m tests inverts exactly.
        assert!((sidak_threshold(0.05, 1) - 1.959963984540054).abs() < 1e-9);
        let t = sidak_threshold(0.01, 192);
        let per = 2.0 * Normal::standard().sf(t);
        assert!((1.0 - (1.0 - per).powi(192) - 0.01).abs() < 1e-9);
    }

    fn estimate_with_known_se(rng: &mut Rng, truth: &[[f64; 3]], se: f64) -> BlockEstimate {
        let mean = truth
            .iter()
            .map(|t| t.map(|v| v + se * rng.normal()))
            .collect();
        BlockEstimate {
            blocks_x: 8,
            blocks_y: truth.len() / 8,
            mean,
            std_error: vec![[se; 3]; truth.len()],
        }
    }

    // With exact standard errors, z is exactly normal, so the family-wise false-alarm rate must be
    // the stated one: a binomial test on the count of false alarms over many null comparisons.
    #[test]
    fn false_alarm_rate_as_stated_with_exact_errors() {
        let mut rng = Rng::new(42);
        let truth: Vec<[f64; 3]> = (0..64).map(|i| [i as f64, 1.0, 0.5]).collect();
        let (trials, alpha) = (4000u64, 0.05);
        let alarms = (0..trials)
            .filter(|_| {
                let a = estimate_with_known_se(&mut rng, &truth, 0.3);
                let b = estimate_with_known_se(&mut rng, &truth, 0.4);
                !agreement(&a, &b, alpha).passed()
            })
            .count() as u64;
        let t = binomial_test(alarms, trials, alpha);
        println!("exact-SE null: {alarms}/{trials} false alarms at stated {alpha}; {t}");
        assert!(!t.rejects(META_ALPHA), "{t}");
    }

    // With standard errors estimated from n passes, z follows roughly Student t with Welch
    // degrees of freedom (2(n−1) for equal variances). The observed rate must match that
    // prediction, and stay within 1.5× the stated rate at n = 64.
    /// Two accumulators of the same noisy image; `skewed` adds an exponential channel.
    fn null_pair(
        rng: &mut Rng,
        w: usize,
        h: usize,
        block: usize,
        n: [usize; 2],
        skewed: bool,
    ) -> [RunningBlocks; 2] {
        let mut est = [
            RunningBlocks::new(w, h, block),
            RunningBlocks::new(w, h, block),
        ];
        for (e, n) in est.iter_mut().zip(n) {
            for _ in 0..n {
                e.add(&Image::from_fn(w, h, |x, _| {
                    let third = if skewed {
                        2.0 * rng.exp()
                    } else {
                        2.0 + 3.0 * rng.normal()
                    };
                    [x as f64 + rng.normal(), rng.uniform(), third]
                }));
            }
        }
        est
    }

    // With standard errors estimated from n passes, z follows roughly Student t with Welch
    // degrees of freedom (2(n−1) for equal variances). The observed rate of the plain test must
    // match that prediction (and stay within 1.5× the stated rate at n = 64); the t-corrected
    // test must hold the stated rate.
    #[test]
    fn false_alarm_rate_with_estimated_errors() {
        let (w, h, block, n, trials, alpha) = (16, 16, 2, 64, 1000u64, 0.05);
        let mut rng = Rng::new(9);
        let (mut plain, mut corrected) = (0, 0);
        for _ in 0..trials {
            let [a, b] = null_pair(&mut rng, w, h, block, [n, n], true);
            plain += !agreement(&a.estimate(), &b.estimate(), alpha).passed() as u64;
            corrected += !agreement_t(&a, &b, alpha).passed() as u64;
        }
        let tests = (w / block) * (h / block) * 3;
        let thr = sidak_threshold(alpha, tests);
        let t_dist = StudentsT::new(0.0, 1.0, 2.0 * (n as f64 - 1.0)).unwrap();
        let predicted = 1.0 - (1.0 - 2.0 * t_dist.sf(thr)).powi(tests as i32);
        let t = binomial_test(plain, trials, predicted);
        println!("estimated-SE null, plain z (n={n}): {plain}/{trials} false alarms, predicted {predicted:.4}, stated {alpha}; {t}");
        assert!(!t.rejects(META_ALPHA), "{t}");
        assert!(predicted < 1.5 * alpha);
        let t = binomial_test(corrected, trials, alpha);
        println!("estimated-SE null, agreement_t (n={n}): {t}");
        assert!(!t.rejects(META_ALPHA), "{t}");
    }

    // Few and unequal pass counts, where the normal approximation is far off: agreement_t and
    // agreement_with_reference_t still hold the stated rate. Near-normal block means here: the
    // t mapping cannot fix skewed ones with so few passes (a one-sample test on 6 passes of
    // exponential-like data false-alarms about 1.5× too often).
    #[test]
    fn t_corrected_rate_with_few_passes() {
        let (w, h, block, trials, alpha) = (8, 8, 2, 2000u64, 0.1);
        let mut rng = Rng::new(10);
        let (mut two, mut reference) = (0, 0);
        let truth = block_means(&Image::from_fn(w, h, |x, _| [x as f64, 0.5, 2.0]), block);
        for _ in 0..trials {
            let [a, b] = null_pair(&mut rng, w, h, block, [6, 11], false);
            two += !agreement_t(&a, &b, alpha).passed() as u64;
            reference += !agreement_with_reference_t(&a, &truth.data, alpha).passed() as u64;
        }
        for (name, k) in [("two-sample", two), ("reference", reference)] {
            let t = binomial_test(k, trials, alpha);
            println!("agreement_t {name}, 6 and 11 passes: {t}");
            assert!(!t.rejects(META_ALPHA), "{name}: {t}");
        }
    }

    // A single region offset by 5σ in one channel must be found, at the rate the normal
    // distribution predicts for z ~ N(5, 1) against the threshold, and named as the worst region.
    #[test]
    fn detects_planted_five_sigma_offset() {
        let mut rng = Rng::new(123);
        let truth: Vec<[f64; 3]> = (0..64).map(|_| [1.0; 3]).collect();
        let (trials, alpha, se) = (400u64, 0.01, 0.1);
        let (mut found, mut named) = (0, 0);
        for _ in 0..trials {
            let mut a = estimate_with_known_se(&mut rng, &truth, se);
            a.mean[37][1] += 5.0 * se;
            let r = agreement_with_reference(&a, &truth, alpha);
            if !r.passed() {
                found += 1;
                named += ((r.worst_region, r.worst_channel) == (37, 1)) as u64;
            }
        }
        let thr = sidak_threshold(alpha, 192);
        let nrm = Normal::standard();
        // Detected if the planted z crosses (either side), or a null region false-alarms.
        let p_plant = nrm.sf(thr - 5.0) + nrm.cdf(-thr - 5.0);
        let p_null = 1.0 - (1.0 - 2.0 * nrm.sf(thr)).powi(191);
        let power = 1.0 - (1.0 - p_plant) * (1.0 - p_null);
        let t = binomial_test(found, trials, power);
        println!("planted 5σ: detected {found}/{trials}, predicted power {power:.4}, named worst {named}; {t}");
        assert!(!t.rejects(META_ALPHA), "{t}");
        // Misnaming needs some null region to out-score the planted one while the test fails,
        // which needs a null false alarm: at most Binomial(trials, p_null) such trials.
        let misnamed = found - named;
        let m = binomial_test(misnamed, trials, p_null);
        assert!(m.p_upper >= META_ALPHA, "misnamed {misnamed}/{trials}: {m}");
    }

    #[test]
    fn zero_errors_and_nan() {
        let e = |m: f64, s: f64| BlockEstimate {
            blocks_x: 1,
            blocks_y: 1,
            mean: vec![[m; 3]],
            std_error: vec![[s; 3]],
        };
        assert!(agreement(&e(1.0, 0.0), &e(1.0, 0.0), 0.01).passed());
        let r = agreement(&e(1.0, 0.0), &e(2.0, 0.0), 0.01);
        assert!(!r.passed() && r.max_abs_z.is_infinite());
        assert!(!agreement(&e(1.0, f64::NAN), &e(1.0, 0.1), 0.01).passed());
        let s = agreement(&e(1.0, 0.1), &e(1.2, 0.0), 0.01).to_string();
        assert!(
            s.contains("max |z| 2.000") && s.contains("threshold"),
            "{s}"
        );
    }
}

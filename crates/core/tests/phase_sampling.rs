//! Sampling tests of the phase functions: χ² of sampled directions against the claimed density
//! (isotropic and Henyey–Greenstein over the range of g), consistency of sample / eval / pdf, and
//! reciprocity. Seeds are fixed; thresholds come from the test statistics.

use lt_core::math::{Frame, Vec3};
use lt_core::medium::phase::PhaseFunction;
use lt_core::sampling::Sampler;
use lt_core::testing::chi2::{self, Chi2Test, SphereGrid};
use lt_core::testing::sidak;

/// Family-wise significance of the χ² tests of this file.
const ALPHA: f64 = 0.01;

fn phases() -> Vec<PhaseFunction> {
    let mut v = vec![PhaseFunction::Isotropic];
    for g in [-0.7, 0.0, 0.3, 0.7, 0.95] {
        v.push(PhaseFunction::henyey_greenstein(g).unwrap());
    }
    v
}

/// Outgoing directions: axis-aligned and oblique (the frame construction's branches).
fn wo_cases() -> [Vec3; 3] {
    [
        Vec3::Z,
        Vec3::new(0.3, -0.5, 0.8).normalize(),
        Vec3::new(-0.6, 0.1, -0.79).normalize(),
    ]
}

/// The direction HG peaks at (−ω_o forward, ω_o backward): rings fine around it.
fn peak(p: &PhaseFunction, wo: Vec3) -> Vec3 {
    match *p {
        PhaseFunction::HenyeyGreenstein { g } if g < 0.0 => wo,
        _ => -wo,
    }
}

#[test]
fn sampled_directions_follow_the_density_chi2() {
    let mut outcomes = Vec::new();
    let mut seed = 100u64;
    for p in phases() {
        for wo in wo_cases() {
            seed += 1;
            // The whole sphere, rings of nearly equal angle around the peak (power 2).
            let grid = SphereGrid::cap(Frame::from_z(peak(&p, wo)), 2.0, 40, 40, 2.0);
            let cfg = Chi2Test {
                samples: 400_000,
                seed,
            };
            outcomes.push(chi2::run(
                &format!("{p:?} wo={wo}"),
                cfg,
                &grid,
                |s: &mut Sampler| p.sample(wo, s.next_2d()).map(|r| r.wi),
                |wi| p.pdf(wo, wi),
            ));
        }
    }
    let level = sidak(ALPHA, outcomes.len());
    let mut failures = Vec::new();
    for o in &outcomes {
        eprintln!("{:<60} {}", o.name, o.summary());
        failures.extend(o.check(level).err());
        failures.extend(o.check_mass().err());
    }
    assert!(
        failures.is_empty(),
        "{} failures (level {level:.2e}):\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn sample_value_pdf_and_eval_agree_and_are_reciprocal() {
    for p in phases() {
        for wo in wo_cases() {
            let mut s = Sampler::new(11, 0, 0);
            for _ in 0..10_000 {
                let r = p
                    .sample(wo, s.next_2d())
                    .expect("these phase functions never reject");
                assert!(
                    (r.wi.length() - 1.0).abs() < 1e-5,
                    "{p:?}: |wi| = {}",
                    r.wi.length()
                );
                // The same f32 expression on the same inputs: equal bit for bit.
                assert_eq!(r.value, r.pdf, "{p:?}");
                assert_eq!(r.pdf, p.pdf(wo, r.wi), "{p:?}");
                assert_eq!(r.value, p.eval(wo, r.wi), "{p:?}");
                // Reciprocity: the cosine is a dot product, symmetric to the bit.
                assert_eq!(p.eval(wo, r.wi), p.eval(r.wi, wo), "{p:?}");
            }
        }
    }
}

#[test]
fn hg_follows_mitsubas_sign_forward_for_positive_g() {
    let wo = Vec3::Z;
    let forward = -wo; // light keeps travelling along −ω_o
    let hg = PhaseFunction::henyey_greenstein(0.7).unwrap();
    assert!(hg.eval(wo, forward) > hg.eval(wo, wo));
    // HG at the forward cosine 1: (1 − g²) / (4π (1 − g)³) = (1 + g) / (4π (1 − g)²).
    let g = 0.7f32;
    let expected = (1.0 + g) / (4.0 * std::f32::consts::PI * (1.0 - g) * (1.0 - g));
    let got = hg.eval(wo, forward);
    assert!(
        (got - expected).abs() <= 8.0 * f32::EPSILON * expected,
        "{got} vs {expected}"
    );
}

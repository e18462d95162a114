//! Sampling tests of every material in `bsdf::test_registry()`: χ² of the sampled directions
//! against the claimed pdf, consistency of sample / eval / pdf, reciprocity, energy, and the
//! specifics of glass and mirrors. Seeds are fixed; thresholds come from the test statistics.

use lt_core::bsdf::{test_registry, BsdfSample, Material, ShadingFrame, TransportMode};
use lt_core::math::{gamma, Frame, Vec3};
use lt_core::sampling::{sample_uniform_sphere, Sampler, UNIFORM_SPHERE_PDF};
use lt_core::testing::chi2::{self, Chi2Test, SphereGrid};
use lt_core::testing::{binomial_z, rounding_bound, sidak, MeanEstimate, DIRECTION_ROUNDING};

/// Family-wise significance of the χ² tests of this file.
const ALPHA: f64 = 0.01;
/// z-score beyond which a binomial or mean test rejects (two-sided p ≈ 6e-5).
const Z_MAX: f64 = 4.0;
const MODES: [TransportMode; 2] = [TransportMode::Radiance, TransportMode::Importance];

/// A tilted frame so that every test also exercises the world ↔ local rotations.
fn flat_frame() -> ShadingFrame {
    let n = Vec3::new(0.3, -0.5, 0.8).normalize();
    ShadingFrame::new(n, n)
}

/// Shading normal tilted away from the geometric one (interpolated normals).
fn bumped_frame() -> ShadingFrame {
    let ng = Vec3::new(0.3, -0.5, 0.8).normalize();
    let ns = (ng + Vec3::new(0.25, 0.1, 0.0)).normalize();
    ShadingFrame::new(ng, ns)
}

fn local_dir(cos: f32, phi: f32) -> Vec3 {
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    Vec3::new(sin * phi.cos(), sin * phi.sin(), cos)
}

/// Outgoing directions in the shading frame: normal, oblique, grazing, and from below.
fn wo_cases() -> Vec<(f32, Vec3)> {
    [
        (1.0, 0.0),
        (0.8, 0.7),
        (0.3, 2.0),
        (0.05, 4.0),
        (-0.6, 1.3),
        (-0.05, 5.5),
    ]
    .iter()
    .map(|&(c, p)| (c, local_dir(c, p)))
    .collect()
}

fn mode_name(m: TransportMode) -> &'static str {
    match m {
        TransportMode::Radiance => "radiance",
        TransportMode::Importance => "importance",
    }
}

/// Roughness α of a glossy lobe (the lobe test centres its bins on the mirror direction and
/// sizes them by α; the larger α of an anisotropic lobe).
fn roughness(m: &Material) -> Option<f32> {
    match m {
        Material::Glossy(g) => Some(g.roughness),
        Material::RoughConductor(c) => Some(c.distribution.max_alpha()),
        Material::RoughPlastic(p) => Some(p.distribution.max_alpha()),
        Material::RoughDielectric(d) => Some(d.distribution.max_alpha()),
        Material::TwoSided(t) => roughness(&t.inner),
        _ => None,
    }
}

/// The smooth refraction of `wo` through the plane of normal `n` (pointing outside), for a
/// material of relative IOR `ior` (inside/outside); None under total internal reflection.
fn refracted(wo: Vec3, n: Vec3, ior: f32) -> Option<Vec3> {
    let cos_i = wo.dot(n);
    let eta = if cos_i > 0.0 { ior } else { 1.0 / ior };
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let n_o = if cos_i > 0.0 { n } else { -n };
    Some(-wo / eta + (cos_i.abs() / eta - (1.0 - sin2_t).sqrt()) * n_o)
}

/// cos θ (from the normal) of the rim where rough refraction ends: the microfacet that refracts
/// wo into wi, m ∝ η_o wo + η_i wi, is vertical when η_o wo.z + η_i wi.z = 0, and the pdf drops
/// from D(m) of a vertical facet (not 0 for GGX) to zero there. `cos_o` is wo.z; None when the
/// cone does not exist (from the denser side at steep incidence).
fn refraction_rim(cos_o: f32, ior: f32) -> Option<f32> {
    let (eta_o, eta_i) = if cos_o > 0.0 { (1.0, ior) } else { (ior, 1.0) };
    let c = -cos_o * eta_o / eta_i;
    (c.abs() < 1.0).then_some(c)
}

/// The whole-sphere chart: 40 rings uniform in cos θ (the horizon, where a hemispherical pdf
/// jumps, on a ring edge) and the refraction rim as one more edge (an edge closer to it than a
/// tenth of a ring moved onto it).
fn sphere_grid(frame: Frame, rim_cos: Option<f32>) -> SphereGrid {
    const RINGS: usize = 40;
    let mut edges: Vec<f64> = (0..=RINGS).map(|i| 2.0 * i as f64 / RINGS as f64).collect();
    if let Some(c) = rim_cos {
        let h = 1.0 - c as f64;
        let ring = 2.0 / RINGS as f64;
        edges.retain(|&e| e == 0.0 || e == 2.0 || e == 1.0 || (e - h).abs() > 0.1 * ring);
        if (h - 1.0).abs() > 1e-9 {
            edges.push(h);
        }
        edges.sort_by(f64::total_cmp);
    }
    SphereGrid::with_edges(frame, edges, 80)
}

/// η_o² of radiance reciprocity across a refracting material: f(wo, wi)/η_o² = f(wi, wo)/η_i²
/// (Veach 1997, eq. 5.14), η_o the IOR of wo's side (outside 1, inside the material's IOR).
/// Roundings a material adds on top of its components' own evaluation, per side of a
/// reciprocity comparison: a blend's (1 − w)·f₀ + w·f₁ costs a product and a sum.
fn combining_roundings(m: &Material) -> i32 {
    match m {
        Material::Blend(b) => 2 + combining_roundings(&b.first).max(combining_roundings(&b.second)),
        _ => 0,
    }
}

/// A stream index from a registry name (FNV-1a), stable under insertions into the registry.
fn name_seed(name: &str) -> u64 {
    name.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
    })
}

fn side_ior_squared(m: &Material, n: Vec3, w: Vec3) -> f32 {
    match m.refraction_ior() {
        Some(ior) if w.dot(n) < 0.0 => ior * ior,
        _ => 1.0,
    }
}

/// True for a one-sided material (Mitsuba's conductors and plastics) seen from behind: it samples
/// nothing, and its pdf and f are zero everywhere (checked here on a spread of directions).
fn absorbs_from(m: &Material, sf: &ShadingFrame, wo: Vec3) -> bool {
    let mut s = Sampler::new(5, 0, 0);
    let samples_nothing = (0..1000).all(|_| {
        let u_lobe = s.next_f32();
        m.sample(sf, wo, u_lobe, s.next_2d(), TransportMode::Radiance)
            .is_none()
    });
    if samples_nothing {
        for _ in 0..1000 {
            let wi = sample_uniform_sphere(s.next_2d());
            let e = m.eval(sf, wo, wi, TransportMode::Radiance);
            assert!(
                e.f_cos == Vec3::ZERO && e.pdf_w == 0.0 && m.pdf(sf, wo, wi) == 0.0,
                "a material that samples nothing from {wo} must have f = pdf = 0, not {e:?}"
            );
        }
    }
    samples_nothing
}

#[test]
fn sampled_directions_follow_the_pdf_chi2() {
    let sf = flat_frame();
    let n = sf.ns();
    let registry = test_registry();
    // The cases in a fixed order with their seeds, then run on every core: the outcomes, gathered
    // back in case order, do not depend on the thread count.
    let mut cases = Vec::new();
    let mut seed = 0u64; // radiance cases keep the seeds they had beside importance ones
    for (index, (_, m)) in registry.iter().enumerate() {
        if m.is_delta() {
            continue;
        }
        for (cos, wo_l) in wo_cases() {
            let wo = sf.frame.to_world(wo_l);
            if absorbs_from(m, &sf, wo) {
                continue; // a one-sided material seen from behind: nothing to fit
            }
            // Radiance mode only: importance-mode sampling draws the same directions with the
            // same pdfs from the same variates (`check_adjoint` holds that exactly), and `pdf`
            // has no mode, so a second mode would fit the same distribution again.
            seed += 2;
            cases.push((index, cos, wo, TransportMode::Radiance, seed));
        }
    }
    let run_case = |&(index, cos, wo, mode, seed): &(usize, f32, Vec3, TransportMode, u64)| {
        let (name, m) = &registry[index];
        let mut outcomes = Vec::new();
        let cfg = Chi2Test {
            samples: 500_000,
            seed,
        };
        let label = format!("{name} cosθo={cos} {}", mode_name(mode));
        // A delta lobe beside smooth ones (plastic) has no density: its samples count
        // as lost mass, which `check_mass` holds to 1 − ∫pdf.
        let sample = |s: &mut Sampler| {
            let u_lobe = s.next_f32();
            m.sample(&sf, wo, u_lobe, s.next_2d(), mode)
                .filter(|b| !b.delta)
                .map(|b| b.wi)
        };
        let pdf = |w: Vec3| m.pdf(&sf, wo, w);
        // Whole sphere, rings uniform in cos θ around the normal, horizon on a ring edge
        // (and the rim of rough refraction, for a material that refracts).
        let rim = m
            .refraction_ior()
            .and_then(|ior| refraction_rim(wo.dot(n), ior));
        let grid = sphere_grid(Frame::from_z(n), rim);
        outcomes.push(chi2::run(
            &format!("{label} sphere"),
            cfg,
            &grid,
            sample,
            pdf,
        ));
        // Cap around the mirror direction with rings of equal angle, to resolve peaks;
        // it stays above the horizon, where the pdf is smooth.
        if let Some(alpha) = roughness(m) {
            let r = 2.0 * wo.dot(n) * n - wo;
            let elevation = wo.dot(n).abs().asin();
            let half_angle = (0.9 * elevation).min(10.0 * alpha) as f64;
            let grid = SphereGrid::cap(Frame::from_z(r), 1.0 - half_angle.cos(), 30, 40, 2.0);
            let cfg = Chi2Test {
                samples: 500_000,
                seed: seed + 1_000,
            };
            outcomes.push(chi2::run(&format!("{label} lobe"), cfg, &grid, sample, pdf));
            // And around the refracted direction, for a material that refracts.
            // It stays above the horizon and inside the rim, where the pdf is smooth.
            if let Some(t) = m.refraction_ior().and_then(|ior| refracted(wo, n, ior)) {
                let elevation = t.dot(n).abs().asin();
                let to_rim = rim.map_or(f32::INFINITY, |c| (c.acos() - t.dot(n).acos()).abs());
                let half_angle = (0.9 * elevation.min(to_rim)).min(10.0 * alpha) as f64;
                let grid = SphereGrid::cap(Frame::from_z(t), 1.0 - half_angle.cos(), 30, 40, 2.0);
                let cfg = Chi2Test {
                    samples: 500_000,
                    seed: seed + 2_000,
                };
                outcomes.push(chi2::run(
                    &format!("{label} refraction lobe"),
                    cfg,
                    &grid,
                    sample,
                    pdf,
                ));
            }
        }
        outcomes
    };
    let outcomes: Vec<_> = on_every_core(&cases, run_case)
        .into_iter()
        .flatten()
        .collect();
    let level = sidak(ALPHA, outcomes.len());
    let mut failures = Vec::new();
    for o in &outcomes {
        eprintln!(
            "{}",
            o.summary().replace("χ²", &format!("{:<36} χ²", o.name))
        );
        failures.extend(o.check(level).err());
        failures.extend(o.check_mass().err());
    }
    let worst = outcomes
        .iter()
        .map(|o| o.p_value)
        .fold(f64::INFINITY, f64::min);
    eprintln!(
        "{} χ² tests, per-test level {level:.2e}, smallest p = {worst:.4}",
        outcomes.len()
    );
    assert!(
        failures.is_empty(),
        "{} failures (level {level:.2e}):\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// `f` of every item, computed on every core (items taken in turn from a shared counter), returned
/// in the items' order.
fn on_every_core<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::Mutex;
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<R>>> = Mutex::new((0..items.len()).map(|_| None).collect());
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(item) = items.get(i) else { break };
                let r = f(item);
                results.lock().unwrap()[i] = Some(r);
            });
        }
    });
    results
        .into_inner()
        .unwrap()
        .into_iter()
        .map(|r| r.expect("every item ran"))
        .collect()
}

/// Sum of how much `f(wo, wi)` may move when either direction is perturbed by rounding.
fn pair_bound(f: impl Fn(Vec3, Vec3) -> f64, wo: Vec3, wi: Vec3) -> f64 {
    rounding_bound(|w| f(wo, w), wi, DIRECTION_ROUNDING)
        + rounding_bound(|w| f(w, wi), wo, DIRECTION_ROUNDING)
}

#[test]
fn sample_weight_and_pdfs_agree_with_eval() {
    let mut failures = Vec::new();
    for sf in [flat_frame(), bumped_frame()] {
        for (name, m) in test_registry() {
            for (cos, wo_l) in wo_cases() {
                let wo = sf.frame.to_world(wo_l);
                let mut s = Sampler::new(7, cos.to_bits() as u64, 0);
                let label = format!("{name} cosθo={cos} ns·ng={:.3}", sf.ns().dot(sf.ng));
                for _ in 0..4000 {
                    let (u_lobe, u) = (s.next_f32(), s.next_2d());
                    let r = m.sample(&sf, wo, u_lobe, u, TransportMode::Radiance);
                    let i = m.sample(&sf, wo, u_lobe, u, TransportMode::Importance);
                    let (r, i) = match (r, i) {
                        (Some(r), Some(i)) => (r, i),
                        (None, None) => continue,
                        (r, i) => {
                            // The χ² test fits radiance mode alone on this equality.
                            failures.push(format!(
                                "{label}: radiance sample {r:?} but importance sample {i:?}"
                            ));
                            break;
                        }
                    };
                    if let Err(e) = check_sample(&m, &sf, wo, &r)
                        .and_then(|_| check_adjoint(&m, &sf, wo, &r, &i))
                    {
                        failures.push(format!("{label}: {e}"));
                        break;
                    }
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A radiance-mode sample against eval and pdf.
fn check_sample(m: &Material, sf: &ShadingFrame, wo: Vec3, b: &BsdfSample) -> Result<(), String> {
    let mode = TransportMode::Radiance;
    let wi = b.wi;
    if !((wi.length() - 1.0).abs() <= 2.0 * DIRECTION_ROUNDING)
        || !b.weight.is_finite()
        || b.weight.min_element() < 0.0
    {
        return Err(format!("bad sample {b:?}"));
    }
    let e = m.eval(sf, wo, wi, mode);
    if (b.delta && !m.has_delta_lobe()) || (!b.delta && m.is_delta()) {
        return Err(format!(
            "delta flag {} on a material with is_delta {}, has_delta_lobe {}",
            b.delta,
            m.is_delta(),
            m.has_delta_lobe()
        ));
    }
    if b.delta {
        // Delta lobes: the pdfs are lobe probabilities; eval and pdf are zero unless smooth
        // lobes lie beside the delta (plastic), which eval and pdf report alone.
        let ok = (!m.is_delta() || (e.f_cos == Vec3::ZERO && m.pdf(sf, wo, wi) == 0.0))
            && b.pdf_w > 0.0
            && b.pdf_w <= 1.0
            && b.pdf_rev_w > 0.0
            && b.pdf_rev_w <= 1.0;
        return if ok {
            Ok(())
        } else {
            Err(format!("delta sample {b:?} eval {e:?}"))
        };
    }
    let pdf = |o: Vec3, i: Vec3| m.pdf(sf, o, i) as f64;
    let tol_pdf = pair_bound(pdf, wo, wi);
    if (b.pdf_w as f64 - pdf(wo, wi)).abs() > tol_pdf {
        return Err(format!(
            "sample pdf {} vs pdf() {} (tol {tol_pdf:.2e})",
            b.pdf_w,
            pdf(wo, wi)
        ));
    }
    let tol_rev = pair_bound(|o, i| pdf(i, o), wo, wi);
    if (b.pdf_rev_w as f64 - pdf(wi, wo)).abs() > tol_rev {
        return Err(format!(
            "sample pdf_rev {} vs pdf(wi→wo) {} (tol {tol_rev:.2e})",
            b.pdf_rev_w,
            pdf(wi, wo)
        ));
    }
    if e.pdf_w != m.pdf(sf, wo, wi) || e.pdf_rev_w != m.pdf(sf, wi, wo) {
        return Err(format!(
            "eval pdfs {e:?} vs pdf() {} / {}",
            pdf(wo, wi),
            pdf(wi, wo)
        ));
    }
    for c in 0..3 {
        let ratio = |o: Vec3, i: Vec3| {
            let e = m.eval(sf, o, i, mode);
            e.f_cos[c] as f64 / e.pdf_w as f64
        };
        let tol = pair_bound(ratio, wo, wi);
        if (b.weight[c] as f64 - ratio(wo, wi)).abs() > tol {
            return Err(format!(
                "weight[{c}] {} vs f_cos/pdf {} (tol {tol:.2e})",
                b.weight[c],
                ratio(wo, wi)
            ));
        }
    }
    Ok(())
}

/// The importance-mode sample of the same variates: same direction and pdfs, and its weight and
/// f_cos differ from radiance mode by Veach's factor |ns·wo||ng·wi| / (|ns·wi||ng·wo|), in both
/// `sample` and `eval`. (Comparing importance weights with eval directly is ill-conditioned near
/// the shading horizon, where the factor is ~1/cos θi and the material's own G1 ~cos θi.)
fn check_adjoint(
    m: &Material,
    sf: &ShadingFrame,
    wo: Vec3,
    r: &BsdfSample,
    i: &BsdfSample,
) -> Result<(), String> {
    if i.wi != r.wi || i.pdf_w != r.pdf_w || i.pdf_rev_w != r.pdf_rev_w || i.delta != r.delta {
        return Err(format!(
            "importance sample {i:?} differs from radiance {r:?} beyond its weight"
        ));
    }
    let wi = r.wi;
    let (ns, ng) = (sf.ns(), sf.ng);
    let factor = |w_o: Vec3, w_i: Vec3| {
        (w_o.dot(ns).abs() * w_i.dot(ng).abs() / (w_i.dot(ns).abs() * w_o.dot(ng).abs())) as f64
    };
    // Refraction scales radiance (not importance) by 1/η², η = η_i/η_o; undo it before comparing.
    // Whether the sample refracted is the shading frame's word: a delta lobe follows it across
    // ng's plane (as in Mitsuba 3 and pbrt-v4), and a smooth lobe is kept only where the two
    // frames agree.
    let glass_scale = match m.refraction_ior() {
        Some(ior) if wi.dot(ns) * wo.dot(ns) < 0.0 => {
            let eta = if wo.dot(ns) > 0.0 { ior } else { 1.0 / ior } as f64;
            eta * eta
        }
        _ => 1.0,
    };
    let tol = gamma(8) as f64 + pair_bound(factor, wo, wi) / factor(wo, wi);
    let expect = factor(wo, wi) * glass_scale;
    let got = i.weight.x as f64 / r.weight.x as f64;
    if (got / expect - 1.0).abs() > tol {
        return Err(format!(
            "importance/radiance weight {got} vs {expect} (tol {tol:.1e})"
        ));
    }
    if !m.is_delta() {
        let (ei, er) = (
            m.eval(sf, wo, wi, TransportMode::Importance),
            m.eval(sf, wo, wi, TransportMode::Radiance),
        );
        let got = ei.f_cos.x as f64 / er.f_cos.x as f64;
        if er.f_cos.x > 0.0 && (got / expect - 1.0).abs() > tol {
            return Err(format!(
                "importance/radiance f_cos {got} vs {expect} (tol {tol:.1e})"
            ));
        }
    }
    Ok(())
}

#[test]
fn non_delta_materials_are_reciprocal() {
    // Radiance mode with ns = ng: f(wo, wi) = f_cos / |cos θi| must equal f(wi, wo); across a
    // refracting interface f(wo, wi)/η_o² must equal f(wi, wo)/η_i² (Veach 1997, eq. 5.14). Each
    // side carries two roundings (× cos in eval, ÷ cos here), hence a relative γ(4), and one
    // more (÷ η² here) when both directions are inside a refracting material; a refracted
    // pair up to ten more per side (η_i², 1/η² in the transport scale, η_o² and ÷ here).
    let sf = flat_frame();
    let n = sf.ns();
    for (name, m) in test_registry() {
        // Each material its own stream: adding an entry to the registry leaves the others'
        // directions as they were.
        let mut s = Sampler::new(11, name_seed(name), 0);
        // Non-reciprocal by design (Mitsuba's principledthin: `Material::is_reciprocal`).
        if m.is_delta() || !m.is_reciprocal() {
            continue;
        }
        let f = |o: Vec3, i: Vec3| {
            m.eval(&sf, o, i, TransportMode::Radiance).f_cos
                / sf.frame.to_local(i).z.abs()
                / side_ior_squared(&m, n, o)
        };
        for k in 0..20_000 {
            let wo = sample_uniform_sphere(s.next_2d());
            let mut wi = sample_uniform_sphere(s.next_2d());
            // Bias towards the mirror (and refracted) direction so narrow lobes are non-zero too.
            let refracted = m.refraction_ior().and_then(|ior| refracted(wo, n, ior));
            match (k % 3, refracted) {
                (1, Some(t)) => wi = (t + 0.1 * wi).normalize(),
                (0 | 1, _) => wi = (2.0 * wo.dot(n) * n - wo + 0.1 * wi).normalize(),
                _ => {}
            }
            let (a, b) = (f(wo, wi), f(wi, wo));
            let across = wo.dot(n) * wi.dot(n) < 0.0 && m.refraction_ior().is_some();
            let inside_both = !across && wo.dot(n) < 0.0 && m.refraction_ior().is_some();
            let per_side = match (across, inside_both) {
                (true, _) => 12,
                (false, true) => 3,
                (false, false) => 2,
            } + combining_roundings(&m);
            let tol = gamma(2 * per_side) * a.max(b);
            assert!(
                a.is_finite() && (a - b).abs().max_element() <= tol.max_element(),
                "{name}: f(wo,wi) = {a} but f(wi,wo) = {b} for wo {wo} wi {wi}"
            );
        }
    }
}

#[test]
fn energy_is_conserved_and_diffuse_returns_its_albedo() {
    let sf = flat_frame();
    // 100k samples per case (200k cost CI a minute): each estimate's standard error grows by √2,
    // and the failure messages print it beside the disagreement.
    let n = 100_000;
    let registry = test_registry();
    // Cases in a fixed order, each with its own seed, run on every core (as the χ² test does).
    let mut cases = Vec::new();
    for index in 0..registry.len() {
        for (cos, wo_l) in wo_cases() {
            for mode in MODES {
                cases.push((index, cos, wo_l, mode));
            }
        }
    }
    let run_case = |&(index, cos, wo_l, mode): &(usize, f32, Vec3, TransportMode)| {
        let (name, m) = &registry[index];
        let mut report = Vec::new();
        let wo = sf.frame.to_world(wo_l);
        // Radiance is not conserved across refraction (it scales by 1/η²); only the
        // adjoint (importance) direction of glass integrates to ≤ 1.
        let refracts_radiance = m.refraction_ior().is_some() && mode == TransportMode::Radiance;
        let mut s = Sampler::new(13, cos.to_bits() as u64, mode as u64);
        let mut by_sampling = [MeanEstimate::default(); 3];
        // The smooth lobes' share of the samples: what eval integrates to.
        let mut smooth_by_sampling = [MeanEstimate::default(); 3];
        let mut by_uniform = [MeanEstimate::default(); 3];
        for _ in 0..n {
            let u_lobe = s.next_f32();
            let b = m.sample(&sf, wo, u_lobe, s.next_2d(), mode);
            let w = b.map_or(Vec3::ZERO, |b| b.weight);
            let smooth = b.map_or(Vec3::ZERO, |b| if b.delta { Vec3::ZERO } else { b.weight });
            let wi = sample_uniform_sphere(s.next_2d());
            let f = m.eval(&sf, wo, wi, mode).f_cos / UNIFORM_SPHERE_PDF;
            for c in 0..3 {
                by_sampling[c].add(w[c] as f64);
                smooth_by_sampling[c].add(smooth[c] as f64);
                by_uniform[c].add(f[c] as f64);
            }
        }
        let label = format!("{name} cosθo={cos} {}", mode_name(mode));
        for c in 0..3 {
            let (a, b) = (by_sampling[c], by_uniform[c]);
            if !refracts_radiance && (a.mean() - 1.0) > Z_MAX * a.std_error() {
                report.push(format!(
                    "{label}[{c}]: ∫f_cos = {:.5} ± {:.1e} exceeds 1",
                    a.mean(),
                    a.std_error()
                ));
            }
            if !m.is_delta() {
                // Two independent unbiased estimates of the same albedo (both exactly 0
                // for a one-sided material seen from behind), of its smooth lobes.
                let a = smooth_by_sampling[c];
                let se = (a.std_error().powi(2) + b.std_error().powi(2)).sqrt();
                let z = if se == 0.0 && a.mean() == b.mean() {
                    0.0
                } else {
                    (a.mean() - b.mean()) / se
                };
                if !(z.abs() < Z_MAX) {
                    report.push(format!(
                        "{label}[{c}]: sampled albedo {:.5} vs uniform {:.5} ± {:.1e}: z = {z:.2}",
                        a.mean(),
                        b.mean(),
                        b.std_error()
                    ));
                }
            }
            if let Material::Diffuse(d) = m {
                let z = (b.mean() - d.albedo[c] as f64) / b.std_error();
                if !(z.abs() < Z_MAX) {
                    report.push(format!(
                        "{label}[{c}]: albedo {:.5} ± {:.1e} vs {}: z = {z:.2}",
                        b.mean(),
                        b.std_error(),
                        d.albedo[c]
                    ));
                }
            }
        }
        report
    };
    let report: Vec<String> = on_every_core(&cases, run_case)
        .into_iter()
        .flatten()
        .collect();
    assert!(report.is_empty(), "{}", report.join("\n"));
}

/// Reference Fresnel reflectance in f64, in the angle form (independent of the f32 code):
/// rs = −sin(θi−θt)/sin(θi+θt), rp = tan(θi−θt)/tan(θi+θt); `eta` = η_t/η_i.
fn fresnel_reference(cos_i: f64, eta: f64) -> f64 {
    let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
    let sin_t = sin_i / eta;
    if sin_t >= 1.0 {
        return 1.0;
    }
    if sin_i < 1e-6 {
        return ((eta - 1.0) / (eta + 1.0)).powi(2);
    }
    let (ti, tt) = (sin_i.asin(), sin_t.asin());
    let rs = -(ti - tt).sin() / (ti + tt).sin();
    let rp = (ti - tt).tan() / (ti + tt).tan();
    0.5 * (rs * rs + rp * rp)
}

fn glasses() -> Vec<(&'static str, f32)> {
    test_registry()
        .into_iter()
        .filter_map(|(name, m)| match m {
            Material::Dielectric(d) => Some((name, d.ior)),
            _ => None,
        })
        .collect()
}

/// Largest u_lobe a `Sampler` produces.
const U_MAX: f32 = 1.0 - 1.0 / (1u32 << 24) as f32;

#[test]
fn glass_follows_fresnel_and_snell() {
    let sf = flat_frame();
    let n = sf.ns();
    let mut worst_z = 0.0f64;
    for (name, ior) in glasses() {
        let m = Material::Dielectric(lt_core::bsdf::Dielectric { ior });
        for (cos, wo_l) in wo_cases() {
            let wo = sf.frame.to_world(wo_l);
            // η = η_t/η_i of the path wo → wi: entering the inside when wo is outside.
            let eta = if cos > 0.0 {
                ior as f64
            } else {
                1.0 / ior as f64
            };
            let cos_i = cos.abs() as f64;
            let f_ref = fresnel_reference(cos_i, eta);
            let tir = f_ref == 1.0;
            let label = format!("{name} cosθo={cos}");
            let on_wo_side = |w: Vec3| w.dot(n) * wo.dot(n) > 0.0;

            // F + T = 1, and F matches the reference up to what rounding of cos θ allows.
            let r = m
                .sample(&sf, wo, 0.0, Default::default(), TransportMode::Radiance)
                .unwrap();
            assert!(
                on_wo_side(r.wi) && r.delta,
                "{label}: u_lobe = 0 must reflect"
            );
            let d = DIRECTION_ROUNDING as f64;
            let tol_f = (fresnel_reference(cos_i * (1.0 - d), eta) - f_ref)
                .abs()
                .max((fresnel_reference((cos_i * (1.0 + d)).min(1.0), eta) - f_ref).abs())
                + 16.0 * f32::EPSILON as f64;
            assert!(
                (r.pdf_w as f64 - f_ref).abs() <= tol_f,
                "{label}: F = {} vs reference {f_ref} (tol {tol_f:.1e})",
                r.pdf_w
            );
            let t = m
                .sample(&sf, wo, U_MAX, Default::default(), TransportMode::Radiance)
                .unwrap();
            if tir {
                assert!(
                    on_wo_side(t.wi) && t.pdf_w == 1.0,
                    "{label}: total internal reflection expected"
                );
            } else {
                assert!(!on_wo_side(t.wi), "{label}: u_lobe → 1 must refract");
                assert!(
                    (r.pdf_w + t.pdf_w - 1.0).abs() <= f32::EPSILON,
                    "{label}: F + T = {}",
                    r.pdf_w + t.pdf_w
                );
                assert_eq!(
                    t.pdf_rev_w, t.pdf_w,
                    "{label}: reverse refraction has the same 1 − F"
                );
            }

            // Exact mirror direction for reflection; Snell's law and the plane of incidence for
            // refraction. sin θ = |n × w| carries the directions' rounding, once per side.
            let mirror = 2.0 * wo.dot(n) * n - wo;
            assert!(
                (r.wi - mirror).length() <= 2.0 * DIRECTION_ROUNDING,
                "{label}: reflection {} vs {mirror}",
                r.wi
            );
            if !tir {
                let (sin_i, sin_t) = (n.cross(wo).length() as f64, n.cross(t.wi).length() as f64);
                let tol = (eta + 1.0) * d;
                assert!(
                    (eta * sin_t - sin_i).abs() <= tol,
                    "{label}: Snell η sinθt = {} vs sinθi = {sin_i}",
                    eta * sin_t
                );
                let (po, pi) = (wo - wo.dot(n) * n, t.wi - t.wi.dot(n) * n);
                if po.length() > 1e-3 {
                    assert!(
                        (po.normalize().dot(pi.normalize()) + 1.0).abs()
                            <= 4.0 * DIRECTION_ROUNDING,
                        "{label}: refraction leaves the plane of incidence"
                    );
                }
            }

            // Radiance vs importance differ by exactly η² on refraction, not at all on reflection.
            for u in [0.0, U_MAX] {
                let a = m
                    .sample(&sf, wo, u, Default::default(), TransportMode::Radiance)
                    .unwrap();
                let b = m
                    .sample(&sf, wo, u, Default::default(), TransportMode::Importance)
                    .unwrap();
                let expect = if on_wo_side(a.wi) { 1.0 } else { eta * eta };
                let ratio = b.weight.x as f64 / a.weight.x as f64;
                assert!(
                    (ratio / expect - 1.0).abs() <= gamma(4) as f64,
                    "{label} u={u}: importance/radiance = {ratio}, expected {expect}"
                );
                assert_eq!(b.weight.x, 1.0, "{label}: importance weight of glass is 1");
            }

            // The frequency of reflection is F (binomial z-test).
            if !tir {
                let trials = 100_000u64;
                let mut s = Sampler::new(17, cos.to_bits() as u64, ior.to_bits() as u64);
                let k = (0..trials)
                    .filter(|_| {
                        on_wo_side(
                            m.sample(&sf, wo, s.next_f32(), s.next_2d(), TransportMode::Radiance)
                                .unwrap()
                                .wi,
                        )
                    })
                    .count();
                let z = binomial_z(k as u64, trials, f_ref);
                worst_z = worst_z.max(z.abs());
                assert!(
                    z.abs() < Z_MAX,
                    "{label}: reflected {k}/{trials}, F = {f_ref}: z = {z:.2}"
                );
            }
        }
    }
    eprintln!("worst |z| of reflection frequency vs F: {worst_z:.2}");
}

#[test]
fn glass_reflects_totally_beyond_the_critical_angle() {
    let sf = flat_frame();
    for (name, ior) in glasses() {
        let m = Material::Dielectric(lt_core::bsdf::Dielectric { ior });
        // From the denser side the relative IOR is < 1 and sin θc = η.
        let (side, eta) = if ior > 1.0 {
            (-1.0f32, 1.0 / ior)
        } else {
            (1.0, ior)
        };
        for (factor, expect_tir) in [(1.01f32, true), (0.99, false)] {
            let sin = (eta * factor).min(1.0);
            let wo = sf
                .frame
                .to_world(Vec3::new(sin, 0.0, side * (1.0 - sin * sin).sqrt()));
            let mut s = Sampler::new(19, ior.to_bits() as u64, 0);
            let mut refracted = 0;
            for _ in 0..2000 {
                let b = m
                    .sample(&sf, wo, s.next_f32(), s.next_2d(), TransportMode::Radiance)
                    .unwrap();
                if b.wi.dot(sf.ns()) * wo.dot(sf.ns()) < 0.0 {
                    refracted += 1;
                } else if expect_tir {
                    assert!(
                        b.pdf_w == 1.0 && b.weight == Vec3::ONE,
                        "{name}: TIR sample {b:?}"
                    );
                }
            }
            assert_eq!(
                refracted == 0,
                expect_tir,
                "{name}: sinθ = {factor}·sinθc refracted {refracted}/2000"
            );
            let t = m
                .sample(&sf, wo, U_MAX, Default::default(), TransportMode::Radiance)
                .unwrap();
            assert_eq!(
                t.wi.dot(sf.ns()) * wo.dot(sf.ns()) > 0.0,
                expect_tir,
                "{name}: u_lobe → 1 at {factor}·sinθc"
            );
        }
    }
}

#[test]
fn mirror_reflects_exactly() {
    for sf in [flat_frame(), bumped_frame()] {
        let n = sf.ns();
        let (_, m) = test_registry()
            .into_iter()
            .find(|(k, _)| *k == "mirror")
            .unwrap();
        let Material::Mirror(mirror) = &m else {
            unreachable!()
        };
        for (cos, wo_l) in wo_cases() {
            let wo = sf.frame.to_world(wo_l);
            let Some(b) = m.sample(&sf, wo, 0.5, Default::default(), TransportMode::Radiance)
            else {
                // Only a shading normal tilted away from ng may reject (light leak guard).
                assert!(sf.ns() != sf.ng, "mirror rejected cosθo={cos} with ns = ng");
                continue;
            };
            let r = 2.0 * wo.dot(n) * n - wo;
            assert!(
                (b.wi - r).length() <= 2.0 * DIRECTION_ROUNDING,
                "cosθo={cos}: {} vs {r}",
                b.wi
            );
            assert!(b.delta && b.pdf_w == 1.0 && b.pdf_rev_w == 1.0);
            assert_eq!(
                b.weight, mirror.reflectance,
                "radiance weight is the reflectance"
            );
        }
    }
}

/// A delta lobe is followed as the shading frame gives it even where the geometric normal puts
/// `wo` or `wi` on the other side (Mitsuba 3's and pbrt-v4's rule; the side check is for smooth
/// lobes): rejecting those samples lost 2–5 % of the light seen through Mitsuba's water ring
/// (homo_dielectric_envmap). Over a grid of `wo` at the tilted frame, the mirror and the glass
/// return their shading-frame direction every time, and some of those directions do cross `ng`'s
/// plane (else the check could not fail).
#[test]
fn delta_lobes_follow_the_shading_frame_across_the_geometric_plane() {
    let sf = bumped_frame();
    let (ns, ng) = (sf.ns(), sf.ng);
    let mut crossing = 0;
    for (name, m) in test_registry() {
        if !matches!(name, "mirror" | "glass-1.5") {
            continue;
        }
        for i in 0..64 {
            for side in [1.0f32, -1.0] {
                let cos = (i as f32 + 0.5) / 64.0;
                let wo = sf.frame.to_world(local_dir(cos, 0.37 * i as f32)) * side;
                for u_lobe in [0.0, U_MAX] {
                    let b = m
                        .sample(&sf, wo, u_lobe, Default::default(), TransportMode::Radiance)
                        .unwrap_or_else(|| panic!("{name}: wo {wo} u_lobe {u_lobe} rejected"));
                    assert!(b.delta, "{name}: a delta sample");
                    let reflected = b.wi.dot(ns) * wo.dot(ns) > 0.0;
                    if reflected {
                        let r = 2.0 * wo.dot(ns) * ns - wo;
                        assert!((b.wi - r).length() <= 4.0 * DIRECTION_ROUNDING, "{name}");
                    }
                    if b.wi.dot(ng) * b.wi.dot(ns) < 0.0 || wo.dot(ng) * wo.dot(ns) < 0.0 {
                        crossing += 1;
                    }
                }
            }
        }
    }
    assert!(
        crossing > 0,
        "no sample crossed ng's plane: the check cannot fail"
    );
}

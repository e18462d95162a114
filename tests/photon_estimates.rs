//! The photon-mapping family (`pm`, `ppm`, `sppm`) against unbiased references, with every error
//! bar taken across independent runs (a consistent estimator's passes share state, so their
//! spread is no error bar; ARCHITECTURE.md, "Error bars"):
//!
//! 1. `pm` at a fixed radius stays biased however many photons it stores: its expected image is
//!    the radiance smoothed by the kernel, E[L̂] = ∫ K_r(x − y) L(y) dy, whatever the photon count
//!    (photon paths are i.i.d. and the estimate is linear in them), so more photons only shrink
//!    the variance.
//! 2. Per path length (max_depth 2 with direct light from photons, max_depth 3 with next-event
//!    estimation), all three agree with `pt` per 8×8 block at a fine setting, and a coarse setting
//!    (big radius, few photons or passes) has a larger relative bias².
//! 3. Caustics: `sppm` agrees with BDPT on the point-light caustic under a glass ball
//!    (`cornell-point-caustic`), and renders the caustic seen only in a mirror (`caustic-sds`,
//!    L S S D S E) with a small fraction of the error BDPT has at equal passes.
//!
//! **Relative bias².** Per block b and channel c, with x̄ the mean of K independent runs, s²/K its
//! variance and r ± se_r the reference: d = (x̄ − r)/r, v = (s²/K + se_r²)/r², and
//! β̂² = d² − v is unbiased for the relative bias² β² (E d² = β² + v). B = Σ β̂² over blocks and
//! channels. Normal theory (d ~ N(β, v)) gives Var d² = 4β²v + 2v²; v itself is estimated, with
//! Var v̂ ≈ 2 (s²/K)²/(K − 1) + 2 se_r⁴/(n − 1) (χ², over r⁴). Terms are independent across blocks
//! and channels only approximately (the three channels of a block share paths), so the standard
//! error sqrt(Σ Var) is a guide, used with a 4σ margin. Left out: blocks that see an emitter
//! directly (their spread across runs is the antialiasing of the emitter's edge — for `ppm`, whose
//! visible points are fixed for a run, it swamps everything — and emission is not a photon
//! estimate; the agreement tests keep them) and terms whose reference is not resolved from zero
//! (r ≤ 4 se_r, where a relative error is undefined).

use lt_core::{Scene, Vec2, Vec3};
use lt_estimators::agreement::{agreement_t, sidak_threshold, Agreement};
use lt_estimators::bias_variance::variance_interval;
use lt_estimators::blocks::RunningBlocks;
use lt_integrators::{make_integrator, render, IntegratorParams, RenderOptions};
use lt_tests::{render_blocks, shipped_scene, CONSISTENT_RUNS};
use std::ops::ControlFlow;
use std::time::Instant;

/// Family-wise false-alarm rate of every comparison here.
const ALPHA: f64 = 1e-3;
const BLOCK: usize = 8;
/// The margin, in standard errors, of the bias² claims (normal theory, see the module docs).
const BIAS_SIGMAS: f64 = 4.0;

fn params(pairs: &[(&str, &str)]) -> IntegratorParams {
    let mut p = IntegratorParams::new();
    for (k, v) in pairs {
        p.set(k, v);
    }
    p
}

/// Block statistics over `runs` independent runs (seeds seed, seed + 1, …) of `passes` passes of
/// a consistent estimator: `render_blocks` with a run count of our choosing.
fn independent_runs(
    scene: &Scene,
    integrator: &str,
    p: &IntegratorParams,
    passes: u32,
    runs: u64,
    seed: u64,
) -> RunningBlocks {
    let integ = make_integrator(integrator, scene, p).unwrap();
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let mut blocks = RunningBlocks::new(w, h, BLOCK);
    for k in 0..runs {
        let opts = RenderOptions {
            passes,
            time_limit: None,
            seed: seed + k,
            threads: 0,
        };
        let r = render(scene, &integ, &opts, |_| ControlFlow::Continue(())).unwrap();
        assert_eq!(r.invalid_samples, 0, "{integrator}: invalid samples");
        blocks.add(&r.estimate);
    }
    blocks
}

/// Block statistics over passes (unbiased) or `CONSISTENT_RUNS` runs (consistent): `render_blocks`.
fn block_stats(
    scene: &Scene,
    integrator: &str,
    p: IntegratorParams,
    passes: u32,
    seed: u64,
) -> RunningBlocks {
    let (r, b) = render_blocks(scene, integrator, p, passes, seed, BLOCK);
    assert_eq!(r.invalid_samples, 0, "{integrator}: invalid samples");
    b
}

/// Camera rays through 4×4 positions in every pixel (edges included), with their block.
fn pixel_rays(scene: &Scene) -> impl Iterator<Item = (usize, lt_core::geometry::Ray)> + '_ {
    let cam = &scene.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let bx = w.div_ceil(BLOCK);
    (0..h).flat_map(move |y| {
        (0..w).flat_map(move |x| {
            (0..16).map(move |s| {
                let raster = Vec2::new(
                    x as f32 + (s % 4) as f32 / 3.0,
                    y as f32 + (s / 4) as f32 / 3.0,
                );
                ((y / BLOCK) * bx + x / BLOCK, cam.generate_ray(raster))
            })
        })
    })
}

/// Blocks any of whose camera rays hits an emitter first.
fn blocks_seeing_emitters(scene: &Scene) -> Vec<bool> {
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let mut seen = vec![false; w.div_ceil(BLOCK) * h.div_ceil(BLOCK)];
    for (b, ray) in pixel_rays(scene) {
        if scene.intersect(&ray).is_some_and(|hit| hit.light.is_some()) {
            seen[b] = true;
        }
    }
    seen
}

/// Σ relative bias² over blocks × channels and its standard error (module docs).
#[derive(Clone, Copy, Debug)]
struct Bias2 {
    sum: f64,
    se: f64,
    terms: usize,
}

impl std::fmt::Display for Bias2 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Σ rel. bias² {:.4e} ± {:.2e} ({:.1} se, {} terms)",
            self.sum,
            self.se,
            self.sum / self.se,
            self.terms
        )
    }
}

fn relative_bias2(x: &RunningBlocks, reference: &RunningBlocks, skip: &[bool]) -> Bias2 {
    let (k, n) = (x.count() as f64, reference.count() as f64);
    let (xe, re) = (x.estimate(), reference.estimate());
    let (mut sum, mut var, mut terms) = (0.0, 0.0, 0);
    for b in (0..re.regions()).filter(|&b| !skip[b]) {
        for c in 0..3 {
            let (r, se_r) = (re.mean[b][c], re.std_error[b][c]);
            if !(r > 4.0 * se_r) {
                continue;
            }
            let r2 = r * r;
            let (vx, vr) = (xe.std_error[b][c].powi(2) / r2, se_r * se_r / r2);
            let v = vx + vr;
            let d = (xe.mean[b][c] - r) / r;
            let b2 = d * d - v;
            sum += b2;
            var += 4.0 * b2.max(0.0) * v
                + 2.0 * v * v
                + 2.0 * vx * vx / (k - 1.0)
                + 2.0 * vr * vr / (n - 1.0);
            terms += 1;
        }
    }
    Bias2 {
        sum,
        se: var.sqrt(),
        terms,
    }
}

fn block_name(a: &Agreement, i: usize) -> String {
    format!("({},{})", i % a.blocks_x, i / a.blocks_x)
}

fn describe(a: &Agreement) -> String {
    format!(
        "max |z| {:.2} (threshold {:.2}) at block {} channel {}, mean z² {:.2}",
        a.max_abs_z,
        a.threshold,
        block_name(a, a.worst_region),
        ["R", "G", "B"][a.worst_channel],
        a.mean_z2
    )
}

/// Max |z| over a subset of blocks and the Šidák threshold for that subset:
/// (max |z|, worst block, worst channel, threshold).
fn over_blocks(a: &Agreement, blocks: &[usize]) -> (f64, usize, usize, f64) {
    let (mut max, mut worst, mut channel) = (0.0f64, 0, 0);
    for &i in blocks {
        for c in 0..3 {
            let z = a.z[i][c].abs();
            if !max.is_nan() && (z.is_nan() || z > max) {
                (max, worst, channel) = (z, i, c);
            }
        }
    }
    (
        max,
        worst,
        channel,
        sidak_threshold(ALPHA, blocks.len() * 3),
    )
}

/// `pm` on `cornell-box` (32×32) with a deliberately large fixed radius, radius_scene = 0.1
/// (0.35 scene units, ≈ 3.5 pixel footprints): at P = 4096 photon paths (the default, 4 per
/// pixel) and at 16 P. Bias at a fixed radius comes from the kernel (the radiance smoothed over
/// the disk, boundary losses where the disk straddles an edge, light gathered across a corner),
/// none of which depends on the photon count, so B(16P) must (1) exclude zero by 4σ and (2) not be
/// smaller than B(P) beyond noise: B(16P) > B(P) − 4 sqrt(se²(P) + se²(16P)).
///
/// K = 32 runs at P (each noisy: 4 photons per pixel) and 12 at 16P, 4 passes each (the passes
/// only average camera samples over the run's fixed map).
#[test]
fn fixed_radius_photon_mapping_stays_biased() {
    let t = Instant::now();
    let scene = shipped_scene("cornell-box", Some((32, 32)));
    let skip = blocks_seeing_emitters(&scene);
    let reference = block_stats(&scene, "pt", IntegratorParams::new(), 4096, 11);
    let p = 4096u64;
    let measure = |photons: u64, runs: u64, seed: u64| {
        let pm = params(&[("radius_scene", "0.1"), ("photons", &photons.to_string())]);
        relative_bias2(
            &independent_runs(&scene, "pm", &pm, 4, runs, seed),
            &reference,
            &skip,
        )
    };
    let b1 = measure(p, 32, 1000);
    let b16 = measure(16 * p, 12, 2000);
    println!("pm radius_scene=0.1, photons={p}: {b1}");
    println!("pm radius_scene=0.1, photons={}: {b16}", 16 * p);
    let floor = b1.sum - BIAS_SIGMAS * b1.se.hypot(b16.se);
    println!(
        "B(16P) {:.4e} vs B(P) − 4σ {floor:.4e}; {:.1?}",
        b16.sum,
        t.elapsed()
    );
    assert!(
        b16.sum > BIAS_SIGMAS * b16.se,
        "pm at a fixed radius with 16 P photons: bias² not resolved from zero: {b16}"
    );
    assert!(
        b16.sum > floor,
        "pm at a fixed radius: bias² fell from {b1} to {b16} with 16× the photons"
    );
}

/// One configuration of test 2: a photon mapper at a fine and at a coarse setting.
struct Setting {
    integrator: &'static str,
    fine: &'static [(&'static str, &'static str)],
    fine_passes: u32,
    coarse: &'static [(&'static str, &'static str)],
    coarse_passes: u32,
}

/// Fine: a radius of half a pixel footprint and many photons (pm: 16 per pixel) or passes
/// (ppm/sppm: 256, where the global schedule r²ᵢ ∝ i^(α−1) has brought r to 0.4 of r₀). Coarse: a
/// radius of half the scene's bounding-sphere diameter, 1 photon per pixel or 4 passes.
const SETTINGS: [Setting; 3] = [
    Setting {
        integrator: "pm",
        fine: &[("photons", "16384"), ("radius_px", "0.5")],
        fine_passes: 16,
        coarse: &[("photons", "1024"), ("radius_scene", "0.5")],
        coarse_passes: 16,
    },
    Setting {
        integrator: "ppm",
        fine: &[("radius_px", "0.5")],
        fine_passes: 256,
        coarse: &[("radius_scene", "0.5")],
        coarse_passes: 4,
    },
    Setting {
        integrator: "sppm",
        fine: &[("radius_px", "0.5")],
        fine_passes: 256,
        coarse: &[("radius_scene", "0.5")],
        coarse_passes: 4,
    },
];

/// `pm`, `ppm` and `sppm` against `pt` per 8×8 block (t-corrected, Šidák-corrected z over blocks
/// × channels, as in tests/agreement.rs) on `cornell-box` at 32×32, per path length:
/// - max_depth 2 with `direct=photons`: the whole image but emission is one photon bounce (with
///   `direct=nee` nothing at depth 2 would come from photons);
/// - max_depth 3 with the default `direct=nee`: direct light by next-event estimation, the
///   one-bounce indirect light from photons of two segments.
///
/// The fine setting must agree; the coarse one must have a larger relative bias² than the fine
/// one by more than z_Šidák(6 comparisons) standard errors of the difference.
#[test]
fn photon_estimates_approach_pt_per_path_length() {
    let t = Instant::now();
    let scene = shipped_scene("cornell-box", Some((32, 32)));
    let skip = blocks_seeing_emitters(&scene);
    let z_approach = sidak_threshold(ALPHA, 2 * SETTINGS.len());
    let mut failures = Vec::new();
    for (depth, direct) in [(2u32, "photons"), (3, "nee")] {
        let with_depth = |pairs: &[(&str, &str)]| {
            let mut p = params(pairs);
            p.set("max_depth", depth);
            p
        };
        let reference = block_stats(&scene, "pt", with_depth(&[]), 4096, 20 + depth as u64);
        for (i, s) in SETTINGS.iter().enumerate() {
            let seed = 100 * depth as u64 + 10 * i as u64;
            let render = |pairs: &[(&str, &str)], passes: u32, seed: u64| {
                let mut p = with_depth(pairs);
                p.set("direct", direct);
                block_stats(&scene, s.integrator, p, passes, seed)
            };
            let fine = render(s.fine, s.fine_passes, seed);
            let coarse = render(s.coarse, s.coarse_passes, seed + 5);
            assert_eq!(fine.count(), CONSISTENT_RUNS as u64);
            let (a_fine, a_coarse) = (
                agreement_t(&fine, &reference, ALPHA),
                agreement_t(&coarse, &reference, ALPHA),
            );
            let (b_fine, b_coarse) = (
                relative_bias2(&fine, &reference, &skip),
                relative_bias2(&coarse, &reference, &skip),
            );
            let z = (b_coarse.sum - b_fine.sum) / b_coarse.se.hypot(b_fine.se);
            let label = format!("max_depth={depth} direct={direct} {}", s.integrator);
            println!(
                "{label} fine {:?} × {} passes vs pt: {}; {b_fine}",
                s.fine,
                s.fine_passes,
                describe(&a_fine)
            );
            println!(
                "{label} coarse {:?} × {} passes vs pt: {}; {b_coarse}; coarse − fine: z = {z:.1} \
                 (threshold {z_approach:.2})",
                s.coarse,
                s.coarse_passes,
                describe(&a_coarse)
            );
            if !a_fine.passed() {
                failures.push(format!(
                    "{label}: the fine setting disagrees with pt: {}",
                    describe(&a_fine)
                ));
            }
            if !(z > z_approach) {
                failures.push(format!(
                    "{label}: the coarse setting's bias² ({b_coarse}) is not above the fine one's \
                     ({b_fine}): z = {z:.2} ≤ {z_approach:.2}"
                ));
            }
        }
    }
    println!("{:.1?}", t.elapsed());
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

/// Blocks any of whose camera rays first hits a non-delta surface within `radius` of `centre`
/// (world coordinates).
fn blocks_seeing_disk(scene: &Scene, centre: Vec3, radius: f32) -> Vec<usize> {
    let c = centre - scene.origin;
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let mut seen = vec![false; w.div_ceil(BLOCK) * h.div_ceil(BLOCK)];
    for (b, ray) in pixel_rays(scene) {
        if let Some(hit) = scene.intersect(&ray) {
            if !scene.material(hit.material).is_delta() && (hit.p - c).length() <= radius {
                seen[b] = true;
            }
        }
    }
    (0..seen.len()).filter(|&b| seen[b]).collect()
}

/// Block statistics of an unbiased estimator over its first `early` passes and over all `passes`.
fn unbiased_with_snapshot(
    scene: &Scene,
    integrator: &str,
    passes: u32,
    early: u32,
    seed: u64,
) -> (RunningBlocks, RunningBlocks) {
    let integ = make_integrator(integrator, scene, &IntegratorParams::new()).unwrap();
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let mut blocks = RunningBlocks::new(w, h, BLOCK);
    let mut snapshot = None;
    let opts = RenderOptions {
        passes,
        time_limit: None,
        seed,
        threads: 0,
    };
    let r = render(scene, &integ, &opts, |r| {
        blocks.add(r.pass_image().expect("an unbiased pass has an image"));
        if r.passes_done == early {
            snapshot = Some(blocks.clone());
        }
        ControlFlow::Continue(())
    })
    .unwrap();
    assert_eq!(r.invalid_samples, 0, "{integrator}: invalid samples");
    (snapshot.expect("early ≤ passes"), blocks)
}

/// (a) `cornell-point-caustic` (64×64, so the caustic has blocks of its own, see
/// tests/agreement.rs): a point light above a glass ball, whose caustic paths L S S D … E `pt`
/// cannot sample at all. The caustic lies inside the ball's shadow on the floor, a disk of radius
/// 1.75 tan(asin(0.25/1.25)) = 0.357 around (0.375, −1, 0.375); on every block that sees that disk
/// `sppm` (8 independent runs) agrees with BDPT (per-pass statistics), Šidák over those blocks.
///
/// (b) `caustic-sds` (64×48): the camera sees the floor only through a mirror, and the ball
/// focuses the light onto the floor at the axis point (0.866, 0, 0) (light centre → ball centre,
/// produced to y = 0), whose mirror image is (0.866, 0, −5). On the block holding its projection:
/// - `sppm`'s caustic — its block mean minus that of `sppm` at max_depth 4, which renders every
///   path of the block but the 5-segment caustic — is more than 4 standard errors above zero;
/// - it agrees with a long BDPT render (2048 passes) of the same block: BDPT is unbiased and can
///   find these paths (by BSDF sampling from the floor through the ball to the light), so it is
///   the reference the photon estimate must be comparable to;
/// - at equal passes BDPT is far noisier: the variance of its mean over `P` passes exceeds the
///   variance of one `sppm` run of `P` passes, with both χ² intervals (99.9 %) apart.
///
/// "Only photons" does not hold literally here: the ball fills a large solid angle of the caustic
/// point's hemisphere with the light's image, so BDPT's unidirectional hits are frequent and its
/// estimate converges, at a much larger error per pass.
#[test]
fn only_photons_render_the_caustic_seen_in_the_mirror() {
    let t = Instant::now();
    // (a)
    let scene = shipped_scene("cornell-point-caustic", Some((64, 64)));
    let caustic = blocks_seeing_disk(&scene, Vec3::new(0.375, -1.0, 0.375), 0.357);
    let sppm = block_stats(&scene, "sppm", params(&[("radius_px", "1")]), 64, 301);
    let bdpt = block_stats(&scene, "bdpt", IntegratorParams::new(), 256, 302);
    let a = agreement_t(&sppm, &bdpt, ALPHA);
    let (z, worst, c, thr) = over_blocks(&a, &caustic);
    let (se, be) = (sppm.estimate(), bdpt.estimate());
    for &i in &caustic {
        println!(
            "cornell-point-caustic block {}: sppm {:.4?} ± {:.4?}, bdpt {:.4?} ± {:.4?}, z {:.2?}",
            block_name(&a, i),
            se.mean[i],
            se.std_error[i],
            be.mean[i],
            be.std_error[i],
            a.z[i]
        );
    }
    println!(
        "cornell-point-caustic sppm vs bdpt over the {} blocks seeing the shadow disk: max |z| \
         {z:.2} (threshold {thr:.2}) at block {} channel {c}; {:.1?}",
        caustic.len(),
        block_name(&a, worst),
        t.elapsed()
    );
    assert!(
        z < thr,
        "cornell-point-caustic: sppm and bdpt disagree on the caustic: |z| {z:.2} ≥ {thr:.2} at \
         block {} channel {c}",
        block_name(&a, worst)
    );

    // (b)
    let scene = shipped_scene("caustic-sds", Some((64, 48)));
    let proj = scene
        .camera
        .project(Vec3::new(0.866, 0.0, -5.0) - scene.origin)
        .expect("the caustic's mirror image is in view");
    let bx = (scene.camera.width as usize).div_ceil(BLOCK);
    let i = (proj.raster.y as usize / BLOCK) * bx + proj.raster.x as usize / BLOCK;
    let passes = 128;
    let sppm = block_stats(&scene, "sppm", IntegratorParams::new(), passes, 401);
    // The caustic's paths E → mirror → floor → glass → glass → light have 5 segments; with
    // max_depth 4 the block keeps everything else it holds (the floor lit directly, 3 segments,
    // and through the mirror, 4), so the caustic is the difference.
    let no_caustic = block_stats(&scene, "sppm", params(&[("max_depth", "4")]), passes, 501);
    let (bdpt_early, bdpt_long) = unbiased_with_snapshot(&scene, "bdpt", 2048, passes, 402);
    let (s, s4, bl, b0) = (
        sppm.estimate(),
        no_caustic.estimate(),
        bdpt_long.estimate(),
        bdpt_early.estimate(),
    );
    let whole = agreement_t(&sppm, &bdpt_long, ALPHA);
    println!(
        "caustic-sds, whole image (reported, not asserted): sppm vs bdpt {} passes: {}; blocks \
         over the threshold: {:?}",
        bdpt_long.count(),
        describe(&whole),
        (0..whole.regions)
            .filter(|&b| whole.z[b].iter().any(|z| !(z.abs() < whole.threshold)))
            .map(|b| (
                block_name(&whole, b),
                s.mean[b][1],
                bl.mean[b][1],
                whole.z[b][1]
            ))
            .collect::<Vec<_>>()
    );
    let a = agreement_t(&sppm, &bdpt_long, ALPHA);
    let (z, _, _, thr) = over_blocks(&a, &[i]);
    let runs = sppm.count() as f64;
    let conf = 1.0 - ALPHA;
    println!(
        "caustic-sds block {} (raster {:.1?}): sppm {passes} passes × {runs} runs {:.4} ± {:.4}; \
         bdpt {passes} passes {:.4} ± {:.4}; bdpt {} passes {:.4} ± {:.4}; sppm vs bdpt(long) \
         max |z| {z:.2} (threshold {thr:.2})",
        block_name(&a, i),
        proj.raster,
        s.mean[i][1],
        s.std_error[i][1],
        b0.mean[i][1],
        b0.std_error[i][1],
        bdpt_long.count(),
        bl.mean[i][1],
        bl.std_error[i][1],
    );
    for ch in 0..3 {
        let (m, e) = (s.mean[i][ch], s.std_error[i][ch]);
        let (caustic, caustic_se) = (m - s4.mean[i][ch], e.hypot(s4.std_error[i][ch]));
        println!(
            "  channel {ch}: sppm max_depth 8 {m:.4} ± {e:.4}, max_depth 4 {:.4} ± {:.4}: the \
             caustic {caustic:.4} ± {caustic_se:.4} ({:.0} % of the block)",
            s4.mean[i][ch],
            s4.std_error[i][ch],
            100.0 * caustic / m
        );
        assert!(
            caustic > 4.0 * caustic_se,
            "caustic-sds: sppm's caustic is not resolved from zero in channel {ch}: \
             {caustic} ± {caustic_se}"
        );
        // Variance of one sppm run (dof runs − 1) against the variance of BDPT's P-pass mean
        // (dof P − 1), each with its χ² interval.
        let sppm_run = variance_interval(e * e * runs, runs - 1.0, conf);
        let bdpt_mean = variance_interval(b0.std_error[i][ch].powi(2), passes as f64 - 1.0, conf);
        println!(
            "  channel {ch}: relative error of one {passes}-pass render: sppm {:.4} [{:.4}, \
             {:.4}], bdpt {:.4} [{:.4}, {:.4}]",
            sppm_run.estimate.sqrt() / m,
            sppm_run.lo.sqrt() / m,
            sppm_run.hi.sqrt() / m,
            bdpt_mean.estimate.sqrt() / m,
            bdpt_mean.lo.sqrt() / m,
            bdpt_mean.hi.sqrt() / m
        );
        assert!(
            bdpt_mean.lo > sppm_run.hi,
            "caustic-sds channel {ch}: bdpt at {passes} passes is not noisier than one sppm run: \
             variance {bdpt_mean} vs {sppm_run}"
        );
    }
    assert!(
        z < thr,
        "caustic-sds: sppm and a long bdpt disagree on the caustic: |z| {z:.2} ≥ {thr:.2}"
    );
    println!("{:.1?}", t.elapsed());
}

/// `cornell-plastic`: the photon family's camera paths follow plastic's delta coating lobe with
/// its probability (`visible::trace_visible_point`), so `sppm` sees what the smooth ball mirrors.
/// Compared with `pt` (max_depth 3: direct light by NEE, one-bounce indirect by photons) over the
/// 4×4-pixel blocks that see nothing but the ball, away from the floor corners where the kernel's
/// bias lives. A camera path that stopped at the ball for its diffuse lobe alone loses the
/// coating's reflection: planted, the worst of these blocks came out at 0.564 of pt, |z| 21.5.
#[test]
fn sppm_sees_the_smooth_plastic_coating() {
    const SMALL: usize = 4;
    // 64×64: the ball is ~17 pixels across, so whole 4×4 blocks lie on it.
    let scene = shipped_scene("cornell-plastic", Some((64, 64)));
    let with_depth = || {
        let mut p = params(&[]);
        p.set("max_depth", 3);
        p
    };
    // 125 passes a run: sppm's bias (∝ N^(−1/3) at α = 2/3) and its runs' standard error
    // (variance ∝ N^(−2/3)) shrink alike, so fewer passes leave their ratio as it was at 500,
    // while the planted miss's |z| (21.5 at 500 with pt at 2048) falls only to ≈ 13.
    let (_, reference) = render_blocks(&scene, "pt", with_depth(), 512, 7, SMALL);
    let (r, sppm) = render_blocks(&scene, "sppm", with_depth(), 125, 3, SMALL);
    assert_eq!(r.invalid_samples, 0);
    // Blocks whose every camera ray (4×4 per pixel) hits the ball (centre, radius 0.38).
    let (centre, radius) = (Vec3::new(-0.4, -0.62, -0.25), 0.38f32);
    let cam = &scene.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let bx = w.div_ceil(SMALL);
    let mut all_ball = vec![true; bx * h.div_ceil(SMALL)];
    for y in 0..h {
        for x in 0..w {
            for (i, j) in (0..4).flat_map(|i| (0..4).map(move |j| (i, j))) {
                let raster = Vec2::new(x as f32 + i as f32 / 3.0, y as f32 + j as f32 / 3.0);
                let ray = cam.generate_ray(raster);
                let oc = centre - ray.o;
                let t = oc.dot(ray.d);
                if !(t > 0.0 && (oc - ray.d * t).length() < radius) {
                    all_ball[(y / SMALL) * bx + x / SMALL] = false;
                }
            }
        }
    }
    let ball: Vec<usize> = (0..all_ball.len()).filter(|&b| all_ball[b]).collect();
    assert!(
        ball.len() >= 3,
        "only {} blocks see nothing but the ball",
        ball.len()
    );
    let a = agreement_t(&sppm, &reference, ALPHA);
    let (z, worst, c, thr) = over_blocks(&a, &ball);
    let (s, r) = (sppm.estimate(), reference.estimate());
    println!(
        "cornell-plastic sppm vs pt over the {} 4×4 blocks seeing only the smooth ball: max |z| \
         {z:.2} (threshold {thr:.2}) at block {} channel {c}, ratio {:.4}",
        ball.len(),
        block_name(&a, worst),
        s.mean[worst][c] / r.mean[worst][c]
    );
    assert!(
        z < thr,
        "sppm misses part of the plastic ball: |z| {z:.2} ≥ {thr:.2}"
    );
}

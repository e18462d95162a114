//! Unidirectional and bidirectional estimators against each other, per 8×8 block (Šidák-corrected,
//! t-corrected z over blocks × channels; `lt_estimators::agreement`):
//!
//! 1. Per path length: `light` and `bdpt` (MIS power and none; balance on `cornell-box` and its
//!    filter and camera twins, its weights held elsewhere by `mis_check`) against `pt` at every
//!    max_depth 1…5 on `cornell-box`, `cornell-mesh-light`, `cornell-env`, `sun-room`,
//!    `cornell-directional` and more. A bias in paths of exactly k segments first shows at
//!    max_depth = k, so the failing depth names the path length. Each estimator renders once at
//!    max_depth 5 and every max_depth's image is taken from its passes split by path length
//!    (`lt_tests::per_length`); Šidák runs over every depth, estimator, block and channel a test
//!    compares. None of these scenes has a delta surface
//!    (mirror, glass), so light tracing, which cannot join the pinhole to a delta vertex, renders
//!    every path the camera can see, and all five estimators estimate the same image. The only
//!    delta light among them, `cornell-directional`'s, is never seen directly by any estimator.
//! 2. Through glass: `light` against `bdpt` on `cornell-point-caustic` (where `pt` is exactly zero
//!    on the caustic, and light tracing must show it), `bdpt` against `pt` on
//!    `cornell-glass-light`.
//! 3. Off axis: `light` against `pt` on a corner block of a wide-angle view, where a wrong power
//!    of cos θ in the camera's importance changes the answer by tens of per cent, and at the
//!    centre.
//! 4. Through media: on every media scene (`scenes/media/`), every integrator of
//!    `registry::HANDLES_MEDIA` (so bdpt joins when it walks media) against `pt` at the scene's
//!    max_depth, whole images: the media walks have no per-length recorder yet.

use lt_core::camera::{Camera, FilterShape, FovAxis, PixelFilter};
use lt_core::{Scene, Vec2, Vec3};
use lt_estimators::agreement::{agreement_t, sidak_threshold, Agreement};
use lt_estimators::blocks::RunningBlocks;
use lt_integrators::IntegratorParams;
use lt_tests::per_length::{render_per_length, PerLength};
use lt_tests::{
    handles_media, render_blocks, shared, shipped_media_scene_names, shipped_scene, Rendered,
};
use std::sync::Arc;

/// Family-wise false-alarm rate of every comparison here.
const ALPHA: f64 = 1e-3;
const BLOCK: usize = 8;
/// The longest path length compared, and the max_depth of the reference's render.
const LENGTHS: u32 = 5;

/// One estimator configuration: a label, an integrator, its MIS key (if any) and its passes.
#[derive(Clone, Copy)]
struct Config {
    label: &'static str,
    integrator: &'static str,
    mis: Option<&'static str>,
    passes: u32,
    seed: u64,
}

impl Config {
    fn params(&self, max_depth: Option<u32>) -> IntegratorParams {
        let mut p = IntegratorParams::new();
        if let Some(d) = max_depth {
            p = p.with("max_depth", d);
        }
        if let Some(m) = self.mis {
            p = p.with("mis", m);
        }
        p
    }

    fn render(&self, scene: &Scene, max_depth: Option<u32>) -> (Rendered, RunningBlocks) {
        let (r, b) = render_blocks(
            scene,
            self.integrator,
            self.params(max_depth),
            self.passes,
            self.seed,
            BLOCK,
        );
        assert_eq!(r.invalid_samples, 0, "{}: invalid samples", self.label);
        (r, b)
    }

    /// Per-length statistics of one render at `max_depth` of `scene` (named `scene_name`:
    /// renders of one name, configuration and depth are made once per test binary).
    fn per_length(&self, scene_name: &str, scene: &Scene, max_depth: u32) -> Arc<PerLength> {
        let key = format!(
            "agreement {scene_name} {} max_depth {max_depth} passes {} seed {}",
            self.label, self.passes, self.seed
        );
        shared(&key, || {
            let r = render_per_length(
                scene,
                self.integrator,
                &self.params(Some(max_depth)),
                self.passes,
                self.seed,
                BLOCK,
            );
            assert_eq!(r.invalid_samples, 0, "{}: invalid samples", self.label);
            r
        })
    }
}

/// The per-comparison false-alarm rate that keeps `ALPHA` over `comparisons` of them (Šidák;
/// `agreement_t` then corrects over the blocks × channels of each).
fn per_comparison(comparisons: usize) -> f64 {
    -(((-ALPHA).ln_1p()) / comparisons.max(1) as f64).exp_m1()
}

/// The reference: path tracing with NEE and MIS, with more passes than the others (it is cheap).
const PT: Config = Config {
    label: "pt",
    integrator: "pt",
    mis: None,
    passes: 2048,
    seed: 101,
};

/// What is compared with `pt` at each depth. Passes put the median block's relative standard
/// error at 1–3 % per channel at 32×32 (bdpt with uniform weights is the noisiest).
const OTHERS: [Config; 4] = [
    Config {
        label: "light",
        integrator: "light",
        mis: None,
        passes: 1024,
        seed: 102,
    },
    Config {
        label: "bdpt mis=power",
        integrator: "bdpt",
        mis: Some("power"),
        passes: 256,
        seed: 103,
    },
    Config {
        label: "bdpt mis=balance",
        integrator: "bdpt",
        mis: Some("balance"),
        passes: 256,
        seed: 104,
    },
    Config {
        label: "bdpt mis=none",
        integrator: "bdpt",
        mis: Some("none"),
        passes: 512,
        seed: 105,
    },
];

/// (scene, label, reason) pairs not compared: an estimator that legitimately cannot be checked on a
/// scene at any affordable sample count. Reported, never silently skipped.
const EXCLUDED: &[(&str, &str, &str)] = &[
    (
        "envmap-spheres",
        "light",
        "the camera sees the glass sphere: a path whose first vertex from the camera is specular \
         (E S …) has no light-tracing technique (connecting to the lens through a delta BSDF has \
         probability zero), so light tracing leaves it out by construction (observed: block ratio \
         0.09–0.6 over the sphere); bdpt, which has the other techniques, is compared",
    ),
    (
        "cornell-thinlens-tent",
        "bdpt mis=none",
        "uniform weights give every technique a third of the k = 2 paths, and behind the card's \
         edge the block means are heavy-tailed at 512 passes: observed ratios 0.81–0.89 at blocks \
         (0,2)/(0,3), |z| up to 5.6, over four seeds, all low; seed 405 at 8192 passes has \
         max |z| 1.57 — convergence, not bias. Checked with more passes by \
         `bdpt_without_mis_agrees_with_pt_on_cornell_thinlens_tent_with_more_passes`",
    ),
    (
        "cornell-plastic",
        "light",
        "the smooth plastic's coating is a delta lobe: what the camera sees mirrored in it is \
         reached by camera walks only (light tracing joins the ball to the pinhole through its \
         diffuse lobe), as for glass and mirrors. Checked on every block off the ball by \
         `light_agrees_with_pt_off_the_smooth_ball_on_cornell_plastic`",
    ),
    (
        "sun-room",
        "bdpt mis=none",
        "the sun (6.87e-5 sr) is found by s = 0 (a camera bounce hitting it) with density ~2e-5 per \
         bounce from the sunlit floor, yet uniform weights give that strategy 1/3 of the k = 2 \
         paths: ~1 hit per block in 512 passes, so the block means are heavy-tailed and the sample \
         standard error misses the rare hits (observed: block mean ratio 0.670 ≈ 2/3, z ≈ −22 at \
         max_depth 2); the power and balance heuristics give s = 0 a negligible weight there",
    ),
    (
        "cornell-rough-glass",
        "bdpt mis=none",
        "uniform weights give every connection at a rough-glass vertex a full share, and through a \
         rough interface of IOR 1.33–1.5 the transmitted lobe is only ≈ (1 − 1/η) α wide, so those \
         joins are heavy-tailed: block means 0.82 of pt (|z| 8.3) at max_depth 4–5 in the sphere's \
         blocks at 512 passes, growing with passes (slab alone at α 0.2: |z| 2.8 at 512, 14 at \
         8192). Tails, not a density error: with α 0.6 uniform weights agree (max |z| 2.9), and at \
         IOR 1.0001 (a near-delta lobe) light tracing is off by |z| 575 while bdpt with power or \
         balance weights (which give those joins nothing) agrees (max |z| 1.9 / 2.0); lt mis-check \
         --mis none holds every weight to the oracle (2842 paths)",
    ),
];

/// `cornell-plastic`'s smooth ball: (centre, radius).
const SMOOTH_PLASTIC_BALL: (Vec3, f32) = (Vec3::new(-0.4, -0.62, -0.25), 0.38);

/// Cases that fail because of an integrator bug, kept asserted: (scene, label, max_depth, bug).
/// Each must still fail, so a fix is noticed and the entry removed.
const KNOWN_FAILURES: &[(&str, &str, u32, &str)] = &[];

/// The worst block's mean ratio (other / reference) in the worst channel, for reports.
fn worst_ratio(a: &Agreement, other: &RunningBlocks, reference: &RunningBlocks) -> f64 {
    let (o, r) = (other.estimate(), reference.estimate());
    o.mean[a.worst_region][a.worst_channel] / r.mean[a.worst_region][a.worst_channel]
}

/// Max |z| over a subset of blocks, with the Šidák threshold for that subset in each of
/// `comparisons` images: (max |z|, worst block, worst channel, threshold).
fn over_blocks(a: &Agreement, blocks: &[usize], comparisons: usize) -> (f64, usize, usize, f64) {
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
        sidak_threshold(ALPHA, comparisons * blocks.len() * 3),
    )
}

fn block_name(a: &Agreement, i: usize) -> String {
    format!("({},{})", i % a.blocks_x, i / a.blocks_x)
}

/// `OTHERS` but the balance heuristic against `PT` at every max_depth 1…`LENGTHS`. The balance
/// heuristic's weights are held to the oracle on every shipped scene (`mis_check`), so once the
/// power heuristic and uniform weights agree here its image can differ only by a weight: it is
/// compared per depth on `cornell-box` and its Gaussian-filtered and orthographic twins.
fn per_depth(scene_name: &str) {
    let others = [OTHERS[0], OTHERS[1], OTHERS[3]];
    per_length_on(
        scene_name,
        &shipped_scene(scene_name, Some((32, 32))),
        LENGTHS,
        &others,
    );
}

/// `others` against `PT` on `scene` (named `scene_name` in reports and in `EXCLUDED`) at every
/// max_depth 1…`lengths`: each rendered once at max_depth `lengths` (`PT` at `LENGTHS`, its
/// render shared with every test of the same scene) and split by path length.
fn per_length_on(scene_name: &str, scene: &Scene, lengths: u32, others: &[Config]) {
    let excluded = |other: &Config| {
        EXCLUDED
            .iter()
            .find(|(s, l, _)| *s == scene_name && *l == other.label)
            .map(|(_, _, why)| *why)
    };
    for other in others {
        if let Some(why) = excluded(other) {
            println!("{scene_name} {}: excluded ({why})", other.label);
        }
    }
    let compared: Vec<&Config> = others.iter().filter(|o| excluded(o).is_none()).collect();
    let alpha = per_comparison(compared.len() * lengths as usize);
    let reference = PT.per_length(scene_name, scene, LENGTHS.max(lengths));
    let mut failures = Vec::new();
    for other in compared {
        let rendered = other.per_length(scene_name, scene, lengths);
        for k in 1..=lengths {
            let (blocks, reference) = (
                &rendered.up_to[k as usize - 1],
                &reference.up_to[k as usize - 1],
            );
            let a = agreement_t(blocks, reference, alpha);
            let line = format!(
                "{scene_name} max_depth={k} {} vs pt: max |z| {:.2} (threshold {:.2}) at block {} \
                 channel {}, mean ratio there {:.4}; mean z² {:.2}",
                other.label,
                a.max_abs_z,
                a.threshold,
                block_name(&a, a.worst_region),
                ["R", "G", "B"][a.worst_channel],
                worst_ratio(&a, blocks, reference),
                a.mean_z2
            );
            let known = KNOWN_FAILURES
                .iter()
                .find(|(s, l, d, _)| *s == scene_name && *l == other.label && *d == k)
                .map(|(_, _, _, why)| *why);
            match (a.passed(), known) {
                (true, None) => println!("{line}"),
                (false, None) => {
                    println!("{line}  FAILED");
                    failures.push(line);
                }
                (false, Some(why)) => println!("{line}  KNOWN FAILURE ({why})"),
                (true, Some(why)) => failures.push(format!(
                    "{line}: listed in KNOWN_FAILURES ({why}) but now passes: remove it"
                )),
            }
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

#[test]
fn light_and_bdpt_agree_with_pt_per_depth_on_cornell_box() {
    let scene = shipped_scene("cornell-box", Some((32, 32)));
    per_length_on("cornell-box", &scene, LENGTHS, &OTHERS);
}

/// A thin lens, a tent filter and a card blocking part of the aperture: camera rays sample the
/// lens and the filter, splats spread over the pixels the tent reaches and connections to lens
/// points behind the card are blocked. Neighbouring pixels share samples through the filter, so
/// the test's units are 8×8 block means of each pass image (independent across passes).
#[test]
fn light_and_bdpt_agree_with_pt_per_depth_on_cornell_thinlens_tent() {
    per_depth("cornell-thinlens-tent");
}

/// `bdpt mis=none` on the thin-lens scene with the passes its heavy tails need (see `EXCLUDED`).
#[test]
fn bdpt_without_mis_agrees_with_pt_on_cornell_thinlens_tent_with_more_passes() {
    // Its own label: `EXCLUDED` leaves out the 512-pass configuration on this scene, not this.
    let none = Config {
        label: "bdpt mis=none, 8192 passes",
        passes: 8192,
        ..OTHERS[3]
    };
    let scene = shipped_scene("cornell-thinlens-tent", Some((32, 32)));
    per_length_on("cornell-thinlens-tent", &scene, 3, &[none]);
}

/// Mitsuba's default filter (Gaussian, stddev 0.5, truncated at 4σ) on the pinhole Cornell box.
#[test]
fn light_and_bdpt_agree_with_pt_per_depth_on_cornell_box_gaussian() {
    let mut scene = shipped_scene("cornell-box", Some((32, 32)));
    let gaussian = PixelFilter::new(FilterShape::Gaussian { stddev: 0.5 }).unwrap();
    scene.camera = scene.camera.with_filter(gaussian);
    per_length_on("cornell-box gaussian", &scene, LENGTHS, &OTHERS);
}

/// An orthographic camera (a delta in direction) with a tent filter: `bdpt` without its t = 1
/// strategy, which no connection can take, against `pt` (`light` refuses such a camera).
#[test]
fn bdpt_agrees_with_pt_per_depth_through_an_orthographic_camera() {
    let mut scene = shipped_scene("cornell-box", Some((32, 32)));
    let tent = PixelFilter::new(FilterShape::Tent { radius: 1.0 }).unwrap();
    scene.camera = scene.camera.orthographic(0.9).unwrap().with_filter(tent);
    assert!(
        lt_integrators::make_integrator("light", &scene, &IntegratorParams::new()).is_err(),
        "light tracing must refuse an orthographic camera"
    );
    per_length_on("cornell-box orthographic", &scene, 4, &OTHERS[1..3]);
}

#[test]
fn light_and_bdpt_agree_with_pt_per_depth_on_cornell_mesh_light() {
    per_depth("cornell-mesh-light");
}

#[test]
fn light_and_bdpt_agree_with_pt_per_depth_on_cornell_env() {
    per_depth("cornell-env");
}

/// Mitsuba's conductors: a rough (Beckmann) gold sphere, a nearly smooth one-sided copper sphere
/// and a two-sided rough GGX aluminium wall: coloured Fresnel on glossy and delta lobes, in both
/// transport modes.
#[test]
fn light_and_bdpt_agree_with_pt_per_depth_on_cornell_conductors() {
    per_depth("cornell-conductors");
}

/// Textures (checkerboard floor, bitmap wall, a rough conductor whose colour and α vary): every
/// estimator must read the same parameters at the same uv, in both transport modes.
/// Rough glass (a GGX slab, a Beckmann sphere) and a thin-glass pane the camera sees only
/// through the slab: rough refraction in both transport modes (radiance scaled by 1/η² crossing
/// an interface, importance not) and delta pass-through reached by light walks and BSDF samples.
#[test]
fn light_and_bdpt_agree_with_pt_per_depth_on_cornell_rough_glass() {
    per_depth("cornell-rough-glass");
}

#[test]
fn light_and_bdpt_agree_with_pt_per_depth_on_cornell_textured() {
    per_depth("cornell-textured");
}

/// At max_depth 1 the camera does not see the sun (it is not in view), so every estimator's image
/// is exactly black there (z = 0 by definition); the sunlit floor patch appears at depth 2.
#[test]
fn light_and_bdpt_agree_with_pt_per_depth_on_sun_room() {
    per_depth("sun-room");
}

/// A directional light (a delta in direction) through a skylight: reached only by next-event
/// estimation and by light walks starting from it, so bdpt's s = 1 must keep its weight and
/// s = 0 and light tracing's x0 get none. At max_depth 1 every image is exactly black.
#[test]
fn light_and_bdpt_agree_with_pt_per_depth_on_cornell_directional() {
    per_depth("cornell-directional");
}

/// Blocks any of whose pixels (sampled at 4×4 positions each, edges included) see the sphere
/// (centre, radius) directly.
fn blocks_seeing_sphere(cam: &Camera, centre: Vec3, radius: f32) -> Vec<bool> {
    let (w, h) = (cam.width as usize, cam.height as usize);
    let bx = w.div_ceil(BLOCK);
    let mut seen = vec![false; bx * h.div_ceil(BLOCK)];
    for y in 0..h {
        for x in 0..w {
            for (i, j) in (0..4).flat_map(|i| (0..4).map(move |j| (i, j))) {
                let raster = Vec2::new(x as f32 + i as f32 / 3.0, y as f32 + j as f32 / 3.0);
                let ray = cam.generate_ray(raster);
                // Ray–sphere: the closest approach of the line to the centre, in front of the eye.
                let oc = centre - ray.o;
                let t = oc.dot(ray.d);
                if t > 0.0 && (oc - ray.d * t).length() <= radius {
                    seen[(y / BLOCK) * bx + x / BLOCK] = true;
                }
            }
        }
    }
    seen
}

/// `cornell-point-caustic`: light tracing and BDPT agree on every block the ball does not cover.
/// Where the camera sees the ball, the paths are E S S …: light tracing cannot join the pinhole to
/// a delta vertex, so its image is (rightly) missing them, while BDPT renders them by NEE behind
/// the ball; those blocks are left out, by geometry, not by their values. On the caustic below
/// the ball, `pt` has zero probability of the L S S D E paths, so light must exceed pt there by
/// far more than the noise: z > 4 at the block holding the caustic's centre.
#[test]
fn light_and_bdpt_agree_through_glass_on_cornell_point_caustic() {
    // 64×64: at 32×32 the caustic (radius ~0.1 on the floor, seen obliquely) shares its block with
    // the bottom of the ball, where light tracing is (rightly) darker than pt.
    let scene = shipped_scene("cornell-point-caustic", Some((64, 64)));
    let light = Config {
        label: "light",
        integrator: "light",
        mis: None,
        passes: 2048,
        seed: 201,
    };
    let bdpt = Config {
        label: "bdpt",
        integrator: "bdpt",
        mis: None,
        passes: 256,
        seed: 202,
    };
    let pt = Config {
        label: "pt",
        integrator: "pt",
        mis: None,
        passes: 1024,
        seed: 203,
    };
    let (_, l) = light.render(&scene, None);
    let (_, b) = bdpt.render(&scene, None);
    let (_, p) = pt.render(&scene, None);

    let ball = blocks_seeing_sphere(&scene.camera, Vec3::new(0.375, -0.5, 0.375), 0.25);
    let kept: Vec<usize> = (0..ball.len()).filter(|&i| !ball[i]).collect();
    let a = agreement_t(&l, &b, ALPHA);
    let (z, worst, c, thr) = over_blocks(&a, &kept, 1);
    let (le, be) = (l.estimate(), b.estimate());
    println!(
        "cornell-point-caustic light vs bdpt over {} of {} blocks (the ball's {} left out): \
         max |z| {z:.2} (threshold {thr:.2}) at block {} channel {}, mean ratio {:.4}",
        kept.len(),
        ball.len(),
        ball.len() - kept.len(),
        block_name(&a, worst),
        ["R", "G", "B"][c],
        le.mean[worst][c] / be.mean[worst][c]
    );
    assert!(
        z < thr,
        "cornell-point-caustic: light vs bdpt disagree: {z} ≥ {thr}"
    );

    // The caustic: around the projection of (0.375, −1, 0.375).
    let proj = scene
        .camera
        .project(Vec3::new(0.375, -1.0, 0.375))
        .expect("the caustic is in view");
    let bx = a.blocks_x;
    let (cx, cy) = (
        proj.raster.x as usize / BLOCK,
        proj.raster.y as usize / BLOCK,
    );
    let centre = cy * bx + cx;
    let lp = agreement_t(&l, &p, ALPHA);
    let pe = p.estimate();
    for dy in -1i64..=1 {
        for dx in -1i64..=1 {
            let (x, y) = (cx as i64 + dx, cy as i64 + dy);
            if x < 0 || y < 0 || x >= bx as i64 || y as usize * bx >= lp.z.len() {
                continue;
            }
            let i = y as usize * bx + x as usize;
            println!(
                "caustic block ({x},{y}){}{}: light {:.4?} pt {:.4?}, z(light − pt) {:.1?}",
                if i == centre { " [centre]" } else { "" },
                if ball[i] { " [sees the ball]" } else { "" },
                le.mean[i],
                pe.mean[i],
                lp.z[i]
            );
        }
    }
    for ch in 0..3 {
        assert!(
            lp.z[centre][ch] > 4.0,
            "caustic block {}: light − pt z = {:.2} in channel {ch}; the caustic is missing",
            block_name(&lp, centre),
            lp.z[centre][ch]
        );
    }
}

/// `cornell-glass-light`: every lit path leaves the emitter through two refractions; pt finds
/// them by BSDF sampling only, BDPT also by light tracing and connections after the shell.
#[test]
fn bdpt_and_pt_agree_through_glass_on_cornell_glass_light() {
    let scene = shipped_scene("cornell-glass-light", Some((32, 32)));
    let pt = Config {
        label: "pt",
        integrator: "pt",
        mis: None,
        passes: 4096,
        seed: 301,
    };
    let bdpt = Config {
        label: "bdpt",
        integrator: "bdpt",
        mis: None,
        passes: 512,
        seed: 302,
    };
    let (_, p) = pt.render(&scene, None);
    let (_, b) = bdpt.render(&scene, None);
    let a = agreement_t(&b, &p, ALPHA);
    println!(
        "cornell-glass-light bdpt vs pt: {a}; mean ratio at the worst block {:.4}",
        worst_ratio(&a, &b, &p)
    );
    assert!(a.passed(), "cornell-glass-light: bdpt vs pt: {a}");
}

/// Light tracing against pt on a corner block and the centre block of a wide view (fov 80° on
/// both axes, from inside cornell-box's opening, so every pixel sees a lit wall).
///
/// Light tracing weighs each splat by the pinhole's importance We ∝ 1/cos⁴θ; pt never uses it.
/// With cos³θ instead, every splat would be scaled by cos θ: ≈ 0.75 on the corner block (−25 %)
/// and ≈ 0.99 at the centre. The test computes that alternative's block mean from pt's own pixel
/// means and asserts that its expected |z| exceeds the threshold by at least 3 (so a cos³ bug
/// fails with probability > 99.8 %), then that light and pt agree on both blocks.
#[test]
fn light_agrees_with_pt_off_axis() {
    let mut scene = shipped_scene("cornell-box", None);
    scene.camera = Camera::look_at(
        Vec3::new(0.0, 0.0, 0.9),
        Vec3::new(0.0, 0.0, -1.0),
        Vec3::Y,
        80.0,
        FovAxis::X,
        32,
        32,
    )
    .unwrap();
    let pt = Config {
        label: "pt",
        integrator: "pt",
        mis: None,
        passes: 2048,
        seed: 401,
    };
    let light = Config {
        label: "light",
        integrator: "light",
        mis: None,
        passes: 2048,
        seed: 402,
    };
    let (pr, p) = pt.render(&scene, Some(4));
    let (_, l) = light.render(&scene, Some(4));
    let a = agreement_t(&l, &p, ALPHA);
    let bx = a.blocks_x;
    let (corner, centre) = (0, (bx / 2) * bx + bx / 2);
    let blocks = [corner, centre];
    let (z, worst, c, thr) = over_blocks(&a, &blocks, 1);
    let (le, pe) = (l.estimate(), p.estimate());
    let pixels = pr.estimate.clone();
    let cam = &scene.camera;
    for (name, i) in [("corner", corner), ("centre", centre)] {
        // The cos³ alternative: pt's pixel means times cos θ at each pixel centre, over the block.
        let (x0, y0) = ((i % bx) * BLOCK, (i / bx) * BLOCK);
        let mut alt = [0.0f64; 3];
        for y in y0..y0 + BLOCK {
            for x in x0..x0 + BLOCK {
                let d = cam
                    .generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5))
                    .d;
                let cos = d.dot(cam.forward()) as f64;
                for ch in 0..3 {
                    alt[ch] += pixels.get(x, y)[ch] * cos / (BLOCK * BLOCK) as f64;
                }
            }
        }
        let z_alt: Vec<f64> = (0..3)
            .map(|ch| {
                (pe.mean[i][ch] - alt[ch]).abs() / le.std_error[i][ch].hypot(pe.std_error[i][ch])
            })
            .collect();
        let min_z_alt = z_alt.iter().cloned().fold(f64::INFINITY, f64::min);
        println!(
            "off-axis {name} block {}: light {:.4?} ± {:.4?}, pt {:.4?} ± {:.4?}, z {:.2?}; \
             with cos³ light would be {:.4?} (ratio {:.3}), expected |z| {:.1?}",
            block_name(&a, i),
            le.mean[i],
            le.std_error[i],
            pe.mean[i],
            pe.std_error[i],
            a.z[i],
            alt,
            alt[0] / pe.mean[i][0],
            z_alt
        );
        if name == "corner" {
            assert!(
                min_z_alt > thr + 3.0,
                "corner block: a cos³ importance would give expected |z| {min_z_alt:.1}, not \
                 enough above the threshold {thr:.2} to be caught"
            );
        }
    }
    assert!(
        z < thr,
        "off-axis light vs pt: max |z| {z:.2} ≥ {thr:.2} at block {} channel {c}",
        block_name(&a, worst)
    );
}

/// Normal and bump maps (a bump-mapped floor, a normal-mapped wall and rough copper sphere, with
/// Mitsuba's flipped invalid normals and shadowing term): the perturbed normal is every vertex's
/// shading normal, so importance transport's shading-normal correction must hold on it, and the
/// flip and shadowing must be the same function of (camera side, light side) in both modes.
#[test]
fn light_and_bdpt_agree_with_pt_per_depth_on_cornell_bumped() {
    per_depth("cornell-bumped");
}

/// An environment map with a small, very bright sun (scenes/textures/sky-sun.hdr): NEE by the
/// map's luminance, BSDF hits evaluating the map, and light paths emitted from the bounding disk
/// must estimate the same image per path length.
#[test]
fn light_and_bdpt_agree_with_pt_per_depth_on_envmap_spheres() {
    per_depth("envmap-spheres");
}

/// Lights delta in position that aim (a textured spot light and a projector, no area light):
/// path tracing reaches them only by next-event estimation, light tracing only by their emitted
/// rays (uniform in the cone / on the image plane), BDPT by both; the intensity towards each
/// vertex (falloff, texture, 1/cos³) must be the same function in all of them.
#[test]
fn light_and_bdpt_agree_with_pt_per_depth_on_cornell_spot() {
    per_depth("cornell-spot");
}

/// Mitsuba's principled BSDFs from TOML: four to five lobes per material, each chosen per sample
/// with its own probability, must sum to the same pdf and the same f in both transport modes.
#[test]
fn light_and_bdpt_agree_with_pt_per_depth_on_cornell_principled() {
    per_depth("cornell-principled");
}

#[test]
fn light_and_bdpt_agree_with_pt_per_depth_on_cornell_plastic() {
    per_depth("cornell-plastic");
}

/// `cornell-plastic`: light tracing agrees with pt at every max_depth on every block that does not
/// see the smooth ball (left out by geometry: there the camera sees the coating's delta reflection,
/// which light tracing cannot join to the pinhole). The rough ball and the rough back wall are in.
/// pt's render is the one `light_and_bdpt_agree_with_pt_per_depth_on_cornell_plastic` uses.
#[test]
fn light_agrees_with_pt_off_the_smooth_ball_on_cornell_plastic() {
    let scene = shipped_scene("cornell-plastic", Some((32, 32)));
    let (centre, radius) = SMOOTH_PLASTIC_BALL;
    let ball = blocks_seeing_sphere(&scene.camera, centre, radius);
    let kept: Vec<usize> = (0..ball.len()).filter(|&i| !ball[i]).collect();
    let reference = PT.per_length("cornell-plastic", &scene, LENGTHS);
    let light = OTHERS[0].per_length("cornell-plastic", &scene, LENGTHS);
    let mut failures = Vec::new();
    for k in 1..=LENGTHS as usize {
        let a = agreement_t(&light.up_to[k - 1], &reference.up_to[k - 1], ALPHA);
        let (z, worst, c, thr) = over_blocks(&a, &kept, LENGTHS as usize);
        let line = format!(
            "cornell-plastic max_depth={k} light vs pt over {} of {} blocks: max |z| {z:.2} \
             (threshold {thr:.2}) at block {} channel {}",
            kept.len(),
            ball.len(),
            block_name(&a, worst),
            ["R", "G", "B"][c]
        );
        println!("{line}");
        if z >= thr {
            failures.push(line);
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

/// Media scenes are compared at this resolution (9 blocks of 8×8).
const MEDIA_RESOLUTION: u32 = 24;

/// Passes per media integrator (the reference `pt` first); one that joins `HANDLES_MEDIA`
/// without a row here renders `MEDIA_DEFAULT_PASSES`.
const MEDIA_PASSES: [(&str, u32); 9] = [
    ("pt", 1024),
    ("pt-bsdf", 1024),
    ("light", 512),
    ("bdpt", 256),
    // Consistent: per run, `CONSISTENT_RUNS` runs (tests/points_beams.rs holds them closer).
    ("pp3d", 32),
    ("pb2d", 32),
    ("bb1d", 32),
    // pp3d's camera walk with bb1d's photon beams, each held at 32 passes above and by
    // tests/points_beams.rs: 8 passes check its beams on every media scene for ≈ 2 CPU s.
    ("bp2d", 8),
    // Its merges query every photon of the pass: 4 passes keep it near 0.5 CPU s per scene
    // (results/points-beams.md, "upbp").
    ("upbp", 4),
];
const MEDIA_DEFAULT_PASSES: u32 = 256;

/// (scene, integrator, reason) pairs on media scenes not compared; reported, never silently.
const MEDIA_EXCLUDED: &[(&str, &str, &str)] = &[
    (
        "media/light-shafts",
        "pp3d",
        "thin fog lit through a slit: at the default 576 photon paths per pass the 3-D kernel \
         gathers about 0.01 photons per query, so a run's block estimate is heavy-tailed and \
         8 runs' t-test is no error bar (seen: |z| 10 at 8 runs, |z| 1.3 at 20,000 photons per \
         pass); results/points-beams.md",
    ),
    (
        "media/grid-smoke",
        "pp3d",
        "sparse photons in the thin parts of the grid: the same heavy-tailed runs as \
         light-shafts (|z| 5.6 at ratio 0.92 in one block); results/points-beams.md",
    ),
    (
        "media/hg-spot",
        "pt-bsdf",
        "the only light is a spot light (a delta in position): BSDF and phase sampling never hit \
     it, so pt-bsdf's image is exactly black (robustness.rs holds it so)",
    ),
];

/// (scene, integrator, sphere centre, radius, reason): compared on the blocks that do not see the
/// sphere only.
const MEDIA_OFF_SPHERE: &[(&str, &str, Vec3, f32, &str)] = &[(
    "media/glass-sphere-medium",
    "light",
    Vec3::new(0.0, -0.49, 0.0),
    0.5,
    "the camera sees the medium only through the smooth glass: E S … paths have no light \
     tracing technique (the pinhole cannot be joined through a delta surface)",
)];

fn media_passes(integrator: &str) -> u32 {
    MEDIA_PASSES
        .iter()
        .find(|(i, _)| *i == integrator)
        .map_or(MEDIA_DEFAULT_PASSES, |(_, p)| *p)
}

/// Every integrator of `HANDLES_MEDIA` against `pt` on every media scene, each at the scene's
/// max_depth, per 8×8 block, Šidák over every comparison of the test.
#[test]
fn media_integrators_agree_with_pt_on_every_media_scene() {
    let names = shipped_media_scene_names();
    let others: Vec<&'static str> = lt_integrators::INTEGRATORS
        .iter()
        .map(|i| i.name)
        .filter(|n| handles_media(n) && *n != "pt")
        .collect();
    assert!(!others.is_empty(), "no integrator but pt handles media");
    let excluded = |scene: &str, integrator: &str| {
        MEDIA_EXCLUDED
            .iter()
            .find(|(s, i, _)| *s == scene && *i == integrator)
            .map(|(_, _, why)| *why)
    };
    let comparisons = names
        .iter()
        .flat_map(|n| others.iter().map(move |o| (n, o)))
        .filter(|(n, o)| excluded(n, o).is_none())
        .count();
    let mut failures = Vec::new();
    for (k, name) in names.iter().enumerate() {
        let scene = shipped_scene(name, Some((MEDIA_RESOLUTION, MEDIA_RESOLUTION)));
        let config = |integrator: &'static str, j: u64| Config {
            label: integrator,
            integrator,
            mis: None,
            passes: media_passes(integrator),
            seed: 501 + 10 * k as u64 + j,
        };
        let (_, reference) = config("pt", 0).render(&scene, None);
        for (j, other) in others.iter().enumerate() {
            if let Some(why) = excluded(name, other) {
                println!("{name} {other}: excluded ({why})");
                continue;
            }
            let (_, blocks) = config(other, 1 + j as u64).render(&scene, None);
            let a = agreement_t(&blocks, &reference, per_comparison(comparisons));
            let off_sphere = MEDIA_OFF_SPHERE
                .iter()
                .find(|(s, i, ..)| s == name && i == other);
            let (z, worst, c, threshold, kept) = match off_sphere {
                Some((_, _, centre, radius, why)) => {
                    let seen = blocks_seeing_sphere(&scene.camera, *centre, *radius);
                    let kept: Vec<usize> = (0..seen.len()).filter(|&i| !seen[i]).collect();
                    println!(
                        "{name} {other}: {} of {} blocks left out ({why})",
                        seen.len() - kept.len(),
                        seen.len()
                    );
                    let (z, w, c, t) = over_blocks(&a, &kept, comparisons);
                    (z, w, c, t, kept.len())
                }
                None => (
                    a.max_abs_z,
                    a.worst_region,
                    a.worst_channel,
                    a.threshold,
                    a.z.len(),
                ),
            };
            let line = format!(
                "{name} {other} vs pt over {kept} blocks: max |z| {z:.2} (threshold {threshold:.2}) \
                 at block {} channel {}, mean ratio there {:.4}",
                block_name(&a, worst),
                ["R", "G", "B"][c],
                blocks.estimate().mean[worst][c] / reference.estimate().mean[worst][c],
            );
            println!("{line}");
            if !(z < threshold) {
                failures.push(line);
            }
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

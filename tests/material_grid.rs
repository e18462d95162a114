//! Every BSDF of the materials issue against Mitsuba 3 itself: `scenes/xml/material-grid.xml`
//! (twelve spheres: rough conductors isotropic and anisotropic, a smooth conductor, rough, smooth
//! and thin dielectrics, plastic, rough plastic, a bitmap-textured diffuse, a bump map, a blend
//! and a mask) rendered by lt's `pt` and `bdpt` and by Mitsuba 3.9.1 (`llvm_ad_rgb`, 16 seeds ×
//! 1024 spp, committed in results/material-grid/ with the command in its README), compared block
//! by block (8 × 8 pixels) with Welch's t per block and channel, Šidák over all of them. The
//! reference's errors are across its seeds, so its variances carry seeds − 1 degrees of freedom.
//! A planted error (the gold sphere 5 % darker) must fail the same comparison.

use lt_core::bsdf::Material;
use lt_core::Scene;
use lt_estimators::agreement::{agreement_t_with_estimate, Agreement};
use lt_estimators::blocks::BlockEstimate;
use lt_experiments::image_io::read_exr;
use lt_integrators::IntegratorParams;
use lt_scene_io::load_scene;
use lt_tests::{render_blocks, scenes_dir};

/// Family-wise false-alarm rate of each comparison.
const ALPHA: f64 = 1e-3;
const BLOCK: usize = 8;
/// Independent one-sample passes of ours: `pt`'s; `bdpt`, 3.5× dearer a pass, takes half as many.
const PASSES: u32 = 1024;
/// Independent seeds of the committed Mitsuba render, and samples per pixel in each
/// (results/material-grid/mitsuba.json).
const MITSUBA_SEEDS: f64 = 16.0;
const MITSUBA_SPP_PER_SEED: f64 = 1024.0;

fn grid() -> Scene {
    load_scene(&scenes_dir().join("xml/material-grid.xml")).unwrap_or_else(|e| panic!("{e}"))
}

fn mitsuba_blocks() -> BlockEstimate {
    let dir = scenes_dir().join("../results/material-grid");
    let mean = read_exr(&dir.join("mitsuba.exr")).unwrap();
    let se = read_exr(&dir.join("mitsuba.stderr.exr")).unwrap();
    // Mitsuba's pixels are sampled independently (box filter, independent sampler).
    let mut blocks = BlockEstimate::from_pixel_estimates(&mean, &se, BLOCK);
    // Mitsuba sums each pixel's samples in f32: a rounding error of about √n·u relative after n
    // additions (Higham's statistical estimate, u = 2⁻²⁴), which no spread across seeds shows
    // where every sample is the same (the constant sky: 0.149999887 for 0.15). It joins the
    // reference's error; elsewhere the noise dwarfs it.
    let rounding = MITSUBA_SPP_PER_SEED.sqrt() * f64::from(f32::EPSILON) / 2.0;
    for (m, e) in blocks.mean.iter().zip(blocks.std_error.iter_mut()) {
        for c in 0..3 {
            e[c] = e[c].hypot(rounding * m[c].abs());
        }
    }
    blocks
}

/// The region-channels whose |z| exceeds 3, worst first (where a disagreement sits).
fn outliers(a: &Agreement) -> String {
    let mut out: Vec<(f64, usize, usize)> =
        a.z.iter()
            .enumerate()
            .flat_map(|(i, z)| (0..3).map(move |c| (z[c], i, c)))
            .filter(|(z, _, _)| !(z.abs() <= 3.0))
            .collect();
    out.sort_by(|x, y| y.0.abs().total_cmp(&x.0.abs()));
    out.iter()
        .take(12)
        .map(|(z, i, c)| format!("({},{})[{c}] {z:+.1}", i % a.blocks_x, i / a.blocks_x))
        .collect::<Vec<_>>()
        .join(", ")
}

fn against_mitsuba(scene: &Scene, integrator: &str, passes: u32) -> Agreement {
    let (r, blocks) = render_blocks(scene, integrator, IntegratorParams::new(), passes, 1, BLOCK);
    assert_eq!(r.invalid_samples, 0, "{integrator}: invalid samples");
    agreement_t_with_estimate(&blocks, &mitsuba_blocks(), MITSUBA_SEEDS - 1.0, ALPHA)
}

#[test]
fn pt_and_bdpt_agree_with_mitsuba_on_every_material() {
    let scene = grid();
    let mut failures = Vec::new();
    for (integrator, passes) in [("pt", PASSES), ("bdpt", PASSES / 2)] {
        let a = against_mitsuba(&scene, integrator, passes);
        println!(
            "material grid, {integrator} ({passes} passes) vs Mitsuba 3: {a}; |z| > 3 at {}",
            outliers(&a)
        );
        if !a.passed() {
            failures.push(format!("{integrator}: {a}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn a_five_percent_darker_gold_sphere_is_caught() {
    let mut scene = grid();
    let gold = scene
        .materials
        .iter_mut()
        .find_map(|m| match m {
            Material::RoughConductor(r) => Some(r),
            _ => None,
        })
        .expect("the grid's first rough conductor is the gold sphere");
    gold.specular_reflectance *= 0.95;
    // A quarter of the passes: the planted error stands out by far more than the threshold.
    let a = against_mitsuba(&scene, "pt", PASSES / 4);
    println!("planted error (gold × 0.95), pt vs Mitsuba 3: {a}");
    assert!(!a.passed(), "a 5 % darker gold sphere went unnoticed: {a}");
}

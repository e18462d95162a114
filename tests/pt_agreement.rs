//! `pt` (NEE + MIS) and `pt-bsdf` (BSDF sampling only) share no light-sampling code, so their
//! agreement per 8×8 block within a Šidák-corrected z threshold checks NEE, light pdfs and MIS
//! weights against the plain estimator.

use lt_estimators::agreement::agreement_t;
use lt_integrators::IntegratorParams;
use lt_tests::{render_blocks, shipped_scene};

fn agree(scene_name: &str, passes_pt: u32, passes_bsdf: u32) {
    let scene = shipped_scene(scene_name, Some((64, 64)));
    let (r1, a) = render_blocks(&scene, "pt", IntegratorParams::default(), passes_pt, 11, 8);
    let (r2, b) = render_blocks(
        &scene,
        "pt-bsdf",
        IntegratorParams::default(),
        passes_bsdf,
        12,
        8,
    );
    assert_eq!(r1.invalid_samples + r2.invalid_samples, 0);
    let result = agreement_t(&a, &b, 1e-3);
    assert!(result.passed(), "{scene_name}: pt vs pt-bsdf: {result}");
}

#[test]
fn pt_and_pt_bsdf_agree_on_cornell_box() {
    agree("cornell-box", 128, 512);
}

/// pt-bsdf finds the smallest light (radius 0.033) from the diffuse backdrop only on rare paths
/// (a few in 10⁵), so its block means are heavy-tailed: with too few passes the sample standard
/// error misses the rare hits and z is inflated (512 passes gave |z| ≈ 11 on correct code). 8192
/// passes put tens of such hits in every block, where the normal approximation holds.
#[test]
fn pt_and_pt_bsdf_agree_on_veach_mis() {
    agree("veach-mis", 256, 8192);
}

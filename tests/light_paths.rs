//! Light subpaths per pass (`light_paths` = M) other than the pixel count N: light tracing then
//! averages its splats over M paths, and BDPT weighs light tracing by n_k / n_s = M/N (Veach's
//! sample counts). Both must still agree with `pt` per 8×8 block, with M below and above N.
//! A splat normalised by N instead of M would be off by M/N (here ×4 or ×¼: hundreds of σ); MIS
//! weights that ignored M/N would stay unbiased only by luck of the sum, which `lt mis-check
//! --light-paths` checks path by path.

use lt_estimators::agreement::agreement_t;
use lt_integrators::IntegratorParams;
use lt_tests::{render_blocks, shipped_scene};

#[test]
fn light_and_bdpt_agree_with_pt_at_other_light_path_counts() {
    let scene = shipped_scene("cornell-box", Some((32, 32)));
    let n = scene.camera.pixel_count() as u64;
    let depth = IntegratorParams::new().with("max_depth", 3);
    let (_, reference) = render_blocks(&scene, "pt", depth.clone(), 2048, 31, 8);
    for (integrator, m, passes) in [
        ("light", n / 4, 2048),
        ("light", 4 * n, 512),
        ("bdpt", n / 4, 256),
        ("bdpt", 4 * n, 128),
    ] {
        let p = depth.clone().with("light_paths", m);
        let (r, blocks) = render_blocks(&scene, integrator, p, passes, 32, 8);
        assert_eq!(r.invalid_samples, 0);
        let result = agreement_t(&blocks, &reference, 1e-3);
        println!("{integrator} M = {m} (N = {n}): {result}");
        assert!(result.passed(), "{integrator} with M = {m}: {result}");
    }
}

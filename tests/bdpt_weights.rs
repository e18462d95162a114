//! bdpt's two computations of one MIS weight, path by path: the O(1) per-vertex recursion
//! (`weights = recursive`, the default) against the O(k) density chain (`weights = chain`, the
//! oracle's arithmetic). With the same seed both take the same paths in the same order (a weight
//! draws no random number), and each path's two weights are f64 arithmetic on the same f32
//! densities: they may differ by rounding only, bounded by `rounding_bound`. On shipped scenes
//! with area, point, spot, directional and infinite lights, a plastic (delta lobe beside smooth
//! ones) and glass, and through media (free flights in the patched densities); power with
//! M = N and balance with M ≠ N light paths.

use lt_core::path::Heuristic;
use lt_core::Scene;
use lt_integrators::bdpt::{Bdpt, BdptParams, BdptWeights};
use lt_integrators::record::{Completed, Recorder};
use lt_tests::shipped_scene;

/// (s, k, raster, weight) of every path in completion order.
#[derive(Default)]
struct Weights(Vec<(usize, usize, [f32; 2], f64)>);

impl Recorder for Weights {
    const ACTIVE: bool = true;
    fn completed(&mut self, p: Completed) {
        let k = p.light.len() + p.camera.len() - 1;
        self.0.push((p.s, k, [p.raster.x, p.raster.y], p.weight));
    }
}

fn weights(scene: &Scene, h: Heuristic, light_paths: Option<u64>, w: BdptWeights) -> Weights {
    let bdpt = Bdpt {
        params: BdptParams {
            max_depth: scene.settings.max_depth,
            rr_depth: scene.settings.rr_depth,
            mis: h,
            light_paths,
            weights: w,
        },
    };
    let mut out = Weights::default();
    bdpt.record_pass(scene, 11, 0, &mut out);
    out
}

/// The largest relative difference two f64 computations of one weight of a k-segment path may
/// show. All their operands are positive (densities, their ratios, sums of powers of ratios), so
/// nothing cancels and each rounding adds at most u = 2⁻⁵³ of relative error (Higham 2002,
/// §3.1: n roundings give at most γ_n = nu / (1 − nu)). Counting roundings of the power
/// heuristic (balance has fewer):
///
/// - chain: each of the k + 2 ratios p_i / p_s is a product of ≤ k + 1 steps of a division and
///   a multiplication (next-event estimation's step four), ≤ 2k + 6; squared, 2(2k + 6) + 1;
///   the count M/N, 1; the sum of k + 2 terms, k + 1; 1 / Σ, 1: n = 5k + 16;
/// - recursion: per vertex of either side u(c/l) (division, square: 2, doubled by the square:
///   3), times the previous sum and plus the vertex's own terms (2): 5 per vertex, ≤ k + 2
///   vertices; the join's two sides (a ratio squared, a product, a sum: 5 each) and 1 / (1 + Σ)
///   (2): n = 5(k + 2) + 12.
///
/// w = 1 / (1 + Σ) moves relatively by at most Σ's relative error, so the two differ by at most
/// γ_{n_chain} + γ_{n_recursion} relatively.
fn rounding_bound(k: usize) -> f64 {
    let u = f64::EPSILON / 2.0;
    let gamma = |n: usize| n as f64 * u / (1.0 - n as f64 * u);
    gamma(5 * k + 16) + gamma(5 * (k + 2) + 12)
}

/// Holds recursive to chain on `names`; returns (paths, worst difference / bound, weights that
/// differ in any bit).
fn compare(names: &[&str], res: (u32, u32)) -> (usize, f64, usize) {
    let (mut paths, mut worst, mut differ) = (0, 0.0f64, 0);
    for name in names {
        let scene = shipped_scene(name, Some(res));
        let m = (res.0 * res.1 / 4) as u64;
        for (h, light_paths) in [(Heuristic::Power, None), (Heuristic::Balance, Some(m))] {
            let got = weights(&scene, h, light_paths, BdptWeights::Recursive);
            let want = weights(&scene, h, light_paths, BdptWeights::Chain);
            assert_eq!(
                got.0.len(),
                want.0.len(),
                "{name} {h:?}: path counts differ"
            );
            for (g, w) in got.0.iter().zip(&want.0) {
                assert_eq!((g.0, g.1, g.2), (w.0, w.1, w.2), "{name}: a different path");
                let (s, k) = (w.0, w.1);
                let diff = (g.3 - w.3).abs();
                let scale = g.3.abs().max(w.3.abs());
                let rel = if scale > 0.0 { diff / scale } else { 0.0 };
                let bound = rounding_bound(k);
                assert!(
                    rel <= bound,
                    "{name} {h:?} s {s} k {k}: recursive {} chain {} (relative {rel:.2e} > {bound:.2e})",
                    g.3,
                    w.3
                );
                worst = worst.max(rel / bound);
                differ += (g.3 != w.3) as usize;
            }
            paths += got.0.len();
        }
    }
    (paths, worst, differ)
}

#[test]
fn bdpt_recursive_weights_match_the_chain_per_path() {
    let names = [
        "cornell-box",
        "cornell-plastic",
        "cornell-spot",
        "cornell-directional",
        "cornell-env",
        "smallvcm-spheres-point",
        "veach-mis",
    ];
    let (paths, worst, differ) = compare(&names, (12, 12));
    eprintln!("surfaces: {paths} paths, {differ} weights differ, worst {worst:.3} of the bound");
    assert!(paths > 5_000, "{paths} paths");
}

#[test]
fn bdpt_recursive_weights_match_the_chain_per_path_through_media() {
    let names = [
        "media/hg-spot",
        "media/glass-sphere-medium",
        "media/grid-smoke",
    ];
    let (paths, worst, differ) = compare(&names, (16, 16));
    eprintln!("media: {paths} paths, {differ} weights differ, worst {worst:.3} of the bound");
    assert!(paths > 2_000, "{paths} paths");
}

//! Techniques s = 0, 1, 2 estimating the same pixels of the analytic plane scenes.

use super::scenes::*;
use super::walks::{camera_walk, light_walk, Made};
use lt_core::math::Vec2;
use lt_core::sampling::Sampler;
use lt_core::Scene;

/// Mean over a block of pixels of one technique's estimate f/(N p_s) on the plane scene, for
/// paths of exactly two segments (camera → plane → light). Returns (mean, standard error).
/// Nothing can occlude a plane-to-light segment there; the camera-to-plane connection of light
/// tracing is tested (from the eye, so no surface offset is involved).
fn block_estimate(scene: &Scene, s: usize, n: u64, block: (Vec2, Vec2)) -> (f64, f64) {
    let cam = &scene.camera;
    let in_block = |r: Vec2| r.cmpge(block.0).all() && r.cmplt(block.1).all();
    let block_px = ((block.1 - block.0).x * (block.1 - block.0).y) as f64;
    let mut stats = Stats::default();
    for i in 0..n {
        let mut rng = Sampler::new(77 + s as u64, i, 0);
        let mut x = 0.0;
        let mut visit = |m: Made| {
            if m.path.k() != 2 || m.s != s {
                return;
            }
            let x1 = m.path.vertices[1].p;
            if s == 2
                && !(in_block(cam.project(x1).unwrap().raster)
                    && scene.visible_between(cam.eye, x1))
            {
                return;
            }
            // Light tracing covers the whole film: N·spp light paths for spp samples per pixel,
            // so one light path stands for N/|B| camera samples of the block.
            let e = m.path.estimate(scene, s).x as f64;
            x += if s == 2 {
                e * cam.pixel_count() as f64 / block_px
            } else {
                e
            };
        };
        if s == 2 {
            light_walk(scene, &mut rng, 2, &mut visit);
        } else {
            let r = block.0 + rng.next_2d() * (block.1 - block.0);
            camera_walk(scene, &mut rng, Some(r), 2, &mut visit);
        }
        stats.add(x);
    }
    (stats.mean(), stats.se())
}

/// The exact block mean: ρ/π · E(x) averaged over the block's raster area by a 16×16 midpoint
/// rule per pixel (smooth integrand: error far below the standard errors).
fn block_exact(scene: &Scene, light: PlaneLight, block: (Vec2, Vec2)) -> f64 {
    let (mut sum, mut n) = (0.0, 0);
    let q = 16;
    let size = (block.1 - block.0) * q as f32;
    for j in 0..size.y as usize {
        for i in 0..size.x as usize {
            let r = block.0 + (Vec2::new(i as f32, j as f32) + 0.5) / q as f32;
            let hit = scene
                .intersect(&scene.camera.generate_ray(r))
                .expect("the block sees the plane");
            assert!(hit.ng.y > 0.99);
            sum += PLANE_ALBEDO as f64 / std::f64::consts::PI * plane_irradiance(light, hit.p);
            n += 1;
        }
    }
    sum / n as f64
}

/// s = 0, 1, 2 estimate the same pixels, pairwise and against the exact value.
pub fn techniques_agree(light: PlaneLight, n: [u64; 3]) {
    let scene = plane(light);
    let block = (Vec2::new(12.0, 8.0), Vec2::new(20.0, 16.0));
    let exact = block_exact(&scene, light, block);
    let est: Vec<(usize, (f64, f64))> = (0..3)
        .filter(|&s| n[s] > 0)
        .map(|s| (s, block_estimate(&scene, s, n[s], block)))
        .collect();
    let mut report = format!("{light:?}: exact {exact:.6}");
    for &(s, e) in &est {
        let za = z(e, (exact, 0.0));
        report += &format!(", s={s} {:.6}±{:.6} (z {za:+.2})", e.0, e.1);
        assert!(
            e.1 < 0.05 * exact,
            "s={s}: standard error too large to test anything"
        );
        assert!(za.abs() < 4.0, "{report}");
    }
    for a in 0..est.len() {
        for b in a + 1..est.len() {
            let zab = z(est[a].1, est[b].1);
            report += &format!(", z(s{}−s{}) {zab:+.2}", est[a].0, est[b].0);
            assert!(zab.abs() < 4.0, "{report}");
        }
    }
    println!("{report}");
}

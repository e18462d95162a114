//! One pass of a pixel-based estimator: every pixel gets one camera sample from its own stream.

use lt_core::math::is_valid_color;
use lt_core::sampling::{Domain, Sampler};
use lt_core::{Color, Scene, Vec2};
use lt_estimators::Image;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// Runs `estimate(sampler, raster)` once per pixel with a box-filtered raster position and the
/// pixel's (seed, pixel, pass) stream. Invalid estimates are replaced by zero and counted.
pub fn pixel_pass(
    scene: &Scene,
    seed: u64,
    pass: u32,
    estimate: impl Fn(&mut Sampler, Vec2) -> Color + Sync,
) -> (Image, u64) {
    let w = scene.camera.width as usize;
    let h = scene.camera.height as usize;
    let mut img = Image::new(w, h);
    let invalid = AtomicU64::new(0);
    img.data.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        let mut bad = 0;
        for (x, px) in row.iter_mut().enumerate() {
            let mut s = Sampler::for_item(Domain::Camera, seed, (y * w + x) as u64, pass as u64);
            let raster = Vec2::new(x as f32 + s.next_f32(), y as f32 + s.next_f32());
            let c = estimate(&mut s, raster);
            if is_valid_color(c) {
                *px = [c.x as f64, c.y as f64, c.z as f64];
            } else {
                bad += 1;
            }
        }
        if bad > 0 {
            invalid.fetch_add(bad, Ordering::Relaxed);
        }
    });
    (img, invalid.into_inner())
}

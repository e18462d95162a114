//! One pass of a pixel-based estimator: every pixel gets one camera sample from its own stream,
//! placed and weighted by the film's pixel filter (`lt_core::camera::filter`).

use lt_core::camera::FilmSample;
use lt_core::math::is_valid_color;
use lt_core::sampling::{Domain, Sampler};
use lt_core::{Color, Scene, Vec2};
use lt_estimators::Image;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// The camera sample of pixel `pixel` (row-major) from its stream: the first two numbers place it
/// (filter importance sampling; the box of one pixel is `x + u`), and the estimate it feeds must
/// be multiplied by `weight`. `None` when the filter's offset left the film: the sample then
/// estimates zero.
#[inline]
pub fn pixel_sample(scene: &Scene, pixel: u64, sampler: &mut Sampler) -> Option<FilmSample> {
    let cam = &scene.camera;
    let w = cam.width as u64;
    let u = sampler.next_f32();
    let v = sampler.next_f32();
    cam.sample_pixel((pixel % w) as u32, (pixel / w) as u32, Vec2::new(u, v))
}

/// Runs `estimate(sampler, raster)` once per pixel at a filtered raster position, with the
/// pixel's (seed, pixel, pass) stream, and weighs it by the filter. Invalid estimates are
/// replaced by zero and counted.
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
            let pixel = (y * w + x) as u64;
            let mut s = Sampler::for_item(Domain::Camera, seed, pixel, pass as u64);
            let Some(film) = pixel_sample(scene, pixel, &mut s) else {
                continue;
            };
            let c = weighted(estimate(&mut s, film.raster), film.weight);
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

/// `c` times a filter weight; the box's weight 1 leaves the bits alone.
#[inline]
pub fn weighted(c: Color, weight: f32) -> Color {
    if weight == 1.0 {
        c
    } else {
        c * weight
    }
}

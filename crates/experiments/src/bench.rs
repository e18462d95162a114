//! Throughput measurements shared by the criterion bench and `lt bench`: raw BVH traversal on
//! incoherent rays, and integrator samples per second.

use lt_core::geometry::Ray;
use lt_core::sampling::{sample_uniform_sphere, Sampler};
use lt_core::{Scene, Vec3};
use lt_integrators::{make_integrator, Estimator, IntegratorParams};
use std::time::Instant;

/// Incoherent rays: origins uniform in the scene's bounding box, directions uniform on the sphere.
pub fn incoherent_rays(scene: &Scene, count: usize, seed: u64) -> Vec<Ray> {
    let (c, r) = scene.bounding_sphere;
    let half = Vec3::splat(r / 3f32.sqrt());
    let mut s = Sampler::new(seed, 0, 0);
    (0..count)
        .map(|_| {
            let u = Vec3::new(s.next_f32(), s.next_f32(), s.next_f32());
            let o = c + (2.0 * u - Vec3::ONE) * half;
            Ray::new(o, sample_uniform_sphere(s.next_2d()))
        })
        .collect()
}

/// Coherent rays: the camera's primary rays through the pixel centres, row by row, repeated to
/// `count`.
pub fn camera_rays(scene: &Scene, count: usize) -> Vec<Ray> {
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    (0..count)
        .map(|i| {
            let px = i % (w * h);
            let raster = lt_core::math::Vec2::new((px % w) as f32 + 0.5, (px / w) as f32 + 0.5);
            scene.camera.generate_ray(raster)
        })
        .collect()
}

/// Rays leaving surfaces, as a path's bounces do: from the hit of each of `rays` that hits, in a
/// uniformly random direction on the side the ray arrived from, offset by the hit's rounding bound
/// (`SurfaceHit::spawn_ray`) — most end a short way off, near where they start.
pub fn surface_rays(scene: &Scene, rays: &[Ray], seed: u64) -> Vec<Ray> {
    let mut s = Sampler::new(seed, 1, 0);
    rays.iter()
        .filter_map(|r| {
            let h = scene.intersect(r)?;
            let mut d = sample_uniform_sphere(s.next_2d());
            if d.dot(h.ng) * r.d.dot(h.ng) > 0.0 {
                d = -d;
            }
            Some(h.spawn_ray(d))
        })
        .collect()
}

/// Closest-hit rays per second on one thread, and the fraction that hit: the ray core's own
/// query (traversal and primitive tests, no hit record), so ray cores are compared on what they do.
pub fn closest_hit_rate(scene: &Scene, rays: &[Ray], repeats: usize) -> (f64, f64) {
    let mut hits = 0usize;
    let accel = scene.accel();
    let start = Instant::now();
    for _ in 0..repeats {
        for r in rays {
            hits += accel.intersect(r).is_some() as usize;
        }
    }
    let secs = start.elapsed().as_secs_f64();
    let n = (rays.len() * repeats) as f64;
    (n / secs, hits as f64 / n)
}

/// Shadow (any-hit) rays per second on one thread: each ray as a segment of length 1, asked of
/// the ray core directly.
pub fn shadow_rate(scene: &Scene, rays: &[Ray], repeats: usize) -> f64 {
    let mut blocked = 0usize;
    let accel = scene.accel();
    let segments: Vec<Ray> = rays.iter().map(|r| Ray { t_max: 1.0, ..*r }).collect();
    let start = Instant::now();
    for _ in 0..repeats {
        for r in &segments {
            blocked += accel.occluded(r) as usize;
        }
    }
    std::hint::black_box(blocked);
    (rays.len() * repeats) as f64 / start.elapsed().as_secs_f64()
}

/// Throughput of an integrator at the scene's resolution.
#[derive(Clone, Copy, Debug)]
pub struct IntegratorRate {
    pub spp_per_second: f64,
    pub samples_per_second: f64,
    /// Closest-hit plus shadow rays per second, all threads together.
    pub rays_per_second: f64,
    pub closest_per_sample: f64,
    pub shadow_per_sample: f64,
}

/// Runs `passes` passes of `integrator` on `threads` threads and counts the rays they trace.
pub fn integrator_rate(
    scene: &Scene,
    integrator: &str,
    max_depth: Option<u32>,
    passes: u32,
    threads: usize,
) -> Result<IntegratorRate, String> {
    let integ = make_integrator(
        integrator,
        scene,
        &match max_depth {
            Some(d) => IntegratorParams::new().with("max_depth", d),
            None => IntegratorParams::new(),
        },
    )?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| e.to_string())?;
    pool.broadcast(|_| lt_core::scene::ray_stats::take());
    let start = Instant::now();
    match &integ {
        Estimator::Unbiased(i) => {
            for pass in 0..passes {
                std::hint::black_box(pool.install(|| i.render_pass(scene, 1, pass)));
            }
        }
        // A progressive run's first pass includes its set-up (a photon map, visible points).
        Estimator::Consistent(p) => {
            let mut run = pool.install(|| p.start(scene, 1));
            run.plan(passes);
            for pass in 0..passes {
                std::hint::black_box(pool.install(|| run.pass(pass)));
            }
            std::hint::black_box(pool.install(|| run.estimate()));
        }
    }
    let secs = start.elapsed().as_secs_f64();
    let counts = pool.broadcast(|_| lt_core::scene::ray_stats::take());
    let (closest, shadow) = counts
        .iter()
        .fold((0u64, 0u64), |a, c| (a.0 + c.0, a.1 + c.1));
    let samples = passes as f64 * scene.camera.pixel_count() as f64;
    Ok(IntegratorRate {
        spp_per_second: passes as f64 / secs,
        samples_per_second: samples / secs,
        rays_per_second: (closest + shadow) as f64 / secs,
        closest_per_sample: closest as f64 / samples,
        shadow_per_sample: shadow as f64 / samples,
    })
}

/// Peak resident memory of this process in MiB (Linux), if known.
pub fn peak_memory_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}

//! Deterministic splatting for estimators that scatter to arbitrary pixels (light tracing, BDPT's
//! t = 1 strategy), each splat spread over the pixels its filter reaches. Work is cut into fixed chunks independent of the thread count; each chunk
//! records its splats in order and the chunks are applied in chunk order, so the floating-point sum
//! in every pixel is the same however many threads ran.

use lt_core::camera::FilmFilter;
use lt_core::math::is_valid_color;
use lt_core::{Color, Vec2};
use lt_estimators::Image;
use rayon::prelude::*;

/// Splats recorded by one chunk of work.
#[derive(Default)]
pub struct Splats {
    entries: Vec<(u32, Color)>,
    invalid: u64,
    width: u32,
    height: u32,
}

impl Splats {
    /// An empty record for a film of `width` × `height` pixels.
    pub fn new(width: u32, height: u32) -> Splats {
        Splats {
            entries: Vec::new(),
            invalid: 0,
            width,
            height,
        }
    }

    /// The splats recorded so far, in order, as (pixel, value).
    pub fn entries(&self) -> &[(u32, Color)] {
        &self.entries
    }

    /// Invalid values dropped so far.
    pub fn invalid(&self) -> u64 {
        self.invalid
    }

    /// Forgets every splat and the invalid count (a buffer reused per sample: Metropolis).
    pub fn clear(&mut self) {
        self.entries.clear();
        self.invalid = 0;
    }

    /// Adds `value` to pixel `index` (row-major); invalid values are dropped and counted.
    pub fn add_to_pixel(&mut self, index: u32, value: Color) {
        if !is_valid_color(value) {
            self.invalid += 1;
            return;
        }
        if value != Color::ZERO {
            self.entries.push((index, value));
        }
    }

    /// Adds `value` at raster point `raster` through the film's pixel filter: to every pixel whose
    /// support covers it, weighted f(raster − c_j) / Z_j (`lt_core::camera::filter`), in a fixed
    /// pixel order. The box of one pixel is `add`.
    pub fn add_filtered(&mut self, film: &FilmFilter, raster: Vec2, value: Color) {
        if film.filter.is_pixel_box() {
            return self.add(raster, value);
        }
        if !is_valid_color(value) {
            self.invalid += 1;
            return;
        }
        film.for_each_splat(raster, |i, w| self.entries.push((i, value * w)));
    }

    /// Adds `value` to the pixel containing `raster`; invalid values are dropped and counted.
    pub fn add(&mut self, raster: Vec2, value: Color) {
        if !is_valid_color(value) {
            self.invalid += 1;
            return;
        }
        let i = pixel_of(raster, self.width, self.height) as u32;
        self.entries.push((i, value));
    }
}

/// The pixel (row-major) holding raster point `raster`, clamped to the film (a negative or NaN
/// coordinate to 0, as `as u32` does).
pub fn pixel_of(raster: Vec2, width: u32, height: u32) -> usize {
    let x = (raster.x as u32).min(width - 1);
    let y = (raster.y as u32).min(height - 1);
    (y * width + x) as usize
}

/// Runs `work(item, splats, state)` for items 0..count in chunks of `chunk` and returns the summed
/// image (each splat added once) with the count of invalid splats. Each chunk gets its own scratch
/// state from `init` (buffers reused across the chunk's items).
pub fn splat_pass_with<S>(
    width: usize,
    height: usize,
    count: u64,
    chunk: u64,
    init: impl Fn() -> S + Sync,
    work: impl Fn(u64, &mut Splats, &mut S) + Sync,
) -> (Image, u64) {
    let chunks = count.div_ceil(chunk.max(1));
    let recorded: Vec<Splats> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let mut s = Splats::new(width as u32, height as u32);
            let mut state = init();
            for item in c * chunk..((c + 1) * chunk).min(count) {
                work(item, &mut s, &mut state);
            }
            s
        })
        .collect();
    let mut img = Image::new(width, height);
    let mut invalid = 0;
    for s in recorded {
        invalid += s.invalid;
        for (i, v) in s.entries {
            let px = &mut img.data[i as usize];
            px[0] += v.x as f64;
            px[1] += v.y as f64;
            px[2] += v.z as f64;
        }
    }
    (img, invalid)
}

#[cfg(test)]
mod tests {
    use super::*;
    use lt_core::sampling::Sampler;

    fn run(threads: usize) -> Image {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            splat_pass_with(
                16,
                8,
                10_000,
                64,
                || (),
                |i, sp, _| {
                    let mut s = Sampler::new(3, i, 0);
                    for _ in 0..3 {
                        let r = Vec2::new(s.next_f32() * 16.0, s.next_f32() * 8.0);
                        sp.add(r, Color::splat(s.next_f32() + 1e-6));
                    }
                },
            )
            .0
        })
    }

    #[test]
    fn splatting_is_identical_for_any_thread_count() {
        let a = run(1);
        let b = run(2);
        let c = run(4);
        assert!(a
            .data
            .iter()
            .zip(&b.data)
            .all(|(x, y)| x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits())));
        assert_eq!(b, c);
        assert!(a.data.iter().all(|p| p[0] > 0.0));
    }
}

/// Which pass of which seed: every random stream of a work item is keyed by these two.
#[derive(Clone, Copy, Debug)]
pub struct Pass {
    pub seed: u64,
    pub pass: u32,
}

/// One worker's mutable state in a splatting pass: the splat buffer it writes, its scratch
/// buffers `S`, and the recorder `R` that hears of every completed path (`NoRecord` when
/// rendering).
pub struct Worker<'a, S, R> {
    pub splats: &'a mut Splats,
    pub scratch: &'a mut S,
    pub rec: &'a mut R,
}

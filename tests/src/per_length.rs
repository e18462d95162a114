//! Every path length's image from one render: `pt`, `light` and `bdpt` at max_depth L give, per
//! pass, the image of the paths of exactly k segments for every k ≤ L (their sum is the pass
//! image), and so the image of every max_depth d ≤ L (the sum of lengths ≤ d). Each pass's images
//! are independent of the other passes', so their per-block spread is their standard error, as
//! for any pass image; rendering each max_depth separately (what the agreement tests did before)
//! costs 1 + 2 + … + L lengths' work instead of L's.
//!
//! How each integrator is split, with its own code:
//! - `pt`: `Pt::radiance_recorded` reports every weighted contribution it adds (`Recorder`), with
//!   its vertices, so k = light + camera vertices − 1.
//! - `bdpt`: `Bdpt::item`, the work item of its pass, with a recorder that places each weighted
//!   contribution as bdpt does (a camera sample's on its pixel times the filter weight, a light
//!   splat through the filter); Veach's pyramid (`lt render --strategies`) does not filter.
//! - `light`: the light tracer has no recorder, so its 20-line pass is repeated here splatting the
//!   vertex y_{s−1} (a path of s segments) into length s's image as well as into the whole image.
//!
//! The first pass of every split is held to the integrator's own `render_pass`: the whole image
//! bit for bit, and the lengths' images summing to it within f32 rounding — so the split can
//! neither drift from the integrator nor drop a contribution.

use lt_core::camera::FilmFilter;
use lt_core::math::is_valid_color;
use lt_core::path::scatter::connectable;
use lt_core::path::PathVertex;
use lt_core::sampling::{Domain, Sampler};
use lt_core::{Color, Scene, Vec2};
use lt_estimators::blocks::RunningBlocks;
use lt_estimators::Image;
use lt_experiments::verify::strategies::make_bdpt;
use lt_integrators::bdpt::Bdpt;
use lt_integrators::connect::connect_to_camera;
use lt_integrators::params::ParamReader;
use lt_integrators::pixel::{pixel_sample, weighted};
use lt_integrators::pt::{Pt, PtParams};
use lt_integrators::record::{Completed, Recorder};
use lt_integrators::splat::{splat_pass_with, Pass, Worker};
use lt_integrators::subpath::walk::{light_subpath, Subpath, WalkLimits};
use lt_integrators::unidirectional::light::{LightParams, LightTracer};
use lt_integrators::{make_integrator, IntegratorParams};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// An integrator whose passes can be split by path length.
enum Split {
    Pt(Pt),
    Light(LightTracer),
    Bdpt(Bdpt),
}

/// One pass: the whole image, and per length k (index k − 1) the image of paths of k segments.
pub struct LengthPass {
    pub whole: Image,
    pub lengths: Vec<Image>,
    pub invalid: u64,
}

/// A render's block statistics per path length, over its passes: `exact[k − 1]` of the image of
/// paths of exactly k segments, `up_to[d − 1]` of paths of at most d segments (what a render at
/// max_depth d estimates; each pass's is the sum of its lengths ≤ d).
pub struct PerLength {
    pub exact: Vec<RunningBlocks>,
    pub up_to: Vec<RunningBlocks>,
    pub invalid_samples: u64,
}

impl Split {
    fn make(integrator: &str, scene: &Scene, params: &IntegratorParams) -> Split {
        let read = |name| ParamReader::new(name, params);
        let split = match integrator {
            "pt" => {
                let r = read("pt");
                let s = Split::Pt(Pt {
                    params: PtParams::read(scene, &r).unwrap(),
                });
                r.finish().unwrap();
                s
            }
            "light" => {
                let r = read("light");
                let s = Split::Light(LightTracer {
                    params: LightParams::read(scene, &r).unwrap(),
                });
                r.finish().unwrap();
                s
            }
            "bdpt" => Split::Bdpt(make_bdpt(scene, params).unwrap()),
            other => panic!("no per-length split of {other} (pt, light, bdpt have one)"),
        };
        split
    }

    fn max_depth(&self) -> usize {
        match self {
            Split::Pt(p) => p.params.max_depth as usize,
            Split::Light(l) => l.params.max_depth as usize,
            Split::Bdpt(b) => b.params.max_depth as usize,
        }
    }

    fn pass(&self, scene: &Scene, seed: u64, pass: u32) -> LengthPass {
        match self {
            Split::Pt(p) => pt_pass(p, scene, seed, pass),
            Split::Light(l) => light_pass(l, scene, seed, pass),
            Split::Bdpt(b) => bdpt_pass(b, scene, seed, pass),
        }
    }
}

/// Renders `passes` passes of `integrator` (`pt`, `light` or `bdpt`) with `params` (its
/// max_depth L is the longest length) under seeds as `lt_integrators::render` uses them, and
/// returns each length's per-block statistics. Panics if the first pass's split does not match
/// the integrator's own pass image.
pub fn render_per_length(
    scene: &Scene,
    integrator: &str,
    params: &IntegratorParams,
    passes: u32,
    seed: u64,
    block: usize,
) -> PerLength {
    let split = Split::make(integrator, scene, params);
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let mut exact = vec![RunningBlocks::new(w, h, block); split.max_depth()];
    let mut up_to = exact.clone();
    let mut invalid = 0;
    for pass in 0..passes {
        let p = split.pass(scene, seed, pass);
        if pass == 0 {
            hold_to_integrator(&p, integrator, scene, params, seed);
        }
        let mut sum = Image::new(w, h);
        for (k, img) in p.lengths.iter().enumerate() {
            exact[k].add(img);
            for (s, v) in sum.data.iter_mut().zip(&img.data) {
                for c in 0..3 {
                    s[c] += v[c];
                }
            }
            up_to[k].add(&sum);
        }
        invalid += p.invalid;
    }
    PerLength {
        exact,
        up_to,
        invalid_samples: invalid,
    }
}

/// The split's whole image is the integrator's pass 0 bit for bit, and its lengths sum to it
/// within the rounding of the integrator's f32 sums: each pixel adds at most 2 contributions per
/// length (pt: a hit and a next-event estimate), each a product of a few f32 factors, so the
/// relative error is below (4 · 2L + 2L) ε_f32 of the sum of magnitudes.
fn hold_to_integrator(
    p: &LengthPass,
    integrator: &str,
    scene: &Scene,
    params: &IntegratorParams,
    seed: u64,
) {
    let est = make_integrator(integrator, scene, params).unwrap();
    let (own, own_invalid) = est.unbiased().unwrap().render_pass(scene, seed, 0);
    assert_eq!(
        own_invalid, p.invalid,
        "{integrator}: invalid samples differ"
    );
    let same_bits = own
        .data
        .iter()
        .zip(&p.whole.data)
        .all(|(a, b)| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()));
    assert!(
        same_bits,
        "{integrator}: the per-length split's pass image is not the integrator's"
    );
    let terms = 2.0 * p.lengths.len() as f64;
    let bound = (4.0 * terms + terms) * f32::EPSILON as f64;
    for (i, whole) in p.whole.data.iter().enumerate() {
        for (c, &image) in whole.iter().enumerate() {
            let sum: f64 = p.lengths.iter().map(|l| l.data[i][c]).sum();
            let size: f64 = p.lengths.iter().map(|l| l.data[i][c].abs()).sum();
            assert!(
                (sum - image).abs() <= bound * size.max(image.abs()),
                "{integrator}: pixel {i} channel {c}: lengths sum to {sum}, the image has {image}"
            );
        }
    }
}

/// Σ weight · value of a sample's completed paths, per length.
struct LengthSums {
    sums: Vec<[f64; 3]>,
}

impl Recorder for LengthSums {
    const ACTIVE: bool = true;

    fn completed(&mut self, p: Completed) {
        let k = p.light.len() + p.camera.len() - 1;
        let v = p.value * p.weight as f32;
        let s = &mut self.sums[k - 1];
        for (c, x) in s.iter_mut().zip([v.x, v.y, v.z]) {
            *c += x as f64;
        }
    }
}

/// One image row of a pt pass: the whole row, each length's row, invalid samples.
type PtRow = (Vec<[f64; 3]>, Vec<Vec<[f64; 3]>>, u64);

/// `pixel_pass` with `Pt::radiance_recorded`: the same streams, positions and filter weights.
fn pt_pass(pt: &Pt, scene: &Scene, seed: u64, pass: u32) -> LengthPass {
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let lengths = pt.params.max_depth as usize;
    let rows: Vec<PtRow> = (0..h)
        .into_par_iter()
        .map(|y| {
            let mut whole = vec![[0.0; 3]; w];
            let mut per = vec![vec![[0.0; 3]; w]; lengths];
            let mut bad = 0;
            for x in 0..w {
                let pixel = (y * w + x) as u64;
                let mut s = Sampler::for_item(Domain::Camera, seed, pixel, pass as u64);
                let Some(film) = pixel_sample(scene, pixel, &mut s) else {
                    continue;
                };
                let mut rec = LengthSums {
                    sums: vec![[0.0; 3]; lengths],
                };
                let c = weighted(
                    pt.radiance_recorded(scene, film.raster, &mut s, &mut rec),
                    film.weight,
                );
                if !is_valid_color(c) {
                    bad += 1;
                    continue;
                }
                whole[x] = [c.x as f64, c.y as f64, c.z as f64];
                for (k, sum) in rec.sums.iter().enumerate() {
                    per[k][x] = sum.map(|v| v * film.weight as f64);
                }
            }
            (whole, per, bad)
        })
        .collect();
    let mut out = LengthPass {
        whole: Image::new(w, h),
        lengths: vec![Image::new(w, h); lengths],
        invalid: 0,
    };
    for (y, (whole, per, bad)) in rows.into_iter().enumerate() {
        out.whole.data[y * w..(y + 1) * w].copy_from_slice(&whole);
        for (img, row) in out.lengths.iter_mut().zip(per) {
            img.data[y * w..(y + 1) * w].copy_from_slice(&row);
        }
        out.invalid += bad;
    }
    out
}

/// `LightTracer::render_pass`, splatting into a film of L + 1 layers: layer 0 the whole image
/// (every splat, in the tracer's order, so its bits are the tracer's), layer s the splats of
/// vertex y_{s−1}, paths of s segments.
fn light_pass(light: &LightTracer, scene: &Scene, seed: u64, pass: u32) -> LengthPass {
    let cam = &scene.camera;
    let m = light.params.light_paths.unwrap_or(cam.pixel_count() as u64);
    let limits = WalkLimits {
        max_vertices: light.params.max_depth as usize,
        rr_depth: light.params.rr_depth,
    };
    let scale = 1.0 / m as f32;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let layer = (w * h) as u32;
    let layers = limits.max_vertices + 1;
    let scratch = || Subpath::with_capacity(limits.max_vertices);
    // Counted as `Splats::add_filtered` counts them: one per invalid splat, which adds nothing.
    let invalid = AtomicU64::new(0);
    let (film, _) = splat_pass_with(w, h * layers, m, 1024, scratch, |i, splats, sub| {
        let mut sampler = Sampler::for_item(Domain::Light, seed, i, pass as u64);
        light_subpath(scene, &mut sampler, limits, sub);
        for (s, y) in (1..).zip(&sub.vertices) {
            let Some((raster, value)) = camera_splat(scene, y, &mut sampler) else {
                continue;
            };
            let value = value * scale;
            if !is_valid_color(value) {
                invalid.fetch_add(1, Ordering::Relaxed);
                continue;
            }
            cam.film().for_each_splat(raster, |j, f| {
                splats.add_to_pixel(j, value * f);
                splats.add_to_pixel(s * layer + j, value * f);
            });
        }
    });
    let mut images = film.data.chunks(w * h).map(|d| Image {
        width: w,
        height: h,
        data: d.to_vec(),
    });
    let whole = images.next().unwrap();
    LengthPass {
        whole,
        lengths: images.collect(),
        invalid: invalid.into_inner(),
    }
}

/// Light vertex `y` joined to the lens, as the light tracer does it: (raster, value).
fn camera_splat(scene: &Scene, y: &PathVertex, sampler: &mut Sampler) -> Option<(Vec2, Color)> {
    if !connectable(scene, y) {
        return None;
    }
    connect_to_camera(scene, y, sampler).map(|c| (c.raster, c.value))
}

/// What one chunk of bdpt's work items completed: (item, layer-stacked pixel, weighted value).
type Entries = Vec<(u64, u32, Color)>;

/// Sorts bdpt's weighted contributions by length, placed as bdpt places them: a camera sample's
/// (t ≥ 2) on its pixel times the filter weight, a light-tracing splat (t = 1) through the filter.
struct LengthEntries<'a> {
    film: &'a FilmFilter,
    layer: u32,
    item: u64,
    pixel: u32,
    film_weight: f32,
    entries: Entries,
    sink: &'a Mutex<Vec<Entries>>,
}

impl Recorder for LengthEntries<'_> {
    const ACTIVE: bool = true;

    fn completed(&mut self, p: Completed) {
        let k = p.light.len() + p.camera.len() - 1;
        let offset = k as u32 * self.layer;
        let v = p.value * p.weight as f32;
        if p.s == k {
            let (item, entries) = (self.item, &mut self.entries);
            self.film
                .for_each_splat(p.raster, |j, f| entries.push((item, offset + j, v * f)));
        } else {
            let v = v * self.film_weight;
            self.entries.push((self.item, offset + self.pixel, v));
        }
    }

    fn begin_item(&mut self, item: u64) {
        self.item = item;
    }

    fn begin_sample(&mut self, pixel: u64, film_weight: f32) {
        (self.pixel, self.film_weight) = (pixel as u32, film_weight);
    }
}

impl Drop for LengthEntries<'_> {
    fn drop(&mut self) {
        let entries = std::mem::take(&mut self.entries);
        self.sink
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(entries);
    }
}

/// bdpt's pass (`Bdpt::item` over its work items, chunks of 256 as `render_pass` cuts them), its
/// contributions sorted into lengths by a recorder; summed in item order, so the lengths' images
/// too are the same at any thread count.
fn bdpt_pass(bdpt: &Bdpt, scene: &Scene, seed: u64, pass: u32) -> LengthPass {
    let cam = &scene.camera;
    let lengths = bdpt.params.max_depth as usize;
    let n = cam.pixel_count() as u64;
    let items = n.max(bdpt.params.light_paths.unwrap_or(n));
    let (w, h) = (cam.width as usize, cam.height as usize);
    let sink = Mutex::new(Vec::new());
    let init = || {
        let rec = LengthEntries {
            film: cam.film(),
            layer: (w * h) as u32,
            item: 0,
            pixel: 0,
            film_weight: 1.0,
            entries: Vec::new(),
            sink: &sink,
        };
        (bdpt.scratch(), rec)
    };
    let (whole, invalid) = splat_pass_with(w, h, items, 256, init, |i, splats, (scratch, rec)| {
        let mut worker = Worker {
            splats,
            scratch,
            rec,
        };
        bdpt.item(scene, Pass { seed, pass }, i, &mut worker);
    });
    let mut entries: Vec<_> = sink.into_inner().unwrap().into_iter().flatten().collect();
    entries.sort_by_key(|e| e.0);
    let mut film = Image::new(w, h * (lengths + 1));
    for (_, j, v) in entries {
        let px = &mut film.data[j as usize];
        for (c, x) in px.iter_mut().zip([v.x, v.y, v.z]) {
            *c += x as f64;
        }
    }
    LengthPass {
        whole,
        lengths: film
            .data
            .chunks(w * h)
            .skip(1)
            .map(|d| Image {
                width: w,
                height: h,
                data: d.to_vec(),
            })
            .collect(),
        invalid,
    }
}

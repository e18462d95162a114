//! One bdpt strategy (s, t) on its own, as MMLT evaluates a chain's state (Hachisuka, Kaplanyan &
//! Dachsbacher 2014, §4): a camera subpath of exactly t vertices and a light subpath of exactly s
//! vertices, walked by the shared subpath tracer (`subpath::walk`) with its vertex limit, one
//! connection, and bdpt's MIS weight of that (s, t) (`strategy_weight::mis_weight`, the code bdpt
//! and the MIS oracle share), so a state costs s + t vertices and one join, not a bdpt sample.
//!
//! Streams, as pbrt-v4's `MLTSampler` has them: the camera walk reads `Domain::Camera` (film
//! position, lens, bounces), the light walk `Domain::Light` (emission, bounces), the connection
//! `Domain::Aux` (next-event estimation's light sample, light tracing's lens point), each from its
//! first number. A small step thus moves the camera and the light ends alike, and a walk stopped
//! after n vertices reads a prefix of what the full walk reads and makes the same n vertices: the
//! only entries it leaves unset are the last vertex's sampled lobe and its predecessor's reverse
//! density, which every join replaces (`with_chain_in`'s patched entries; the end vertices are
//! judged by their material). So strategy (s, t) has the same value on u whether the walks stop at
//! s and t vertices (`one_strategy`, a chain's state) or run to `max_depth` (`every_strategy`, the
//! bootstrap, which reads every (s, t) from one pair of walks, each join rewound to the first
//! connection number) — bit for bit.

use crate::film::pixel::{pixel_sample, weighted};
use crate::film::splat::Splats;
use crate::subpath::connect::{connect_to_camera, join, nee_density, next_event};
use crate::subpath::strategy_weight::{mis_weight, EndEvals, Split};
use crate::subpath::walk::{camera_subpath, light_subpath, Subpath, WalkLimits};
use lt_core::camera::FilmSample;
use lt_core::path::scatter::connectable;
use lt_core::path::{Heuristic, PathVertex};
use lt_core::primary_space::rewind_installed;
use lt_core::sampling::{Domain, Sampler};
use lt_core::{Color, Scene};

/// The connection's stream, rewound for each strategy the bootstrap evaluates.
const CONNECTION: Domain = Domain::Aux;

/// bdpt's settings a strategy needs: Russian roulette's start and the heuristic.
#[derive(Clone, Copy, Debug)]
pub struct Rules {
    pub rr_depth: u32,
    pub mis: Heuristic,
}

/// bdpt's light subpaths per camera sample, M/N: one, as MMLT's bdpt has it (its `light_paths`
/// is unset), so light tracing's weight carries no extra count.
const LIGHT_TRACING_RATIO: f64 = 1.0;

/// Per-thread walks of one primary-sample point.
pub struct Walks {
    camera: Subpath,
    light: Subpath,
    /// The pixel the camera walk samples, and its film sample (`None`: no camera walk).
    pixel: u32,
    film: Option<FilmSample>,
    /// A camera walk and the light endpoint it reached (s = 0), as one path.
    reached: Vec<PathVertex>,
}

impl Walks {
    pub fn new(max_depth: u32) -> Walks {
        let d = max_depth as usize;
        Walks {
            camera: Subpath::with_capacity(d + 1),
            light: Subpath::with_capacity(d),
            pixel: 0,
            film: None,
            reached: Vec::with_capacity(d + 2),
        }
    }

    /// The camera subpath through `pixel`, at most `vertices` vertices (z0 included).
    fn walk_camera(&mut self, scene: &Scene, pixel: u64, vertices: usize, rr_depth: u32) {
        let mut cs = Sampler::for_item(Domain::Camera, 0, pixel, 0);
        self.pixel = pixel as u32;
        self.film = pixel_sample(scene, pixel, &mut cs);
        self.camera.vertices.clear();
        self.camera.escape = None;
        if let Some(film) = self.film {
            let limits = WalkLimits {
                max_vertices: vertices,
                rr_depth,
            };
            camera_subpath(scene, film.raster, &mut cs, limits, &mut self.camera);
        }
    }

    /// The light subpath, at most `vertices` vertices (y0 included).
    fn walk_light(&mut self, scene: &Scene, vertices: usize, rr_depth: u32) {
        let mut ls = Sampler::for_item(Domain::Light, 0, 0, 0);
        let limits = WalkLimits {
            max_vertices: vertices,
            rr_depth,
        };
        light_subpath(scene, &mut ls, limits, &mut self.light);
    }

    fn skip_camera(&mut self) {
        self.film = None;
        self.camera.vertices.clear();
        self.camera.escape = None;
    }

    fn skip_light(&mut self) {
        self.light.vertices.clear();
    }

    /// Adds strategy (s, t)'s MIS-weighted contribution to `out`, times `n_pixels` · (k + 1) where
    /// it lands on the sampled pixel (t ≥ 2) and (k + 1) where light tracing splats it (t = 1: its
    /// 1/M of M = N light subpaths cancels the N): MMLT's F_k on u (`target`).
    fn add(
        &mut self,
        scene: &Scene,
        mis: Heuristic,
        (s, t): (usize, usize),
        n_pixels: f32,
        out: &mut Splats,
    ) {
        let count = (s + t) as f32;
        let mut conn = Sampler::for_item(CONNECTION, 0, 0, 0);
        if t == 1 {
            if let Some((raster, c)) = self.light_traced(scene, mis, s, &mut conn) {
                out.add_filtered(scene.camera.film(), raster, c * count);
            }
            return;
        }
        let Some(film) = self.film else {
            return;
        };
        let c = match s {
            0 => self.emitter_reached(scene, mis, t),
            1 => self.next_event(scene, mis, t, &mut conn),
            _ => self.connection(scene, mis, (s, t)),
        };
        if c != Color::ZERO {
            out.add_to_pixel(self.pixel, weighted(c, film.weight) * (n_pixels * count));
        }
    }

    /// s = 0: z_{t−1} is an emitter, or the walk of t − 1 vertices left the scene towards
    /// lights at infinity (every one of them: each is strategy (0, t)).
    fn emitter_reached(&mut self, scene: &Scene, mis: Heuristic, t: usize) -> Color {
        let z = &self.camera.vertices;
        let mut l = Color::ZERO;
        let mut weigh = |path: &Vec<PathVertex>, value: Color| {
            let (split, evals) = Split::reached(path);
            let w = mis_weight(scene, split, evals, mis, LIGHT_TRACING_RATIO);
            l += value * w as f32;
        };
        if z.len() >= t {
            let zv = &z[t - 1];
            let (Some(x0), Some(li)) = (zv.as_light_endpoint(), zv.emitter()) else {
                return l;
            };
            let le = scene.lights[li as usize].emitted(x0.ng, x0.wo, x0.uv);
            if le == Color::ZERO {
                return l;
            }
            self.reached.clear();
            self.reached.extend_from_slice(&z[..t - 1]);
            self.reached.push(x0);
            weigh(&self.reached, zv.beta * le);
        } else if z.len() + 1 == t {
            let Some(esc) = self.camera.escape else {
                return l;
            };
            for &li in &scene.infinite_lights {
                let le = scene.lights[li as usize].escaped(esc.dir);
                if le == Color::ZERO {
                    continue;
                }
                self.reached.clear();
                self.reached.extend_from_slice(z);
                self.reached
                    .push(PathVertex::light_escaped(li, esc.dir, esc.beta, esc.pdf_w));
                weigh(&self.reached, esc.beta * le);
            }
        }
        l
    }

    /// s = 1: next-event estimation from z_{t−1}.
    fn next_event(&self, scene: &Scene, mis: Heuristic, t: usize, conn: &mut Sampler) -> Color {
        let z = &self.camera.vertices;
        if z.len() < t || !connectable(scene, &z[t - 1]) {
            return Color::ZERO;
        }
        let Some(ne) = next_event(scene, &z[t - 1], conn) else {
            return Color::ZERO;
        };
        let (split, evals) = Split::next_event(&z[..t], &ne.x0, ne.camera_end);
        let w = mis_weight(scene, split, evals, mis, LIGHT_TRACING_RATIO);
        ne.value * w as f32
    }

    /// s, t ≥ 2: a shadow ray between y_{s−1} and z_{t−1}.
    fn connection(&self, scene: &Scene, mis: Heuristic, (s, t): (usize, usize)) -> Color {
        let (y, z) = (&self.light.vertices, &self.camera.vertices);
        if y.len() < s || z.len() < t {
            return Color::ZERO;
        }
        let (yv, zv) = (&y[s - 1], &z[t - 1]);
        if !connectable(scene, zv) || !connectable(scene, yv) {
            return Color::ZERO;
        }
        let Some(j) = join(scene, yv, zv) else {
            return Color::ZERO;
        };
        let split = Split {
            light: &y[..s],
            camera: &z[..t],
            light_nee: nee_density(scene, &y[0], &y[1]),
        };
        let evals = EndEvals {
            light_end: Some(j.light_end),
            camera_end: Some(j.camera_end),
            flights: None,
        };
        j.value * mis_weight(scene, split, evals, mis, LIGHT_TRACING_RATIO) as f32
    }

    /// t = 1: y_{s−1} joined to the lens; the raster point it lands on and its weighted value.
    fn light_traced(
        &self,
        scene: &Scene,
        mis: Heuristic,
        s: usize,
        conn: &mut Sampler,
    ) -> Option<(lt_core::Vec2, Color)> {
        let y = &self.light.vertices;
        if y.len() < s || !connectable(scene, &y[s - 1]) {
            return None;
        }
        let c = connect_to_camera(scene, &y[s - 1], conn)?;
        let camera_only = [c.camera];
        let split = Split {
            light: &y[..s],
            camera: &camera_only,
            // Read only from s ≥ 2 (`Chain::one_is_nee`: k = s ≥ 2).
            light_nee: if s >= 2 {
                nee_density(scene, &y[0], &y[1])
            } else {
                0.0
            },
        };
        let evals = EndEvals {
            light_end: c.eval,
            camera_end: None,
            flights: None,
        };
        let w = mis_weight(scene, split, evals, mis, LIGHT_TRACING_RATIO);
        (w > 0.0).then(|| (c.raster, c.value * w as f32))
    }
}

/// A chain's state: strategy (s, t) on `pixel` alone — a camera walk of t vertices (none for
/// t = 1), a light walk of s vertices (none for s ≤ 1 < t), one connection — into `out`.
pub fn one_strategy(
    scene: &Scene,
    rules: Rules,
    pixel: u64,
    (s, t): (usize, usize),
    walks: &mut Walks,
    out: &mut Splats,
) {
    if t >= 2 {
        walks.walk_camera(scene, pixel, t, rules.rr_depth);
    } else {
        walks.skip_camera();
    }
    if s >= 2 || t == 1 {
        walks.walk_light(scene, s, rules.rr_depth);
    } else {
        walks.skip_light();
    }
    let n = scene.camera.pixel_count() as f32;
    walks.add(scene, rules.mis, (s, t), n, out);
}

/// The bootstrap's point: one camera walk of `lengths` + 1 vertices and one light walk of
/// `lengths`, and every strategy (s, t) of every length k = 1 … `lengths` read from them, each
/// into `scratch` (cleared first) and handed to `each(k, s, scratch)` — what `one_strategy` gives
/// for that (s, t) on the same point, bit for bit.
pub fn every_strategy(
    scene: &Scene,
    rules: Rules,
    pixel: u64,
    lengths: usize,
    walks: &mut Walks,
    scratch: &mut Splats,
    mut each: impl FnMut(usize, usize, &Splats),
) {
    walks.walk_camera(scene, pixel, lengths + 1, rules.rr_depth);
    walks.walk_light(scene, lengths, rules.rr_depth);
    let n = scene.camera.pixel_count() as f32;
    for k in 1..=lengths {
        for s in 0..=k {
            scratch.clear();
            // Each strategy's join reads the connection stream from its first number, as a
            // chain evaluating it alone does.
            rewind_installed(1 + CONNECTION as usize);
            walks.add(scene, rules.mis, (s, k + 1 - s), n, scratch);
            each(k, s, scratch);
        }
    }
}

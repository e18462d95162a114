//! `lvc-bdpt` — bidirectional path tracing with a light-vertex cache (Davidovič, Křivánek, Hašan,
//! Slusallek 2014, "Progressive Light Transport Simulation on the GPU: Survey and Improvements",
//! §LVC-BPT). Per pass, L light subpaths are traced once into a cache; light tracing (t = 1)
//! splats every one of them as `bdpt` does. Each camera vertex then connects to N cache vertices
//! drawn uniformly (with replacement) over the whole cache instead of to the vertices of one
//! light subpath; next-event estimation (s = 1) and emission hits (s = 0) are `bdpt`'s.
//!
//! **Sample counts** (Veach 1997, eq. 9.13: the heuristics weigh n_i p_i). The cache C holds
//! the connectable light vertices y_{s−1}, 2 ≤ s ≤ max_depth − 1, of L subpaths. One pick
//! chooses a light prefix ending at y with density Σ_l p_l(y)/|C| → L·p_light(y)/|C| (the
//! subpaths are independent; p_light(y) already carries the probability of reaching depth s,
//! so the depth's share of the cache cancels: c_d/|C| picks land at depth d, and each of the
//! c_d ≈ L·P(depth d) vertices there is one of L draws of p_light). N picks per camera vertex
//! make the connection technique (s ≥ 2, t ≥ 2) an estimator with
//!
//!   n_conn = N · L / |C| = N / L̄,   L̄ = |C| / L the cached vertices per light subpath,
//!
//! in the units where bdpt's connections (one light subpath per camera sample) count 1, the
//! same for every s (Davidovič et al. 2014, the LVC-BPT paragraph: "n_c / average light path
//! length"). NEE and s = 0 keep 1; light tracing keeps M/N (`Chain::light_tracing_ratio`). A
//! pick's contribution is scaled by |C| / (N·L), so that given the cache its mean over picks is
//! (1/L) Σ_{v∈C} w·f/p — bdpt's connection sum averaged over the L subpaths.
//!
//! L̄ in n_conn comes from a pilot of `PILOT_PATHS` light subpaths traced once, with a fixed
//! seed, when the integrator is built: a constant, so the weights are a function of the path
//! alone and every pass is exactly unbiased. (The pass's own |C| / L would tie the weights to
//! the light subpaths they weigh — an O(1/L) bias.) The pick's scale uses the pass's own |C|.
//!
//! | key | type | default | meaning |
//! |---|---|---|---|
//! | `max_depth` | u32 | scene `[render] max_depth` (8) | longest path in segments, camera ray included |
//! | `rr_depth` | u32 | scene `[render] rr_depth` (5) | Russian roulette from this many segments on |
//! | `mis` | power/balance/none | power | heuristic over the strategies (none: uniform weights) |
//! | `light_paths` | u64 | the pixel count | light subpaths traced into the cache per pass |
//! | `connections` | u32 | 1 | cache vertices each camera vertex connects to (N) |

use crate::film::splat::{splat_pass_with, Pass, Splats, Worker};
use crate::params::ParamReader;
use crate::record::tally::{pool_cpu_seconds, tallied_pass, PassClock, PassTally, Tally};
use crate::record::{NoRecord, Recorder, Work};
use crate::subpath::camera_loop::{
    camera_sample, CameraPolicy, CameraScratch, Depths, Joins, Weight,
};
use crate::subpath::connect::{nee_density, splat_light_subpath, JoinFlights};
use crate::subpath::strategy_weight::{with_chain, EndEvals, Split};
use crate::subpath::walk::{light_subpath, Subpath, WalkLimits};
use crate::Integrator;
use lt_core::bsdf::BsdfEval;
use lt_core::math::{Color, Vec2};
use lt_core::path::scatter::connectable;
use lt_core::path::{Chain, Heuristic, PathVertex};
use lt_core::sampling::{Domain, Sampler};
use lt_core::Scene;
use lt_estimators::Image;
use rayon::prelude::*;

#[derive(Clone, Copy, Debug)]
pub struct LvcParams {
    pub max_depth: u32,
    pub rr_depth: u32,
    pub mis: Heuristic,
    /// `None`: one light subpath per pixel.
    pub light_paths: Option<u64>,
    /// N: cache vertices per camera vertex.
    pub connections: u32,
}

impl LvcParams {
    pub fn read(scene: &Scene, r: &ParamReader) -> Result<LvcParams, String> {
        let connections = r.get::<u32>("connections")?.unwrap_or(1);
        if connections == 0 {
            return Err("lvc-bdpt: connections must be at least 1".into());
        }
        Ok(LvcParams {
            max_depth: r.max_depth(scene)?,
            rr_depth: r.rr_depth(scene)?,
            mis: r
                .get_with("mis", Heuristic::parse)?
                .unwrap_or(Heuristic::Power),
            light_paths: r.light_paths()?,
            connections,
        })
    }
}

/// Light subpaths of the pilot that measures L̄.
pub const PILOT_PATHS: u64 = 4096;
/// The pilot's seed (any constant: the pilot only fixes the MIS sample count).
const PILOT_SEED: u64 = 0x1c5_c0de;

pub struct LvcBdpt {
    pub params: LvcParams,
    /// L̄: cached vertices per light subpath, from the pilot.
    pub mean_cached: f64,
}

/// Whether light vertex y_{s−1} (prefix of s vertices) goes into the cache: a connectable
/// surface a camera vertex can still join within `max_k` segments (s + t − 1 ≤ max_k, t ≥ 2).
pub fn cacheable(scene: &Scene, y: &[PathVertex], s: usize, max_k: usize) -> bool {
    s >= 2 && s < max_k && s <= y.len() && connectable(scene, &y[s - 1])
}

/// The weight of technique s when connections (2 ≤ s ≤ k − 1) count `n_conn` samples instead
/// of bdpt's 1: the chain's ratios r_i = n_i p_i / (n_s p_s) rescaled by the new counts.
pub fn lvc_weight(chain: &Chain, s: usize, h: Heuristic, n_conn: f64) -> f64 {
    if !chain.valid(s) || chain.technique(s) == 0.0 {
        return 0.0;
    }
    let k = chain.k();
    let count = |i: usize| {
        if i >= 2 && i < k {
            n_conn
        } else {
            chain.sample_count(i)
        }
    };
    let ns = count(s) / chain.sample_count(s);
    if !(ns > 0.0) {
        return 0.0;
    }
    let mut stack = [0.0f64; 26];
    let mut heap = Vec::new();
    let r: &mut [f64] = if k + 2 <= stack.len() {
        &mut stack[..k + 2]
    } else {
        heap.resize(k + 2, 0.0);
        &mut heap
    };
    chain.relative(s, r);
    for (i, ri) in r.iter_mut().enumerate() {
        *ri *= count(i) / chain.sample_count(i) / ns;
    }
    h.weight_from_ratios(r)
}

/// One pass's light subpaths, concatenated, and the cache entries into them.
pub struct Cache {
    vertices: Vec<PathVertex>,
    /// Per subpath: first vertex, vertex count, next-event density of its x0 from x1.
    paths: Vec<(usize, usize, f64)>,
    /// (subpath, s): the cached vertex y_{s−1} of that subpath.
    entries: Vec<(u32, u32)>,
}

impl Cache {
    fn path(&self, i: usize) -> (&[PathVertex], f64) {
        let (start, len, nee) = self.paths[i];
        (&self.vertices[start..start + len], nee)
    }

    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

/// The MIS inputs every strategy of one pass shares.
#[derive(Clone, Copy)]
struct Mis {
    h: Heuristic,
    /// M/N.
    ratio: f64,
    n_conn: f64,
}

impl Mis {
    fn weight(&self, scene: &Scene, split: Split, evals: EndEvals) -> f64 {
        with_chain(scene, split, evals, self.ratio, |c, s| {
            lvc_weight(c, s, self.h, self.n_conn)
        })
    }
}

/// Per-thread buffers of one camera sample.
pub struct Scratch {
    camera: CameraScratch,
}

impl LvcBdpt {
    /// Builds the integrator and runs the pilot that measures L̄ on `scene`.
    pub fn new(scene: &Scene, params: LvcParams) -> LvcBdpt {
        let max_k = params.max_depth as usize;
        let limits = WalkLimits::light(params.max_depth, params.rr_depth);
        let cached: u64 = (0..PILOT_PATHS)
            .into_par_iter()
            .map_init(
                || Subpath::with_capacity(max_k),
                |sub, i| {
                    let mut ls = Sampler::for_item(Domain::Light, PILOT_SEED, i, 0);
                    light_subpath(scene, &mut ls, limits, sub);
                    let y = &sub.vertices;
                    (2..=y.len())
                        .filter(|&s| cacheable(scene, y, s, max_k))
                        .count() as u64
                },
            )
            .sum();
        LvcBdpt {
            params,
            mean_cached: cached as f64 / PILOT_PATHS as f64,
        }
    }

    fn light_paths(&self, scene: &Scene) -> u64 {
        self.params
            .light_paths
            .unwrap_or(scene.camera.pixel_count() as u64)
    }

    /// M/N: light subpaths per camera sample.
    pub fn ratio(&self, scene: &Scene) -> f64 {
        self.light_paths(scene) as f64 / scene.camera.pixel_count() as f64
    }

    /// n_conn = N / L̄ (module docs); 0 when the pilot cached nothing (no connection is made).
    pub fn connection_count(&self) -> f64 {
        if self.mean_cached > 0.0 {
            self.params.connections as f64 / self.mean_cached
        } else {
            0.0
        }
    }

    fn mis(&self, scene: &Scene) -> Mis {
        Mis {
            h: self.params.mis,
            ratio: self.ratio(scene),
            n_conn: self.connection_count(),
        }
    }

    /// Traces the pass's L light subpaths (subpath i from bdpt's stream for light path i).
    pub fn build_cache(&self, scene: &Scene, pass: Pass) -> Cache {
        let max_k = self.params.max_depth as usize;
        let limits = WalkLimits::light(self.params.max_depth, self.params.rr_depth);
        let traced: Vec<(Vec<PathVertex>, f64)> = (0..self.light_paths(scene))
            .into_par_iter()
            .map_init(
                || Subpath::with_capacity(max_k),
                |sub, i| {
                    let mut ls = Sampler::for_item(Domain::Light, pass.seed, i, pass.pass as u64);
                    light_subpath(scene, &mut ls, limits, sub);
                    let y = &sub.vertices;
                    let nee = if y.len() >= 2 {
                        nee_density(scene, &y[0], &y[1])
                    } else {
                        0.0
                    };
                    (y.clone(), nee)
                },
            )
            .collect();
        let mut cache = Cache {
            vertices: Vec::with_capacity(traced.iter().map(|t| t.0.len()).sum()),
            paths: Vec::with_capacity(traced.len()),
            entries: Vec::new(),
        };
        for (i, (y, nee)) in traced.into_iter().enumerate() {
            for s in 2..=y.len() {
                if cacheable(scene, &y, s, max_k) {
                    cache.entries.push((i as u32, s as u32));
                }
            }
            cache.paths.push((cache.vertices.len(), y.len(), nee));
            cache.vertices.extend_from_slice(&y);
        }
        cache
    }

    pub fn scratch(&self) -> Scratch {
        Scratch {
            camera: CameraScratch::new(self.params.max_depth),
        }
    }

    /// t = 1 for light subpath i: every connectable vertex joined to the camera.
    fn splat_light<R: Recorder>(
        &self,
        scene: &Scene,
        cache: &Cache,
        pass: Pass,
        i: u64,
        splats: &mut Splats,
        rec: &mut R,
    ) {
        let mis = self.mis(scene);
        let max_k = self.params.max_depth as usize;
        let scale = 1.0 / self.light_paths(scene) as f32;
        let (y, light_nee) = cache.path(i as usize);
        let mut lens = Sampler::for_item(Domain::Lens, pass.seed, i, pass.pass as u64);
        splat_light_subpath(scene, y, max_k, scale, &mut lens, splats, rec, |s, c| {
            let camera_only = [c.camera];
            let split = Split {
                light: &y[..s],
                camera: &camera_only,
                light_nee,
            };
            let evals = EndEvals {
                light_end: c.eval,
                camera_end: None,
                flights: None,
            };
            (mis.weight(scene, split, evals), None)
        });
    }

    /// The camera sample of `pixel`: s = 0, s = 1 and N cache connections at every vertex.
    fn camera_sample<R: Recorder>(
        &self,
        scene: &Scene,
        cache: &Cache,
        pass: Pass,
        pixel: u64,
        scratch: &mut Scratch,
        rec: &mut R,
    ) -> Color {
        let n = self.params.connections;
        let mut policy = Policy {
            cache,
            mis: self.mis(scene),
            picks: n,
            // |C| / (N·L): one pick's share of the mean over the cache (module docs).
            pick_scale: cache.len() as f32 / (n as f32 * self.light_paths(scene) as f32),
        };
        let depths = Depths {
            max_depth: self.params.max_depth,
            rr_depth: self.params.rr_depth,
        };
        camera_sample(
            scene,
            (pass, pixel),
            depths,
            &mut policy,
            &mut scratch.camera,
            rec,
        )
    }

    /// Work item i of a pass over `cache`: light subpath i splatted (i < L), pixel i (i < N).
    pub fn item<R: Recorder>(
        &self,
        scene: &Scene,
        cache: &Cache,
        pass: Pass,
        i: u64,
        worker: &mut Worker<'_, Scratch, R>,
    ) {
        worker.rec.begin_item(i);
        if i < self.light_paths(scene) {
            self.splat_light(scene, cache, pass, i, worker.splats, worker.rec);
        }
        if i < scene.camera.pixel_count() as u64 {
            let l = self.camera_sample(scene, cache, pass, i, worker.scratch, worker.rec);
            worker.splats.add_to_pixel(i as u32, l);
        }
    }

    /// One pass with every path reported to `rec` (for `lt mis-check`), on one thread; the
    /// image is discarded.
    pub fn record_pass<R: Recorder>(&self, scene: &Scene, seed: u64, pass: u32, rec: &mut R) {
        let pass = Pass { seed, pass };
        let cache = self.build_cache(scene, pass);
        let items = (scene.camera.pixel_count() as u64).max(self.light_paths(scene));
        let mut scratch = self.scratch();
        let mut splats = Splats::new(scene.camera.width, scene.camera.height);
        let mut worker = Worker {
            splats: &mut splats,
            scratch: &mut scratch,
            rec,
        };
        for i in 0..items {
            self.item(scene, &cache, pass, i, &mut worker);
        }
    }
}

/// A uniform index below `n` from 48 random bits (two draws): f32's 24 bits alone would favour
/// some entries of a cache of millions by a visible fraction.
fn uniform_index(s: &mut Sampler, n: usize) -> usize {
    let hi = (s.next_f32() * (1u32 << 24) as f32) as u64;
    let lo = (s.next_f32() * (1u32 << 24) as f32) as u64;
    let x = (hi << 24) | lo;
    (((x as u128) * (n as u128)) >> 48) as usize
}

/// lvc-bdpt's policy in the camera loop: every camera vertex joins `picks` vertices drawn
/// uniformly from the cache; weights from the stored densities with n_conn connections.
struct Policy<'a> {
    cache: &'a Cache,
    mis: Mis,
    /// N.
    picks: u32,
    /// |C| / (N·L).
    pick_scale: f32,
}

impl CameraPolicy for Policy<'_> {
    fn emitter_weight(
        &self,
        scene: &Scene,
        path: &[PathVertex],
        _: JoinFlights,
        _: Vec2,
    ) -> Weight {
        let (split, evals) = Split::reached(path);
        (self.mis.weight(scene, split, evals), None)
    }

    fn next_event_weight(
        &self,
        scene: &Scene,
        z: &[PathVertex],
        (x0, camera_end): (&PathVertex, BsdfEval),
        _: JoinFlights,
        _: Vec2,
    ) -> Weight {
        let (split, evals) = Split::next_event(z, x0, camera_end);
        (self.mis.weight(scene, split, evals), None)
    }

    fn connect<R: Recorder>(
        &mut self,
        scene: &Scene,
        joins: &mut Joins<'_, R>,
        sampler: &mut Sampler,
    ) {
        let (cache, t, max_k) = (self.cache, joins.t(), joins.max_k());
        if cache.is_empty() || t + 1 > max_k {
            return;
        }
        for _ in 0..self.picks {
            let (p, s) = cache.entries[uniform_index(sampler, cache.len())];
            let (y, light_nee) = cache.path(p as usize);
            let s = s as usize;
            if s + t - 1 > max_k {
                continue;
            }
            joins.join(scene, &y[..s], self.pick_scale, |c| {
                let (split, evals) = Split::connection(c, light_nee);
                (self.mis.weight(scene, split, evals), None)
            });
        }
    }
}

/// Work items per splat chunk (fixed, so the image does not depend on the thread count).
const CHUNK: u64 = 256;

impl LvcBdpt {
    /// `render_pass` with every technique's contributions and time tallied (`crate::record::tally`):
    /// the same image, bit for bit. The cache's light walks are one phase (`Work::LightWalk`).
    pub fn tally_pass(
        &self,
        scene: &Scene,
        seed: u64,
        pass: u32,
        every: u64,
    ) -> (Image, u64, PassTally) {
        let clock = PassClock::start();
        let p = Pass { seed, pass };
        let cpu0 = pool_cpu_seconds();
        let cache = self.build_cache(scene, p);
        let walk = pool_cpu_seconds() - cpu0;
        let items = (scene.camera.pixel_count() as u64).max(self.light_paths(scene));
        let (img, invalid, tally) = tallied_pass(
            scene,
            pass,
            every,
            (items, CHUNK),
            || self.scratch(),
            |i, splats, scratch, rec: &mut Tally| {
                let mut worker = Worker {
                    splats,
                    scratch,
                    rec,
                };
                self.item(scene, &cache, p, i, &mut worker)
            },
        );
        (
            img,
            invalid,
            tally.finish(clock, &[(Work::LightWalk, walk)]),
        )
    }
}

impl Integrator for LvcBdpt {
    fn name(&self) -> &'static str {
        "lvc-bdpt"
    }

    fn render_pass(&self, scene: &Scene, seed: u64, pass: u32) -> (Image, u64) {
        let pass = Pass { seed, pass };
        let cache = self.build_cache(scene, pass);
        let cam = &scene.camera;
        let items = (cam.pixel_count() as u64).max(self.light_paths(scene));
        splat_pass_with(
            cam.width as usize,
            cam.height as usize,
            items,
            CHUNK,
            || self.scratch(),
            |i, splats, scratch| {
                let mut worker = Worker {
                    splats,
                    scratch,
                    rec: &mut NoRecord,
                };
                self.item(scene, &cache, pass, i, &mut worker)
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_index_stays_below_n_and_reaches_both_ends() {
        let mut s = Sampler::new(1, 2, 3);
        let n = 7;
        let mut seen = [false; 7];
        for _ in 0..1000 {
            let i = uniform_index(&mut s, n);
            assert!(i < n);
            seen[i] = true;
        }
        assert!(seen.iter().all(|&b| b));
    }
}

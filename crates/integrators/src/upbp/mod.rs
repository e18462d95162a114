//! `upbp` — unified points, beams and paths (Křivánek, Georgiev, Hachisuka, Vévoda, Šik,
//! Nowrouzezahrai & Jarosz 2014): bdpt's connections through media and three of the volumetric
//! density estimators under one MIS, on the one bidirectional camera loop
//! (`subpath::camera_loop`, policy in `policy`):
//!
//! - `bpt`: every connection technique (s, t) as `bdpt` walks and joins them through media
//!   (s = 0 always runs: the only technique for some paths);
//! - `pp3d`: each medium vertex of the camera walk gathers the pass's photons (medium vertices of
//!   all M light subpaths) within r_P, 3-D kernel 1/((4/3)π r_P³);
//! - `pb2d`: each segment of the camera walk, as a short beam (the flight the walk sampled),
//!   gathers the photons within r_B of it, 2-D kernel 1/(π r_B²), T evaluated along it;
//! - `surf`: vcm's vertex merging at every non-delta surface vertex of the camera walk with the
//!   light subpaths' non-delta surface vertices within r_S = r_B (disk kernel 1/(π r_S²), the
//!   side tests and BSDF evaluation of `density::surface_merge`, shared with vcm): on a scene
//!   without media `bpt,surf` is vcm's technique set;
//! - `bb1d`: the same short camera beams gather the light subpaths' segments through media as
//!   photon beams (`light_beams`, short by default, long with `beams=long`) within r_BB, 1-D
//!   kernel 1/(2 r_BB) over sin θ, T evaluated along both (`camera_beams`);
//! - `bp2d`: each medium vertex of the camera walk gathers the same photon beams within r_B of
//!   it, 2-D kernel 1/(π r_B²) across each beam, T evaluated along it (`policy::beam_points`).
//!
//! Weights: `weights` (full-path densities, the measures and η's stated there and in
//! `lt_core::path::volume_merging`, the oracle). Per pass, camera sample j pairs
//! with light subpath j mod M for its connections (bdpt's pairing) and queries all M for merges;
//! radii shrink per kernel dimension (`volume_density::schedule`): r_P,i = r₁ i^((α_P−1)/3),
//! r_B,i = r₁ i^((α−1)/2) (PB2D, BP2D, surface merges), r_BB,i = r₁ i^(α_BB−1). A scene without media has no photons: upbp
//! is bdpt there by default, vcm with `techniques=all` or `bpt,surf`.
//!
//! | key | type | default | meaning |
//! |---|---|---|---|
//! | `max_depth` | u32 | scene `[render] max_depth` (8) | longest path in segments, camera ray included |
//! | `rr_depth` | u32 | scene `[render] rr_depth` (5) | Russian roulette from this many segments on |
//! | `mis` | power/balance/none | power | heuristic over every technique |
//! | `techniques` | all/bpt/surf/pp3d/pb2d/bb1d/bp2d | bpt,pp3d,pb2d,bb1d | `all` (the six), or a comma- or plus-separated subset of bpt, surf, pp3d, pb2d, bb1d, bp2d (SmallUPBP's names); surf and bp2d are opt-in (`DEFAULT_TECHNIQUES`) |
//! | `mode` | full/compatible/previous | full | SmallUPBP's modes (`lt_core::path::UpbpMode`): every path; only paths ES*M(S|D|M)*L with full weights; those paths with only the techniques meeting at their first medium vertex from the camera |
//! | `beams` | short/long | short | the photon beams of BB1D and BP2D: the flight the light walk sampled, or on to the next surface (`light_beams`) |
//! | `photons_per_pass` | u64 | the pixel count | light subpaths per pass (M) |
//! | `radius` | f32 | — | initial radius r₁ in scene units (every kernel) |
//! | `radius_scene` | f32 | 0.01 | initial radius as a fraction of the scene's bounding-sphere diameter |
//! | `alpha` | f64 | 2/3 | PB2D's and surface merges' radius reduction: r_B,i = r_S,i = r₁ i^((α−1)/2) |
//! | `alpha_points` | f64 | 4/7 | PP3D's radius reduction: r_P,i = r₁ i^((α_P−1)/3) |
//! | `alpha_beam_beams` | f64 | 4/5 | BB1D's radius reduction: r_BB,i = r₁ i^(α_BB−1) |
//! | `beam_paths` | u64 | ⌈M/8⌉ | light subpaths (the pass's first) whose segments are BB1D's and BP2D's photon beams |

mod beam_end;
pub mod camera_beams;
pub mod light_beams;
pub mod light_store;
pub mod policy;
pub mod rates;
pub mod weights;

use crate::film::splat::{splat_pass_with, Pass, Splats, Worker};
use crate::params::ParamReader;
use crate::record::tally::{
    pool_cpu_seconds, tallied_pass, ItemTally, PassClock, PassTally, Tally,
};
use crate::record::{NoRecord, Recorder, Work};
use crate::subpath::camera_loop::{camera_sample, CameraScratch, Depths};
use crate::subpath::connect::{splat_light_subpath_in, JoinFlights};
use crate::subpath::strategy_weight::{with_chain_in, EndEvals, Split};
use crate::subpath::walk::{Subpath, WalkLimits};
use crate::volume_density::schedule::{balanced_alpha, radius_scale};
use crate::volume_density::VolumeParams;
use crate::{ProgressLog, Progressive, ProgressiveRun};
use light_store::{BeamSetup, LightStore};
use lt_core::math::PI;
use lt_core::path::{Heuristic, UpbpMode, VolumeSet};
use lt_core::sampling::{Domain, Sampler};
use lt_core::Scene;
use lt_estimators::Image;
use policy::{connection_weight, PassData, Policy};
use rates::{junction, Needs};

/// Which of the techniques run (`techniques`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Techniques {
    pub bpt: bool,
    pub pp3d: bool,
    pub pb2d: bool,
    pub bb1d: bool,
    /// Surface vertex merging (vcm's; SmallUPBP's `surf`).
    pub surf: bool,
    /// Photon beams at camera points (SmallUPBP's `bp2d`).
    pub bp2d: bool,
}

impl Techniques {
    /// `all`, or a comma- or plus-separated subset of `bpt`, `surf`, `pp3d`, `pb2d`, `bb1d`,
    /// `bp2d`.
    pub fn parse(text: &str) -> Result<Techniques, String> {
        if text.trim() == "all" {
            return Ok(Techniques {
                bpt: true,
                pp3d: true,
                pb2d: true,
                bb1d: true,
                surf: true,
                bp2d: true,
            });
        }
        let mut t = Techniques {
            bpt: false,
            pp3d: false,
            pb2d: false,
            bb1d: false,
            surf: false,
            bp2d: false,
        };
        for name in text.split([',', '+']) {
            match name.trim() {
                "bpt" => t.bpt = true,
                "pp3d" => t.pp3d = true,
                "pb2d" => t.pb2d = true,
                "bb1d" => t.bb1d = true,
                "surf" => t.surf = true,
                "bp2d" => t.bp2d = true,
                other => {
                    return Err(format!(
                        "unknown technique '{other}' (known: all, or a comma-separated subset of \
                         bpt, surf, pp3d, pb2d, bb1d, bp2d)"
                    ))
                }
            }
        }
        Ok(t)
    }
}

/// `techniques` by default: every technique but the surface merges and BP2D. Surface merges are
/// opt-in (`all`, or `+surf`): a merge's weight here is formed from the full path (O(k) per
/// merge, not vcm's O(1) recursion), which made upbp 5–7× slower on cornell-box at its default
/// radius, and the registry's loops hold upbp at bdpt's budget on surface scenes. BP2D (`+bp2d`)
/// is opt-in so that the default's images stay those the registry's studies were run with.
pub const DEFAULT_TECHNIQUES: &str = "bpt,pp3d,pb2d,bb1d";

#[derive(Clone, Copy, Debug)]
pub struct UpbpParams {
    pub volume: VolumeParams,
    pub alpha_points: f64,
    pub alpha_beam_beams: f64,
    /// `beam_paths` (None: ⌈M/8⌉).
    pub beam_paths: Option<u64>,
    pub mis: Heuristic,
    pub techniques: Techniques,
    /// `beams=long`: BB1D's and BP2D's photon beams run to the next surface (`light_beams`).
    pub long_beams: bool,
    /// `mode`: SmallUPBP's compatible/previous (`UpbpMode`).
    pub mode: UpbpMode,
}

impl UpbpParams {
    pub fn read(scene: &Scene, r: &ParamReader) -> Result<UpbpParams, String> {
        let volume = VolumeParams::read(scene, r, "upbp", 2)?;
        let alpha_points = r.get::<f64>("alpha_points")?.unwrap_or(balanced_alpha(3));
        if !(alpha_points > 0.0 && alpha_points <= 1.0) {
            return Err(format!(
                "upbp: alpha_points must lie in (0, 1], got {alpha_points}"
            ));
        }
        let alpha_beam_beams = r
            .get::<f64>("alpha_beam_beams")?
            .unwrap_or(balanced_alpha(1));
        if !(alpha_beam_beams > 0.0 && alpha_beam_beams <= 1.0) {
            return Err(format!(
                "upbp: alpha_beam_beams must lie in (0, 1], got {alpha_beam_beams}"
            ));
        }
        let beam_paths = r.get::<u64>("beam_paths")?;
        if beam_paths == Some(0) {
            return Err("upbp: beam_paths must be at least 1".into());
        }
        Ok(UpbpParams {
            volume,
            alpha_points,
            alpha_beam_beams,
            beam_paths,
            mis: r
                .get_with("mis", Heuristic::parse)?
                .unwrap_or(Heuristic::Power),
            techniques: r
                .get_with("techniques", Techniques::parse)?
                .unwrap_or(Techniques::parse(DEFAULT_TECHNIQUES)?),
            long_beams: r.get_with("beams", parse_beams)?.unwrap_or(false),
            mode: r.get_with("mode", UpbpMode::parse)?.unwrap_or_default(),
        })
    }
}

/// `beams`: `long` (true) or `short`.
fn parse_beams(text: &str) -> Result<bool, String> {
    match text.trim() {
        "long" => Ok(true),
        "short" => Ok(false),
        other => Err(format!("unknown beams '{other}' (known: short, long)")),
    }
}

pub struct Upbp {
    pub params: UpbpParams,
}

impl Upbp {
    pub fn read(scene: &Scene, r: &ParamReader) -> Result<Upbp, String> {
        Ok(Upbp {
            params: UpbpParams::read(scene, r)?,
        })
    }

    /// M, light subpaths per pass.
    pub fn light_paths(&self, scene: &Scene) -> u64 {
        self.params
            .volume
            .photons_per_pass
            .unwrap_or(scene.camera.pixel_count() as u64)
    }

    /// M_BB, the light subpaths whose segments are photon beams: a beam reaches every camera
    /// beam that passes it, so far fewer than M keep BB1D's variance near the others' at a
    /// fraction of the query cost (its density counts M_BB, not M).
    pub fn beam_paths(&self, scene: &Scene) -> u64 {
        let m = self.light_paths(scene);
        self.params.beam_paths.unwrap_or(m.div_ceil(8)).min(m)
    }

    /// The radii (r_P, r_B, r_BB) of pass `pass` (0-based).
    pub fn radii(&self, pass: u32) -> (f32, f32, f32) {
        let v = &self.params.volume;
        let rp = v.radius * radius_scale(pass + 1, self.alpha_points(), 3) as f32;
        let rb = v.radius * radius_scale(pass + 1, v.alpha, 2) as f32;
        let rbb = v.radius * radius_scale(pass + 1, self.params.alpha_beam_beams, 1) as f32;
        (rp, rb, rbb)
    }

    fn alpha_points(&self) -> f64 {
        self.params.alpha_points
    }

    /// The pass's light subpaths and the technique set with its η's.
    pub fn setup(&self, scene: &Scene, seed: u64, pass: u32) -> (LightStore, PassSetup) {
        let t = self.params.techniques;
        let m = self.light_paths(scene);
        let (rp, rb, rbb) = self.radii(pass);
        let v = &self.params.volume;
        let limits = WalkLimits::light(v.max_depth, v.rr_depth);
        let (mf, rpf, rbf) = (m as f64, rp as f64, rb as f64);
        let points_eta = if t.pp3d {
            mf * 4.0 / 3.0 * PI as f64 * rpf * rpf * rpf
        } else {
            0.0
        };
        let beams_eta = if t.pb2d {
            mf * PI as f64 * rbf * rbf
        } else {
            0.0
        };
        let m_bb = self.beam_paths(scene);
        let beam_beams_eta = if t.bb1d {
            m_bb as f64 * 2.0 * rbb as f64
        } else {
            0.0
        };
        // BP2D shares PB2D's 2-D schedule (r_B) and BB1D's beams (M_B of them).
        let beam_points_eta = if t.bp2d {
            m_bb as f64 * PI as f64 * rbf * rbf
        } else {
            0.0
        };
        // Surface merges share PB2D's 2-D schedule (the same kernel dimension): r_S = r_B.
        let surface_eta = if t.surf {
            mf * PI as f64 * rbf * rbf
        } else {
            0.0
        };
        let set = VolumeSet {
            connections: t.bpt,
            points_eta,
            beams_eta,
            beam_beams_eta,
            surface_eta,
            beam_points_eta,
            long_beams: self.params.long_beams,
            mode: self.params.mode,
        };
        // One beam index serves both beam techniques: listed within the larger radius.
        let r_index = match (t.bb1d, t.bp2d) {
            (true, true) => rbb.max(rb),
            (true, false) => rbb,
            _ => rb,
        };
        let beams = (t.bb1d || t.bp2d).then_some(BeamSetup {
            r_index,
            paths: m_bb,
            long: self.params.long_beams,
        });
        let radii = (
            t.pp3d.then_some(rp),
            t.pb2d.then_some(rb),
            beams,
            t.surf.then_some(rb),
        );
        let needs = Needs::of(&set);
        let store = LightStore::trace(scene, (seed, pass), (m, limits, needs), radii);
        let setup = PassSetup {
            set,
            r_points: rp,
            r_beams: rb,
            r_beam_beams: rbb,
            light_paths: m,
        };
        (store, setup)
    }

    fn scratch(&self) -> Scratch {
        let d = self.params.volume.max_depth as usize;
        Scratch {
            camera: CameraScratch::new(self.params.volume.max_depth),
            light: Subpath::with_capacity(d),
        }
    }

    /// Work item i (0 … max(N, M)−1): pixel i (i < N) with light subpath i mod M, splatting light
    /// subpath i (i < M) by light tracing.
    pub fn item<R: Recorder>(
        &self,
        scene: &Scene,
        (data, pass): (&PassData, Pass),
        i: u64,
        worker: &mut Worker<'_, Scratch, R>,
    ) {
        if scene.has_media {
            self.item_in::<true, R>(scene, (data, pass), i, worker)
        } else {
            self.item_in::<false, R>(scene, (data, pass), i, worker)
        }
    }

    fn item_in<const MEDIA: bool, R: Recorder>(
        &self,
        scene: &Scene,
        (data, pass): (&PassData, Pass),
        i: u64,
        worker: &mut Worker<'_, Scratch, R>,
    ) {
        let n = scene.camera.pixel_count() as u64;
        let m = data.store.len() as u64;
        let Worker {
            splats,
            scratch,
            rec,
        } = worker;
        rec.begin_item(i);
        let ly = data.store.path((i % m) as usize);
        let y = &mut scratch.light;
        y.vertices.clear();
        y.vertices.extend_from_slice(ly.vertices);
        y.back_flight.clear();
        y.back_flight.extend_from_slice(ly.back_flight);
        rec.lap(Work::LightWalk);
        if i < m && data.set.connections {
            let mut lens = Sampler::for_item(Domain::Lens, pass.seed, i, pass.pass as u64);
            let scale = 1.0 / m as f32;
            let rec = &mut **rec;
            let yv = ly.vertices;
            splat_light_subpath_in::<MEDIA, R>(
                scene,
                yv,
                data.max_k,
                scale,
                &mut lens,
                splats,
                rec,
                |s, c| {
                    let camera_only = [c.camera];
                    let split = Split {
                        light: &yv[..s],
                        camera: &camera_only,
                        light_nee: ly.nee,
                    };
                    let flights = JoinFlights {
                        edge: c.flights,
                        light_back: ly.back_flight[s - 1],
                        camera_back: 1.0,
                    };
                    let evals = EndEvals {
                        light_end: c.eval,
                        camera_end: None,
                        flights: Some(flights),
                    };
                    let camera_end = rates::camera_vertex(scene, &camera_only, 0, data.needs);
                    let (y_end, c_end) = junction(
                        scene,
                        (&yv[..s], &camera_only),
                        (ly.rates[s - 1], camera_end),
                        data.needs,
                    );
                    let ends = [(s - 1, y_end), (s, c_end)];
                    let w = with_chain_in::<MEDIA, _>(scene, split, evals, data.ratio, |ch, s| {
                        connection_weight(data, ch, s, (ly.rates, &[]), &ends)
                    });
                    (w, None)
                },
            );
        }
        if i >= n {
            return;
        }
        let mut policy = Policy::<MEDIA>::new(data, &scratch.light, ly);
        let depths = Depths {
            max_depth: self.params.volume.max_depth,
            rr_depth: self.params.volume.rr_depth,
        };
        let l = camera_sample(
            scene,
            (pass, i),
            depths,
            &mut policy,
            &mut scratch.camera,
            &mut **rec,
        );
        splats.add_to_pixel(i as u32, l);
    }

    /// One pass's image and invalid-sample count.
    pub fn render_pass(&self, scene: &Scene, data: &PassData, pass: Pass) -> (Image, u64) {
        let cam = &scene.camera;
        let items = (cam.pixel_count() as u64).max(data.store.len() as u64);
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
                self.item(scene, (data, pass), i, &mut worker)
            },
        )
    }

    /// `pass` with every technique's contributions and time tallied (`crate::record::tally`):
    /// the image `render_pass` makes, bit for bit. Tracing and storing the light paths (photons,
    /// beams and their indices) is one phase (`Work::LightWalk`), timed once per pass.
    pub fn tally_pass(
        &self,
        scene: &Scene,
        seed: u64,
        pass: u32,
        every: u64,
    ) -> (Image, u64, PassTally) {
        let clock = PassClock::start();
        let cpu0 = pool_cpu_seconds();
        let (store, setup) = self.setup(scene, seed, pass);
        let data = setup.data(self, scene, &store);
        let walk = pool_cpu_seconds() - cpu0;
        let items = (scene.camera.pixel_count() as u64).max(store.len() as u64);
        let p = Pass { seed, pass };
        let (img, invalid, tally): (Image, u64, ItemTally) = tallied_pass(
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
                self.item(scene, (&data, p), i, &mut worker)
            },
        );
        (
            img,
            invalid,
            tally.finish(clock, &[(Work::LightWalk, walk)]),
        )
    }

    /// One pass with every path reported to `rec` (for `lt mis-check`), item by item on one
    /// thread; the image is discarded. Returns the pass's setup.
    pub fn record_pass<R: Recorder>(
        &self,
        scene: &Scene,
        seed: u64,
        pass: u32,
        rec: &mut R,
    ) -> PassSetup {
        let (store, setup) = self.setup(scene, seed, pass);
        let data = setup.data(self, scene, &store);
        let cam = &scene.camera;
        let mut scratch = self.scratch();
        let mut splats = Splats::new(cam.width, cam.height);
        let mut worker = Worker {
            splats: &mut splats,
            scratch: &mut scratch,
            rec,
        };
        let items = (cam.pixel_count() as u64).max(store.len() as u64);
        for i in 0..items {
            self.item(scene, (&data, Pass { seed, pass }), i, &mut worker);
        }
        setup
    }
}

/// Adds a pass's image to a run's sum (`Run::pass` and the tallied run: the same sums).
pub fn add_pass(sum: &mut Image, image: &Image) {
    for (s, v) in sum.data.iter_mut().zip(&image.data) {
        for c in 0..3 {
            s[c] += v[c];
        }
    }
}

/// Work items per splat chunk (fixed: the image does not depend on the thread count).
const CHUNK: u64 = 256;

/// Per-thread buffers.
pub struct Scratch {
    camera: CameraScratch,
    light: Subpath,
}

/// What a pass decided: the technique set with its η's, the radii, M.
#[derive(Clone, Copy, Debug)]
pub struct PassSetup {
    pub set: VolumeSet,
    pub r_points: f32,
    pub r_beams: f32,
    pub r_beam_beams: f32,
    pub light_paths: u64,
}

impl PassSetup {
    fn data<'a>(&self, upbp: &Upbp, scene: &Scene, store: &'a LightStore) -> PassData<'a> {
        let m = self.light_paths as f64;
        let norm = |eta: f64| if eta > 0.0 { (1.0 / eta) as f32 } else { 0.0 };
        PassData {
            store,
            set: self.set,
            h: upbp.params.mis,
            ratio: m / scene.camera.pixel_count() as f64,
            max_k: upbp.params.volume.max_depth as usize,
            r_points: self.r_points,
            r_beams: self.r_beams,
            r_beam_beams: self.r_beam_beams,
            point_norm: norm(self.set.points_eta),
            beam_norm: norm(self.set.beams_eta),
            beam_beam_norm: norm(self.set.beam_beams_eta),
            surface_norm: norm(self.set.surface_eta),
            beam_point_norm: norm(self.set.beam_points_eta),
            needs: Needs::of(&self.set),
        }
    }
}

impl Progressive for Upbp {
    fn name(&self) -> &'static str {
        "upbp"
    }

    fn start<'a>(&'a self, scene: &'a Scene, seed: u64) -> Box<dyn ProgressiveRun + 'a> {
        let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
        Box::new(Run {
            upbp: self,
            scene,
            seed,
            sum: Image::new(w, h),
            passes: 0,
            log: ProgressLog::default(),
        })
    }
}

/// A run of `upbp`: the sum of its pass images.
struct Run<'a> {
    upbp: &'a Upbp,
    scene: &'a Scene,
    seed: u64,
    sum: Image,
    passes: u32,
    log: ProgressLog,
}

impl ProgressiveRun for Run<'_> {
    fn pass(&mut self, pass: u32) -> u64 {
        let (store, setup) = self.upbp.setup(self.scene, self.seed, pass);
        let data = setup.data(self.upbp, self.scene, &store);
        let p = Pass {
            seed: self.seed,
            pass,
        };
        let (image, invalid) = self.upbp.render_pass(self.scene, &data, p);
        add_pass(&mut self.sum, &image);
        self.passes += 1;
        let r1 = self.upbp.params.volume.radius as f64;
        self.log.photon_paths.push(setup.light_paths);
        self.log.radius_scale.push(setup.r_beams as f64 / r1);
        self.log.mean_radius.push(setup.r_beams as f64);
        self.log.facts.retain(|(k, _)| !k.starts_with("last pass"));
        self.log.facts.push((
            "last pass volume photons".into(),
            format!(
                "{} (r_P {:.4e}, r_B {:.4e})",
                store.photons.len(),
                setup.r_points,
                setup.r_beams
            ),
        ));
        if let Some(b) = &store.light_beams {
            self.log.facts.push((
                "last pass photon beams".into(),
                format!(
                    "{} (r_BB {:.4e}, {} bytes with index)",
                    b.beams.len(),
                    setup.r_beam_beams,
                    b.bytes()
                ),
            ));
        }
        invalid
    }

    fn estimate(&self) -> Image {
        self.sum.mean_of_passes(self.passes)
    }

    fn log(&self) -> ProgressLog {
        self.log.clone()
    }
}

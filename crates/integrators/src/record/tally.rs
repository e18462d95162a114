//! Per-technique cost and second moment (issue 25, item 1): what each technique of `bdpt`,
//! `lvc-bdpt`, `vcm`, `bpm` and `upbp` costs in time and what it adds to the image and to its noise.
//! A `Tally` is a `Recorder`: the integrator renders its pass exactly as always (same random
//! numbers, same sums in the same order, same image bits — `tally_run` returns the image, and
//! the tests compare it bit for bit with `render`'s), and hears of every weighted contribution
//! and of every lap of time. Rendering with `NoRecord` compiles all of it away.
//!
//! **Techniques.** A connection (s, t): s light vertices, t camera vertices, k = s + t − 1
//! segments — s = 0 emission hits (t = k + 1), s = 1 next-event estimation, t = 1 light-tracing
//! splats; a merge at camera vertex count t (all light lengths of one range query together);
//! upbp's volumetric merges by family (PP3D, PB2D, BP2D, BB1D) and camera vertex count t.
//! Beside them two shared costs: the light walk (`bdpt`: per item; `lvc-bdpt`: the cache;
//! `vcm`/`bpm`: light subpaths, their MIS records and the merge grid) and the camera walk.
//!
//! **Moments.** In one pass, technique τ's estimate of pixel j is F_τ(j): the sum of the
//! MIS-weighted contributions τ made to pixel j (its one camera sample's, or for light tracing
//! every splat that lands in j, spread by the film filter as the splat is), channel mean, times
//! the film weight. Σ_τ F_τ(j) is the pass image. The pass's mean and second moment of τ are
//! the averages over pixels of F_τ(j) and F_τ(j)²; a run averages them over its passes. Intervals
//! come from independent runs (the `techniques` study), never from the passes of one run.
//!
//! **Time.** Reading a clock around every attempt of every technique costs about as much as a
//! cheap attempt (an emission check, a blocked shadow ray's setup) and would distort what it
//! measures. So a work item (one light subpath and one camera sample) is timed with probability
//! 1/`every`, decided by a hash of (item, pass) — not every k-th item, which at a width that is
//! a multiple of k would time the same image columns in every pass. A timed item reads the
//! time-stamp counter (`rdtsc`: invariant TSC on x86-64, tens of cycles; `Instant` elsewhere)
//! once per lap, and each lap's cycles go to the technique the code since the previous lap ran;
//! untimed items read no clock. A technique's time in the pass is its timed cycles × (items /
//! timed items), in seconds by the pass's own ticks per wall second. Phases outside the items
//! (`lvc-bdpt`'s cache, `vcm`'s light subpaths and grid) are timed once per pass. What no lap
//! covers — splat sums, the end of each item — is the pass's CPU time minus the attributed
//! time, reported as `other`. The pass and its phases are timed by the CPU clocks of the pool's
//! threads (`pool_cpu_seconds`), so other work on a shared machine is not counted; a lap is a
//! stretch of wall time, microseconds long, and a lap in which the thread was descheduled is
//! dropped with its item (`VOID_LAP`).

use crate::film::splat::{splat_pass_with, Splats};
use crate::record::{Completed, Merged, Recorder, VolumeFamily, VolumeMerged, Work};
use lt_core::camera::FilmFilter;
use lt_core::math::is_valid_color;
use lt_core::{Color, Scene};
use lt_estimators::Image;
use std::collections::BTreeMap;
use std::sync::Mutex;
use std::time::Instant;

/// The time-stamp counter (x86-64), or nanoseconds since the first call elsewhere.
#[inline]
fn ticks() -> u64 {
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: RDTSC has no preconditions on x86-64.
        #[allow(unused_unsafe)]
        unsafe {
            core::arch::x86_64::_rdtsc()
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        static EPOCH: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
        EPOCH.get_or_init(Instant::now).elapsed().as_nanos() as u64
    }
}

/// CPU seconds of every thread of the current pool, summed (`cpu_clock`): what a pass or phase
/// costs on a machine shared with other work (wall seconds would count the other work too).
pub fn pool_cpu_seconds() -> f64 {
    crate::record::cpu_clock::current_pool_cpu_time().as_secs_f64()
}

/// A 64-bit mix (SplitMix64's finaliser): which items are timed.
#[inline]
fn mix(mut x: u64) -> u64 {
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// The channel mean of a contribution.
#[inline]
fn grey(c: Color) -> f64 {
    (c.x as f64 + c.y as f64 + c.z as f64) / 3.0
}

/// Ticks (≈ 1 ms at 2–4 GHz) beyond which a lap is taken to contain a context switch or an
/// interrupt, not work: one technique attempt at the film sizes studied takes microseconds.
const VOID_LAP: u64 = 1 << 22;

/// The tally of one chunk of work items (one per thread at a time; chunks are merged in order).
pub struct Tally<'a> {
    film: &'a FilmFilter,
    width: u32,
    height: u32,
    every: u64,
    pass: u32,
    pixel: u32,
    film_weight: f32,
    timing: bool,
    last: u64,
    items: u64,
    timed_items: u64,
    cycles: Vec<(Work, u64)>,
    /// The laps of the item being timed, committed when it ends unless one of them was void.
    pending: Vec<(Work, u64)>,
    void: bool,
    /// (technique, pixel, weighted contribution).
    entries: Vec<(Work, u32, f64)>,
}

impl<'a> Tally<'a> {
    pub fn new(scene: &'a Scene, pass: u32, every: u64) -> Tally<'a> {
        Tally {
            film: scene.camera.film(),
            width: scene.camera.width,
            height: scene.camera.height,
            every,
            pass,
            pixel: 0,
            film_weight: 1.0,
            timing: false,
            last: 0,
            items: 0,
            timed_items: 0,
            cycles: Vec::new(),
            pending: Vec::new(),
            void: false,
            entries: Vec::new(),
        }
    }

    /// Ends the timed item: its laps count, unless one was longer than `VOID_LAP` (the thread was
    /// descheduled or the machine busy — one such lap, multiplied by `every`, would swamp the
    /// technique it fell in); then the item counts as untimed.
    fn commit(&mut self) {
        if !self.timing {
            return;
        }
        self.timing = false;
        if std::mem::take(&mut self.void) {
            self.pending.clear();
            return;
        }
        self.timed_items += 1;
        for (work, c) in self.pending.drain(..) {
            match self.cycles.iter_mut().find(|(w, _)| *w == work) {
                Some(e) => e.1 += c,
                None => self.cycles.push((work, c)),
            }
        }
    }
}

impl Recorder for Tally<'_> {
    const ACTIVE: bool = true;

    fn completed(&mut self, p: Completed) {
        let c = p.value * p.weight as f32;
        if p.weight == 0.0 || !is_valid_color(c) {
            return;
        }
        let k = p.light.len() + p.camera.len() - 1;
        let t = k + 1 - p.s;
        let work = Work::Connection {
            s: p.s as u16,
            t: t as u16,
        };
        if t == 1 {
            // A splat, where the film puts it.
            let v = grey(p.value) * p.weight;
            if self.film.filter.is_pixel_box() {
                let x = (p.raster.x as u32).min(self.width - 1);
                let y = (p.raster.y as u32).min(self.height - 1);
                self.entries.push((work, y * self.width + x, v));
            } else {
                let entries = &mut self.entries;
                self.film
                    .for_each_splat(p.raster, |i, w| entries.push((work, i, v * w as f64)));
            }
        } else {
            let v = grey(p.value) * p.weight * self.film_weight as f64;
            self.entries.push((work, self.pixel, v));
        }
    }

    fn merged(&mut self, p: Merged) {
        if p.weight == 0.0 || !is_valid_color(p.value * p.weight as f32) {
            return;
        }
        let work = Work::Merge {
            t: p.camera.len() as u16,
        };
        let v = grey(p.value) * p.weight * self.film_weight as f64;
        self.entries.push((work, self.pixel, v));
    }

    fn volume_merged(&mut self, p: VolumeMerged) {
        if p.weight == 0.0 || !is_valid_color(p.value * p.weight as f32) {
            return;
        }
        let Some(work) = VolumeFamily::work_of(p.technique, p.camera.len() as u16) else {
            return;
        };
        let v = grey(p.value) * p.weight * self.film_weight as f64;
        self.entries.push((work, self.pixel, v));
    }

    #[inline]
    fn begin_item(&mut self, item: u64) {
        self.commit();
        self.items += 1;
        self.timing =
            self.every > 0 && mix(item ^ ((self.pass as u64) << 40)).is_multiple_of(self.every);
        if self.timing {
            self.last = ticks();
        }
    }

    #[inline]
    fn begin_sample(&mut self, pixel: u64, film_weight: f32) {
        self.pixel = pixel as u32;
        self.film_weight = film_weight;
    }

    #[inline]
    fn lap(&mut self, work: Work) {
        if self.timing {
            let now = ticks();
            let c = now.wrapping_sub(self.last);
            self.void |= c > VOID_LAP;
            self.pending.push((work, c));
            self.last = now;
        }
    }
}

/// One technique's figures in one pass (or averaged over a run's passes).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TechniqueFigures {
    /// Mean over pixels of F_τ(j).
    pub mean: f64,
    /// Mean over pixels of F_τ(j)².
    pub second_moment: f64,
    /// Seconds the technique took in the pass (summed over threads).
    pub seconds: f64,
}

/// What one pass tallied.
#[derive(Clone, Debug, Default)]
pub struct PassTally {
    pub techniques: BTreeMap<Work, TechniqueFigures>,
    /// The pass's CPU seconds (every thread of the pool).
    pub seconds: f64,
    /// Seconds no lap and no phase covers.
    pub other_seconds: f64,
    /// Mean over pixels and channels of the pass image.
    pub image_mean: f64,
    /// Items timed / items run.
    pub timed_fraction: f64,
}

/// A pass's clock: started before its first phase.
pub struct PassClock {
    t0: Instant,
    c0: u64,
    cpu0: f64,
}

impl PassClock {
    pub fn start() -> PassClock {
        PassClock {
            t0: Instant::now(),
            c0: ticks(),
            cpu0: pool_cpu_seconds(),
        }
    }
}

/// A splatting pass (as `splat_pass_with`, whose sums it reuses unchanged) whose work items
/// report to a `Tally` per chunk; returns the image, the invalid count and the merged tally.
pub fn tallied_pass<S>(
    scene: &Scene,
    pass: u32,
    every: u64,
    (items, chunk): (u64, u64),
    init: impl Fn() -> S + Sync,
    work: impl Fn(u64, &mut Splats, &mut S, &mut Tally) + Sync,
) -> (Image, u64, ItemTally) {
    let cam = &scene.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let done: Mutex<Vec<(u64, ChunkResult)>> = Mutex::new(Vec::new());
    let (img, invalid) = splat_pass_with(
        w,
        h,
        items,
        chunk,
        || Holder {
            state: init(),
            tally: Tally::new(scene, pass, every),
            first: None,
            done: &done,
        },
        |i, splats, hold| {
            hold.first.get_or_insert(i);
            work(i, splats, &mut hold.state, &mut hold.tally)
        },
    );
    let mut chunks = done.into_inner().unwrap_or_else(|e| e.into_inner());
    chunks.sort_by_key(|c| c.0);
    let mut cycles: BTreeMap<Work, u64> = BTreeMap::new();
    let mut f: BTreeMap<Work, Vec<f64>> = BTreeMap::new();
    let (mut n_items, mut n_timed) = (0u64, 0u64);
    for (_, c) in chunks {
        n_items += c.items;
        n_timed += c.timed_items;
        for (wk, cy) in c.cycles {
            *cycles.entry(wk).or_default() += cy;
        }
        for (wk, px, v) in c.entries {
            f.entry(wk).or_insert_with(|| vec![0.0; w * h])[px as usize] += v;
        }
    }
    let npx = (w * h).max(1) as f64;
    let moments = f
        .into_iter()
        .map(|(wk, px)| {
            let (s1, s2) = px.iter().fold((0.0, 0.0), |(a, b), v| (a + v, b + v * v));
            (wk, (s1 / npx, s2 / npx))
        })
        .collect();
    let image_mean = img.data.iter().map(|p| p[0] + p[1] + p[2]).sum::<f64>() / (3.0 * npx);
    let tally = ItemTally {
        cycles,
        moments,
        items: n_items,
        timed_items: n_timed,
        image_mean,
    };
    (img, invalid, tally)
}

struct ChunkResult {
    items: u64,
    timed_items: u64,
    cycles: Vec<(Work, u64)>,
    entries: Vec<(Work, u32, f64)>,
}

/// A chunk's scratch state and tally; hands the tally over when the chunk ends.
struct Holder<'a, 's, S> {
    state: S,
    tally: Tally<'s>,
    first: Option<u64>,
    done: &'a Mutex<Vec<(u64, ChunkResult)>>,
}

impl<S> Drop for Holder<'_, '_, S> {
    fn drop(&mut self) {
        let Some(first) = self.first else {
            return;
        };
        let t = &mut self.tally;
        t.commit();
        let r = ChunkResult {
            items: t.items,
            timed_items: t.timed_items,
            cycles: std::mem::take(&mut t.cycles),
            entries: std::mem::take(&mut t.entries),
        };
        if let Ok(mut d) = self.done.lock() {
            d.push((first, r));
        }
    }
}

/// The items' share of a pass's tally, before the clock stops.
pub struct ItemTally {
    cycles: BTreeMap<Work, u64>,
    moments: BTreeMap<Work, (f64, f64)>,
    items: u64,
    timed_items: u64,
    image_mean: f64,
}

impl ItemTally {
    /// The pass's tally, with `phases` timed outside the items (CPU seconds).
    pub fn finish(self, clock: PassClock, phases: &[(Work, f64)]) -> PassTally {
        let wall = clock.t0.elapsed().as_secs_f64();
        let ticks_per_second = ticks().wrapping_sub(clock.c0) as f64 / wall.max(1e-12);
        let scale = if self.timed_items > 0 {
            self.items as f64 / self.timed_items as f64
        } else {
            0.0
        };
        let mut techniques: BTreeMap<Work, TechniqueFigures> = BTreeMap::new();
        for (wk, (m, q)) in self.moments {
            let e = techniques.entry(wk).or_default();
            e.mean = m;
            e.second_moment = q;
        }
        for (wk, c) in self.cycles {
            techniques.entry(wk).or_default().seconds += c as f64 * scale / ticks_per_second;
        }
        for &(wk, s) in phases {
            techniques.entry(wk).or_default().seconds += s;
        }
        let seconds = pool_cpu_seconds() - clock.cpu0;
        let attributed: f64 = techniques.values().map(|t| t.seconds).sum();
        PassTally {
            techniques,
            seconds,
            other_seconds: seconds - attributed,
            image_mean: self.image_mean,
            timed_fraction: self.timed_items as f64 / self.items.max(1) as f64,
        }
    }
}

/// One run's tallies: per-pass figures averaged over its passes.
#[derive(Clone, Debug, Default)]
pub struct RunTally {
    pub passes: u32,
    pub techniques: BTreeMap<Work, TechniqueFigures>,
    /// Per pass.
    pub seconds: f64,
    pub other_seconds: f64,
    pub image_mean: f64,
    pub timed_fraction: f64,
}

impl RunTally {
    pub(crate) fn add(&mut self, p: &PassTally) {
        let n = self.passes as f64;
        let avg = |a: f64, b: f64| (a * n + b) / (n + 1.0);
        for (wk, f) in &p.techniques {
            let e = self.techniques.entry(*wk).or_default();
            e.mean += f.mean;
            e.second_moment += f.second_moment;
            e.seconds += f.seconds;
        }
        self.seconds = avg(self.seconds, p.seconds);
        self.other_seconds = avg(self.other_seconds, p.other_seconds);
        self.image_mean = avg(self.image_mean, p.image_mean);
        self.timed_fraction = avg(self.timed_fraction, p.timed_fraction);
        self.passes += 1;
    }

    /// Sums to per-pass averages (a technique absent from a pass counts as zero there).
    pub(crate) fn close(&mut self) {
        let n = self.passes.max(1) as f64;
        for f in self.techniques.values_mut() {
            f.mean /= n;
            f.second_moment /= n;
            f.seconds /= n;
        }
    }
}

/// A short name of a technique for tables: `s=2,t=3`, `merge t=2`, `light walk`, `camera walk`.
pub fn label(w: Work) -> String {
    match w {
        Work::LightWalk => "light walk".into(),
        Work::CameraWalk => "camera walk".into(),
        Work::Connection { s, t } => format!("s={s},t={t}"),
        Work::Merge { t } => format!("merge t={t}"),
        Work::VolumeMerge { family, t } => format!("{} t={t}", family.name()),
    }
}

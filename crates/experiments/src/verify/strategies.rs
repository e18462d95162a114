//! Veach's "path pyramid" for `bdpt` (Veach 1997, fig. 10.3): the image split by path length
//! k and strategy (s, t), s + t − 1 = k, each both as MIS-weighted contribution (the weighted
//! images of one length sum to that length's part of the bdpt image) and unweighted (each alone
//! an unbiased estimate of the length-k image wherever the strategy can sample the path).
//!
//! Design. A pyramid pass runs exactly `Bdpt::render_pass`'s work — the same work items in the
//! same fixed chunks through `splat_pass_with` — with a recorder attached, so the pass's main
//! image is the bdpt image bit for bit (a test holds it to `Bdpt::render_pass`) and is
//! computed once, not re-rendered. Each chunk's recorder keeps the completed paths it saw as
//! (work item, strategy, pixel, value, weight) records; when the chunk's state is dropped they go
//! to a shared list, which is put back into work-item order before the records are summed (f64)
//! into per-strategy pass images, so the strategy images too are independent of the thread count.
//! [`PyramidIntegrator`] wraps this as an `Integrator`, so `lt render` runs it under the ordinary
//! pass loop (time budget, checkpoints, Ctrl-C) and each pass's strategy images go into
//! `RunningImage`s: the standard error of a strategy image is the spread of its passes.

use crate::image_io::{write_atomic, write_exr, write_png_preview};
use lt_core::math::is_valid_color;
use lt_core::{Color, Scene};
use lt_estimators::running::{RunningImage, RunningStat};
use lt_estimators::Image;
use lt_integrators::bdpt::{Bdpt, BdptParams, Scratch};
use lt_integrators::params::ParamReader;
use lt_integrators::record::{Completed, Recorder};
use lt_integrators::splat::splat_pass_with;
use lt_integrators::splat::{Pass, Worker};
use lt_integrators::{
    render, EstimatorRef, Integrator, IntegratorParams, PassReport, RenderOptions, RenderResult,
};
use std::fmt::Write as _;
use std::ops::ControlFlow;
use std::path::Path;
use std::sync::Mutex;

/// Default longest path length of the pyramid (`--strategy-length`).
pub const DEFAULT_LENGTH: usize = 5;

/// Work items per chunk. Must be bdpt's own chunk size for the main image to be bdpt's bit for
/// bit; `tests/strategies.rs` checks that it is.
const CHUNK: u64 = 256;

/// One strategy: s light vertices, t camera vertices, k = s + t − 1 segments.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Strategy {
    pub k: usize,
    pub s: usize,
    pub t: usize,
}

impl Strategy {
    /// File stem, `k{k}_s{s}_t{t}`.
    pub fn stem(&self) -> String {
        format!("k{}_s{}_t{}", self.k, self.s, self.t)
    }

    /// Tile label, `s=…,t=…`.
    pub fn label(&self) -> String {
        format!("s={},t={}", self.s, self.t)
    }
}

/// Every strategy with 1 ≤ k ≤ `max_length`, by k then s (the order of all per-strategy vectors).
pub fn strategies(max_length: usize) -> Vec<Strategy> {
    (1..=max_length)
        .flat_map(|k| (0..=k).map(move |s| Strategy { k, s, t: k + 1 - s }))
        .collect()
}

/// Position of (k, s) in [`strategies`]: lengths below k contribute 2 + 3 + … + k entries.
pub fn strategy_index(k: usize, s: usize) -> usize {
    debug_assert!(k >= 1 && s <= k);
    k * (k + 1) / 2 - 1 + s
}

/// Builds bdpt from `params` (the same keys `lt render -i bdpt` takes).
pub fn make_bdpt(scene: &Scene, params: &IntegratorParams) -> Result<Bdpt, String> {
    let reader = ParamReader::new("bdpt", params);
    let p = BdptParams::read(scene, &reader)?;
    reader.finish()?;
    Ok(Bdpt { params: p })
}

/// One completed path as a chunk recorded it.
struct Record {
    item: u64,
    strategy: u32,
    pixel: u32,
    value: Color,
    weight: f64,
}

struct StrategyRecorder {
    item: u64,
    width: u32,
    height: u32,
    max_length: usize,
    records: Vec<Record>,
    invalid: u64,
}

impl Recorder for StrategyRecorder {
    const ACTIVE: bool = true;

    fn completed(&mut self, p: Completed) {
        // s ≥ 1: x0 … x_{s−1} and x_s … x_k. s = 0: `light` is the single x0 the camera walk
        // reached and `camera` x_k … x_1, so the same count gives k = camera.len().
        let k = p.light.len() + p.camera.len() - 1;
        if k == 0 || k > self.max_length || p.s > k {
            return;
        }
        if !(is_valid_color(p.value) && p.weight.is_finite() && p.weight >= 0.0) {
            self.invalid += 1;
            return;
        }
        if p.value == Color::ZERO {
            return;
        }
        let x = (p.raster.x as u32).min(self.width - 1);
        let y = (p.raster.y as u32).min(self.height - 1);
        self.records.push(Record {
            item: self.item,
            strategy: strategy_index(k, p.s) as u32,
            pixel: y * self.width + x,
            value: p.value,
            weight: p.weight,
        });
    }
}

type Sink = Mutex<Vec<(Vec<Record>, u64)>>;

/// Per-chunk state of `splat_pass_with`: bdpt's buffers and the recorder, whose records go to
/// the sink when the chunk is done (the state is dropped).
struct ChunkState<'a> {
    scratch: Scratch,
    rec: StrategyRecorder,
    sink: &'a Sink,
}

impl Drop for ChunkState<'_> {
    fn drop(&mut self) {
        let records = std::mem::take(&mut self.rec.records);
        let entry = (records, self.rec.invalid);
        self.sink
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(entry);
    }
}

/// One pass: bdpt's image and every strategy's weighted and unweighted image.
pub struct PyramidPass {
    /// Exactly `Bdpt::render_pass(scene, seed, pass)` (all lengths up to max_depth).
    pub main: Image,
    /// Samples bdpt dropped as invalid.
    pub main_invalid: u64,
    /// Per strategy, in [`strategies`] order: Σ weight · value per pixel (f64).
    pub weighted: Vec<Image>,
    /// Per strategy: Σ value per pixel.
    pub unweighted: Vec<Image>,
    /// Recorded paths dropped as invalid (NaN, infinite or negative value or weight).
    pub invalid: u64,
}

/// Pass `pass` of bdpt with every path of length ≤ `max_length` sorted into its strategy image.
pub fn pyramid_pass(
    bdpt: &Bdpt,
    scene: &Scene,
    seed: u64,
    pass: u32,
    max_length: usize,
) -> PyramidPass {
    let cam = &scene.camera;
    let (w, h) = (cam.width, cam.height);
    let n = cam.pixel_count() as u64;
    let items = n.max(bdpt.params.light_paths.unwrap_or(n));
    let sink: Sink = Mutex::new(Vec::new());
    let (main, main_invalid) = splat_pass_with(
        w as usize,
        h as usize,
        items,
        CHUNK,
        || ChunkState {
            scratch: bdpt.scratch(),
            rec: StrategyRecorder {
                item: 0,
                width: w,
                height: h,
                max_length,
                records: Vec::new(),
                invalid: 0,
            },
            sink: &sink,
        },
        |i, splats, st| {
            st.rec.item = i;
            let mut worker = Worker {
                splats,
                scratch: &mut st.scratch,
                rec: &mut st.rec,
            };
            bdpt.item(scene, Pass { seed, pass }, i, &mut worker);
        },
    );
    let mut lists = sink.into_inner().unwrap_or_else(|e| e.into_inner());
    // Chunks cover disjoint item ranges in increasing order within each; order the lists by their
    // first item, and fall back to a stable sort of everything should that not give item order.
    lists.sort_by_key(|(r, _)| r.first().map_or(u64::MAX, |r| r.item));
    let invalid = lists.iter().map(|(_, bad)| bad).sum();
    let mut records: Vec<Record> = lists.into_iter().flat_map(|(r, _)| r).collect();
    if !records.windows(2).all(|p| p[0].item <= p[1].item) {
        records.sort_by_key(|r| r.item);
    }
    let count = strategies(max_length).len();
    let mut weighted = vec![Image::new(w as usize, h as usize); count];
    let mut unweighted = weighted.clone();
    for r in &records {
        let (i, p) = (r.strategy as usize, r.pixel as usize);
        let v = [r.value.x as f64, r.value.y as f64, r.value.z as f64];
        let (pw, pu) = (&mut weighted[i].data[p], &mut unweighted[i].data[p]);
        for c in 0..3 {
            pw[c] += v[c] * r.weight;
            pu[c] += v[c];
        }
    }
    PyramidPass {
        main,
        main_invalid,
        weighted,
        unweighted,
        invalid,
    }
}

fn image_mean(img: &Image) -> [f64; 3] {
    let mut m = [0.0; 3];
    for p in &img.data {
        for c in 0..3 {
            m[c] += p[c];
        }
    }
    m.map(|v| v / img.data.len().max(1) as f64)
}

/// The strategy images accumulated over passes.
#[derive(Clone, Debug)]
pub struct Pyramid {
    pub max_length: usize,
    pub strategies: Vec<Strategy>,
    pub weighted: Vec<RunningImage>,
    pub unweighted: Vec<RunningImage>,
    /// Per strategy and channel: running statistics of each pass's image mean.
    pub weighted_means: Vec<[RunningStat; 3]>,
    pub unweighted_means: Vec<[RunningStat; 3]>,
    /// The same for bdpt's own image.
    pub main_mean: [RunningStat; 3],
    pub invalid: u64,
}

impl Pyramid {
    pub fn new(width: usize, height: usize, max_length: usize) -> Pyramid {
        let strategies = strategies(max_length);
        let n = strategies.len();
        Pyramid {
            max_length,
            strategies,
            weighted: vec![RunningImage::new(width, height); n],
            unweighted: vec![RunningImage::new(width, height); n],
            weighted_means: vec![[RunningStat::new(); 3]; n],
            unweighted_means: vec![[RunningStat::new(); 3]; n],
            main_mean: [RunningStat::new(); 3],
            invalid: 0,
        }
    }

    pub fn add(&mut self, pass: &PyramidPass) {
        for i in 0..self.strategies.len() {
            self.weighted[i].add(&pass.weighted[i]);
            self.unweighted[i].add(&pass.unweighted[i]);
            let (mw, mu) = (
                image_mean(&pass.weighted[i]),
                image_mean(&pass.unweighted[i]),
            );
            for c in 0..3 {
                self.weighted_means[i][c].add(mw[c]);
                self.unweighted_means[i][c].add(mu[c]);
            }
        }
        let m = image_mean(&pass.main);
        for (stat, v) in self.main_mean.iter_mut().zip(m) {
            stat.add(v);
        }
        self.invalid += pass.invalid;
    }

    pub fn passes(&self) -> u64 {
        self.main_mean[0].count()
    }

    /// Index of (k, s).
    pub fn index(&self, k: usize, s: usize) -> usize {
        strategy_index(k, s)
    }
}

/// bdpt whose passes also fill a [`Pyramid`]: its `render_pass` returns bdpt's image unchanged.
pub struct PyramidIntegrator {
    pub bdpt: Bdpt,
    pub max_length: usize,
    acc: Mutex<Pyramid>,
}

impl PyramidIntegrator {
    pub fn new(scene: &Scene, bdpt: Bdpt, max_length: usize) -> PyramidIntegrator {
        let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
        PyramidIntegrator {
            bdpt,
            max_length,
            acc: Mutex::new(Pyramid::new(w, h, max_length)),
        }
    }

    /// Runs `f` on the pyramid accumulated so far.
    pub fn with_pyramid<T>(&self, f: impl FnOnce(&Pyramid) -> T) -> T {
        f(&self.acc.lock().unwrap_or_else(|e| e.into_inner()))
    }

    pub fn into_pyramid(self) -> Pyramid {
        self.acc.into_inner().unwrap_or_else(|e| e.into_inner())
    }
}

impl Integrator for PyramidIntegrator {
    fn name(&self) -> &'static str {
        "bdpt"
    }

    fn render_pass(&self, scene: &Scene, seed: u64, pass: u32) -> (Image, u64) {
        let p = pyramid_pass(&self.bdpt, scene, seed, pass, self.max_length);
        self.acc.lock().unwrap_or_else(|e| e.into_inner()).add(&p);
        (p.main, p.main_invalid)
    }
}

/// Renders bdpt with `params` under the ordinary pass loop and returns its result with the
/// pyramid of strategies of length ≤ `max_length` over the same passes.
pub fn render_pyramid(
    scene: &Scene,
    params: &IntegratorParams,
    opts: &RenderOptions,
    max_length: usize,
    on_pass: impl FnMut(&PassReport) -> ControlFlow<()>,
) -> Result<(RenderResult, Pyramid), String> {
    let integ = PyramidIntegrator::new(scene, make_bdpt(scene, params)?, max_length);
    let result = render(scene, EstimatorRef::Unbiased(&integ), opts, on_pass)?;
    Ok((result, integ.into_pyramid()))
}

/// What the written files say about how the pyramid was made.
#[derive(Clone, Debug, Default)]
pub struct PyramidMeta {
    pub scene: String,
    pub seed: u64,
    pub max_depth: u32,
}

/// Writes the pyramid into `dir` (created if missing): per strategy `k{k}_s{s}_t{t}` with
/// `.weighted.exr`, `.unweighted.exr`, `.weighted.stderr.exr`, `.unweighted.stderr.exr`; the
/// tiled `pyramid.png`; `README.md` listing the tiles; `strategies.json` with image means.
pub fn write_pyramid(dir: &Path, pyr: &Pyramid, meta: &PyramidMeta) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let means: Vec<Image> = pyr.weighted.iter().map(RunningImage::mean).collect();
    for (i, st) in pyr.strategies.iter().enumerate() {
        let stem = st.stem();
        write_exr(&dir.join(format!("{stem}.weighted.exr")), &means[i])?;
        write_exr(
            &dir.join(format!("{stem}.weighted.stderr.exr")),
            &pyr.weighted[i].std_error(),
        )?;
        write_exr(
            &dir.join(format!("{stem}.unweighted.exr")),
            &pyr.unweighted[i].mean(),
        )?;
        write_exr(
            &dir.join(format!("{stem}.unweighted.stderr.exr")),
            &pyr.unweighted[i].std_error(),
        )?;
    }
    let exposure = auto_exposure(&means);
    let sheet = pyramid_sheet(pyr, &means, exposure);
    write_png_preview(&dir.join("pyramid.png"), &sheet.image)?;
    write_atomic(
        &dir.join("README.md"),
        readme(pyr, meta, exposure, &sheet).as_bytes(),
    )?;
    let json = summary_json(pyr, meta, exposure);
    write_atomic(
        &dir.join("strategies.json"),
        serde_json::to_string_pretty(&json).unwrap().as_bytes(),
    )
}

fn luminance(p: [f64; 3]) -> f64 {
    0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
}

/// One exposure for every tile, so tiles compare: the 99th percentile of the positive luminances
/// over all weighted images maps to 1.
fn auto_exposure(images: &[Image]) -> f64 {
    let mut lum: Vec<f64> = images
        .iter()
        .flat_map(|img| img.data.iter().map(|&p| luminance(p)))
        .filter(|l| *l > 0.0 && l.is_finite())
        .collect();
    if lum.is_empty() {
        return 1.0;
    }
    let q = ((lum.len() - 1) as f64 * 0.99) as usize;
    let (_, v, _) = lum.select_nth_unstable_by(q, |a, b| a.total_cmp(b));
    1.0 / *v
}

/// The laid-out pyramid and where each tile went.
struct Sheet {
    image: Image,
    /// Per strategy: top-left corner of its tile.
    corners: Vec<(usize, usize)>,
    tile: (usize, usize),
}

/// Veach's layout: row k (top k = 1) holds the k + 1 tiles s = 0 … k, centred, each labelled
/// `s=…,t=…` beneath; `k=…` at the left of the row.
fn pyramid_sheet(pyr: &Pyramid, means: &[Image], exposure: f64) -> Sheet {
    let (w, h) = (means[0].width, means[0].height);
    // Tiles about 128–320 px: box-filtered down, or pixel-replicated up.
    let big = w.max(h);
    let (down, up) = if big > 320 {
        (big.div_ceil(320), 1)
    } else if big < 128 {
        (1, 128usize.div_ceil(big))
    } else {
        (1, 1)
    };
    let (tw, th) = ((w / down).max(1) * up, (h / down).max(1) * up);
    let label_scale = if tw >= 8 * 6 * 2 { 2 } else { 1 };
    let (gap, label_h) = (8, 7 * label_scale + 8);
    let left = 3 * 6 * 2 + 2 * gap;
    let l = pyr.max_length;
    let width = left + (l + 1) * (tw + gap) + gap;
    let height = gap + l * (th + label_h + gap);
    let background = [0.01; 3];
    let mut img = Image::from_fn(width, height, |_, _| background);
    let mut corners = Vec::new();
    for (i, st) in pyr.strategies.iter().enumerate() {
        let y0 = gap + (st.k - 1) * (th + label_h + gap);
        let x0 = left + (l - st.k) * (tw + gap) / 2 + st.s * (tw + gap);
        corners.push((x0, y0));
        for ty in 0..th {
            for tx in 0..tw {
                let (sx, sy) = ((tx / up) * down, (ty / up) * down);
                let mut acc = [0.0; 3];
                let mut n = 0.0;
                for y in sy..(sy + down).min(h) {
                    for x in sx..(sx + down).min(w) {
                        let p = means[i].get(x, y);
                        for c in 0..3 {
                            acc[c] += p[c];
                        }
                        n += 1.0;
                    }
                }
                img.data[(y0 + ty) * width + x0 + tx] = acc.map(|v| v / n * exposure);
            }
        }
        let text = st.label();
        let text_w = text.len() * 6 * label_scale;
        let tx = x0 + tw.saturating_sub(text_w) / 2;
        draw_text(&mut img, tx, y0 + th + 4, &text, label_scale);
        if st.s == 0 {
            // Just left of the row's first tile (`left` leaves room for it on the widest row).
            let label_x = x0 - 3 * 6 * 2 - gap;
            draw_text(
                &mut img,
                label_x,
                y0 + th / 2 - 7,
                &format!("k={}", st.k),
                2,
            );
        }
    }
    Sheet {
        image: img,
        corners,
        tile: (tw, th),
    }
}

/// 5×7 glyphs of the characters labels use (rows top first, bit 4 = leftmost column).
fn glyph(c: char) -> [u8; 7] {
    match c {
        '0' => [0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E],
        '1' => [0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E],
        '2' => [0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F],
        '3' => [0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E],
        '4' => [0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02],
        '5' => [0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E],
        '6' => [0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E],
        '7' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08],
        '8' => [0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E],
        '9' => [0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C],
        's' => [0x00, 0x00, 0x0E, 0x10, 0x0E, 0x01, 0x1E],
        't' => [0x08, 0x08, 0x1C, 0x08, 0x08, 0x09, 0x06],
        'k' => [0x10, 0x10, 0x12, 0x14, 0x18, 0x14, 0x12],
        '=' => [0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00],
        ',' => [0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08],
        _ => [0; 7],
    }
}

/// White text with its top-left corner at (x, y), each font pixel `scale`² image pixels; what
/// falls outside the image is clipped.
fn draw_text(img: &mut Image, x: usize, y: usize, text: &str, scale: usize) {
    for (n, ch) in text.chars().enumerate() {
        let g = glyph(ch);
        for (row, bits) in g.iter().enumerate() {
            for col in 0..5 {
                if bits & (0x10 >> col) == 0 {
                    continue;
                }
                for dy in 0..scale {
                    for dx in 0..scale {
                        let px = x + (n * 6 + col) * scale + dx;
                        let py = y + row * scale + dy;
                        if px < img.width && py < img.height {
                            img.data[py * img.width + px] = [1.0; 3];
                        }
                    }
                }
            }
        }
    }
}

fn rgb(v: [f64; 3]) -> String {
    format!("{:.6} {:.6} {:.6}", v[0], v[1], v[2])
}

fn stat_means(s: &[RunningStat; 3]) -> [f64; 3] {
    [s[0].mean(), s[1].mean(), s[2].mean()]
}

fn stat_errors(s: &[RunningStat; 3]) -> [f64; 3] {
    [s[0].std_error(), s[1].std_error(), s[2].std_error()]
}

fn readme(pyr: &Pyramid, meta: &PyramidMeta, exposure: f64, sheet: &Sheet) -> String {
    let mut r = String::new();
    let _ = writeln!(r, "# bdpt path pyramid\n");
    let _ = writeln!(
        r,
        "Scene `{}`, seed {}, {} passes, bdpt max_depth {}, lengths k = 1 … {} \
         (Veach 1997, fig. 10.3).\n",
        meta.scene,
        meta.seed,
        pyr.passes(),
        meta.max_depth,
        pyr.max_length
    );
    let _ = writeln!(
        r,
        "Strategy (s, t): s light-subpath vertices, t camera-subpath vertices, k = s + t − 1 \
         segments. `*.weighted.exr` is the MIS-weighted contribution (per length, the weighted \
         images sum to that length's part of the bdpt image); `*.unweighted.exr` the strategy \
         alone, an unbiased estimate of the length-k image where the strategy can sample the \
         path. `*.stderr.exr`: per-pixel standard error over the passes. Lengths above max_depth \
         are never sampled (zero images).\n"
    );
    let _ = writeln!(
        r,
        "`pyramid.png`: row k (top: k = 1) holds tiles s = 0 … k left to right, each the \
         weighted image times {exposure:.4} (one exposure for all tiles), sRGB, {}×{} px.\n",
        sheet.tile.0, sheet.tile.1
    );
    let _ = writeln!(
        r,
        "| k | s | t | tile at (x, y) | weighted | unweighted | weighted mean (RGB) | unweighted mean (RGB) |"
    );
    let _ = writeln!(r, "|---|---|---|---|---|---|---|---|");
    for (i, st) in pyr.strategies.iter().enumerate() {
        let stem = st.stem();
        let (x, y) = sheet.corners[i];
        let _ = writeln!(
            r,
            "| {} | {} | {} | ({x}, {y}) | `{stem}.weighted.exr` | `{stem}.unweighted.exr` | {} | {} |",
            st.k,
            st.s,
            st.t,
            rgb(stat_means(&pyr.weighted_means[i])),
            rgb(stat_means(&pyr.unweighted_means[i])),
        );
    }
    let _ = writeln!(
        r,
        "\nbdpt image mean (all lengths ≤ max_depth): {}",
        rgb(stat_means(&pyr.main_mean))
    );
    r
}

fn summary_json(pyr: &Pyramid, meta: &PyramidMeta, exposure: f64) -> serde_json::Value {
    let strategies: Vec<_> = pyr
        .strategies
        .iter()
        .enumerate()
        .map(|(i, st)| {
            let stem = st.stem();
            serde_json::json!({
                "k": st.k,
                "s": st.s,
                "t": st.t,
                "weighted": format!("{stem}.weighted.exr"),
                "unweighted": format!("{stem}.unweighted.exr"),
                "weighted_mean": stat_means(&pyr.weighted_means[i]),
                "weighted_mean_stderr": stat_errors(&pyr.weighted_means[i]),
                "unweighted_mean": stat_means(&pyr.unweighted_means[i]),
                "unweighted_mean_stderr": stat_errors(&pyr.unweighted_means[i]),
            })
        })
        .collect();
    let lengths: Vec<_> = (1..=pyr.max_length)
        .map(|k| {
            let mut sum = [0.0; 3];
            for s in 0..=k {
                let m = stat_means(&pyr.weighted_means[strategy_index(k, s)]);
                for c in 0..3 {
                    sum[c] += m[c];
                }
            }
            serde_json::json!({ "k": k, "weighted_mean_sum": sum })
        })
        .collect();
    serde_json::json!({
        "scene": meta.scene,
        "seed": meta.seed,
        "passes": pyr.passes(),
        "max_depth": meta.max_depth,
        "max_length": pyr.max_length,
        "png_exposure": exposure,
        "invalid_records": pyr.invalid,
        "main_mean": stat_means(&pyr.main_mean),
        "main_mean_stderr": stat_errors(&pyr.main_mean),
        "lengths": lengths,
        "strategies": strategies,
    })
}

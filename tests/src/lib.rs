//! Shared helpers of the workspace-level tests.

use lt_core::Scene;
use lt_estimators::blocks::{BlockEstimate, RunningBlocks};
use lt_estimators::running::{RunningImage, RunningStat};
use lt_estimators::Image;
use lt_integrators::{make_integrator, render, IntegratorParams, Kind, RenderOptions};
use lt_scene_io::load_scene;
use std::any::Any;
use std::collections::HashMap;
use std::ops::ControlFlow;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

pub mod per_length;

/// The repository's `scenes/` folder.
pub fn scenes_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenes")
}

/// The file of shipped scene `name`: `scenes/NAME.toml`, or `scenes/NAME.xml` for the media
/// scenes (`media/…`, Mitsuba XML: TOML has no media yet).
pub fn shipped_scene_path(name: &str) -> PathBuf {
    let toml = scenes_dir().join(format!("{name}.toml"));
    if toml.exists() {
        return toml;
    }
    scenes_dir().join(format!("{name}.xml"))
}

/// Loads shipped scene `name` (`shipped_scene_path`), optionally at a smaller resolution.
pub fn shipped_scene(name: &str, resolution: Option<(u32, u32)>) -> Scene {
    let mut scene = load_scene(&shipped_scene_path(name)).unwrap_or_else(|e| panic!("{e}"));
    if let Some((w, h)) = resolution {
        scene.camera = scene.camera.with_resolution(w, h);
    }
    scene
}

/// What `make` returns, made once per test binary for each `key` and shared by every test that
/// asks for the same key (tests run on parallel threads: a second asker waits for the first).
/// The key must name everything the value depends on (scene and its changes, integrator,
/// parameters, passes, seed); asking for one key with two types panics.
pub fn shared<T: Send + Sync + 'static>(key: &str, make: impl FnOnce() -> T) -> Arc<T> {
    type Cell = Arc<OnceLock<Arc<dyn Any + Send + Sync>>>;
    static CELLS: OnceLock<Mutex<HashMap<String, Cell>>> = OnceLock::new();
    let cell = CELLS
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .entry(key.to_string())
        .or_default()
        .clone();
    let value = cell.get_or_init(|| Arc::new(make())).clone();
    value
        .downcast::<T>()
        .unwrap_or_else(|_| panic!("shared value '{key}' asked for with another type"))
}

/// Every shipped scene without media: the `scenes/*.toml` files' names. The media scenes are
/// [`shipped_media_scene_names`], kept apart because only `registry::HANDLES_MEDIA` renders them:
/// a loop over these names may build any integrator on any of them.
pub fn shipped_scene_names() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(scenes_dir())
        .expect("scenes/ exists")
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            e.file_name()
                .to_str()
                .and_then(|n| n.strip_suffix(".toml"))
                .map(str::to_string)
        })
        .collect();
    names.sort();
    names
}

/// Every shipped scene with participating media: `media/NAME` for each `scenes/media/NAME.xml`,
/// sorted. Loops over them render with the integrators of `registry::HANDLES_MEDIA` and hold
/// every other integrator to its refusal ([`media_refusal`]).
pub fn shipped_media_scene_names() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(scenes_dir().join("media"))
        .expect("scenes/media/ exists")
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            e.file_name()
                .to_str()
                .and_then(|n| n.strip_suffix(".xml"))
                .map(|n| format!("media/{n}"))
        })
        .collect();
    names.sort();
    names
}

/// Whether `integrator` is `pt` on scenes without media (`registry::PT_WITHOUT_MEDIA`): the
/// surface loops then hold it to pt's image ([`assert_same_image_as_pt`]) rather than to their
/// own checks, which pt's entry already passes.
pub fn is_pt_without_media(integrator: &str) -> bool {
    lt_integrators::registry::PT_WITHOUT_MEDIA.contains(&integrator)
}

/// Renders `integrator` and `pt` with default keys for one pass (seed 5) on `scene`, a scene
/// without media, and asserts the same image bit for bit and the same invalid-sample count;
/// `who` names the case in the message.
pub fn assert_same_image_as_pt(scene: &Scene, who: &str, integrator: &str) {
    assert!(!scene.has_media, "{who}: the scene has media");
    let image = |name: &str| {
        let integ = make_integrator(name, scene, &IntegratorParams::default())
            .unwrap_or_else(|e| panic!("{who}: {name}: {e}"));
        let opts = RenderOptions {
            passes: 1,
            time_limit: None,
            seed: 5,
            threads: 0,
        };
        let result = render(scene, &integ, &opts, |_| ControlFlow::Continue(())).unwrap();
        let bits: Vec<u64> = (result.estimate.data.iter().flatten())
            .map(|v| v.to_bits())
            .collect();
        (bits, result.invalid_samples)
    };
    let (ours, pts) = (image(integrator), image("pt"));
    assert_eq!(
        ours.1, pts.1,
        "{who}: {integrator}'s invalid samples differ from pt's"
    );
    let first = ours.0.iter().zip(&pts.0).position(|(a, b)| a != b);
    assert!(
        ours.0.len() == pts.0.len() && first.is_none(),
        "{who}: {integrator} is listed in PT_WITHOUT_MEDIA but its image differs from pt's \
         (first at value {first:?}: {:?} against {:?})",
        first.map(|i| f64::from_bits(ours.0[i])),
        first.map(|i| f64::from_bits(pts.0[i]))
    );
}

/// Whether `integrator` renders scenes with media (`registry::HANDLES_MEDIA`).
pub fn handles_media(integrator: &str) -> bool {
    lt_integrators::registry::HANDLES_MEDIA.contains(&integrator)
}

/// For an integrator outside `HANDLES_MEDIA`, checks that it refuses `scene` (which has media) in
/// one line naming itself and participating media, and returns that line; panics if it builds
/// or says anything else (tests/media.rs holds the exact wording).
pub fn media_refusal(integrator: &str, scene: &Scene, scene_name: &str) -> String {
    let made = make_integrator(integrator, scene, &IntegratorParams::default());
    let Err(e) = made else {
        panic!("{integrator} on {scene_name}: built for a scene with media, outside HANDLES_MEDIA");
    };
    assert!(
        !e.contains('\n') && e.contains(integrator) && e.contains("participating media"),
        "{integrator} on {scene_name}: not a one-line media refusal: {e}"
    );
    e
}

/// Independent runs a consistent estimator's block statistics are taken over (its passes are
/// not independent, so their spread is no error bar).
pub const CONSISTENT_RUNS: u32 = 8;

/// What a test render produced.
pub struct Rendered {
    pub kind: Kind,
    /// The image: the mean of the passes (unbiased) or of the runs' estimates (consistent).
    pub estimate: Image,
    pub invalid_samples: u64,
}

/// Renders `passes` passes and returns the image and per-block statistics over independent
/// estimates (feed them to `agreement_t`, which accounts for standard errors estimated from few
/// samples): the passes of an unbiased estimator, or [`CONSISTENT_RUNS`] independent runs of
/// `passes` passes each (seeds `seed`, `seed + 1`, …) of a consistent one. The registry's kind
/// decides, so a loop over the registry picks the right error bars for every integrator.
pub fn render_blocks(
    scene: &Scene,
    integrator: &str,
    params: IntegratorParams,
    passes: u32,
    seed: u64,
    block: usize,
) -> (Rendered, RunningBlocks) {
    let integ = make_integrator(integrator, scene, &params).unwrap();
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let mut blocks = RunningBlocks::new(w, h, block);
    let opts = |seed| RenderOptions {
        passes,
        time_limit: None,
        seed,
        threads: 0,
    };
    match integ.kind() {
        Kind::Unbiased => {
            let result = render(scene, &integ, &opts(seed), |r| {
                blocks.add(r.pass_image().expect("an unbiased pass has an image"));
                ControlFlow::Continue(())
            })
            .unwrap();
            let rendered = Rendered {
                kind: Kind::Unbiased,
                estimate: result.estimate,
                invalid_samples: result.invalid_samples,
            };
            (rendered, blocks)
        }
        Kind::Consistent => {
            let mut across = RunningImage::new(w, h);
            let mut invalid = 0;
            for k in 0..CONSISTENT_RUNS as u64 {
                let r = render(
                    scene,
                    &integ,
                    &opts(seed + k),
                    |_| ControlFlow::Continue(()),
                )
                .unwrap();
                blocks.add(&r.estimate);
                across.add(&r.estimate);
                invalid += r.invalid_samples;
            }
            let rendered = Rendered {
                kind: Kind::Consistent,
                estimate: across.mean(),
                invalid_samples: invalid,
            };
            (rendered, blocks)
        }
    }
}

// Bias² of a consistent estimator against an unbiased reference, from K independent runs (moved
// here from consistency.rs, which documents the statistic; vcm_consistency.rs uses it too).
// Per block b and channel c, relative to the reference r: S(N) = Σ w [(x̄_b(N) − r_b)² −
// s²_b(N)/K] − Σ w se²_ref,b, the unbiased estimate of Σ w bias², with inverse-variance weights w.

/// `runs` independent runs (seeds `seed`, `seed + 1`, …) of `integrator` on `scene`, each run's
/// estimate kept after every pass count in `checkpoints` (ascending): result[c][k] is run k at
/// checkpoint c. Asserts that no run produced an invalid sample.
pub fn runs_at(
    scene: &Scene,
    integrator: &str,
    params: &IntegratorParams,
    checkpoints: &[u32],
    runs: u64,
    seed: u64,
) -> Vec<Vec<Image>> {
    let integ = make_integrator(integrator, scene, params).unwrap();
    let mut out = vec![Vec::new(); checkpoints.len()];
    for k in 0..runs {
        let opts = RenderOptions {
            passes: *checkpoints.last().unwrap(),
            time_limit: None,
            seed: seed + k,
            threads: 0,
        };
        let r = render(scene, &integ, &opts, |r| {
            if let Some(c) = checkpoints.iter().position(|&n| n == r.passes_done) {
                out[c].push(r.estimate());
            }
            ControlFlow::Continue(())
        })
        .unwrap();
        assert_eq!(r.invalid_samples, 0, "{integrator}: invalid samples");
    }
    out
}

/// Σ over blocks and channels of w [(x̄ − r)² − s²/K], over the runs `keep` selects.
// Block and channel index four parallel arrays at once; an index loop says it plainest.
#[allow(clippy::needless_range_loop)]
pub fn bias2_without_reference(
    blocks: &[Image],
    reference: &BlockEstimate,
    weights: &[[f64; 3]],
    keep: impl Fn(usize) -> bool,
) -> f64 {
    let mut sum = 0.0;
    for b in 0..reference.regions() {
        for c in 0..3 {
            let s = RunningStat::from_slice(
                &blocks
                    .iter()
                    .enumerate()
                    .filter(|(k, _)| keep(*k))
                    .map(|(_, x)| x.data[b][c])
                    .collect::<Vec<_>>(),
            );
            let r = reference.mean[b][c];
            sum +=
                ((s.mean() - r).powi(2) - s.sample_variance() / s.count() as f64) * weights[b][c];
        }
    }
    sum
}

/// Σ w se²_ref: the reference's own noise in S(N).
pub fn reference_noise(reference: &BlockEstimate, weights: &[[f64; 3]]) -> f64 {
    (0..reference.regions())
        .flat_map(|b| (0..3).map(move |c| (b, c)))
        .map(|(b, c)| reference.std_error[b][c].powi(2) * weights[b][c])
        .sum()
}

/// Per block and channel, 1 / (the variance of the K-run mean at the last pass count + the
/// reference's variance): blocks whose estimate is noisy (a light's edge, where the visible
/// points' position within their pixels dominates) count less, in every S(N) alike.
pub fn inverse_variance_weights(last: &[Image], reference: &BlockEstimate) -> Vec<[f64; 3]> {
    (0..reference.regions())
        .map(|b| {
            std::array::from_fn(|c| {
                let s =
                    RunningStat::from_slice(&last.iter().map(|x| x.data[b][c]).collect::<Vec<_>>());
                1.0 / (s.sample_variance() / s.count() as f64 + reference.std_error[b][c].powi(2))
            })
        })
        .collect()
}

/// Δ = S(a) − S(b) and its standard error (jackknife over runs + the reference's cross term).
// Block and channel index the runs, the reference and the weights at once.
#[allow(clippy::needless_range_loop)]
pub fn bias2_decrease(
    a: &[Image],
    b: &[Image],
    reference: &BlockEstimate,
    w: &[[f64; 3]],
) -> (f64, f64) {
    let k = a.len();
    let s =
        |x: &[Image], keep: &dyn Fn(usize) -> bool| bias2_without_reference(x, reference, w, keep);
    let full = s(a, &|_| true) - s(b, &|_| true);
    let loo: Vec<f64> = (0..k)
        .map(|j| s(a, &|i| i != j) - s(b, &|i| i != j))
        .collect();
    let mean = loo.iter().sum::<f64>() / k as f64;
    let jack = (k as f64 - 1.0) / k as f64 * loo.iter().map(|x| (x - mean).powi(2)).sum::<f64>();
    let mut cross = 0.0;
    for blk in 0..reference.regions() {
        for c in 0..3 {
            let m = |x: &[Image]| x.iter().map(|i| i.data[blk][c]).sum::<f64>() / k as f64;
            cross += 4.0
                * (m(a) - m(b)).powi(2)
                * reference.std_error[blk][c].powi(2)
                * w[blk][c].powi(2);
        }
    }
    (full, (jack + cross).sqrt())
}

//! Shared helpers of the workspace-level tests.

use lt_core::scene::load_scene;
use lt_core::Scene;
use lt_estimators::blocks::RunningBlocks;
use lt_estimators::running::RunningImage;
use lt_estimators::Image;
use lt_integrators::{make_integrator, render, IntegratorParams, Kind, RenderOptions};
use std::ops::ControlFlow;
use std::path::PathBuf;

/// The repository's `scenes/` folder.
pub fn scenes_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenes")
}

/// Loads `scenes/NAME.toml`, optionally at a smaller resolution.
pub fn shipped_scene(name: &str, resolution: Option<(u32, u32)>) -> Scene {
    let mut scene =
        load_scene(&scenes_dir().join(format!("{name}.toml"))).unwrap_or_else(|e| panic!("{e}"));
    if let Some((w, h)) = resolution {
        scene.camera = scene.camera.with_resolution(w, h);
    }
    scene
}

/// Every shipped scene's name.
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

//! Shared helpers of the workspace-level tests.

use lt_core::scene::load_scene;
use lt_core::Scene;
use lt_estimators::blocks::RunningBlocks;
use lt_integrators::{make_integrator, render, IntegratorParams, RenderOptions, RenderResult};
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

/// Renders `passes` passes; returns the result and per-block statistics over the passes (feed
/// them to `agreement_t`, which accounts for standard errors estimated from few passes).
pub fn render_blocks(
    scene: &Scene,
    integrator: &str,
    params: IntegratorParams,
    passes: u32,
    seed: u64,
    block: usize,
) -> (RenderResult, RunningBlocks) {
    let integ = make_integrator(integrator, scene, &params).unwrap();
    let mut blocks = RunningBlocks::new(
        scene.camera.width as usize,
        scene.camera.height as usize,
        block,
    );
    let opts = RenderOptions {
        passes,
        time_limit: None,
        seed,
        threads: 0,
    };
    let result = render(scene, integ.as_ref(), &opts, |r| {
        blocks.add(r.pass_image);
        ControlFlow::Continue(())
    })
    .unwrap();
    (result, blocks)
}

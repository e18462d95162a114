//! The plain renders on one thread: what a configuration costs without the tally, and the images
//! the tallied runs must equal bit for bit.

use crate::image_io::{write_atomic, write_exr};
use crate::runs::RunSpec;
use crate::study::StudyContext;
use lt_integrators::tally::pool_cpu_seconds;
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A plain render on one thread (an integrator `tally_run` does not take): its cache entry (the
/// image and the record's facts) and CPU seconds.
pub(super) fn plain_entry(ctx: &StudyContext, spec: &RunSpec) -> Result<(PathBuf, f64), String> {
    let scene = spec.load_scene()?;
    let mut material = spec.key_material(&scene)?;
    material["what"] = json!("techniques-plain");
    ctx.say(&format!("techniques (plain): {}", spec.label()));
    let dir = ctx.runs.cache.get_or_build(&material, |tmp| {
        let p = spec.integrator_params();
        let est = lt_integrators::make_integrator(&spec.integrator, &scene, &p)?;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .map_err(|e| e.to_string())?;
        let (img, cpu, facts) =
            pool.install(|| timed_plain_logged(&scene, &est, spec.seed, spec.passes));
        write_exr(&tmp.join("plain.exr"), &img)?;
        let text = serde_json::to_string_pretty(&json!({
            "plain_cpu_seconds": cpu,
            "facts": facts.into_iter().collect::<BTreeMap<_, _>>(),
        }))
        .map_err(|e| e.to_string())?;
        write_atomic(&tmp.join("plain.json"), text.as_bytes())
    })?;
    let v = read_json(&dir.join("plain.json"))?;
    Ok((dir, v["plain_cpu_seconds"].as_f64().unwrap_or(f64::NAN)))
}

/// A cache entry's JSON file, parsed.
pub(super) fn read_json(path: &Path) -> Result<Value, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// `timed_plain` with the run's recorded facts (a progressive run's log; none for unbiased ones).
fn timed_plain_logged(
    scene: &lt_core::Scene,
    est: &lt_integrators::Estimator,
    seed: u64,
    passes: u32,
) -> (lt_estimators::Image, f64, Vec<(String, String)>) {
    let c0 = pool_cpu_seconds();
    match est {
        lt_integrators::Estimator::Unbiased(_) => {
            let (img, cpu) = timed_plain(scene, est, seed, passes);
            (img, cpu, Vec::new())
        }
        lt_integrators::Estimator::Consistent(p) => {
            let mut run = p.start(scene, seed);
            run.plan(passes);
            for pass in 0..passes {
                run.pass(pass);
            }
            let img = run.estimate();
            (img, pool_cpu_seconds() - c0, run.log().facts)
        }
    }
}

/// The plain render `render` makes (its passes accumulated the same way, so the same bits), on
/// the current pool, with the pool's CPU seconds.
pub(super) fn timed_plain(
    scene: &lt_core::Scene,
    est: &lt_integrators::Estimator,
    seed: u64,
    passes: u32,
) -> (lt_estimators::Image, f64) {
    let c0 = pool_cpu_seconds();
    let cam = &scene.camera;
    let img = match est {
        lt_integrators::Estimator::Unbiased(i) => {
            let mut acc = lt_estimators::RunningImage::new(cam.width as usize, cam.height as usize);
            for pass in 0..passes {
                acc.add(&i.render_pass(scene, seed, pass).0);
            }
            acc.mean()
        }
        lt_integrators::Estimator::Consistent(p) => {
            let mut run = p.start(scene, seed);
            run.plan(passes);
            for pass in 0..passes {
                run.pass(pass);
            }
            run.estimate()
        }
    };
    (img, pool_cpu_seconds() - c0)
}

//! What the tally costs: seconds per pass plain, tallied without timing, timing one item in
//! `EVERY` and timing every item.

use super::config::{spec, StudySize, EVERY, TALLIED};
use super::plain::timed_plain;
use crate::image_io::write_atomic;
use crate::study::output::{stem, StudyOutput};
use crate::study::StudyContext;
use lt_integrators::tally::pool_cpu_seconds;
use lt_integrators::tally_run::{tally_run, Tallied};
use serde_json::{json, Value};

/// Seconds per pass of one integrator on the focus scene: plain, tallied without timing, timed
/// on one item in `EVERY`, and timed on every item — interleaved rounds on one thread, so a
/// change of machine load falls on all four alike.
pub(super) fn overhead(
    ctx: &StudyContext,
    size: &StudySize,
    out: &mut StudyOutput,
) -> Result<(), String> {
    const ROUNDS: usize = 3;
    let Some(scene_path) = size.scenes.first() else {
        return Ok(());
    };
    let mut rows = Vec::new();
    for (lab, integ, params) in TALLIED {
        let s = spec(size, scene_path, integ, params, 1);
        let scene = s.load_scene()?;
        let mut material = s.key_material(&scene)?;
        material["what"] = json!("technique-overhead");
        material["rounds"] = json!(ROUNDS);
        material["every"] = json!(EVERY);
        let dir = ctx.runs.cache.get_or_build(&material, |tmp| {
            let p = s.integrator_params();
            let est = lt_integrators::make_integrator(integ, &scene, &p)?;
            let t = Tallied::make(integ, &scene, &p)?;
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .map_err(|e| e.to_string())?;
            let mut secs = vec![Vec::new(); 4];
            for _ in 0..ROUNDS {
                let plain = pool.install(|| timed_plain(&scene, &est, 1, s.passes).1);
                secs[0].push(plain / s.passes as f64);
                for (k, every) in [(1, 0), (2, EVERY), (3, 1)] {
                    let c = pool.install(|| {
                        let c0 = pool_cpu_seconds();
                        tally_run(&scene, &t, 1, s.passes, every);
                        pool_cpu_seconds() - c0
                    });
                    secs[k].push(c / s.passes as f64);
                }
            }
            let text = serde_json::to_string_pretty(&json!({ "seconds_per_pass": secs }))
                .map_err(|e| e.to_string())?;
            write_atomic(&tmp.join("overhead.json"), text.as_bytes())
        })?;
        let path = dir.join("overhead.json");
        let v: Value = serde_json::from_str(
            &std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?,
        )
        .map_err(|e| format!("{}: {e}", path.display()))?;
        let secs: Vec<Vec<f64>> = (0..4)
            .map(|k| {
                v["seconds_per_pass"][k]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .filter_map(|x| x.as_f64())
                    .collect()
            })
            .collect();
        let min = |k: usize| secs[k].iter().copied().fold(f64::INFINITY, f64::min);
        let cell = |k: usize| {
            let all: Vec<String> = secs[k].iter().map(|x| format!("{x:.4}")).collect();
            if k == 0 {
                format!("{:.4} ({})", min(0), all.join(", "))
            } else {
                format!(
                    "{:.4} ({:+.1} %; {})",
                    min(k),
                    100.0 * (min(k) / min(0) - 1.0),
                    all.join(", ")
                )
            }
        };
        rows.push(vec![lab.to_string(), cell(0), cell(1), cell(2), cell(3)]);
    }
    out.table(
        "overhead",
        "What the tally costs",
        &format!(
            "CPU seconds per pass on `{}` at {} px, one thread, {} passes, {ROUNDS} interleaved \
             rounds: the fastest round (the least disturbed by other work on the machine), its \
             change against the plain render, and every round. Moments alone (no clock), with \
             one item in {EVERY} timed (what the tables above use), and with every item timed.",
            stem(scene_path),
            size.width,
            size.passes
        ),
        &[
            "integrator",
            "plain render",
            "tally, no timing",
            &format!("tally, timing 1 in {EVERY}"),
            "tally, timing every item",
        ],
        rows,
        true,
    )
}

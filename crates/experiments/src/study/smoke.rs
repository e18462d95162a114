//! `smoke`, a hidden study (not in `all`, not in the report): a few small `pt` renders of the
//! focus scene (the Cornell box) whose collection writes `RESULTS/smoke/summary.json`. It
//! exercises plans, submission and collection in the tests without a real study's cost.

use super::context::StudyContext;
use super::scale::Scale;
use crate::runs::RunSpec;

pub fn specs(scale: &Scale) -> Result<Vec<RunSpec>, String> {
    let (res, passes, seeds) = match scale.name {
        "test" => ((16, 16), 4, 2),
        "quick" => ((64, 64), 16, 4),
        "full" => ((256, 256), 256, 8),
        other => return Err(format!("unknown scale '{other}' (test, quick, full)")),
    };
    Ok((1..=seeds)
        .map(|seed| {
            RunSpec::new(&scale.focus_scene, "pt", seed, passes)
                .resolution(Some(res))
                .snapshots([passes / 4, passes / 2])
        })
        .collect())
}

/// Each render's mean, one line per render, in `summary.json`.
pub fn run(ctx: &StudyContext) -> Result<(), String> {
    let mut rows = Vec::new();
    for spec in specs(&ctx.scale)? {
        let entry = ctx.run(&spec)?;
        let img = entry.image()?;
        let mean = img.data.iter().flatten().sum::<f64>() / (img.data.len() * 3).max(1) as f64;
        ctx.say(&format!("{}: mean {mean:.6}", spec.label()));
        rows.push(serde_json::json!({
            "run": spec.label(),
            "entry": entry.dir,
            "mean": mean,
            "seconds": entry.record.seconds,
        }));
    }
    let dir = ctx.study_dir("smoke");
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let text = serde_json::to_string_pretty(
        &serde_json::json!({ "study": "smoke", "scale": ctx.scale.name, "runs": rows }),
    )
    .map_err(|e| e.to_string())?;
    crate::image_io::write_atomic(&dir.join("summary.json"), text.as_bytes())
}

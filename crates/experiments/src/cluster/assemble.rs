//! A study render split into pass ranges (`lt plan study --split-passes`) made whole again: its
//! shards' parts are merged, in pass order, into the cache entry `runs::Executor` would have
//! written for its `RunSpec` — `snapshot-P.exr` at every snapshot (the merge of the parts before
//! P: the cuts fall on the snapshots), `stderr.exr` (spread of passes) and `record.json` — so the
//! study finds it like any other render. The images equal a one-process render within f64
//! rounding before they are written as f32 (see `partial::merge`).

use super::partial::{merge, Partial, Span, ENTRY_FILE};
use super::plan::{Assembly, Plan};
use crate::cache::{key_of, Key, RenderCache, CODE_VERSION};
use crate::image_io::{write_atomic, write_exr};
use crate::runs::RunRecord;
use lt_estimators::running::RunningImage;

/// Builds the entry of `a` from its finished parts; `Ok(false)` if the entry already exists.
pub fn assemble(plan: &Plan, a: &Assembly) -> Result<bool, String> {
    let cache = RenderCache::new(&a.cache);
    if cache.lookup(&Key(a.key.clone())).is_some() {
        return Ok(false);
    }
    let spec = &a.spec;
    let scene = spec.load_scene()?;
    let material = spec.key_material(&scene)?;
    if key_of(&material).0 != a.key {
        return Err(format!(
            "{}: its inputs changed since the plan was made (a scene edited?); plan again",
            spec.label()
        ));
    }
    let mut parts = Vec::new();
    for &i in &a.shards {
        let entry = plan.finished(i).ok_or_else(|| {
            format!(
                "{}: shard {i} ({}) is not finished",
                spec.label(),
                plan.shards[i].label
            )
        })?;
        let file = entry.join(ENTRY_FILE);
        let part = Partial::read(&file)?;
        parts.push((file, part));
    }
    let merged = merge(&parts, false).map_err(|e| format!("{}: {e}", spec.label()))?;
    if merged.span
        != (Span::Passes {
            seed: spec.seed,
            start: 0,
            end: spec.passes,
        })
    {
        return Err(format!(
            "{}: its parts cover {}, it needs passes 0..{}",
            spec.label(),
            merged.span.describe(),
            spec.passes
        ));
    }
    parts.sort_by_key(|(_, p)| match p.header.span {
        Span::Passes { start, .. } => start,
        Span::Runs { .. } => 0,
    });
    cache.get_or_build(&material, |tmp| {
        let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
        let mut acc = RunningImage::new(w, h);
        let mut seconds = Vec::new();
        let mut elapsed = 0.0;
        for (_, p) in &parts {
            acc.merge(&p.acc);
            elapsed += p.header.seconds;
            let done = acc.count() as u32;
            if spec.snapshots.contains(&done) {
                write_exr(&tmp.join(format!("snapshot-{done}.exr")), &acc.mean())?;
                seconds.push(elapsed);
            }
        }
        if seconds.len() != spec.snapshots.len() {
            return Err(format!(
                "{}: the parts do not end at every snapshot {:?}",
                spec.label(),
                spec.snapshots
            ));
        }
        let se = (acc.count() >= 2).then(|| acc.std_error());
        if let Some(se) = &se {
            write_exr(&tmp.join("stderr.exr"), se)?;
        }
        let record = RunRecord {
            spec: spec.clone(),
            kind: "unbiased".into(),
            seconds,
            // The parts ran on machines whose CPU clocks are not summed here.
            cpu_seconds: Vec::new(),
            passes_done: spec.passes,
            invalid_samples: merged.invalid_samples,
            mean_std_error: se.as_ref().map(crate::image_io::mean_of),
            std_error_source: if se.is_some() {
                "spread of passes".into()
            } else {
                "none".into()
            },
            radius_scale: Vec::new(),
            mean_radius: Vec::new(),
            facts: Vec::new(),
            code_version: CODE_VERSION.into(),
            threads: 0,
        };
        let text = serde_json::to_string_pretty(&record).map_err(|e| e.to_string())?;
        write_atomic(&tmp.join("record.json"), text.as_bytes())
    })?;
    Ok(true)
}

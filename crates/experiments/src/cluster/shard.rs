//! `lt run-shard PLAN/ INDEX`: runs one shard of a plan into the cache, or does nothing if it is
//! finished. Beside the cache entry it keeps `PLAN/state/shard-INDEX.json` — running (host, pid,
//! scheduler job, start), then done or failed (with the error) — which is how `lt collect` tells
//! a failed shard from a killed one and names its log.

use super::partial::ENTRY_FILE;
use super::plan::{state_dir, state_path, Plan, Shard, ShardWork};
use crate::cache::{key_of, Key, RenderCache};
use crate::runs::Executor;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::{Instant, SystemTime, UNIX_EPOCH};

/// What `state/shard-I.json` says.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ShardState {
    /// "running", "done" or "failed".
    pub state: String,
    pub host: String,
    pub pid: u32,
    /// The scheduler's name for this attempt (Slurm job, GNU parallel slot), when there is one.
    pub scheduler: Option<String>,
    /// 1 for the first attempt, counting every start.
    pub attempt: u32,
    /// Unix seconds.
    pub started: f64,
    pub ended: Option<f64>,
    pub seconds: Option<f64>,
    /// The shard was already in the cache: nothing was rendered.
    pub reused: bool,
    pub error: Option<String>,
}

pub fn now_unix() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0)
}

/// Unix seconds as `YYYY-MM-DD HH:MM:SS UTC`.
pub fn utc(t: f64) -> String {
    let s = t.max(0.0) as i64;
    let (days, rem) = (s.div_euclid(86400), s.rem_euclid(86400));
    // Civil date from days since 1970-01-01 (Howard Hinnant's algorithm).
    let z = days + 719468;
    let era = z.div_euclid(146097);
    let doe = z - era * 146097;
    let yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02}:{:02} UTC",
        rem / 3600,
        rem / 60 % 60,
        rem % 60
    )
}

pub fn read_state(plan_dir: &Path, i: usize) -> Option<ShardState> {
    let text = std::fs::read_to_string(state_path(plan_dir, i)).ok()?;
    serde_json::from_str(&text).ok()
}

fn write_state(plan_dir: &Path, i: usize, s: &ShardState) -> Result<(), String> {
    std::fs::create_dir_all(state_dir(plan_dir))
        .map_err(|e| format!("cannot create {}: {e}", state_dir(plan_dir).display()))?;
    let text = serde_json::to_string_pretty(s).map_err(|e| e.to_string())?;
    crate::image_io::write_atomic(&state_path(plan_dir, i), text.as_bytes())
}

fn scheduler_name() -> Option<String> {
    let var = |k: &str| std::env::var(k).ok();
    if let (Some(j), Some(t)) = (var("SLURM_ARRAY_JOB_ID"), var("SLURM_ARRAY_TASK_ID")) {
        return Some(format!("Slurm job {j}_{t}"));
    }
    if let Some(j) = var("SLURM_JOB_ID") {
        return Some(format!("Slurm job {j}"));
    }
    var("PARALLEL_SEQ").map(|s| format!("GNU parallel job {s}"))
}

/// Threads for a shard: the flag, else the plan's, else under Slurm the CPUs it was given.
fn threads(plan: &Plan, given: Option<usize>) -> usize {
    if let Some(t) = given {
        return t;
    }
    if plan.threads != 0 {
        return plan.threads;
    }
    std::env::var("SLURM_CPUS_PER_TASK")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0)
}

/// Runs `shard`'s work into its cache entry; returns (entry, reused).
fn execute(shard: &Shard, threads: usize, total: usize) -> Result<(PathBuf, bool), String> {
    let cache = RenderCache::new(&shard.cache);
    let key = Key(shard.key.clone());
    if let Some(dir) = cache.lookup(&key) {
        return Ok((dir, true));
    }
    let changed = |now: &Key| {
        format!(
            "its inputs changed since the plan was made (a scene or mesh file edited?): its key \
             is now {now}, the plan's is {key}. Make the plan again"
        )
    };
    let i = shard.index;
    match &shard.work {
        ShardWork::Partial(job) => {
            let scene = job.load_scene()?;
            let material = job.key_material(&scene)?;
            let now = key_of(&material);
            if now != key {
                return Err(changed(&now));
            }
            let start = Instant::now();
            let mut last = None::<Instant>;
            let dir = cache.get_or_build(&material, |tmp| {
                let part = job.render(&scene, threads, |done, all| {
                    if last.is_none_or(|t| t.elapsed().as_secs_f64() >= 0.5) || done == all {
                        last = Some(Instant::now());
                        eprintln!(
                            "[lt] shard {i} of {total}: pass {done} of {all} ({:.1} s)",
                            start.elapsed().as_secs_f64()
                        );
                    }
                })?;
                part.write(&tmp.join(ENTRY_FILE))
            })?;
            Ok((dir, false))
        }
        ShardWork::Run(spec) => {
            let scene = spec.load_scene()?;
            let now = key_of(&spec.key_material(&scene)?);
            if now != key {
                return Err(changed(&now));
            }
            let entry = Executor {
                cache: cache.clone(),
                threads,
            }
            .run(spec)?;
            Ok((entry.dir, false))
        }
    }
}

/// Runs shard `index` of the plan in `plan_dir`, keeping its state file.
pub fn run_one(
    plan_dir: &Path,
    plan: &Plan,
    index: usize,
    threads_flag: Option<usize>,
) -> Result<(), String> {
    let n = plan.shards.len();
    let shard = plan.shards.get(index).ok_or_else(|| {
        format!(
            "{} has shards 0 to {}, not {index}",
            plan_dir.display(),
            n.saturating_sub(1)
        )
    })?;
    let threads = threads(plan, threads_flag);
    let attempt = read_state(plan_dir, index).map_or(0, |s| s.attempt) + 1;
    let mut state = ShardState {
        state: "running".into(),
        host: super::partial::hostname(),
        pid: std::process::id(),
        scheduler: scheduler_name(),
        attempt,
        started: now_unix(),
        ended: None,
        seconds: None,
        reused: false,
        error: None,
    };
    let finished_before = plan.finished(index).is_some();
    if !finished_before {
        write_state(plan_dir, index, &state)?;
    }
    eprintln!(
        "[lt] shard {index} of {n} ({}): attempt {attempt} on {} (pid {}{}) at {}, {} threads",
        shard.label,
        state.host,
        state.pid,
        state
            .scheduler
            .as_deref()
            .map(|s| format!(", {s}"))
            .unwrap_or_default(),
        utc(state.started),
        if threads == 0 {
            "all".to_string()
        } else {
            threads.to_string()
        }
    );
    let t = Instant::now();
    let result = execute(shard, threads, n);
    state.ended = Some(now_unix());
    state.seconds = Some(t.elapsed().as_secs_f64());
    match result {
        Ok((dir, reused)) => {
            if reused {
                eprintln!(
                    "[lt] shard {index} of {n}: already finished ({}): nothing to do",
                    dir.display()
                );
                if finished_before {
                    return Ok(());
                }
            } else {
                eprintln!(
                    "[lt] shard {index} of {n}: rendered in {:.2} s -> {}",
                    t.elapsed().as_secs_f64(),
                    dir.display()
                );
            }
            state.state = "done".into();
            state.reused = reused;
            write_state(plan_dir, index, &state)
        }
        Err(e) => {
            let msg = format!("shard {index} of {n} ({}): {e}", shard.label);
            eprintln!("[lt] {msg}");
            state.state = "failed".into();
            state.error = Some(e);
            let _ = write_state(plan_dir, index, &state);
            Err(msg)
        }
    }
}

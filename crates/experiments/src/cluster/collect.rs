//! `lt collect PLAN/`: merges a plan's finished shards into its render, or runs its study again
//! (every render then comes from the cache). A shard that is not finished is named with what its
//! state file knows (failed with an error, or started and never finished: killed, out of time)
//! and its log; an incomplete plan is refused unless `--allow-incomplete`, which says what is
//! missing and merges the rest.

use super::partial::{merge, Partial, ENTRY_FILE};
use super::plan::{absolute, log_path, Plan, Target};
use super::shard::{read_state, utc};
use super::study_link;
use std::path::{Path, PathBuf};

/// What `lt collect` is asked: the plan folder and how to treat missing shards.
#[derive(Clone, Debug)]
pub struct CollectOptions {
    /// The plan folder.
    pub plan: PathBuf,
    /// Merge the finished shards even if some are missing.
    pub allow_incomplete: bool,
    /// Where the render goes instead of where the plan says (render plans).
    pub output: Option<PathBuf>,
    /// Worker threads for what a study renders itself (0 = one per core).
    pub threads: usize,
}

/// The last non-empty line of a log, if it has one.
fn last_line(path: &Path) -> Option<String> {
    let text = std::fs::read_to_string(path).ok()?;
    text.lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .map(|l| l.trim().chars().take(200).collect())
}

/// Why shard `i` is not finished, with its log.
pub fn why_missing(dir: &Path, plan: &Plan, i: usize) -> String {
    let shard = &plan.shards[i];
    let log = log_path(dir, i);
    let log_note = if log.is_file() {
        match last_line(&log) {
            Some(l) => format!("log {} (last line: {l})", log.display()),
            None => format!("log {} (empty)", log.display()),
        }
    } else {
        format!("no log at {}", log.display())
    };
    let what = match read_state(dir, i) {
        None => "never started".to_string(),
        Some(s) => {
            let sched = s.scheduler.map(|x| format!(", {x}")).unwrap_or_default();
            match s.state.as_str() {
                "failed" => format!(
                    "failed on {} (attempt {}{sched}) at {}: {}",
                    s.host,
                    s.attempt,
                    utc(s.ended.unwrap_or(s.started)),
                    s.error.unwrap_or_default()
                ),
                "done" => format!(
                    "finished on {} at {} but its cache entry is gone from {}",
                    s.host,
                    utc(s.ended.unwrap_or(s.started)),
                    shard.cache.display()
                ),
                _ => format!(
                    "started on {} (pid {}, attempt {}{sched}) at {} and never finished: killed, \
                     out of time or memory, or still running",
                    s.host,
                    s.pid,
                    s.attempt,
                    utc(s.started)
                ),
            }
        }
    };
    format!("shard {i} ({}): {what}; {log_note}", shard.label)
}

/// Merges a plan's finished shards into its render, or reruns its study from the cache.
pub fn collect(args: &CollectOptions) -> Result<(), String> {
    let dir = absolute(&args.plan)?;
    let plan = Plan::read(&dir)?;
    plan.check_code(&dir)?;
    let missing = plan.unfinished();
    let n = plan.shards.len();
    if !missing.is_empty() {
        let lines: Vec<String> = missing
            .iter()
            .map(|&i| why_missing(&dir, &plan, i))
            .collect();
        if !args.allow_incomplete {
            return Err(format!(
                "{} of {n} shards of {} are not finished:\n  {}\nResubmit (`lt submit {} \
                 --slurm|--parallel|--local` runs only the unfinished shards), or collect what is \
                 there with --allow-incomplete",
                missing.len(),
                dir.display(),
                lines.join("\n  "),
                super::plan::shell_quote(&dir.display().to_string())
            ));
        }
        eprintln!(
            "warning: collecting {} of {n} shards; missing:\n  {}",
            n - missing.len(),
            lines.join("\n  ")
        );
    }
    match &plan.target {
        Target::Render { output, span, .. } => {
            let out = args.output.as_ref().map(|p| absolute(p)).transpose()?;
            let out = out.unwrap_or_else(|| output.clone());
            let mut parts = Vec::new();
            for i in 0..n {
                if let Some(entry) = plan.finished(i) {
                    let file = entry.join(ENTRY_FILE);
                    let part = Partial::read(&file)
                        .map_err(|e| format!("shard {i} ({}): {e}", plan.shards[i].label))?;
                    parts.push((file, part));
                }
            }
            if parts.is_empty() {
                return Err(format!(
                    "no shard of {} is finished: nothing to collect",
                    dir.display()
                ));
            }
            let merged = merge(&parts, args.allow_incomplete)?;
            if missing.is_empty() && merged.span != *span {
                return Err(format!(
                    "{}: the shards cover {}, the plan says {}",
                    dir.display(),
                    merged.span.describe(),
                    span.describe()
                ));
            }
            if let Some(parent) = out.parent() {
                std::fs::create_dir_all(parent)
                    .map_err(|e| format!("cannot create {}: {e}", parent.display()))?;
            }
            let sources: Vec<String> = parts.iter().map(|(p, _)| p.display().to_string()).collect();
            let missing_labels: Vec<String> = missing
                .iter()
                .map(|&i| format!("shard {i}: {}", plan.shards[i].label))
                .collect();
            merged.write_outputs(
                &out,
                &sources,
                serde_json::json!({
                    "plan": dir,
                    "shards": n,
                    "shards_merged": parts.len(),
                    "missing_shards": missing_labels,
                    "planned": span,
                }),
            )?;
            eprintln!(
                "collected {} of {n} shards ({}; {:.2} s of shard rendering) -> {}",
                parts.len(),
                merged.span.describe(),
                merged.seconds,
                out.display()
            );
            Ok(())
        }
        Target::Study {
            name,
            scale,
            results,
            scenes,
            cache,
        } => {
            let mut assembled = 0;
            for a in &plan.assemble {
                if a.shards.iter().any(|&i| missing.contains(&i)) {
                    continue;
                }
                if super::assemble::assemble(&plan, a)? {
                    assembled += 1;
                }
            }
            if assembled > 0 {
                eprintln!(
                    "merged the pass ranges of {assembled} split renders into their cache entries"
                );
            }
            if !missing.is_empty() {
                eprintln!(
                    "warning: the study renders what the {} missing shards lacked here",
                    missing.len()
                );
            }
            let (found, made) =
                study_link::collect(name, scale, results, scenes, cache, args.threads)?;
            eprintln!(
                "study {name} collected from {} ({} renders found in the cache, {} made here) -> {}",
                dir.display(),
                found,
                made,
                results.join(name).display()
            );
            Ok(())
        }
    }
}

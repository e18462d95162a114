//! `lt submit PLAN/ --slurm|--parallel|--local`: hands a plan's unfinished shards to a scheduler.
//! The testbed schedules nothing itself: it writes what the cluster's own tools take (an sbatch
//! job array and a collect job depending on it, or a GNU parallel command with a job log) and
//! runs them. Submitting again after a failure runs only what is unfinished: Slurm gets an array
//! of just those indices; GNU parallel's `--resume-failed` reruns only the failed jobs of its
//! job log; and every shard that is in the cache returns at once anyway.

use super::collect::{collect, CollectOptions};
use super::plan::{absolute, logs_dir, shell_quote, Plan, JOBLOG};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Where the shards run, with that scheduler's options.
#[derive(Clone, Debug)]
pub enum Engine {
    /// An sbatch job array of the unfinished shards and a collect job after it.
    Slurm(SlurmOptions),
    /// GNU parallel (--joblog, --resume-failed), then collect.
    Parallel(ParallelOptions),
    /// Here, one shard after the other, then collect.
    Local,
}

/// Slurm's options for the shards' job (`lt submit --slurm`'s flags).
#[derive(Clone, Debug, Default)]
pub struct SlurmOptions {
    pub partition: Option<String>,
    /// At most N shards at once (--array=…%N).
    pub max_running: Option<u32>,
    pub cpus_per_task: Option<u32>,
    /// sbatch --mem.
    pub mem: Option<String>,
    /// sbatch --time.
    pub time_limit: Option<String>,
    /// Further sbatch options, each a line `#SBATCH OPTION`.
    pub sbatch_args: Vec<String>,
}

/// GNU parallel's options (`lt submit --parallel`'s flags).
#[derive(Clone, Debug, Default)]
pub struct ParallelOptions {
    /// Jobs at once (default: cores / threads per shard).
    pub jobs: Option<String>,
    /// Hosts to run on (--sshloginfile).
    pub sshloginfile: Option<PathBuf>,
}

/// A plan handed to a scheduler.
#[derive(Clone, Debug)]
pub struct Submission {
    /// The plan folder.
    pub plan: PathBuf,
    pub engine: Engine,
    /// Write the scripts and print the commands instead of running them.
    pub print: bool,
    /// GNU parallel and local: do not collect after the shards.
    pub no_collect: bool,
}

/// `0-7`, `1,3,5-6`: Slurm's array syntax for sorted indices.
pub fn array_spec(indices: &[usize]) -> String {
    let mut parts = Vec::new();
    let mut i = 0;
    while i < indices.len() {
        let mut j = i;
        while j + 1 < indices.len() && indices[j + 1] == indices[j] + 1 {
            j += 1;
        }
        parts.push(if i == j {
            indices[i].to_string()
        } else {
            format!("{}-{}", indices[i], indices[j])
        });
        i = j + 1;
    }
    parts.join(",")
}

fn run_capture(cmd: &mut Command, what: &str) -> Result<String, String> {
    let out = cmd
        .output()
        .map_err(|e| format!("cannot run {what}: {e} (is it installed and on PATH?)"))?;
    if !out.status.success() {
        return Err(format!(
            "{what} failed ({}): {}",
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    Ok(String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn write_script(path: &Path, text: &str) -> Result<(), String> {
    crate::image_io::write_atomic(path, text.as_bytes())?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755))
            .map_err(|e| format!("cannot make {} executable: {e}", path.display()))?;
    }
    Ok(())
}

fn slurm(
    dir: &Path,
    plan: &Plan,
    todo: &[usize],
    args: &SlurmOptions,
    print: bool,
) -> Result<(), String> {
    let q = |p: &Path| shell_quote(&p.display().to_string());
    let sdir = dir.join("slurm");
    std::fs::create_dir_all(&sdir).map_err(|e| format!("cannot create {}: {e}", sdir.display()))?;
    std::fs::create_dir_all(logs_dir(dir))
        .map_err(|e| format!("cannot create {}: {e}", logs_dir(dir).display()))?;
    let mut array = array_spec(todo);
    if let Some(n) = args.max_running {
        if n == 0 {
            return Err("--max-running must be at least 1".into());
        }
        array = format!("{array}%{n}");
    }
    let mut head = vec![
        "#!/bin/bash".to_string(),
        format!("#SBATCH --job-name=lt-shards"),
        format!("#SBATCH --array={array}"),
        format!(
            "#SBATCH --output={}",
            logs_dir(dir).join("shard-%a.log").display()
        ),
        "#SBATCH --open-mode=append".to_string(),
        format!("#SBATCH --chdir={}", dir.display()),
    ];
    let mut common = Vec::new();
    if let Some(p) = &args.partition {
        common.push(format!("#SBATCH --partition={p}"));
    }
    head.extend(common.iter().cloned());
    if let Some(c) = args.cpus_per_task {
        head.push(format!("#SBATCH --cpus-per-task={c}"));
    }
    if let Some(m) = &args.mem {
        head.push(format!("#SBATCH --mem={m}"));
    }
    if let Some(t) = &args.time_limit {
        head.push(format!("#SBATCH --time={t}"));
    }
    for a in &args.sbatch_args {
        head.push(format!("#SBATCH {a}"));
    }
    let shards_script = format!(
        "{}\n# Written by lt submit: one array task per unfinished shard of {}.\n\
         exec {} run-shard {} \"$SLURM_ARRAY_TASK_ID\"\n",
        head.join("\n"),
        dir.display(),
        q(&plan.lt),
        q(dir)
    );
    let mut chead = vec![
        "#!/bin/bash".to_string(),
        "#SBATCH --job-name=lt-collect".to_string(),
        format!(
            "#SBATCH --output={}",
            logs_dir(dir).join("collect.log").display()
        ),
        "#SBATCH --open-mode=append".to_string(),
        format!("#SBATCH --chdir={}", dir.display()),
    ];
    chead.extend(common);
    let collect_script = format!(
        "{}\n# Written by lt submit: runs once every shard job has succeeded.\n\
         exec {} collect {}\n",
        chead.join("\n"),
        q(&plan.lt),
        q(dir)
    );
    let shards_path = sdir.join("shards.sbatch");
    let collect_path = sdir.join("collect.sbatch");
    write_script(&shards_path, &shards_script)?;
    write_script(&collect_path, &collect_script)?;
    if print {
        println!("JOB=$(sbatch --parsable {})", q(&shards_path));
        println!(
            "sbatch --parsable --dependency=afterok:${{JOB%%;*}} --kill-on-invalid-dep=yes {}",
            q(&collect_path)
        );
        return Ok(());
    }
    let job = run_capture(
        Command::new("sbatch").arg("--parsable").arg(&shards_path),
        "sbatch",
    )?;
    let job = job.split(';').next().unwrap_or("").trim().to_string();
    if job.is_empty() || !job.chars().all(|c| c.is_ascii_digit()) {
        return Err(format!("sbatch gave no job id (got '{job}')"));
    }
    let collect_job = run_capture(
        Command::new("sbatch")
            .arg("--parsable")
            .arg(format!("--dependency=afterok:{job}"))
            .arg("--kill-on-invalid-dep=yes")
            .arg(&collect_path),
        "sbatch (collect job)",
    )?;
    let collect_job = collect_job
        .split(';')
        .next()
        .unwrap_or("")
        .trim()
        .to_string();
    let record = serde_json::json!({
        "submitted": super::shard::now_unix(),
        "shards_job": job,
        "collect_job": collect_job,
        "array": array,
        "shards": todo,
    });
    let hist = sdir.join("submissions.jsonl");
    let mut text = std::fs::read_to_string(&hist).unwrap_or_default();
    text.push_str(&record.to_string());
    text.push('\n');
    crate::image_io::write_atomic(&hist, text.as_bytes())?;
    eprintln!(
        "submitted {} of {} shards as Slurm job array {job} (--array={array}) and the collect \
         job {collect_job} (after all of them succeed). Watch: squeue -j {job},{collect_job}; \
         logs in {}",
        todo.len(),
        plan.shards.len(),
        logs_dir(dir).display()
    );
    println!("shards_job={job} collect_job={collect_job} array={array}");
    Ok(())
}

/// The last joblog line of every sequence number: (seq, exit value, signal).
pub fn joblog_results(path: &Path) -> Vec<(usize, i64, i64)> {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let mut last: Vec<(usize, i64, i64)> = Vec::new();
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split('\t').collect();
        if f.len() < 9 {
            continue;
        }
        let (Ok(seq), Ok(exit), Ok(sig)) = (f[0].parse(), f[6].parse(), f[7].parse()) else {
            continue;
        };
        last.retain(|(s, _, _)| *s != seq);
        last.push((seq, exit, sig));
    }
    last.sort();
    last
}

fn parallel(dir: &Path, plan: &Plan, args: &ParallelOptions, print: bool) -> Result<bool, String> {
    let q = |p: &Path| shell_quote(&p.display().to_string());
    std::fs::create_dir_all(logs_dir(dir))
        .map_err(|e| format!("cannot create {}: {e}", logs_dir(dir).display()))?;
    let jobs = match &args.jobs {
        Some(j) => j.clone(),
        None => {
            let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
            // Shards of every core (threads 0) run one at a time.
            cores
                .checked_div(plan.threads)
                .unwrap_or(1)
                .max(1)
                .to_string()
        }
    };
    let joblog = dir.join(JOBLOG);
    // Every shard, always in the same order: the joblog's sequence numbers name them (seq = index
    // + 1), so --resume-failed finds the failed ones and skips the finished.
    let template = format!(
        "{} run-shard {} {{}} >> {}/shard-{{}}.log 2>&1",
        q(&plan.lt),
        q(dir),
        q(&logs_dir(dir))
    );
    let mut pargs: Vec<String> = vec![
        "--will-cite".into(),
        "--joblog".into(),
        joblog.display().to_string(),
        "--resume-failed".into(),
        "--jobs".into(),
        jobs,
    ];
    if let Some(f) = &args.sshloginfile {
        pargs.push("--sshloginfile".into());
        pargs.push(absolute(f)?.display().to_string());
    }
    pargs.push(template);
    pargs.push(":::".into());
    pargs.extend((0..plan.shards.len()).map(|i| i.to_string()));
    if print {
        let words: Vec<String> = pargs.iter().map(|a| shell_quote(a)).collect();
        println!("parallel {}", words.join(" "));
        println!("{} collect {}", q(&plan.lt), q(dir));
        return Ok(false);
    }
    eprintln!(
        "running {} shards with GNU parallel (job log {})",
        plan.shards.len(),
        joblog.display()
    );
    let status = Command::new("parallel")
        .args(&pargs)
        .status()
        .map_err(|e| {
            format!(
                "cannot run GNU parallel: {e} (install it: apt-get install parallel; or run the \
             lines of {})",
                dir.join("commands.txt").display()
            )
        })?;
    if status.success() {
        return Ok(true);
    }
    let failed: Vec<String> = joblog_results(&joblog)
        .into_iter()
        .filter(|&(_, e, s)| e != 0 || s != 0)
        .map(|(seq, e, s)| {
            let i = seq - 1;
            let how = if s != 0 {
                format!("killed by signal {s}")
            } else {
                format!("exit {e}")
            };
            format!(
                "shard {i} ({how}): {}",
                super::collect::why_missing(dir, plan, i)
            )
        })
        .collect();
    Err(format!(
        "GNU parallel: {} shards failed:\n  {}\nRun `lt submit {} --parallel` again: \
         --resume-failed reruns only those",
        failed.len(),
        failed.join("\n  "),
        q(dir)
    ))
}

/// Runs (or, with `print`, prints) a plan's unfinished shards where `args.engine` says, and
/// collects them unless `no_collect` (Slurm: a collect job after the shards' array).
pub fn submit(args: &Submission) -> Result<(), String> {
    let dir = absolute(&args.plan)?;
    let plan = Plan::read(&dir)?;
    plan.check_code(&dir)?;
    if !plan.lt.is_file() {
        return Err(format!(
            "the plan's lt binary {} does not exist (plan again with --lt PATH)",
            plan.lt.display()
        ));
    }
    let todo = plan.unfinished();
    let collect_args = CollectOptions {
        plan: dir.clone(),
        allow_incomplete: false,
        output: None,
        threads: plan.threads,
    };
    if let Engine::Slurm(slurm_options) = &args.engine {
        if todo.is_empty() {
            eprintln!(
                "all {} shards are finished: nothing to submit; `lt collect {}` merges them",
                plan.shards.len(),
                shell_quote(&dir.display().to_string())
            );
            return Ok(());
        }
        return slurm(&dir, &plan, &todo, slurm_options, args.print);
    }
    if let Engine::Parallel(parallel_options) = &args.engine {
        let ran = parallel(&dir, &plan, parallel_options, args.print)?;
        if ran && !args.no_collect {
            collect(&collect_args)?;
        }
        return Ok(());
    }
    // Local: every unfinished shard here, in order; failures are reported together.
    if args.print {
        for &i in &todo {
            println!("{}", plan.command(&dir, i));
        }
        println!(
            "{} collect {}",
            shell_quote(&plan.lt.display().to_string()),
            shell_quote(&dir.display().to_string())
        );
        return Ok(());
    }
    let mut failed = Vec::new();
    for &i in &todo {
        if let Err(e) = super::shard::run_one(&dir, &plan, i, None) {
            failed.push(e);
        }
    }
    if !failed.is_empty() {
        return Err(format!(
            "{} of {} shards failed:\n  {}",
            failed.len(),
            todo.len(),
            failed.join("\n  ")
        ));
    }
    if !args.no_collect {
        collect(&collect_args)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn array_specs() {
        assert_eq!(array_spec(&[0, 1, 2, 3]), "0-3");
        assert_eq!(array_spec(&[1]), "1");
        assert_eq!(array_spec(&[0, 2, 3, 4, 7]), "0,2-4,7");
    }
}

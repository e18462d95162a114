//! A plan run on a real Slurm: a private one-node cluster started under a temporary folder
//! (crates/experiments/scripts/slurm-private.sh: auth/none, proctrack/linuxproc, task/none, node
//! `ltnode`, explicit ports), a 4-shard plan submitted as a job array (`%2`) with a collect job
//! (`afterok`), one shard cancelled midway, the collect refused naming it, the resubmission
//! running only that shard, the collect job merging, and the result compared with the local
//! one-process render: within one f32 ulp per value (the f64 merge is within rounding of the
//! one-process accumulator; see partial_merge.rs for the bound).
//!
//! Without Slurm installed the test says so loudly and passes, unless LT_REQUIRE_SLURM=1 (CI).
//! LT_SLURM_CONF=/path/slurm.conf uses an existing cluster instead of starting one
//! (LT_SLURM_PARTITION picks its partition). The daemons it starts are stopped whatever happens
//! (a guard's Drop runs on success and on panic).

use crate::cluster_common::*;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

struct Cluster {
    conf: PathBuf,
    /// The folder of a cluster this test started (and must stop).
    owned: Option<PathBuf>,
}

fn script() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scripts/slurm-private.sh")
}

impl Drop for Cluster {
    fn drop(&mut self) {
        if let Some(dir) = &self.owned {
            let out = Command::new("bash")
                .arg(script())
                .arg("stop")
                .arg(dir)
                .output();
            eprintln!(
                "slurm-private stop {}: {}",
                dir.display(),
                out.map(|o| o.status.to_string())
                    .unwrap_or_else(|e| e.to_string())
            );
        }
    }
}

fn start_cluster(dir: &Path) -> Option<Cluster> {
    if let Some(conf) = std::env::var_os("LT_SLURM_CONF") {
        return Some(Cluster {
            conf: conf.into(),
            owned: None,
        });
    }
    let tools = [
        "slurmctld",
        "slurmd",
        "sbatch",
        "squeue",
        "scancel",
        "sinfo",
    ];
    if !have(
        &tools,
        "LT_REQUIRE_SLURM",
        "Slurm (slurmctld slurmd slurm-client)",
    ) {
        return None;
    }
    // The guard exists before the daemons do: whatever start leaves running is stopped.
    let cluster = Cluster {
        conf: dir.join("slurm.conf"),
        owned: Some(dir.to_path_buf()),
    };
    let out = Command::new("bash")
        .arg(script())
        .arg("start")
        .arg(dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "the private Slurm cluster did not start:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    Some(cluster)
}

impl Cluster {
    fn cmd(&self, program: &Path) -> Command {
        let mut c = Command::new(program);
        c.env("SLURM_CONF", &self.conf);
        c
    }

    fn lt(&self, lt: &Path, args: &[&str]) -> String {
        let out = self.cmd(lt).args(args).output().unwrap();
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(
            out.status.success(),
            "lt {} failed:\n{text}",
            args.join(" ")
        );
        text
    }

    /// Jobs of `ids` not yet ended.
    fn active(&self, ids: &[&str]) -> String {
        let out = self
            .cmd(Path::new("squeue"))
            .args([
                "-h",
                "-t",
                "PD,R,CG,CF,S",
                "-o",
                "%i %T",
                "-j",
                &ids.join(","),
            ])
            .output()
            .unwrap();
        String::from_utf8_lossy(&out.stdout).trim().to_string()
    }

    fn wait_all(&self, ids: &[&str], plan: &Path) {
        let done = wait_for(120.0, || self.active(ids).is_empty());
        if !done {
            let logs: String = (0..4)
                .map(|i| read(&plan.join(format!("logs/shard-{i}.log"))))
                .collect();
            panic!(
                "Slurm jobs {ids:?} still active after 120 s: {}\n{logs}",
                self.active(ids)
            );
        }
    }
}

/// (shards job, collect job, array) from `lt submit --slurm`'s summary line.
fn submitted(out: &str) -> (String, String, String) {
    let line = out
        .lines()
        .find(|l| l.starts_with("shards_job="))
        .unwrap_or_else(|| panic!("no job ids in:\n{out}"));
    let field = |name: &str| {
        line.split_whitespace()
            .find_map(|w| w.strip_prefix(&format!("{name}=")).map(str::to_string))
            .unwrap()
    };
    (field("shards_job"), field("collect_job"), field("array"))
}

#[test]
fn a_plan_on_slurm_with_a_shard_killed_midway_equals_the_local_render() {
    let dir = scratch("cluster-slurm");
    let Some(cluster) = start_cluster(&dir.join("slurm")) else {
        return;
    };
    let lt = lt_binary(&dir);
    let scene = small_scene(&dir, 32, 32);
    let reference = dir.join("reference.exr");
    let t_local = one_process_render(&lt, &scene, 2000, &reference);
    let plan = dir.join("plan");
    let p = plan.to_str().unwrap();
    let cache = dir.join("cache");
    plan_render(&lt, &scene, 2000, 4, &plan, &cache);
    let mut submit = vec![
        "submit",
        p,
        "--slurm",
        "--max-running",
        "2",
        "--cpus-per-task",
        "1",
    ];
    let partition = std::env::var("LT_SLURM_PARTITION").ok();
    if let Some(part) = &partition {
        submit.extend(["--partition", part]);
    }
    let t = Instant::now();
    let (job, collect_job, array) = submitted(&cluster.lt(&lt, &submit));
    assert_eq!(array, "0-3%2");
    let script = read(&plan.join("slurm/shards.sbatch"));
    assert!(script.contains("#SBATCH --array=0-3%2"), "{script}");

    // Cancel shard 1 once it is rendering.
    let log1 = plan.join("logs/shard-1.log");
    assert!(
        wait_for(60.0, || read(&log1).contains(" pass ")),
        "shard 1 never started rendering:\n{}",
        read(&log1)
    );
    let out = cluster
        .cmd(Path::new("scancel"))
        .arg(format!("{job}_1"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let t_kill = t.elapsed().as_secs_f64();
    cluster.wait_all(&[&job, &collect_job], &plan);
    let t_first = t.elapsed().as_secs_f64();
    let st = state(&plan, 1).expect("shard 1 wrote its state");
    assert_eq!(
        st.state, "running",
        "shard 1 finished before it was cancelled: {st:?}"
    );
    assert!(read(&log1).contains("CANCELLED"), "{}", read(&log1));
    let before = entry_times(&plan);
    assert!(
        before[0].is_some() && before[1].is_none() && before[2].is_some() && before[3].is_some()
    );
    assert!(
        !plan.join("logs/collect.log").exists(),
        "the collect job must not run after a failed shard"
    );
    let e = lt_err(&lt, &["collect", p]);
    assert!(
        e.contains("1 of 4 shards")
            && e.contains("shard 1 (")
            && e.contains("never finished")
            && e.contains(&format!("Slurm job {job}_1"))
            && e.contains("shard-1.log"),
        "{e}"
    );

    // Resubmit: an array of shard 1 alone; the collect job then merges all four.
    let t = Instant::now();
    let (job2, collect2, array2) = submitted(&cluster.lt(&lt, &submit));
    assert_eq!(array2, "1%2");
    cluster.wait_all(&[&job2, &collect2], &plan);
    let t_second = t.elapsed().as_secs_f64();
    let after = entry_times(&plan);
    for i in [0, 2, 3] {
        assert_eq!(before[i], after[i], "shard {i} was redone");
    }
    assert!(after[1].is_some());
    let attempts: Vec<u32> = (0..4).map(|i| state(&plan, i).unwrap().attempt).collect();
    assert_eq!(attempts, [1, 2, 1, 1]);
    let collect_log = read(&plan.join("logs/collect.log"));
    assert!(
        collect_log.contains("collected 4 of 4 shards"),
        "{collect_log}"
    );

    let (ulps, differ, n) = ulp_distance(&plan.join("render.exr"), &reference);
    let (se_ulps, se_differ, _) = ulp_distance(
        &plan.join("render.stderr.exr"),
        &dir.join("reference.stderr.exr"),
    );
    eprintln!(
        "Slurm: 4 shards of 500 passes (32x32 pt), --array=0-3%2, shard 1 cancelled {t_kill:.1} s \
         after submission; first round done in {t_first:.1} s; resubmitted --array=1%2, done and \
         collected in {t_second:.1} s; attempts per shard {attempts:?}. Local one-process render \
         (2 threads) {t_local:.1} s. Collected vs local: image {differ} of {n} values differ, at \
         most {ulps} f32 ulp; standard error {se_differ} differ, at most {se_ulps} ulp"
    );
    assert!(ulps <= 1 && se_ulps <= 1);
    drop(cluster);
    let _ = std::fs::remove_dir_all(&dir);
}

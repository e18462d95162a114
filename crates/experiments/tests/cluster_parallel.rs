//! A plan run with GNU parallel (`lt submit --parallel`: --joblog, --resume-failed): one shard's
//! process is killed midway (SIGKILL), parallel reports it and the collect is refused naming it,
//! the second submission reruns only that job of the job log, and the collected render equals the
//! local one-process render within one f32 ulp per value.
//!
//! Without GNU parallel installed the test says so loudly and passes, unless
//! LT_REQUIRE_PARALLEL=1 (CI).

use crate::cluster_common::*;
use std::process::{Command, Stdio};
use std::time::Instant;

/// Joblog rows: (sequence number, exit value, signal).
fn joblog(path: &std::path::Path) -> Vec<(usize, i64, i64)> {
    read(path)
        .lines()
        .skip(1)
        .filter_map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            Some((
                f.first()?.parse().ok()?,
                f.get(6)?.parse().ok()?,
                f.get(7)?.parse().ok()?,
            ))
        })
        .collect()
}

#[test]
fn a_plan_on_gnu_parallel_with_a_shard_killed_midway_equals_the_local_render() {
    if !have(&["parallel"], "parallel", "LT_REQUIRE_PARALLEL") {
        return;
    }
    let dir = scratch("cluster-parallel");
    let lt = lt_binary(&dir);
    let scene = small_scene(&dir, 32, 32);
    let reference = dir.join("reference.exr");
    let t_local = one_process_render(&lt, &scene, 2000, &reference);
    let plan = dir.join("plan");
    let p = plan.to_str().unwrap();
    let cache = dir.join("cache");
    plan_render(&lt, &scene, 2000, 4, &plan, &cache);
    let printed = lt_ok(&lt, &["submit", p, "--parallel", "--print"]);
    assert!(
        printed.contains("--joblog") && printed.contains("--resume-failed"),
        "{printed}"
    );

    let t = Instant::now();
    let mut child = Command::new(&lt)
        .args(["submit", p, "--parallel", "--jobs", "2"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let log1 = plan.join("logs/shard-1.log");
    let rendering = wait_for(60.0, || {
        state(&plan, 1).is_some_and(|s| s.state == "running") && read(&log1).contains(" pass ")
    });
    if !rendering {
        let _ = child.kill();
        panic!("shard 1 never started rendering:\n{}", read(&log1));
    }
    let pid = state(&plan, 1).unwrap().pid;
    let killed = Command::new("kill")
        .args(["-KILL", &pid.to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let t_kill = t.elapsed().as_secs_f64();
    let out = child.wait_with_output().unwrap();
    let t_first = t.elapsed().as_secs_f64();
    let text = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        !out.status.success(),
        "parallel must report the killed shard:\n{text}"
    );
    assert!(
        text.contains("1 shards failed")
            && text.contains("shard 1 (")
            && text.contains("--resume-failed"),
        "{text}"
    );
    let st = state(&plan, 1).unwrap();
    assert_eq!(
        st.state, "running",
        "shard 1 finished before it was killed: {st:?}"
    );
    let before = entry_times(&plan);
    assert!(
        before[0].is_some() && before[1].is_none() && before[2].is_some() && before[3].is_some()
    );
    let e = lt_err(&lt, &["collect", p]);
    assert!(
        e.contains("1 of 4 shards") && e.contains("shard 1 (") && e.contains("never finished"),
        "{e}"
    );
    let log = plan.join("parallel.joblog");
    let first = joblog(&log);
    assert_eq!(first.len(), 4, "{first:?}");
    assert!(
        first
            .iter()
            .all(|&(seq, e, sig)| (seq == 2) == (e != 0 || sig != 0)),
        "only job 2 (shard 1) failed: {first:?}"
    );

    let t = Instant::now();
    let out = lt_ok(&lt, &["submit", p, "--parallel", "--jobs", "2"]);
    let t_second = t.elapsed().as_secs_f64();
    assert!(out.contains("collected 4 of 4 shards"), "{out}");
    let second = joblog(&log);
    assert_eq!(second.len(), 5, "one more job ran: {second:?}");
    assert_eq!(
        (second[4].0, second[4].1, second[4].2),
        (2, 0, 0),
        "{second:?}"
    );
    let after = entry_times(&plan);
    for i in [0, 2, 3] {
        assert_eq!(before[i], after[i], "shard {i} was redone");
    }
    let attempts: Vec<u32> = (0..4).map(|i| state(&plan, i).unwrap().attempt).collect();
    assert_eq!(attempts, [1, 2, 1, 1]);

    let (ulps, differ, n) = ulp_distance(&plan.join("render.exr"), &reference);
    let (se_ulps, se_differ, _) = ulp_distance(
        &plan.join("render.stderr.exr"),
        &dir.join("reference.stderr.exr"),
    );
    eprintln!(
        "GNU parallel: 4 shards of 500 passes (32x32 pt), --jobs 2, shard 1 killed (SIGKILL) \
         {t_kill:.1} s in; first round ended in {t_first:.1} s (joblog: {first:?}); rerun with \
         --resume-failed ran 1 job and collected in {t_second:.1} s; attempts {attempts:?}. \
         Local one-process render (2 threads) {t_local:.1} s. Collected vs local: image {differ} \
         of {n} values differ, at most {ulps} f32 ulp; standard error {se_differ} differ, at \
         most {se_ulps} ulp"
    );
    assert!(ulps <= 1 && se_ulps <= 1);
    let _ = std::fs::remove_dir_all(&dir);
}

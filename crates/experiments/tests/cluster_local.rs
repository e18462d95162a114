//! `lt plan` / `submit --local` / `collect` / `merge` end to end through the binary: the collected
//! render equals the one-process `lt render` to within one f32 ulp per value (the f64 merge is
//! within rounding of the one-process accumulator, see partial_merge.rs; writing f32 can then
//! round the two to neighbouring floats), a merge of the same parts in another order is bit for
//! bit the collected render, a lost shard is named and redone alone, and bad requests get one
//! clear error.

use crate::cluster_common::*;

#[test]
fn local_plan_collects_the_one_process_render_and_redoes_only_what_is_lost() {
    let dir = scratch("cluster-local");
    let lt = lt_binary(&dir);
    let scene = small_scene(&dir, 24, 16);
    let reference = dir.join("reference.exr");
    one_process_render(&lt, &scene, 60, &reference);
    let plan = dir.join("plan");
    let cache = dir.join("cache");
    let p = plan.to_str().unwrap();
    plan_render(&lt, &scene, 60, 3, &plan, &cache);
    assert_eq!(read(&plan.join("commands.txt")).lines().count(), 3);

    let e = lt_err(&lt, &["collect", p]);
    assert!(
        e.contains("3 of 3 shards") && e.contains("never started") && e.contains("shard-0.log"),
        "{e}"
    );

    let out = lt_ok(&lt, &["submit", p, "--local"]);
    assert!(out.contains("collected 3 of 3 shards"), "{out}");
    let render = plan.join("render.exr");
    let (ulps, differ, n) = ulp_distance(&render, &reference);
    let (se_ulps, se_differ, _) = ulp_distance(
        &plan.join("render.stderr.exr"),
        &dir.join("reference.stderr.exr"),
    );
    eprintln!(
        "local plan of 3 shards vs one-process lt render (24x16, 60 spp): image {differ} of {n} \
         values differ, at most {ulps} f32 ulp; standard error {se_differ} differ, at most \
         {se_ulps} ulp"
    );
    assert!(ulps <= 1 && se_ulps <= 1, "{ulps} / {se_ulps} ulps");

    // The parts in another order: lt merge gives the collected render bit for bit.
    let planned = lt_experiments::cluster::plan::Plan::read(&plan).unwrap();
    let mut parts: Vec<String> = (0..3)
        .map(|i| {
            planned
                .finished(i)
                .unwrap()
                .join("partial.ltp")
                .display()
                .to_string()
        })
        .collect();
    parts.reverse();
    let merged = dir.join("merged.exr");
    let mut args = vec!["merge"];
    args.extend(parts.iter().map(String::as_str));
    args.extend(["-o", merged.to_str().unwrap()]);
    lt_ok(&lt, &args);
    assert_eq!(ulp_distance(&merged, &render).1, 0);
    assert_eq!(
        std::fs::read(&merged).unwrap(),
        std::fs::read(&render).unwrap()
    );

    // A lost shard: named, collected around with --allow-incomplete, redone alone.
    let before = entry_times(&plan);
    std::fs::remove_dir_all(planned.finished(1).unwrap()).unwrap();
    let e = lt_err(&lt, &["collect", p]);
    assert!(
        e.contains("1 of 3 shards") && e.contains("shard 1 (") && e.contains("cache entry is gone"),
        "{e}"
    );
    let partial_out = dir.join("partial.exr");
    let out = lt_ok(
        &lt,
        &[
            "collect",
            p,
            "--allow-incomplete",
            "-o",
            partial_out.to_str().unwrap(),
        ],
    );
    assert!(out.contains("collected 2 of 3 shards"), "{out}");
    let record = read(&dir.join("partial.json"));
    assert!(
        record.contains("\"missing_shards\"") && record.contains("passes 20..40"),
        "{record}"
    );
    lt_ok(&lt, &["submit", p, "--local"]);
    let after = entry_times(&plan);
    assert_eq!(
        (before[0], before[2]),
        (after[0], after[2]),
        "shards 0 and 2 were not redone"
    );
    assert!(after[1].is_some());
    let attempts: Vec<u32> = (0..3).map(|i| state(&plan, i).unwrap().attempt).collect();
    assert_eq!(attempts, [1, 2, 1]);
    assert_eq!(
        std::fs::read(&render).unwrap(),
        std::fs::read(&merged).unwrap(),
        "the redone shard is bit for bit the lost one"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_requests_get_one_clear_error() {
    let dir = scratch("cluster-errors");
    let lt = lt_binary(&dir);
    let scene = small_scene(&dir, 8, 8);
    let s = scene.to_str().unwrap();
    let p = dir.join("p");
    let p = p.to_str().unwrap();
    let e = lt_err(
        &lt,
        &[
            "plan", "render", s, "-i", "sppm", "--spp", "4", "--shards", "2", "-o", p,
        ],
    );
    assert!(e.contains("consistent") && e.contains("--runs"), "{e}");
    let e = lt_err(&lt, &["plan", "render", s, "--spp", "4", "-o", p]);
    assert!(e.contains("--shards N or --passes-per-shard M"), "{e}");
    let e = lt_err(
        &lt,
        &["plan", "render", s, "--spp", "4", "--shards", "5", "-o", p],
    );
    assert!(e.contains("more shards than there are passes"), "{e}");
    let x = dir.join("x.ltp");
    let e = lt_err(
        &lt,
        &[
            "render",
            s,
            "-i",
            "sppm",
            "--passes",
            "0..2",
            "--partial",
            x.to_str().unwrap(),
        ],
    );
    assert!(e.contains("consistent"), "{e}");
    let e = lt_err(
        &lt,
        &[
            "render",
            s,
            "--passes",
            "3..3",
            "--partial",
            x.to_str().unwrap(),
        ],
    );
    assert!(e.contains("empty"), "{e}");
    let e = lt_err(&lt, &["render", s, "--passes", "0..2", "-o", "y.exr"]);
    assert!(e.contains("--partial"), "{e}");
    let xs = x.to_str().unwrap();
    let e = lt_err(&lt, &["render", s, "--time", "1", "--partial", xs]);
    assert!(e.contains("--time"), "{e}");
    let e = lt_err(&lt, &["run-shard", dir.to_str().unwrap(), "0"]);
    assert!(e.contains("plan.json"), "{e}");
    // Runs of a consistent estimator shard and collect as --runs K does.
    let cache = dir.join("c");
    lt_ok(
        &lt,
        &[
            "plan",
            "render",
            s,
            "-i",
            "sppm",
            "--spp",
            "2",
            "--runs",
            "3",
            "-o",
            p,
            "--cache",
            cache.to_str().unwrap(),
        ],
    );
    let out = lt_ok(&lt, &["submit", p, "--local"]);
    assert!(
        out.contains("collected 3 of 3 shards (runs of seeds 1..4"),
        "{out}"
    );
    let record = read(&dir.join("p").join("render.json"));
    assert!(
        record.contains("\"std_error_source\": \"independent runs\""),
        "{record}"
    );
    // A different plan in the same folder needs --force.
    let e = lt_err(
        &lt,
        &["plan", "render", s, "--spp", "4", "--shards", "2", "-o", p],
    );
    assert!(e.contains("different plan") && e.contains("--force"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_study_plan_is_collected_from_the_cache() {
    let dir = scratch("cluster-study");
    let lt = lt_binary(&dir);
    let plan = dir.join("plan");
    let results = dir.join("results");
    let scenes = scenes_dir();
    let cache = results.join("cache");
    let args = [
        "plan",
        "study",
        "smoke",
        "--scale",
        "test",
        "--results",
        results.to_str().unwrap(),
        "--scenes",
        scenes.to_str().unwrap(),
        "--cache",
        cache.to_str().unwrap(),
        "-o",
        plan.to_str().unwrap(),
    ];
    lt_ok(&lt, &args);
    let out = lt_ok(&lt, &["submit", plan.to_str().unwrap(), "--local"]);
    assert!(
        out.contains("2 renders found in the cache, 0 made here"),
        "{out}"
    );
    assert!(results.join("smoke").join("summary.json").is_file());

    // The same study with its renders split into pass ranges (cut at the snapshots 1, 2, 4):
    // collecting merges them into the renders' own entries, equal to the whole renders within
    // one f32 ulp, and the study then finds every render.
    let split_plan = dir.join("split-plan");
    let split_cache = dir.join("split-cache");
    let mut args2 = args.to_vec();
    let (sc, sp) = (split_cache.to_str().unwrap(), split_plan.to_str().unwrap());
    args2[10] = sc;
    args2[12] = sp;
    args2.extend(["--split-passes", "2"]);
    lt_ok(&lt, &args2);
    let planned = lt_experiments::cluster::plan::Plan::read(&split_plan).unwrap();
    assert_eq!((planned.shards.len(), planned.assemble.len()), (6, 2));
    let out = lt_ok(&lt, &["submit", sp, "--local"]);
    assert!(
        out.contains("merged the pass ranges of 2 split renders")
            && out.contains("2 renders found in the cache, 0 made here"),
        "{out}"
    );
    let (whole, split) = (
        lt_experiments::cache::RenderCache::new(&cache),
        lt_experiments::cache::RenderCache::new(&split_cache),
    );
    let mut worst = 0;
    for a in &planned.assemble {
        let key = lt_experiments::cache::Key(a.key.clone());
        let (dw, ds) = (whole.lookup(&key).unwrap(), split.lookup(&key).unwrap());
        for f in [
            "snapshot-1.exr",
            "snapshot-2.exr",
            "snapshot-4.exr",
            "stderr.exr",
        ] {
            let (ulps, _, _) = ulp_distance(&dw.join(f), &ds.join(f));
            worst = worst.max(ulps);
        }
    }
    eprintln!("split study renders vs whole ones: at most {worst} f32 ulp");
    assert!(worst <= 1);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_study_of_the_testbed_is_planned_and_collected_from_the_cache() {
    let dir = scratch("cluster-real-study");
    let lt = lt_binary(&dir);
    let plan = dir.join("plan");
    let results = dir.join("results");
    let scenes = scenes_dir();
    let p = plan.to_str().unwrap();
    lt_ok(
        &lt,
        &[
            "plan",
            "study",
            "convergence",
            "--scale",
            "test",
            "--results",
            results.to_str().unwrap(),
            "--scenes",
            scenes.to_str().unwrap(),
            "--threads",
            "1",
            "-o",
            p,
        ],
    );
    let planned = lt_experiments::cluster::plan::Plan::read(&plan).unwrap();
    let n = planned.shards.len();
    let references = planned
        .shards
        .iter()
        .filter(|s| s.cache == results.join("references"))
        .count();
    assert!(
        n > 10 && references >= 1,
        "{n} shards, {references} references"
    );
    let out = lt_ok(&lt, &["submit", p, "--local"]);
    assert!(
        out.contains(&format!("({n} renders found in the cache, 0 made here)")),
        "{out}"
    );
    assert!(results.join("convergence").join("manifest.json").is_file());
    eprintln!("study convergence (test scale): {n} shards ({references} references), collected with every render from the cache");
    let _ = std::fs::remove_dir_all(&dir);
}

//! What the cluster tests (`cluster_*`) share: the `lt` binary they drive, a small scene, and
//! image comparison in f32 ulps.

#![allow(dead_code)]

use lt_experiments::cluster::plan::Plan;
use lt_experiments::cluster::shard::{read_state, ShardState};
use lt_experiments::image_io::read_exr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository's `scenes/` folder.
pub fn scenes_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

/// A fresh scratch folder for test `name`.
pub fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lt-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The `lt` binary, copied once per test process (so that a rebuild during the tests cannot
/// change it under the shards). `LT_BIN` names one; else it is the `lt` cargo built beside this
/// test (the workspace's `cargo test` builds it).
pub fn lt_binary(_dir: &Path) -> PathBuf {
    static COPY: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    COPY.get_or_init(|| {
        let built = match std::env::var_os("LT_BIN") {
            Some(p) => PathBuf::from(p),
            None => {
                let exe = std::env::current_exe().unwrap();
                // target/<profile>/deps/<test>-<hash> → target/<profile>/lt
                exe.parent().unwrap().parent().unwrap().join("lt")
            }
        };
        assert!(
            built.is_file(),
            "no lt binary at {}: build it (cargo build --release --bin lt) or set LT_BIN",
            built.display()
        );
        // One copy per build (named by size and modification time), shared by test processes.
        let meta = built.metadata().unwrap();
        let stamp = meta
            .modified()
            .unwrap()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .as_nanos();
        let dir = std::env::temp_dir().join(format!("lt-test-bin-{}-{stamp}", meta.len()));
        let copy = dir.join("lt");
        if !copy.is_file() {
            std::fs::create_dir_all(&dir).unwrap();
            let tmp = dir.join(format!("lt.part-{}", std::process::id()));
            std::fs::copy(&built, &tmp).unwrap();
            std::fs::rename(&tmp, &copy).unwrap();
        }
        copy
    })
    .clone()
}

/// Runs `cmd`; retries while the binary is "text file busy" (a file being written when another
/// test thread forked keeps a write handle until that child execs).
pub fn run(cmd: &mut Command) -> Output {
    for _ in 0..100 {
        match cmd.output() {
            Err(e) if e.raw_os_error() == Some(26) => {
                std::thread::sleep(std::time::Duration::from_millis(20))
            }
            r => return r.unwrap_or_else(|e| panic!("cannot run {cmd:?}: {e}")),
        }
    }
    panic!("{cmd:?}: text file busy for 2 s")
}

/// Runs `lt ARGS`, asserting success; returns stdout + stderr.
pub fn lt_ok(lt: &Path, args: &[&str]) -> String {
    let out = run(Command::new(lt).args(args));
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

/// Runs `lt ARGS`, asserting failure; returns stderr.
pub fn lt_err(lt: &Path, args: &[&str]) -> String {
    let out = run(Command::new(lt).args(args));
    let text = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        !out.status.success(),
        "lt {} should have failed:\n{text}",
        args.join(" ")
    );
    assert!(!text.contains("panicked"), "a panic, not an error:\n{text}");
    text
}

/// The Cornell box at a small resolution, written into `dir` (its content is what is hashed).
pub fn small_scene(dir: &Path, w: u32, h: u32) -> PathBuf {
    let src = scenes_dir().join("cornell-box.toml");
    let text = std::fs::read_to_string(src).unwrap();
    assert!(text.contains("resolution = [256, 256]"));
    let text = text.replace(
        "resolution = [256, 256]",
        &format!("resolution = [{w}, {h}]"),
    );
    let p = dir.join(format!("cornell-{w}x{h}.toml"));
    std::fs::write(&p, text).unwrap();
    p
}

/// How far apart two EXR images are, in units of the f32 spacing at each value: (largest
/// difference in ulps, how many values differ at all, values compared).
pub fn ulp_distance(a: &Path, b: &Path) -> (u32, usize, usize) {
    let (ia, ib) = (read_exr(a).unwrap(), read_exr(b).unwrap());
    assert_eq!((ia.width, ia.height), (ib.width, ib.height));
    let (mut worst, mut differ, mut n) = (0u32, 0usize, 0usize);
    for (pa, pb) in ia.data.iter().zip(&ib.data) {
        for c in 0..3 {
            let (x, y) = (pa[c] as f32, pb[c] as f32);
            n += 1;
            if x.to_bits() == y.to_bits() {
                continue;
            }
            differ += 1;
            let d = if x.is_sign_negative() == y.is_sign_negative() {
                x.to_bits().abs_diff(y.to_bits())
            } else {
                u32::MAX
            };
            worst = worst.max(d);
        }
    }
    (worst, differ, n)
}

/// Whether `tool` is on PATH.
pub fn installed(tool: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {tool}")])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false)
}

/// True if `tools` are all installed; otherwise says so loudly, naming the Debian `packages`
/// that provide them, and fails when `require_var=1`.
pub fn have(tools: &[&str], packages: &str, require_var: &str) -> bool {
    let missing: Vec<&str> = tools.iter().copied().filter(|t| !installed(t)).collect();
    if missing.is_empty() {
        return true;
    }
    let msg = format!(
        "{} not installed: install them (Debian: apt-get install {packages}) to run this test",
        missing.join(", "),
    );
    if std::env::var(require_var).as_deref() == Ok("1") {
        panic!("{require_var}=1 but {msg}");
    }
    // Straight to stderr, past the test harness's capture, so a skip is seen.
    use std::io::Write;
    let bar = "!".repeat(78);
    let _ = writeln!(std::io::stderr(), "\n{bar}\nSKIPPED: {msg}\n{bar}\n");
    false
}

/// Polls `done` every 50 ms for at most `secs` seconds.
pub fn wait_for(secs: f64, mut done: impl FnMut() -> bool) -> bool {
    let t = std::time::Instant::now();
    while t.elapsed().as_secs_f64() < secs {
        if done() {
            return true;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    done()
}

pub fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_default()
}

/// A shard's state file.
pub fn state(plan: &Path, i: usize) -> Option<ShardState> {
    read_state(plan, i)
}

/// Modification times of the cache entries of a plan's shards (None while unfinished).
pub fn entry_times(plan: &Path) -> Vec<Option<std::time::SystemTime>> {
    let p = Plan::read(plan).unwrap();
    (0..p.shards.len())
        .map(|i| {
            p.finished(i)
                .and_then(|d| d.join("partial.ltp").metadata().ok())
                .and_then(|m| m.modified().ok())
        })
        .collect()
}

/// The one-process render a collected plan must equal: `lt render SCENE --spp N --threads 2`
/// into `out`. Returns its wall seconds.
pub fn one_process_render(lt: &Path, scene: &Path, spp: u32, out: &Path) -> f64 {
    let t = std::time::Instant::now();
    let n = spp.to_string();
    let args = [
        "render",
        scene.to_str().unwrap(),
        "--spp",
        &n,
        "--threads",
        "2",
        "--quiet",
        "-o",
    ];
    let mut all: Vec<&str> = args.to_vec();
    all.push(out.to_str().unwrap());
    lt_ok(lt, &all);
    t.elapsed().as_secs_f64()
}

/// `lt plan render SCENE --spp N --shards K --threads 1 -o PLAN --cache CACHE`.
pub fn plan_render(lt: &Path, scene: &Path, spp: u32, shards: u32, plan: &Path, cache: &Path) {
    let (n, k) = (spp.to_string(), shards.to_string());
    lt_ok(
        lt,
        &[
            "plan",
            "render",
            scene.to_str().unwrap(),
            "--spp",
            &n,
            "--shards",
            &k,
            "--threads",
            "1",
            "-o",
            plan.to_str().unwrap(),
            "--cache",
            cache.to_str().unwrap(),
        ],
    );
}

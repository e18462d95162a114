//! The `lt` binary end to end: a render writes its four files, bad input gives one clear error
//! and a non-zero exit, never a panic.

use std::path::PathBuf;
use std::process::Command;

fn lt() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lt"))
}

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lt-cli-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn render_writes_exr_png_stderr_and_record() {
    let dir = temp_dir("render");
    let out = dir.join("cb.exr");
    let status = lt()
        .args(["render", "--spp", "2", "--quiet", "--threads", "2", "-o"])
        .arg(&out)
        .arg(repo().join("scenes/cornell-box.toml"))
        .status()
        .unwrap();
    assert!(status.success());
    for f in ["cb.exr", "cb.png", "cb.stderr.exr", "cb.json"] {
        assert!(
            dir.join(f).metadata().map(|m| m.len() > 0).unwrap_or(false),
            "{f} missing"
        );
    }
    let record = std::fs::read_to_string(dir.join("cb.json")).unwrap();
    assert!(
        record.contains("\"spp\": 2") && record.contains("\"invalid_samples\": 0"),
        "{record}"
    );
    let img = lt_experiments::image_io::read_exr(&out).unwrap();
    assert_eq!((img.width, img.height), (256, 256));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_bad_scene_is_one_clear_error() {
    let dir = temp_dir("bad");
    let scene = dir.join("broken.toml");
    std::fs::write(&scene, "[camera]\neye = [0, 0, 1]\ntarget = [0, 0, 0]\nfov = 40\nresolution = [8, 8]\n\n[materials.m]\ntype = \"velvet\"\n").unwrap();
    let out = lt()
        .args(["render", "-o"])
        .arg(dir.join("x.exr"))
        .arg(&scene)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("broken.toml") && err.contains("velvet") && !err.contains("panicked"),
        "{err}"
    );
    assert!(!dir.join("x.exr").exists());
    let out = lt()
        .args(["render", "-i", "vcm-42", "-o"])
        .arg(dir.join("y.exr"))
        .arg(repo().join("scenes/cornell-box.toml"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("unknown integrator 'vcm-42'"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// One run of a consistent estimator has no honest error bar: no `.stderr.exr` is written (and
/// a stale one is removed); `--runs 2` writes the error across the runs and says so.
#[test]
fn consistent_estimators_get_error_bars_only_from_runs() {
    let dir = temp_dir("runs");
    let out = dir.join("pm.exr");
    let stderr = dir.join("pm.stderr.exr");
    std::fs::write(&stderr, b"stale").unwrap();
    let render = |extra: &[&str]| {
        let status = lt()
            .args([
                "render",
                "-i",
                "pm",
                "--spp",
                "1",
                "--photons",
                "20000",
                "--quiet",
                "-o",
            ])
            .arg(&out)
            .args(extra)
            .arg(repo().join("scenes/cornell-box.toml"))
            .status()
            .unwrap();
        assert!(status.success());
        std::fs::read_to_string(dir.join("pm.json")).unwrap()
    };
    let one = render(&[]);
    assert!(
        !stderr.exists(),
        "a stale stderr.exr survived one run of pm"
    );
    assert!(one.contains("\"kind\": \"consistent\""), "{one}");
    assert!(one.contains("\"mean_std_error\": null"), "{one}");
    let two = render(&["--runs", "2"]);
    assert!(stderr.exists(), "--runs 2 wrote no stderr.exr");
    assert!(
        two.contains("\"std_error_source\": \"independent runs\""),
        "{two}"
    );
    assert!(
        two.contains("\"run_seeds\": [\n    1,\n    2\n  ]"),
        "{two}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// `--no-merge` reaches vcm as `merging = false` (its image is then bdpt's, see
/// tests/vcm_is_bdpt.rs), and the record says so; other integrators refuse the key.
#[test]
fn no_merge_turns_vcm_into_bdpt() {
    let dir = temp_dir("no_merge");
    let render = |integrator: &str, extra: &[&str]| {
        let out = dir.join(format!("{integrator}.exr"));
        let o = lt()
            .args(["render", "-i", integrator, "--spp", "1", "--quiet", "-o"])
            .arg(&out)
            .args(extra)
            .arg(repo().join("scenes/cornell-box.toml"))
            .output()
            .unwrap();
        (
            o.status.success(),
            String::from_utf8_lossy(&o.stderr).to_string(),
        )
    };
    let (ok, err) = render("vcm", &["--no-merge"]);
    assert!(ok, "{err}");
    let record = std::fs::read_to_string(dir.join("vcm.json")).unwrap();
    assert!(record.contains("merging"), "{record}");
    let (ok, err) = render("bdpt", &["--no-merge"]);
    assert!(!ok, "bdpt took --no-merge");
    assert!(err.contains("merging"), "{err}");
    let _ = std::fs::remove_dir_all(dir);
}

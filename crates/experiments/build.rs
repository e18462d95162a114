//! Computes the code version the cache keys carry: a hash of every source file that decides what
//! a render produces (core, scene-io and integrators, their manifests and the lock file). Editing a study
//! or the report does not invalidate finished renders; editing an integrator does.

use std::path::{Path, PathBuf};

fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            collect(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs" || x == "toml") {
            out.push(p);
        }
    }
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let inputs = [
        root.join("crates/core"),
        root.join("crates/scene-io"),
        root.join("crates/integrators"),
    ];
    let mut files = Vec::new();
    for dir in &inputs {
        println!("cargo:rerun-if-changed={}", dir.display());
        collect(dir, &mut files);
    }
    let lock = root.join("Cargo.lock");
    println!("cargo:rerun-if-changed={}", lock.display());
    files.push(lock);
    files.retain(|p| !p.components().any(|c| c.as_os_str() == "target"));
    let mut rel: Vec<(String, PathBuf)> = files
        .into_iter()
        .map(|p| {
            let r = p
                .strip_prefix(&root)
                .unwrap_or(&p)
                .to_string_lossy()
                .replace('\\', "/");
            (r, p)
        })
        .collect();
    rel.sort();
    let mut h = blake3::Hasher::new();
    for (name, path) in &rel {
        let bytes = std::fs::read(path).unwrap_or_default();
        h.update(name.as_bytes());
        h.update(&(bytes.len() as u64).to_le_bytes());
        h.update(&bytes);
    }
    let hex = h.finalize().to_hex();
    println!("cargo:rustc-env=LT_CODE_VERSION={}", &hex[..16]);
}

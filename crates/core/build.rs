//! Finds Embree 3 (Debian's `libembree-dev`) and, when it is there, builds the `embree` ray core
//! (`geometry/embree.rs`, cfg `lt_embree`). Without it the portable cores build alone, so a
//! machine without Embree still builds and tests everything else. `LT_EMBREE=0` leaves it out;
//! `LT_EMBREE_DIR` names a folder holding `libembree3.so` beyond the usual ones.

use std::path::PathBuf;

fn main() {
    println!("cargo::rustc-check-cfg=cfg(lt_embree)");
    println!("cargo:rerun-if-env-changed=LT_EMBREE");
    println!("cargo:rerun-if-env-changed=LT_EMBREE_DIR");
    if std::env::var("LT_EMBREE").is_ok_and(|v| v == "0") {
        return;
    }
    let mut dirs: Vec<PathBuf> = std::env::var_os("LT_EMBREE_DIR")
        .map(|d| vec![PathBuf::from(d)])
        .unwrap_or_default();
    dirs.extend(
        [
            "/usr/lib/x86_64-linux-gnu",
            "/usr/lib/aarch64-linux-gnu",
            "/usr/lib64",
            "/usr/lib",
            "/usr/local/lib",
        ]
        .map(PathBuf::from),
    );
    if let Some(dir) = dirs.iter().find(|d| d.join("libembree3.so").is_file()) {
        println!(
            "cargo:rerun-if-changed={}",
            dir.join("libembree3.so").display()
        );
        println!("cargo:rustc-link-search=native={}", dir.display());
        println!("cargo:rustc-link-lib=dylib=embree3");
        println!("cargo:rustc-cfg=lt_embree");
    }
}

//! The one content-addressed cache of finished work: references, study runs and cluster shards
//! all live in it. An entry is a folder named by the hash of what made it — the key material (a
//! JSON value: scene content hash, integrator, parameters, seeds, pass counts) together with the
//! code version — so a rerun finds what is finished and redoes nothing, and any change to a scene
//! or to the rendering code makes new entries instead of serving stale ones.
//!
//! An entry is built in a temporary folder and renamed into place, so an interrupted run leaves
//! no half-written entry: it is either finished and complete, or absent.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// Hash of the sources that decide what a render produces (see build.rs).
pub const CODE_VERSION: &str = env!("LT_CODE_VERSION");

/// The file in every entry holding its key material, for a reader who wants to know what it is.
pub const KEY_FILE: &str = "key.json";

#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Key(pub String);

impl std::fmt::Display for Key {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

/// The key of some material: blake3 over the code version and the canonical JSON (serde_json's
/// maps are sorted, so equal values serialise to equal bytes).
pub fn key_of(material: &Value) -> Key {
    let mut h = blake3::Hasher::new();
    h.update(CODE_VERSION.as_bytes());
    h.update(b"\n");
    h.update(material.to_string().as_bytes());
    Key(h.finalize().to_hex()[..32].to_string())
}

/// The content hash of a scene: every file it was read from (`Scene::source_files`), names
/// excluded, so a moved or copied scene keeps its hash and an edited mesh changes it; and the
/// load options that changed what was read (`-D` definitions of an XML scene, `--approximate`),
/// when given.
pub fn scene_hash(files: &[PathBuf]) -> Result<String, String> {
    if files.is_empty() {
        return Err("the scene names no source files, so it has no content hash".into());
    }
    let mut h = blake3::Hasher::new();
    for f in files {
        let bytes =
            std::fs::read(f).map_err(|e| format!("cannot read {} to hash it: {e}", f.display()))?;
        h.update(&(bytes.len() as u64).to_le_bytes());
        h.update(&bytes);
    }
    // The options the scene was read with (`scene_load`: the first file is the scene's own).
    let opts = crate::scene_load::options_for(&files[0]);
    if opts.approximate || !opts.defines.is_empty() {
        h.update(format!("load {} {:?}", opts.approximate, opts.defines).as_bytes());
    }
    Ok(h.finalize().to_hex()[..32].to_string())
}

/// A cache folder, and how many entries this handle (and its clones) built and found finished:
/// what a resumed run reports.
#[derive(Clone, Debug)]
pub struct RenderCache {
    pub root: PathBuf,
    built: Arc<AtomicU64>,
    reused: Arc<AtomicU64>,
}

impl RenderCache {
    pub fn new(root: impl Into<PathBuf>) -> RenderCache {
        RenderCache {
            root: root.into(),
            built: Arc::default(),
            reused: Arc::default(),
        }
    }

    /// (entries built, entries found finished) through this handle.
    pub fn counts(&self) -> (u64, u64) {
        (
            self.built.load(Ordering::SeqCst),
            self.reused.load(Ordering::SeqCst),
        )
    }

    /// Where the entry of `key` lives (whether or not it is finished).
    pub fn path(&self, key: &Key) -> PathBuf {
        self.root.join(&key.0[..2]).join(&key.0)
    }

    /// The finished entry of `key`, if there is one.
    pub fn lookup(&self, key: &Key) -> Option<PathBuf> {
        let p = self.path(key);
        p.join(KEY_FILE).is_file().then_some(p)
    }

    /// The entry of `material`: the finished one if it exists, else `build` fills a fresh folder
    /// which then becomes the entry in one rename. When two processes race, the first rename
    /// wins and the other's folder is dropped; both return the winner.
    pub fn get_or_build(
        &self,
        material: &Value,
        build: impl FnOnce(&Path) -> Result<(), String>,
    ) -> Result<PathBuf, String> {
        let key = key_of(material);
        if let Some(p) = self.lookup(&key) {
            self.reused.fetch_add(1, Ordering::SeqCst);
            return Ok(p);
        }
        let dest = self.path(&key);
        let parent = dest.parent().expect("entries have a parent folder");
        std::fs::create_dir_all(parent)
            .map_err(|e| format!("cannot create the cache folder {}: {e}", parent.display()))?;
        // Host and pid name the builder, so processes on different hosts of a shared
        // filesystem never share a folder; folders this host's dead processes left are removed.
        let host = hostname();
        let tmp = parent.join(format!(".tmp-{}-{host}-{}", key.0, std::process::id()));
        remove_stale(parent, &key, &host);
        let _ = std::fs::remove_dir_all(&tmp);
        std::fs::create_dir_all(&tmp)
            .map_err(|e| format!("cannot create {}: {e}", tmp.display()))?;
        let result = build(&tmp).and_then(|()| {
            let text = serde_json::to_string_pretty(&serde_json::json!({
                "code_version": CODE_VERSION,
                "material": material,
            }))
            .map_err(|e| e.to_string())?;
            std::fs::write(tmp.join(KEY_FILE), text)
                .map_err(|e| format!("cannot write {}: {e}", tmp.join(KEY_FILE).display()))
        });
        if let Err(e) = result {
            let _ = std::fs::remove_dir_all(&tmp);
            return Err(e);
        }
        match std::fs::rename(&tmp, &dest) {
            Ok(()) => {
                self.built.fetch_add(1, Ordering::SeqCst);
                Ok(dest)
            }
            Err(_) if self.lookup(&key).is_some() => {
                let _ = std::fs::remove_dir_all(&tmp);
                self.reused.fetch_add(1, Ordering::SeqCst);
                Ok(dest)
            }
            Err(e) => {
                let _ = std::fs::remove_dir_all(&tmp);
                Err(format!(
                    "cannot move the finished entry into {}: {e}",
                    dest.display()
                ))
            }
        }
    }
}

fn hostname() -> String {
    let h = std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .or_else(|| std::env::var("HOSTNAME").ok())
        .unwrap_or_else(|| "host".into());
    h.trim().replace(['/', '-'], "_")
}

/// Removes `.tmp-KEY-HOST-PID` folders of this host whose process is gone (killed builds).
fn remove_stale(parent: &Path, key: &Key, host: &str) {
    let prefix = format!(".tmp-{}-{host}-", key.0);
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().to_string();
        let Some(pid) = name.strip_prefix(&prefix) else {
            continue;
        };
        let alive = pid
            .parse::<u32>()
            .is_ok_and(|p| Path::new(&format!("/proc/{p}")).exists());
        if !alive {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_cache(name: &str) -> RenderCache {
        let dir = std::env::temp_dir().join(format!("lt-cache-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        RenderCache::new(dir)
    }

    #[test]
    fn equal_material_is_built_once_and_different_material_twice() {
        let cache = temp_cache("once");
        let mut builds = 0;
        let a = serde_json::json!({"seed": 1, "integrator": "pt"});
        // Same map, other insertion order: the same key.
        let a2 = serde_json::json!({"integrator": "pt", "seed": 1});
        let b = serde_json::json!({"seed": 2, "integrator": "pt"});
        for m in [&a, &a2, &b, &a] {
            cache
                .get_or_build(m, |dir| {
                    builds += 1;
                    std::fs::write(dir.join("x"), b"1").map_err(|e| e.to_string())
                })
                .unwrap();
        }
        assert_eq!(builds, 2);
        assert_eq!(key_of(&a), key_of(&a2));
        assert_ne!(key_of(&a), key_of(&b));
    }

    #[test]
    fn a_failed_build_leaves_no_entry() {
        let cache = temp_cache("fail");
        let m = serde_json::json!({"n": 1});
        let r = cache.get_or_build(&m, |dir| {
            std::fs::write(dir.join("half"), b"x").unwrap();
            Err("interrupted".into())
        });
        assert!(r.is_err());
        assert!(cache.lookup(&key_of(&m)).is_none());
        let leftovers = std::fs::read_dir(cache.path(&key_of(&m)).parent().unwrap())
            .unwrap()
            .count();
        assert_eq!(leftovers, 0, "the temporary folder is removed");
    }

    #[test]
    fn a_killed_builds_folder_is_removed_by_the_next_build() {
        let cache = temp_cache("stale");
        let m = serde_json::json!({"n": 2});
        let key = key_of(&m);
        let parent = cache.path(&key).parent().unwrap().to_path_buf();
        // A pid that cannot be alive (above Linux's pid_max).
        let stale = parent.join(format!(".tmp-{}-{}-4294967295", key.0, hostname()));
        std::fs::create_dir_all(&stale).unwrap();
        cache.get_or_build(&m, |_| Ok(())).unwrap();
        assert!(!stale.exists());
    }
}

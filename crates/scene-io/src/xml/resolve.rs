//! Mitsuba's file resolver: a relative file name (an `<include>`, a mesh, a texture) is looked up
//! in the main scene file's folder first, then in each folder a `<path value="…"/>` names
//! (relative to the main scene file's folder), in document order. An included fragment's own
//! names resolve the same way, not against the fragment's folder. An absolute name is taken as
//! it is.

use std::path::{Path, PathBuf};

#[derive(Clone, Debug)]
pub(crate) struct Resolver {
    /// The scene file's folder, then every `<path>` folder.
    dirs: Vec<PathBuf>,
}

impl Resolver {
    pub fn new(scene_file: &Path) -> Resolver {
        Resolver {
            dirs: vec![scene_folder(scene_file)],
        }
    }

    /// A `<path value>` (relative to the scene file's folder unless absolute).
    pub fn add(&mut self, value: &str) {
        let dir = self.dirs[0].join(value);
        if !self.dirs.contains(&dir) {
            self.dirs.push(dir);
        }
    }

    /// The first existing file of that name, or every candidate looked at (for the error).
    pub fn resolve(&self, name: &str) -> Result<PathBuf, Vec<PathBuf>> {
        let candidates = self.candidates(name);
        match candidates.iter().find(|p| p.is_file()) {
            Some(p) => Ok(p.clone()),
            None => Err(candidates),
        }
    }

    /// The message for a name `resolve` did not find.
    pub fn not_found(what: &str, name: &str, looked: &[PathBuf]) -> String {
        let list: Vec<String> = looked.iter().map(|p| p.display().to_string()).collect();
        format!(
            "{what} `{name}` not found in the scene's folder or a <path> folder (looked for {})",
            list.join(", ")
        )
    }

    fn candidates(&self, name: &str) -> Vec<PathBuf> {
        if Path::new(name).is_absolute() {
            return vec![PathBuf::from(name)];
        }
        self.dirs.iter().map(|d| d.join(name)).collect()
    }
}

fn scene_folder(scene_file: &Path) -> PathBuf {
    scene_file
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xml_resolver_tries_the_scene_folder_then_each_path() {
        let tmp = std::env::temp_dir().join(format!("lt-resolve-{}", std::process::id()));
        std::fs::create_dir_all(tmp.join("scene/sub")).unwrap();
        std::fs::create_dir_all(tmp.join("common/meshes")).unwrap();
        std::fs::write(tmp.join("common/meshes/a.obj"), "").unwrap();
        std::fs::write(tmp.join("scene/sub/b.xml"), "").unwrap();
        let mut r = Resolver::new(&tmp.join("scene/main.xml"));
        assert!(r.resolve("meshes/a.obj").is_err());
        r.add("../common");
        assert_eq!(
            r.resolve("meshes/a.obj").unwrap(),
            tmp.join("scene/../common/meshes/a.obj")
        );
        assert_eq!(r.resolve("sub/b.xml").unwrap(), tmp.join("scene/sub/b.xml"));
        let looked = r.resolve("c.obj").unwrap_err();
        assert_eq!(
            looked,
            vec![tmp.join("scene/c.obj"), tmp.join("scene/../common/c.obj")]
        );
        std::fs::remove_dir_all(&tmp).unwrap();
    }
}

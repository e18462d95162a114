//! The XML document as the plugin code sees it: an owned element tree with every `include`
//! spliced in, every `default` applied, every `$name` substituted and, in files older than
//! version 2, every parameter name upgraded from camelCase to snake_case (what Mitsuba 3 does
//! when it reads a 0.6 file). Each element remembers its source file and byte range, so any later
//! error can name the file, line and column. `<path>` elements feed the file resolver
//! (`resolve`), through which includes here and meshes later are found; definitions given on the
//! command line (`-D key=value`) come before every `<default>`, so they win.

use super::resolve::Resolver;
use crate::error::Ctx;
use crate::SceneError;
use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Includes nested deeper than this are taken for a cycle.
const MAX_INCLUDE_DEPTH: usize = 16;

/// One file read: the scene file first, then every included file.
pub(crate) struct Source {
    pub path: PathBuf,
    pub shown: String,
    pub text: String,
    /// The file's format version as written (`version="0.6.0"` gives (0, 6, 0)).
    pub version: (u32, u32, u32),
}

#[derive(Debug)]
pub(crate) struct Elem {
    pub tag: String,
    /// Attributes after substitution (and the 0.6 upgrade of `name`), in document order.
    pub attrs: Vec<(String, String)>,
    pub children: Vec<Elem>,
    /// Index into `Doc::sources`.
    pub src: usize,
    pub range: Range<usize>,
}

impl Elem {
    pub fn attr(&self, key: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
}

pub(crate) struct Doc {
    pub sources: Vec<Source>,
    /// The `<scene>` element of the scene file, includes spliced in.
    pub root: Elem,
    /// The scene file's folder and every `<path>` folder.
    pub resolver: Resolver,
}

impl Doc {
    /// The error context of an element's file (for `Ctx::at`).
    pub fn ctx(&self, src: usize) -> Ctx<'_> {
        let s = &self.sources[src];
        Ctx {
            file: s.shown.clone(),
            text: &s.text,
            base_dir: s.path.parent().map(Path::to_path_buf).unwrap_or_default(),
        }
    }

    /// An error at the element's start tag.
    pub fn err(&self, e: &Elem, message: impl Into<String>) -> SceneError {
        self.ctx(e.src).at(e.range.clone(), message)
    }

    /// "file:line" of the element, for report entries.
    pub fn place(&self, e: &Elem) -> String {
        let err = self.err(e, "");
        match err.line {
            Some(l) => format!("{}:{l}", err.file),
            None => err.file,
        }
    }
}

/// Reads the scene file and everything it includes; `defines` are the command line's
/// `-D key=value` definitions.
pub(super) fn read(path: &Path, defines: &[(String, String)]) -> Result<Doc, SceneError> {
    let mut r = Reader {
        sources: Vec::new(),
        params: HashMap::new(),
        resolver: Resolver::new(path),
    };
    for (k, v) in defines {
        r.params.entry(k.clone()).or_insert_with(|| v.clone());
    }
    let root = r.file(path, path.display().to_string(), 0, None)?;
    Ok(Doc {
        sources: r.sources,
        root,
        resolver: r.resolver,
    })
}

struct Reader {
    sources: Vec<Source>,
    /// Command-line definitions, then `default` values (first definition wins).
    params: HashMap<String, String>,
    resolver: Resolver,
}

impl Reader {
    fn file_error(
        &self,
        shown: &str,
        line: Option<usize>,
        col: Option<usize>,
        m: String,
    ) -> SceneError {
        SceneError {
            file: shown.to_string(),
            line,
            column: col,
            message: m,
        }
    }

    /// Parses one file into its `<scene>` element. `from` is the include element, if any, that
    /// a missing file is reported at.
    fn file(
        &mut self,
        path: &Path,
        shown: String,
        depth: usize,
        from: Option<(&Source, &Range<usize>)>,
    ) -> Result<Elem, SceneError> {
        let text = match std::fs::read_to_string(path) {
            Ok(t) => t,
            Err(e) => {
                let message = format!("cannot read the scene file {}: {e}", path.display());
                return Err(match from {
                    Some((s, range)) => Ctx {
                        file: s.shown.clone(),
                        text: &s.text,
                        base_dir: PathBuf::new(),
                    }
                    .at(range.clone(), message),
                    None => self.file_error(&shown, None, None, message),
                });
            }
        };
        let opts = roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        };
        let doc = roxmltree::Document::parse_with_options(&text, opts).map_err(|e| {
            let p = e.pos();
            self.file_error(
                &shown,
                Some(p.row as usize),
                Some(p.col as usize),
                format!("malformed XML: {e}"),
            )
        })?;
        let root = doc.root_element();
        let at = |node: roxmltree::Node, m: String| {
            let p = doc.text_pos_at(node.range().start);
            self.file_error(&shown, Some(p.row as usize), Some(p.col as usize), m)
        };
        if root.tag_name().name() != "scene" {
            return Err(at(
                root,
                format!(
                    "the root element is <{}>, expected <scene version=\"3.0.0\">",
                    root.tag_name().name()
                ),
            ));
        }
        let Some(v) = root.attribute("version") else {
            return Err(at(
                root,
                "<scene> has no `version` attribute (write e.g. version=\"3.0.0\")".into(),
            ));
        };
        let version = parse_version(v).ok_or_else(|| {
            at(
                root,
                format!("`version` must be MAJOR.MINOR.PATCH, got `{v}`"),
            )
        })?;
        if version.0 > 3 || version.0 == 1 {
            return Err(at(
                root,
                format!("scene format version {v} is not one this loader reads (0.x, 2.x and 3.x)"),
            ));
        }
        let src = self.sources.len();
        self.sources.push(Source {
            path: path.to_path_buf(),
            shown,
            text: text.clone(),
            version,
        });
        let upgrade = version.0 < 2;
        let mut out = self.element(root, src, upgrade, depth)?;
        Ok(out
            .pop()
            .expect("the root element is never an include or a default"))
    }

    /// An element with its children: no element for `default`, the included file's children for
    /// `include`, else the element itself.
    fn element(
        &mut self,
        node: roxmltree::Node,
        src: usize,
        upgrade: bool,
        depth: usize,
    ) -> Result<Vec<Elem>, SceneError> {
        let range = node.range();
        let err = |r: &Reader, m: String| {
            let s = &r.sources[src];
            Ctx {
                file: s.shown.clone(),
                text: &s.text,
                base_dir: PathBuf::new(),
            }
            .at(range.clone(), m)
        };
        let tag = node.tag_name().name().to_string();
        let mut attrs = Vec::new();
        for a in node.attributes() {
            let value = substitute(a.value(), &self.params).map_err(|m| err(self, m))?;
            let value = if upgrade && a.name() == "name" {
                camel_to_snake(&value)
            } else {
                value
            };
            attrs.push((a.name().to_string(), value));
        }
        let get = |k: &str| attrs.iter().find(|(n, _)| n == k).map(|(_, v)| v.clone());
        match tag.as_str() {
            "default" => {
                let (Some(name), Some(value)) = (get("name"), get("value")) else {
                    return Err(err(self, "<default> needs `name` and `value`".into()));
                };
                self.params.entry(name).or_insert(value);
                return Ok(Vec::new());
            }
            "path" => {
                let Some(value) = get("value") else {
                    return Err(err(
                        self,
                        "<path> needs a `value` (a folder to look for files in)".into(),
                    ));
                };
                self.resolver.add(&value);
                return Ok(Vec::new());
            }
            "include" => {
                let Some(file) = get("filename") else {
                    return Err(err(self, "<include> needs a `filename`".into()));
                };
                if depth >= MAX_INCLUDE_DEPTH {
                    return Err(err(
                        self,
                        format!("includes nested more than {MAX_INCLUDE_DEPTH} deep (a cycle?)"),
                    ));
                }
                let path = self.resolver.resolve(&file).map_err(|looked| {
                    err(self, Resolver::not_found("included file", &file, &looked))
                })?;
                let s = &self.sources[src];
                let from = Source {
                    path: s.path.clone(),
                    shown: s.shown.clone(),
                    text: s.text.clone(),
                    version: s.version,
                };
                let root = self.file(
                    &path,
                    path.display().to_string(),
                    depth + 1,
                    Some((&from, &range)),
                )?;
                return Ok(root.children);
            }
            _ => {}
        }
        let mut children = Vec::new();
        for c in node.children().filter(|c| c.is_element()) {
            children.extend(self.element(c, src, upgrade, depth)?);
        }
        Ok(vec![Elem {
            tag,
            attrs,
            children,
            src,
            range,
        }])
    }
}

fn parse_version(v: &str) -> Option<(u32, u32, u32)> {
    let parts: Vec<u32> = v
        .trim()
        .split('.')
        .map(|p| p.parse().ok())
        .collect::<Option<_>>()?;
    match parts[..] {
        [a, b, c] => Some((a, b, c)),
        [a, b] => Some((a, b, 0)),
        _ => None,
    }
}

/// Replaces every `$name` by its value; an undefined name is an error.
fn substitute(s: &str, params: &HashMap<String, String>) -> Result<String, String> {
    if !s.contains('$') {
        return Ok(s.to_string());
    }
    let mut out = String::with_capacity(s.len());
    let mut rest = s;
    while let Some(i) = rest.find('$') {
        out.push_str(&rest[..i]);
        let after = &rest[i + 1..];
        let n = after
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
            .unwrap_or(after.len());
        let name = &after[..n];
        if name.is_empty() {
            return Err(format!("a `$` not followed by a parameter name in `{s}`"));
        }
        match params.get(name) {
            Some(v) => out.push_str(v),
            None => {
                return Err(format!(
                    "parameter `${name}` is not defined (add <default name=\"{name}\" value=\"…\"/> before its use)"
                ))
            }
        }
        rest = &after[n..];
    }
    out.push_str(rest);
    Ok(out)
}

/// Mitsuba 0.6's camelCase parameter names in Mitsuba 3's spelling: `toWorld` → `to_world`,
/// `intIOR` → `int_ior`, `sampleCount` → `sample_count`.
pub(super) fn camel_to_snake(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 4);
    let mut prev_lower = false;
    for c in s.chars() {
        if c.is_ascii_uppercase() {
            if prev_lower {
                out.push('_');
            }
            out.push(c.to_ascii_lowercase());
            prev_lower = false;
        } else {
            out.push(c);
            prev_lower = c.is_ascii_lowercase() || c.is_ascii_digit();
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xml_camel_case_upgrade() {
        for (a, b) in [
            ("toWorld", "to_world"),
            ("intIOR", "int_ior"),
            ("extIOR", "ext_ior"),
            ("sampleCount", "sample_count"),
            ("maxDepth", "max_depth"),
            ("fov", "fov"),
            ("specularReflectance", "specular_reflectance"),
            ("to_world", "to_world"),
        ] {
            assert_eq!(camel_to_snake(a), b);
        }
    }

    #[test]
    fn xml_substitution() {
        let p: HashMap<String, String> = [("spp".to_string(), "16".to_string())].into();
        assert_eq!(substitute("$spp", &p).unwrap(), "16");
        assert_eq!(substitute("a $spp b", &p).unwrap(), "a 16 b");
        assert!(substitute("$sp", &p).is_err());
        assert!(substitute("$", &p).is_err());
    }
}

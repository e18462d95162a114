//! The plugin tree as Mitsuba 3 XML text: each element on its own line, indented by depth,
//! attributes in their order, values escaped. What `lt convert` writes for every plugin it
//! builds as a tree (`toml_scene::tree`), so the writer knows no plugin's parameters.

use super::doc::Elem;
use std::fmt::Write as _;

/// `e` and everything under it, at `depth` levels of four spaces.
pub(crate) fn print(e: &Elem, depth: usize, out: &mut String) {
    let pad = "    ".repeat(depth);
    let _ = write!(out, "{pad}<{}", e.tag);
    for (k, v) in &e.attrs {
        let _ = write!(out, " {k}=\"{}\"", escape(v));
    }
    if e.children.is_empty() {
        out.push_str("/>\n");
        return;
    }
    out.push_str(">\n");
    for c in &e.children {
        print(c, depth + 1, out);
    }
    let _ = writeln!(out, "{pad}</{}>", e.tag);
}

/// Text for an XML attribute value.
pub(crate) fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Every `filename` under `e` passed through `f` (file names as the source wrote them, made
/// relative to where the XML goes).
pub(crate) fn map_filenames(e: &mut Elem, f: &dyn Fn(&str) -> String) {
    if e.tag == "string" && e.attr("name") == Some("filename") {
        for (k, v) in &mut e.attrs {
            if k == "value" {
                *v = f(v);
            }
        }
    }
    for c in &mut e.children {
        map_filenames(c, f);
    }
}

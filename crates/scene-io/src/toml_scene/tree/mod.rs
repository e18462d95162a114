//! TOML tables as the plugin tree the XML builders read (`xml::doc::Elem`): TOML's key names
//! renamed to the tree's property names, plus the few structural translations TOML needs
//! (a one-sided Mitsuba BSDF inside `twosided` for our two-sided materials, a material's
//! normal map and mask as the BSDFs around it, names as ids). Every TOML check that speaks of
//! TOML's keys is made here, before the tree exists, so errors keep naming the TOML key and
//! line; the values themselves are then built by `xml/build`, once for both formats.
//!
//! Each element's `range` is the byte span of the TOML value it comes from (of the table for a
//! plugin), and `src` is 0, the TOML file: a builder's error names the TOML line.

/// The keys of a TOML table that were given, as `[(key, Some(span) or None)]` in the order
/// listed (`field as "Key"` where the file spells it otherwise): serde knows only the union of
/// every type's keys, so each type's checks (`Ctx::only`) ask which of them the file gave.
macro_rules! given {
    ($d:expr; $($field:ident $(as $key:literal)?),* $(,)?) => {
        [$((given!(@key $field $($key)?), $d.$field.as_ref().map(toml::Spanned::span))),*]
    };
    (@key $field:ident) => { stringify!($field) };
    (@key $field:ident $key:literal) => { $key };
}

mod camera;
mod light;
mod material;
mod medium;
mod shape;
mod texture;

pub(crate) use camera::{integrator, sensor, settings};
pub(crate) use light::{light, with_medium};
pub(crate) use material::material;
pub(crate) use medium::medium;
pub(crate) use shape::shape;

use crate::xml::doc::{Doc, Elem, Source};
use crate::xml::resolve::Resolver;
use std::ops::Range;
use std::path::Path;

/// A tree element at `span` of the TOML file.
pub(crate) fn elem(tag: &str, attrs: &[(&str, &str)], span: Range<usize>) -> Elem {
    Elem {
        tag: tag.into(),
        attrs: attrs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
        children: Vec::new(),
        src: 0,
        range: span,
    }
}

/// A plugin (`<bsdf type=…>`, `<medium type=…>`, …).
pub(crate) fn plugin(tag: &str, kind: &str, span: Range<usize>) -> Elem {
    elem(tag, &[("type", kind)], span)
}

/// A plugin with one nested plugin.
pub(crate) fn wrap(tag: &str, kind: &str, span: Range<usize>, inner: Elem) -> Elem {
    let mut e = plugin(tag, kind, span);
    e.children.push(inner);
    e
}

/// The numbers as the tree writes them: the shortest decimal that reads back to the same f32,
/// which is what both loaders round every value to.
pub(crate) fn num(x: f32) -> String {
    format!("{x}")
}

pub(crate) fn float(name: &str, x: f32, span: Range<usize>) -> Elem {
    elem("float", &[("name", name), ("value", &num(x))], span)
}

/// A number the builder reads in f64 (its exact decimal).
pub(crate) fn float64(name: &str, x: f64, span: Range<usize>) -> Elem {
    elem("float", &[("name", name), ("value", &format!("{x}"))], span)
}

pub(crate) fn integer(name: &str, v: i64, span: Range<usize>) -> Elem {
    elem(
        "integer",
        &[("name", name), ("value", &v.to_string())],
        span,
    )
}

/// A point or vector in f64, as given (its exact decimal).
pub(crate) fn point(name: &str, p: glam::DVec3, span: Range<usize>) -> Elem {
    let v = format!("{}, {}, {}", p.x, p.y, p.z);
    elem("point", &[("name", name), ("value", &v)], span)
}

pub(crate) fn rgb(name: &str, c: [f32; 3], span: Range<usize>) -> Elem {
    let v = format!("{}, {}, {}", num(c[0]), num(c[1]), num(c[2]));
    elem("rgb", &[("name", name), ("value", &v)], span)
}

pub(crate) fn string(name: &str, v: &str, span: Range<usize>) -> Elem {
    elem("string", &[("name", name), ("value", v)], span)
}

pub(crate) fn boolean(name: &str, v: bool, span: Range<usize>) -> Elem {
    let v = if v { "true" } else { "false" };
    elem("boolean", &[("name", name), ("value", v)], span)
}

/// `<ref name=… id=…/>`.
pub(crate) fn reference(name: &str, id: &str, span: Range<usize>) -> Elem {
    elem("ref", &[("name", name), ("id", id)], span)
}

/// A 4×4 `to_world` given by its rows (f64, as composed).
pub(crate) fn matrix(name: &str, rows: [[f64; 4]; 4], span: Range<usize>) -> Elem {
    let text: Vec<String> = rows
        .iter()
        .map(|r| format!("{} {} {} {}", r[0], r[1], r[2], r[3]))
        .collect();
    let mut t = elem("transform", &[("name", name)], span.clone());
    t.children
        .push(elem("matrix", &[("value", &text.join("  "))], span));
    t
}

/// The tree of a TOML file: its top-level plugins under `<scene>`, every element placed in the
/// TOML text (file names resolve from the scene's folder, as TOML's always did).
pub(crate) fn document(path: &Path, text: &str, children: Vec<Elem>) -> Doc {
    let mut root = elem("scene", &[("version", "3.0.0")], 0..0);
    root.children = children;
    Doc {
        sources: vec![Source {
            path: path.to_path_buf(),
            shown: path.display().to_string(),
            text: text.to_string(),
            version: (3, 0, 0),
        }],
        root,
        resolver: Resolver::new(path),
    }
}

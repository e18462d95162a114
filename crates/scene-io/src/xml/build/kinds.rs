//! The plugin kinds lt reads, each with the types it knows, and the checks made on the whole tree
//! before any plugin is built, so that what a user needs first comes first: every unknown type
//! (with the known ones of its kind), every reference to an undefined id (a medium's too) and
//! every element lt does not read at the top level, listed together.
//!
//! Adding a plugin kind (as media added `medium`, `phase`, `volume`) is one row of `KINDS` with
//! the builder file that owns its types, and a call to that builder where the kind is met.

use crate::xml::doc::{Doc, Elem};
use crate::xml::props::Ids;
use crate::SceneError;
use std::collections::HashSet;

/// A plugin kind: its tag, how errors name it, the types its builder knows, and what to add to an
/// unknown type's message.
pub(super) struct Kind {
    pub tag: &'static str,
    pub what: &'static str,
    pub types: fn() -> Vec<&'static str>,
    pub hint: &'static str,
}

pub(super) const KINDS: &[Kind] = &[
    Kind {
        tag: "sensor",
        what: "sensor",
        types: || super::sensor::SENSORS.to_vec(),
        hint: "",
    },
    Kind {
        tag: "film",
        what: "film",
        types: || super::sensor::FILMS.to_vec(),
        hint: "",
    },
    Kind {
        tag: "rfilter",
        what: "reconstruction filter",
        types: || super::sensor::RFILTERS.to_vec(),
        hint: "",
    },
    Kind {
        tag: "sampler",
        what: "sampler",
        types: || super::sensor::SAMPLERS.to_vec(),
        hint: "",
    },
    Kind {
        tag: "integrator",
        what: "integrator",
        types: || super::integrator::INTEGRATORS.to_vec(),
        hint: ": lt reads an integrator for its max_depth only, the estimator is chosen on lt's \
               command line; where the file writes type=\"$integrator\", -D integrator=path \
               renders it",
    },
    Kind {
        tag: "bsdf",
        what: "BSDF",
        types: || super::bsdf::BSDFS.iter().map(|(name, ..)| *name).collect(),
        hint: "",
    },
    Kind {
        tag: "texture",
        what: "texture",
        types: || super::texture::TEXTURES.to_vec(),
        hint: "",
    },
    Kind {
        tag: "shape",
        what: "shape",
        types: super::shape::shape_types,
        hint: "",
    },
    Kind {
        tag: "emitter",
        what: "emitter",
        types: || super::emitter::EMITTERS.to_vec(),
        hint: "",
    },
    Kind {
        tag: "medium",
        what: "medium",
        types: || super::medium::MEDIA.to_vec(),
        hint: "",
    },
    Kind {
        tag: "phase",
        what: "phase function",
        types: || super::medium::PHASES.to_vec(),
        hint: "",
    },
    Kind {
        tag: "volume",
        what: "volume",
        types: || super::medium::VOLUMES.to_vec(),
        hint: "",
    },
];

/// Elements that may stand at the top level of a scene.
const TOP_LEVEL: [&str; 8] = [
    "sensor",
    "integrator",
    "bsdf",
    "shape",
    "emitter",
    "texture",
    "medium",
    "phase",
];

/// The error for an element whose type its kind's builder does not know.
pub(super) fn unknown_type(doc: &Doc, e: &Elem) -> SceneError {
    let ty = e.attr("type").unwrap_or("");
    match KINDS.iter().find(|k| k.tag == e.tag) {
        Some(k) => {
            let known = (k.types)().join(", ");
            let message = if ty.is_empty() {
                format!("<{}> needs a `type` (lt reads {known})", e.tag)
            } else {
                format!(
                    "{} `{ty}` is not supported (lt reads {known}){}",
                    k.what, k.hint
                )
            };
            doc.err(e, message)
        }
        None => doc.err(e, format!("<{}> is not a plugin lt reads", e.tag)),
    }
}

/// What the whole tree gets wrong before any value is read, in document order; the ids some
/// `<ref>` names go to `referenced`.
pub(super) fn problems<'a>(
    doc: &'a Doc,
    ids: &Ids<'a>,
    referenced: &mut HashSet<&'a str>,
) -> Vec<SceneError> {
    let mut found = Vec::new();
    walk(doc, &doc.root, ids, referenced, &mut found);
    found
}

fn walk<'a>(
    doc: &'a Doc,
    e: &'a Elem,
    ids: &Ids<'a>,
    referenced: &mut HashSet<&'a str>,
    found: &mut Vec<SceneError>,
) {
    let top = std::ptr::eq(e, &doc.root);
    for c in &e.children {
        if top && !TOP_LEVEL.contains(&c.tag.as_str()) {
            found.push(doc.err(
                c,
                format!("<{}> is not supported at the top level of a scene", c.tag),
            ));
            continue;
        }
        if c.tag == "ref" {
            match c.attr("id") {
                Some(id) if ids.contains_key(id) => {
                    referenced.insert(id);
                }
                Some(id) => found.push(doc.err(c, undefined_id(id, ids))),
                // Reported where the reference is read.
                None => {}
            }
            continue;
        }
        if let Some(k) = KINDS.iter().find(|k| k.tag == c.tag) {
            let ty = c.attr("type").unwrap_or("");
            // A `<texture name=…>` inside a plugin is a parameter; its type still counts.
            if !(k.types)().contains(&ty) {
                found.push(unknown_type(doc, c));
                continue;
            }
        }
        walk(doc, c, ids, referenced, found);
    }
}

/// "reference to an undefined id", with the ids that are defined.
fn undefined_id(id: &str, ids: &Ids) -> String {
    let mut defined: Vec<&str> = ids.keys().copied().collect();
    defined.sort_unstable();
    let list = if defined.is_empty() {
        "no element has an id".to_string()
    } else {
        format!("defined: {}", defined.join(", "))
    };
    format!("reference to an undefined id `{id}` ({list})")
}

/// One error for every problem found: the first one's place, every one listed with its own.
pub(super) fn combined(mut found: Vec<SceneError>) -> SceneError {
    if found.len() == 1 {
        return found.remove(0);
    }
    let list: Vec<String> = found.iter().map(|e| format!("  {e}")).collect();
    let first = &found[0];
    SceneError {
        file: first.file.clone(),
        line: first.line,
        column: first.column,
        message: format!(
            "{} ({} problems in this scene, each below)\n{}",
            first.message,
            found.len(),
            list.join("\n")
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::KINDS;

    /// docs/xml.md's row of each kind names every type its builder reads (a type added to a
    /// table and not to the docs fails here; so does one dropped from the docs).
    #[test]
    fn xml_docs_list_every_type_the_builders_read() {
        let docs = include_str!("../../../../../docs/xml.md");
        for k in KINDS {
            let label = match k.tag {
                "rfilter" => "film",
                "bsdf" => "BSDF",
                "phase" | "volume" => "medium",
                tag => tag,
            };
            let row = docs
                .lines()
                .find(|l| l.starts_with(&format!("| {label} |")))
                .unwrap_or_else(|| panic!("docs/xml.md has no `| {label} |` row"));
            for ty in (k.types)() {
                assert!(
                    row.contains(&format!("`{ty}`")),
                    "docs/xml.md's {label} row does not name `{ty}`"
                );
            }
        }
    }
}

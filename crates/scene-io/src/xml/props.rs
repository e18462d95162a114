//! A plugin element's parameters (`<float name=…>`, `<rgb name=…>`, …) and nested objects
//! (`<bsdf>`, `<emitter>`, `<film>`, `<ref>`, …), each taken at most once by the code that knows
//! the plugin: whatever is left over at the end is an error naming it, or, for the parameters
//! Mitsuba writes by default that change nothing we render, an entry of the load report.

use super::doc::{Doc, Elem};
use super::spectrum;
use super::values::{number, numbers, transform, triple, Xform};
use crate::SceneError;
use crate::{LoadOptions, LoadReport};
use lt_core::math::Color;
use std::cell::Cell;

/// Tags that are parameters (they carry `name`), as opposed to nested objects.
const PARAM_TAGS: [&str; 10] = [
    "float",
    "integer",
    "boolean",
    "string",
    "rgb",
    "spectrum",
    "vector",
    "point",
    "transform",
    "blackbody",
];

pub(super) struct Plugin<'a> {
    pub doc: &'a Doc,
    pub elem: &'a Elem,
    /// e.g. "bsdf `diffuse`".
    pub what: String,
    pub kind: &'a str,
    params: Vec<(&'a str, &'a Elem, Cell<bool>)>,
    /// (as written, resolved through `ref`, taken).
    nested: Vec<(&'a Elem, &'a Elem, Cell<bool>)>,
}

/// Every element with an `id`, in the whole document.
pub(super) type Ids<'a> = std::collections::HashMap<&'a str, &'a Elem>;

/// How a colour parameter converts a spectrum (Mitsuba's RGB variants treat reflectances and
/// emission differently).
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum ColorUse {
    /// In [0, 1].
    Reflectance,
    /// ≥ 0, a surface's other spectra (a conductor's η and k).
    Unbounded,
    /// ≥ 0, inside an emitter (radiance, intensity, irradiance).
    Emission,
}

impl ColorUse {
    fn spectrum(self) -> spectrum::SpectrumUse {
        match self {
            ColorUse::Reflectance => spectrum::SpectrumUse::Bounded,
            ColorUse::Unbounded => spectrum::SpectrumUse::Unbounded,
            ColorUse::Emission => spectrum::SpectrumUse::Emission,
        }
    }
}

impl<'a> Plugin<'a> {
    pub fn new(
        doc: &'a Doc,
        ids: &Ids<'a>,
        elem: &'a Elem,
        report: &mut LoadReport,
    ) -> Result<Plugin<'a>, SceneError> {
        let kind = elem.attr("type").unwrap_or("");
        let what = format!("{} `{kind}`", elem.tag);
        let mut params: Vec<(&'a str, &'a Elem, Cell<bool>)> = Vec::new();
        let mut nested = Vec::new();
        for c in &elem.children {
            if c.tag == "ref" {
                let id = super::values::need(doc, c, "id")?;
                let Some(&target) = ids.get(id) else {
                    return Err(doc.err(c, format!("reference to an undefined id `{id}`")));
                };
                if target.tag == "texture" {
                    // A named reference to a texture is a parameter of that name.
                    let Some(name) = c.attr("name") else {
                        return Err(doc.err(c, format!("a <ref> to the texture `{id}` needs the `name` of the parameter it sets")));
                    };
                    params.push((name, target, Cell::new(false)));
                    continue;
                }
                // A medium's `name` (interior, exterior, medium) is read by `named_all`.
                if let Some(name) = c.attr("name").filter(|_| target.tag != "medium") {
                    report.ignored.push(format!(
                        "{}: the `name` (\"{name}\") of a <ref> to `{id}` accepted and ignored",
                        doc.place(c)
                    ));
                }
                nested.push((c, target, Cell::new(false)));
                continue;
            }
            let is_param = PARAM_TAGS.contains(&c.tag.as_str())
                || (c.tag == "texture" && c.attr("name").is_some());
            if is_param {
                let Some(name) = c.attr("name") else {
                    return Err(doc.err(c, format!("<{}> inside {what} needs a `name`", c.tag)));
                };
                if params.iter().any(|(n, ..)| *n == name) {
                    return Err(doc.err(c, format!("parameter `{name}` of {what} is given twice")));
                }
                params.push((name, c, Cell::new(false)));
            } else {
                nested.push((c, c, Cell::new(false)));
            }
        }
        Ok(Plugin {
            doc,
            elem,
            what,
            kind,
            params,
            nested,
        })
    }

    pub fn err(&self, e: &Elem, m: impl Into<String>) -> SceneError {
        self.doc.err(e, m)
    }

    fn take(&self, name: &str) -> Option<&'a Elem> {
        self.params
            .iter()
            .find(|(n, ..)| *n == name)
            .map(|(_, e, used)| {
                used.set(true);
                *e
            })
    }

    pub fn has(&self, name: &str) -> bool {
        self.params.iter().any(|(n, ..)| *n == name)
    }

    /// The `<texture>` a parameter is given as (nested or through a `<ref>`), marked as taken;
    /// None when the parameter is absent or a plain value.
    pub fn texture(&self, name: &str) -> Option<&'a Elem> {
        let (_, e, used) = self.params.iter().find(|(n, ..)| *n == name)?;
        if e.tag != "texture" {
            return None;
        }
        used.set(true);
        Some(*e)
    }

    /// Every `<texture>` given, under any name or none (marked as taken): Mitsuba's `bumpmap`
    /// takes its one texture whatever it is called.
    pub fn any_textures(&self) -> Vec<&'a Elem> {
        let named = self.params.iter().filter(|(_, e, _)| e.tag == "texture");
        let unnamed = self.nested.iter().filter(|(_, e, _)| e.tag == "texture");
        named
            .map(|(_, e, used)| (*e, used))
            .chain(unnamed.map(|(_, e, used)| (*e, used)))
            .map(|(e, used)| {
                used.set(true);
                e
            })
            .collect()
    }

    /// The element of a parameter, marked as taken (for callers that read it themselves).
    pub fn take_elem(&self, name: &str) -> Option<&'a Elem> {
        self.take(name)
    }

    fn value(&self, e: &'a Elem) -> Result<&'a str, SceneError> {
        e.attr("value").ok_or_else(|| {
            self.err(
                e,
                format!(
                    "<{}> `{}` has no `value`",
                    e.tag,
                    e.attr("name").unwrap_or("")
                ),
            )
        })
    }

    fn wrong_type(&self, e: &Elem, expected: &str) -> SceneError {
        if e.tag == "texture" || e.tag == "ref" {
            return textures_refused(self.doc, e);
        }
        self.err(
            e,
            format!(
                "parameter `{}` of {} must be {expected}, got <{}>",
                e.attr("name").unwrap_or(""),
                self.what,
                e.tag
            ),
        )
    }

    pub fn float(&self, name: &str) -> Result<Option<f64>, SceneError> {
        let Some(e) = self.take(name) else {
            return Ok(None);
        };
        if e.tag != "float" && e.tag != "integer" {
            return Err(self.wrong_type(e, "a <float>"));
        }
        let what = format!("`{name}` of {}", self.what);
        number(self.doc, e, self.value(e)?, &what).map(Some)
    }

    pub fn integer(&self, name: &str) -> Result<Option<i64>, SceneError> {
        let Some(e) = self.take(name) else {
            return Ok(None);
        };
        if e.tag != "integer" {
            return Err(self.wrong_type(e, "an <integer>"));
        }
        let v = self.value(e)?.trim();
        v.parse::<i64>().map(Some).map_err(|_| {
            self.err(
                e,
                format!("`{name}` of {}: `{v}` is not an integer", self.what),
            )
        })
    }

    pub fn boolean(&self, name: &str) -> Result<Option<bool>, SceneError> {
        let Some(e) = self.take(name) else {
            return Ok(None);
        };
        if e.tag != "boolean" {
            return Err(self.wrong_type(e, "a <boolean>"));
        }
        match self.value(e)?.trim().to_ascii_lowercase().as_str() {
            "true" => Ok(Some(true)),
            "false" => Ok(Some(false)),
            v => Err(self.err(
                e,
                format!("`{name}` of {}: `{v}` is not true or false", self.what),
            )),
        }
    }

    pub fn string(&self, name: &str) -> Result<Option<(&'a str, &'a Elem)>, SceneError> {
        let Some(e) = self.take(name) else {
            return Ok(None);
        };
        if e.tag != "string" {
            return Err(self.wrong_type(e, "a <string>"));
        }
        Ok(Some((self.value(e)?, e)))
    }

    /// A `<vector>` or `<point>` (x/y/z attributes or `value`).
    pub fn vec3(&self, name: &str) -> Result<Option<[f64; 3]>, SceneError> {
        let Some(e) = self.take(name) else {
            return Ok(None);
        };
        if e.tag != "vector" && e.tag != "point" {
            return Err(self.wrong_type(e, "a <point> or <vector>"));
        }
        let what = format!("`{name}` of {}", self.what);
        triple(self.doc, e, 0.0, &what).map(Some)
    }

    pub fn transform(&self, name: &str) -> Result<Option<(Xform, &'a Elem)>, SceneError> {
        let Some(e) = self.take(name) else {
            return Ok(None);
        };
        if e.tag != "transform" {
            return Err(self.wrong_type(e, "a <transform>"));
        }
        Ok(Some((transform(self.doc, e)?, e)))
    }

    /// A colour: `<rgb>`, a `<float>` (grey), or a `<spectrum>` (one value or wavelength:value
    /// pairs, converted to RGB as Mitsuba's RGB variants do: `spectrum`).
    pub fn color(
        &self,
        name: &str,
        usage: ColorUse,
        // Unused since spectra convert exactly; kept so every caller reads the same.
        _opts: &LoadOptions,
        _report: &mut LoadReport,
    ) -> Result<Option<Color>, SceneError> {
        let Some(e) = self.take(name) else {
            return Ok(None);
        };
        let what = format!("`{name}` of {}", self.what);
        let rgb = match e.tag.as_str() {
            "float" | "integer" => [number(self.doc, e, self.value(e)?, &what)?; 3],
            "rgb" => {
                let v = self.value(e)?;
                let n = numbers(self.doc, e, v, &what)?;
                match n[..] {
                    [g] => [g; 3],
                    [r, g, b] => [r, g, b],
                    _ => {
                        return Err(self.err(
                            e,
                            format!("{what}: an <rgb> needs 1 or 3 numbers, got `{v}`"),
                        ))
                    }
                }
            }
            "spectrum" => {
                if e.attr("filename").is_some() {
                    return Err(self.err(
                        e,
                        format!(
                            "{what}: spectra read from files are not supported (give an <rgb>)"
                        ),
                    ));
                }
                let v = self.value(e)?;
                if !v.contains(':') {
                    let n = numbers(self.doc, e, v, &what)?;
                    match n[..] {
                        [c] => spectrum::constant_to_rgb(c, usage.spectrum()),
                        _ => return Err(self.err(e, format!("{what}: a <spectrum> is one number or wavelength:value pairs, got `{v}`"))),
                    }
                } else {
                    let pairs = spectrum::parse_pairs(v)
                        .map_err(|m| self.err(e, format!("{what}: {m}")))?;
                    spectrum::pairs_to_rgb(&pairs, usage.spectrum())
                }
            }
            "blackbody" => {
                return Err(self.err(
                    e,
                    format!("{what}: blackbody spectra are not supported (give an <rgb>)"),
                ))
            }
            _ => return Err(self.wrong_type(e, "a colour (<rgb>, <float> or <spectrum>)")),
        };
        if rgb.iter().any(|x| !x.is_finite()) {
            return Err(self.err(e, format!("{what} must be finite, got {rgb:?}")));
        }
        if rgb.iter().any(|&x| x < 0.0) {
            return Err(self.err(e, format!("{what} must not be negative, got {rgb:?}")));
        }
        if usage == ColorUse::Reflectance && rgb.iter().any(|&x| x as f32 > 1.0) {
            return Err(self.err(
                e,
                format!("{what} must be at most 1 (a surface cannot reflect more than it receives), got {rgb:?}"),
            ));
        }
        Ok(Some(Color::new(
            rgb[0] as f32,
            rgb[1] as f32,
            rgb[2] as f32,
        )))
    }

    /// The nested object elements with one of these tags (marked as taken).
    pub fn nested(&self, tags: &[&str]) -> Vec<&'a Elem> {
        self.nested
            .iter()
            .filter(|(_, e, _)| tags.contains(&e.tag.as_str()))
            .map(|(_, e, used)| {
                used.set(true);
                *e
            })
            .collect()
    }

    /// Every nested object of these tags with its `name` (on the `<ref>` when referenced), the
    /// element as written and the one it resolves to (marked as taken).
    pub fn named_all(&self, tags: &[&str]) -> Vec<(Option<&'a str>, &'a Elem, &'a Elem)> {
        self.nested
            .iter()
            .filter(|(_, e, _)| tags.contains(&e.tag.as_str()))
            .map(|(written, e, used)| {
                used.set(true);
                (written.attr("name"), *written, *e)
            })
            .collect()
    }

    /// The one nested object of these tags named `name` (marked as taken), if any.
    pub fn named_nested(&self, tags: &[&str], name: &str) -> Result<Option<&'a Elem>, SceneError> {
        let mut found = None;
        for (written, e, used) in &self.nested {
            if tags.contains(&e.tag.as_str()) && written.attr("name") == Some(name) {
                if found.is_some() {
                    return Err(
                        self.err(written, format!("`{name}` of {} is given twice", self.what))
                    );
                }
                used.set(true);
                found = Some(*e);
            }
        }
        Ok(found)
    }

    /// At most one nested object of these tags.
    pub fn one_nested(&self, tags: &[&str], what: &str) -> Result<Option<&'a Elem>, SceneError> {
        let v = self.nested(tags);
        if v.len() > 1 {
            return Err(self.err(
                v[1],
                format!("{} takes one {what}, this is a second one", self.what),
            ));
        }
        Ok(v.first().copied())
    }

    /// Ends the plugin: `ignorable` parameters left over go to the report, any other leftover
    /// parameter or nested element is an error.
    pub fn finish(&self, ignorable: &[&str], report: &mut LoadReport) -> Result<(), SceneError> {
        for (name, e, used) in &self.params {
            if used.get() {
                continue;
            }
            if ignorable.contains(name) {
                report.ignored.push(format!(
                    "{}: `{name}` of {} accepted and ignored (it changes nothing lt renders)",
                    self.doc.place(e),
                    self.what
                ));
                continue;
            }
            if e.tag == "texture" {
                return Err(textures_refused(self.doc, e));
            }
            return Err(self.err(
                e,
                format!("parameter `{name}` of {} is not supported", self.what),
            ));
        }
        for (written, e, used) in &self.nested {
            if !used.get() {
                if e.tag == "texture" {
                    return Err(textures_refused(self.doc, e));
                }
                let via = if written.tag == "ref" {
                    " (through a <ref>)"
                } else {
                    ""
                };
                return Err(self.err(
                    written,
                    format!("<{}> is not supported inside {}{via}", e.tag, self.what),
                ));
            }
        }
        Ok(())
    }
}

pub(super) fn textures_refused(doc: &Doc, e: &Elem) -> SceneError {
    let kind = e.attr("type").unwrap_or(if e.tag == "ref" {
        "a reference to a texture"
    } else {
        "?"
    });
    doc.err(e, format!("textures are not supported: {kind}"))
}

//! `<integrator>`: only its max_depth and rr_depth (the estimator is chosen on lt's command
//! line); `moment` reads its inner integrator, `direct` is max_depth 2.

use super::Loader;
use crate::xml::doc::Elem;
use crate::xml::props::Plugin;
use crate::SceneError;

/// What `--approximate` puts in place of Mitsuba's unbounded `max_depth = -1`.
/// The integrators lt reads (for their max_depth only).
pub(super) const INTEGRATORS: [&str; 6] = [
    "path",
    "volpath",
    "volpathmis",
    "ptracer",
    "direct",
    "moment",
];
pub const UNBOUNDED_DEPTH_SUBSTITUTE: u32 = 64;

impl<'a> Loader<'a> {
    pub(super) fn integrator(
        &mut self,
        e: Option<&'a Elem>,
        root: &Elem,
    ) -> Result<(u32, u32), SceneError> {
        let (depth, rr, at) = match e {
            None => (-1, 5, root),
            Some(e) => {
                let p = self.plugin(e)?;
                match p.kind {
                    "path" | "volpath" | "volpathmis" | "ptracer" => {}
                    "moment" => return self.moment(&p, root),
                    "direct" => return self.direct(&p),
                    _ => return Err(super::kinds::unknown_type(self.doc, e)),
                }
                if p.boolean("hide_emitters")? == Some(true) {
                    return Err(p.err(e, "`hide_emitters` = true is not supported"));
                }
                let depth = p.integer("max_depth")?.unwrap_or(-1);
                let rr = p.integer("rr_depth")?.unwrap_or(5);
                p.finish(&["samples_per_pass"], &mut self.report)?;
                (depth, rr, e)
            }
        };
        let depth = match depth {
            -1 => {
                self.substitute(
                    at,
                    "max_depth = -1 (unbounded, Mitsuba's default) is not supported: lt's estimators size their paths by max_depth".into(),
                    format!("use max_depth = {UNBOUNDED_DEPTH_SUBSTITUTE}"),
                )?;
                UNBOUNDED_DEPTH_SUBSTITUTE
            }
            d if (1..=1 << 20).contains(&d) => d as u32,
            d => {
                return Err(self.doc.err(
                    at,
                    format!("`max_depth` must be -1 or between 1 and 2^20, got {d} (1 = emitters seen directly)"),
                ))
            }
        };
        if !(0..=1 << 20).contains(&rr) {
            return Err(self.doc.err(
                at,
                format!("`rr_depth` must be between 0 and 2^20, got {rr}"),
            ));
        }
        Ok((depth, rr as u32))
    }

    /// Mitsuba's `moment` renders its inner integrator and adds the second moment as extra
    /// channels; lt's renders carry their own variance, so the inner integrator is what counts.
    pub(super) fn moment(&mut self, p: &Plugin<'a>, root: &Elem) -> Result<(u32, u32), SceneError> {
        let inner = p.nested(&["integrator"]);
        p.finish(&[], &mut self.report)?;
        match inner[..] {
            [i] => self.integrator(Some(i), root),
            [] => Err(p.err(
                p.elem,
                "integrator `moment` needs the integrator it wraps inside it",
            )),
            [_, second, ..] => Err(p.err(
                second,
                "a second integrator inside `moment`: lt renders one estimator per image",
            )),
        }
    }

    /// Mitsuba's `direct`: emitters seen directly plus direct illumination at the first hit,
    /// emitter and BSDF samples joined by MIS. Its expectation is every path of at most two
    /// segments — lt's `max_depth = 2` (camera segment included), which every estimator renders
    /// (`pt` with next-event estimation and MIS is the same estimator). The sample counts change
    /// only the noise while both are positive; a zero count drops a whole class of paths (lights
    /// reached through a mirror, point lights), so it is refused.
    pub(super) fn direct(&mut self, p: &Plugin<'a>) -> Result<(u32, u32), SceneError> {
        if p.boolean("hide_emitters")? == Some(true) {
            return Err(p.err(p.elem, "`hide_emitters` = true is not supported"));
        }
        for key in ["emitter_samples", "bsdf_samples", "shading_samples"] {
            if let Some(n) = p.integer(key)? {
                if n < 1 {
                    return Err(p.err(p.elem, format!("`{key}` = {n} of integrator `direct`: lt renders every path of two segments, a count below 1 leaves some out")));
                }
                self.report.ignored.push(format!(
                    "{}: `{key}` = {n} of integrator `direct` accepted and ignored (it changes the noise, not the expectation)",
                    self.doc.place(p.elem)
                ));
            }
        }
        p.finish(&[], &mut self.report)?;
        Ok((2, 5))
    }
}

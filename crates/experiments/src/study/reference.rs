//! Reference images: which integrator renders a scene best without bias, and the cached render
//! every study measures against. A reference's own noise is not zero: its mean per-pixel
//! variance (the square of its standard error) is what an MSE against it over-states by, and the
//! studies subtract it (E[(I − R̂)²] = E[(I − R)²] + Var R̂ for independent I and R̂).

use super::Scale;
use crate::gallery::Entry;
use crate::runs::{RunEntry, RunSpec};
use lt_estimators::Image;
use std::path::Path;

/// Seeds of references start here, far from the studies' seeds (1 …), so no study run shares a
/// random sequence with the reference it is measured against.
pub const REFERENCE_SEED: u64 = 1_000_000;

/// The reference integrator of a scene and why, by the scene file's stem. Scenes whose light
/// reaches the camera only along L S⁺ D S⁺ E from a delta (or near-delta) light have no unbiased
/// estimator here that samples them; they get independent runs of `vcm` at a small radius and
/// are marked consistent.
pub fn integrator_for(scene_stem: &str) -> (&'static str, &'static str) {
    match scene_stem {
        "smallvcm-spheres-point" | "smallvcm-spheres-sun" => (
            "vcm",
            "a delta light seen through specular balls (L S⁺ D S⁺ E): no unbiased estimator \
             samples it; independent vcm runs at radius 1 px",
        ),
        "caustic-sds" => (
            "vcm",
            "the caustic seen in the mirror (L S D S E) is heavy-tailed for pt and bdpt; \
             independent vcm runs at radius 1 px",
        ),
        _ => (
            "bdpt",
            "bidirectional path tracing, all strategies, power heuristic",
        ),
    }
}

/// Runs of a consistent reference: its standard error comes from their spread.
pub const CONSISTENT_REFERENCE_RUNS: u32 = 8;

pub fn spec(scale: &Scale, scene: &Path, max_depth: Option<u32>) -> Result<RunSpec, String> {
    let stem = scene
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    let (integrator, _) = integrator_for(&stem);
    let res = super::output::film(scale, scene)?;
    let mut s = if crate::runs::is_consistent(integrator) {
        RunSpec::new(
            scene,
            integrator,
            REFERENCE_SEED,
            scale.reference_passes / CONSISTENT_REFERENCE_RUNS,
        )
        .runs(CONSISTENT_REFERENCE_RUNS)
        .param("radius_px", 1)
    } else {
        RunSpec::new(scene, integrator, REFERENCE_SEED, scale.reference_passes)
    }
    .resolution(Some(res));
    if let Some(d) = max_depth {
        s = s.param("max_depth", d);
    }
    Ok(s)
}

/// Whether `s` is a reference as `spec` makes them, at whatever film and passes (a study may
/// make its references at its own, as the figures do): the scene's reference integrator, the
/// reference seed, and the runs and parameters `spec` gives it. `lt plan study` sends these to
/// the reference cache.
pub fn is_reference(s: &RunSpec) -> bool {
    let stem = s
        .scene
        .file_stem()
        .map(|x| x.to_string_lossy().to_string())
        .unwrap_or_default();
    let (integrator, _) = integrator_for(&stem);
    let consistent = crate::runs::is_consistent(integrator);
    // A consistent reference is made at radius 1 px, an unbiased one has no radius.
    let radius_given = s.params.iter().any(|(k, v)| k == "radius_px" && v == "1");
    let params_fit = radius_given == consistent
        && s.params
            .iter()
            .all(|(k, v)| k == "max_depth" || (consistent && k == "radius_px" && v == "1"));
    s.integrator == integrator
        && s.seed == REFERENCE_SEED
        && s.runs
            == if consistent {
                CONSISTENT_REFERENCE_RUNS
            } else {
                1
            }
        && params_fit
}

/// A reference as the studies use it.
pub struct Reference {
    pub image: Image,
    /// Per pixel and channel, the variance of the reference's mean (its standard error squared).
    pub variance: Image,
    /// The mean of `variance`: what a raw MSE against this reference over-states.
    pub mean_variance: f64,
    pub integrator: String,
    pub passes: u32,
    pub runs: u32,
    pub consistent: bool,
    pub seconds: f64,
}

impl Reference {
    /// The reference as a gallery's first image, noted by its integrator and passes.
    pub fn gallery_entry(&self, stem: String) -> Entry<'_> {
        Entry {
            label: "reference",
            note: format!("{} {}", self.integrator, self.passes),
            image: &self.image,
            stem,
        }
    }

    /// How the reference was made, for a gallery's caption: "bdpt at 512 passes", or
    /// "8 independent runs of vcm at 512 passes each".
    pub fn described(&self) -> String {
        if self.consistent {
            format!(
                "{} independent runs of {} at {} passes each",
                self.runs, self.integrator, self.passes
            )
        } else {
            format!("{} at {} passes", self.integrator, self.passes)
        }
    }

    pub fn from_entry(e: &RunEntry) -> Result<Reference, String> {
        let image = e.image()?;
        let se = e.std_error()?.ok_or_else(|| {
            format!(
                "reference {} has no standard error: a reference needs one",
                e.dir.display()
            )
        })?;
        let mut variance = se.clone();
        let mut sum = 0.0;
        for p in variance.data.iter_mut() {
            for v in p.iter_mut() {
                *v = if v.is_finite() { *v * *v } else { 0.0 };
                sum += *v;
            }
        }
        let mean_variance = sum / (3 * variance.data.len()).max(1) as f64;
        Ok(Reference {
            image,
            variance,
            mean_variance,
            integrator: e.record.spec.integrator.clone(),
            passes: e.record.spec.passes,
            runs: e.record.spec.runs,
            consistent: e.record.consistent(),
            seconds: e.record.seconds.last().copied().unwrap_or(0.0),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::{is_reference, CONSISTENT_REFERENCE_RUNS, REFERENCE_SEED};
    use crate::runs::RunSpec;

    /// A reference is told by what it is, at any film and passes; a study run is not one.
    #[test]
    fn references_are_told_at_any_film_and_passes() {
        let bdpt = |seed| RunSpec::new("scenes/cornell-box.toml", "bdpt", seed, 512);
        assert!(is_reference(
            &bdpt(REFERENCE_SEED).resolution(Some((128, 128)))
        ));
        assert!(is_reference(&bdpt(REFERENCE_SEED).param("max_depth", 4)));
        assert!(!is_reference(&bdpt(1)));
        assert!(!is_reference(&bdpt(REFERENCE_SEED).param("mis", "balance")));
        let vcm = RunSpec::new("scenes/caustic-sds.toml", "vcm", REFERENCE_SEED, 64);
        assert!(is_reference(
            &vcm.clone()
                .runs(CONSISTENT_REFERENCE_RUNS)
                .param("radius_px", 1)
        ));
        assert!(!is_reference(&vcm.clone().param("radius_px", 1)));
        assert!(!is_reference(&vcm.runs(CONSISTENT_REFERENCE_RUNS)));
    }
}

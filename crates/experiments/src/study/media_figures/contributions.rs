//! upbp's per-technique shares of the image: how much of its pixel mean each technique's
//! MIS-weighted estimate carries. The techniques study's tally (`lt_integrators::tally`) covers
//! bdpt, lvc-bdpt, vcm and bpm and ignores volumetric merges, so it does not fit; instead the
//! sums are heard through the `Recorder` upbp already reports every path to (`record_pass`, as
//! `lt mis-check` uses it): no change to upbp, and no timing — shares of the image only.
//!
//! A pass's image mean is Σ over reported paths of weight × value / pixels, camera-side paths
//! times their sample's film weight (`camera_loop::camera_sample`), light-tracing splats (t = 1)
//! as splatted; a run's estimate is the mean of its passes. The study checks the sum of the
//! shares against the plain render of the same seed (`SumCheck`).

use crate::image_io::write_atomic;
use crate::runs::RunSpec;
use crate::study::StudyContext;
use lt_core::path::VolumeTechnique;
use lt_integrators::params::ParamReader;
use lt_integrators::record::{Completed, Recorder, VolumeMerged};
use lt_integrators::upbp::Upbp;
use serde_json::json;

/// The technique families, in the tables' order.
pub const FAMILIES: [&str; 8] = [
    "emission (s = 0)",
    "next event (s = 1)",
    "light tracing (t = 1)",
    "connections (s, t ≥ 2)",
    "PP3D",
    "PB2D",
    "BB1D",
    "surface merges",
];

/// Σ weight × value (channel mean) per family over one pass.
struct Sums {
    film_weight: f64,
    by: [f64; FAMILIES.len()],
}

fn mean(c: lt_core::Color) -> f64 {
    (c.x as f64 + c.y as f64 + c.z as f64) / 3.0
}

impl Recorder for Sums {
    const ACTIVE: bool = true;

    fn begin_sample(&mut self, _pixel: u64, film_weight: f32) {
        self.film_weight = film_weight as f64;
    }

    fn completed(&mut self, p: Completed) {
        let v = mean(p.value) * p.weight;
        // t = 1 (one camera vertex, s ≥ 1) is a light-tracing splat: no film weight.
        let (family, w) = match (p.s, p.camera.len()) {
            (s, 1) if s >= 1 => (2, 1.0),
            (0, _) => (0, self.film_weight),
            (1, _) => (1, self.film_weight),
            _ => (3, self.film_weight),
        };
        self.by[family] += v * w;
    }

    fn volume_merged(&mut self, p: VolumeMerged) {
        let family = match p.technique {
            VolumeTechnique::Point(_) => 4,
            VolumeTechnique::Beam(_) => 5,
            VolumeTechnique::BeamBeam(_) => 6,
            VolumeTechnique::Connect(_) => 3,
            VolumeTechnique::Surface(_) => 7,
            // BP2D is in none of the studies' technique sets; counted with the 2-D kernel.
            VolumeTechnique::BeamPoint(_) => 5,
        };
        self.by[family] += mean(p.value) * p.weight * self.film_weight;
    }
}

/// One run's per-family means (image units, the pixel mean's part) and their sum.
pub struct Shares {
    pub by: [f64; FAMILIES.len()],
    pub sum: f64,
}

/// The shares of `spec`'s upbp run (same scene, film, parameters, seed and passes as the plain
/// run they are checked against), from the runs cache or computed now on one thread.
pub fn shares(ctx: &StudyContext, spec: &RunSpec) -> Result<Shares, String> {
    let scene = spec.load_scene()?;
    let mut material = spec.key_material(&scene)?;
    material["what"] = json!("upbp-contributions");
    let dir = ctx.runs.cache.get_or_build(&material, |tmp| {
        let p = spec.integrator_params();
        let r = ParamReader::new("upbp", &p);
        let upbp = Upbp::read(&scene, &r)?;
        r.finish()?;
        let pixels = scene.camera.pixel_count() as f64;
        let mut by = [0.0; FAMILIES.len()];
        for pass in 0..spec.passes {
            let mut s = Sums {
                film_weight: 1.0,
                by: [0.0; FAMILIES.len()],
            };
            upbp.record_pass(&scene, spec.seed, pass, &mut s);
            for (a, v) in by.iter_mut().zip(s.by) {
                *a += v / pixels / spec.passes as f64;
            }
        }
        let text = serde_json::to_string_pretty(&json!({ "families": FAMILIES, "means": by }))
            .map_err(|e| e.to_string())?;
        write_atomic(&tmp.join("shares.json"), text.as_bytes())
    })?;
    let path = dir.join("shares.json");
    let text = std::fs::read_to_string(&path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let v: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| format!("{}: not a shares record: {e}", path.display()))?;
    let mut by = [0.0; FAMILIES.len()];
    for (i, b) in by.iter_mut().enumerate() {
        *b = v["means"][i]
            .as_f64()
            .ok_or_else(|| format!("{}: entry {i} of \"means\" is not a number", path.display()))?;
    }
    Ok(Shares {
        by,
        sum: by.iter().sum(),
    })
}

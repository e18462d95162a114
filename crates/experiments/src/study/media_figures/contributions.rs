//! upbp's per-technique shares of the image and of the time: how much of its pixel mean each
//! technique family's MIS-weighted estimate carries, and how much of the run's CPU time the
//! family's code took. Both come from the techniques study's tally (`lt_integrators::tally`),
//! which covers upbp's volumetric merges: the tallied run makes the plain run's image bit for
//! bit (checked here against the cached plain render of the same seed, at the f32 its EXR
//! stores) and hears every
//! weighted contribution and every lap of time. Times are shares of the run's CPU time,
//! including the light paths' tracing and storing (one phase per pass), the camera walks and
//! what no lap covers (`other`).

use crate::image_io::write_atomic;
use crate::runs::RunSpec;
use crate::study::StudyContext;
use lt_estimators::Image;
use lt_integrators::record::tally::pool_cpu_seconds;
use lt_integrators::record::{VolumeFamily, Work};
use lt_integrators::tally_run::{tally_run, Tallied};
use serde_json::json;

/// The technique families, in the tables' order; the last three cost time and add nothing.
pub const FAMILIES: [&str; 12] = [
    "emission (s = 0)",
    "next event (s = 1)",
    "light tracing (t = 1)",
    "connections (s, t ≥ 2)",
    "PP3D",
    "PB2D",
    "BP2D",
    "BB1D",
    "surface merges",
    "light paths (trace, store)",
    "camera walk",
    "other",
];

/// Items timed: one in `EVERY` (as the techniques study).
const EVERY: u64 = 16;

/// The family (index into `FAMILIES`) of a tallied technique.
fn family(w: Work) -> usize {
    match w {
        Work::Connection { s: 0, .. } => 0,
        Work::Connection { s: 1, t } if t > 1 => 1,
        Work::Connection { t: 1, .. } => 2,
        Work::Connection { .. } => 3,
        Work::VolumeMerge { family, .. } => match family {
            VolumeFamily::Pp3d => 4,
            VolumeFamily::Pb2d => 5,
            VolumeFamily::Bp2d => 6,
            VolumeFamily::Bb1d => 7,
        },
        Work::Merge { .. } => 8,
        Work::LightWalk => 9,
        Work::CameraWalk => 10,
    }
}

/// One run's per-family means (image units, the pixel mean's part) and their sum, its
/// per-family CPU seconds per pass, and whether its image is the plain render's bit for bit.
pub struct Shares {
    pub by: [f64; FAMILIES.len()],
    pub sum: f64,
    pub seconds: [f64; FAMILIES.len()],
    pub bit_equal: bool,
}

/// The shares of `spec`'s upbp run (same scene, film, parameters, seed and passes as the plain
/// run `plain` is), from the runs cache or tallied now on one thread.
pub fn shares(ctx: &StudyContext, spec: &RunSpec, plain: &Image) -> Result<Shares, String> {
    let scene = spec.load_scene()?;
    let mut material = spec.key_material(&scene)?;
    material["what"] = json!("upbp-tally");
    material["every"] = json!(EVERY);
    let dir = ctx.runs.cache.get_or_build(&material, |tmp| {
        let p = spec.integrator_params();
        let t = Tallied::make("upbp", &scene, &p)?;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .map_err(|e| e.to_string())?;
        let (img, run, cpu) = pool.install(|| {
            let c0 = pool_cpu_seconds();
            let (img, run) = tally_run(&scene, &t, spec.seed, spec.passes, EVERY);
            (img, run, pool_cpu_seconds() - c0)
        });
        let mut by = [0.0; FAMILIES.len()];
        let mut seconds = [0.0; FAMILIES.len()];
        for (w, f) in &run.techniques {
            by[family(*w)] += f.mean;
            seconds[family(*w)] += f.seconds;
        }
        seconds[FAMILIES.len() - 1] += run.other_seconds;
        // The cached plain image is an f32 EXR: compare at f32, as it was stored.
        let bit_equal = img.data.len() == plain.data.len()
            && img.data.iter().zip(&plain.data).all(|(a, b)| {
                a.iter()
                    .zip(b)
                    .all(|(x, y)| (*x as f32).to_bits() == (*y as f32).to_bits())
            });
        let text = serde_json::to_string_pretty(&json!({
            "families": FAMILIES, "means": by, "seconds_per_pass": seconds,
            "tallied_cpu_seconds": cpu, "bit_equal": bit_equal,
        }))
        .map_err(|e| e.to_string())?;
        write_atomic(&tmp.join("shares.json"), text.as_bytes())
    })?;
    let path = dir.join("shares.json");
    let text = std::fs::read_to_string(&path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let v: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| format!("{}: not a shares record: {e}", path.display()))?;
    let read = |key: &str| -> Result<[f64; FAMILIES.len()], String> {
        let mut out = [0.0; FAMILIES.len()];
        for (i, b) in out.iter_mut().enumerate() {
            *b = v[key][i].as_f64().ok_or_else(|| {
                format!("{}: entry {i} of \"{key}\" is not a number", path.display())
            })?;
        }
        Ok(out)
    };
    let by = read("means")?;
    Ok(Shares {
        by,
        sum: by.iter().sum(),
        seconds: read("seconds_per_pass")?,
        bit_equal: v["bit_equal"].as_bool() == Some(true),
    })
}

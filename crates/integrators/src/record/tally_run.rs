//! Tallied runs of the integrators `tally` covers: the one place that names them, so the tally
//! machinery (`tally.rs`), which the integrators themselves import, imports none of them.

use crate::bidirectional::bdpt::{Bdpt, BdptParams};
use crate::bidirectional::lvc_bdpt::{LvcBdpt, LvcParams};
use crate::params::{IntegratorParams, ParamReader};
use crate::record::tally::RunTally;
use crate::upbp::{add_pass, Upbp};
use crate::vcm::bpm::Bpm;
use crate::vcm::engine::{Run, VcmParams};
use crate::vcm::Vcm;
use crate::ProgressiveRun;
use lt_core::Scene;
use lt_estimators::running::RunningImage;
use lt_estimators::Image;

/// The integrators a tally covers, built from the registry's parameters.
pub enum Tallied {
    Bdpt(Bdpt),
    LvcBdpt(LvcBdpt),
    /// `vcm` or `bpm`.
    Vcm(VcmParams),
    Upbp(Upbp),
}

/// The integrators `Tallied` covers.
pub const TALLIED: [&str; 5] = ["bdpt", "lvc-bdpt", "vcm", "bpm", "upbp"];

impl Tallied {
    pub fn make(name: &str, scene: &Scene, params: &IntegratorParams) -> Result<Tallied, String> {
        let info = crate::registry::find(name)?;
        let r = ParamReader::new(info.name, params);
        let t = match info.name {
            "bdpt" => Tallied::Bdpt(Bdpt {
                params: BdptParams::read(scene, &r)?,
            }),
            "lvc-bdpt" => Tallied::LvcBdpt(LvcBdpt::new(scene, LvcParams::read(scene, &r)?)),
            "vcm" => Tallied::Vcm(Vcm::read(scene, &r)?.params),
            "bpm" => Tallied::Vcm(Bpm::read(scene, &r)?.params),
            "upbp" => Tallied::Upbp(Upbp::read(scene, &r)?),
            other => {
                return Err(format!(
                    "per-technique tallies cover {}, not {other}",
                    TALLIED.join(", ")
                ))
            }
        };
        r.finish()?;
        Ok(t)
    }
}

/// `passes` passes of `t` under `seed`, on the current thread pool, timing items with
/// probability 1/`every` (0: none): the image `render` makes (bit for bit) and the run's tally.
pub fn tally_run(
    scene: &Scene,
    t: &Tallied,
    seed: u64,
    passes: u32,
    every: u64,
) -> (Image, RunTally) {
    let cam = &scene.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let mut run = RunTally::default();
    let image = match t {
        Tallied::Bdpt(b) => {
            let mut acc = RunningImage::new(w, h);
            for pass in 0..passes {
                let (img, _, tally) = b.tally_pass(scene, seed, pass, every);
                acc.add(&img);
                run.add(&tally);
            }
            acc.mean()
        }
        Tallied::LvcBdpt(l) => {
            let mut acc = RunningImage::new(w, h);
            for pass in 0..passes {
                let (img, _, tally) = l.tally_pass(scene, seed, pass, every);
                acc.add(&img);
                run.add(&tally);
            }
            acc.mean()
        }
        Tallied::Vcm(p) => {
            let mut r = Run::new(p, scene, seed);
            for pass in 0..passes {
                let (_, tally) = r.tally_pass(pass, every);
                run.add(&tally);
            }
            r.estimate()
        }
        Tallied::Upbp(u) => {
            let mut sum = Image::new(w, h);
            for pass in 0..passes {
                let (img, _, tally) = u.tally_pass(scene, seed, pass, every);
                add_pass(&mut sum, &img);
                run.add(&tally);
            }
            sum.mean_of_passes(passes)
        }
    };
    run.close();
    (image, run)
}

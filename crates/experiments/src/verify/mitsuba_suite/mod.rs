//! `lt mitsuba-suite DIR`: Mitsuba 3's render-test suite (mitsuba-data's `tests/scenes`, with
//! its reference images) run as a peer's test suite. `cases` finds the scenes and the estimators
//! their names imply, this module loads and renders each under a stated budget, `judge` applies
//! Mitsuba's rule with lt's own standard errors, `table` writes the scoreboard.

pub mod cases;
pub mod judge;
pub mod table;

use crate::image_io::{read_exr, write_exr};
use cases::Case;
use judge::Judgement;
use lt_core::Scene;
use lt_estimators::running::RunningImage;
use lt_estimators::Image;
use lt_integrators::render::{render, RenderOptions};
use lt_integrators::{make_integrator, IntegratorParams};
use lt_scene_io::{load_scene_with, LoadOptions};
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The scoreboard's home, written by a full run.
pub const DEFAULT_OUT: &str = "results/mitsuba-render-tests.md";

/// What every render of the suite may spend.
#[derive(Clone, Debug)]
pub struct Budget {
    pub passes: u32,
    pub spp_per_pass: u32,
    pub time_per_estimator: Duration,
    pub threads: usize,
    pub seed: u64,
    /// Where each judged render's mean and signed z map are written as EXR (`--diagnostics`).
    pub diagnostics: Option<PathBuf>,
}

/// One estimator's result on one scene.
#[derive(Clone, Debug)]
pub enum Outcome {
    Judged {
        judgement: Judgement,
        spp: u64,
    },
    /// It could not render or be judged (named).
    Error(String),
    /// Not run: the estimator cannot produce what the reference holds (named; `not_judged`).
    NotJudged(String),
}

impl Outcome {
    pub fn passes(&self) -> bool {
        matches!(self, Outcome::Judged { judgement, .. } if judgement.passes())
    }
}

/// One scene's row of the scoreboard.
#[derive(Clone, Debug)]
pub struct Row {
    pub name: String,
    /// The load error's message, when the scene is refused.
    pub refusal: Option<String>,
    /// (estimator, outcome), for the estimators the file name implies (none when refused).
    pub outcomes: Vec<(&'static str, Outcome)>,
}

/// Loads, renders and judges every scene of the suite in `dir`.
pub fn run_suite(dir: &Path, budget: &Budget) -> Result<Vec<Row>, String> {
    run_suite_only(dir, budget, &[])
}

/// `run_suite` for the scenes whose name contains one of `only` (all when it is empty).
pub fn run_suite_only(dir: &Path, budget: &Budget, only: &[String]) -> Result<Vec<Row>, String> {
    let chosen = |name: &str| only.is_empty() || only.iter().any(|o| name.contains(o.as_str()));
    run_suite_pairs(dir, budget, |name, _| chosen(name))
}

/// `run_suite` for the (scene, estimator) pairs `pick` accepts; a scene none of whose estimators
/// is picked is left out, an estimator not picked has no outcome in its row.
pub fn run_suite_pairs(
    dir: &Path,
    budget: &Budget,
    pick: impl Fn(&str, &str) -> bool,
) -> Result<Vec<Row>, String> {
    let shown_dir = format!("{}/", dir.display());
    let cases = cases::discover(dir)?;
    let chosen = |c: &Case| c.estimators.iter().any(|e| pick(&c.name, e));
    let mut rows = Vec::new();
    for case in cases.iter().filter(|c| chosen(c)) {
        let row = match load_scene_with(&case.xml, &LoadOptions::default()) {
            // Messages name files relative to the suite's folder, so the table reads the same
            // wherever the suite lives.
            Err(e) => Row {
                name: case.name.clone(),
                refusal: Some(e.to_string().replace(&shown_dir, "")),
                outcomes: Vec::new(),
            },
            Ok((scene, _)) => Row {
                name: case.name.clone(),
                refusal: None,
                outcomes: case
                    .estimators
                    .iter()
                    .filter(|e| pick(&case.name, e))
                    .map(|&e| {
                        let outcome = match not_judged(&scene, e, case) {
                            Some(why) => Outcome::NotJudged(why),
                            None => render_and_judge(&scene, e, case, budget),
                        };
                        (e, outcome)
                    })
                    .collect(),
            },
        };
        eprintln!("{}: {}", row.name, summary(&row));
        rows.push(row);
    }
    Ok(rows)
}

fn summary(row: &Row) -> String {
    match &row.refusal {
        Some(r) => format!("refused: {r}"),
        None => row
            .outcomes
            .iter()
            .map(|(e, o)| match o {
                Outcome::NotJudged(_) => format!("{e} not judged"),
                _ => format!("{e} {}", if o.passes() { "pass" } else { "FAIL" }),
            })
            .collect::<Vec<_>>()
            .join(", "),
    }
}

/// Why `estimator` is not judged on the case's scene, if it is not: a light tracer (`light`)
/// against a reference traced from the camera, where the camera sees a surface with a delta lobe
/// directly (past `null` boundaries) — light subpaths cannot join the camera through that lobe,
/// so what it reflects or refracts is missing from the image by construction (the media scenes'
/// glass spheres and panes, surf_area_light's smooth plastic coat).
pub fn not_judged(scene: &Scene, estimator: &str, case: &Case) -> Option<String> {
    if estimator != "light" || !case.traced_from_camera {
        return None;
    }
    let (w, h) = (scene.camera.width, scene.camera.height);
    let mut sampler = lt_core::sampling::Sampler::new(0, 0, 0);
    for y in 0..h {
        for x in 0..w {
            let raster = lt_core::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let mut ray = scene.camera.sample_ray(raster, &mut sampler);
            // Past null boundaries (a straight line crosses finitely many).
            for _ in 0..64 {
                let Some(hit) = scene.intersect(&ray) else {
                    break;
                };
                if scene.shapes[hit.shape as usize].null {
                    ray = hit.spawn_ray(ray.d);
                    continue;
                }
                if scene.material(hit.material).has_delta_lobe() {
                    return Some(format!(
                        "the camera sees a surface with a delta lobe (pixel {x}, {y}): light \
                         tracing cannot join the camera through it"
                    ));
                }
                break;
            }
        }
    }
    None
}

fn render_and_judge(scene: &Scene, estimator: &str, case: &Case, budget: &Budget) -> Outcome {
    let judged = || -> Result<Outcome, String> {
        let reference = read_exr(&case.reference)?;
        let reference_var = read_exr(&case.reference_var)?;
        let (batches, spp) = render_batches(scene, estimator, budget)?;
        let (mean, se) = (batches.mean(), batches.std_error());
        let judgement = judge::judge(&mean, &se, spp as f64, &reference, &reference_var)?;
        if let Some(dir) = &budget.diagnostics {
            let z = judge::signed_z(&mean, &se, spp as f64, &reference, &reference_var);
            let stem = format!("{}_{estimator}", case.name.replace('/', "_"));
            write_exr(&dir.join(format!("{stem}_mean.exr")), &mean)?;
            write_exr(&dir.join(format!("{stem}_z.exr")), &z)?;
        }
        Ok(Outcome::Judged { judgement, spp })
    };
    judged().unwrap_or_else(Outcome::Error)
}

/// Renders `passes` batches of `spp_per_pass` lt passes (one sample per pixel each) and keeps the
/// batch means: the independent passes the standard errors come from.
fn render_batches(
    scene: &Scene,
    estimator: &str,
    budget: &Budget,
) -> Result<(RunningImage, u64), String> {
    let est = make_integrator(estimator, scene, &IntegratorParams::new())?;
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let k = budget.spp_per_pass.max(1);
    let opts = RenderOptions {
        passes: budget.passes * k,
        time_limit: Some(budget.time_per_estimator),
        seed: budget.seed,
        threads: budget.threads,
    };
    let mut batches = RunningImage::new(w, h);
    let mut batch = Image::new(w, h);
    let mut in_batch = 0;
    let mut unbiased = true;
    render(scene, &est, &opts, |report| {
        let Some(pass) = report.pass_image() else {
            unbiased = false;
            return ControlFlow::Break(());
        };
        for (b, p) in batch.data.iter_mut().zip(&pass.data) {
            for c in 0..3 {
                b[c] += p[c] / k as f64;
            }
        }
        in_batch += 1;
        if in_batch == k {
            batches.add(&batch);
            batch = Image::new(w, h);
            in_batch = 0;
        }
        ControlFlow::Continue(())
    })?;
    if !unbiased {
        return Err(format!(
            "{estimator} has no independent passes to take errors from"
        ));
    }
    if batches.count() < 2 {
        return Err(format!(
            "the time budget ({:.0} s) allowed {} pass(es) of {k} spp; standard errors need 2",
            budget.time_per_estimator.as_secs_f64(),
            batches.count()
        ));
    }
    let spp = batches.count() * k as u64;
    Ok((batches, spp))
}

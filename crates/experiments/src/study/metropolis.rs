//! `lt study metropolis`: Veach's door for Metropolis light transport (issue 46, item 6) —
//! `pt`, `bdpt`, `pssmlt` and `mmlt` at equal CPU time on `veach-door` (and Bitterli's
//! `veach-bidir` when it loads: `-D integrator=path`), and a p_large × σ sweep of `pssmlt` on
//! `veach-door`.
//!
//! Equal time as in `equal_time`: a probe run per integrator (seed 0) measures its CPU seconds
//! per pass, each then gets round(budget / cost) passes; the images depend on those counts only,
//! which the tables record. Each integrator's `runs` independent runs (seeds 1 …) give relMSE
//! (pbrt-v4's, `metrics::rel_mse`) with a t interval over runs, the error-against-time slope
//! (snapshots at doublings, jackknifed over runs, `metrics::log_log_slope`) and, for the Markov
//! chains, the batch-means ESS/P of their records (median over lit pixels, averaged over runs).
//! The reference is bdpt at `reference_passes` on the same film.

use super::metrics::{log_log_slope, mean_of_runs, rel_mse};
use super::output::{num, stem, StudyOutput};
use super::reference::Reference;
use super::{Scale, StudyContext};
use crate::plot::{Chart, Series, Style};
use crate::runs::{RunEntry, RunSpec};
use lt_estimators::jackknife;
use std::path::PathBuf;

pub const NAME: &str = "metropolis";

const INTEGRATORS: [&str; 4] = ["pt", "bdpt", "pssmlt", "mmlt"];
const P_LARGE: [f64; 3] = [0.1, 0.3, 0.7];
const SIGMA: [f64; 3] = [0.003, 0.01, 0.03];
const PROBE_PASSES: u32 = 4;

/// The study's film and budgets at a scale.
struct Plan {
    width: u32,
    runs: usize,
    /// CPU seconds per run at equal time.
    budget: f64,
    reference_passes: u32,
    /// Passes of each sweep run.
    sweep_passes: u32,
}

fn plan(scale: &Scale) -> Plan {
    match scale.name {
        "test" => Plan {
            width: 16,
            runs: 3,
            budget: 0.2,
            reference_passes: 16,
            sweep_passes: 4,
        },
        "full" => Plan {
            width: 256,
            runs: 8,
            budget: 600.0,
            reference_passes: 16384,
            sweep_passes: 256,
        },
        // What a shared 2-core machine affords in one session: about 25 CPU minutes.
        _ => Plan {
            width: 64,
            runs: 6,
            budget: 12.0,
            reference_passes: 2048,
            sweep_passes: 64,
        },
    }
}

/// veach-door and Bitterli's veach-bidir, those of them that load: TOML scenes refuse `-D` and
/// veach-bidir needs `-D integrator=path`, so `lt study metropolis` renders the door and
/// `lt study metropolis --scale bitterli -D integrator=path` veach-bidir.
fn scenes(scale: &Scale) -> Result<Vec<PathBuf>, String> {
    let mut candidates: Vec<PathBuf> = Vec::new();
    for p in scale
        .scenes
        .iter()
        .chain(std::iter::once(&scale.focus_scene))
    {
        match stem(p).as_str() {
            "veach-door" => candidates.extend([
                p.clone(),
                p.with_file_name("bitterli/veach-bidir/scene.xml"),
            ]),
            // scenes/bitterli/veach-bidir/scene.xml → scenes/veach-door.toml
            "veach-bidir" => candidates.extend(
                [
                    Some(p.clone()),
                    p.ancestors().nth(3).map(|d| d.join("veach-door.toml")),
                ]
                .into_iter()
                .flatten(),
            ),
            _ => {}
        }
    }
    let mut v: Vec<PathBuf> = Vec::new();
    for c in candidates {
        if !v.contains(&c) && c.is_file() && lt_scene_io::load_scene(&c).is_ok() {
            v.push(c);
        }
    }
    v.sort_by_key(|p| stem(p) != "veach-door");
    if v.is_empty() {
        return Err("the metropolis study needs veach-door (quick scale) or veach-bidir (bitterli scale, -D integrator=path) among the scale's scenes".into());
    }
    Ok(v)
}

/// The scene of the p_large × σ sweep: veach-door, when it is rendered.
fn sweep_scene(scenes: &[PathBuf]) -> Option<&PathBuf> {
    scenes.iter().find(|p| stem(p) == "veach-door")
}

fn film(p: &Plan, scene: &PathBuf) -> Result<(u32, u32), String> {
    let s = lt_scene_io::load_scene(scene).map_err(|e| e.to_string())?;
    let (w, h) = (s.camera.width, s.camera.height);
    let height = ((p.width as f64) * h as f64 / w as f64).round().max(1.0) as u32;
    Ok((p.width, height))
}

fn base(p: &Plan, scene: &PathBuf, integrator: &str, seed: u64, passes: u32) -> RunSpec {
    RunSpec::new(scene, integrator, seed, passes).resolution(film(p, scene).ok())
}

fn reference_spec(p: &Plan, scene: &PathBuf) -> RunSpec {
    base(p, scene, "bdpt", 1_000_003, p.reference_passes)
}

fn probe_spec(p: &Plan, scene: &PathBuf, integrator: &str) -> RunSpec {
    base(p, scene, integrator, 0, PROBE_PASSES).snapshots([1])
}

/// Passes for `budget` CPU s from a probe: the cost per pass from passes 2 … `PROBE_PASSES`, and
/// the run's fixed start (the first pass's excess: a Metropolis run's bootstrap and chain starts,
/// which the first pass pays) taken off the budget — so a chain whose passes are cheap beside
/// its bootstrap is not given a fraction of the budget (mmlt got 5–9 of 12 CPU s from the
/// probe's mean cost per pass).
fn passes_for(probe: &RunEntry, budget: f64) -> u32 {
    let (first, all) = (probe.cpu_seconds_at(1), probe.cpu_seconds_at(PROBE_PASSES));
    let (Some(first), Some(all)) = (first, all) else {
        return 1;
    };
    let cost = (all - first) / (PROBE_PASSES - 1) as f64;
    let start = (first - cost).max(0.0);
    (((budget - start) / cost).round() as u32).max(1)
}

fn run_spec(p: &Plan, scene: &PathBuf, integrator: &str, run: usize, passes: u32) -> RunSpec {
    base(p, scene, integrator, 1 + run as u64, passes).snapshots(Scale::doublings(passes))
}

fn sweep_spec(p: &Plan, scene: &PathBuf, p_large: f64, sigma: f64, run: usize) -> RunSpec {
    base(p, scene, "pssmlt", 1 + run as u64, p.sweep_passes)
        .param("p_large", p_large)
        .param("sigma", sigma)
}

/// The renders that need no timing: references, probes and the sweep.
pub fn specs(scale: &Scale) -> Result<Vec<RunSpec>, String> {
    let p = plan(scale);
    let scenes = scenes(scale)?;
    let mut v = Vec::new();
    for s in &scenes {
        v.push(reference_spec(&p, s));
        v.extend(INTEGRATORS.iter().map(|i| probe_spec(&p, s, i)));
    }
    if let Some(door) = sweep_scene(&scenes) {
        for &pl in &P_LARGE {
            for &sg in &SIGMA {
                v.extend((0..p.runs).map(|r| sweep_spec(&p, door, pl, sg, r)));
            }
        }
    }
    Ok(v)
}

/// The batch-means ESS/P median of a Metropolis run's record, if it has one.
fn ess_median(e: &RunEntry) -> Option<f64> {
    e.record
        .facts
        .iter()
        .find(|(k, _)| k == "ess_over_passes_median")
        .and_then(|(_, v)| v.parse().ok())
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// One integrator's equal-time runs on a scene.
struct Measured {
    integrator: &'static str,
    passes: u32,
    seconds: f64,
    rel: Vec<f64>,
    slope: Result<lt_estimators::Jackknifed, String>,
    ess: Vec<f64>,
    curve: Vec<(f64, f64)>,
}

fn equal_time(
    ctx: &StudyContext,
    p: &Plan,
    scene: &PathBuf,
    r: &Reference,
) -> Result<Vec<Measured>, String> {
    let conf = ctx.scale.confidence;
    let mut out = Vec::new();
    for integrator in INTEGRATORS {
        let probe = ctx.run(&probe_spec(p, scene, integrator))?;
        let passes = passes_for(&probe, p.budget);
        let entries: Vec<RunEntry> = (0..p.runs)
            .map(|k| ctx.run(&run_spec(p, scene, integrator, k, passes)))
            .collect::<Result<_, _>>()?;
        let snaps = Scale::doublings(passes);
        // per_snapshot[j][k]: run k's relMSE at snapshot j; times: mean CPU seconds there.
        let mut per_snapshot = Vec::new();
        let mut times = Vec::new();
        for &s in &snaps {
            let mut v = Vec::new();
            for e in &entries {
                v.push(rel_mse(&e.snapshot(s)?, r));
            }
            per_snapshot.push(v);
            times.push(mean(
                &entries
                    .iter()
                    .map(|e| e.cpu_seconds_at(s).unwrap_or(f64::NAN))
                    .collect::<Vec<_>>(),
            ));
        }
        let rel = per_snapshot.last().cloned().unwrap_or_default();
        // The fit starts at the fourth doubling (8 passes), past the chains' start.
        let from = snaps.iter().position(|&s| s >= 8).unwrap_or(0);
        let (xs, ys) = (&times[from..], &per_snapshot[from..]);
        let slope = if xs.len() >= 3 {
            jackknife(p.runs, conf, |kept| log_log_slope(xs, ys, kept))
        } else {
            Err("fewer than 3 snapshots past 8 passes".into())
        };
        let curve = times
            .iter()
            .zip(&per_snapshot)
            .map(|(&t, v)| (t, mean(v)))
            .collect();
        out.push(Measured {
            integrator,
            passes,
            seconds: *times.last().unwrap_or(&f64::NAN),
            rel,
            slope,
            ess: entries.iter().filter_map(ess_median).collect(),
            curve,
        });
    }
    Ok(out)
}

fn interval_cells(values: &[f64], conf: f64) -> (String, String) {
    let i = mean_of_runs(values, conf);
    (num(i.estimate), format!("[{}, {}]", num(i.lo), num(i.hi)))
}

pub fn run(ctx: &StudyContext) -> Result<(), String> {
    let before = ctx.spent();
    let p = plan(&ctx.scale);
    let conf = ctx.scale.confidence;
    let scenes = scenes(&ctx.scale)?;
    ctx.expect(specs(&ctx.scale)?.len() + scenes.len() * INTEGRATORS.len() * p.runs);
    let mut out = StudyOutput::new(
        ctx.study_dir(NAME),
        NAME,
        "Metropolis on Veach's door: equal time, error against time, ESS, p_large × σ",
        &ctx.scale,
    )?;
    out.para(&format!(
        "Film {} px wide; {} independent runs per integrator of about {} CPU s each (passes from \
         a {PROBE_PASSES}-pass probe: its cost per pass after the first, and the first pass's \
         excess, a Metropolis run's bootstrap, taken off the budget); reference bdpt at {} passes on the same \
         film. relMSE is pbrt-v4's, mean over runs with its {} % t interval; the slope is \
         ln relMSE against ln CPU seconds from 8 passes on, jackknifed over runs; ESS/P is the \
         Metropolis record's batch-means median over lit pixels, mean over runs.",
        p.width,
        p.runs,
        num(p.budget),
        p.reference_passes,
        num(conf * 100.0)
    ));
    for scene in &scenes {
        let name = stem(scene);
        let r = Reference::from_entry(&ctx.run(&reference_spec(&p, scene))?)?;
        let measured = equal_time(ctx, &p, scene, &r)?;
        let mut rows = Vec::new();
        for m in &measured {
            let (rel, rel_i) = interval_cells(&m.rel, conf);
            let (slope, slope_i) = match &m.slope {
                Ok(j) => (
                    num(j.estimate),
                    format!("[{}, {}]", num(j.interval.lo), num(j.interval.hi)),
                ),
                Err(e) => ("–".into(), e.clone()),
            };
            let ess = if m.ess.is_empty() {
                "–".into()
            } else {
                num(mean(&m.ess))
            };
            rows.push(vec![
                m.integrator.to_string(),
                m.passes.to_string(),
                num(m.seconds),
                rel,
                rel_i,
                num(mean(&m.rel).sqrt()),
                slope,
                slope_i,
                ess,
            ]);
        }
        out.table(
            &format!("{name}-equal-time"),
            &format!("{name}: equal CPU time"),
            "relMSE after the budget; RMSE-like column √relMSE; slope of relMSE against time \
             (−1 for independent passes).",
            &[
                "integrator",
                "passes",
                "CPU s",
                "relMSE",
                "interval",
                "√relMSE",
                "slope",
                "slope interval",
                "ESS/P",
            ],
            rows,
            true,
        )?;
        let chart = Chart {
            title: format!("{name}: relMSE against CPU time (mean of runs)"),
            x_label: "CPU seconds".into(),
            y_label: "relMSE".into(),
            log_x: true,
            log_y: true,
            series: measured
                .iter()
                .map(|m| Series {
                    name: m.integrator.into(),
                    points: m.curve.clone(),
                    y_interval: Vec::new(),
                    style: Style::Measured,
                })
                .collect(),
        };
        out.chart(
            &format!("{name}-time"),
            &chart,
            "relMSE against CPU time, mean of the runs",
        )?;
    }
    // The sweep: pssmlt on veach-door at fixed passes.
    let Some(door) = sweep_scene(&scenes) else {
        out.para(&ctx.compute_note(before));
        return out.finish();
    };
    let r = Reference::from_entry(&ctx.run(&reference_spec(&p, door))?)?;
    let mut rows = Vec::new();
    for &pl in &P_LARGE {
        for &sg in &SIGMA {
            let entries: Vec<RunEntry> = (0..p.runs)
                .map(|k| ctx.run(&sweep_spec(&p, door, pl, sg, k)))
                .collect::<Result<_, _>>()?;
            let rel: Vec<f64> = entries
                .iter()
                .map(|e| e.image().map(|i| rel_mse(&i, &r)))
                .collect::<Result<_, _>>()?;
            let secs = mean(
                &entries
                    .iter()
                    .map(|e| e.cpu_seconds_at(p.sweep_passes).unwrap_or(f64::NAN))
                    .collect::<Vec<_>>(),
            );
            let (m, i) = interval_cells(&rel, conf);
            let ess: Vec<f64> = entries.iter().filter_map(ess_median).collect();
            rows.push(vec![num(pl), num(sg), m, i, num(secs), num(mean(&ess))]);
        }
    }
    out.table(
        "sweep",
        &format!("pssmlt on {}: p_large × σ", stem(door)),
        &format!("{} passes per run, {} runs; relMSE with its interval, CPU s per run, batch-means ESS/P.", p.sweep_passes, p.runs),
        &["p_large", "σ", "relMSE", "interval", "CPU s", "ESS/P"],
        rows,
        true,
    )?;
    out.para(&ctx.compute_note(before));
    out.finish()
}

//! `lt study per-length`: which estimator wins on which light paths. Every integrator renders
//! each scene with max_depth k = 1, 2, … (paths of at most k segments, camera ray included),
//! against a reference of the same max_depth; the error of paths up to length k, and its growth
//! from k − 1 to k, say where each estimator's error comes from. The per-strategy view of bdpt
//! (Veach's path pyramid) is `lt render -i bdpt --strategies DIR`.
//!
//! The error up to length k rather than of length exactly k: the integrators take max_depth, not
//! a minimum depth, and the difference of two independent renders would add both their noises.

use super::convergence::integrators;
use super::metrics::{mean_of_runs, mse};
use super::output::{film, num, pct, stem, StudyOutput};
use super::{Scale, StudyContext};
use crate::plot::{Chart, Series, Style};
use crate::runs::RunSpec;
use std::path::Path;

pub const NAME: &str = "per-length";

fn spec(scale: &Scale, scene: &Path, integrator: &str, depth: u32, run: usize) -> RunSpec {
    RunSpec::new(scene, integrator, 1 + run as u64, scale.max_passes)
        .resolution(film(scale, scene).ok())
        .param("max_depth", depth)
}

pub fn specs(scale: &Scale) -> Vec<RunSpec> {
    let mut v = Vec::new();
    for scene in &scale.length_scenes {
        for k in 1..=scale.max_length {
            v.extend(super::reference::spec(scale, scene, Some(k)));
            for i in integrators() {
                for r in 0..scale.runs {
                    v.push(spec(scale, scene, i, k, r));
                }
            }
        }
    }
    v
}

pub fn run(ctx: &StudyContext) -> Result<(), String> {
    let scale = &ctx.scale;
    let mut out = StudyOutput::new(
        ctx.study_dir(NAME),
        NAME,
        "Per path length: which estimator wins on which paths",
        scale,
    )?;
    out.para(&format!(
        "Each integrator at {} passes ({} runs, {} px wide) with max_depth k = 1 … {}, against a \
         reference of the same max_depth. MSE(≤ k) is the error of the image made of paths of at \
         most k segments (mean over runs with {} % t intervals); the winner at k is the lowest. \
         Its growth from k − 1 to k is where length-k paths add error.",
        scale.max_passes,
        scale.runs,
        scale.width,
        scale.max_length,
        pct(scale.confidence)
    ));
    let before = ctx.spent();
    let mut rows = Vec::new();
    let mut winners = Vec::new();
    for scene in &scale.length_scenes {
        let name = stem(scene);
        let mut series = Vec::new();
        let mut by_depth: Vec<Vec<(String, f64)>> = vec![Vec::new(); scale.max_length as usize];
        for i in integrators() {
            let mut points = Vec::new();
            let mut iv = Vec::new();
            for k in 1..=scale.max_length {
                let reference = ctx.reference(scene, Some(k))?;
                let specs: Vec<RunSpec> = (0..scale.runs)
                    .map(|r| spec(scale, scene, i, k, r))
                    .collect();
                let entries = ctx.run_all(&specs)?;
                let errs: Vec<f64> = entries
                    .iter()
                    .map(|e| e.image().map(|img| mse(&img, &reference)))
                    .collect::<Result<_, _>>()?;
                let ci = mean_of_runs(&errs, scale.confidence);
                let m = ci.estimate;
                rows.push(vec![
                    name.clone(),
                    i.to_string(),
                    k.to_string(),
                    format!("{:.6e}", m),
                    format!("{:.6e}", ci.lo),
                    format!("{:.6e}", ci.hi),
                ]);
                by_depth[(k - 1) as usize].push((i.to_string(), m));
                points.push((k as f64, m));
                iv.push((ci.lo, ci.hi));
            }
            series.push(Series {
                name: i.to_string(),
                points,
                y_interval: iv,
                style: Style::Measured,
            });
        }
        for (d, v) in by_depth.iter().enumerate() {
            let mut v = v.clone();
            v.sort_by(|a, b| a.1.total_cmp(&b.1));
            if let (Some(best), Some(second)) = (v.first(), v.get(1)) {
                // Equal errors (a deterministic image, or the same camera samples) are a tie.
                let tied: Vec<&str> = v
                    .iter()
                    .filter(|(_, m)| *m == best.1)
                    .map(|(i, _)| i.as_str())
                    .collect();
                let label = if tied.len() > 1 {
                    format!("tie: {}", tied.join(", "))
                } else {
                    best.0.clone()
                };
                winners.push(vec![
                    name.clone(),
                    (d + 1).to_string(),
                    label,
                    num(best.1),
                    second.0.clone(),
                    num(second.1),
                ]);
            }
        }
        out.chart(
            &format!("length-{name}"),
            &Chart {
                title: format!("{name}: MSE of paths up to length k"),
                x_label: "max path length k (segments)".into(),
                y_label: "MSE(≤ k)".into(),
                log_x: false,
                log_y: true,
                series,
            },
            &format!("{name}: error of the image of paths with at most k segments, per integrator, at equal samples."),
        )?;
    }
    out.table(
        "winners",
        "The winner at each length",
        "Lowest MSE(≤ k) and the runner-up, at equal samples.",
        &["scene", "k", "best", "MSE", "second", "MSE"],
        winners,
        true,
    )?;
    out.table(
        "per-length",
        "MSE(≤ k) per integrator",
        "With t intervals over runs.",
        &["scene", "integrator", "k", "mse", "mse_lo", "mse_hi"],
        rows,
        false,
    )?;
    out.para(&ctx.compute_note(before));
    out.finish()
}

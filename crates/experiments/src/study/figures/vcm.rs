//! Figure 4: Georgiev et al. 2012 (vertex connection and merging). `bdpt` (connections), `ppm`
//! (merging: Hachisuka et al.'s photon mapping) and `vcm` (both under one MIS) at equal CPU time
//! on three scenes where a different technique wins — `cornell-box` (diffuse: connections),
//! `veach-door` (light through a door ajar: long connections), `caustic-sds` (a caustic seen in
//! a mirror: only merging) — with the per-technique contributions the techniques study measured
//! on the same scenes (results/techniques/families.csv; read, never recomputed).

use super::{
    at, cell, columns, errors, film, inefficiency, labelled_entries, num, reference_scale,
    toml_scene, Budget, Contender, EqualTime,
};
use crate::gallery::write_gallery;
use crate::runs::RunSpec;
use crate::study::output::StudyOutput;
use crate::study::{Scale, StudyContext};
use lt_estimators::Interval;
use std::path::PathBuf;

/// The scenes, in `Budget::vcm_passes`' order; the techniques study's committed scenes.
pub(super) const SCENES: [&str; 3] = ["cornell-box", "veach-door", "caustic-sds"];

const VCM: Contender = Contender("vcm");
const BDPT: Contender = Contender("bdpt");
const PPM: Contender = Contender("ppm");

fn reference_at(scale: &Scale, b: &Budget, scene: &std::path::Path) -> Scale {
    reference_scale(scale, b, scene, b.vcm_reference_passes)
}

fn comparison(scale: &Scale, b: &Budget, k: usize) -> Result<EqualTime, String> {
    let scene = toml_scene(scale, SCENES[k]);
    let res = film(&at(scale, b, b.vcm_reference_passes), &scene)?;
    Ok(EqualTime {
        scene,
        res,
        runs: b.comparison_runs,
        probes: b.probes,
        setter: VCM,
        setter_passes: b.vcm_passes[k],
        others: vec![BDPT, PPM],
    })
}

pub(super) fn specs(
    scale: &Scale,
    b: &Budget,
    ctx: Option<&StudyContext>,
) -> Result<Vec<RunSpec>, String> {
    let mut v = Vec::new();
    for k in 0..SCENES.len() {
        let scene: PathBuf = toml_scene(scale, SCENES[k]);
        v.extend(crate::study::reference::spec(
            &reference_at(scale, b, &scene),
            &scene,
            None,
        ));
        v.extend(comparison(scale, b, k)?.planned(ctx)?);
    }
    Ok(v)
}

pub(super) fn figure(ctx: &StudyContext, b: &Budget, out: &mut StudyOutput) -> Result<(), String> {
    let scale = &ctx.scale;
    let mut rows = Vec::new();
    let mut verdicts = Vec::new();
    let mut drift = Vec::new();
    for k in 0..SCENES.len() {
        let name = SCENES[k];
        let cmp = comparison(scale, b, k)?;
        let reference = ctx.reference_at(&reference_at(scale, b, &cmp.scene), &cmp.scene, None)?;
        let (budget_s, arms) = cmp.run(ctx)?;
        // (name, relMSE × CPU s) of bdpt, ppm, vcm: what the verdict compares.
        let mut measured: Vec<(&str, Interval)> = Vec::new();
        let mut shown = Vec::new();
        // Table order: bdpt, ppm, vcm (the setter, first in `arms`).
        for &i in &[1, 2, 0] {
            let arm = &arms[i];
            let (e, images) = errors(&arm.entries, &reference, scale.confidence)?;
            let ineff = inefficiency(&e.rel_runs, &arm.entries, scale.confidence);
            let mut row = vec![
                name.to_string(),
                arm.contender.0.to_string(),
                arm.passes.to_string(),
                num(super::mean_cpu(&arm.entries)),
            ];
            row.extend(cell(&e.rel));
            row.extend(cell(&e.flip));
            row.extend(cell(&ineff));
            rows.push(row);
            shown.push((
                arm.contender.0,
                images.into_iter().next().ok_or("no runs")?,
                format!(
                    "{} spp, relMSE {}, FLIP {}",
                    arm.passes,
                    num(e.rel.estimate),
                    num(e.flip.estimate)
                ),
            ));
            measured.push((arm.contender.0, ineff));
        }
        verdicts.push(scene_verdict(name, &measured));
        drift.push(format!(
            "{name} {}",
            ["bdpt", "ppm"]
                .iter()
                .zip([1, 2])
                .map(|(who, i)| format!(
                    "{who} {}×",
                    num(super::mean_cpu(&arms[i].entries) / super::mean_cpu(&arms[0].entries))
                ))
                .collect::<Vec<_>>()
                .join(", ")
        ));
        let entries = labelled_entries(&shown, &format!("vcm-{name}"));
        let g = write_gallery(
            &out.dir,
            &format!("Figure 4: {name}, bdpt, ppm and vcm at equal CPU time"),
            &format!(
                "Equal CPU time ({} s per run, vcm's mean at {} passes). Reference: {}.",
                num(budget_s),
                cmp.setter_passes,
                reference.described()
            ),
            &reference.gallery_entry(format!("gallery/vcm-{name}/reference")),
            &entries,
            Some((b.width / 4).max(4)),
        )?;
        out.manifest.galleries.push(g);
    }
    out.table(
        "vcm",
        "Figure 4: bdpt, ppm and vcm at equal time (Georgiev et al. 2012)",
        &format!(
            "{} independent runs per estimator on each scene; vcm's pass count fixes the CPU \
             time, bdpt's and ppm's pass counts come from {} interleaved probes of each at vcm's \
             count (their mean CPU s per pass), and the runs are interleaved too (run 1 of each, \
             then run 2, …), so a change of the machine's load hits all three alike. CPU s is \
             what each arm took (mean per run); relMSE × CPU s is each run's product, its mean \
             with a Student-t interval: the time-normalised error the verdict compares. \
             References: bdpt at {} passes (cornell-box, veach-door), independent vcm runs at \
             radius 1 px (caustic-sds).",
            b.comparison_runs, b.probes, b.vcm_reference_passes
        ),
        &columns(
            &["scene", "integrator", "passes", "CPU s"],
            &INEFFICIENCY_COLUMNS,
        ),
        rows,
        true,
    )?;
    let near = verdicts.iter().filter(|v| !v.contains(NOT_NEAR)).count();
    out.para(&format!(
        "**Verdict (figure 4).** Georgiev et al.'s claim — vcm is robust: near the better of \
         bdpt and photon mapping on every scene — holds on {near} of {} scenes, by relMSE × CPU \
         s ({}). Near means vcm's interval reaches below the geometric mean of the two others': \
         nearer the better than the worse on the log scale the errors span.",
        SCENES.len(),
        verdicts.join("; ")
    ));
    out.para(&format!(
        "Equal time as achieved: CPU s per run against vcm's, {}. relMSE × CPU s is \
         time-invariant for the unbiased bdpt and vcm; ppm's relMSE falls slower than 1/N, so \
         its product grows with the budget — a small correction where the times agree.",
        drift.join("; ")
    ));
    techniques_table(ctx, out)
}

/// The columns of relMSE × CPU s and its interval's ends.
const INEFFICIENCY_COLUMNS: [&str; 3] =
    ["relMSE × CPU s", "relMSE × CPU s lo", "relMSE × CPU s hi"];

/// The phrase of a scene where vcm is not near the better technique.
const NOT_NEAR: &str = "not near the better";

/// One scene's verdict: vcm against the better and the worse of bdpt and ppm by relMSE × CPU s
/// (`m` in bdpt, ppm, vcm order).
fn scene_verdict(name: &str, m: &[(&str, Interval)]) -> String {
    let (bdpt, ppm, vcm) = (&m[0], &m[1], &m[2]);
    let (better, worse) = if bdpt.1.estimate <= ppm.1.estimate {
        (bdpt, ppm)
    } else {
        (ppm, bdpt)
    };
    let v = &vcm.1;
    let midpoint = (better.1.estimate * worse.1.estimate).sqrt();
    let how = if v.lo <= better.1.hi {
        "as good as the better (the intervals meet, or vcm's lies below)"
    } else if v.lo <= midpoint {
        "near the better (below the geometric mean)"
    } else {
        NOT_NEAR
    };
    format!(
        "{name}: vcm's is {}× {}'s (the better) and {}× {}'s, {how}",
        num(v.estimate / better.1.estimate),
        better.0,
        num(v.estimate / worse.1.estimate),
        worse.0
    )
}

/// The techniques study's per-family shares on the figure's scenes, for bdpt and vcm: the part
/// of the time and of the image each family of techniques has (the mean's share of their sum).
fn techniques_table(ctx: &StudyContext, out: &mut StudyOutput) -> Result<(), String> {
    let path = ctx
        .study_dir(crate::study::techniques::NAME)
        .join("families.csv");
    let Ok(rows) = crate::report::findings::csv(&path) else {
        out.para(&format!(
            "The per-technique contributions are not shown: `{}` is missing; `lt study \
             techniques --scale committed` writes it.",
            path.display()
        ));
        return Ok(());
    };
    let lead = |s: &str| {
        s.split_whitespace()
            .next()
            .and_then(|x| x.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    let mut table = Vec::new();
    for scene in SCENES {
        for integrator in ["bdpt", "vcm"] {
            let of: Vec<_> = rows
                .iter()
                .filter(|r| r["scene"] == scene && r["integrator"] == integrator)
                .collect();
            let total: f64 = of.iter().map(|r| lead(&r["mean"])).sum();
            for r in of.iter().filter(|r| lead(&r["mean"]) > 0.0) {
                table.push(vec![
                    scene.to_string(),
                    integrator.to_string(),
                    r["family"].clone(),
                    r["share of time"].clone(),
                    num(lead(&r["mean"]) / total),
                ]);
            }
        }
    }
    out.table(
        "vcm-techniques",
        "Figure 4b: what each family of techniques contributes (from the techniques study)",
        &format!(
            "Read from `{}/families.csv` (the techniques study: 4 runs of 8 passes at 128 px, one thread, \
             techniques timed by the time-stamp counter): each family's share of the pass's CPU \
             time (Student-t interval over runs) and its share of the image's mean (the \
             family's mean over the sum of all). Families that contribute nothing (the walks, \
             `other`) are left out.",
            crate::study::techniques::NAME
        ),
        &[
            "scene",
            "integrator",
            "family",
            "share of time",
            "share of image",
        ],
        table,
        true,
    )
}

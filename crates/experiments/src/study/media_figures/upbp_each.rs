//! Figure (b), Křivánek, Georgiev, Hachisuka, Vévoda, Šik, Nowrouzezahrai & Jarosz 2014
//! ("Unifying points, beams, and paths in volumetric light transport simulation"): at equal
//! time, upbp is never far from the best single estimator and is the most robust across scenes.
//! Beside it, the share of upbp's image each of its techniques carries (`contributions`).

use super::super::metrics::mean_of_runs;
use super::super::output::{num, StudyOutput};
use super::super::{Scale, StudyContext};
use super::cells::Cell;
use super::contributions::{shares, FAMILIES};
use super::{gallery, measure, media_scene, row, Budget, Measured, COLUMNS};

pub const SCENES: [&str; 3] = ["smallupbp-isosph", "glass-sphere-medium", "grid-smoke"];
pub const ESTIMATORS: [&str; 6] = ["upbp", "pp3d", "pb2d", "bb1d", "bdpt", "pt"];

/// "Far" from the best: upbp's relMSE interval wholly above this many times the best's.
pub const FAR: f64 = 2.0;

pub fn cells(scale: &Scale) -> Vec<Cell> {
    SCENES
        .iter()
        .flat_map(|s| {
            ESTIMATORS
                .iter()
                .map(move |i| Cell::new(media_scene(scale, s), i))
        })
        .collect()
}

/// Why vcm is not in the figure, in its own words.
fn vcm_refusal(scene: &std::path::Path) -> String {
    match lt_scene_io::load_scene(scene) {
        Ok(s) => match lt_integrators::make_integrator(
            "vcm",
            &s,
            &lt_integrators::IntegratorParams::new(),
        ) {
            Err(e) => e,
            Ok(_) => "vcm accepts this scene now: add it to the figure".into(),
        },
        Err(e) => e.to_string(),
    }
}

/// Renders what the cache lacks, writes the tables and galleries; returns one verdict row.
pub fn figure(
    ctx: &StudyContext,
    b: &Budget,
    fs: &Scale,
    out: &mut StudyOutput,
) -> Result<Vec<Vec<String>>, String> {
    let conf = ctx.scale.confidence;
    let mut rows = Vec::new();
    let mut share_rows = Vec::new();
    // Per scene: each estimator's relMSE mean, and upbp's against the best single one.
    let mut by_scene: Vec<(String, Vec<(String, f64)>)> = Vec::new();
    let mut near = Vec::new();
    for name in SCENES {
        let scene = media_scene(&ctx.scale, name);
        let reference = ctx.reference_at(fs, &scene, None)?;
        let ms: Vec<Measured> = ESTIMATORS
            .iter()
            .map(|i| measure(ctx, &Cell::new(scene.clone(), i), i, (b, fs), &reference))
            .collect::<Result<_, _>>()?;
        for m in &ms {
            let mut r = vec![name.to_string()];
            r.extend(row(m));
            rows.push(r);
        }
        let upbp = &ms[0];
        let best = ms[1..]
            .iter()
            .min_by(|a, c| a.errors.rel.estimate.total_cmp(&c.errors.rel.estimate))
            .expect("five single estimators");
        let ratio = upbp.errors.rel.estimate / best.errors.rel.estimate;
        let far = upbp.errors.rel.lo > FAR * best.errors.rel.hi;
        near.push((name, best.label.clone(), ratio, far));
        by_scene.push((
            name.to_string(),
            ms.iter()
                .map(|m| (m.label.clone(), m.errors.rel.estimate))
                .collect(),
        ));
        share_rows.extend(share_table(ctx, name, upbp, conf)?);
        gallery(
            out,
            (
                &format!("Figure (b): {name}, upbp against each estimator at equal CPU time"),
                &format!(
                    "{} CPU s per run. Reference: {} passes of {}. vcm: {}.",
                    num(b.cpu_seconds),
                    reference.passes,
                    reference.integrator,
                    vcm_refusal(&scene)
                ),
            ),
            name,
            &reference,
            &ms,
        )?;
    }
    let mut columns = vec!["scene"];
    columns.extend(COLUMNS);
    out.table(
        "upbp-vs-each",
        "Figure (b): upbp against each estimator alone at equal time (Křivánek et al. 2014)",
        &format!(
            "{} CPU s per run on each scene. vcm is not in the figure: it refuses media scenes \
             (\"{}\").",
            num(b.cpu_seconds),
            vcm_refusal(&media_scene(&ctx.scale, SCENES[0]))
        ),
        &columns,
        rows,
        true,
    )?;
    let robust = robustness(&by_scene);
    out.table(
        "robustness",
        "Figure (b): robustness across the three scenes",
        "Each estimator's relMSE over the best of all six on each scene, and the largest of \
         those ratios (1 = best everywhere).",
        &["estimator", SCENES[0], SCENES[1], SCENES[2], "worst ratio"],
        robust
            .iter()
            .map(|(l, rs, w)| {
                let mut r = vec![l.clone()];
                r.extend(rs.iter().map(|v| num(*v)));
                r.push(num(*w));
                r
            })
            .collect(),
        true,
    )?;
    out.table(
        "upbp-contributions",
        "Figure (b): the share of upbp's image and time each technique carries",
        &format!(
            "Per technique family, its MIS-weighted estimate's part of upbp's pixel mean, and its \
             code's part of the run's CPU time (the techniques study's tally, one item in 16 \
             timed; the light paths' tracing and storing, the camera walks and what no lap covers \
             are rows of their own), over the same runs as the table above ({} % Student-t \
             intervals over the runs). Each tallied run is its plain render bit for bit (checked); \
             `sum / image` checks the shares against that render's mean (largest relative \
             difference over the runs).",
            super::super::output::pct(conf)
        ),
        &[
            "scene",
            "technique",
            "share",
            "share lo",
            "share hi",
            "time share",
            "time lo",
            "time hi",
            "sum / image − 1",
        ],
        share_rows,
        true,
    )?;
    let far_on: Vec<&str> = near.iter().filter(|n| n.3).map(|n| n.0).collect();
    let most_robust = robust
        .iter()
        .min_by(|a, c| a.2.total_cmp(&c.2))
        .map(|r| r.0.clone())
        .unwrap_or_default();
    let verdict = match (far_on.is_empty(), most_robust == "upbp") {
        (true, true) => "holds".to_string(),
        (true, false) => format!("holds in part: never far, but {most_robust} is more robust"),
        (false, _) => format!("does not hold: far from the best on {}", far_on.join(", ")),
    };
    let numbers = format!(
        "upbp/best single: {}; worst ratio upbp {}, {most_robust} {}",
        near.iter()
            .map(|(s, l, r, _)| format!("{s} {}× ({l})", num(*r)))
            .collect::<Vec<_>>()
            .join(", "),
        num(robust
            .iter()
            .find(|r| r.0 == "upbp")
            .map_or(f64::NAN, |r| r.2)),
        num(robust
            .iter()
            .find(|r| r.0 == most_robust)
            .map_or(f64::NAN, |r| r.2)),
    );
    out.para(&format!(
        "**Verdict (b).** Křivánek et al.'s claim — upbp is never far from the best single \
         estimator (here: its relMSE interval never wholly above {FAR}× the best's) and is the \
         most robust across the three scenes (the smallest worst ratio) — {verdict}: {numbers}."
    ));
    Ok(vec![vec![
        "b".into(),
        "upbp is never far from the best single estimator and the most robust across three scenes"
            .into(),
        verdict,
        numbers,
    ]])
}

/// Per estimator: relMSE over the scene's best (of all six) per scene, and the largest.
fn robustness(by_scene: &[(String, Vec<(String, f64)>)]) -> Vec<(String, Vec<f64>, f64)> {
    let labels: Vec<String> = by_scene[0].1.iter().map(|(l, _)| l.clone()).collect();
    labels
        .iter()
        .map(|l| {
            let rs: Vec<f64> = by_scene
                .iter()
                .map(|(_, v)| {
                    let best = v.iter().map(|x| x.1).fold(f64::INFINITY, f64::min);
                    v.iter().find(|x| &x.0 == l).map_or(f64::NAN, |x| x.1) / best
                })
                .collect();
            let worst = rs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            (l.clone(), rs, worst)
        })
        .collect()
}

/// upbp's per-family shares of the image and of the CPU time on one scene, one row per family.
fn share_table(
    ctx: &StudyContext,
    scene: &str,
    upbp: &Measured,
    conf: f64,
) -> Result<Vec<Vec<String>>, String> {
    let mut per_run = Vec::new();
    let mut time_per_run = Vec::new();
    let mut worst: f64 = 0.0;
    for e in &upbp.entries {
        let img = e.image()?;
        let s = shares(ctx, &e.record.spec, &img)?;
        if !s.bit_equal {
            return Err(format!(
                "{scene}: upbp's tallied run {} is not its plain render bit for bit",
                e.record.spec.label()
            ));
        }
        let image_mean = img
            .data
            .iter()
            .map(|p| (p[0] + p[1] + p[2]) / 3.0)
            .sum::<f64>()
            / img.data.len().max(1) as f64;
        worst = worst.max((s.sum / image_mean - 1.0).abs());
        per_run.push(s.by.map(|v| v / s.sum));
        let total: f64 = s.seconds.iter().sum();
        time_per_run.push(s.seconds.map(|v| v / total));
    }
    Ok(FAMILIES
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let v: Vec<f64> = per_run.iter().map(|r| r[i]).collect();
            let m = mean_of_runs(&v, conf);
            let tv: Vec<f64> = time_per_run.iter().map(|r| r[i]).collect();
            let tm = mean_of_runs(&tv, conf);
            vec![
                scene.to_string(),
                f.to_string(),
                num(m.estimate),
                num(m.lo),
                num(m.hi),
                num(tm.estimate),
                num(tm.lo),
                num(tm.hi),
                format!("{worst:.1e}"),
            ]
        })
        .collect())
}

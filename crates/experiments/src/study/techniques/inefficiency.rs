//! relMSE × time of the compared configurations (bdpt, lvc-bdpt, vcm, eamis and its fixed
//! choices) from independent plain runs against the scene's reference, and what eamis chose.

use super::config::{spec, StudySize, COMPARED, EVERY, FIXED_PREFIX};
use super::plain::{plain_entry, read_json};
use super::tally::{iv, tally_entry};
use crate::image_io::read_exr;
use crate::study::metrics::{mean_of_runs, rel_mse};
use crate::study::output::{num, stem, StudyOutput};
use crate::study::StudyContext;
use std::collections::BTreeMap;
use std::path::Path;

/// relMSE × seconds of each configuration, from independent plain runs.
pub(super) fn inefficiency(
    ctx: &StudyContext,
    size: &StudySize,
    out: &mut StudyOutput,
    tally_cpu: &mut f64,
    bit_equal: &mut (usize, usize),
) -> Result<(), String> {
    let conf = ctx.scale.confidence;
    let mut rows = Vec::new();
    let mut efficiency_aware_rows = Vec::new();
    for scene in &size.scenes {
        let reference = ctx.reference_at(&size.scale, scene, None)?;
        let mut by_label: BTreeMap<&str, Vec<f64>> = BTreeMap::new();
        let (mut choices, mut pilot_share, mut without_pilot) =
            (Vec::new(), Vec::new(), Vec::new());
        for &(lab, integ, params) in COMPARED {
            let (mut rel, mut secs, mut ineff, mut over) =
                (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            for seed in 1..=size.runs as u64 {
                let run_spec = spec(size, scene, integ, params, seed);
                // eamis has no tallied twin: its plain render alone.
                let (dir, plain_cpu) = if lt_integrators::tally_run::TALLIED.contains(&integ) {
                    let e = tally_entry(ctx, &run_spec)?;
                    *tally_cpu += e.plain_cpu + e.tallied_cpu;
                    bit_equal.1 += 1;
                    bit_equal.0 += e.bit_equal as usize;
                    over.push(100.0 * (e.tallied_cpu / e.plain_cpu - 1.0));
                    (e.dir, e.plain_cpu)
                } else {
                    let e = plain_entry(ctx, &run_spec)?;
                    *tally_cpu += e.1;
                    over.push(f64::NAN);
                    (e.0, e.1)
                };
                let r = rel_mse(&read_exr(&dir.join("plain.exr"))?, &reference);
                if lab == "eamis" {
                    let (choice, pilot) = eamis_choice(&dir)?;
                    choices.push(choice);
                    pilot_share.push(pilot / plain_cpu);
                    without_pilot.push(r * (plain_cpu - pilot));
                }
                rel.push(r);
                secs.push(plain_cpu);
                ineff.push(r * plain_cpu);
            }
            by_label.insert(lab, ineff.clone());
            rows.push(vec![
                stem(scene),
                lab.to_string(),
                size.passes.to_string(),
                iv(&secs, conf).1,
                iv(&rel, conf).1,
                iv(&ineff, conf).1,
                iv(&over, conf).1,
            ]);
        }
        by_label.insert("eamis without its pilot", without_pilot);
        let mut row = efficiency_aware_row(&stem(scene), &by_label, &choices, conf);
        row.push(iv(&pilot_share, conf).1);
        efficiency_aware_rows.push(row);
    }
    out.table(
        "inefficiency",
        "Inefficiency: relMSE × time",
        &format!(
            "{} independent runs per configuration (seeds 1 …), each {} passes; relMSE against the \
             scene's reference (`lt study`'s, at this film); seconds = CPU seconds of the plain \
             render on one thread; intervals Student-t over the runs. Lower is better. The last \
             column: the same run tallied (timing 1 item in {EVERY}) against plain, in CPU time.",
            size.runs, size.passes
        ),
        &[
            "scene",
            "configuration",
            "passes",
            "CPU seconds",
            "relMSE",
            "relMSE × seconds",
            "tally overhead %",
        ],
        rows,
        true,
    )?;
    out.table(
        "efficiency-aware",
        "Efficiency-aware MIS against the fixed configurations it chooses from",
        &format!(
            "Per scene: the configuration `eamis` chose in each run (M per pixel, vertex \
             connections, share of pixels that merge; the same in every run unless listed), the \
             best of its {} fixed configurations by mean relMSE × seconds (each rendered without \
             a pilot, `eamis fixed=…`), and the ratio eamis / best fixed with an interval from \
             the two Student-t intervals' ends (conservative). A ratio above 1 is the pilot's \
             cost (one pass of {} on one thread, merging everywhere, with moments and counts) \
             or a wrong choice: the last two columns separate them — the ratio with the pilot's \
             CPU seconds taken out of eamis's (its image keeps the pilot pass), and the \
             pilot's share of eamis's CPU time.",
            COMPARED
                .iter()
                .filter(|c| c.0.starts_with(FIXED_PREFIX))
                .count(),
            size.passes
        ),
        &[
            "scene",
            "eamis chose",
            "eamis relMSE × s",
            "best fixed",
            "its relMSE × s",
            "eamis / best fixed",
            "without the pilot's CPU",
            "pilot share of CPU",
        ],
        efficiency_aware_rows,
        true,
    )
}

/// One row of the efficiency-aware table from each configuration's per-run inefficiencies.
fn efficiency_aware_row(
    scene: &str,
    by_label: &BTreeMap<&str, Vec<f64>>,
    choices: &[String],
    conf: f64,
) -> Vec<String> {
    let interval = |v: &[f64]| mean_of_runs(v, conf);
    let best = by_label
        .iter()
        .filter(|(l, v)| l.starts_with(FIXED_PREFIX) && v.iter().all(|x| x.is_finite()))
        .map(|(l, v)| (*l, interval(v)))
        .min_by(|a, b| a.1.estimate.total_cmp(&b.1.estimate));
    let mut chosen: Vec<&String> = choices.iter().collect();
    chosen.dedup();
    let chose = chosen
        .iter()
        .map(|s| s.as_str())
        .collect::<Vec<_>>()
        .join("; ");
    let Some(e) = by_label.get("eamis").map(|v| interval(v)) else {
        let dash = || "—".to_string();
        return vec![scene.into(), chose, dash(), dash(), dash(), dash(), dash()];
    };
    let bare = by_label
        .get("eamis without its pilot")
        .filter(|v| !v.is_empty())
        .map(|v| interval(v));
    let show = |i: &lt_estimators::bias_variance::Interval| {
        format!("{} [{}, {}]", num(i.estimate), num(i.lo), num(i.hi))
    };
    let ratio = |a: &lt_estimators::bias_variance::Interval,
                 b: &lt_estimators::bias_variance::Interval| {
        let hi = if b.lo > 0.0 {
            a.hi / b.lo
        } else {
            f64::INFINITY
        };
        format!(
            "{} [{}, {}]",
            num(a.estimate / b.estimate),
            num(a.lo / b.hi),
            num(hi)
        )
    };
    match best {
        None => {
            let dash = || "—".to_string();
            vec![
                scene.into(),
                chose,
                show(&e),
                dash(),
                dash(),
                dash(),
                dash(),
            ]
        }
        Some((label, b)) => vec![
            scene.into(),
            chose,
            show(&e),
            label.trim_start_matches(FIXED_PREFIX).to_string(),
            show(&b),
            ratio(&e, &b),
            bare.map_or("—".into(), |x| ratio(&x, &b)),
        ],
    }
}

/// What eamis chose in the run cached in `dir` (from its record's `eamis_*` facts), and the CPU
/// seconds its pilot took.
fn eamis_choice(dir: &Path) -> Result<(String, f64), String> {
    let v = read_json(&dir.join("plain.json"))?;
    let fact = |k: &str| v["facts"][k].as_str().unwrap_or("?").to_string();
    let merging: f64 = fact("eamis_merging_pixels").parse().unwrap_or(f64::NAN);
    let choice = format!(
        "M {}×, vc {}, merge {:.0} %",
        fact("eamis_light_ratio"),
        if fact("eamis_vertex_connections") == "true" {
            "on"
        } else {
            "off"
        },
        100.0 * merging
    );
    let pilot = fact("eamis_pilot_cpu_seconds").parse().unwrap_or(f64::NAN);
    Ok((choice, pilot))
}

//! The tallied runs (one cache entry each) and the per-technique tables, chart and sum check made
//! from them.

use super::config::{spec, StudySize, EVERY, TALLIED};
use super::plain::{read_json, timed_plain};
use crate::image_io::{write_atomic, write_exr};
use crate::plot::{Chart, Series, Style};
use crate::runs::RunSpec;
use crate::study::metrics::mean_of_runs;
use crate::study::output::{num, stem, StudyOutput};
use crate::study::StudyContext;
use lt_integrators::record::{VolumeFamily, Work};
use lt_integrators::tally::{label, pool_cpu_seconds};
use lt_integrators::tally_run::{tally_run, Tallied};
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// Every scene's per-technique table, the families and sum-check tables and the time-against-
/// moment chart; the sum checks for `checks.json`.
pub(super) fn tables(
    ctx: &StudyContext,
    size: &StudySize,
    out: &mut StudyOutput,
) -> Result<Vec<SumCheck>, String> {
    let conf = ctx.scale.confidence;
    let mut checks = Vec::new();
    let mut check_rows = Vec::new();
    let mut chart = Chart {
        title: "Where the time goes and what it buys".into(),
        x_label: "cumulative share of time".into(),
        y_label: "cumulative share of second moment".into(),
        log_x: false,
        log_y: false,
        series: vec![Series {
            name: "equal shares".into(),
            points: vec![(0.0, 0.0), (1.0, 1.0)],
            y_interval: Vec::new(),
            style: Style::Fitted,
        }],
    };
    let mut family_rows = Vec::new();
    for scene in &size.scenes {
        let sname = stem(scene);
        let mut full_rows = Vec::new();
        for (lab, integ, params) in TALLIED {
            let mut entries = Vec::new();
            for seed in 1..=size.runs as u64 {
                let e = tally_entry(ctx, &spec(size, scene, integ, params, seed))?;
                entries.push(e);
            }
            let by_tech = rows(&entries, false);
            let mut names: Vec<(Work, String)> = Vec::new();
            for (m, _) in &by_tech {
                for k in m.keys() {
                    if k != "other" && !names.iter().any(|n| &n.1 == k) {
                        names.push((parse_label(k), k.clone()));
                    }
                }
            }
            names.sort_by_key(|n| order(n.0));
            let mut ordered: Vec<String> = names.into_iter().map(|n| n.1).collect();
            ordered.push("other".into());
            full_rows.extend(table_rows(&by_tech, &ordered, conf, &[lab.to_string()]));
            let fams: Vec<String> = FAMILIES.iter().map(|f| f.to_string()).collect();
            family_rows.extend(table_rows(
                &rows(&entries, true),
                &fams,
                conf,
                &[sname.clone(), lab.to_string()],
            ));
            chart.series.push(Series {
                name: format!("{sname}, {lab}"),
                points: lorenz(&by_tech),
                y_interval: Vec::new(),
                style: Style::Measured,
            });
            // Σ of the technique means against the image mean, per run.
            let sums: Vec<f64> = entries
                .iter()
                .map(|e| e.techniques.values().map(|v| v.0).sum())
                .collect();
            let images: Vec<f64> = entries.iter().map(|e| e.image_mean).collect();
            let paired = sums
                .iter()
                .zip(&images)
                .map(|(s, i)| (s - i).abs() / i.abs().max(1e-300))
                .fold(0.0, f64::max);
            let sum = mean_of_runs(&sums, conf);
            let image = images.iter().sum::<f64>() / images.len().max(1) as f64;
            check_rows.push(vec![
                sname.clone(),
                lab.to_string(),
                format!("{} [{}, {}]", num(sum.estimate), num(sum.lo), num(sum.hi)),
                num(image),
                format!("{paired:.1e}"),
            ]);
            checks.push(SumCheck {
                scene: sname.clone(),
                integrator: lab.to_string(),
                sum,
                image,
                paired_rel: paired,
            });
        }
        out.table(
            &format!("{sname}-techniques"),
            &format!("{sname}: every technique"),
            "Per technique (s, t) and merge t, per integrator: share of the pass's time, mean and \
             second moment of its weighted per-pixel estimate, efficiency 1/(second moment × \
             seconds per pass); intervals over the runs.",
            &[
                "integrator",
                "technique",
                "share of time",
                "mean",
                "second moment",
                "efficiency",
            ],
            full_rows,
            false,
        )?;
    }
    out.table(
        "families",
        "By family of techniques",
        "Each scene and integrator, techniques summed by family (seconds, means and second \
         moments added; efficiency from the sums). Every (s, t) is in `<scene>-techniques.csv`.",
        &[
            "scene",
            "integrator",
            "family",
            "share of time",
            "mean",
            "Σ second moments",
            "efficiency",
        ],
        family_rows,
        true,
    )?;
    out.table(
        "check",
        "Techniques add up to the image",
        "Σ over techniques of their means (interval over runs) against the image mean, and the \
         largest relative difference within one run (f64 sums of the f32 contributions the \
         image adds in f32; a technique left out would show as its own share of the mean).",
        &[
            "scene",
            "integrator",
            "Σ technique means",
            "image mean",
            "max |Σ − image| / image",
        ],
        check_rows,
        true,
    )?;
    out.chart(
        "time-vs-moment",
        &chart,
        "Techniques sorted by second-moment share over time share, largest first; each curve \
         climbs from (0, 0) to (1, 1). A curve far above the diagonal: a few techniques take \
         little time and carry most of the second moment (worth more samples); the flat end: \
         time that adds no second moment (walks, other, techniques that rarely contribute).",
    )?;
    Ok(checks)
}

/// One tallied run as stored: per technique (mean, second moment, seconds per pass).
#[derive(Clone, Debug, Default)]
pub(super) struct TallyEntry {
    pub(super) techniques: BTreeMap<String, (f64, f64, f64)>,
    /// Per pass, wall × 1 thread.
    pub(super) seconds: f64,
    pub(super) other_seconds: f64,
    pub(super) image_mean: f64,
    /// CPU seconds of the plain render of the same seed and passes, and of the tallied one.
    pub(super) plain_cpu: f64,
    pub(super) tallied_cpu: f64,
    pub(super) bit_equal: bool,
    pub(super) dir: PathBuf,
}

/// The sort key of a technique label: walks, then connections by (k, s), merges by t.
fn order(w: Work) -> (u8, u16, u16) {
    match w {
        Work::LightWalk => (0, 0, 0),
        Work::CameraWalk => (1, 0, 0),
        Work::Connection { s, t } => (2, s + t - 1, s),
        Work::Merge { t } => (3, t, 0),
        Work::VolumeMerge { family, t } => (4, t, family as u16),
    }
}

/// The tallied run of `spec`, from the cache or rendered now on one thread.
pub(super) fn tally_entry(ctx: &StudyContext, spec: &RunSpec) -> Result<TallyEntry, String> {
    let scene = spec.load_scene()?;
    let mut material = spec.key_material(&scene)?;
    material["what"] = json!("techniques");
    material["every"] = json!(EVERY);
    ctx.say(&format!("techniques: {}", spec.label()));
    let dir = ctx.runs.cache.get_or_build(&material, |tmp| {
        let p = spec.integrator_params();
        let est = lt_integrators::make_integrator(&spec.integrator, &scene, &p)?;
        let t = Tallied::make(&spec.integrator, &scene, &p)?;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .map_err(|e| e.to_string())?;
        // The plain render first, on the same thread: its CPU time is the configuration's cost,
        // its image what the tallied one must equal.
        let (plain, plain_cpu) = pool.install(|| timed_plain(&scene, &est, spec.seed, spec.passes));
        let (img, run, tally_cpu) = pool.install(|| {
            let c0 = pool_cpu_seconds();
            let (img, run) = tally_run(&scene, &t, spec.seed, spec.passes, EVERY);
            (img, run, pool_cpu_seconds() - c0)
        });
        write_exr(&tmp.join("image.exr"), &img)?;
        write_exr(&tmp.join("plain.exr"), &plain)?;
        let bit_equal = img.data.len() == plain.data.len()
            && img
                .data
                .iter()
                .zip(&plain.data)
                .all(|(a, b)| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()));
        let mut rows: Vec<(Work, Value)> = run
            .techniques
            .iter()
            .map(|(w, f)| {
                (
                    *w,
                    json!({"technique": label(*w), "mean": f.mean,
                       "second_moment": f.second_moment, "seconds": f.seconds}),
                )
            })
            .collect();
        rows.sort_by_key(|r| order(r.0));
        let text = serde_json::to_string_pretty(&json!({
            "passes": run.passes,
            "seconds_per_pass": run.seconds,
            "other_seconds_per_pass": run.other_seconds,
            "image_mean": run.image_mean,
            "timed_fraction": run.timed_fraction,
            "every": EVERY,
            "plain_cpu_seconds": plain_cpu,
            "tallied_cpu_seconds": tally_cpu,
            "bit_equal": bit_equal,
            "techniques": rows.into_iter().map(|r| r.1).collect::<Vec<_>>(),
        }))
        .map_err(|e| e.to_string())?;
        write_atomic(&tmp.join("tally.json"), text.as_bytes())
    })?;
    let v = read_json(&dir.join("tally.json"))?;
    let f = |v: &Value, k: &str| v[k].as_f64().unwrap_or(f64::NAN);
    let mut e = TallyEntry {
        seconds: f(&v, "seconds_per_pass"),
        other_seconds: f(&v, "other_seconds_per_pass"),
        image_mean: f(&v, "image_mean"),
        plain_cpu: f(&v, "plain_cpu_seconds"),
        tallied_cpu: f(&v, "tallied_cpu_seconds"),
        bit_equal: v["bit_equal"].as_bool().unwrap_or(false),
        dir,
        ..TallyEntry::default()
    };
    for t in v["techniques"].as_array().into_iter().flatten() {
        let name = t["technique"].as_str().unwrap_or("?").to_string();
        e.techniques
            .insert(name, (f(t, "mean"), f(t, "second_moment"), f(t, "seconds")));
    }
    Ok(e)
}

/// A technique's family, for the summary's condensed tables.
fn family(name: &str) -> &'static str {
    if name == "light walk" || name == "camera walk" {
        return if name == "light walk" {
            "light walk"
        } else {
            "camera walk"
        };
    }
    if name.starts_with("merge") {
        return "merges";
    }
    if let Work::VolumeMerge { .. } = parse_label(name) {
        return "volumetric merges";
    }
    if name.starts_with("s=0,") {
        "emission hits (s=0)"
    } else if name.starts_with("s=1,") {
        "next event (s=1)"
    } else if name.ends_with(",t=1") {
        "light tracing (t=1)"
    } else {
        "connections (s,t≥2)"
    }
}

const FAMILIES: [&str; 9] = [
    "light walk",
    "camera walk",
    "emission hits (s=0)",
    "next event (s=1)",
    "light tracing (t=1)",
    "connections (s,t≥2)",
    "merges",
    "volumetric merges",
    "other",
];

/// "est [lo, hi]" of per-run values (Student-t over runs).
pub(super) fn iv(values: &[f64], conf: f64) -> (f64, String) {
    if values.iter().any(|v| !v.is_finite()) {
        return (f64::NAN, "—".into());
    }
    let i = mean_of_runs(values, conf);
    (
        i.estimate,
        format!("{} [{}, {}]", num(i.estimate), num(i.lo), num(i.hi)),
    )
}

/// Per run, per row name: (mean, second moment, seconds per pass), and the run's total seconds.
type Rows = Vec<(BTreeMap<String, (f64, f64, f64)>, f64)>;

/// Per run figures by technique (with `other`), or by family when `by_family`.
fn rows(entries: &[TallyEntry], by_family: bool) -> Rows {
    entries
        .iter()
        .map(|e| {
            let mut m: BTreeMap<String, (f64, f64, f64)> = BTreeMap::new();
            for (name, &(a, b, c)) in &e.techniques {
                let key = if by_family {
                    family(name).to_string()
                } else {
                    name.clone()
                };
                let r = m.entry(key).or_default();
                r.0 += a;
                r.1 += b;
                r.2 += c;
            }
            m.insert("other".into(), (0.0, 0.0, e.other_seconds));
            (m, e.seconds)
        })
        .collect()
}

/// The table rows of one integrator on one scene: technique | share of time | mean | second
/// moment | efficiency, each with its interval over runs.
fn table_rows(rows: &Rows, names: &[String], conf: f64, lead: &[String]) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    for name in names {
        let get = |k: usize| -> Vec<f64> {
            rows.iter()
                .map(|(m, total)| {
                    let r = m.get(name).copied().unwrap_or_default();
                    match k {
                        0 => r.2 / total,
                        1 => r.0,
                        2 => r.1,
                        _ => 1.0 / (r.1 * r.2),
                    }
                })
                .collect()
        };
        let (share, share_s) = iv(&get(0), conf);
        if !(share.abs() > 1e-9) && rows.iter().all(|(m, _)| !m.contains_key(name)) {
            continue;
        }
        let eff = get(3);
        let eff_s = if eff.iter().all(|e| e.is_finite()) {
            iv(&eff, conf).1
        } else {
            "—".into()
        };
        let mut row = lead.to_vec();
        row.extend([
            name.clone(),
            share_s,
            iv(&get(1), conf).1,
            iv(&get(2), conf).1,
            eff_s,
        ]);
        out.push(row);
    }
    out
}

/// Run-averaged (share of time, share of second moment) per technique, sorted by second-moment
/// share over time share, descending, as cumulative points from (0, 0).
fn lorenz(rows: &Rows) -> Vec<(f64, f64)> {
    let n = rows.len().max(1) as f64;
    let mut avg: BTreeMap<&String, (f64, f64, f64)> = BTreeMap::new();
    for (m, _) in rows {
        for (k, v) in m {
            let a = avg.entry(k).or_default();
            a.1 += v.1 / n;
            a.2 += v.2 / n;
        }
    }
    let time: f64 = avg.values().map(|v| v.2).sum();
    let q: f64 = avg.values().map(|v| v.1).sum();
    let mut pts: Vec<(f64, f64)> = avg
        .values()
        .map(|v| (v.2 / time, v.1 / q.max(1e-300)))
        .collect();
    pts.sort_by(|a, b| {
        let ra = a.1 / a.0.max(1e-300);
        let rb = b.1 / b.0.max(1e-300);
        rb.total_cmp(&ra)
    });
    let mut cum = vec![(0.0, 0.0)];
    let (mut x, mut y) = (0.0, 0.0);
    for (dx, dy) in pts {
        x += dx;
        y += dy;
        cum.push((x, y));
    }
    cum
}

/// The check the test asserts: per run, Σ of the technique means against the image mean.
pub struct SumCheck {
    pub scene: String,
    pub integrator: String,
    /// Σ technique means, over runs (Student-t).
    pub sum: lt_estimators::Interval,
    /// The image mean, over runs.
    pub image: f64,
    /// Largest |Σ − image| / image over runs (paired: the same run's passes).
    pub paired_rel: f64,
}

/// The `Work` a table label names (for ordering rows).
fn parse_label(s: &str) -> Work {
    if s == "light walk" {
        return Work::LightWalk;
    }
    if s == "camera walk" {
        return Work::CameraWalk;
    }
    let num_after = |key: &str| -> u16 {
        s.split(key)
            .nth(1)
            .and_then(|r| r.split(',').next())
            .and_then(|v| v.trim().parse().ok())
            .unwrap_or(0)
    };
    if s.starts_with("merge") {
        return Work::Merge { t: num_after("t=") };
    }
    for family in VolumeFamily::ALL {
        if s.starts_with(family.name()) {
            let t = num_after("t=");
            return Work::VolumeMerge { family, t };
        }
    }
    Work::Connection {
        s: num_after("s="),
        t: num_after("t="),
    }
}

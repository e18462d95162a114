//! `lt study techniques` (issue 25, item 1): where a bidirectional estimator's time goes and what
//! it buys. Per scene, `bdpt`, `lvc-bdpt` (N = 1) and `vcm` render independent runs with every
//! technique tallied (`lt_integrators::tally`: per (s, t) connection, light-tracing splat, next
//! event, emission hit and merge, the time it took and the mean and second moment of its
//! MIS-weighted per-pixel estimate); the tables give each technique's share of the time, mean,
//! second moment and efficiency 1/(second moment × time), with Student-t intervals over the
//! runs. Beside them, the inefficiency relMSE × time of `bdpt`, `lvc-bdpt` at N ∈ {1, 4, 16} and
//! `vcm`, from independent plain renders against the scene's reference.
//!
//! Each run is one cache entry of its own (key `what: techniques`): the plain render and the
//! tallied one of the same seed, one after the other on one thread, each timed by its CPU clock
//! (wall seconds on a shared machine count other work), with both images — the summary counts
//! how many are equal bit for bit. The study, like every other, is a function of cache entries.

use super::metrics::{mean_of_runs, rel_mse};
use super::output::{film, num, pct, stem, StudyOutput};
use super::{Scale, StudyContext};
use crate::image_io::{read_exr, write_atomic, write_exr};
use crate::plot::{Chart, Series, Style};
use crate::runs::RunSpec;
use lt_integrators::record::Work;
use lt_integrators::tally::{label, pool_cpu_seconds};
use lt_integrators::tally_run::{tally_run, Tallied};
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub const NAME: &str = "techniques";

/// Items timed: one in `EVERY` (see `lt_integrators::tally`).
pub const EVERY: u64 = 16;

/// (label, integrator, parameters) of one configuration.
pub type Config = (
    &'static str,
    &'static str,
    &'static [(&'static str, &'static str)],
);

/// The integrators whose techniques are tallied.
pub const TALLIED: [Config; 3] = [
    ("bdpt", "bdpt", &[]),
    ("lvc-bdpt N=1", "lvc-bdpt", &[("connections", "1")]),
    ("vcm", "vcm", &[]),
];

/// The configurations of the inefficiency table: bdpt, the light-vertex cache at several N, vcm
/// with and without correlation-aware MIS, efficiency-aware MIS (`eamis`) and every fixed
/// configuration its choice ranges over (rendered by `eamis fixed=…`: the same code without the
/// pilot, so a gap between the choice and the best fixed one is the pilot's cost or a wrong
/// choice).
pub const COMPARED: &[Config] = &[
    ("bdpt", "bdpt", &[]),
    ("lvc-bdpt N=1", "lvc-bdpt", &[("connections", "1")]),
    ("lvc-bdpt N=4", "lvc-bdpt", &[("connections", "4")]),
    ("lvc-bdpt N=16", "lvc-bdpt", &[("connections", "16")]),
    ("vcm", "vcm", &[]),
    (
        "vcm correlation-aware",
        "vcm",
        &[("correlation_aware", "true")],
    ),
    ("eamis", "eamis", &[]),
    (
        "eamis fixed m0.25_vc1_merge",
        "eamis",
        &[("fixed", "m0.25_vc1_merge")],
    ),
    (
        "eamis fixed m0.25_vc1_nomerge",
        "eamis",
        &[("fixed", "m0.25_vc1_nomerge")],
    ),
    (
        "eamis fixed m0.25_vc0_merge",
        "eamis",
        &[("fixed", "m0.25_vc0_merge")],
    ),
    (
        "eamis fixed m0.25_vc0_nomerge",
        "eamis",
        &[("fixed", "m0.25_vc0_nomerge")],
    ),
    (
        "eamis fixed m0.5_vc1_merge",
        "eamis",
        &[("fixed", "m0.5_vc1_merge")],
    ),
    (
        "eamis fixed m0.5_vc1_nomerge",
        "eamis",
        &[("fixed", "m0.5_vc1_nomerge")],
    ),
    (
        "eamis fixed m0.5_vc0_merge",
        "eamis",
        &[("fixed", "m0.5_vc0_merge")],
    ),
    (
        "eamis fixed m0.5_vc0_nomerge",
        "eamis",
        &[("fixed", "m0.5_vc0_nomerge")],
    ),
    (
        "eamis fixed m1_vc1_merge",
        "eamis",
        &[("fixed", "m1_vc1_merge")],
    ),
    (
        "eamis fixed m1_vc1_nomerge",
        "eamis",
        &[("fixed", "m1_vc1_nomerge")],
    ),
    (
        "eamis fixed m1_vc0_merge",
        "eamis",
        &[("fixed", "m1_vc0_merge")],
    ),
    (
        "eamis fixed m1_vc0_nomerge",
        "eamis",
        &[("fixed", "m1_vc0_nomerge")],
    ),
    (
        "eamis fixed m2_vc1_merge",
        "eamis",
        &[("fixed", "m2_vc1_merge")],
    ),
    (
        "eamis fixed m2_vc1_nomerge",
        "eamis",
        &[("fixed", "m2_vc1_nomerge")],
    ),
    (
        "eamis fixed m2_vc0_merge",
        "eamis",
        &[("fixed", "m2_vc0_merge")],
    ),
    (
        "eamis fixed m2_vc0_nomerge",
        "eamis",
        &[("fixed", "m2_vc0_nomerge")],
    ),
];

/// The prefix of the fixed configurations' labels in `COMPARED`.
const FIXED_PREFIX: &str = "eamis fixed ";

/// How big the study is at a scale (the scale's own fields are read, never changed).
#[derive(Clone, Debug)]
pub struct StudySize {
    pub width: u32,
    pub runs: u32,
    pub passes: u32,
    pub scenes: Vec<PathBuf>,
    /// The scale with this film, for its references.
    pub scale: Scale,
}

pub fn size(scale: &Scale) -> StudySize {
    let dir = scale
        .focus_scene
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    let named = |names: &[&str]| -> Vec<PathBuf> {
        names
            .iter()
            .map(|n| dir.join(format!("{n}.toml")))
            .filter(|p| p.is_file())
            .collect()
    };
    let (width, runs, passes, scenes) = match scale.name {
        "test" => (16, 4, 4, named(&["cornell-box"])),
        // Bitterli's veach-bidir loads only with `-D integrator=path`, which TOML scenes refuse:
        // it is the `bitterli` scale's (`lt study techniques --scale bitterli -D
        // integrator=path`, into results/techniques-bitterli/).
        "bitterli" => (
            128,
            4,
            8,
            scale
                .scenes
                .iter()
                .filter(|p| stem(p) == "veach-bidir")
                .cloned()
                .collect(),
        ),
        _ => (
            128,
            4,
            8,
            named(&["cornell-box", "veach-door", "caustic-sds"]),
        ),
    };
    StudySize {
        width,
        runs,
        passes,
        scenes,
        scale: Scale {
            width,
            ..scale.clone()
        },
    }
}

fn spec(
    size: &StudySize,
    scene: &Path,
    integrator: &str,
    params: &[(&str, &str)],
    seed: u64,
) -> RunSpec {
    let mut s = RunSpec::new(scene, integrator, seed, size.passes)
        .resolution(film(&size.scale, scene).ok());
    for (k, v) in params {
        s = s.param(k, v);
    }
    s
}

/// The references the study asks for; its runs (plain and tallied, on one thread, in one
/// entry per seed) are entries of their own, which `lt plan` does not list.
pub fn specs(scale: &Scale) -> Vec<RunSpec> {
    let size = size(scale);
    size.scenes
        .iter()
        .filter_map(|scene| super::reference::spec(&size.scale, scene, None).ok())
        .collect()
}

/// One tallied run as stored: per technique (mean, second moment, seconds per pass).
#[derive(Clone, Debug, Default)]
struct TallyEntry {
    techniques: BTreeMap<String, (f64, f64, f64)>,
    /// Per pass, wall × 1 thread.
    seconds: f64,
    other_seconds: f64,
    image_mean: f64,
    /// CPU seconds of the plain render of the same seed and passes, and of the tallied one.
    plain_cpu: f64,
    tallied_cpu: f64,
    bit_equal: bool,
    dir: PathBuf,
}

/// The sort key of a technique label: walks, then connections by (k, s), merges by t.
fn order(w: Work) -> (u8, u16, u16) {
    match w {
        Work::LightWalk => (0, 0, 0),
        Work::CameraWalk => (1, 0, 0),
        Work::Connection { s, t } => (2, s + t - 1, s),
        Work::Merge { t } => (3, t, 0),
    }
}

/// The tallied run of `spec`, from the cache or rendered now on one thread.
fn tally_entry(ctx: &StudyContext, spec: &RunSpec) -> Result<TallyEntry, String> {
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

/// A cache entry's JSON file, parsed.
fn read_json(path: &Path) -> Result<Value, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
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

const FAMILIES: [&str; 8] = [
    "light walk",
    "camera walk",
    "emission hits (s=0)",
    "next event (s=1)",
    "light tracing (t=1)",
    "connections (s,t≥2)",
    "merges",
    "other",
];

/// "est [lo, hi]" of per-run values (Student-t over runs).
fn iv(values: &[f64], conf: f64) -> (f64, String) {
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

pub fn run(ctx: &StudyContext) -> Result<(), String> {
    let size = size(&ctx.scale);
    let conf = ctx.scale.confidence;
    let mut out = StudyOutput::new(
        ctx.study_dir(NAME),
        NAME,
        "Per technique: where the time goes and what it buys",
        &size.scale,
    )?;
    let before = ctx.spent();
    let t_start = Instant::now();
    let mut tally_seconds = 0.0;
    out.para(&format!(
        "Scenes {}, {} px wide, max_depth as each scene file says; {} independent runs (seeds \
         1 … {}) of {} passes per configuration; intervals are Student-t at {} % over the runs. \
         Per technique — a connection (s, t) with s light and t camera vertices (path length k = \
         s + t − 1; s = 0 emission hits, s = 1 next-event estimation, t = 1 light-tracing \
         splats), or a merge at camera vertex t — the **mean** and **second moment** are those of \
         its MIS-weighted estimate of a pixel in one pass (channel mean, averaged over the \
         image); **share of time** is its part of the pass's CPU time (one thread), measured by \
         the time-stamp counter on one work item in {EVERY}, chosen by hash (lt_integrators::tally \
         says why, and what `other` is); **efficiency** = 1/(second moment × seconds per pass). \
         Second moments of techniques do not add up to the image's (their cross terms are not \
         measured); means do, and the check table shows it.",
        size.scenes
            .iter()
            .map(|s| format!("`{}`", stem(s)))
            .collect::<Vec<_>>()
            .join(", "),
        size.width,
        size.runs,
        size.runs,
        size.passes,
        pct(conf),
    ));
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
    let mut bit_equal = (0usize, 0usize);
    let mut family_rows = Vec::new();
    for scene in &size.scenes {
        let sname = stem(scene);
        let mut full_rows = Vec::new();
        for (lab, integ, params) in TALLIED {
            let mut entries = Vec::new();
            for seed in 1..=size.runs as u64 {
                let e = tally_entry(ctx, &spec(&size, scene, integ, params, seed))?;
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
    inefficiency(ctx, &size, &mut out, &mut tally_seconds, &mut bit_equal)?;
    overhead(ctx, &size, &mut out)?;
    out.para(&format!(
        "Tallied images against the plain renders of the same seeds: {} of {} bit for bit equal \
         (each cache entry keeps both, `image.exr` and `plain.exr`).",
        bit_equal.0, bit_equal.1
    ));
    out.para(&format!(
        "{} Plain and tallied runs (one thread each, CPU time): {:.1} core-minutes. Study wall \
         time {:.0} s.",
        ctx.compute_note(before),
        tally_seconds / 60.0,
        t_start.elapsed().as_secs_f64()
    ));
    out.finish()?;
    let path = ctx.study_dir(NAME).join("checks.json");
    let j: Vec<Value> = checks
        .iter()
        .map(|c| {
            json!({"scene": c.scene, "integrator": c.integrator, "sum": c.sum.estimate,
                   "sum_lo": c.sum.lo, "sum_hi": c.sum.hi, "image": c.image,
                   "paired_rel": c.paired_rel})
        })
        .collect();
    write_atomic(
        &path,
        serde_json::to_string_pretty(&j)
            .map_err(|e| e.to_string())?
            .as_bytes(),
    )
}

/// relMSE × seconds of each configuration, from independent plain runs.
fn inefficiency(
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

/// A plain render on one thread (an integrator `tally_run` does not take): its cache entry (the
/// image and the record's facts) and CPU seconds.
fn plain_entry(ctx: &StudyContext, spec: &RunSpec) -> Result<(PathBuf, f64), String> {
    let scene = spec.load_scene()?;
    let mut material = spec.key_material(&scene)?;
    material["what"] = json!("techniques-plain");
    ctx.say(&format!("techniques (plain): {}", spec.label()));
    let dir = ctx.runs.cache.get_or_build(&material, |tmp| {
        let p = spec.integrator_params();
        let est = lt_integrators::make_integrator(&spec.integrator, &scene, &p)?;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .map_err(|e| e.to_string())?;
        let (img, cpu, facts) =
            pool.install(|| timed_plain_logged(&scene, &est, spec.seed, spec.passes));
        write_exr(&tmp.join("plain.exr"), &img)?;
        let text = serde_json::to_string_pretty(&json!({
            "plain_cpu_seconds": cpu,
            "facts": facts.into_iter().collect::<BTreeMap<_, _>>(),
        }))
        .map_err(|e| e.to_string())?;
        write_atomic(&tmp.join("plain.json"), text.as_bytes())
    })?;
    let v = read_json(&dir.join("plain.json"))?;
    Ok((dir, v["plain_cpu_seconds"].as_f64().unwrap_or(f64::NAN)))
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
    Work::Connection {
        s: num_after("s="),
        t: num_after("t="),
    }
}

/// Seconds per pass of one integrator on the focus scene: plain, tallied without timing, timed
/// on one item in `EVERY`, and timed on every item — interleaved rounds on one thread, so a
/// change of machine load falls on all four alike.
fn overhead(ctx: &StudyContext, size: &StudySize, out: &mut StudyOutput) -> Result<(), String> {
    const ROUNDS: usize = 3;
    let Some(scene_path) = size.scenes.first() else {
        return Ok(());
    };
    let mut rows = Vec::new();
    for (lab, integ, params) in TALLIED {
        let s = spec(size, scene_path, integ, params, 1);
        let scene = s.load_scene()?;
        let mut material = s.key_material(&scene)?;
        material["what"] = json!("technique-overhead");
        material["rounds"] = json!(ROUNDS);
        material["every"] = json!(EVERY);
        let dir = ctx.runs.cache.get_or_build(&material, |tmp| {
            let p = s.integrator_params();
            let est = lt_integrators::make_integrator(integ, &scene, &p)?;
            let t = Tallied::make(integ, &scene, &p)?;
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .map_err(|e| e.to_string())?;
            let mut secs = vec![Vec::new(); 4];
            for _ in 0..ROUNDS {
                let plain = pool.install(|| timed_plain(&scene, &est, 1, s.passes).1);
                secs[0].push(plain / s.passes as f64);
                for (k, every) in [(1, 0), (2, EVERY), (3, 1)] {
                    let c = pool.install(|| {
                        let c0 = pool_cpu_seconds();
                        tally_run(&scene, &t, 1, s.passes, every);
                        pool_cpu_seconds() - c0
                    });
                    secs[k].push(c / s.passes as f64);
                }
            }
            let text = serde_json::to_string_pretty(&json!({ "seconds_per_pass": secs }))
                .map_err(|e| e.to_string())?;
            write_atomic(&tmp.join("overhead.json"), text.as_bytes())
        })?;
        let path = dir.join("overhead.json");
        let v: Value = serde_json::from_str(
            &std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?,
        )
        .map_err(|e| format!("{}: {e}", path.display()))?;
        let secs: Vec<Vec<f64>> = (0..4)
            .map(|k| {
                v["seconds_per_pass"][k]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .filter_map(|x| x.as_f64())
                    .collect()
            })
            .collect();
        let min = |k: usize| secs[k].iter().copied().fold(f64::INFINITY, f64::min);
        let cell = |k: usize| {
            let all: Vec<String> = secs[k].iter().map(|x| format!("{x:.4}")).collect();
            if k == 0 {
                format!("{:.4} ({})", min(0), all.join(", "))
            } else {
                format!(
                    "{:.4} ({:+.1} %; {})",
                    min(k),
                    100.0 * (min(k) / min(0) - 1.0),
                    all.join(", ")
                )
            }
        };
        rows.push(vec![lab.to_string(), cell(0), cell(1), cell(2), cell(3)]);
    }
    out.table(
        "overhead",
        "What the tally costs",
        &format!(
            "CPU seconds per pass on `{}` at {} px, one thread, {} passes, {ROUNDS} interleaved \
             rounds: the fastest round (the least disturbed by other work on the machine), its \
             change against the plain render, and every round. Moments alone (no clock), with \
             one item in {EVERY} timed (what the tables above use), and with every item timed.",
            stem(scene_path),
            size.width,
            size.passes
        ),
        &[
            "integrator",
            "plain render",
            "tally, no timing",
            &format!("tally, timing 1 in {EVERY}"),
            "tally, timing every item",
        ],
        rows,
        true,
    )
}

/// The plain render `render` makes (its passes accumulated the same way, so the same bits), on
/// the current pool, with the pool's CPU seconds.
/// `timed_plain` with the run's recorded facts (a progressive run's log; none for unbiased ones).
fn timed_plain_logged(
    scene: &lt_core::Scene,
    est: &lt_integrators::Estimator,
    seed: u64,
    passes: u32,
) -> (lt_estimators::Image, f64, Vec<(String, String)>) {
    let c0 = pool_cpu_seconds();
    match est {
        lt_integrators::Estimator::Unbiased(_) => {
            let (img, cpu) = timed_plain(scene, est, seed, passes);
            (img, cpu, Vec::new())
        }
        lt_integrators::Estimator::Consistent(p) => {
            let mut run = p.start(scene, seed);
            run.plan(passes);
            for pass in 0..passes {
                run.pass(pass);
            }
            let img = run.estimate();
            (img, pool_cpu_seconds() - c0, run.log().facts)
        }
    }
}

fn timed_plain(
    scene: &lt_core::Scene,
    est: &lt_integrators::Estimator,
    seed: u64,
    passes: u32,
) -> (lt_estimators::Image, f64) {
    let c0 = pool_cpu_seconds();
    let cam = &scene.camera;
    let img = match est {
        lt_integrators::Estimator::Unbiased(i) => {
            let mut acc = lt_estimators::RunningImage::new(cam.width as usize, cam.height as usize);
            for pass in 0..passes {
                acc.add(&i.render_pass(scene, seed, pass).0);
            }
            acc.mean()
        }
        lt_integrators::Estimator::Consistent(p) => {
            let mut run = p.start(scene, seed);
            run.plan(passes);
            for pass in 0..passes {
                run.pass(pass);
            }
            run.estimate()
        }
    };
    (img, pool_cpu_seconds() - c0)
}

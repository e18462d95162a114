//! `lt study slides` (issue 48, item 5): the lecture's slides (results/seed-slides,
//! results/sppm-slides, each a single seed-1 render) remade with independent runs, so every
//! slide's relMSE and FLIP carries a Student-t interval and every claim a verdict from them.
//!
//! - The seed slides: `pt`, `light` and `bdpt` at 4 and 32 spp on four scenes of rising
//!   difficulty (the lecture's Cornell box, smaller light, glass-enclosed light, and Veach's door).
//! - The sppm slides: `sppm` after 1, 4, 32 and 256 passes beside `bdpt` at the same counts, on
//!   `cornell-box` (diffuse: bdpt's ground) and `caustic-sds` (a caustic seen in a mirror).
//!
//! Each run is one render of its own seed whose lower pass counts are snapshots of the same
//! render (as the single-seed slides' "N-pass image is the first N passes of the longest"), so
//! the counts of one run are not independent of each other, but the runs are. The references and
//! film are the figures' (`super::budget`: 128 px wide, bdpt at 512 passes, or independent vcm
//! runs where bdpt cannot converge), shared with figures 3 and 4 through the cache.

use super::{
    at, cell, columns, errors_of_images, film, num, reference_scale, run_spec, toml_scene,
};
use crate::gallery::{write_gallery, Entry};
use crate::runs::{RunEntry, RunSpec};
use crate::study::output::StudyOutput;
use crate::study::{Scale, StudyContext};
use lt_estimators::{Image, Interval};
use std::path::PathBuf;

pub const NAME: &str = "slides";

/// The seed lecture's scenes, in its order of difficulty, and Veach's door.
const SEED_SCENES: [&str; 4] = [
    "cornell-box",
    "cornell-small-light",
    "cornell-glass-light",
    "veach-door",
];
const SEED_INTEGRATORS: [&str; 3] = ["pt", "light", "bdpt"];
const SPPM_SCENES: [&str; 2] = ["cornell-box", "caustic-sds"];

struct Budget {
    runs: usize,
    /// The seed slides' spp; the last is each run's length.
    seed_spp: Vec<u32>,
    /// The sppm slides' passes (sppm and bdpt alike); the last is each run's length.
    sppm_passes: Vec<u32>,
}

fn budget(scale: &Scale) -> Budget {
    if scale.name == "test" {
        Budget {
            runs: 3,
            seed_spp: vec![1, 2],
            sppm_passes: vec![1, 2, 4],
        }
    } else {
        Budget {
            // 8 (t₇ = 2.36): what the compute of 2026-12-06 allowed; 12 would cost half again.
            runs: 8,
            seed_spp: vec![4, 32],
            // 256, not the single-seed slides' 2048/4096: ≈ 75 CPU s per run at 128 px.
            sppm_passes: vec![1, 4, 32, 256],
        }
    }
}

/// The figures' scale for `scene`'s reference and film.
fn reference_at(scale: &Scale, scene: &std::path::Path) -> Scale {
    let b = super::budget(scale);
    reference_scale(scale, &b, scene, b.vcm_reference_passes)
}

/// One slide set's runs of `integrator` on `scene`: seeds 1 … K, each `counts.last()` passes
/// with a snapshot at every count.
fn run_specs(
    scale: &Scale,
    scene: &str,
    integrator: &str,
    counts: &[u32],
    runs: usize,
) -> Result<Vec<RunSpec>, String> {
    let path = toml_scene(scale, scene);
    let res = film(&at(scale, &super::budget(scale), 0), &path)?;
    let last = *counts.last().ok_or("no pass counts")?;
    Ok((0..runs)
        .map(|r| {
            run_spec(&path, res, integrator, 1 + r as u64, last).snapshots(counts.iter().copied())
        })
        .collect())
}

/// The slide sets: (set, scene, integrators, pass counts).
fn sets(b: &Budget) -> Vec<(&'static str, &'static str, Vec<&'static str>, Vec<u32>)> {
    let mut v = Vec::new();
    for s in SEED_SCENES {
        v.push(("seed", s, SEED_INTEGRATORS.to_vec(), b.seed_spp.clone()));
    }
    for s in SPPM_SCENES {
        v.push(("sppm", s, vec!["sppm", "bdpt"], b.sppm_passes.clone()));
    }
    v
}

pub fn specs(scale: &Scale, _ctx: Option<&StudyContext>) -> Result<Vec<RunSpec>, String> {
    let b = budget(scale);
    let mut v = Vec::new();
    for (_, scene, integrators, counts) in sets(&b) {
        let path = toml_scene(scale, scene);
        v.extend(crate::study::reference::spec(
            &reference_at(scale, &path),
            &path,
            None,
        ));
        for i in integrators {
            v.extend(run_specs(scale, scene, i, &counts, b.runs)?);
        }
    }
    Ok(v)
}

/// One slide's measured errors: (set, scene, integrator, passes) and its relMSE and FLIP.
struct Slide {
    set: &'static str,
    scene: &'static str,
    integrator: &'static str,
    passes: u32,
    rel: Interval,
    flip: Interval,
}

pub fn run(ctx: &StudyContext) -> Result<(), String> {
    let scale = &ctx.scale;
    let b = budget(scale);
    let width = super::budget(scale).width;
    let mut out = StudyOutput::new(
        ctx.study_dir(NAME),
        NAME,
        "The lecture's slides with independent runs",
        scale,
    )?;
    out.para(&format!(
        "The seed lecture's slides (results/seed-slides, results/sppm-slides: one seed each) \
         remade with {} independent runs (seeds 1 … {}) at {} px wide: relMSE (ε = 0.01) and \
         FLIP against the figures' references, means over the runs with {} % Student-t \
         intervals ({} degrees of freedom: wide). Within a run the lower pass counts are \
         snapshots of the same render; the runs are independent. CPU s is the mean per run \
         at that count.",
        b.runs,
        b.runs,
        width,
        crate::study::output::pct(scale.confidence),
        b.runs - 1
    ));
    let before = ctx.spent();
    let mut slides = Vec::new();
    let mut rows = Vec::new();
    for (set, scene, integrators, counts) in sets(&b) {
        let path: PathBuf = toml_scene(scale, scene);
        let reference = ctx.reference_at(&reference_at(scale, &path), &path, None)?;
        let mut shown: Vec<(String, Image, String)> = Vec::new();
        for integrator in integrators {
            let entries = ctx.run_all(&run_specs(scale, scene, integrator, &counts, b.runs)?)?;
            for &n in &counts {
                let images: Vec<Image> = entries
                    .iter()
                    .map(|e| e.snapshot(n))
                    .collect::<Result<_, _>>()?;
                let e = errors_of_images(&images, &reference, scale.confidence)?;
                let mut row = vec![
                    set.to_string(),
                    scene.to_string(),
                    integrator.to_string(),
                    n.to_string(),
                    num(mean_cpu_at(&entries, n)),
                ];
                row.extend(cell(&e.rel));
                row.extend(cell(&e.flip));
                rows.push(row);
                shown.push((
                    format!("{integrator}-{n}"),
                    images.into_iter().next().ok_or("no runs")?,
                    format!(
                        "relMSE {}, FLIP {}",
                        num(e.rel.estimate),
                        num(e.flip.estimate)
                    ),
                ));
                slides.push(Slide {
                    set,
                    scene,
                    integrator,
                    passes: n,
                    rel: e.rel,
                    flip: e.flip,
                });
            }
        }
        let dir = format!("{set}-{scene}");
        let entries: Vec<Entry> = shown
            .iter()
            .map(|(label, image, note)| Entry {
                label,
                note: note.clone(),
                image,
                stem: format!("gallery/{dir}/{label}"),
            })
            .collect();
        let g = write_gallery(
            &out.dir,
            &format!("The {set} slides: {scene}"),
            &format!(
                "Run 1 of {} of each slide (seed 1). Reference: {}.",
                b.runs,
                reference.described()
            ),
            &reference.gallery_entry(format!("gallery/{dir}/reference")),
            &entries,
            Some((width / 4).max(4)),
        )?;
        out.manifest.galleries.push(g);
    }
    out.table(
        "slides",
        "The slides with independent runs",
        "Each slide's relMSE and FLIP: the mean over the runs and its Student-t interval.",
        &columns(&["set", "scene", "integrator", "passes", "CPU s"], &[]),
        rows,
        true,
    )?;
    for v in verdicts(&slides, &b) {
        out.para(&v);
    }
    out.para(&ctx.compute_note(before));
    out.finish()
}

fn mean_cpu_at(v: &[RunEntry], n: u32) -> f64 {
    v.iter()
        .map(|e| e.cpu_seconds_at(n).unwrap_or(f64::NAN))
        .sum::<f64>()
        / v.len().max(1) as f64
}

/// The phrase of a verdict whose intervals show the claim.
pub const HOLDS: &str = "— holds:";
/// The phrase of a verdict whose intervals do not.
pub const NOT_SHOWN: &str = "— is not shown:";

/// `a`'s relMSE interval lies below `b`'s.
fn below(a: &Slide, b: &Slide) -> bool {
    a.rel.hi < b.rel.lo
}

/// The slides' claims, each judged by relMSE intervals (tests/studies.rs recomputes them from
/// slides.csv): the lecture's ordering of pt over its three Cornell scenes at the lowest spp;
/// bdpt below pt at equal spp on the glass-enclosed light and on the door, at every spp; sppm
/// below bdpt at equal passes on caustic-sds and above it on cornell-box, at the most passes.
fn verdicts(slides: &[Slide], b: &Budget) -> Vec<String> {
    let get = |set: &str, scene: &str, i: &str, n: u32| {
        slides
            .iter()
            .find(|s| s.set == set && s.scene == scene && s.integrator == i && s.passes == n)
            .expect("every slide is measured")
    };
    let ratio = |a: &Slide, b: &Slide| num(a.rel.estimate / b.rel.estimate);
    let flip_ratio = |a: &Slide, b: &Slide| num(a.flip.estimate / b.flip.estimate);
    let verdict = |title: &str, claim: &str, shown: bool, how: String| {
        format!(
            "**Verdict ({title}).** {claim} {} {how}.",
            if shown { HOLDS } else { NOT_SHOWN }
        )
    };
    let mut v = Vec::new();
    let low = b.seed_spp[0];
    let pts: Vec<&Slide> = SEED_SCENES[..3]
        .iter()
        .map(|s| get("seed", s, "pt", low))
        .collect();
    v.push(verdict(
        "slides, pt's difficulty",
        &format!(
            "The lecture's ordering — pt at {low} spp does worse on each harder Cornell scene"
        ),
        below(pts[0], pts[1]) && below(pts[1], pts[2]),
        format!(
            "pt's relMSE {} → {} → {} (cornell-box, cornell-small-light, cornell-glass-light), \
             steps of {}× and {}×",
            num(pts[0].rel.estimate),
            num(pts[1].rel.estimate),
            num(pts[2].rel.estimate),
            ratio(pts[1], pts[0]),
            ratio(pts[2], pts[1])
        ),
    ));
    for scene in ["cornell-glass-light", "veach-door"] {
        let pairs: Vec<(u32, &Slide, &Slide)> = b
            .seed_spp
            .iter()
            .map(|&n| {
                (
                    n,
                    get("seed", scene, "bdpt", n),
                    get("seed", scene, "pt", n),
                )
            })
            .collect();
        v.push(verdict(
            &format!("slides, {scene}"),
            "The lecture's claim — bdpt beats pt at equal spp",
            pairs.iter().all(|(_, bd, p)| below(bd, p)),
            pairs
                .iter()
                .map(|(n, bd, p)| {
                    format!(
                        "at {n} spp pt's relMSE is {}× bdpt's (FLIP {}×)",
                        ratio(p, bd),
                        flip_ratio(p, bd)
                    )
                })
                .collect::<Vec<_>>()
                .join(", "),
        ));
    }
    let top = *b.sppm_passes.last().expect("pass counts");
    let (s, d) = (
        get("sppm", "caustic-sds", "sppm", top),
        get("sppm", "caustic-sds", "bdpt", top),
    );
    v.push(verdict(
        "slides, caustic-sds",
        &format!("The lecture's claim — on a caustic seen in a mirror sppm beats bdpt (at {top} passes each)"),
        below(s, d),
        format!(
            "bdpt's relMSE is {}× sppm's (FLIP {}×)",
            ratio(d, s),
            flip_ratio(d, s)
        ),
    ));
    let (s, d) = (
        get("sppm", "cornell-box", "sppm", top),
        get("sppm", "cornell-box", "bdpt", top),
    );
    v.push(verdict(
        "slides, cornell-box",
        &format!(
            "The sppm slides' finding — on the diffuse box bdpt beats sppm (at {top} passes each)"
        ),
        below(d, s),
        format!(
            "sppm's relMSE is {}× bdpt's (FLIP {}×)",
            ratio(s, d),
            flip_ratio(s, d)
        ),
    ));
    v
}

//! Figure 1: Veach's bidirectional room (Veach & Guibas 1995; Veach 1997, ch. 10), Bitterli's
//! `veach-bidir`: `pt` against `bdpt` at equal CPU time, and bdpt's per-strategy (s, t) images
//! of the path pyramid, read from `lt render --strategies` output (see `PYRAMID_DIR`).

use super::{at, cell, columns, errors, film, labelled_entries, num, Budget, Contender, EqualTime};
use crate::gallery::{write_gallery, Entry};
use crate::runs::RunSpec;
use crate::study::output::{stem, StudyOutput};
use crate::study::{Scale, StudyContext};
use lt_estimators::Image;
use std::path::{Path, PathBuf};

/// Where the pyramid's EXRs are read from, under the results folder: inside the (uncommitted)
/// cache, since the 80 EXRs weigh ~9 MB. Made by the command `pyramid_command` prints.
pub const PYRAMID_DIR: &str = "cache/figures-pyramid";

/// The strategies shown for the lamp-lit ceiling: every (s, t) of length k = 3 (the ceiling lit
/// by the lamp through one diffuse bounce is k = 3: camera → ceiling → lamp shade → lamp), and
/// k = 4 beside it.
const PYRAMID_LENGTHS: [u32; 2] = [3, 4];

fn scene(scale: &Scale) -> PathBuf {
    scale.scene_beside_focus("bitterli/veach-bidir/scene.xml")
}

/// bdpt's pass count fixes the budget; both are probed at it (`EqualTime`).
fn comparison(scale: &Scale, b: &Budget) -> Result<EqualTime, String> {
    let scene = scene(scale);
    let res = film(&at(scale, b, b.bidir_reference_passes), &scene)?;
    Ok(EqualTime {
        scene,
        res,
        runs: b.runs,
        probes: b.probes,
        setter: Contender("bdpt"),
        setter_passes: b.bdpt_passes,
        others: vec![Contender("pt")],
    })
}

/// The reference and the probes; the runs once the probes are in the context's cache.
pub(super) fn specs(
    scale: &Scale,
    b: &Budget,
    ctx: Option<&StudyContext>,
) -> Result<Vec<RunSpec>, String> {
    let mut v = Vec::new();
    v.extend(crate::study::reference::spec(
        &at(scale, b, b.bidir_reference_passes),
        &scene(scale),
        None,
    ));
    v.extend(comparison(scale, b)?.planned(ctx)?);
    Ok(v)
}

pub(super) fn figure(ctx: &StudyContext, b: &Budget, out: &mut StudyOutput) -> Result<(), String> {
    let scale = &ctx.scale;
    let fs = at(scale, b, b.bidir_reference_passes);
    let scene = scene(scale);
    let reference = ctx.reference_at(&fs, &scene, None)?;
    let (budget_s, arms) = comparison(scale, b)?.run(ctx)?;
    let (bdpt, pt) = (&arms[0], &arms[1]);
    let n = pt.passes;
    let (eb, ib) = errors(&bdpt.entries, &reference, scale.confidence)?;
    let (ep, ip) = errors(&pt.entries, &reference, scale.confidence)?;
    let mut rows = Vec::new();
    for (arm, e) in [(pt, &ep), (bdpt, &eb)] {
        let mut row = vec![
            arm.contender.0.to_string(),
            arm.passes.to_string(),
            num(super::mean_cpu(&arm.entries)),
        ];
        row.extend(cell(&e.rel));
        row.extend(cell(&e.flip));
        row.extend(cell(&e.mse));
        rows.push(row);
    }
    out.table(
        "bidir",
        "Figure 1: Veach's bidirectional room at equal time",
        &format!(
            "veach-bidir (Bitterli's), pt against bdpt at {} CPU s per run (bdpt's cost at {} \
             passes; pt's pass count from {} interleaved probes of each at that count, the runs \
             interleaved too; CPU s is what each arm took). Reference: {} passes of {}.",
            num(budget_s),
            b.bdpt_passes,
            b.probes,
            reference.passes,
            reference.integrator
        ),
        &columns(
            &["integrator", "passes", "CPU s"],
            &["MSE", "MSE lo", "MSE hi"],
        ),
        rows,
        true,
    )?;
    let ratio = ep.rel.estimate / eb.rel.estimate;
    let flip_ratio = ep.flip.estimate / eb.flip.estimate;
    let rel_apart = eb.rel.hi < ep.rel.lo;
    let flip_apart = eb.flip.hi < ep.flip.lo;
    // pt's error here is a few bright fireflies (caustic paths through the lamp's glass): its
    // relMSE is heavy-tailed, and K runs may not bound its mean even when every image shows it.
    let verdict = match (rel_apart, flip_apart) {
        (true, true) => format!(
            "holds: at equal CPU time pt's relMSE is {}× bdpt's and its FLIP {}× (both intervals \
             apart)",
            num(ratio),
            num(flip_ratio)
        ),
        (false, true) => format!(
            "holds to the eye: at equal CPU time pt's FLIP is {}× bdpt's, the intervals apart; \
             pt's relMSE is {}× bdpt's by its mean, but its interval reaches below bdpt's: pt's \
             error is a few fireflies whose mean {} runs cannot bound",
            num(flip_ratio),
            num(ratio),
            b.runs
        ),
        _ => format!(
            "is not shown at this budget: pt's relMSE is {}× bdpt's and its FLIP {}×, the \
             intervals overlapping",
            num(ratio),
            num(flip_ratio)
        ),
    };
    out.para(&format!(
        "**Verdict (figure 1).** Veach's claim — bidirectional sampling renders the room lit \
         from the lamp's shade far better than path tracing in the same time — {verdict}."
    ));
    let name = stem(&scene);
    let notes = [
        (
            "pt",
            &ip[0],
            format!(
                "{n} spp, relMSE {}, FLIP {}",
                num(ep.rel.estimate),
                num(ep.flip.estimate)
            ),
        ),
        (
            "bdpt",
            &ib[0],
            format!(
                "{} spp, relMSE {}, FLIP {}",
                b.bdpt_passes,
                num(eb.rel.estimate),
                num(eb.flip.estimate)
            ),
        ),
    ];
    let entries = labelled_entries(&notes, &name);
    let g = write_gallery(
        &out.dir,
        "Figure 1: veach-bidir, pt against bdpt at equal CPU time",
        &format!(
            "Equal CPU time ({} s per run). Reference: {} passes of bdpt.",
            num(budget_s),
            reference.passes
        ),
        &reference.gallery_entry(format!("gallery/{name}/reference")),
        &entries,
        Some((b.width / 4).max(4)),
    )?;
    out.manifest.galleries.push(g);
    Ok(())
}

/// The command that writes the pyramid the study reads.
pub fn pyramid_command(results: &Path) -> String {
    format!(
        "lt -D integrator=path -D resx=128 -D resy=128 render scenes/bitterli/veach-bidir/scene.xml \
         -i bdpt --spp 16 --seed 7 --threads 1 --strategies {} -o /tmp/figpyr-img.exr",
        results.join(PYRAMID_DIR).display()
    )
}

/// bdpt's per-strategy images of veach-bidir (weighted by MIS), lengths `PYRAMID_LENGTHS`, when
/// `lt render --strategies` wrote them under `PYRAMID_DIR`; otherwise a line saying how to.
pub(super) fn pyramid_gallery(ctx: &StudyContext, out: &mut StudyOutput) -> Result<(), String> {
    let dir = ctx.results.join(PYRAMID_DIR);
    if !dir.is_dir() {
        out.para(&format!(
            "The path pyramid is not shown: `{}` is missing; `{}` writes it.",
            dir.display(),
            pyramid_command(&ctx.results)
        ));
        return Ok(());
    }
    for k in PYRAMID_LENGTHS {
        let mut images = Vec::new();
        let mut sum: Option<Image> = None;
        for s in 0..=k {
            let t = k + 1 - s;
            let path = dir.join(format!("k{k}_s{s}_t{t}.weighted.exr"));
            let img = crate::image_io::read_exr(&path)?;
            sum = Some(match sum {
                None => img.clone(),
                Some(mut acc) => {
                    for (a, p) in acc.data.iter_mut().zip(&img.data) {
                        for c in 0..3 {
                            a[c] += p[c];
                        }
                    }
                    acc
                }
            });
            images.push((format!("s={s}, t={t}"), img));
        }
        let sum = sum.ok_or("empty pyramid row")?;
        let entries: Vec<Entry> = images
            .iter()
            .enumerate()
            .map(|(i, (l, img))| Entry {
                label: l,
                note: "MIS-weighted".into(),
                image: img,
                stem: format!("gallery/pyramid/k{k}-{i}"),
            })
            .collect();
        let g = write_gallery(
            &out.dir,
            &format!("Figure 1b: bdpt's path pyramid on veach-bidir, paths of {k} segments"),
            &format!(
                "Each strategy (s light vertices, t camera vertices, s + t − 1 = {k}) with its MIS \
                 weight; they sum to the image of length-{k} paths (\"reference\" here). \
                 Veach 1997, fig. 10.3. Written by `{}`.",
                pyramid_command(Path::new("results"))
            ),
            &Entry {
                label: "sum",
                note: format!("all paths of {k} segments"),
                image: &sum,
                stem: format!("gallery/pyramid/k{k}-sum"),
            },
            &entries,
            None,
        )?;
        out.manifest.galleries.push(g);
    }
    Ok(())
}

//! Figure (a), Jarosz, Nowrouzezahrai, Sadeghi & Jensen 2011 ("A comprehensive theory of
//! volumetric radiance estimation using photon points and beams"): at equal time, in a thin
//! medium lit through an opening, beams (pb2d, bb1d) beat points (pp3d) by a wide margin.

use super::super::output::{num, StudyOutput};
use super::super::{Scale, StudyContext};
use super::cells::Cell;
use super::{gallery, measure, media_scene, row, wide_margin, Budget, Measured, COLUMNS};

pub const SCENE: &str = "light-shafts";
const ESTIMATORS: [&str; 5] = ["pp3d", "pb2d", "bb1d", "upbp", "pt"];

pub fn cells(scale: &Scale) -> Vec<Cell> {
    ESTIMATORS
        .iter()
        .map(|i| Cell::new(media_scene(scale, SCENE), i))
        .collect()
}

/// Renders what the cache lacks, writes the table and gallery; returns the verdict row.
pub fn figure(
    ctx: &StudyContext,
    b: &Budget,
    fs: &Scale,
    out: &mut StudyOutput,
) -> Result<Vec<String>, String> {
    let scene = media_scene(&ctx.scale, SCENE);
    let reference = ctx.reference_at(fs, &scene, None)?;
    let ms: Vec<Measured> = cells(&ctx.scale)
        .iter()
        .map(|c| measure(ctx, c, c.integrator, (b, fs), &reference))
        .collect::<Result<_, _>>()?;
    let rows = ms.iter().map(row).collect();
    out.table(
        "points-vs-beams",
        "Figure (a): points against beams at equal time (Jarosz et al. 2011)",
        &format!(
            "{SCENE} (fog σt 0.25, albedo 0.8, lit through a 0.1-wide slit), {} CPU s per run; \
             pt is the unbiased baseline, upbp (bdpt + PP3D + PB2D + BB1D) beside them.",
            num(b.cpu_seconds)
        ),
        &COLUMNS,
        rows,
        true,
    )?;
    let get = |l: &str| {
        ms.iter()
            .find(|m| m.label == l)
            .expect("every estimator ran")
    };
    let points = &get("pp3d").errors.rel;
    let beams = ["pb2d", "bb1d"];
    let wins: Vec<&str> = beams
        .iter()
        .copied()
        .filter(|l| wide_margin(&get(l).errors.rel, points))
        .collect();
    let verdict = match wins.len() {
        2 => "holds".to_string(),
        1 => format!("holds for {} only", wins[0]),
        _ => "does not hold".to_string(),
    };
    let ratio = |l: &str| points.estimate / get(l).errors.rel.estimate;
    let flip_ratio = |l: &str| get("pp3d").errors.flip.estimate / get(l).errors.flip.estimate;
    let numbers = format!(
        "relMSE pp3d/pb2d {}×, pp3d/bb1d {}×; FLIP pp3d/pb2d {}×, pp3d/bb1d {}×; pt/pp3d {}×",
        num(ratio("pb2d")),
        num(ratio("bb1d")),
        num(flip_ratio("pb2d")),
        num(flip_ratio("bb1d")),
        num(get("pt").errors.rel.estimate / points.estimate)
    );
    out.para(&format!(
        "**Verdict (a).** Jarosz et al.'s claim — beams beat points by a wide margin in a thin \
         medium at equal time (here: the beam's relMSE interval wholly below pp3d's and its mean \
         at most half) — {verdict} on {SCENE}: {numbers}."
    ));
    gallery(
        out,
        (
            &format!("Figure (a): {SCENE}, points against beams at equal CPU time"),
            &format!(
                "{} CPU s per run. Reference: {} passes of {}.",
                num(b.cpu_seconds),
                reference.passes,
                reference.integrator
            ),
        ),
        SCENE,
        &reference,
        &ms,
    )?;
    Ok(vec![
        "a".into(),
        "beams (pb2d, bb1d) beat points (pp3d) by a wide margin in a thin medium".into(),
        verdict,
        numbers,
    ])
}

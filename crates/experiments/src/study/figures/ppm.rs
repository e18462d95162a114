//! Figure 3: Hachisuka, Ogaki & Jensen 2008 (progressive photon mapping). On `caustic-sds` the
//! camera sees a glass ball's caustic only in a mirror: its paths are L S S D S E, whose diffuse
//! vertex no connection can reach (both its neighbours are specular), so `pt` and `bdpt` find
//! them only when a BSDF-sampled ray happens to hit the small lamp — a few bright fireflies —
//! while `ppm` and `sppm` gather them as photons. On `cornell-point-caustic` a point light's
//! caustic under a glass ball is seen directly (L S S D E): `pt` cannot sample it at all (no ray
//! hits a point, no shadow ray passes the glass), `bdpt` can, by light tracing. All four at equal
//! CPU time (sppm's pass count fixes it; `EqualTime`), errors over the whole image and over the
//! caustic's crop, each against the scene's reference (`reference::integrator_for`).

use super::{
    cell, columns, crop_image, crop_reference, errors, errors_of_images, film, labelled_entries,
    num, reference_scale, toml_scene, Budget, Contender, EqualTime, Errors,
};
use crate::gallery::write_gallery;
use crate::manifest::Crop;
use crate::runs::RunSpec;
use crate::study::output::StudyOutput;
use crate::study::{Scale, StudyContext};
use std::path::PathBuf;

/// One scene of the figure: its name, the caustic's crop as fractions of the film (x0, y0, x1,
/// y1) — where its reference shows the caustic — and what the caustic's paths are.
pub(super) struct CausticScene {
    pub name: &'static str,
    pub crop: [f64; 4],
    pub paths: &'static str,
}

/// The scenes, in `Budget::sppm_passes`' order.
pub(super) const SCENES: [CausticScene; 2] = [
    CausticScene {
        name: "caustic-sds",
        // The bright ellipse beside the ball, in the ball's shadow, seen in the mirror.
        crop: [0.33, 0.4, 0.7, 0.6],
        paths: "the caustic seen in the mirror, L S S D S E",
    },
    CausticScene {
        name: "cornell-point-caustic",
        // The focused spot on the floor under the ball and the shadow around it (the reference
        // at 128 px: peak at (82, 114), 1.8–3.3 against 0.1 on the floor around).
        crop: [0.56, 0.86, 0.74, 0.93],
        paths: "a point light's caustic under the glass ball, seen directly, L S S D E",
    },
];

/// The unbiased estimators first, then the consistent ones; `sppm` fixes the time.
const UNBIASED: [Contender; 2] = [Contender("pt"), Contender("bdpt")];
const PPM: Contender = Contender("ppm");
const SPPM: Contender = Contender("sppm");

fn scene(scale: &Scale, k: usize) -> PathBuf {
    toml_scene(scale, SCENES[k].name)
}

fn reference_at(scale: &Scale, b: &Budget, k: usize) -> Scale {
    reference_scale(scale, b, &scene(scale, k), b.vcm_reference_passes)
}

fn comparison(scale: &Scale, b: &Budget, k: usize) -> Result<EqualTime, String> {
    let scene = scene(scale, k);
    let res = film(&reference_at(scale, b, k), &scene)?;
    Ok(EqualTime {
        scene,
        res,
        runs: b.comparison_runs,
        probes: b.probes,
        setter: SPPM,
        setter_passes: b.sppm_passes[k],
        others: vec![UNBIASED[0], UNBIASED[1], PPM],
    })
}

/// `fractions` (x0, y0, x1, y1) in pixels of a `w`×`h` film (at least one pixel each way).
pub(super) fn crop_of(fractions: [f64; 4], w: usize, h: usize) -> Crop {
    let [x0, y0, x1, y1] = fractions;
    let x = ((x0 * w as f64).floor() as u32).min(w as u32 - 1);
    let y = ((y0 * h as f64).floor() as u32).min(h as u32 - 1);
    let x_end = ((x1 * w as f64).ceil() as u32).clamp(x + 1, w as u32);
    let y_end = ((y1 * h as f64).ceil() as u32).clamp(y + 1, h as u32);
    Crop {
        x,
        y,
        w: x_end - x,
        h: y_end - y,
    }
}

pub(super) fn specs(
    scale: &Scale,
    b: &Budget,
    ctx: Option<&StudyContext>,
) -> Result<Vec<RunSpec>, String> {
    let mut v = Vec::new();
    for k in 0..SCENES.len() {
        v.extend(crate::study::reference::spec(
            &reference_at(scale, b, k),
            &scene(scale, k),
            None,
        ));
        v.extend(comparison(scale, b, k)?.planned(ctx)?);
    }
    Ok(v)
}

/// `winner` is shown better than `loser`: its interval lies below.
fn below(winner: &lt_estimators::Interval, loser: &lt_estimators::Interval) -> bool {
    winner.hi < loser.lo
}

pub(super) fn figure(ctx: &StudyContext, b: &Budget, out: &mut StudyOutput) -> Result<(), String> {
    let mut rows = Vec::new();
    let mut budgets = Vec::new();
    let mut verdicts = Vec::new();
    for k in 0..SCENES.len() {
        let (budget_s, v) = scene_figure(ctx, b, k, out, &mut rows)?;
        budgets.push(format!(
            "{} {} CPU s per run (sppm at {} passes)",
            SCENES[k].name,
            num(budget_s),
            b.sppm_passes[k]
        ));
        verdicts.push(v);
    }
    out.table(
        "ppm",
        "Figure 3: caustics at equal time (Hachisuka et al. 2008)",
        &format!(
            "{} independent runs per estimator at equal CPU time: {}. The others' pass counts \
             come from {} interleaved probes of each at sppm's count (their mean CPU s per \
             pass), the runs interleaved too (`EqualTime`); CPU s is what each arm took. Errors \
             over the whole image and over the caustic's crop (caustic-sds: the caustic seen in \
             the mirror; cornell-point-caustic: the spot under the ball). References: \
             independent vcm runs at radius 1 px (caustic-sds), bdpt at {} passes \
             (cornell-point-caustic).",
            b.comparison_runs,
            budgets.join("; "),
            b.probes,
            b.vcm_reference_passes,
        ),
        &columns(
            &["scene", "integrator", "kind", "passes", "CPU s"],
            &[
                "caustic relMSE",
                "caustic relMSE lo",
                "caustic relMSE hi",
                "caustic FLIP",
                "caustic FLIP lo",
                "caustic FLIP hi",
            ],
        ),
        rows,
        true,
    )?;
    for v in verdicts {
        out.para(&v);
    }
    Ok(())
}

/// Scene `k`'s rows (into `rows`) and gallery; its budget in CPU s per run and its verdict.
fn scene_figure(
    ctx: &StudyContext,
    b: &Budget,
    k: usize,
    out: &mut StudyOutput,
    rows: &mut Vec<Vec<String>>,
) -> Result<(f64, String), String> {
    let scale = &ctx.scale;
    let sc = &SCENES[k];
    let reference = ctx.reference_at(&reference_at(scale, b, k), &scene(scale, k), None)?;
    let (budget_s, arms) = comparison(scale, b, k)?.run(ctx)?;
    let crop = crop_of(sc.crop, reference.image.width, reference.image.height);
    let cropped = crop_reference(&reference, crop);
    // Table order: pt, bdpt, ppm, then sppm (the setter, first in `arms`).
    let order = [1, 2, 3, 0];
    let mut measured: Vec<(&str, Errors, Errors)> = Vec::new();
    let mut shown = Vec::new();
    for &i in &order {
        let arm = &arms[i];
        let (full, images) = errors(&arm.entries, &reference, scale.confidence)?;
        let crops: Vec<_> = images.iter().map(|img| crop_image(img, crop)).collect();
        let sds = errors_of_images(&crops, &cropped, scale.confidence)?;
        let consistent = crate::runs::is_consistent(arm.contender.0);
        let mut row = vec![
            sc.name.to_string(),
            arm.contender.0.to_string(),
            if consistent { "consistent" } else { "unbiased" }.to_string(),
            arm.passes.to_string(),
            num(super::mean_cpu(&arm.entries)),
        ];
        row.extend(cell(&full.rel));
        row.extend(cell(&full.flip));
        row.extend(cell(&sds.rel));
        row.extend(cell(&sds.flip));
        rows.push(row);
        shown.push((
            arm.contender.0,
            images.into_iter().next().ok_or("no runs")?,
            format!(
                "{} spp, relMSE {} (caustic {}), FLIP {}",
                arm.passes,
                num(full.rel.estimate),
                num(sds.rel.estimate),
                num(full.flip.estimate)
            ),
        ));
        measured.push((arm.contender.0, full, sds));
    }
    let dir = format!("ppm-{}", sc.name);
    let entries = labelled_entries(&shown, &dir);
    let g = write_gallery(
        &out.dir,
        &format!("Figure 3: {}, {} at equal CPU time", sc.name, sc.paths),
        &format!(
            "Equal CPU time ({} s per run); the caustic is the crop {}×{} at ({}, {}). \
             Reference: {}.",
            num(budget_s),
            crop.w,
            crop.h,
            crop.x,
            crop.y,
            reference.described()
        ),
        &reference.gallery_entry(format!("gallery/{dir}/reference")),
        &entries,
        Some((b.width / 4).max(4)),
    )?;
    out.manifest.galleries.push(g);
    Ok((budget_s, verdict(sc, &measured)))
}

/// The verdict on Hachisuka et al.'s claim from the caustic crop's errors: the better consistent
/// estimator against the better unbiased one (by relMSE), each measure's intervals apart or not.
fn verdict(sc: &CausticScene, measured: &[(&str, Errors, Errors)]) -> String {
    let best = |consistent: bool| {
        measured
            .iter()
            .filter(|m| crate::runs::is_consistent(m.0) == consistent)
            .min_by(|a, b| a.2.rel.estimate.total_cmp(&b.2.rel.estimate))
            .expect("both kinds are measured")
    };
    let (c, u) = (best(true), best(false));
    let rel_ratio = u.2.rel.estimate / c.2.rel.estimate;
    let flip_ratio = u.2.flip.estimate / c.2.flip.estimate;
    let rel_apart = below(&c.2.rel, &u.2.rel);
    let flip_apart = below(&c.2.flip, &u.2.flip);
    let claim = match (rel_apart, flip_apart) {
        (true, true) => format!(
            "holds: on the caustic, the better consistent estimator ({}) has {}× less relMSE \
             than the better unbiased one ({}) and {}× less FLIP, both intervals apart",
            c.0,
            num(rel_ratio),
            u.0,
            num(flip_ratio)
        ),
        (false, true) => format!(
            "holds to the eye: on the caustic, {}'s FLIP is {}× below {}'s, the intervals \
             apart; by relMSE {}× less, but the intervals meet",
            c.0,
            num(flip_ratio),
            u.0,
            num(rel_ratio)
        ),
        _ => format!(
            "is not shown at this budget: on the caustic, the better unbiased estimator ({}) \
             has {}× the relMSE of the better consistent one ({}) and {}× its FLIP, the FLIP \
             intervals not apart in the consistent one's favour",
            u.0,
            num(rel_ratio),
            c.0,
            num(flip_ratio)
        ),
    };
    format!(
        "**Verdict (figure 3, {}).** Hachisuka et al.'s claim — on caustics seen through a \
         specular surface only the consistent estimators converge — {claim}. Here the caustic \
         is {}. Over the whole image the better unbiased estimator's error is {}.",
        sc.name,
        sc.paths,
        whole_image(c, u)
    )
}

fn whole_image(c: &(&str, Errors, Errors), u: &(&str, Errors, Errors)) -> String {
    format!(
        "{}× {}'s by relMSE and {}× by FLIP",
        num(u.1.rel.estimate / c.1.rel.estimate),
        c.0,
        num(u.1.flip.estimate / c.1.flip.estimate)
    )
}

//! Figure 3: Hachisuka, Ogaki & Jensen 2008 (progressive photon mapping). On `caustic-sds` the
//! camera sees a glass ball's caustic only in a mirror: its paths are L S S D S E, whose diffuse
//! vertex no connection can reach (both its neighbours are specular), so `pt` and `bdpt` find
//! them only when a BSDF-sampled ray happens to hit the small lamp — a few bright fireflies —
//! while `ppm` and `sppm` gather them as photons. All four at equal CPU time (sppm's runs fix
//! it), errors over the whole image and over the caustic's crop (`SDS_CROP`), each against
//! independent vcm runs at radius 1 px (`reference::integrator_for`).

use super::{
    cell, columns, crop_image, crop_reference, errors, errors_of_images, film, labelled_entries,
    num, reference_scale, toml_scene, Budget, Contender, EqualTime, Errors,
};
use crate::gallery::write_gallery;
use crate::manifest::Crop;
use crate::runs::RunSpec;
use crate::study::output::{stem, StudyOutput};
use crate::study::{Scale, StudyContext};
use std::path::PathBuf;

/// The caustic as seen in the mirror, as fractions of the film (x0, y0, x1, y1): where the
/// reference's caustic is (the bright ellipse beside the ball, in the ball's shadow).
pub(super) const SDS_CROP: [f64; 4] = [0.33, 0.4, 0.7, 0.6];

/// The unbiased estimators first, then the consistent ones; `sppm` fixes the time.
const UNBIASED: [Contender; 2] = [Contender("pt"), Contender("bdpt")];
const PPM: Contender = Contender("ppm");
const SPPM: Contender = Contender("sppm");

fn scene(scale: &Scale) -> PathBuf {
    toml_scene(scale, "caustic-sds")
}

fn reference_at(scale: &Scale, b: &Budget) -> Scale {
    reference_scale(scale, b, &scene(scale), b.vcm_reference_passes)
}

fn comparison(scale: &Scale, b: &Budget) -> Result<EqualTime, String> {
    let scene = scene(scale);
    let res = film(&reference_at(scale, b), &scene)?;
    Ok(EqualTime {
        scene,
        res,
        runs: b.comparison_runs,
        setter: SPPM,
        setter_passes: b.sppm_passes,
        others: vec![UNBIASED[0], UNBIASED[1], PPM],
    })
}

/// `SDS_CROP` in pixels of a `w`×`h` film (at least one pixel each way).
pub(super) fn sds_crop(w: usize, h: usize) -> Crop {
    let [x0, y0, x1, y1] = SDS_CROP;
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
    v.extend(crate::study::reference::spec(
        &reference_at(scale, b),
        &scene(scale),
        None,
    ));
    v.extend(comparison(scale, b)?.planned(ctx)?);
    Ok(v)
}

/// `winner` is shown better than `loser`: its interval lies below.
fn below(winner: &lt_estimators::Interval, loser: &lt_estimators::Interval) -> bool {
    winner.hi < loser.lo
}

pub(super) fn figure(ctx: &StudyContext, b: &Budget, out: &mut StudyOutput) -> Result<(), String> {
    let scale = &ctx.scale;
    let scene = scene(scale);
    let reference = ctx.reference_at(&reference_at(scale, b), &scene, None)?;
    let (budget_s, arms) = comparison(scale, b)?.run(ctx)?;
    let crop = sds_crop(reference.image.width, reference.image.height);
    let cropped = crop_reference(&reference, crop);
    // Table order: pt, bdpt, ppm, then sppm (the setter, first in `arms`).
    let order = [1, 2, 3, 0];
    let mut rows = Vec::new();
    let mut measured: Vec<(&str, Errors, Errors)> = Vec::new();
    let mut shown = Vec::new();
    for &i in &order {
        let arm = &arms[i];
        let (full, images) = errors(&arm.entries, &reference, scale.confidence)?;
        let crops: Vec<_> = images.iter().map(|img| crop_image(img, crop)).collect();
        let sds = errors_of_images(&crops, &cropped, scale.confidence)?;
        let consistent = crate::runs::is_consistent(arm.contender.0);
        let mut row = vec![
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
    out.table(
        "ppm",
        "Figure 3: caustics seen in a mirror at equal time (Hachisuka et al. 2008)",
        &format!(
            "caustic-sds, {} independent runs per estimator at {} CPU s per run (sppm's mean at \
             {} passes; the others' pass counts from their CPU time per pass at {} passes). \
             Errors over the whole image and over the caustic seen in the mirror (the crop \
             {}×{} at ({}, {})). Reference: {} independent runs of {} at radius 1 px, {} passes \
             in all.",
            b.comparison_runs,
            num(budget_s),
            b.sppm_passes,
            b.sppm_passes,
            crop.w,
            crop.h,
            crop.x,
            crop.y,
            reference.runs,
            reference.integrator,
            reference.passes * reference.runs,
        ),
        &columns(
            &["integrator", "kind", "passes", "CPU s"],
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
    out.para(&verdict(&measured));
    let name = stem(&scene);
    let entries = labelled_entries(&shown, &format!("sds-{name}"));
    let g = write_gallery(
        &out.dir,
        "Figure 3: caustic-sds, the caustic seen in the mirror at equal CPU time",
        &format!(
            "Equal CPU time ({} s per run); the caustic is the bright patch in the mirror. \
             Reference: {} runs of {} at radius 1 px.",
            num(budget_s),
            reference.runs,
            reference.integrator
        ),
        &reference.gallery_entry(format!("gallery/sds-{name}/reference")),
        &entries,
        Some((b.width / 4).max(4)),
    )?;
    out.manifest.galleries.push(g);
    Ok(())
}

/// The verdict on Hachisuka et al.'s claim from the caustic crop's errors: the better consistent
/// estimator against the better unbiased one (by relMSE), each measure's intervals apart or not.
fn verdict(measured: &[(&str, Errors, Errors)]) -> String {
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
            "is not shown at this budget: on the caustic, {} against {}: relMSE ratio {}, FLIP \
             ratio {}, the intervals meeting",
            c.0,
            u.0,
            num(rel_ratio),
            num(flip_ratio)
        ),
    };
    format!(
        "**Verdict (figure 3).** Hachisuka et al.'s claim — on caustics seen through a specular \
         surface only the consistent estimators converge — {claim}. Over the whole image (the \
         diffuse floor and ball dominate) the unbiased estimators' error is {}.",
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

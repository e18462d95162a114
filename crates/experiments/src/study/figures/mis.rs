//! Figure 2: Veach & Guibas 1995's MIS figure — pt with BSDF sampling only, light sampling only,
//! the balance and the power heuristic, at equal samples — on Bitterli's `veach-mis` and ours
//! (`scenes/veach-mis.toml`, which takes none of the study's `-D` definitions: they apply to
//! Mitsuba XML scenes only, see `crate::scene_load`).

use super::{at, cell, columns, errors, film, num, run_spec, Budget};
use crate::gallery::{write_gallery, Entry};
use crate::runs::RunSpec;
use crate::study::equal_time::VEACH;
use crate::study::output::{stem, StudyOutput};
use crate::study::{Scale, StudyContext};
use std::path::{Path, PathBuf};

/// Bitterli's and ours.
fn scenes(scale: &Scale) -> Vec<PathBuf> {
    vec![
        scale.scene_beside_focus("bitterli/veach-mis/scene.xml"),
        super::toml_scene(scale, "veach-mis"),
    ]
}

/// A scene's label in the table and its galleries' folder (Bitterli's and ours share a stem).
fn names(scene: &Path) -> (String, String) {
    let name = stem(scene);
    if scene.extension().is_some_and(|e| e == "xml") {
        (format!("{name} (Bitterli)"), name)
    } else {
        (format!("{name} (ours)"), format!("{name}-ours"))
    }
}

fn spec(scene: &Path, res: (u32, u32), params: &[(&str, &str)], seed: u64, passes: u32) -> RunSpec {
    let mut s = run_spec(scene, res, "pt", seed, passes);
    for (k, v) in params {
        s = s.param(k, v);
    }
    s
}

pub(super) fn specs(scale: &Scale, b: &Budget) -> Result<Vec<RunSpec>, String> {
    let fs = at(scale, b, b.mis_reference_passes);
    let mut v = Vec::new();
    for scene in scenes(scale) {
        let res = film(&fs, &scene)?;
        v.extend(crate::study::reference::spec(&fs, &scene, None));
        for (_, p) in VEACH {
            for r in 0..b.runs {
                v.push(spec(&scene, res, p, 1 + r as u64, b.mis_passes));
            }
        }
    }
    Ok(v)
}

pub(super) fn figure(ctx: &StudyContext, b: &Budget, out: &mut StudyOutput) -> Result<(), String> {
    let scale = &ctx.scale;
    let fs = at(scale, b, b.mis_reference_passes);
    let mut rows = Vec::new();
    let mut verdicts = Vec::new();
    for scene in scenes(scale) {
        let (label, name) = names(&scene);
        let res = film(&fs, &scene)?;
        let reference = ctx.reference_at(&fs, &scene, None)?;
        let mut shown = Vec::new();
        let mut rel = Vec::new();
        for (k, (technique, params)) in VEACH.iter().enumerate() {
            let specs: Vec<RunSpec> = (0..b.runs)
                .map(|r| spec(&scene, res, params, 1 + r as u64, b.mis_passes))
                .collect();
            let entries = ctx.run_all(&specs)?;
            let (e, mut imgs) = errors(&entries, &reference, scale.confidence)?;
            let mut row = vec![
                label.clone(),
                technique.to_string(),
                b.mis_passes.to_string(),
                num(super::mean_cpu(&entries)),
            ];
            row.extend(cell(&e.rel));
            row.extend(cell(&e.flip));
            rows.push(row);
            shown.push((
                k,
                *technique,
                imgs.swap_remove(0),
                format!(
                    "relMSE {}, FLIP {}",
                    num(e.rel.estimate),
                    num(e.flip.estimate)
                ),
            ));
            rel.push(e.rel);
        }
        // VEACH's order: bsdf, light, balance, power.
        let best_single = if rel[0].estimate <= rel[1].estimate {
            0
        } else {
            1
        };
        let worst_single = 1 - best_single;
        let power = &rel[3];
        let robust = power.lo <= rel[best_single].hi;
        verdicts.push(format!(
            "on {label} the power heuristic's relMSE is {}× the better single technique's \
             ({}) and {}× the worse one's ({}){}; balance/power = {:.2}",
            num(power.estimate / rel[best_single].estimate),
            VEACH[best_single].0,
            num(power.estimate / rel[worst_single].estimate),
            VEACH[worst_single].0,
            if robust {
                ", within the better one's interval or below it"
            } else {
                ", above the better one's interval"
            },
            rel[2].estimate / power.estimate
        ));
        let entries: Vec<Entry> = shown
            .iter()
            .map(|(k, l, img, note)| Entry {
                label: l,
                note: note.clone(),
                image: img,
                stem: format!("gallery/mis-{name}/{k}"),
            })
            .collect();
        let g = write_gallery(
            &out.dir,
            &format!("Figure 2: Veach's MIS comparison on {label}, equal samples"),
            &format!(
                "pt at {} passes with BSDF sampling only, light sampling only, and both combined \
                 by the balance and the power heuristic. Reference: {} passes of {}.",
                b.mis_passes, reference.passes, reference.integrator
            ),
            &reference.gallery_entry(format!("gallery/mis-{name}/reference")),
            &entries,
            Some((b.width / 4).max(4)),
        )?;
        out.manifest.galleries.push(g);
    }
    out.table(
        "mis",
        "Figure 2: Veach's MIS comparison at equal samples",
        "pt by technique and heuristic, the same passes for each; CPU s is the mean per run.",
        &columns(&["scene", "technique", "passes", "CPU s"], &[]),
        rows,
        true,
    )?;
    out.para(&format!(
        "**Verdict (figure 2).** Veach & Guibas's claim — MIS is never much worse than the \
         better single technique and far better than the worse — holds where the power heuristic's interval reaches the \
         better one's: {}.",
        verdicts.join("; ")
    ));
    Ok(())
}

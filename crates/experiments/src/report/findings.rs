//! The report's first section: the three things the studies exist to show, one figure each with
//! the number that proves it, read from the committed CSVs (so the page and `results/findings.md`
//! say what the tables say). tests/studies.rs holds every number quoted here to its own interval.
//! Absent when the studies' CSVs are (a results folder of other studies).

use std::collections::HashMap;
use std::path::Path;

/// One finding: its heading, the figure (study folder, file stem) and the Markdown text.
pub struct Finding {
    pub title: &'static str,
    pub folder: &'static str,
    pub figure: &'static str,
    pub text: String,
}

/// The rows of a study table (the writer quotes cells holding commas).
pub fn csv(path: &Path) -> Result<Vec<HashMap<String, String>>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .ok_or_else(|| format!("{}: empty", path.display()))?
        .split(',')
        .map(String::from)
        .collect();
    Ok(lines
        .map(|l| {
            let mut cells = Vec::new();
            let (mut cur, mut quoted) = (String::new(), false);
            for ch in l.chars() {
                match ch {
                    '"' => quoted = !quoted,
                    ',' if !quoted => cells.push(std::mem::take(&mut cur)),
                    c => cur.push(c),
                }
            }
            cells.push(cur);
            header.iter().cloned().zip(cells).collect()
        })
        .collect())
}

fn row<'a>(
    rows: &'a [HashMap<String, String>],
    integrator: &str,
    alpha: &str,
    quantity: &str,
) -> Result<&'a HashMap<String, String>, String> {
    rows.iter()
        .find(|r| r["integrator"] == integrator && r["α"] == alpha && r["quantity"] == quantity)
        .ok_or_else(|| format!("no row {integrator} α = {alpha} {quantity}"))
}

fn slope(r: &HashMap<String, String>) -> String {
    format!("{} {}", r["measured"], r["CI"])
}

pub fn findings(results: &Path) -> Result<Vec<Finding>, String> {
    let uc = csv(&results.join("unbiased-vs-consistent/rates.csv"))?;
    let claims = csv(&results.join("unbiased-vs-consistent/claims.csv"))?;
    let plane = csv(&results.join("radius-shrinkage-plane/rates.csv"))?;
    let holds = claims.iter().filter(|r| r["holds"] == "yes").count();
    let consistent_n1: Vec<String> = claims
        .iter()
        .filter(|r| r["family"] == "consistent")
        .map(|r| format!("{} {}", r["estimator"], r["bias² at N = 1"]))
        .collect();
    let kz_rows: Vec<&HashMap<String, String>> = plane
        .iter()
        .filter(|r| r["quantity"] == "MSE" && r["inside"] == "yes")
        .collect();
    let mse_rows = plane.iter().filter(|r| r["quantity"] == "MSE").count();
    let mut fs = vec![
        Finding {
            title: "Unbiased estimators' MSE falls as 1/N, consistent ones' more slowly",
            folder: "unbiased-vs-consistent",
            figure: "mse",
            text: format!(
                "On `point-plane-pinhole` (exact reference), the MSE slope against N is pt {}, \
                 bdpt {}, light {} (predicted −1), and sppm {}, vcm {} (α = 2/3: predicted \
                 −min(α, 2(1−α)) = −2/3); fixed-radius pm levels off ({}).",
                slope(row(&uc, "pt", "—", "MSE")?),
                slope(row(&uc, "bdpt", "—", "MSE")?),
                slope(row(&uc, "light", "—", "MSE")?),
                slope(row(&uc, "sppm", "2/3", "MSE")?),
                slope(row(&uc, "vcm", "2/3", "MSE")?),
                slope(row(&uc, "pm (fixed radius)", "—", "MSE")?),
            ),
        },
        Finding {
            title: "Consistent estimators are biased, and their bias² decays at the predicted rate",
            folder: "unbiased-vs-consistent",
            figure: "bias2-consistent",
            text: format!(
                "bias² at N = 1 excludes 0 for every consistent estimator ({}), while every \
                 unbiased estimator's interval holds 0 at every N ({holds} of {} family claims \
                 hold, family-wise 95 %). The bias² slope is ppm {} against {} exact at these N \
                 (−2/3 asymptotic), vcm {}.",
                consistent_n1.join("; "),
                claims.len(),
                slope(row(&uc, "ppm", "2/3", "bias²")?),
                row(&uc, "ppm", "2/3", "bias²")?["predicted at these N"],
                slope(row(&uc, "vcm", "2/3", "bias²")?),
            ),
        },
        Finding {
            title: "The MSE rate against α follows Knaus & Zwicker's curve, best at α = 2/3",
            folder: "radius-shrinkage-plane",
            figure: "mse-rate",
            text: format!(
                "At frozen points on `point-plane` the MSE slope at α = 2/3 is ppm {} (predicted \
                 −2/3), sppm's photon part {}, vcm's merging {}; at α = 0.9 ppm {} (−0.2) and at \
                 α = 0.3 ppm {} (−0.3 asymptotic, {} at these N). {} of {} MSE slopes hold K&Z's \
                 rate (at these N where the model is exact) inside their interval; the others \
                 miss by a few hundredths, where bias² and variance are still of comparable size.",
                slope(row(&plane, "ppm", "2/3", "MSE")?),
                slope(row(&plane, "sppm (photon part)", "2/3", "MSE")?),
                slope(row(&plane, "vcm (merging)", "2/3", "MSE")?),
                slope(row(&plane, "ppm", "0.9", "MSE")?),
                slope(row(&plane, "ppm", "0.3", "MSE")?),
                row(&plane, "ppm", "0.3", "MSE")?["predicted at these N"],
                kz_rows.len(),
                mse_rows,
            ),
        },
    ];
    // The convergence slopes, when the study's table carries its verdicts (a committed run).
    if let Ok(rows) = csv(&results.join("convergence/slopes.csv")) {
        if rows.first().is_some_and(|r| r.contains_key("verdict")) {
            fs.push(convergence(&rows));
        }
    }
    // The media papers' three claims (issue 45, item 4), when their study's verdicts exist.
    if let Ok(rows) = csv(&results.join("media-figures/verdicts.csv")) {
        fs.push(media_figures(&rows));
    }
    Ok(fs)
}

/// Finding 4: how many slopes the convergence study tells apart, how many hold their expected
/// rate, the figure's scene's numbers, and the rows with no slope and why.
fn convergence(rows: &[HashMap<String, String>]) -> Finding {
    let slopes: Vec<&HashMap<String, String>> =
        rows.iter().filter(|r| r["verdict"] == "slope").collect();
    let count = |kind: &str, inside: &str| {
        slopes
            .iter()
            .filter(|r| r["kind"] == kind && r["inside"] == inside)
            .count()
    };
    // Consistent slopes that miss K&Z's rate, below it (faster) or above it (slower).
    let faster = |below: bool| {
        slopes
            .iter()
            .filter(|r| r["kind"] == "consistent" && r["inside"] == "no")
            .filter(|r| {
                let (s, e) = (
                    r["slope vs N"].parse::<f64>().unwrap_or(f64::NAN),
                    r["expected"].parse::<f64>().unwrap_or(f64::NAN),
                );
                (s < e) == below
            })
            .count()
    };
    let scenes: std::collections::BTreeSet<&str> =
        rows.iter().map(|r| r["scene"].as_str()).collect();
    let scene = rows
        .iter()
        .find(|r| r["scene"] == "cornell-box")
        .map_or_else(|| rows[0]["scene"].as_str(), |r| r["scene"].as_str());
    let quoted: Vec<String> = ["pt", "bdpt", "ppm", "sppm", "vcm"]
        .iter()
        .filter_map(|i| {
            rows.iter()
                .find(|r| r["scene"] == scene && r["integrator"] == *i)
        })
        .map(|r| match r["verdict"].as_str() {
            "slope" => format!("{} {} {}", r["integrator"], r["slope vs N"], r["CI vs N"]),
            v => format!("{} {}", r["integrator"], v.split(':').next().unwrap_or(v)),
        })
        .collect();
    let none: Vec<String> = rows
        .iter()
        .filter(|r| r["verdict"].starts_with("no slope"))
        .map(|r| format!("{} {}", r["scene"], r["integrator"]))
        .collect();
    let flat = rows
        .iter()
        .filter(|r| r["verdict"].starts_with("flat"))
        .count();
    Finding {
        title: "Convergence slopes told apart: unbiased −1, progressive photon mapping slower",
        folder: "convergence",
        figure: "mse-findings",
        text: format!(
            "Over {} scenes, {} of {} (scene, estimator) slopes of ln MSE against ln N have a 95 % \
             interval narrower than 0.2 that excludes 0. Of those, {} of {} unbiased ones hold \
             −1; {} of {} consistent ones hold Knaus & Zwicker's asymptotic −min(α, 2(1−α)): {} \
             fall faster (near −1, where variance still dominates bias² at these N) and {} \
             slower (where bias² dominates). On {scene}: {}. {} rows \
             are flat (fixed-radius bias, or light an estimator cannot sample). No slope ({}): \
             {} — their interval is wider than 0.2, and the slopes table says why (heavy tails, \
             or a curve that bends).",
            scenes.len(),
            slopes.len(),
            rows.len(),
            count("unbiased", "yes"),
            count("unbiased", "yes") + count("unbiased", "no"),
            count("consistent", "yes"),
            count("consistent", "yes") + count("consistent", "no"),
            faster(true),
            faster(false),
            quoted.join(", "),
            flat,
            none.len(),
            if none.is_empty() {
                "none".to_string()
            } else {
                none.join(", ")
            },
        ),
    }
}

/// Finding 5: each media figure's claim, verdict and the numbers that decide it
/// (results/media-figures/verdicts.csv; tests/media_figures.rs recomputes each verdict).
fn media_figures(rows: &[HashMap<String, String>]) -> Finding {
    let said: Vec<String> = rows
        .iter()
        .map(|r| {
            format!(
                "({}) {}: **{}** — {}.",
                r["figure"], r["claim"], r["verdict"], r["numbers"]
            )
        })
        .collect();
    Finding {
        title: "The media papers' claims at equal time: points or beams, upbp or one estimator, \
                which radius",
        folder: "media-figures",
        figure: "radius-heatmap",
        text: format!(
            "Jarosz et al. 2011 and Křivánek et al. 2014 on our media scenes, 8 independent runs \
             per cell at equal CPU time, relMSE with 95 % intervals. {}",
            said.join(" ")
        ),
    }
}

/// The findings as Markdown (`results/findings.md`), figures linked relative to `results/`.
pub fn markdown(fs: &[Finding]) -> String {
    let mut s = String::from(
        "# Findings\n\nWhat the studies show, each with its figure and the number that proves \
         it (intervals 95 %, from independent runs; tests/studies.rs holds each to its CSV).\n\n",
    );
    for (i, f) in fs.iter().enumerate() {
        s.push_str(&format!(
            "## {}. {}\n\n![{}]({}/{}.svg)\n\n{}\n\n",
            i + 1,
            f.title,
            f.title,
            f.folder,
            f.figure,
            f.text
        ));
    }
    s
}

//! The suite's scoreboard as Markdown: scene | loads | pt | bdpt | light | reason if refused.

use super::judge::PASS_FRACTION;
use super::{Budget, Outcome, Row};

/// The columns of estimators, in order.
pub const COLUMNS: [&str; 3] = ["pt", "bdpt", "light"];

fn cell(o: Option<&Outcome>) -> String {
    match o {
        None => "—".into(),
        Some(Outcome::Judged { judgement: j, spp }) => format!(
            "{} {:.2} % ({spp} spp, max \\|z\\| {:.1}, mean ×{:.3})",
            if j.passes() { "pass" } else { "**FAIL**" },
            100.0 * j.passed_fraction,
            j.max_z,
            j.mean_ratio
        ),
        Some(Outcome::Error(m)) => format!("error: {}", escape(m)),
        Some(Outcome::NotJudged(m)) => format!("not judged: {}", escape(m)),
    }
}

/// Table cells hold no `|` or newline.
fn escape(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

pub fn markdown(rows: &[Row], budget: &Budget, command: &str) -> String {
    let loads = rows.iter().filter(|r| r.refusal.is_none()).count();
    let passing: usize = rows
        .iter()
        .map(|r| r.outcomes.iter().filter(|(_, o)| o.passes()).count())
        .sum();
    let run: usize = rows.iter().map(|r| r.outcomes.len()).sum();
    let mut s = format!(
        "# Mitsuba 3's render-test suite, rendered by lt\n\n\
         `{command}` — every scene of `tests/scenes/*/`, loaded as written (no `--approximate`), \
         rendered with the estimators its file name implies (`_path`, `_direct`: pt and bdpt; \
         `_ptracer`: light and bdpt; `_volpath`, `_volpathmis`: {}, light not judged where the \
         camera sees a delta lobe) and judged against Mitsuba's reference \
         by its own rule with lt's standard errors: per pixel value z = |mean − ref| / \
         sqrt(max(se², 1e-4/n) + max(var, 1e-4)/32000 + (1e-3·ref)²) with n = min(spp, \
         2·10⁶/pixels) (Mitsuba's floor at no more than its own test's budget) and the reference's \
         f32 accumulation precision 1e-3 (judge.rs says why), a value passing when its \
         two-sided p-value is above the Šidák level 1 − 0.99^(1/pixels), the image when at least \
         {:.2} % of its values pass.\n\n\
         Budget: {} independent passes of {} samples per pixel ({} spp) per estimator, at most {:.0} s \
         per estimator, seed {}; the standard errors are the spread of the passes.\n\n\
         {loads} of {} scenes load; {passing} of {run} renders pass.\n\n\
         | scene | loads | pt | bdpt | light | reason if refused |\n|---|---|---|---|---|---|\n",
        super::cases::MEDIA_ESTIMATORS.join(" and "),
        100.0 * PASS_FRACTION,
        budget.passes,
        budget.spp_per_pass,
        budget.passes * budget.spp_per_pass,
        budget.time_per_estimator.as_secs_f64(),
        budget.seed,
        rows.len(),
    );
    for r in rows {
        let find = |c: &str| r.outcomes.iter().find(|(e, _)| *e == c).map(|(_, o)| o);
        s += &format!(
            "| {} | {} | {} | {} | {} | {} |\n",
            r.name,
            if r.refusal.is_none() { "yes" } else { "no" },
            cell(find(COLUMNS[0])),
            cell(find(COLUMNS[1])),
            cell(find(COLUMNS[2])),
            r.refusal.as_deref().map(escape).unwrap_or_default(),
        );
    }
    s
}

//! `lt compare A.exr B.exr`: our metrics of A against B, per-block z-scores when standard-error
//! images are given, and OpenImageIO's own numbers (idiff, else `oiiotool --diff`) beside ours
//! when those tools are installed, as an independent check of the metric code.

use crate::image_io::read_exr_with_alpha;
use lt_estimators::{
    agreement, agreement_with_reference, block_means, image_metrics, BlockEstimate, Image,
    ImageMetrics,
};
use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Family-wise false-alarm rate of the z-score test.
pub const FALSE_ALARM_RATE: f64 = 0.01;

/// Two images to compare (what `lt compare` takes).
#[derive(Clone, Debug)]
pub struct Comparison {
    /// Image to assess (EXR).
    pub a: PathBuf,
    /// Reference image (EXR); relative MSE divides by it.
    pub b: PathBuf,
    /// Block side in pixels for the per-region z-scores.
    pub blocks: usize,
    /// Per-pixel standard-error image of A (e.g. A.stderr.exr from `lt render`).
    pub a_stderr: Option<PathBuf>,
    /// Per-pixel standard-error image of B; without it B is taken as exact.
    pub b_stderr: Option<PathBuf>,
}

/// The text `lt compare` prints.
pub fn report(args: &Comparison) -> Result<String, String> {
    if args.blocks == 0 {
        return Err("--blocks must be at least 1".into());
    }
    let (a, a_alpha) = read_exr_with_alpha(&args.a)?;
    let (b, b_alpha) = read_exr_with_alpha(&args.b)?;
    same_size(&a, &args.a, &b, &args.b)?;
    let m = image_metrics(&a, &b);
    let mut out = String::new();
    writeln!(
        out,
        "A: {} ({}x{})\nB (reference): {}",
        args.a.display(),
        a.width,
        a.height,
        args.b.display()
    )
    .unwrap();
    write_metrics(&mut out, &m, oiio_peak(&a, &b));
    write_z_scores(&mut out, args, &a, &b)?;
    match oiio_diff(&args.a, &args.b)? {
        None => writeln!(
            out,
            "OpenImageIO (idiff/oiiotool) not found on PATH: no cross-check of the metrics."
        )
        .unwrap(),
        Some(o) => {
            if a_alpha || b_alpha {
                writeln!(out, "note: an input has an alpha channel, which OpenImageIO's averages include and ours do not.").unwrap();
            }
            write_oiio(&mut out, &o, &m, oiio_peak(&a, &b));
        }
    }
    Ok(out)
}

fn same_size(a: &Image, pa: &Path, b: &Image, pb: &Path) -> Result<(), String> {
    if a.same_size(b) {
        Ok(())
    } else {
        Err(format!(
            "{} is {}x{} but {} is {}x{}",
            pa.display(),
            a.width,
            a.height,
            pb.display(),
            b.width,
            b.height
        ))
    }
}

fn write_metrics(out: &mut String, m: &ImageMetrics, peak: f64) {
    writeln!(
        out,
        "\nMetrics of A against B (relative MSE = mean((a-b)^2/(b+0.01)^2), pbrt-v4's guard):"
    )
    .unwrap();
    writeln!(
        out,
        "{:8} {:>13} {:>13} {:>13} {:>13} {:>13}",
        "channel", "MSE", "relMSE", "RMSE", "MAE", "max |err|"
    )
    .unwrap();
    let rows = m
        .channels
        .iter()
        .zip(["R", "G", "B"])
        .chain(std::iter::once((&m.overall, "all")));
    for (c, name) in rows {
        writeln!(
            out,
            "{name:8} {:13.6e} {:13.6e} {:13.6e} {:13.6e} {:13.6e}",
            c.mse, c.rel_mse, c.rmse, c.mae, c.max_abs
        )
        .unwrap();
    }
    let (x, y, c) = m.max_at;
    writeln!(
        out,
        "largest error at pixel ({x}, {y}) channel {}",
        ["R", "G", "B"][c]
    )
    .unwrap();
    writeln!(out, "PSNR {:.4} dB (peak 1); {:.4} dB (peak max(1, largest value) = {peak:.6}, OpenImageIO's convention)", m.psnr(1.0), m.psnr(peak)).unwrap();
    if m.nonfinite_pixels > 0 {
        writeln!(
            out,
            "WARNING: {} pixels of A are NaN or infinite; the metrics above are not finite.",
            m.nonfinite_pixels
        )
        .unwrap();
    }
}

/// The PSNR peak OpenImageIO uses: the largest value in either image, at least 1.
pub fn oiio_peak(a: &Image, b: &Image) -> f64 {
    a.data
        .iter()
        .chain(&b.data)
        .flatten()
        .filter(|v| v.is_finite())
        .fold(1.0f64, |m, &v| m.max(v))
}

fn write_z_scores(out: &mut String, args: &Comparison, a: &Image, b: &Image) -> Result<(), String> {
    let load = |p: &Option<PathBuf>| -> Result<Option<Image>, String> {
        p.as_ref()
            .map(|p| {
                crate::image_io::read_exr(p)
                    .and_then(|se| same_size(&se, p, a, &args.a).map(|()| se))
            })
            .transpose()
    };
    let (sa, sb) = (load(&args.a_stderr)?, load(&args.b_stderr)?);
    let k = args.blocks;
    let est = |img: &Image, se: &Image| BlockEstimate::from_pixel_estimates(img, se, k);
    let result = match (&sa, &sb) {
        (None, None) => {
            writeln!(
                out,
                "\nNo standard-error images given (--a-stderr/--b-stderr): no z-scores."
            )
            .unwrap();
            return Ok(());
        }
        (Some(sa), Some(sb)) => agreement(&est(a, sa), &est(b, sb), FALSE_ALARM_RATE),
        (Some(sa), None) => {
            agreement_with_reference(&est(a, sa), &block_means(b, k).data, FALSE_ALARM_RATE)
        }
        (None, Some(sb)) => {
            agreement_with_reference(&est(b, sb), &block_means(a, k).data, FALSE_ALARM_RATE)
        }
    };
    writeln!(
        out,
        "\nz-scores over {k}x{k}-pixel blocks (pixel errors assumed independent; {} with |z| > 3):",
        result.count_above(3.0)
    )
    .unwrap();
    writeln!(out, "{result}").unwrap();
    Ok(())
}

/// A number as a tool printed it, with the half-unit of its last significant digit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Printed {
    pub value: f64,
    pub half_ulp: f64,
}

impl Printed {
    /// Parses a number printed by C's %g, which keeps `sig_digits` significant digits but drops
    /// trailing zeros ("0.1" may stand for 0.100000): the precision is the finer of what the
    /// digits shown and what `sig_digits` imply.
    pub fn parse(token: &str, sig_digits: i32) -> Option<Printed> {
        let value: f64 = token.parse().ok()?;
        let (mantissa, exp) = match token.find(['e', 'E']) {
            Some(i) => (&token[..i], token[i + 1..].parse::<i32>().ok()?),
            None => (token, 0),
        };
        let decimals = mantissa.find('.').map_or(0, |i| mantissa.len() - i - 1) as i32;
        let shown = 0.5 * 10f64.powi(exp - decimals);
        let g = if value == 0.0 || !value.is_finite() {
            0.0
        } else {
            0.5 * 10f64.powi(value.abs().log10().floor() as i32 - (sig_digits - 1))
        };
        Some(Printed {
            value,
            half_ulp: shown.min(g),
        })
    }
}

/// What OpenImageIO reported for a pair; fields are None where it printed nothing (it prints no
/// statistics for identical images).
#[derive(Clone, Debug, PartialEq)]
pub struct OiioDiff {
    pub tool: String,
    pub mean_error: Option<Printed>,
    pub rms_error: Option<Printed>,
    pub psnr: Option<Printed>,
    pub max_error: Option<Printed>,
    pub identical: bool,
}

/// Parses idiff's or `oiiotool --diff`'s report.
pub fn parse_oiio_diff(tool: &str, text: &str) -> OiioDiff {
    let field = |key: &str| {
        text.lines().find_map(|l| {
            let l = l.trim_start();
            let rest = l.strip_prefix(key)?.trim_start().strip_prefix('=')?;
            // OpenImageIO prints these with %g: 6 significant digits.
            Printed::parse(rest.split_whitespace().next()?, 6)
        })
    };
    OiioDiff {
        tool: tool.into(),
        mean_error: field("Mean error"),
        rms_error: field("RMS error"),
        psnr: field("Peak SNR"),
        max_error: field("Max error"),
        identical: text.lines().any(|l| l.trim() == "PASS") && field("RMS error").is_none(),
    }
}

fn find_on_path(name: &str) -> Option<PathBuf> {
    std::env::split_paths(&std::env::var_os("PATH")?)
        .map(|d| d.join(name))
        .find(|p| p.is_file())
}

/// Runs idiff (else oiiotool --diff) on the pair. Ok(None) when neither is installed.
pub fn oiio_diff(a: &Path, b: &Path) -> Result<Option<OiioDiff>, String> {
    match oiio_diff_using("idiff", a, b)? {
        Some(d) => Ok(Some(d)),
        None => oiio_diff_using("oiiotool", a, b),
    }
}

/// Runs one tool, "idiff" or "oiiotool" (as `oiiotool A B --diff`). Ok(None) when not on PATH.
pub fn oiio_diff_using(tool: &str, a: &Path, b: &Path) -> Result<Option<OiioDiff>, String> {
    let Some(exe) = find_on_path(tool) else {
        return Ok(None);
    };
    let mut cmd = Command::new(exe);
    cmd.arg(a).arg(b);
    let name = match tool {
        "idiff" => "idiff",
        "oiiotool" => {
            cmd.arg("--diff");
            "oiiotool --diff"
        }
        _ => return Err(format!("unknown OpenImageIO tool {tool}")),
    };
    // Exit status is nonzero whenever the images differ; the report on stdout is what counts.
    let o = cmd
        .output()
        .map_err(|e| format!("cannot run {name}: {e}"))?;
    let text = String::from_utf8_lossy(&o.stdout);
    let d = parse_oiio_diff(name, &text);
    if d.rms_error.is_none() && !d.identical {
        return Err(format!(
            "could not read {name}'s report on {} vs {}:\n{text}{}",
            a.display(),
            b.display(),
            String::from_utf8_lossy(&o.stderr)
        ));
    }
    Ok(Some(d))
}

/// True when `ours` is within what `theirs` can resolve: the printed precision plus float
/// rounding of their per-value differences (relative 2^-24, OpenImageIO subtracts in f32).
pub fn agrees(theirs: Printed, ours: f64) -> bool {
    (theirs.value - ours).abs() <= theirs.half_ulp + ours.abs() * f32::EPSILON as f64
}

fn write_oiio(out: &mut String, o: &OiioDiff, m: &ImageMetrics, peak: f64) {
    writeln!(out, "\nOpenImageIO ({}) beside ours:", o.tool).unwrap();
    if o.identical {
        let same = m.overall.max_abs == 0.0;
        writeln!(
            out,
            "  it reports the images identical; ours: max |err| {:e} ({})",
            m.overall.max_abs,
            if same { "agree" } else { "DIFFER" }
        )
        .unwrap();
        return;
    }
    // OpenImageIO averages over every channel, as our "all" row does.
    let rows = [
        ("RMSE", o.rms_error, m.overall.rmse),
        ("PSNR", o.psnr, m.psnr(peak)),
        ("mean |err|", o.mean_error, m.overall.mae),
        ("max |err|", o.max_error, m.overall.max_abs),
    ];
    for (name, theirs, ours) in rows {
        if let Some(t) = theirs {
            let verdict = if agrees(t, ours) {
                "agree to printed precision"
            } else {
                "DIFFER"
            };
            writeln!(
                out,
                "  {name:10} theirs {:<12} ours {:<16} {verdict}",
                t.value,
                sig(ours, 9)
            )
            .unwrap();
        }
    }
}

/// `v` with `digits` significant digits, fixed-point where that stays readable.
fn sig(v: f64, digits: i32) -> String {
    if v == 0.0 || !v.is_finite() {
        return v.to_string();
    }
    let e = v.abs().log10().floor() as i32;
    if (-4..6).contains(&e) {
        format!("{v:.*}", (digits - 1 - e).max(0) as usize)
    } else {
        format!("{v:.*e}", (digits - 1) as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_idiff_report() {
        let text = "Comparing \"a.exr\" and \"b.exr\"\n  Mean error = 0.640182\n  RMS error = 0.802266\n  Peak SNR = 7.92569\n  Max error  = 1.9442 @ (3, 0, B)  values are 0.97, 0.65 vs 1.7, 0.3\n  128 pixels (100%) over 1e-06\nFAILURE\n";
        let d = parse_oiio_diff("idiff", text);
        assert_eq!(
            d.rms_error,
            Some(Printed {
                value: 0.802266,
                half_ulp: 0.5e-6
            })
        );
        assert_eq!(d.max_error.unwrap().value, 1.9442);
        assert!((d.max_error.unwrap().half_ulp - 0.5e-5).abs() < 1e-20); // 1.94420, zero dropped
        assert!((d.psnr.unwrap().half_ulp - 0.5e-5).abs() < 1e-20);
        assert!(!d.identical);
        assert!(parse_oiio_diff("idiff", "Comparing \"a\" and \"a\"\nPASS\n").identical);
        let p = Printed::parse("1.5e-07", 6).unwrap();
        assert!((p.half_ulp - 0.5e-12).abs() < 1e-26);
        assert!((Printed::parse("0.1", 6).unwrap().half_ulp - 0.5e-6).abs() < 1e-20);
        assert!((Printed::parse("0.123456789", 6).unwrap().half_ulp - 0.5e-9).abs() < 1e-22);
    }
}

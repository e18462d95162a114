//! Our image metrics against OpenImageIO's (idiff and `oiiotool --diff`) on the same EXR pair.
//! They must agree to what float storage and OIIO's printed digits allow. Without OIIO the test
//! skips locally but fails under CI (where `.ci/run` installs it).

use lt_estimators::{image_metrics, Image};
use lt_experiments::compare::{
    self, agrees, oiio_diff_using, oiio_peak, Comparison, OiioDiff, Printed,
};
use lt_experiments::image_io::{read_exr, write_exr};
use std::path::{Path, PathBuf};

/// f32 round-to-nearest: relative error at most half an ulp, 2^-24.
const F32_HALF_ULP: f64 = f32::EPSILON as f64 / 2.0;

struct SplitMix(u64);
impl SplitMix {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn scratch() -> PathBuf {
    let d = std::env::temp_dir().join(format!("lt-oiio-agreement-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Reference-like smooth image with values up to ~3 (so OIIO's PSNR peak is not 1), and a noisy
/// estimate of it; odd sizes, f64 values that f32 cannot hold exactly.
fn pair() -> (Image, Image) {
    let mut rng = SplitMix(2718);
    let (w, h) = (67, 45);
    let r = Image::from_fn(w, h, |x, y| {
        let (u, v) = (x as f64 / w as f64, y as f64 / h as f64);
        [3.0 * u * v + 0.1, (u * 7.0).sin().abs(), 0.5 + 0.25 * v]
    });
    let a = Image {
        width: w,
        height: h,
        data: r
            .data
            .iter()
            .map(|p| p.map(|v| (v + 0.2 * (rng.uniform() - 0.5)).max(0.0)))
            .collect(),
    };
    (a, r)
}

fn oiio_or_skip(tool: &str, a: &Path, b: &Path) -> Option<OiioDiff> {
    match oiio_diff_using(tool, a, b).unwrap() {
        Some(d) => Some(d),
        None if std::env::var_os("CI").is_some() => {
            panic!("{tool} not on PATH under CI: install openimageio-tools")
        }
        None => {
            println!("{tool} not on PATH: skipping the OpenImageIO cross-check (it is required when CI is set)");
            None
        }
    }
}

#[test]
fn metrics_agree_with_openimageio() {
    let (a, b) = pair();
    let dir = scratch();
    let (pa, pb) = (dir.join("a.exr"), dir.join("b.exr"));
    write_exr(&pa, &a).unwrap();
    write_exr(&pb, &b).unwrap();
    // OIIO sees the stored f32 values; compute ours on exactly those, and on the f64 originals.
    let (sa, sb) = (read_exr(&pa).unwrap(), read_exr(&pb).unwrap());
    let stored = image_metrics(&sa, &sb);
    let orig = image_metrics(&a, &b);
    let peak = oiio_peak(&sa, &sb);

    // Storage bound: each stored value is within 2^-24 relative of the original, so each
    // difference moves by at most 2^-24(|a|+|b|); the RMS, mean and max of those bound how far
    // RMSE, MAE and max error can move (triangle inequality in each norm).
    let moves: Vec<f64> = a
        .data
        .iter()
        .zip(&b.data)
        .flat_map(|(p, q)| [0, 1, 2].map(|c| F32_HALF_ULP * (p[c].abs() + q[c].abs())))
        .collect();
    let n = moves.len() as f64;
    let rms_move = (moves.iter().map(|m| m * m).sum::<f64>() / n).sqrt();
    let mae_move = moves.iter().sum::<f64>() / n;
    let max_move = moves.iter().cloned().fold(0.0, f64::max);
    // PSNR = 20 log10(peak/rmse): relative moves of rmse and of the (stored) peak.
    let db = 20.0 / std::f64::consts::LN_10;
    let psnr_move = db * (rms_move / orig.overall.rmse + F32_HALF_ULP);

    for tool in ["idiff", "oiiotool"] {
        let Some(o) = oiio_or_skip(tool, &pa, &pb) else {
            continue;
        };
        let rows: [(&str, Option<Printed>, f64, f64, f64); 4] = [
            (
                "RMSE",
                o.rms_error,
                stored.overall.rmse,
                orig.overall.rmse,
                rms_move,
            ),
            (
                "PSNR",
                o.psnr,
                stored.psnr(peak),
                orig.psnr(oiio_peak(&a, &b)),
                psnr_move,
            ),
            (
                "MAE",
                o.mean_error,
                stored.overall.mae,
                orig.overall.mae,
                mae_move,
            ),
            (
                "max",
                o.max_error,
                stored.overall.max_abs,
                orig.overall.max_abs,
                max_move,
            ),
        ];
        for (name, theirs, ours_stored, ours_orig, storage) in rows {
            let t = theirs.unwrap_or_else(|| panic!("{tool} printed no {name}"));
            let d_stored = (t.value - ours_stored).abs();
            let d_orig = (t.value - ours_orig).abs();
            println!(
                "{tool:8} {name:4}: theirs {} (±{:.1e} printed), ours on stored f32 {ours_stored:.10} (|diff| {d_stored:.2e}), \
                 ours on f64 originals {ours_orig:.10} (|diff| {d_orig:.2e}, storage bound {storage:.2e})",
                t.value, t.half_ulp
            );
            assert!(
                agrees(t, ours_stored),
                "{tool} {name}: {} vs ours {ours_stored}",
                t.value
            );
            let tol = t.half_ulp + ours_orig.abs() * f32::EPSILON as f64 + storage;
            assert!(
                d_orig <= tol,
                "{tool} {name}: {} vs ours on originals {ours_orig} (tolerance {tol:e})",
                t.value
            );
        }
    }
}

#[test]
fn identical_images_and_the_report() {
    let (a, b) = pair();
    let dir = scratch();
    let (pa, pb, pse) = (
        dir.join("ra.exr"),
        dir.join("rb.exr"),
        dir.join("ra.stderr.exr"),
    );
    write_exr(&pa, &a).unwrap();
    write_exr(&pb, &b).unwrap();
    write_exr(
        &pse,
        &Image {
            width: a.width,
            height: a.height,
            data: vec![[0.06; 3]; a.data.len()],
        },
    )
    .unwrap();
    let report = compare::report(&Comparison {
        a: pa.clone(),
        b: pb.clone(),
        blocks: 8,
        a_stderr: Some(pse),
        b_stderr: None,
    })
    .unwrap();
    println!("{report}");
    assert!(
        report.contains("RMSE") && report.contains("z-scores"),
        "{report}"
    );
    assert!(!report.contains("DIFFER"), "{report}");
    if let Some(o) = oiio_or_skip("idiff", &pa, &pa) {
        assert!(o.identical, "{o:?}");
    }
}

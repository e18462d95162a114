//! What the techniques study runs: the tallied and compared configurations and their size at a
//! scale.

use crate::runs::RunSpec;
use crate::study::output::{film, stem};
use crate::study::Scale;
use std::path::{Path, PathBuf};

pub const NAME: &str = "techniques";

/// Items timed: one in `EVERY` (see `lt_integrators::tally`).
pub const EVERY: u64 = 16;

/// (label, integrator, parameters) of one configuration.
pub type Config = (
    &'static str,
    &'static str,
    &'static [(&'static str, &'static str)],
);

/// The integrators whose techniques are tallied.
pub const TALLIED: [Config; 3] = [
    ("bdpt", "bdpt", &[]),
    ("lvc-bdpt N=1", "lvc-bdpt", &[("connections", "1")]),
    ("vcm", "vcm", &[]),
];

/// The configurations of the inefficiency table: bdpt, the light-vertex cache at several N, vcm
/// with and without correlation-aware MIS, efficiency-aware MIS (`eamis`) and every fixed
/// configuration its choice ranges over (rendered by `eamis fixed=…`: the same code without the
/// pilot, so a gap between the choice and the best fixed one is the pilot's cost or a wrong
/// choice).
pub const COMPARED: &[Config] = &[
    ("bdpt", "bdpt", &[]),
    ("lvc-bdpt N=1", "lvc-bdpt", &[("connections", "1")]),
    ("lvc-bdpt N=4", "lvc-bdpt", &[("connections", "4")]),
    ("lvc-bdpt N=16", "lvc-bdpt", &[("connections", "16")]),
    ("vcm", "vcm", &[]),
    (
        "vcm correlation-aware",
        "vcm",
        &[("correlation_aware", "true")],
    ),
    ("eamis", "eamis", &[]),
    (
        "eamis fixed m0.25_vc1_merge",
        "eamis",
        &[("fixed", "m0.25_vc1_merge")],
    ),
    (
        "eamis fixed m0.25_vc1_nomerge",
        "eamis",
        &[("fixed", "m0.25_vc1_nomerge")],
    ),
    (
        "eamis fixed m0.25_vc0_merge",
        "eamis",
        &[("fixed", "m0.25_vc0_merge")],
    ),
    (
        "eamis fixed m0.25_vc0_nomerge",
        "eamis",
        &[("fixed", "m0.25_vc0_nomerge")],
    ),
    (
        "eamis fixed m0.5_vc1_merge",
        "eamis",
        &[("fixed", "m0.5_vc1_merge")],
    ),
    (
        "eamis fixed m0.5_vc1_nomerge",
        "eamis",
        &[("fixed", "m0.5_vc1_nomerge")],
    ),
    (
        "eamis fixed m0.5_vc0_merge",
        "eamis",
        &[("fixed", "m0.5_vc0_merge")],
    ),
    (
        "eamis fixed m0.5_vc0_nomerge",
        "eamis",
        &[("fixed", "m0.5_vc0_nomerge")],
    ),
    (
        "eamis fixed m1_vc1_merge",
        "eamis",
        &[("fixed", "m1_vc1_merge")],
    ),
    (
        "eamis fixed m1_vc1_nomerge",
        "eamis",
        &[("fixed", "m1_vc1_nomerge")],
    ),
    (
        "eamis fixed m1_vc0_merge",
        "eamis",
        &[("fixed", "m1_vc0_merge")],
    ),
    (
        "eamis fixed m1_vc0_nomerge",
        "eamis",
        &[("fixed", "m1_vc0_nomerge")],
    ),
    (
        "eamis fixed m2_vc1_merge",
        "eamis",
        &[("fixed", "m2_vc1_merge")],
    ),
    (
        "eamis fixed m2_vc1_nomerge",
        "eamis",
        &[("fixed", "m2_vc1_nomerge")],
    ),
    (
        "eamis fixed m2_vc0_merge",
        "eamis",
        &[("fixed", "m2_vc0_merge")],
    ),
    (
        "eamis fixed m2_vc0_nomerge",
        "eamis",
        &[("fixed", "m2_vc0_nomerge")],
    ),
];

/// The prefix of the fixed configurations' labels in `COMPARED`.
pub(super) const FIXED_PREFIX: &str = "eamis fixed ";

/// How big the study is at a scale (the scale's own fields are read, never changed).
#[derive(Clone, Debug)]
pub struct StudySize {
    pub width: u32,
    pub runs: u32,
    pub passes: u32,
    pub scenes: Vec<PathBuf>,
    /// The scale with this film, for its references.
    pub scale: Scale,
}

pub fn size(scale: &Scale) -> StudySize {
    let dir = scale
        .focus_scene
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    let named = |names: &[&str]| -> Vec<PathBuf> {
        names
            .iter()
            .map(|n| dir.join(format!("{n}.toml")))
            .filter(|p| p.is_file())
            .collect()
    };
    let (width, runs, passes, scenes) = match scale.name {
        "test" => (16, 4, 4, named(&["cornell-box"])),
        // Bitterli's veach-bidir loads only with `-D integrator=path`: it is the `bitterli`
        // scale's (`lt study techniques --scale bitterli -D integrator=path`, into
        // results/techniques-bitterli/; study renders apply `-D` to XML scenes only).
        "bitterli" => (
            128,
            4,
            8,
            scale
                .scenes
                .iter()
                .filter(|p| stem(p) == "veach-bidir")
                .cloned()
                .collect(),
        ),
        _ => (
            128,
            4,
            8,
            named(&["cornell-box", "veach-door", "caustic-sds"]),
        ),
    };
    StudySize {
        width,
        runs,
        passes,
        scenes,
        scale: Scale {
            width,
            ..scale.clone()
        },
    }
}

pub(super) fn spec(
    size: &StudySize,
    scene: &Path,
    integrator: &str,
    params: &[(&str, &str)],
    seed: u64,
) -> RunSpec {
    let mut s = RunSpec::new(scene, integrator, seed, size.passes)
        .resolution(film(&size.scale, scene).ok());
    for (k, v) in params {
        s = s.param(k, v);
    }
    s
}

/// The references the study asks for; its runs (plain and tallied, on one thread, in one
/// entry per seed) are entries of their own, which `lt plan` does not list.
pub fn specs(scale: &Scale) -> Vec<RunSpec> {
    let size = size(scale);
    size.scenes
        .iter()
        .filter_map(|scene| crate::study::reference::spec(&size.scale, scene, None).ok())
        .collect()
}

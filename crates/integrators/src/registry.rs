//! The one table from integrator names to constructors (the CLI, the tests and the experiments
//! all use it). Tests that loop over `INTEGRATORS` cover a new integrator without new test code.

use crate::bidirectional::bdpt::{Bdpt, BdptParams};
use crate::bidirectional::lvc_bdpt::{LvcBdpt, LvcParams};
use crate::metropolis::mmlt::Mmlt;
use crate::metropolis::pssmlt::Pssmlt;
use crate::params::{IntegratorParams, ParamReader};
use crate::photon::pm::{Pm, PmParams};
use crate::photon::ppm::Ppm;
use crate::photon::sppm::Sppm;
use crate::unidirectional::light::{LightParams, LightTracer};
use crate::unidirectional::pt_bsdf::{PtBsdf, PtBsdfParams};
use crate::upbp::Upbp;
use crate::vcm::bpm::Bpm;
use crate::vcm::eamis::Eamis;
use crate::vcm::Vcm;
use crate::volume_density::bb1d::Bb1d;
use crate::volume_density::bp2d::Bp2d;
use crate::volume_density::pb2d::Pb2d;
use crate::volume_density::pp3d::Pp3d;
use crate::{Estimator, Kind};
use lt_core::Scene;

type Constructor = fn(&Scene, &ParamReader) -> Result<Estimator, String>;

/// What the registry knows of one integrator.
pub struct IntegratorInfo {
    pub name: &'static str,
    /// One line for `lt list`.
    pub about: &'static str,
    /// The integrator's source file, whose opening table documents its keys.
    pub source: &'static str,
    /// Unbiased or consistent: where the error bars of its images come from.
    pub kind: Kind,
    /// Which MIS weights it applies, and so which checker of `lt mis-check` holds them to the
    /// path-space oracle.
    pub weights: Weights,
    /// Its density-estimation radius, if any: what the studies of bias against N need to know.
    pub radius: Radius,
    pub make: Constructor,
}

/// An integrator's gather radius and how it changes with the pass count N.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Radius {
    /// No density estimation (the unbiased integrators).
    None,
    /// One radius for the whole run (pm): a bias no number of passes removes.
    Fixed,
    /// Knaus & Zwicker's global schedule r²ᵢ = r²₁ Π_{j<i}(j+α)/(j+1) by default (ppm, sppm;
    /// `radius_update` offers the others).
    KnausZwicker,
    /// The pure power law rᵢ = r₁ i^((α−1)/2) (vcm, bpm: Georgiev et al. 2012, SmallVCM).
    Power,
    /// rᵢ = r₁ i^((α−1)/d) for a kernel of dimension d (the volumetric estimators:
    /// `volume_density::schedule`).
    Dimension(u32),
}

impl Radius {
    /// r²ᵢ / r²₁ at pass i (1-based) with reduction α; `None` without a radius.
    pub fn scale2(self, i: u32, alpha: f64) -> Option<f64> {
        match self {
            Radius::None => None,
            Radius::Fixed => Some(1.0),
            Radius::KnausZwicker => Some(crate::density::radius::global_scale2(i, alpha)),
            Radius::Power => Some(crate::density::radius::power_scale2(i, alpha)),
            Radius::Dimension(d) => {
                Some(crate::volume_density::schedule::radius_scale(i, alpha, d).powi(2))
            }
        }
    }
}

impl IntegratorInfo {
    /// Whether the integrator reads `key` (its source's key table, which the test below holds
    /// to what it reads).
    pub fn takes(&self, key: &str) -> bool {
        crate::params::documented_keys(self.source)
            .iter()
            .any(|(k, _)| k == key)
    }
}

/// The MIS weights an integrator applies to the paths it completes (through its `Recorder`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Weights {
    /// None: each path comes from one technique (pt-bsdf, light tracing, the photon family).
    None,
    /// pt's: BSDF sampling against next-event estimation.
    PathTracing,
    /// bdpt's: every connection technique (s, t).
    Connections,
    /// vcm's (`connections` true) or bpm's (false): merging, with or without connections, under
    /// one recursive MIS (`connect_merge`).
    ConnectMerge { connections: bool },
    /// lvc-bdpt's: bdpt's techniques, connections counted N / L̄ times (`lvc_bdpt`).
    VertexCache,
    /// upbp's: bdpt's connections and the volumetric and surface merges under one MIS from the
    /// full path's densities (`upbp::weights`; the oracle `lt_core::path::volume_merging`).
    Volumetric,
    /// eamis's: vcm's full-path weights with the counts its pilot chose (`eamis`); `lt mis-check`
    /// holds those weights through vcm with the same counts (`vertex_connections`).
    EfficiencyAware,
}

pub const INTEGRATORS: &[IntegratorInfo] = &[
    IntegratorInfo {
        name: "pt",
        about: "path tracing with next-event estimation and MIS (power heuristic)",
        kind: Kind::Unbiased,
        weights: Weights::PathTracing,
        source: include_str!("unidirectional/pt.rs"),
        radius: Radius::None,
        make: crate::unidirectional::pt_lanes::make,
    },
    IntegratorInfo {
        name: "pt-bsdf",
        about: "path tracing by BSDF sampling only (the cross-check of pt)",
        kind: Kind::Unbiased,
        weights: Weights::None,
        source: include_str!("unidirectional/pt_bsdf.rs"),
        radius: Radius::None,
        make: |s, r| {
            Ok(Estimator::Unbiased(Box::new(PtBsdf {
                params: PtBsdfParams::read(s, r)?,
            })))
        },
    },
    IntegratorInfo {
        name: "light",
        about: "light tracing: light subpaths splatted to the camera at every vertex",
        kind: Kind::Unbiased,
        weights: Weights::None,
        source: include_str!("unidirectional/light.rs"),
        radius: Radius::None,
        make: |s, r| {
            Ok(Estimator::Unbiased(Box::new(LightTracer {
                params: LightParams::read(s, r)?,
            })))
        },
    },
    IntegratorInfo {
        name: "bdpt",
        about: "bidirectional path tracing: every (s,t) strategy under MIS (power heuristic)",
        kind: Kind::Unbiased,
        weights: Weights::Connections,
        source: include_str!("bidirectional/bdpt.rs"),
        radius: Radius::None,
        make: |s, r| {
            Ok(Estimator::Unbiased(Box::new(Bdpt {
                params: BdptParams::read(s, r)?,
            })))
        },
    },
    IntegratorInfo {
        name: "lvc-bdpt",
        about: "bdpt with a light-vertex cache: each camera vertex joins N random cached light vertices",
        kind: Kind::Unbiased,
        weights: Weights::VertexCache,
        source: include_str!("bidirectional/lvc_bdpt.rs"),
        radius: Radius::None,
        make: |s, r| {
            let params = LvcParams::read(s, r)?;
            Ok(Estimator::Unbiased(Box::new(LvcBdpt::new(s, params))))
        },
    },
    IntegratorInfo {
        name: "pm",
        about: "photon mapping: one photon map per run, gathered at the first non-delta vertex",
        kind: Kind::Consistent,
        weights: Weights::None,
        source: include_str!("photon/pm.rs"),
        radius: Radius::Fixed,
        make: |s, r| {
            Ok(Estimator::Consistent(Box::new(Pm {
                params: PmParams::read(s, r)?,
            })))
        },
    },
    IntegratorInfo {
        name: "ppm",
        about: "progressive photon mapping: fixed visible points gathering each photon pass",
        kind: Kind::Consistent,
        weights: Weights::None,
        source: include_str!("photon/ppm.rs"),
        radius: Radius::KnausZwicker,
        make: |s, r| Ok(Estimator::Consistent(Box::new(Ppm::read(s, r)?))),
    },
    IntegratorInfo {
        name: "sppm",
        about: "stochastic progressive photon mapping: new visible points every pass",
        kind: Kind::Consistent,
        weights: Weights::None,
        source: include_str!("photon/sppm.rs"),
        radius: Radius::KnausZwicker,
        make: |s, r| Ok(Estimator::Consistent(Box::new(Sppm::read(s, r)?))),
    },
    IntegratorInfo {
        name: "bpm",
        about: "bidirectional photon mapping: merging at every camera vertex under MIS",
        kind: Kind::Consistent,
        weights: Weights::ConnectMerge { connections: false },
        source: include_str!("vcm/bpm.rs"),
        radius: Radius::Power,
        make: |s, r| Ok(Estimator::Consistent(Box::new(Bpm::read(s, r)?))),
    },
    IntegratorInfo {
        name: "vcm",
        about: "vertex connection and merging: bdpt's connections and merging under one MIS",
        kind: Kind::Consistent,
        weights: Weights::ConnectMerge { connections: true },
        source: include_str!("vcm/mod.rs"),
        radius: Radius::Power,
        make: |s, r| Ok(Estimator::Consistent(Box::new(Vcm::read(s, r)?))),
    },
    IntegratorInfo {
        name: "eamis",
        about: "efficiency-aware MIS over vcm's techniques: a pilot chooses light paths, \
                vertex connections and per-pixel merging",
        kind: Kind::Consistent,
        weights: Weights::EfficiencyAware,
        source: include_str!("vcm/eamis/mod.rs"),
        radius: Radius::Power,
        make: |s, r| Ok(Estimator::Consistent(Box::new(Eamis::read(s, r)?))),
    },
    IntegratorInfo {
        name: "pp3d",
        about: "volumetric photon mapping: photon points gathered at the first medium vertex \
                (3-D kernel), pt elsewhere",
        kind: Kind::Consistent,
        weights: Weights::None,
        source: include_str!("volume_density/pp3d.rs"),
        radius: Radius::Dimension(3),
        make: |s, r| Ok(Estimator::Consistent(Box::new(Pp3d::read(s, r)?))),
    },
    IntegratorInfo {
        name: "pb2d",
        about: "beam radiance estimate: photon points gathered along camera beams in media \
                (2-D kernel), pt elsewhere",
        kind: Kind::Consistent,
        weights: Weights::None,
        source: include_str!("volume_density/pb2d.rs"),
        radius: Radius::Dimension(2),
        make: |s, r| Ok(Estimator::Consistent(Box::new(Pb2d::read(s, r)?))),
    },
    IntegratorInfo {
        name: "bb1d",
        about: "photon beams: light subpaths' flights through media gathered along camera beams \
                (1-D kernel), pt elsewhere",
        kind: Kind::Consistent,
        weights: Weights::None,
        source: include_str!("volume_density/bb1d.rs"),
        radius: Radius::Dimension(1),
        make: |s, r| Ok(Estimator::Consistent(Box::new(Bb1d::read(s, r)?))),
    },
    IntegratorInfo {
        name: "bp2d",
        about: "photon beams gathered at the first medium vertex (2-D kernel), pt elsewhere",
        kind: Kind::Consistent,
        weights: Weights::None,
        source: include_str!("volume_density/bp2d.rs"),
        radius: Radius::Dimension(2),
        make: |s, r| Ok(Estimator::Consistent(Box::new(Bp2d::read(s, r)?))),
    },
    IntegratorInfo {
        name: "upbp",
        about: "unified points, beams and paths: bdpt's connections, PP3D, PB2D, BB1D and \
                (opt-in, `techniques=all`) vcm's surface merges and BP2D under one MIS; short \
                or long photon beams, SmallUPBP's compatible/previous modes",
        kind: Kind::Consistent,
        weights: Weights::Volumetric,
        source: include_str!("upbp/mod.rs"),
        radius: Radius::Dimension(2),
        make: |s, r| Ok(Estimator::Consistent(Box::new(Upbp::read(s, r)?))),
    },
    IntegratorInfo {
        name: "pssmlt",
        about: "primary-sample-space Metropolis (Kelemen) over bdpt's or pt's samples; \
                error bars from independent runs",
        kind: Kind::Consistent,
        weights: Weights::None,
        source: include_str!("metropolis/pssmlt.rs"),
        radius: Radius::None,
        make: |s, r| Ok(Estimator::Consistent(Box::new(Pssmlt::read(s, r)?))),
    },
    IntegratorInfo {
        name: "mmlt",
        about: "multiplexed Metropolis: one chain set per path length, one bdpt strategy per state",
        kind: Kind::Consistent,
        weights: Weights::None,
        source: include_str!("metropolis/mmlt.rs"),
        radius: Radius::None,
        make: |s, r| Ok(Estimator::Consistent(Box::new(Mmlt::read(s, r)?))),
    },
];

/// The names of the integrators whose weights `w` describes, in table order.
pub fn with_weights(w: impl Fn(Weights) -> bool) -> impl Iterator<Item = &'static str> {
    INTEGRATORS
        .iter()
        .filter(move |i| w(i.weights))
        .map(|i| i.name)
}

/// The registered names, in table order.
pub fn names() -> impl Iterator<Item = &'static str> {
    INTEGRATORS.iter().map(|i| i.name)
}

pub fn find(name: &str) -> Result<&'static IntegratorInfo, String> {
    INTEGRATORS.iter().find(|i| i.name == name).ok_or_else(|| {
        let known: Vec<&str> = names().collect();
        format!("unknown integrator '{name}' (known: {})", known.join(", "))
    })
}

/// Builds `name` with `params`; refuses keys the integrator does not take.
pub fn make_integrator(
    name: &str,
    scene: &Scene,
    params: &IntegratorParams,
) -> Result<Estimator, String> {
    let info = find(name)?;
    refuse_media(info.name, scene)?;
    let reader = ParamReader::new(info.name, params);
    let integrator = (info.make)(scene, &reader)?;
    reader.finish()?;
    Ok(integrator)
}

/// The integrators that walk participating media (`media/`); every other refuses a scene with
/// media rather than render it silently wrong (issue 43, item 4).
pub const HANDLES_MEDIA: &[&str] = &[
    "pt", "pt-bsdf", "light", "bdpt", "pp3d", "pb2d", "bb1d", "bp2d", "upbp",
];

/// The volumetric density estimators: they store photons and beams only in media and walk `pt`'s
/// camera path elsewhere, so on a scene without media their image is `pt`'s bit for bit. The
/// surface loops of the tests hold them to exactly that (`lt_tests::assert_same_image_as_pt`)
/// instead of rendering a consistent estimator's independent runs of what is `pt`.
pub const PT_WITHOUT_MEDIA: &[&str] = &["pp3d", "pb2d", "bb1d", "bp2d"];

/// One clear line for an integrator that cannot render the scene's media.
fn refuse_media(name: &str, scene: &Scene) -> Result<(), String> {
    if !scene.has_media || HANDLES_MEDIA.contains(&name) {
        return Ok(());
    }
    Err(format!(
        "integrator {name} does not handle participating media yet; the scene has {} media",
        scene.media.len()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::documented_keys;
    use lt_core::camera::{Camera, FovAxis};
    use lt_core::scene::{RenderSettings, SceneBuilder};
    use lt_core::Vec3;

    fn empty_scene() -> Scene {
        let cam = Camera::look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0, FovAxis::X, 4, 4).unwrap();
        SceneBuilder::new(cam, RenderSettings::default()).build()
    }

    /// A value of a documented type: numbers, or each of the listed alternatives.
    fn sample_values(ty: &str) -> Vec<String> {
        match ty {
            "u32" | "u64" => vec!["3".into()],
            "f64" | "f32" => vec!["0.5".into()],
            alts => alts.split('/').map(|a| a.trim().to_string()).collect(),
        }
    }

    #[test]
    fn every_documented_key_is_read_and_every_read_key_is_documented() {
        let scene = empty_scene();
        for info in INTEGRATORS {
            let documented = documented_keys(info.source);
            assert!(!documented.is_empty(), "{}: no key table", info.name);
            let none = IntegratorParams::default();
            let reader = ParamReader::new(info.name, &none);
            (info.make)(&scene, &reader).unwrap();
            let mut asked = reader.asked();
            asked.sort();
            asked.dedup();
            let mut keys: Vec<&str> = documented.iter().map(|(k, _)| k.as_str()).collect();
            keys.sort();
            assert_eq!(asked, keys, "{}: keys read vs documented", info.name);
            for (key, ty) in &documented {
                for v in sample_values(ty) {
                    let p = IntegratorParams::new().with(key, &v);
                    make_integrator(info.name, &scene, &p)
                        .unwrap_or_else(|e| panic!("{} {key}={v}: {e}", info.name));
                }
                let bad = IntegratorParams::new().with(key, "not-a-value");
                assert!(
                    make_integrator(info.name, &scene, &bad).is_err(),
                    "{} accepts {key}=not-a-value",
                    info.name
                );
            }
            // A radius property exactly where the integrator takes a radius.
            assert_eq!(
                info.radius == Radius::None,
                !info.takes("radius"),
                "{}: radius property against its keys",
                info.name
            );
            let built = make_integrator(info.name, &scene, &none).unwrap();
            assert_eq!(built.kind(), info.kind, "{}: registry kind", info.name);
            assert_eq!(built.name(), info.name);
            let unknown = IntegratorParams::new().with("no_such_key", 1);
            let err = make_integrator(info.name, &scene, &unknown).err().unwrap();
            assert!(err.contains("no_such_key"), "{err}");
        }
    }
}

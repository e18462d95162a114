//! The one table from integrator names to constructors (the CLI and the experiments both use it).

use crate::pt::{Pt, PtParams};
use crate::pt_bsdf::PtBsdf;
use crate::Integrator;
use lt_core::Scene;

/// Command-line overrides; `None` falls back to the scene's `[render]` settings.
#[derive(Clone, Copy, Debug, Default)]
pub struct IntegratorParams {
    pub max_depth: Option<u32>,
    pub rr_depth: Option<u32>,
}

type Constructor = fn(&Scene, &IntegratorParams) -> Box<dyn Integrator>;

/// (name, one-line description, constructor).
pub const INTEGRATORS: &[(&str, &str, Constructor)] = &[
    (
        "pt",
        "path tracing with next-event estimation and MIS (power heuristic)",
        |s, p| {
            Box::new(Pt {
                params: pt_params(s, p),
            })
        },
    ),
    (
        "pt-bsdf",
        "path tracing by BSDF sampling only (the cross-check of pt)",
        |s, p| {
            Box::new(PtBsdf {
                params: pt_params(s, p),
            })
        },
    ),
];

fn pt_params(scene: &Scene, p: &IntegratorParams) -> PtParams {
    PtParams {
        max_depth: p.max_depth.unwrap_or(scene.settings.max_depth),
        rr_depth: p.rr_depth.unwrap_or(scene.settings.rr_depth),
    }
}

pub fn make_integrator(
    name: &str,
    scene: &Scene,
    params: &IntegratorParams,
) -> Result<Box<dyn Integrator>, String> {
    INTEGRATORS
        .iter()
        .find(|(n, _, _)| *n == name)
        .map(|(_, _, make)| make(scene, params))
        .ok_or_else(|| {
            let known: Vec<&str> = INTEGRATORS.iter().map(|(n, _, _)| *n).collect();
            format!("unknown integrator '{name}' (known: {})", known.join(", "))
        })
}

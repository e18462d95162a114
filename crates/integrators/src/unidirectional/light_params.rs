//! `light`'s parameters and its splat chunk, read by the scalar tracer (`light`) and the
//! lane-parallel one (`light_lanes`) alike: a module of its own so that neither imports the other.

use crate::params::ParamReader;
use crate::subpath::walk::WalkLimits;
use lt_core::Scene;

/// Light subpaths walked together by `lanes=8` (`light_lanes`): one packet of the ray core.
pub const LANES: usize = lt_core::geometry::packet::PACKET;

#[derive(Clone, Copy, Debug)]
pub struct LightParams {
    pub max_depth: u32,
    pub rr_depth: u32,
    /// `None`: one light subpath per pixel.
    pub light_paths: Option<u64>,
    /// Walk eight subpaths at a time (`unidirectional::light_lanes`).
    pub lanes: bool,
}

impl LightParams {
    pub fn read(scene: &Scene, r: &ParamReader) -> Result<LightParams, String> {
        if scene.camera.is_delta_direction() {
            return Err(
                "light tracing cannot see through an orthographic camera (a delta in \
                        direction: no connection reaches it); use pt or bdpt"
                    .into(),
            );
        }
        let lanes = r
            .get_with("lanes", |v| match v {
                "1" => Ok(false),
                "8" => Ok(true),
                _ => Err(format!("'{v}' is not a lane width (known: 1, {LANES})")),
            })?
            .unwrap_or(false);
        if lanes && scene.has_media {
            return Err(format!(
                "light: lanes={LANES} does not handle participating media yet; the scene has {} \
                 media (lanes=1 renders it)",
                scene.media.len()
            ));
        }
        Ok(LightParams {
            max_depth: r.max_depth(scene)?,
            rr_depth: r.rr_depth(scene)?,
            light_paths: r.light_paths()?,
            lanes,
        })
    }

    /// The subpaths' limits: s light vertices and the pinhole make a path of s segments.
    pub fn walk_limits(&self) -> WalkLimits {
        WalkLimits {
            max_vertices: self.max_depth as usize,
            rr_depth: self.rr_depth,
        }
    }
}

/// Light subpaths per splat chunk: enough to amortise the chunk's bookkeeping.
pub const CHUNK: u64 = 1024;

//! A batch's connections to the lens, splatted in the scalar order: `LightTracer::render_pass`'s
//! loop over each subpath's vertices, with `subpath::connect::connect_to_camera` (without media)
//! split at its visibility test so that the shadow rays go through the packet occlusion query
//! eight at a time.

use super::walk::Batch;
use super::LANES;
use crate::film::splat::Splats;
use crate::subpath::connect::eval_towards;
use lt_core::bsdf::TransportMode;
use lt_core::math::{Color, Vec2};
use lt_core::path::scatter::connectable;
use lt_core::path::{PathVertex, VertexKind};
use lt_core::sampling::Sampler;
use lt_core::scene::ShadowRay;
use lt_core::Scene;

/// A connection found before its visibility is known: where it lands and its splat value
/// (`CameraConnection::value`), and the shadow query that decides whether it counts.
struct Pending {
    raster: Vec2,
    value: Color,
    shadow: ShadowRay,
}

/// Every connection of the batch's subpaths, in subpath then vertex order, splatted (times
/// `scale`) where visible.
pub fn splat_batch(scene: &Scene, batch: &mut Batch, scale: f32, splats: &mut Splats) {
    let mut pending = Vec::with_capacity(LANES * 4);
    for i in 0..batch.len {
        let (sub, sampler) = (&batch.subpaths[i], &mut batch.samplers[i]);
        for y in &sub.vertices {
            if !connectable(scene, y) {
                continue;
            }
            if let Some(c) = lens_connection(scene, y, sampler) {
                pending.push(c);
            }
        }
    }
    let film = scene.camera.film();
    for group in pending.chunks(LANES) {
        let queries =
            std::array::from_fn(|k| group.get(k).map_or(ShadowRay::Known(false), |c| c.shadow));
        let visible = scene.resolve_shadow_packet(&queries);
        for (c, _) in group.iter().zip(visible).filter(|(_, v)| *v) {
            splats.add_filtered(film, c.raster, c.value * scale);
        }
    }
}

/// `connect_to_camera_in::<false>` up to its visibility test: the lens point (drawn from
/// `sampler`), the value β · f_cos · We · cos θ_c / d² (Le / pdf_fwd at x0 on a light), and the
/// shadow query of `connection_visible`. `None` where the scalar function returns `None` before
/// tracing.
fn lens_connection(scene: &Scene, y: &PathVertex, sampler: &mut Sampler) -> Option<Pending> {
    let cam = &scene.camera;
    let (lens, value) = match y.kind {
        VertexKind::Light { light, infinite } => {
            let l = &scene.lights[light as usize];
            if infinite {
                let lens = cam.connect_direction(y.p, sampler)?;
                (lens, l.escaped(y.p) / y.pdf_fwd)
            } else if !y.on_surface() {
                return None;
            } else {
                let lens = cam.connect(y.p, sampler)?;
                let dir = lens.dir;
                let le = l.emitted(y.ng, -dir, y.uv) * y.ng.dot(dir).abs();
                (lens, le / y.pdf_fwd)
            }
        }
        VertexKind::Surface { .. } | VertexKind::Medium { .. } => {
            let lens = cam.connect(y.p, sampler)?;
            let ev = eval_towards(scene, y, -lens.dir, TransportMode::Importance)?;
            (lens, y.beta * ev.f_cos)
        }
        VertexKind::Camera => return None,
    };
    if value == Color::ZERO {
        return None;
    }
    let camera = PathVertex::camera_at(cam, lens.origin, Color::ONE);
    Some(Pending {
        raster: lens.raster,
        value: value * (lens.importance * lens.cos_lens / lens.distance_squared),
        shadow: scene.connection_shadow(y, &camera),
    })
}

//! A chunk's connections to the lens, splatted in the scalar order: `LightTracer::render_pass`'s
//! loop over each subpath's vertices, with `subpath::connect::connect_to_camera` (without media)
//! split at its visibility test so that the shadow rays go through the packet occlusion query
//! eight at a time, whichever subpaths they come from.

use super::LANES;
use crate::film::splat::Splats;
use crate::subpath::connect::eval_towards;
use crate::subpath::walk::Subpath;
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

/// A chunk's connections: found as each subpath's walk ends (`add_subpath`), splatted at the end
/// in the scalar order (`splat`).
pub struct Connections {
    pending: Vec<Pending>,
    /// Per subpath of the chunk (index from the chunk's first), its connections in `pending`:
    /// (first, count).
    of_item: Vec<(u32, u32)>,
    first_item: u64,
}

impl Connections {
    /// Room for `per_chunk` connections before the first reallocation (each chunk starts a new
    /// one: `splat_pass_with` makes its scratch per chunk).
    pub fn with_capacity(per_chunk: usize) -> Connections {
        Connections {
            pending: Vec::with_capacity(per_chunk),
            of_item: Vec::new(),
            first_item: 0,
        }
    }

    /// Forgets the last chunk; the next holds `count` subpaths from `first_item` on.
    pub fn clear(&mut self, first_item: u64, count: usize) {
        self.pending.clear();
        self.of_item.clear();
        self.of_item.resize(count, (0, 0));
        self.first_item = first_item;
    }

    /// `LightTracer::render_pass`'s loop over one subpath's vertices up to the shadow rays: each
    /// connectable vertex joined to the lens (drawing from the subpath's own `sampler`).
    pub fn add_subpath(&mut self, scene: &Scene, item: u64, sub: &Subpath, sampler: &mut Sampler) {
        let first = self.pending.len();
        for y in &sub.vertices {
            if !connectable(scene, y) {
                continue;
            }
            if let Some(c) = lens_connection(scene, y, sampler) {
                self.pending.push(c);
            }
        }
        let count = self.pending.len() - first;
        self.of_item[(item - self.first_item) as usize] = (first as u32, count as u32);
    }

    /// The chunk's shadow rays, `LANES` at a time in the order they were found, then every
    /// visible connection splatted (times `scale`) subpath by subpath, vertex by vertex: the
    /// scalar order.
    pub fn splat(&mut self, scene: &Scene, scale: f32, splats: &mut Splats) {
        let mut visible = vec![false; self.pending.len()];
        for (group, vis) in self.pending.chunks(LANES).zip(visible.chunks_mut(LANES)) {
            let queries =
                std::array::from_fn(|k| group.get(k).map_or(ShadowRay::Known(false), |c| c.shadow));
            let answers = scene.resolve_shadow_packet(&queries);
            vis.copy_from_slice(&answers[..vis.len()]);
        }
        let film = scene.camera.film();
        for &(first, count) in &self.of_item {
            let range = first as usize..(first + count) as usize;
            for (c, _) in self.pending[range.clone()]
                .iter()
                .zip(&visible[range])
                .filter(|(_, v)| **v)
            {
                splats.add_filtered(film, c.raster, c.value * scale);
            }
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

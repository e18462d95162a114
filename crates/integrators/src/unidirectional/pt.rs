//! `pt` — unidirectional path tracing with next-event estimation, combined with BSDF sampling by
//! multiple importance sampling (Veach & Guibas 1995).
//!
//! At every non-delta vertex one light is chosen by power and sampled towards the vertex (NEE);
//! the BSDF-sampled continuation may hit an emitter too. Both techniques can produce the same path,
//! so each contribution is weighted by the heuristic over their solid-angle pdfs at the vertex.
//! Delta lights (point, directional) and delta BSDF lobes (mirror, glass) are reached by one
//! technique only and get weight one: a delta light's `pdf_li` is 0, so BSDF sampling never
//! finds it, and its `sample_li` reports `delta`. `techniques = light` or `bsdf` keeps one of the
//! two (weight one where it is the only one left): Veach's MIS comparison on `veach-mis` is four
//! runs of this integrator.
//!
//! | key | type | default | meaning |
//! |---|---|---|---|
//! | `max_depth` | u32 | scene `[render] max_depth` (8) | longest path in segments, camera ray included |
//! | `rr_depth` | u32 | scene `[render] rr_depth` (5) | Russian roulette from this many segments on |
//! | `mis` | power/balance | power | heuristic combining NEE and BSDF sampling |
//! | `techniques` | both/light/bsdf | both | NEE and BSDF sampling, NEE only, or BSDF sampling only |
//! | `lanes` | 1/8 | 1 | paths walked together: 8 runs `pt_lanes` (same image bit for bit, no media) |

use crate::film::pixel::pixel_pass;
use crate::params::ParamReader;
use crate::record::{Completed, NoRecord, Recorder};
use crate::subpath::walk::{continue_path, escaped_radiance, WalkPoint, WalkRules};
use crate::Integrator;
use lt_core::bsdf::TransportMode;
use lt_core::math::Color;
use lt_core::path::{Heuristic, PathVertex};
use lt_core::sampling::Sampler;
use lt_core::{Scene, Vec2};
use lt_estimators::Image;

/// Which of the two techniques run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Techniques {
    Both,
    /// Next-event estimation only (emitters hit by BSDF samples count only after delta bounces).
    Light,
    /// BSDF sampling only (`pt-bsdf` without sharing its code).
    Bsdf,
}

impl Techniques {
    fn parse(s: &str) -> Result<Techniques, String> {
        match s {
            "both" => Ok(Techniques::Both),
            "light" => Ok(Techniques::Light),
            "bsdf" => Ok(Techniques::Bsdf),
            _ => Err(format!(
                "unknown techniques '{s}' (known: both, light, bsdf)"
            )),
        }
    }
}

/// Where NEE reports the path it completes when a recorder listens (`lt mis-check`): the
/// recorder, the camera subpath so far and the pixel.
struct Report<'a, R> {
    rec: &'a mut R,
    camera_path: &'a [PathVertex],
    raster: Vec2,
}

#[derive(Clone, Copy, Debug)]
pub struct PtParams {
    pub max_depth: u32,
    pub rr_depth: u32,
    pub mis: Heuristic,
    pub techniques: Techniques,
}

impl PtParams {
    pub fn read(scene: &Scene, r: &ParamReader) -> Result<PtParams, String> {
        let mis = r
            .get_with("mis", |v| match Heuristic::parse(v)? {
                Heuristic::Uniform => Err("pt takes power or balance".to_string()),
                h => Ok(h),
            })?
            .unwrap_or(Heuristic::Power);
        Ok(PtParams {
            max_depth: r.max_depth(scene)?,
            rr_depth: r.rr_depth(scene)?,
            mis,
            techniques: r
                .get_with("techniques", Techniques::parse)?
                .unwrap_or(Techniques::Both),
        })
    }
}

pub struct Pt {
    pub params: PtParams,
}

impl Pt {
    /// The weight of technique a against b (solid-angle densities at one vertex).
    #[inline]
    pub(crate) fn weight(&self, a: f32, b: f32) -> f32 {
        match self.params.mis {
            Heuristic::Balance => {
                if a.is_infinite() {
                    1.0
                } else if a + b > 0.0 {
                    a / (a + b)
                } else {
                    0.0
                }
            }
            _ => lt_core::sampling::power_heuristic(a, b),
        }
    }

    /// The weight of a BSDF-sampled emitter hit, with `light_pdf` the NEE density of the same
    /// direction; `(this, the NEE weight of the same path)`.
    #[inline]
    pub(crate) fn hit_weights(
        &self,
        prev_delta: bool,
        prev_pdf_w: f32,
        light_pdf: f32,
    ) -> (f32, f32) {
        match self.params.techniques {
            _ if prev_delta => (1.0, 0.0),
            Techniques::Both => (
                self.weight(prev_pdf_w, light_pdf),
                self.weight(light_pdf, prev_pdf_w),
            ),
            Techniques::Light => (0.0, 1.0),
            Techniques::Bsdf => (1.0, 0.0),
        }
    }

    /// Next-event estimation at `at`: one light chosen by power, weighted against the BSDF.
    fn direct_light<R: Recorder>(
        &self,
        scene: &Scene,
        at: &WalkPoint,
        sampler: &mut Sampler,
        report: Report<'_, R>,
    ) -> Color {
        let WalkPoint { hit, sf, wo } = *at;
        let Report {
            rec,
            camera_path,
            raster,
        } = report;
        let Some((li, pmf, _)) = scene.light_sampler.sample(sampler.next_f32()) else {
            return Color::ZERO;
        };
        let u = sampler.next_2d();
        let light = &scene.lights[li];
        let Some(ls) = light.sample_li(hit.p, u) else {
            return Color::ZERO;
        };
        if ls.radiance == Color::ZERO || ls.pdf_w == 0.0 {
            return Color::ZERO;
        }
        let material = scene.material(hit.material);
        let ev = material.eval(sf, wo, ls.wi, TransportMode::Radiance);
        if ev.f_cos == Color::ZERO {
            return Color::ZERO;
        }
        if !scene.visible_light(hit, &ls) {
            return Color::ZERO;
        }
        let light_pdf = pmf * ls.pdf_w;
        let (w, w_bsdf) = if ls.delta || self.params.techniques == Techniques::Light {
            (1.0, 0.0)
        } else {
            (
                self.weight(light_pdf, ev.pdf_w),
                self.weight(ev.pdf_w, light_pdf),
            )
        };
        if R::ACTIVE {
            let from = camera_path.last().expect("the vertex NEE starts from");
            let x0 = PathVertex::light_sampled(scene, li as u32, &ls, pmf, from);
            rec.completed(Completed {
                s: 1,
                light: &[x0],
                camera: camera_path,
                weight: w as f64,
                value: from.beta * ev.f_cos * ls.radiance / light_pdf,
                raster,
                alternatives: &[(0, w_bsdf as f64)],
            });
        }
        ev.f_cos * ls.radiance * (w / light_pdf)
    }

    pub fn radiance(&self, scene: &Scene, raster: Vec2, sampler: &mut Sampler) -> Color {
        self.radiance_recorded(scene, raster, sampler, &mut NoRecord)
    }

    /// `radiance`, reporting every path it completes to `rec` (for `lt mis-check`).
    pub fn radiance_recorded<R: Recorder>(
        &self,
        scene: &Scene,
        raster: Vec2,
        sampler: &mut Sampler,
        rec: &mut R,
    ) -> Color {
        let nee = self.params.techniques != Techniques::Bsdf;
        let rules = WalkRules::camera(self.params.rr_depth);
        let mut ray = scene.camera.sample_ray(raster, sampler);
        let mut beta = Color::ONE;
        let mut l = Color::ZERO;
        // The previous vertex's BSDF pdf (solid angle) and whether it was a delta lobe; the camera
        // counts as a delta so emitters seen directly get full weight, and its pdf is only asked
        // for the recorder's vertices (no weight reads it).
        let mut prev_pdf_w = if R::ACTIVE {
            scene.camera.pdf_dir(ray.o, ray.d)
        } else {
            0.0
        };
        let mut prev_delta = true;
        let mut prev_p = ray.o;
        // The camera subpath so far, only kept for a recorder.
        let mut verts: Vec<PathVertex> = Vec::new();
        if R::ACTIVE {
            verts.push(PathVertex::camera_at(&scene.camera, ray.o, Color::ONE));
        }
        for depth in 1..=self.params.max_depth {
            let Some(hit) = scene.intersect(&ray) else {
                l += beta
                    * escaped_radiance(scene, ray.d, |i| {
                        let light_pdf = scene.light_sampler.pmf(i as usize)
                            * scene.lights[i as usize].pdf_li(prev_p, ray.d, ray.d, -ray.d);
                        let (w, w_nee) = self.hit_weights(prev_delta, prev_pdf_w, light_pdf);
                        if R::ACTIVE {
                            let x0 = PathVertex::light_escaped(i, ray.d, beta, prev_pdf_w);
                            rec.completed(Completed {
                                s: 0,
                                light: &[x0],
                                camera: &verts,
                                weight: w as f64,
                                value: beta * scene.lights[i as usize].escaped(ray.d),
                                raster,
                                alternatives: &[(1, w_nee as f64)],
                            });
                        }
                        w
                    });
                break;
            };
            let wo = -ray.d;
            if R::ACTIVE {
                let prev = *verts.last().unwrap();
                verts.push(PathVertex::surface(&hit, wo, beta, prev_pdf_w, &prev));
            }
            if let Some(li) = hit.light {
                let light = &scene.lights[li as usize];
                let le = light.emitted(hit.ng, wo, hit.uv);
                if le != Color::ZERO {
                    let light_pdf = scene.light_sampler.pmf(li as usize)
                        * light.pdf_li(prev_p, ray.d, hit.p, hit.ng);
                    let (w, w_nee) = self.hit_weights(prev_delta, prev_pdf_w, light_pdf);
                    if R::ACTIVE {
                        let n = verts.len();
                        let x0 = verts[n - 1].as_light_endpoint().unwrap();
                        rec.completed(Completed {
                            s: 0,
                            light: &[x0],
                            camera: &verts[..n - 1],
                            weight: w as f64,
                            value: beta * le,
                            raster,
                            alternatives: &[(1, w_nee as f64)],
                        });
                    }
                    l += beta * le * w;
                }
            }
            if depth == self.params.max_depth {
                break;
            }
            let sf = hit.shading_frame();
            let at = WalkPoint {
                hit: &hit,
                sf: &sf,
                wo,
            };
            if nee && !scene.material_is_delta(hit.material) {
                let report = Report {
                    rec: &mut *rec,
                    camera_path: &verts,
                    raster,
                };
                l += beta * self.direct_light(scene, &at, sampler, report);
            }
            let Some(bs) = continue_path(scene, &at, &rules, &mut beta, depth, sampler) else {
                break;
            };
            if R::ACTIVE {
                verts.last_mut().unwrap().delta = bs.delta;
            }
            prev_pdf_w = bs.pdf_w;
            prev_delta = bs.delta;
            prev_p = hit.p;
            ray = hit.spawn_ray(bs.wi);
        }
        l
    }
}

impl Integrator for Pt {
    fn name(&self) -> &'static str {
        "pt"
    }

    fn render_pass(&self, scene: &Scene, seed: u64, pass: u32) -> (Image, u64) {
        if scene.has_media {
            return pixel_pass(scene, seed, pass, |s, raster| {
                crate::media::pt::radiance(self, scene, raster, s)
            });
        }
        pixel_pass(scene, seed, pass, |s, raster| {
            self.radiance(scene, raster, s)
        })
    }
}

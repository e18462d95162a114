//! How big a study is: the film width, the independent runs, the pass counts, the scenes and
//! integrators. `quick` is a newcomer's first run (all studies in minutes on 2 cores; `lt study`
//! writes it under results/quick/, beside the committed report), `committed` is what the committed
//! report shows for convergence and the galleries, `bitterli` runs the studies on Bitterli's
//! scenes, `full` is publication scale, `test` is what the tests afford.

use std::path::{Path, PathBuf};

#[derive(Clone, Debug)]
pub struct Scale {
    pub name: &'static str,
    /// Film width in pixels; the height follows the scene's aspect ratio.
    pub width: u32,
    /// Independent runs per configuration (the error bars of every statistic).
    pub runs: usize,
    /// Largest pass count; snapshots at 1, 2, 4, … up to it.
    pub max_passes: u32,
    /// Passes of a reference render (per run, for a consistent reference).
    pub reference_passes: u32,
    /// Scenes of the convergence and equal-time studies.
    pub scenes: Vec<PathBuf>,
    /// The scene of the studies that look at one scene closely.
    pub focus_scene: PathBuf,
    /// The scene of the unbiased-vs-consistent study: sharp sun shadows, so a fixed radius's
    /// blur is a bias the runs can tell from noise.
    pub bias_scene: PathBuf,
    /// Scenes of the per-length study, and its longest max_depth.
    pub length_scenes: Vec<PathBuf>,
    pub max_length: u32,
    /// Radius-reduction exponents of the radius-shrinkage study.
    pub alphas: Vec<f64>,
    /// Independent runs of the radius-shrinkage and unbiased-vs-consistent studies (their
    /// bias² and variance come from the spread of runs alone).
    pub bias_runs: usize,
    /// Passes of the radius-shrinkage and unbiased-vs-consistent studies.
    pub progressive_passes: u32,
    /// The radius-shrinkage-plane study (ppm at frozen points on `point-plane`): independent
    /// runs, passes and photon paths per pass.
    pub plane_runs: usize,
    pub plane_passes: u32,
    pub plane_photons: u64,
    /// Repetitions of the lecture's 1-D example per N.
    pub lecture_repetitions: usize,
    pub confidence: f64,
    /// The equal-time galleries' film width, passes at equal samples and reference passes: a
    /// gallery must be wide enough to show light paths, a convergence study only needs pixels
    /// enough to average over. Equal to `width`, `max_passes`, `reference_passes` at the quick
    /// scale, where the galleries reuse the convergence study's first runs.
    pub gallery_width: u32,
    pub gallery_passes: u32,
    pub gallery_reference_passes: u32,
    /// The galleries' scenes, when not `scenes`: a 256-px gallery of every integrator costs
    /// minutes per scene, so the committed scale shows the scenes whose light paths differ most.
    pub gallery_scenes: Option<Vec<PathBuf>>,
    /// Veach's MIS comparison's scene (pt by technique), when the scale has one.
    pub veach_scene: Option<PathBuf>,
    /// Appended to every study folder's name (`convergence-bitterli`), so a scale whose results
    /// sit beside another's in one report overwrites none of them.
    pub folder_suffix: &'static str,
}

pub const ALL_ALPHAS: [f64; 6] = [0.3, 0.5, 2.0 / 3.0, 0.75, 0.9, 1.0];

/// The shipped scenes, sorted by name: every `.toml` in the folder, then the media scenes (every
/// `.xml` in its `media/` subfolder, Mitsuba XML: TOML has no media yet).
pub fn shipped_scenes(dir: &Path) -> Result<Vec<PathBuf>, String> {
    let mut v = files_with_extension(dir, "toml")?;
    if v.is_empty() {
        return Err(format!("{} holds no .toml scenes", dir.display()));
    }
    let media = dir.join("media");
    if media.is_dir() {
        v.extend(files_with_extension(&media, "xml")?);
    }
    Ok(v)
}

fn files_with_extension(dir: &Path, ext: &str) -> Result<Vec<PathBuf>, String> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("cannot list the scenes in {}: {e}", dir.display()))?
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == ext))
        .collect();
    v.sort();
    Ok(v)
}

/// The scenes every registered integrator accepts. A scene one of them refuses — `point-plane`'s
/// orthographic camera, which light tracing, bpm and vcm cannot connect to; the media scenes,
/// which only `registry::HANDLES_MEDIA` renders — belongs to the study written for it
/// (radius-shrinkage-plane; the media tests), not to the comparisons of every estimator; each
/// is named on stderr with the first refusal. A scene that does not load stays: its render
/// reports the file, place and problem.
fn every_integrator_renders(scenes: Vec<PathBuf>) -> Vec<PathBuf> {
    let params = lt_integrators::IntegratorParams::new();
    scenes
        .into_iter()
        .filter(|p| match lt_scene_io::load_scene(p) {
            Ok(scene) => {
                let refusal = lt_integrators::INTEGRATORS
                    .iter()
                    .find_map(|i| lt_integrators::make_integrator(i.name, &scene, &params).err());
                if let Some(why) = &refusal {
                    eprintln!(
                        "note: {} is left out of the studies that compare every integrator: {why}",
                        p.display()
                    );
                }
                refusal.is_none()
            }
            Err(_) => true,
        })
        .collect()
}

impl Scale {
    /// A scene file named relative to the focus scene's folder (`scenes/` when the focus scene
    /// has none): the studies' own scenes live beside it.
    pub fn scene_beside_focus(&self, relative: &str) -> PathBuf {
        self.focus_scene
            .parent()
            .map(|d| d.join(relative))
            .unwrap_or_else(|| PathBuf::from("scenes").join(relative))
    }

    pub fn named(name: &str, scenes_dir: &Path) -> Result<Scale, String> {
        let all = every_integrator_renders(shipped_scenes(scenes_dir)?);
        let scene = |n: &str| scenes_dir.join(format!("{n}.toml"));
        let base = Scale {
            name: "quick",
            width: 32,
            runs: 4,
            // 16, not 32: with twelve integrators on every shipped scene, 32 passes took the
            // quick run past five minutes on 2 cores (312 s measured 2026-12-04).
            max_passes: 16,
            reference_passes: 1024,
            scenes: all.clone(),
            focus_scene: scene("cornell-box"),
            bias_scene: scene("sun-room"),
            length_scenes: vec![
                scene("cornell-box"),
                scene("cornell-glass-light"),
                scene("caustic-sds"),
            ],
            max_length: 6,
            alphas: ALL_ALPHAS.to_vec(),
            bias_runs: 8,
            progressive_passes: 64,
            plane_runs: 16,
            plane_passes: 256,
            plane_photons: 1000,
            lecture_repetitions: 20_000,
            confidence: 0.95,
            gallery_width: 32,
            gallery_passes: 32,
            gallery_reference_passes: 1024,
            gallery_scenes: None,
            veach_scene: Some(scene("veach-mis")).filter(|p| p.is_file()),
            folder_suffix: "",
        };
        // Bitterli's scenes: one Mitsuba XML file per folder, rendered with `-D integrator=path`.
        let bitterli = |n: &str| scenes_dir.join("bitterli").join(n).join("scene.xml");
        match name {
            "quick" => Ok(base),
            "full" => Ok(Scale {
                name: "full",
                width: 128,
                runs: 16,
                max_passes: 256,
                reference_passes: 16384,
                max_length: 8,
                bias_runs: 16,
                progressive_passes: 1024,
                plane_runs: 64,
                plane_passes: 1024,
                plane_photons: 4000,
                lecture_repetitions: 200_000,
                gallery_width: 256,
                gallery_passes: 64,
                gallery_reference_passes: 4096,
                ..base
            }),
            // What the committed report shows for convergence and the galleries: slopes fitted
            // over 1 … 256 passes from 16 runs (the quick scale's 4 runs over 1 … 16 give
            // intervals several units wide), at 32 px, where a run costs little, on
            // every shipped scene; galleries at 256 px, where a reader sees the light paths,
            // of every shipped scene every integrator renders (results/committed-scale.md states
            // the compute).
            "committed" => Ok(Scale {
                name: "committed",
                scenes: all.clone(),
                gallery_scenes: Some(all.clone()),
                runs: 16,
                max_passes: 256,
                reference_passes: 8192,
                gallery_width: 256,
                gallery_passes: 16,
                gallery_reference_passes: 256,
                ..base
            }),
            // Bitterli's three scenes (scenes/bitterli/, Mitsuba XML, `-D integrator=path`) at
            // 256 px, every study of one scene's light paths, on a budget one session affords
            // (results/convergence-bitterli/summary.md states it).
            "bitterli" => Ok(Scale {
                name: "bitterli",
                width: 256,
                runs: 4,
                max_passes: 16,
                reference_passes: 128,
                scenes: vec![
                    bitterli("cornell-box"),
                    bitterli("veach-bidir"),
                    bitterli("veach-mis"),
                ],
                focus_scene: bitterli("cornell-box"),
                // Veach's plates alone: max_depth 3 is the file's own, and per-length renders
                // every integrator at every depth, which the cornell-box's 30 bounces make dear.
                length_scenes: vec![bitterli("veach-mis")],
                max_length: 3,
                gallery_width: 256,
                gallery_passes: 16,
                gallery_reference_passes: 128,
                veach_scene: Some(bitterli("veach-mis")),
                folder_suffix: "-bitterli",
                ..base
            }),
            "test" => Ok(Scale {
                name: "test",
                width: 16,
                runs: 6,
                max_passes: 16,
                reference_passes: 512,
                scenes: vec![scene("cornell-box"), scene("veach-mis")],
                length_scenes: vec![scene("cornell-box")],
                max_length: 3,
                alphas: vec![0.5, 2.0 / 3.0, 1.0],
                bias_runs: 16,
                progressive_passes: 64,
                // bias² at N = 1 must clear 0 at the test's strict level.
                plane_runs: 16,
                plane_passes: 64,
                plane_photons: 4000,
                lecture_repetitions: 4000,
                // The tests check dozens of intervals; at 0.999 each, the chance that any of 50
                // misses by luck is 1 − 0.999⁵⁰ ≈ 5 % (Šidák), which a fixed seed then pins.
                confidence: 0.999,
                gallery_width: 16,
                gallery_passes: 16,
                gallery_reference_passes: 512,
                ..base
            }),
            other => Err(format!(
                "unknown scale '{other}' (quick, committed, full, bitterli, test)"
            )),
        }
    }

    /// Snapshot pass counts 1, 2, 4, … up to `max` (and `max` itself).
    pub fn doublings(max: u32) -> Vec<u32> {
        let mut v: Vec<u32> = std::iter::successors(Some(1u32), |n| n.checked_mul(2))
            .take_while(|&n| n <= max)
            .collect();
        if v.last() != Some(&max) {
            v.push(max);
        }
        v
    }

    /// This scale with the galleries' film, passes and references as its own: what the
    /// equal-time study renders at. At the quick scale it is the scale itself.
    pub fn gallery(&self) -> Scale {
        Scale {
            width: self.gallery_width,
            max_passes: self.gallery_passes,
            reference_passes: self.gallery_reference_passes,
            scenes: self.gallery_scenes.clone().unwrap_or(self.scenes.clone()),
            ..self.clone()
        }
    }

    /// The film of a scene at this scale: `width` wide, the scene's aspect ratio kept.
    pub fn resolution(&self, scene_size: (u32, u32)) -> (u32, u32) {
        let (w, h) = scene_size;
        let height = ((self.width as f64) * h as f64 / w as f64).round().max(1.0) as u32;
        (self.width, height)
    }
}

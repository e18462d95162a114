//! What every study runs with: its scale, the cache executors (runs and references), where it
//! writes, and one progress bar with an ETA over all the renders it asks for.

use super::reference::Reference;
use super::scale::Scale;
use crate::cache::RenderCache;
use crate::runs::{Executor, RunEntry, RunSpec};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Where and how a study runs: what `lt study`'s flags, `lt plan study` and `lt collect` give.
#[derive(Clone, Debug)]
pub struct StudySetup {
    /// quick, full or test (`Scale::named`).
    pub scale: String,
    /// Where the study folders (and index.html) are written.
    pub results: PathBuf,
    /// The cache of finished renders (default RESULTS/cache; references in RESULTS/references).
    pub cache: Option<PathBuf>,
    /// The shipped scenes.
    pub scenes: PathBuf,
    /// Worker threads (0 = one per core).
    pub threads: usize,
    pub quiet: bool,
    /// Test hook: fail after this many new renders, as an interruption would.
    pub stop_after: Option<u64>,
}

pub struct StudyContext {
    pub scale: Scale,
    pub runs: Executor,
    pub references: Executor,
    pub results: PathBuf,
    quiet: bool,
    stop_after: Option<u64>,
    bar: ProgressBar,
    /// (core-seconds, renders) of every entry handed to a study so far, found in the cache or
    /// rendered now: what the studies' results cost (`spent`).
    spent: Mutex<(f64, u64)>,
    /// References loaded this process, by the key of their spec.
    loaded: Mutex<Vec<(String, std::sync::Arc<Reference>)>>,
}

impl StudyContext {
    pub fn new(args: &StudySetup) -> Result<StudyContext, String> {
        let scale = Scale::named(&args.scale, &args.scenes)?;
        let cache = args
            .cache
            .clone()
            .unwrap_or_else(|| args.results.join("cache"));
        Ok(StudyContext::with(
            scale,
            RenderCache::new(cache),
            RenderCache::new(args.results.join("references")),
            args.results.clone(),
            args.threads,
            args.quiet,
            args.stop_after,
        ))
    }

    pub fn with(
        scale: Scale,
        runs: RenderCache,
        references: RenderCache,
        results: PathBuf,
        threads: usize,
        quiet: bool,
        stop_after: Option<u64>,
    ) -> StudyContext {
        let bar = if quiet {
            ProgressBar::hidden()
        } else {
            let b = ProgressBar::new(0);
            b.set_style(
                ProgressStyle::with_template(
                    "[{elapsed_precise}] {bar:30} {pos}/{len} renders  {msg}  ETA {eta}",
                )
                .unwrap(),
            );
            b
        };
        StudyContext {
            scale,
            runs: Executor {
                cache: runs,
                threads,
            },
            references: Executor {
                cache: references,
                threads,
            },
            results,
            quiet,
            stop_after,
            bar,
            spent: Mutex::new((0.0, 0)),
            loaded: Mutex::new(Vec::new()),
        }
    }

    /// (renders made, renders found in the cache) so far, references included.
    pub fn counts(&self) -> (u64, u64) {
        let (a, b) = self.runs.cache.counts();
        let (c, d) = self.references.cache.counts();
        (a + c, b + d)
    }

    /// The folder of `study`: RESULTS/<study><the scale's folder suffix>.
    pub fn study_dir(&self, study: &str) -> PathBuf {
        self.results
            .join(format!("{study}{}", self.scale.folder_suffix))
    }

    /// A line above the progress bar.
    pub fn say(&self, line: &str) {
        if self.quiet {
        } else if self.bar.is_hidden() {
            // Not a terminal (a log file, a cluster job): plain lines instead of a bar.
            eprintln!("{line}");
        } else {
            self.bar.println(line);
        }
    }

    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }

    /// Announces `n` more renders to the progress bar (its length is what is left to ask for).
    pub fn expect(&self, n: usize) {
        self.bar.inc_length(n as u64);
    }

    fn check_interruption(&self) -> Result<(), String> {
        if let Some(n) = self.stop_after {
            if self.counts().0 >= n {
                return Err(format!("stopped after {n} new renders (--stop-after)"));
            }
        }
        Ok(())
    }

    /// The finished entry of `spec`, rendered now if the cache lacks it.
    pub fn run(&self, spec: &RunSpec) -> Result<RunEntry, String> {
        self.check_interruption()?;
        self.bar.set_message(spec.label());
        let e = self.runs.run(spec)?;
        self.bar.inc(1);
        self.count(&e);
        Ok(e)
    }

    /// Adds an entry's cost, the CPU seconds its threads spent, to `spent`.
    fn count(&self, e: &RunEntry) {
        let secs = e.cpu_seconds_at(e.record.spec.passes).unwrap_or(0.0);
        let mut s = self.spent.lock().unwrap();
        s.0 += secs;
        s.1 += 1;
    }

    /// (core-seconds, renders) of the entries the studies were handed so far; a study states
    /// the difference across its run as its compute.
    pub fn spent(&self) -> (f64, u64) {
        *self.spent.lock().unwrap()
    }

    /// The sentence a summary states its compute with, since `before` (`spent()` at its start).
    pub fn compute_note(&self, before: (f64, u64)) -> String {
        let (s, n) = self.spent();
        format!(
            "**Compute.** {:.1} core-minutes of rendering over {} renders (each render's recorded \
             wall time × its threads, references included: an upper bound on a machine shared with \
             other work; a render shared with another study is counted in both).",
            (s - before.0) / 60.0,
            n - before.1
        )
    }

    /// All of `specs`, in order.
    pub fn run_all(&self, specs: &[RunSpec]) -> Result<Vec<RunEntry>, String> {
        self.expect(specs.len());
        specs.iter().map(|s| self.run(s)).collect()
    }

    /// The reference of `scene` at this scale (and `max_depth`, if given), from the reference
    /// cache or rendered now.
    pub fn reference(
        &self,
        scene: &Path,
        max_depth: Option<u32>,
    ) -> Result<std::sync::Arc<Reference>, String> {
        self.reference_at(&self.scale, scene, max_depth)
    }

    /// The same at another scale's film and passes (the galleries': `Scale::gallery`).
    pub fn reference_at(
        &self,
        scale: &Scale,
        scene: &Path,
        max_depth: Option<u32>,
    ) -> Result<std::sync::Arc<Reference>, String> {
        let spec = super::reference::spec(scale, scene, max_depth)?;
        let id = serde_json::to_string(&spec).unwrap_or_default();
        if let Some((_, r)) = self.loaded.lock().unwrap().iter().find(|(k, _)| *k == id) {
            return Ok(r.clone());
        }
        self.check_interruption()?;
        self.bar.inc_length(1);
        self.bar.set_message(format!("reference {}", spec.label()));
        let entry = self.references.run(&spec)?;
        self.bar.inc(1);
        self.count(&entry);
        let r = std::sync::Arc::new(Reference::from_entry(&entry)?);
        self.loaded.lock().unwrap().push((id, r.clone()));
        Ok(r)
    }
}

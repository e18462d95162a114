//! How a scene file is read (`LoadOptions`) and what a load substituted or passed over
//! (`LoadReport`); the process-wide defaults the command line sets once.

use std::sync::OnceLock;

/// How a scene file is read.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// Substitute the nearest feature lt has where a file asks for one it lacks (listed in the
    /// report); without it such a file is refused.
    pub approximate: bool,
    /// Print the accepted-but-ignored parameters too (the command line's `--verbose`).
    pub verbose: bool,
    /// `-D key=value`: an XML scene's `$key` parameters, defined before (so over) the file's own
    /// `<default>`s, as Mitsuba's `-D` does (e.g. `integrator=path`). TOML scenes take none.
    pub defines: Vec<(String, String)>,
}

impl LoadOptions {
    /// Parses one `-D` argument, `key=value`, the key a parameter name Mitsuba accepts.
    pub fn parse_define(s: &str) -> Result<(String, String), String> {
        let Some((k, v)) = s.split_once('=') else {
            return Err(format!(
                "-D `{s}`: write key=value (e.g. -D integrator=path)"
            ));
        };
        let k = k.trim();
        if k.is_empty() || !k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return Err(format!(
                "-D `{s}`: `{k}` is not a parameter name (letters, digits and _)"
            ));
        }
        Ok((k.to_string(), v.to_string()))
    }
}

/// What a load changed or passed over, one line each, each starting with `file:line`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LoadReport {
    /// Substitutions `--approximate` made (the image differs from Mitsuba's by these).
    pub substitutions: Vec<String>,
    /// Parameters accepted and ignored because they change nothing lt renders.
    pub ignored: Vec<String>,
}

impl LoadReport {
    /// Prints the substitutions (always) and the ignored parameters (when `verbose`) to stderr.
    pub fn print(&self, verbose: bool) {
        for s in &self.substitutions {
            eprintln!("approximated: {s}");
        }
        if verbose {
            for s in &self.ignored {
                eprintln!("ignored: {s}");
            }
        }
    }
}

static DEFAULT_OPTIONS: OnceLock<LoadOptions> = OnceLock::new();

/// Sets the options `load_scene` uses (once per process: the command line's global flags).
/// Returns false when they were already set.
pub fn set_default_load_options(opts: LoadOptions) -> bool {
    DEFAULT_OPTIONS.set(opts).is_ok()
}

/// The options `load_scene` uses: those set by `set_default_load_options`, else the defaults.
pub fn default_load_options() -> LoadOptions {
    DEFAULT_OPTIONS.get().cloned().unwrap_or_default()
}

//! Integrator parameters as the user gives them (`key = value` strings from the command line),
//! read by each integrator's constructor. Every key an integrator reads is a row of the table
//! that opens its file; a test holds the two equal (`registry::tests`).

use std::cell::RefCell;
use std::str::FromStr;

/// `key = value` pairs, in the order given; later values override earlier ones.
#[derive(Clone, Debug, Default)]
pub struct IntegratorParams {
    given: Vec<(String, String)>,
}

impl IntegratorParams {
    pub fn new() -> IntegratorParams {
        IntegratorParams::default()
    }

    /// Sets `key` (builder style, for tests and experiments).
    pub fn with(mut self, key: &str, value: impl ToString) -> IntegratorParams {
        self.set(key, value);
        self
    }

    pub fn set(&mut self, key: &str, value: impl ToString) {
        self.given.push((key.to_string(), value.to_string()));
    }

    /// Parses `key=value` (the `--set` flag).
    pub fn set_pair(&mut self, pair: &str) -> Result<(), String> {
        let (k, v) = pair
            .split_once('=')
            .ok_or_else(|| format!("--set expects key=value, got '{pair}'"))?;
        self.set(k.trim(), v.trim());
        Ok(())
    }

    /// The pairs as given (for records of how an image was made).
    pub fn pairs(&self) -> &[(String, String)] {
        &self.given
    }

    fn value(&self, key: &str) -> Option<&str> {
        self.given
            .iter()
            .rev()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
}

/// Reads parameters for one integrator and remembers which keys it asked for, so that keys the
/// integrator does not know are refused (`finish`) and the documentation can be checked.
pub struct ParamReader<'a> {
    params: &'a IntegratorParams,
    integrator: &'a str,
    asked: RefCell<Vec<&'static str>>,
}

impl<'a> ParamReader<'a> {
    pub fn new(integrator: &'a str, params: &'a IntegratorParams) -> ParamReader<'a> {
        ParamReader {
            params,
            integrator,
            asked: RefCell::new(Vec::new()),
        }
    }

    /// The value of `key` parsed as T, or `None` when not given.
    pub fn get<T: FromStr>(&self, key: &'static str) -> Result<Option<T>, String>
    where
        T::Err: std::fmt::Display,
    {
        self.asked.borrow_mut().push(key);
        match self.params.value(key) {
            None => Ok(None),
            Some(v) => v
                .parse()
                .map(Some)
                .map_err(|e| format!("{}: cannot read {key} = '{v}': {e}", self.integrator)),
        }
    }

    /// The value of `key` mapped through `parse` (for enumerations with their own names).
    pub fn get_with<T>(
        &self,
        key: &'static str,
        parse: impl Fn(&str) -> Result<T, String>,
    ) -> Result<Option<T>, String> {
        self.asked.borrow_mut().push(key);
        match self.params.value(key) {
            None => Ok(None),
            Some(v) => parse(v)
                .map(Some)
                .map_err(|e| format!("{}: {key}: {e}", self.integrator)),
        }
    }

    /// `max_depth`, defaulting to the scene's `[render] max_depth`.
    pub fn max_depth(&self, scene: &lt_core::Scene) -> Result<u32, String> {
        Ok(self.get("max_depth")?.unwrap_or(scene.settings.max_depth))
    }

    /// `rr_depth`, defaulting to the scene's `[render] rr_depth`.
    pub fn rr_depth(&self, scene: &lt_core::Scene) -> Result<u32, String> {
        Ok(self.get("rr_depth")?.unwrap_or(scene.settings.rr_depth))
    }

    /// `light_paths` (light subpaths per pass), at least 1; `None` means one per pixel.
    pub fn light_paths(&self) -> Result<Option<u64>, String> {
        let m = self.get::<u64>("light_paths")?;
        if m == Some(0) {
            return Err(format!(
                "{}: light_paths must be at least 1",
                self.integrator
            ));
        }
        Ok(m)
    }

    /// Keys asked for so far.
    pub fn asked(&self) -> Vec<&'static str> {
        self.asked.borrow().clone()
    }

    /// Fails naming every given key that the integrator did not ask for.
    pub fn finish(&self) -> Result<(), String> {
        let asked = self.asked.borrow();
        let unknown: Vec<&str> = self
            .params
            .given
            .iter()
            .map(|(k, _)| k.as_str())
            .filter(|k| !asked.contains(k))
            .collect();
        if unknown.is_empty() {
            return Ok(());
        }
        let mut known = asked.clone();
        known.sort();
        known.dedup();
        Err(format!(
            "{} does not take {} (it takes: {})",
            self.integrator,
            unknown.join(", "),
            known.join(", ")
        ))
    }
}

/// Reads the `| key | type | default | meaning |` table of an integrator's module docs: the keys
/// with their type column (`u32`, `u64`, or alternatives separated by `/`).
pub fn documented_keys(source: &str) -> Vec<(String, String)> {
    source
        .lines()
        .take_while(|l| l.starts_with("//!"))
        .filter_map(|l| {
            let row = l.trim_start_matches("//!").trim();
            let cells: Vec<&str> = row.split('|').map(str::trim).collect();
            // "| `key` | type | … |" splits into ["", "`key`", "type", …].
            let key = cells.get(1)?.strip_prefix('`')?.strip_suffix('`')?;
            Some((key.to_string(), cells.get(2)?.to_string()))
        })
        .collect()
}

//! How every command reads a scene file: the command line's one group of load flags
//! (`--approximate`, `--verbose`, `-D key=value`), global so each command that takes a scene
//! takes them, turned into `lt_scene_io::LoadOptions`.

use lt_scene_io::LoadOptions;

#[derive(clap::Args, Clone, Debug, Default)]
pub struct LoadArgs {
    /// Where a Mitsuba XML scene asks for something lt lacks (a Gaussian pixel
    /// filter, unbounded max_depth), substitute the nearest it has and list each
    /// substitution, instead of refusing the scene.
    #[arg(long, global = true)]
    pub approximate: bool,
    /// List the parameters of an XML scene that were accepted but change nothing lt renders.
    #[arg(long, global = true)]
    pub verbose: bool,
    /// Define an XML scene's `$KEY` parameter (over the file's own <default>), as Mitsuba's -D
    /// does: e.g. -D integrator=path, -D spp=64. Repeatable.
    #[arg(short = 'D', value_name = "KEY=VALUE", global = true, value_parser = LoadOptions::parse_define)]
    pub define: Vec<(String, String)>,
}

impl LoadArgs {
    pub fn options(&self) -> LoadOptions {
        LoadOptions {
            approximate: self.approximate,
            verbose: self.verbose,
            defines: self.define.clone(),
        }
    }
}

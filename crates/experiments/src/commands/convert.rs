//! `lt convert SCENE.toml -o SCENE.xml`: one of our scenes as Mitsuba 3 XML, wherever Mitsuba
//! can express it (`lt_scene_io::xml::write`; a scene with a finite-cone sun is refused).
//! Mesh files are referenced relative to the output's folder. Reading the XML back with `lt`
//! gives the same scene (tests/xml_roundtrip.rs); `scripts/mitsuba_reference.py` renders it.

use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct ConvertArgs {
    /// The TOML scene to convert.
    pub scene: PathBuf,
    /// Where to write the Mitsuba 3 XML.
    #[arg(long, short)]
    pub output: PathBuf,
}

pub fn run(args: &ConvertArgs) -> Result<(), String> {
    let out_dir = match args.output.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&out_dir)
        .map_err(|e| format!("cannot create {}: {e}", out_dir.display()))?;
    let xml = lt_scene_io::xml::write::to_mitsuba_xml(&args.scene, &out_dir)
        .map_err(|e| e.to_string())?;
    // Written beside the target and renamed, so a failed write leaves no half file.
    let tmp = args.output.with_extension("xml.partial");
    std::fs::write(&tmp, xml).map_err(|e| format!("cannot write {}: {e}", tmp.display()))?;
    std::fs::rename(&tmp, &args.output)
        .map_err(|e| format!("cannot write {}: {e}", args.output.display()))?;
    eprintln!("wrote {}", args.output.display());
    Ok(())
}

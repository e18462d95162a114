//! The docs list what the code has: every `lt` subcommand (from `lt --help`) is named in the
//! README's command list and in ARCHITECTURE.md, the README's scene count is the number of
//! shipped scenes, every shipped scene has its row in scenes/README.md, and `lt mis-check`'s help
//! names every integrator whose weights it checks (from the registry).

use lt_integrators::registry::{self, Weights};
use std::path::PathBuf;
use std::process::Command;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn read(rel: &str) -> String {
    std::fs::read_to_string(repo().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

fn help(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_lt"))
        .args(args)
        .output()
        .unwrap();
    assert!(out.status.success(), "lt {args:?} --help failed");
    String::from_utf8(out.stdout).unwrap()
}

/// The subcommands `lt --help` lists (clap's "Commands:" block), without `help`.
fn subcommands() -> Vec<String> {
    let text = help(&["--help"]);
    text.lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .map(str::to_string)
        .collect()
}

/// The shipped scenes' names (every `scenes/*.toml`).
fn scenes() -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(repo().join("scenes"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().to_string())
        .collect();
    v.sort();
    v
}

const NUMBERS: [&str; 41] = [
    "zero",
    "one",
    "two",
    "three",
    "four",
    "five",
    "six",
    "seven",
    "eight",
    "nine",
    "ten",
    "eleven",
    "twelve",
    "thirteen",
    "fourteen",
    "fifteen",
    "sixteen",
    "seventeen",
    "eighteen",
    "nineteen",
    "twenty",
    "twenty-one",
    "twenty-two",
    "twenty-three",
    "twenty-four",
    "twenty-five",
    "twenty-six",
    "twenty-seven",
    "twenty-eight",
    "twenty-nine",
    "thirty",
    "thirty-one",
    "thirty-two",
    "thirty-three",
    "thirty-four",
    "thirty-five",
    "thirty-six",
    "thirty-seven",
    "thirty-eight",
    "thirty-nine",
    "forty",
];

#[test]
fn readme_and_architecture_name_every_subcommand() {
    let commands = subcommands();
    assert!(commands.len() >= 10, "parsed {commands:?} from lt --help");
    let (readme, arch) = (read("README.md"), read("ARCHITECTURE.md"));
    let mut missing = Vec::new();
    for c in &commands {
        let named = format!("lt {c}");
        if !readme.contains(&named) {
            missing.push(format!("README.md lacks `{named}`"));
        }
        if !arch.contains(&named) {
            missing.push(format!("ARCHITECTURE.md lacks `{named}`"));
        }
    }
    assert!(missing.is_empty(), "{}", missing.join("\n"));
}

#[test]
fn readme_counts_the_shipped_scenes_and_scenes_readme_has_each() {
    let scenes = scenes();
    let readme = read("README.md");
    let word = NUMBERS
        .get(scenes.len())
        .unwrap_or_else(|| panic!("{} scenes: extend NUMBERS", scenes.len()));
    let said = format!("{} scenes ship", capitalised(word));
    assert!(
        readme.contains(&said),
        "README.md should say \"{said}\" ({} .toml files in scenes/)",
        scenes.len()
    );
    let table = read("scenes/README.md");
    let missing: Vec<&String> = scenes
        .iter()
        .filter(|s| !table.contains(&format!("| `{s}` |")))
        .collect();
    assert!(
        missing.is_empty(),
        "scenes/README.md has no row for {missing:?}"
    );
}

fn capitalised(w: &str) -> String {
    let mut c = w.chars();
    c.next()
        .map(|f| f.to_uppercase().chain(c).collect())
        .unwrap_or_default()
}

#[test]
fn mis_check_help_names_the_integrators_it_checks() {
    let top = help(&["--help"]);
    let line = top
        .lines()
        .find(|l| l.trim_start().starts_with("mis-check"))
        .expect("mis-check in lt --help");
    let own = help(&["mis-check", "--help"]);
    let checked: Vec<&str> = registry::with_weights(|w| w != Weights::None).collect();
    assert!(checked.len() >= 4, "{checked:?}");
    for name in checked {
        assert!(
            line.contains(name),
            "lt --help's mis-check line lacks {name}: {line}"
        );
        assert!(
            own.contains(&format!("{name},")) || own.contains(&format!("{name} ")),
            "lt mis-check --help lacks {name}"
        );
    }
}

//! The docs list what the code has: every `lt` subcommand (from `lt --help`) is named in the
//! README's command list and in ARCHITECTURE.md, the README's scene count is the number of
//! shipped scenes, every shipped scene has its row in scenes/README.md, and `lt mis-check`'s help
//! names every integrator whose weights it checks (from the registry). README's integrator table
//! has a row for every registered integrator and names every key each takes; its lists of
//! materials, lights, media, cameras and pixel filters hold every type the TOML and XML loaders
//! read; README and ARCHITECTURE describe every study scale; and the docs name no constant and
//! no file of the repository that does not exist.

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

// ---------------------------------------------------------------------------------------------
// README's lists against the code: integrators and their keys (the registry), scales (the study
// scales), and the scene elements — materials, lights, media, cameras, pixel filters — as the
// loaders name them. The loaders have no table of names a test can import, but they answer an
// unknown type with the types of that kind they read; that answer, from both formats, is the
// list README must cover (and each list must be non-empty, so a changed message fails here
// rather than passing with nothing to check).

/// README's section under `## {title}`, up to the next `## ` heading.
fn section<'a>(text: &'a str, title: &str) -> &'a str {
    let head = format!("\n## {title}\n");
    let start = text
        .find(&head)
        .unwrap_or_else(|| panic!("README.md has no section \"## {title}\""));
    let body = &text[start + head.len()..];
    &body[..body.find("\n## ").unwrap_or(body.len())]
}

/// The paragraph of `text` that begins with `lead` (up to the next blank line).
fn paragraph<'a>(text: &'a str, lead: &str) -> &'a str {
    let start = text
        .find(&format!("\n{lead}"))
        .unwrap_or_else(|| panic!("README.md has no paragraph beginning \"{lead}\""));
    let body = &text[start + 1..];
    &body[..body.find("\n\n").unwrap_or(body.len())]
}

/// The names a loader's error lists after "known", "expected" or "reads", up to the closing
/// parenthesis: "(known: a, b and c)" → [a, b, c]. Empty when it lists none.
fn listed_names(message: &str) -> Vec<String> {
    let Some(at) = ["known", "expected", "reads"]
        .iter()
        .filter_map(|k| message.rfind(k).map(|i| i + k.len()))
        .max()
    else {
        return Vec::new();
    };
    let rest = &message[at..];
    let list = &rest[..rest.find(')').unwrap_or(rest.len())];
    list.split([',', ' ', ':', '\n'])
        .map(|w| w.trim_matches('`'))
        .filter(|w| !w.is_empty() && !["or", "and", "types", "type"].contains(w))
        .filter(|w| {
            w.chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
        })
        .map(str::to_string)
        .collect()
}

/// Loads `text` (written as `name` in a temporary folder: the probes refer to no other file) and
/// returns the load error.
fn load_error(name: &str, text: &str) -> String {
    let dir = std::env::temp_dir().join(format!("lt-docs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    let err = match lt_scene_io::load_scene(&path) {
        Ok(_) => panic!("{name}: a scene with an unknown type loaded"),
        Err(e) => e.to_string(),
    };
    std::fs::remove_file(&path).unwrap();
    err
}

/// A shipped scene with the first `from` replaced by `to`.
fn probe(file: &str, from: &str, to: &str) -> String {
    let text = read(file);
    assert!(text.contains(from), "{file} lacks {from}");
    text.replacen(from, to, 1)
}

/// The types of one kind the loaders read: from the TOML reader's and the XML reader's answer
/// to an unknown type (`None`: that format has no such element), each a non-empty list unless
/// `may_be_empty`.
fn loader_names(toml: Option<String>, xml: Option<String>, may_be_empty: bool) -> Vec<String> {
    let mut names = Vec::new();
    for (format, text) in [("toml", toml), ("xml", xml)] {
        let Some(text) = text else { continue };
        let error = load_error(&format!("probe.{format}"), &text);
        let listed = listed_names(&error);
        // The unknown type must be what failed — unless the whole kind is refused (media today).
        assert!(
            error.contains("nosuch") || (may_be_empty && listed.is_empty()),
            "{format}: the error does not name the unknown type: {error}"
        );
        assert!(
            may_be_empty || listed.len() >= 2,
            "the {format} loader's answer to an unknown type lists {listed:?}: has its message \
             changed? (docs.rs reads the known types from it) {error}"
        );
        names.extend(listed);
    }
    names.sort();
    names.dedup();
    names
}

/// Every name of `names` in backticks in `text`; the missing ones, as failures.
fn missing_names(names: &[String], text: &str, what: &str) -> Vec<String> {
    names
        .iter()
        .filter(|n| !text.contains(&format!("`{n}`")))
        .map(|n| format!("README.md's {what} lacks `{n}`"))
        .collect()
}

fn materials() -> Vec<String> {
    loader_names(
        Some(probe(
            "scenes/cornell-box.toml",
            "type = \"diffuse\"",
            "type = \"nosuch\"",
        )),
        Some(probe(
            "scenes/xml/cornell-box.xml",
            "<bsdf type=\"diffuse\"",
            "<bsdf type=\"nosuch\"",
        )),
        false,
    )
}

fn lights() -> Vec<String> {
    loader_names(
        Some(probe(
            "scenes/sun-room.toml",
            "type = \"sun\"",
            "type = \"nosuch\"",
        )),
        Some(probe(
            "scenes/xml/cornell-box.xml",
            "</scene>",
            "<emitter type=\"nosuch\"/>\n</scene>",
        )),
        false,
    )
}

fn cameras() -> Vec<String> {
    loader_names(
        Some(probe(
            "scenes/cornell-box.toml",
            "[camera]\n",
            "[camera]\ntype = \"nosuch\"\n",
        )),
        Some(probe(
            "scenes/xml/cornell-box.xml",
            "<sensor type=\"perspective\"",
            "<sensor type=\"nosuch\"",
        )),
        false,
    )
}

fn filters() -> Vec<String> {
    loader_names(
        Some(probe(
            "scenes/cornell-thinlens-tent.toml",
            "type = \"tent\"",
            "type = \"nosuch\"",
        )),
        Some(probe(
            "scenes/xml/cornell-box.xml",
            "<rfilter type=\"box\"",
            "<rfilter type=\"nosuch\"",
        )),
        false,
    )
}

/// Media: both loaders read them (TOML's `[media.NAME]` through the XML reader's builder), and
/// each answers an unknown type with the types it knows.
fn media() -> Vec<String> {
    let medium = "<medium type=\"nosuch\" id=\"docs-probe\"/>\n</scene>";
    loader_names(
        Some(probe(
            "scenes/cornell-box.toml",
            "[camera]\n",
            "[media.probe]\ntype = \"nosuch\"\n\n[camera]\n",
        )),
        Some(probe("scenes/xml/cornell-box.xml", "</scene>", medium)),
        true,
    )
}

#[test]
fn readme_lists_every_material_light_medium_camera_and_filter() {
    let readme = read("README.md");
    let elements = section(&readme, "Materials, lights, media, cameras and filters");
    let mut missing = Vec::new();
    for (lead, names) in [
        ("Materials:", materials()),
        ("Lights:", lights()),
        ("Cameras:", cameras()),
        ("Pixel filters:", filters()),
    ] {
        missing.extend(missing_names(&names, paragraph(elements, lead), lead));
    }
    let media = media();
    let said = paragraph(elements, "Media:");
    if media.is_empty() {
        assert!(
            said.contains("none"),
            "the loaders read no medium, and README.md's \"Media:\" should say none: {said}"
        );
    } else {
        missing.extend(missing_names(&media, said, "Media:"));
    }
    assert!(missing.is_empty(), "{}", missing.join("\n"));
}

#[test]
fn readme_has_a_row_for_every_integrator_and_names_every_key() {
    let readme = read("README.md");
    let table = section(&readme, "Integrators");
    let mut missing = Vec::new();
    for i in lt_integrators::INTEGRATORS {
        if !table.contains(&format!("| `{}` |", i.name)) {
            missing.push(format!(
                "README.md's integrator table has no row for `{}`",
                i.name
            ));
        }
        for (key, _) in lt_integrators::params::documented_keys(i.source) {
            let flag = format!("--{}", key.replace('_', "-"));
            let named = [format!("`{key}`"), format!("`{key}="), flag.clone()];
            if !named.iter().any(|n| table.contains(n.as_str())) {
                missing.push(format!(
                    "README.md's Integrators section names neither `{key}` nor {flag} ({} takes it)",
                    i.name
                ));
            }
        }
    }
    assert!(missing.is_empty(), "{}", missing.join("\n"));
}

/// The study scales: the names `Scale::named` lists when asked for an unknown one, each of which
/// it must then know (so the list it gives is the one it has).
fn scales() -> Vec<String> {
    use lt_experiments::study::scale::Scale;
    let dir = repo().join("scenes");
    let err = Scale::named("nosuch", &dir)
        .err()
        .expect("an unknown scale is refused");
    let inside = &err[err.rfind('(').expect("the scales in parentheses") + 1..];
    let names: Vec<String> = inside
        .trim_end_matches(')')
        .split([',', ' '])
        .filter(|w| !w.is_empty())
        .map(str::to_string)
        .collect();
    assert!(names.len() >= 3, "scales parsed from {err:?}: {names:?}");
    for n in &names {
        if let Err(e) = Scale::named(n, &dir) {
            panic!("Scale::named lists `{n}` as a scale but refuses it: {e}");
        }
    }
    names
}

#[test]
fn readme_and_architecture_describe_every_scale() {
    let scales = scales();
    let readme = read("README.md");
    let studies = section(&readme, "Studies");
    let arch = read("ARCHITECTURE.md");
    let at = arch
        .find("`scale` (")
        .expect("ARCHITECTURE.md's `scale` (…) entry");
    let arch_list = &arch[at..at + arch[at..].find(')').unwrap()];
    let mut missing = Vec::new();
    for s in &scales {
        if !studies.contains(&format!("- `{s}`")) {
            missing.push(format!(
                "README.md's Studies section has no item \"- `{s}`\""
            ));
        }
        if !arch_list.contains(s.as_str()) {
            missing.push(format!(
                "ARCHITECTURE.md's `scale` entry lacks {s}: {arch_list}"
            ));
        }
    }
    assert!(missing.is_empty(), "{}", missing.join("\n"));
}

/// The documents this file holds to the code, beside README and ARCHITECTURE.
const DOCS: [&str; 4] = [
    "README.md",
    "ARCHITECTURE.md",
    "scenes/README.md",
    "docs/cluster.md",
];

/// Every Rust source file under crates/ and tests/, concatenated.
fn sources() -> String {
    fn walk(dir: &std::path::Path, out: &mut String) {
        for e in std::fs::read_dir(dir).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() && p.file_name().is_some_and(|n| n != "target") {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push_str(&std::fs::read_to_string(&p).unwrap_or_default());
            }
        }
    }
    let mut out = String::new();
    walk(&repo().join("crates"), &mut out);
    walk(&repo().join("tests"), &mut out);
    out
}

/// Backticked words of `text` that look like `what` (a constant's name, a path).
fn backticked<'a>(
    text: &'a str,
    looks: impl Fn(&str) -> bool + 'a,
) -> impl Iterator<Item = &'a str> + 'a {
    text.split('`').skip(1).step_by(2).filter(move |w| looks(w))
}

#[test]
fn docs_name_only_constants_and_files_that_exist() {
    let code = sources();
    let is_constant = |w: &str| {
        w.len() > 3
            && w.chars()
                .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
            && w.contains('_')
    };
    let is_repo_path = |w: &str| {
        ["crates/", "tests/", "scenes/", "docs/"]
            .iter()
            .any(|p| w.starts_with(p))
            && !w.contains(['*', '<', ' ', '…'])
    };
    let mut missing = Vec::new();
    for doc in DOCS {
        let text = read(doc);
        for c in backticked(&text, is_constant) {
            if !code.contains(c) {
                missing.push(format!("{doc} names `{c}`, which no source file defines"));
            }
        }
        for p in backticked(&text, is_repo_path) {
            if !repo().join(p.trim_end_matches('/')).exists() {
                missing.push(format!("{doc} names `{p}`, which does not exist"));
            }
        }
    }
    missing.sort();
    missing.dedup();
    assert!(missing.is_empty(), "{}", missing.join("\n"));
}

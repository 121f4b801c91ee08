//! The documentation agrees with the code: docs/scenes.md's key tables with the scene parser (both ways), the
//! README's command synopsis with clap's definitions, and no file refers to a document outside the repository.

mod common;
use caustics::scene::Scene;
use std::collections::BTreeSet;
use std::path::Path;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn read(rel: &str) -> String {
    std::fs::read_to_string(Path::new(ROOT).join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

const BASE: &str = r#"
[[light]]
kind = "spot"
position = [0.0, 2.0, 0.0]
target = [0.0, 0.5, 0.0]
cone_deg = 40.0
intensity = 1.0

[[camera]]
name = "top"
kind = "orthographic"
position = [0.0, 3.0, 0.0]
target = [0.0, 0.0, 0.0]
half_height = 1.0

[[object]]
name = "floor"
shape = "plane"
size = [2.0, 2.0]
material = { kind = "diffuse" }
"#;

/// The keys the parser accepts in one table, from serde's unknown-field message (it lists every field of the
/// struct), so that the list comes from src/scene/schema.rs itself.
fn parser_keys(section: &str) -> BTreeSet<String> {
    let probe = "zz_probe = 1";
    let text = match section {
        "Top level" => format!("{probe}\n{BASE}"),
        "[[light]]" => BASE.replacen("intensity = 1.0", &format!("intensity = 1.0\n{probe}"), 1),
        "[[camera]]" => BASE.replacen("half_height = 1.0", &format!("half_height = 1.0\n{probe}"), 1),
        "[[object]]" => BASE.replacen("size = [2.0, 2.0]", &format!("size = [2.0, 2.0]\n{probe}"), 1),
        "material" => BASE.replacen("{ kind = \"diffuse\" }", "{ kind = \"diffuse\", zz_probe = 1 }", 1),
        s => panic!("unknown section {s}"),
    };
    let e = Scene::parse(&text, Path::new("probe.toml")).unwrap_err().to_string();
    let (_, expected) = e.split_once("expected").unwrap_or_else(|| panic!("no key list in `{e}`"));
    let keys: BTreeSet<String> = expected.split('`').skip(1).step_by(2).map(str::to_string).collect();
    assert!(e.contains("zz_probe") && !keys.is_empty(), "{e}");
    keys
}

/// docs/scenes.md: the first column of the table under each `## ` heading, backquotes removed.
fn doc_keys() -> Vec<(String, BTreeSet<String>)> {
    let text = read("docs/scenes.md");
    let mut out: Vec<(String, BTreeSet<String>)> = Vec::new();
    for line in text.lines() {
        if let Some(h) = line.strip_prefix("## ") {
            out.push((h.trim().trim_matches('`').to_string(), BTreeSet::new()));
        } else if let (Some(cell), Some(last)) = (line.strip_prefix("| `"), out.last_mut()) {
            let key = cell.split('`').next().unwrap();
            last.1.insert(key.to_string());
        }
    }
    out
}

#[test]
fn scenes_md_matches_the_parser() {
    let docs = doc_keys();
    let sections: Vec<&str> = docs.iter().map(|(s, _)| s.as_str()).collect();
    assert_eq!(sections, ["Top level", "[[light]]", "[[camera]]", "[[object]]", "material"]);
    for (section, keys) in &docs {
        let parser = parser_keys(section);
        let undocumented: Vec<_> = parser.difference(keys).collect();
        let unknown: Vec<_> = keys.difference(&parser).collect();
        assert!(undocumented.is_empty(), "{section}: the parser accepts {undocumented:?}, docs/scenes.md lacks them");
        assert!(unknown.is_empty(), "{section}: docs/scenes.md lists {unknown:?}, the parser rejects them");
    }
}

#[test]
fn every_shipped_scene_parses() {
    for e in std::fs::read_dir(Path::new(ROOT).join("assets/scenes")).unwrap().flatten() {
        Scene::load(&e.path()).unwrap_or_else(|err| panic!("{err}"));
    }
}

/// The README's synopsis block (under "## Commands"): each `caustics SUB` line and its continuation lines.
fn readme_synopsis() -> Vec<(String, Vec<String>)> {
    let text = read("README.md");
    let start = text.find("## Commands").expect("README has ## Commands");
    let block = text[start..].split("```").nth(1).expect("a code block");
    let mut out: Vec<(String, Vec<String>)> = Vec::new();
    for line in block.lines() {
        let mut words = line.split_whitespace().peekable();
        if words.peek() == Some(&"caustics") {
            words.next();
            out.push((words.next().expect("subcommand").to_string(), Vec::new()));
        }
        let Some(last) = out.last_mut() else { continue };
        for w in words {
            if let Some(i) = w.find("--") {
                let flag: String = w[i..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '-').collect();
                last.1.push(flag);
            }
        }
    }
    out
}

#[test]
fn readme_synopsis_matches_clap() {
    let synopsis = readme_synopsis();
    let subs: Vec<&str> = synopsis.iter().map(|(s, _)| s.as_str()).collect();
    assert_eq!(subs, ["render", "profile", "reference", "compare", "bench", "view", "temporal"]);
    for (sub, flags) in &synopsis {
        let o = common::caustics(&[sub, "--help"]);
        assert!(o.status.success(), "caustics {sub} --help");
        let help = String::from_utf8_lossy(&o.stdout);
        for f in flags {
            let found = help.split(|c: char| !(c.is_ascii_alphanumeric() || c == '-')).any(|w| w == f);
            assert!(found, "README: `caustics {sub} {f}` is not an option of `caustics {sub} --help`:\n{help}");
        }
    }
}

#[test]
fn help_documents_every_option_and_the_environment() {
    let o = common::caustics(&["--help"]);
    let top = String::from_utf8_lossy(&o.stdout);
    for v in ["CAUSTICS_DEVICE", "CAUSTICS_VALIDATION", "CAUSTICS_CACHE_DIR"] {
        assert!(top.contains(v), "caustics --help lacks {v}:\n{top}");
    }
    for sub in ["render", "profile", "reference", "compare", "bench", "view"] {
        let o = common::caustics(&[sub, "--help"]);
        let help = String::from_utf8_lossy(&o.stdout).into_owned();
        // `--help` prints each option's help on its own line or lines after it (or on the same line, after two
        // spaces); an option without help text is followed at once by a blank line or the next option.
        let lines: Vec<&str> = help.lines().map(str::trim).collect();
        for (i, line) in lines.iter().enumerate() {
            let option = line.starts_with("--") || (line.starts_with('-') && line.get(2..3) == Some(","));
            if option {
                let same_line = line.split("  ").filter(|s| !s.trim().is_empty()).count() >= 2;
                let next = lines.get(i + 1).copied().unwrap_or("");
                let next_line = !next.is_empty() && !next.starts_with('-');
                assert!(same_line || next_line, "caustics {sub}: `{line}` has no help text:\n{help}");
            }
        }
    }
    let o = common::caustics(&["view", "--help"]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("--print-controls"));
}

#[test]
fn no_reference_to_files_outside_the_repository() {
    let mut bad = Vec::new();
    let mut stack = vec![Path::new(ROOT).to_path_buf()];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap().flatten() {
            let p = e.path();
            let name = e.file_name().to_string_lossy().into_owned();
            if p.is_dir() {
                if !["target", ".git", "bench"].contains(&name.as_str()) {
                    stack.push(p);
                }
                continue;
            }
            let ok_ext = ["rs", "md", "toml", "comp", "vert", "frag", "glsl"];
            if !ok_ext.iter().any(|x| name.ends_with(&format!(".{x}"))) || name == "docs.rs" || name == "design.md" {
                continue;
            }
            let text = std::fs::read_to_string(&p).unwrap_or_default();
            for needle in ["DESIGN.md", "../shared", "PLATFORM.md"] {
                if text.contains(needle) {
                    bad.push(format!("{}: {needle}", p.display()));
                }
            }
        }
    }
    assert!(bad.is_empty(), "references outside the repository:\n{}", bad.join("\n"));
}

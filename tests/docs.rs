//! The documentation agrees with the code: docs/scenes.md's key tables with the scene parser (both ways), docs/cli.md
//! with clap's definitions (both ways), the environment and the stats JSON, docs/viewer.md with the viewer's
//! controls; every relative link resolves and every file under docs/bench is named; the pipeline's step numbers
//! cited in the code exist; no file names a work round; no file refers to a document outside the repository; and the
//! README and docs/results.md stay within their lengths.

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
        "[[object.keyframe]]" => format!("{BASE}\n[[object.keyframe]]\ntime = 0.0\n{probe}\n"),
        "waves" => format!(
            "{BASE}\n[[object]]\nname = \"w\"\nshape = \"water\"\nsize = 1.0\nmaterial = {{ kind = \"diffuse\" }}\n\
             waves = [{{ amplitude = 0.01, wavelength = 0.5, {probe} }}]\n"
        ),
        "[environment]" => format!("{BASE}\n[environment]\npath = \"x.hdr\"\n{probe}\n"),
        // Two tables: `simulation.KEY` and `drops[].KEY`.
        "simulation" => {
            let water = |line: &str| {
                format!(
                    "{BASE}\n[[object]]\nname = \"w\"\nshape = \"water\"\nsize = 1.0\nmaterial = {{ kind = \"diffuse\" }}\n{line}\n"
                )
            };
            let sim = parser_keys_of(&water(&format!("simulation = {{ {probe} }}")));
            let drops = parser_keys_of(&water(&format!("drops = [{{ time = 0.0, at = [0.0, 0.0], {probe} }}]")));
            let sim = sim.into_iter().map(|k| format!("simulation.{k}"));
            return sim.chain(drops.into_iter().map(|k| format!("drops[].{k}"))).collect();
        }
        s => panic!("unknown section {s}"),
    };
    parser_keys_of(&text)
}

/// The keys serde's unknown-field message for `text` (with one `zz_probe` key) lists.
fn parser_keys_of(text: &str) -> BTreeSet<String> {
    let e = Scene::parse(text, Path::new("probe.toml")).unwrap_err().to_string();
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
    assert_eq!(
        sections,
        [
            "Top level",
            "[[light]]",
            "[[camera]]",
            "[[object]]",
            "[[object.keyframe]]",
            "waves",
            "simulation",
            "material",
            "[environment]"
        ]
    );
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

/// docs/cli.md's synopsis block (the first code block under "## Commands"): each `caustics SUB` line and its
/// continuation lines, and the `METHOD:` group, whose options every sub-command that names `[METHOD]` takes.
fn cli_synopsis() -> Vec<(String, BTreeSet<String>)> {
    let text = read("docs/cli.md");
    let start = text.find("## Commands").expect("docs/cli.md has ## Commands");
    let block = text[start..].split("```").nth(1).expect("a code block");
    let mut subs: Vec<(String, BTreeSet<String>, bool)> = Vec::new();
    let mut method = BTreeSet::new();
    let mut in_method = false;
    for line in block.lines() {
        let mut words = line.split_whitespace().peekable();
        match words.peek() {
            Some(&"caustics") => {
                words.next();
                subs.push((words.next().expect("subcommand").to_string(), BTreeSet::new(), false));
                in_method = false;
            }
            Some(&"METHOD:") => in_method = true,
            _ => {}
        }
        for w in words {
            if w.contains("[METHOD]") {
                subs.last_mut().expect("a command before [METHOD]").2 = true;
            }
            if let Some(i) = w.find("--") {
                let flag: String = w[i..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '-').collect();
                if in_method {
                    method.insert(flag);
                } else if let Some(last) = subs.last_mut() {
                    last.1.insert(flag);
                }
            }
        }
    }
    assert!(!method.is_empty(), "docs/cli.md: no METHOD: group");
    subs.into_iter()
        .map(|(sub, mut flags, takes_method)| {
            if takes_method {
                flags.extend(method.iter().cloned());
            }
            (sub, flags)
        })
        .collect()
}

/// The long options `caustics SUB --help` lists (hidden ones are not listed), without `--help` itself.
fn help_options(sub: &str) -> BTreeSet<String> {
    let o = common::caustics(&[sub, "--help"]);
    assert!(o.status.success(), "caustics {sub} --help");
    let help = String::from_utf8_lossy(&o.stdout);
    help.lines()
        // Options sit at most 6 columns in; their descriptions further in.
        .filter(|l| l.len() - l.trim_start().len() <= 6)
        .map(str::trim_start)
        .filter_map(|l| {
            let l = if l.starts_with('-') && l.get(2..4) == Some(", ") { &l[4..] } else { l };
            l.starts_with("--").then(|| l.chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '-').collect())
        })
        .filter(|f: &String| f != "--help" && f != "--version")
        .collect()
}

#[test]
fn cli_synopsis_matches_clap() {
    let synopsis = cli_synopsis();
    let subs: Vec<&str> = synopsis.iter().map(|(s, _)| s.as_str()).collect();
    assert_eq!(subs, ["render", "profile", "reference", "compare", "bench", "view", "temporal"]);
    for (sub, flags) in &synopsis {
        let help = help_options(sub);
        let unknown: Vec<_> = flags.difference(&help).collect();
        let undocumented: Vec<_> = help.difference(flags).collect();
        assert!(unknown.is_empty(), "docs/cli.md: `caustics {sub}` lists {unknown:?}, which its --help lacks");
        assert!(undocumented.is_empty(), "docs/cli.md: `caustics {sub}` lacks {undocumented:?} of its --help");
    }
}

/// The `CAUSTICS_*` names in a text.
fn env_vars(text: &str) -> BTreeSet<String> {
    text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .filter(|w| w.starts_with("CAUSTICS_") && w.len() > "CAUSTICS_".len())
        .map(str::to_string)
        .collect()
}

#[test]
fn cli_environment_matches_help() {
    let o = common::caustics(&["--help"]);
    let help = env_vars(&String::from_utf8_lossy(&o.stdout));
    let text = read("docs/cli.md");
    let start = text.find("## Environment").expect("docs/cli.md has ## Environment");
    let section = text[start + 3..].split("\n## ").next().unwrap();
    assert_eq!(env_vars(section), help, "docs/cli.md's Environment against `caustics --help`");
}

/// The keys in the first column of docs/cli.md's stats table: every backquoted name of the cell.
fn documented_stats_keys() -> BTreeSet<String> {
    let text = read("docs/cli.md");
    let start = text.find("## Stats JSON").expect("docs/cli.md has ## Stats JSON");
    let section = text[start + 3..].split("\n## ").next().unwrap();
    let mut keys = BTreeSet::new();
    for line in section.lines().filter(|l| l.starts_with("| `")) {
        let cell = line.split('|').nth(1).unwrap();
        keys.extend(cell.split('`').skip(1).step_by(2).map(str::to_string));
    }
    keys
}

#[test]
fn cli_stats_keys_match_render() {
    let dir = common::out_dir("docs_stats_keys");
    let args = ["--transport", "exact", "--camera", "top", "--aov", "caustics", "--size", "32x32", "--level", "0"];
    let (stats, _) = common::render(&dir, "stats", common::SPHERE, &args);
    let written: BTreeSet<String> = stats.as_object().expect("an object").keys().cloned().collect();
    let documented = documented_stats_keys();
    let undocumented: Vec<_> = written.difference(&documented).collect();
    let unknown: Vec<_> = documented.difference(&written).collect();
    assert!(undocumented.is_empty(), "render --stats writes {undocumented:?}, docs/cli.md's stats table lacks them");
    assert!(unknown.is_empty(), "docs/cli.md's stats table lists {unknown:?}, which render --stats does not write");
}

#[test]
fn viewer_md_has_the_controls() {
    let o = common::caustics(&["view", "--print-controls"]);
    assert!(o.status.success(), "caustics view --print-controls");
    let table = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(read("docs/viewer.md").contains(table.trim()), "docs/viewer.md lacks the controls table:\n{table}");
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

/// Every file git tracks or would track (not ignored), or, outside a git checkout, every file under the root but
/// target/ and .git/; relative to the root, with its text: `None` for a binary file (a NUL byte, or not UTF-8).
fn tracked_files() -> Vec<(String, Option<String>)> {
    let root = Path::new(ROOT);
    let listed = std::process::Command::new("git")
        .args(["ls-files", "-z", "--cached", "--others", "--exclude-standard"])
        .current_dir(root)
        .output();
    let names: Vec<String> = match listed {
        Ok(o) if o.status.success() => {
            String::from_utf8_lossy(&o.stdout).split('\0').filter(|n| !n.is_empty()).map(str::to_string).collect()
        }
        _ => {
            let mut out = Vec::new();
            let mut stack = vec![root.to_path_buf()];
            while let Some(dir) = stack.pop() {
                for e in std::fs::read_dir(&dir).unwrap().flatten() {
                    let p = e.path();
                    if p.is_dir() {
                        if !["target", ".git"].contains(&e.file_name().to_string_lossy().as_ref()) {
                            stack.push(p);
                        }
                    } else {
                        out.push(p.strip_prefix(root).unwrap().to_string_lossy().replace('\\', "/"));
                    }
                }
            }
            out
        }
    };
    names
        .into_iter()
        .filter(|n| root.join(n).is_file())
        .map(|n| {
            let bytes = std::fs::read(root.join(&n)).unwrap_or_default();
            let text = if bytes.contains(&0) { None } else { String::from_utf8(bytes).ok() };
            (n, text)
        })
        .collect()
}

/// Phrases that name a round of work instead of the product: a stop, an issue or a round with its number (in
/// prose or in a file name), the possessive of an issue, a stop or round named as this, that, the last or the next one,
/// the present day's anything, the word brief after "the", and a wave of work with its data. The exact transport's bounce waves
/// (`wave_01`, wave 0, the waves) are product terms and pass. Returns each offending phrase with its neighbours.
fn round_names(text: &str) -> Vec<String> {
    let lower = text.to_lowercase();
    // Words: runs of letters, digits and apostrophes (so that a possessive stays one word).
    let words: Vec<&str> = lower
        .split(|c: char| !(c.is_alphanumeric() || c == '\'' || c == '\u{2019}'))
        .filter(|w| !w.is_empty())
        .collect();
    let number = |w: &str| w.chars().next().is_some_and(|c| c.is_ascii_digit());
    let ordinal = ["this", "that", "last", "previous", "next", "earlier", "later", "first", "second", "third"];
    let mut found = Vec::new();
    for (i, w) in words.iter().enumerate() {
        let next = words.get(i + 1).copied().unwrap_or("");
        let prev = if i > 0 { words[i - 1] } else { "" };
        let stem = w.trim_end_matches("'s").trim_end_matches("\u{2019}s").trim_end_matches(['\'', '\u{2019}']);
        let hit = match stem {
            "stop" | "stops" | "round" | "rounds" | "issue" | "issues" => {
                number(next)
                    || (ordinal.contains(&prev) && matches!(stem, "stop" | "round" | "rounds"))
                    || (stem == "issue" && stem != *w)
            }
            "wave" | "waves" => {
                (stem != *w || next == "of") && ordinal.contains(&prev) && {
                    let after = words.get(i + 2).copied().unwrap_or("");
                    matches!(next, "data" | "results" | "numbers" | "code") || (next == "of" && after == "work")
                }
            }
            "today" => stem != *w,
            "brief" => prev == "the",
            _ => {
                // A number glued to the word, as in a file name (split at its underscores).
                ["stop", "issue", "round"].iter().any(|p| w.strip_prefix(p).is_some_and(&number))
            }
        };
        if hit {
            found.push(format!("{prev} {w} {next}").trim().to_string());
        }
    }
    found
}

#[test]
fn round_name_detector_flags_round_names_only() {
    // Built from pieces, so that this file passes its own scan.
    let st = ["st", "op"].concat();
    let is = ["iss", "ue"].concat();
    for bad in [
        format!("measured in {} 25", st),
        format!("{} 23: prediction", ["St", "op"].concat()),
        format!("docs/bench/{}24_before.json", st),
        format!("profiles/{}25_s_d5.json", st),
        format!("{} 11's goals", is),
        format!("the {}'s goals", is),
        format!("after this {}", st),
        format!("this {}", ["ro", "und"].concat()),
        format!("the later {}' data", ["ro", "unds"].concat()),
        format!("the radius ({}'s kernel)", ["to", "day"].concat()),
        format!("the first {}'s data", ["wa", "ve"].concat()),
        format!("as {} #9 asked", is),
    ] {
        assert!(!round_names(&bad).is_empty(), "not flagged: {bad}");
    }
    for good in [
        "transport_bounces.wave_01 to wave_32",
        "wave 0 appends up to two children; the first wave's rays",
        "the bounce waves, and the waves' tail",
        "exposure in stops (EV); stop_above; Stop tracing once",
        "a round splat of the spread; a host round trip; rounded up",
        "photons this work group emits; a non-issue",
        "the brightest receiver; brief; in brief",
    ] {
        assert!(round_names(good).is_empty(), "flagged: {good}: {:?}", round_names(good));
    }
}

#[test]
fn no_file_names_a_round_of_work() {
    let mut bad = Vec::new();
    for (name, text) in tracked_files() {
        for phrase in round_names(&name) {
            bad.push(format!("{name} (its name): {phrase}"));
        }
        for phrase in text.as_deref().map(round_names).unwrap_or_default() {
            bad.push(format!("{name}: {phrase}"));
        }
    }
    assert!(bad.is_empty(), "round names (say what the product does, not when the work was done):\n{}", bad.join("\n"));
}

/// GitHub's anchor of a Markdown heading: lowercase, spaces to hyphens, punctuation dropped.
fn anchor(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// The anchors of a Markdown file's headings (outside code blocks), with GitHub's -1, -2 for repeats.
fn anchors(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut fenced = false;
    for line in text.lines() {
        if line.starts_with("```") {
            fenced = !fenced;
        }
        if fenced || !line.starts_with('#') {
            continue;
        }
        let base = anchor(line.trim_start_matches('#'));
        let mut a = base.clone();
        let mut k = 0;
        while !out.insert(a.clone()) {
            k += 1;
            a = format!("{base}-{k}");
        }
    }
    out
}

/// The targets of a Markdown file's inline links and images, outside code blocks and code spans.
fn link_targets(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut fenced = false;
    for line in text.lines() {
        if line.starts_with("```") {
            fenced = !fenced;
        }
        if fenced {
            continue;
        }
        let unquoted: String = line.split('`').step_by(2).collect::<Vec<_>>().join("");
        let mut rest = unquoted.as_str();
        while let Some(i) = rest.find("](") {
            let tail = &rest[i + 2..];
            let end = tail.find(')').unwrap_or(tail.len());
            out.push(tail[..end].trim().to_string());
            rest = &tail[end..];
        }
    }
    out
}

/// Resolve `target` (relative to the directory `base`, both repository-relative) to a normalized path.
fn resolve(base: &str, target: &str) -> String {
    let mut parts: Vec<&str> = base.split('/').filter(|p| !p.is_empty()).collect();
    for p in target.split('/') {
        match p {
            "" | "." => {}
            ".." => {
                parts.pop();
            }
            p => parts.push(p),
        }
    }
    parts.join("/")
}

#[test]
fn every_relative_link_resolves() {
    let files = tracked_files();
    let mut bad = Vec::new();
    for (name, text) in files.iter().filter(|(n, _)| n.ends_with(".md")) {
        let Some(text) = text else { continue };
        let dir = name.rsplit_once('/').map_or("", |(d, _)| d);
        for target in link_targets(text) {
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            let (path, frag) = target.split_once('#').unwrap_or((target.as_str(), ""));
            let resolved = if path.is_empty() { name.clone() } else { resolve(dir, path) };
            let full = Path::new(ROOT).join(&resolved);
            if !full.exists() {
                bad.push(format!("{name}: {target}: no such file"));
            } else if !frag.is_empty() && resolved.ends_with(".md") {
                let doc = std::fs::read_to_string(&full).unwrap_or_default();
                if !anchors(&doc).contains(frag) {
                    bad.push(format!("{name}: {target}: no heading #{frag} in {resolved}"));
                }
            }
        }
    }
    assert!(bad.is_empty(), "broken links:\n{}", bad.join("\n"));
}

#[test]
fn every_bench_file_is_named() {
    let files = tracked_files();
    let texts: Vec<(&str, &str)> = files
        .iter()
        .filter(|(n, _)| !n.starts_with("docs/bench/"))
        .filter_map(|(n, t)| t.as_deref().map(|t| (n.as_str(), t)))
        .collect();
    let mut unnamed = Vec::new();
    for (name, _) in files.iter().filter(|(n, _)| n.starts_with("docs/bench/")) {
        let from_docs = name.trim_start_matches("docs/");
        let file = name.rsplit('/').next().unwrap();
        // A document names it by its path; a tool by its file name (the tools write into a folder they are given).
        let named = texts.iter().any(|(n, t)| {
            t.contains(name.as_str()) || t.contains(from_docs) || (n.starts_with("tools/") && t.contains(file))
        });
        if !named {
            unnamed.push(name.clone());
        }
    }
    assert!(unnamed.is_empty(), "files under docs/bench that no document or tool names:\n{}", unnamed.join("\n"));
}

/// The pipeline's steps: docs/design.md's "### N. Title" headings under "## Pipeline" are 1..=n, src/frame/mod.rs lists
/// the same n, and every "design.md step N" or "design.md, step N" cited anywhere has 1 <= N <= n.
#[test]
fn pipeline_steps_are_numbered_once() {
    let design = read("docs/design.md");
    let start = design.find("## Pipeline\n").expect("docs/design.md has ## Pipeline");
    let section = design[start + 3..].split("\n## ").next().unwrap();
    let steps: Vec<u32> =
        section.lines().filter_map(|l| l.strip_prefix("### ")?.split_once(". ")?.0.parse().ok()).collect();
    let n = steps.len() as u32;
    assert!(n > 0 && steps == (1..=n).collect::<Vec<_>>(), "docs/design.md's steps: {steps:?}");
    let frame = read("src/frame/mod.rs");
    let listed = frame
        .lines()
        .take_while(|l| l.starts_with("//!"))
        .filter(|l| l.starts_with("//! ") && l[4..].split_once(". ").is_some_and(|(k, _)| k.parse::<u32>().is_ok()))
        .count();
    assert_eq!(listed as u32, n, "src/frame/mod.rs's header lists {listed} steps, docs/design.md {n}");
    let mut bad = Vec::new();
    for (name, text) in tracked_files() {
        let Some(text) = text else { continue };
        for pat in ["design.md step ", "design.md, step "] {
            for (i, _) in text.match_indices(pat) {
                let k: String = text[i + pat.len()..].chars().take_while(char::is_ascii_digit).collect();
                // "step N" with a letter is the convention's own description, not a citation.
                if !k.is_empty() && !k.parse::<u32>().is_ok_and(|k| (1..=n).contains(&k)) {
                    bad.push(format!("{name}: {pat}{k}"));
                }
            }
        }
    }
    assert!(bad.is_empty(), "citations of steps docs/design.md does not have (1 to {n}):\n{}", bad.join("\n"));
}

/// Every citation of a section by name, `docs/X.md "Title"` (or `X.md, "Title"`), names a heading of X.md that
/// starts with that title, or a paragraph that opens with it in bold.
#[test]
fn cited_sections_exist() {
    let docs = ["design", "results", "experiments", "cli", "viewer", "scenes"];
    let mut bad = Vec::new();
    for (name, text) in tracked_files() {
        let Some(text) = text else { continue };
        for doc in docs {
            let file = format!("{doc}.md");
            for (i, _) in text.match_indices(&file) {
                let rest = text[i + file.len()..].trim_start_matches([' ', ',', '(']);
                let Some(quoted) = rest.strip_prefix('"') else { continue };
                let Some(title) = quoted.split('"').next().filter(|t| !t.contains('\n')) else { continue };
                if !title.starts_with(|c: char| c.is_alphanumeric() || c == '`') {
                    continue; // code, not a citation
                }
                let target = read(&format!("docs/{file}"));
                let found = target.lines().any(|l| {
                    let l = l.replace('`', "");
                    l.trim_start_matches('#').trim().starts_with(title) && l.starts_with('#')
                        || l.starts_with(&format!("**{title}"))
                });
                if !found {
                    bad.push(format!("{name}: {file} \"{title}\""));
                }
            }
        }
    }
    assert!(bad.is_empty(), "citations of sections that do not exist:\n{}", bad.join("\n"));
}

/// The README stays a front page (at most 200 lines) and docs/results.md a page of current tables (at most 350);
/// what was measured and replaced goes to docs/experiments.md.
#[test]
fn the_front_pages_stay_short() {
    for (file, limit) in [("README.md", 200), ("docs/results.md", 350)] {
        let n = read(file).lines().count();
        assert!(n <= limit, "{file} has {n} lines; at most {limit} (move what was tried to docs/experiments.md)");
    }
}

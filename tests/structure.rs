//! The code stays in pieces a reader can hold: no Rust function longer than 120 lines (src/, build.rs, build/,
//! tests/, examples/), and no GLSL function longer than 150. The functions that were longer when the limits were set
//! were listed below with their lengths then, each allowed only to shrink until it fit; all of them fit now, and the
//! list stays empty: a function over its limit fails the test.

use std::path::{Path, PathBuf};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const RUST_LIMIT: usize = 120;
const GLSL_LIMIT: usize = 150;

/// (file, function, its length in lines when the limits were set).
const OVER: &[(&str, &str, usize)] = &[];

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            files(&p, out);
        } else {
            out.push(p);
        }
    }
}

/// A line without its `//` comment and with its string and char literals emptied (braces in them do not count).
fn code(line: &str) -> String {
    let mut out = String::new();
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '/' if chars.peek() == Some(&'/') => break,
            '"' => {
                while let Some(d) = chars.next() {
                    match d {
                        '\\' => {
                            chars.next();
                        }
                        '"' => break,
                        _ => {}
                    }
                }
            }
            '\'' => {
                // A char literal ('{', '\n'); a lifetime ('a) has no closing quote within two characters.
                let rest: String = chars.clone().take(3).collect();
                if rest.starts_with('\\') && rest.chars().nth(2) == Some('\'') {
                    chars.nth(2);
                } else if rest.chars().nth(1) == Some('\'') {
                    chars.nth(1);
                }
            }
            _ => out.push(c),
        }
    }
    out
}

/// The name of the function a line starts, if it starts one.
fn function_name(line: &str, glsl: bool) -> Option<String> {
    let t = line.trim_start();
    if glsl {
        // `type name(` at the start of a line, not a statement: a definition (a prototype ends with `;`).
        let words: Vec<&str> = t.split('(').next()?.split_whitespace().collect();
        let ok = words.len() >= 2
            && t.contains('(')
            && !t.trim_end().ends_with(';')
            && words.iter().all(|w| w.chars().all(|c| c.is_alphanumeric() || c == '_'))
            && !["return", "else", "if", "for", "while", "switch"].contains(&words[0]);
        return ok.then(|| words[words.len() - 1].to_string());
    }
    let mut rest = t;
    for prefix in ["pub(crate) ", "pub(super) ", "pub ", "const ", "unsafe ", "async "] {
        rest = rest.strip_prefix(prefix).unwrap_or(rest);
    }
    let name = rest.strip_prefix("fn ")?;
    Some(name.split(|c: char| !(c.is_alphanumeric() || c == '_')).next()?.to_string())
}

/// Every function of `text` with its length in lines (its signature's first line to its closing brace).
fn functions(text: &str, glsl: bool) -> Vec<(String, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let Some(name) = function_name(lines[i], glsl) else {
            i += 1;
            continue;
        };
        let (mut depth, mut opened, mut j) = (0i32, false, i);
        while j < lines.len() {
            let c = code(lines[j]);
            for ch in c.chars() {
                match ch {
                    '{' => {
                        depth += 1;
                        opened = true;
                    }
                    '}' => depth -= 1,
                    _ => {}
                }
            }
            if (opened && depth <= 0) || (!opened && c.trim_end().ends_with(';')) {
                break;
            }
            j += 1;
        }
        if opened {
            out.push((name, j - i + 1));
            i = j + 1;
        } else {
            i += 1;
        }
    }
    out
}

#[test]
fn functions_stay_within_their_limits() {
    let root = Path::new(ROOT);
    let mut all = Vec::new();
    files(&root.join("src"), &mut all);
    files(&root.join("glsl"), &mut all);
    for dir in ["build", "tests", "examples"] {
        files(&root.join(dir), &mut all);
    }
    all.push(root.join("build.rs"));
    let mut found = Vec::new();
    let mut problems = Vec::new();
    for path in all {
        let rel = path.strip_prefix(root).unwrap().to_string_lossy().into_owned();
        let glsl = rel.starts_with("glsl/");
        if !glsl && !rel.ends_with(".rs") {
            continue;
        }
        let limit = if glsl { GLSL_LIMIT } else { RUST_LIMIT };
        let text = std::fs::read_to_string(&path).unwrap();
        // Functions of one name in one file (several `new`s) are held by the longest.
        let mut longest: Vec<(String, usize)> = Vec::new();
        for (name, len) in functions(&text, glsl) {
            match longest.iter_mut().find(|(n, _)| *n == name) {
                Some(e) => e.1 = e.1.max(len),
                None => longest.push((name, len)),
            }
        }
        for (name, len) in longest {
            let listed = OVER.iter().find(|(f, n, _)| *f == rel && *n == name);
            match listed {
                Some(&(_, _, was)) => {
                    found.push((rel.clone(), name.clone()));
                    if len > was {
                        problems.push(format!("{rel}: {name} grew to {len} lines (listed at {was}; limit {limit})"));
                    } else if len <= limit {
                        problems
                            .push(format!("{rel}: {name} is {len} lines now, within {limit}: take it off the list"));
                    }
                }
                None if len > limit => problems.push(format!("{rel}: {name} is {len} lines, over {limit}: split it")),
                None => {}
            }
        }
    }
    for (file, name, _) in OVER {
        if !found.iter().any(|(f, n)| f == file && n == name) {
            problems.push(format!("{file}: {name} is listed but not found: take it off the list"));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn the_scanner_measures_what_it_should() {
    let rust = "pub fn a() {\n    let s = \"}\";\n    let c = '{';\n}\nfn b<'x>(v: &'x str) -> &'x str {\n    v\n}\n";
    assert_eq!(functions(rust, false), vec![("a".to_string(), 4), ("b".to_string(), 3)]);
    let glsl = "vec3 f(vec3 p);\nvec3 f(vec3 p) {\n    if (p.x > 0.0) { return p; } // }\n    return -p;\n}\n";
    assert_eq!(functions(glsl, true), vec![("f".to_string(), 4)]);
}

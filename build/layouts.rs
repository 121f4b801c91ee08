//! The build's binding checks. A pipeline's descriptor layout is reflected from its SPIR-V when it is created
//! (src/vk/pipeline.rs), so the shaders are the layout's only source; what the build checks is how they name it:
//! - every `binding =` in glsl/ names a constant of src/shader_consts.rs, never a number, so that the Rust pass
//!   binds each resource by the same name (`ordered([(XB_NAME, use), ...])`);
//! - the constant names what the declaration does: `binding = WA_HEIGHTS` declares `Heights` (a block's name, or a
//!   variable's without its `t_`, `o_` or `u_`), so that two bindings swapped on one side fail the build
//!   ([`names_agree`]);
//! - a shader names the constants of one family (one prefix, `XB_`), the family of the passes that share them;
//! - every shader of a family declares a binding with one kind: a variant that reads it through a texel view
//!   where the others load a storage buffer or sample an image is the one allowed difference.

use super::spirv::{Descriptor, Module};
use std::collections::HashMap;
use std::path::Path;

/// The text of a GLSL file and of every file it includes (resolved against glsl/), once each.
pub fn with_includes(glsl: &Path, file: &Path, seen: &mut Vec<std::path::PathBuf>) -> String {
    if seen.iter().any(|s| s == file) {
        return String::new();
    }
    seen.push(file.to_path_buf());
    let text = std::fs::read_to_string(file).unwrap_or_default();
    let mut all = text.clone();
    for line in text.lines() {
        if let Some(inc) = line.trim().strip_prefix("#include \"").and_then(|l| l.strip_suffix('"')) {
            all.push_str(&with_includes(glsl, &glsl.join(inc), seen));
        }
    }
    all
}

/// Abbreviations a declaration may use for a word of its constant.
const ABBREVIATIONS: &[(&str, &str)] = &[("recv", "receivers"), ("irr", "irradiance"), ("lin", "linear")];

/// The words of a name (`snake_case`, `CamelCase` or `UPPER_CASE`; digits are words of their own), lowercase,
/// abbreviations spelled out, each without a plural `s`, and without the container words a declaration adds
/// (`Buf`, `Ubo`, `texels`) at its end.
fn words(name: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let mut word = String::new();
    let mut prev: Option<char> = None;
    for c in name.chars() {
        let split = c == '_'
            || prev.is_some_and(|p| {
                (p.is_ascii_lowercase() && c.is_ascii_uppercase()) || (p.is_ascii_digit() != c.is_ascii_digit())
            });
        if split && !word.is_empty() {
            out.push(std::mem::take(&mut word));
        }
        if c != '_' {
            word.push(c.to_ascii_lowercase());
        }
        prev = Some(c);
    }
    if !word.is_empty() {
        out.push(word);
    }
    while out.last().is_some_and(|w| ["buf", "ubo", "texels"].contains(&w.as_str())) {
        out.pop();
    }
    out.iter()
        .map(|w| {
            let w = ABBREVIATIONS.iter().find(|(a, _)| a == w).map_or(w.as_str(), |(_, full)| full);
            w.strip_suffix('s').filter(|s| !s.is_empty()).unwrap_or(w).to_string()
        })
        .collect()
}

/// A binding constant's family (`WA_`) and the rest of its name (`HEIGHTS`).
fn family_split(constant: &str) -> (String, &str) {
    let (family, rest) = constant.split_once('_').unwrap_or((constant, ""));
    (format!("{family}_"), rest)
}

/// Whether the constant `constant` (its family prefix included) names the declaration `declared`: the same words
/// ([`words`]) once the family and the declaration's `t_`, `o_` or `u_` are left off.
pub fn names_agree(constant: &str, declared: &str) -> bool {
    let (_, suffix) = family_split(constant);
    let declared = ["t_", "o_", "u_"].iter().find_map(|p| declared.strip_prefix(p)).unwrap_or(declared);
    words(suffix) == words(declared)
}

/// The name a declaration's line gives (after its `layout(...)`): a block's name (`buffer Heights { ... };`), or
/// else the variable's (`uniform usampler2D t_recv;`).
fn declared_name(line: &str) -> Option<String> {
    let ident = |t: &str| t.chars().rev().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect::<String>();
    let rest = &line[line.find("layout(")?..];
    let rest = &rest[rest.find(')')? + 1..];
    let end = rest.find('{').or_else(|| rest.find(';'))?;
    let name: String = ident(rest[..end].trim_end()).chars().rev().collect();
    (!name.is_empty()).then_some(name)
}

/// The names `binding = NAME` gives in `text` (the file `file`), each with its line; a number, or a name that is no
/// shader constant, or one that does not name what its line declares, is refused with its line.
pub fn binding_names(file: &str, text: &str, consts: &HashMap<String, u32>) -> Result<Vec<(usize, String)>, String> {
    let mut names = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let code = line.split("//").next().unwrap_or_default();
        let Some(at) = code.find("binding") else { continue };
        let Some(rest) = code[at + "binding".len()..].trim_start().strip_prefix('=') else { continue };
        let name: String = rest.trim_start().chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
        if name.is_empty() || name.starts_with(|c: char| c.is_ascii_digit()) {
            return Err(format!(
                "{file}:{}: `binding = {name}`: a binding is named by a constant of src/shader_consts.rs, which the \
                 pass binds by too",
                n + 1
            ));
        }
        if !consts.contains_key(&name) {
            return Err(format!("{file}:{}: `{name}` is not a constant of src/shader_consts.rs", n + 1));
        }
        if let Some(declared) = declared_name(code) {
            if !names_agree(&name, &declared) {
                return Err(format!(
                    "{file}:{}: binding `{name}` (src/shader_consts.rs) declares `{declared}` here: the constant and \
                     the declaration name one resource, so that the pass binds by it what the shader reads",
                    n + 1
                ));
            }
        }
        names.push((n + 1, name));
    }
    Ok(names)
}

/// The constant family (`XB_`) a shader's source and its includes bind by, if it declares descriptors.
pub fn family_of(shader: &str, text: &str, consts: &HashMap<String, u32>) -> Result<Option<String>, String> {
    let mut family: Option<String> = None;
    for (_, name) in binding_names(shader, text, consts)? {
        let (prefix, _) = family_split(&name);
        match &family {
            Some(f) if *f != prefix => {
                return Err(format!("{shader}: binds by the constants of two families, {f} and {prefix}"));
            }
            _ => family = Some(prefix),
        }
    }
    Ok(family)
}

/// Whether two shaders' declarations of one binding agree: the same kind, or a texel buffer where the other reads
/// a storage buffer or samples an image (a variant that gathers through texels what the others load or sample:
/// the wide BVH layout's, the resolve of the compute splat's flux texels).
fn agree(a: Descriptor, b: Descriptor) -> bool {
    use Descriptor::*;
    a == b || matches!((a, b), (Storage | Sampled, UniformTexel) | (UniformTexel, Storage | Sampled))
}

/// What the shaders of each family declare at each binding, as the build meets them.
#[derive(Default)]
pub struct Families {
    /// (family, binding) → the kind, and the shader and variable that declared it first.
    seen: HashMap<(String, u32), (Descriptor, String, String)>,
}

impl Families {
    /// Adds a compiled shader of `family`; refuses a binding it declares with another kind than an earlier shader
    /// of the family, or outside set 0.
    pub fn check(&mut self, shader: &str, family: &str, words: &[u32]) -> Result<(), String> {
        let module = Module::parse(words).map_err(|e| format!("{shader}: {e}"))?;
        for (&(set, binding), (declared, var)) in &module.bindings {
            if set != 0 {
                return Err(format!("{shader}: `{var}` is in set {set}: every binding is in set 0"));
            }
            let key = (family.to_string(), binding);
            match self.seen.get(&key) {
                Some((kind, first, first_var)) if !agree(*kind, *declared) => {
                    return Err(format!(
                        "{shader}: `{var}` is binding {binding} of {family} as a {declared:?} descriptor; {first} \
                         declares it (`{first_var}`) as {kind:?}"
                    ));
                }
                Some(_) => {}
                None => {
                    self.seen.insert(key, (*declared, shader.to_string(), var.clone()));
                }
            }
        }
        Ok(())
    }
}

//! The binding check: each compiled shader's descriptors, reflected from its SPIR-V, against the Rust declaration
//! of the layout it binds by. A shared layout is a table `const NAME: [(u32, BindKind); N] = [(XB_NAME,
//! BindKind::Kind), ...]` in a pass's source, and a shader binds by it when it (or a file it includes) names its
//! constants (`binding = XB_...`). A shader that declares a binding the table lacks, or with another kind, fails the
//! build. Pipelines with a layout of their own (a few bindings, written at the pipeline) are checked when they are
//! created (src/vk/pipeline.rs), as every pipeline is against the device's limits.

use super::spirv::{Descriptor, Module};
use std::collections::HashMap;
use std::path::Path;

/// (binding-constant prefix, the Rust file, its table).
pub const LAYOUTS: &[(&str, &str, &str)] = &[
    ("PB_", "src/passes/photons.rs", "LAYOUT"),
    ("CB_", "src/passes/composite.rs", "LAYOUT"),
    ("EB_", "src/passes/eye.rs", "SHADE_LAYOUT"),
];

/// A declared layout: binding → kind (`Uniform`, `Storage`, `Sampled`, `StorageImage`, `Texels`).
pub struct Layout {
    pub prefix: &'static str,
    pub origin: String,
    pub kinds: HashMap<u32, String>,
}

/// Reads table `name` of `text` (the file `file`).
pub fn parse(
    file: &str,
    text: &str,
    name: &str,
    consts: &HashMap<String, u32>,
) -> Result<HashMap<u32, String>, String> {
    let head = format!("const {name}: [(u32, BindKind);");
    let (start, _) = text
        .lines()
        .enumerate()
        .find(|(_, l)| l.trim_start().starts_with(&head))
        .ok_or_else(|| format!("{file}: no `{head}` table"))?;
    let mut kinds = HashMap::new();
    for (n, line) in text.lines().enumerate().skip(start + 1) {
        let line = line.trim();
        if line == "];" {
            return Ok(kinds);
        }
        let at = |m: String| format!("{file}:{}: {m}", n + 1);
        let entry = line
            .strip_prefix('(')
            .and_then(|l| l.strip_suffix("),"))
            .ok_or_else(|| at(format!("a layout entry reads `(XB_NAME, BindKind::Kind),`: `{line}`")))?;
        let (constant, kind) = entry.split_once(',').ok_or_else(|| at(format!("no kind in `{line}`")))?;
        let binding =
            *consts.get(constant.trim()).ok_or_else(|| at(format!("`{constant}` is not a shader constant")))?;
        let kind = kind.trim().strip_prefix("BindKind::").ok_or_else(|| at(format!("`{kind}`: not a BindKind")))?;
        if kinds.insert(binding, kind.to_string()).is_some() {
            return Err(at(format!("binding {binding} is declared twice")));
        }
    }
    Err(format!("{file}: table {name} has no end"))
}

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

/// The layout a shader's source binds by, if it names one's constants (and only one's).
pub fn layout_of<'a>(shader: &str, text: &str, layouts: &'a [Layout]) -> Result<Option<&'a Layout>, String> {
    let named: Vec<&Layout> = layouts.iter().filter(|l| text.contains(&format!("binding = {}", l.prefix))).collect();
    match named.as_slice() {
        [] => Ok(None),
        [one] => Ok(Some(one)),
        _ => Err(format!("{shader}: binds by several layouts' constants")),
    }
}

/// Whether a descriptor the shader declares fits the layout's kind. A storage buffer may be read through its texel
/// view: the pass then binds it as `Texels` for that build (src/vk/pipeline.rs, `with_texels`).
fn fits(declared: Descriptor, kind: &str) -> bool {
    matches!(
        (declared, kind),
        (Descriptor::Uniform, "Uniform")
            | (Descriptor::Storage, "Storage")
            | (Descriptor::Sampled, "Sampled")
            | (Descriptor::StorageImage, "StorageImage")
            | (Descriptor::UniformTexel, "Texels" | "Storage")
    )
}

/// Checks every descriptor a compiled shader declares against its layout.
pub fn check(shader: &str, words: &[u32], layout: &Layout) -> Result<(), String> {
    let module = Module::parse(words).map_err(|e| format!("{shader}: {e}"))?;
    for (&(set, binding), (declared, var)) in &module.bindings {
        let kind = layout.kinds.get(&binding).filter(|_| set == 0);
        if !kind.is_some_and(|k| fits(*declared, k)) {
            return Err(format!(
                "{shader}: `{var}` is set {set}, binding {binding}, a {declared:?} descriptor; {} has {}",
                layout.origin,
                kind.map_or("nothing there".to_string(), |k| format!("BindKind::{k}"))
            ));
        }
    }
    Ok(())
}

//! The GPU structs, written once in Rust, turned into GLSL.
//!
//! Every `#[repr(C)]` struct of the listed Rust files is a GPU struct. This module parses their declarations (one
//! field per line, the types below) and writes:
//! - `gpu_structs.glsl`: the same structs in GLSL, with the Rust doc comments, for the shaders to include;
//! - `gpu_layout.rs`: the byte offset of every field and every struct's size, asserted against the Rust types;
//! - the layouts the SPIR-V check ([`check_spirv`]) compares each compiled shader's struct decorations with.
//!
//! Field types: `f32`, `u32`, `i32`; `[T; 2]` and `[T; 4]` of those (`vec2`, `uvec4`, ...); `[f32; 3]` (`vec3`,
//! which a scalar may follow in its last four bytes, but no array may hold); `[f32; 16]` (`mat4`);
//! another GPU struct; and arrays `[T; N]` of any of these, where N may name constants of src/shader_consts.rs.
//! A field that GLSL would place at another offset than Rust (std430 or std140) fails the build.

use std::collections::HashMap;
use std::fmt::Write as _;

/// The Rust files whose `#[repr(C)]` structs are the GPU structs, with their module paths.
pub const SOURCES: &[(&str, &str)] = &[("src/gpu_types.rs", "crate::gpu_types"), ("src/bvh/records.rs", "crate::bvh")];

/// The constants of src/shader_consts.rs (`text`), as (name, value as written): the macros build.rs passes to
/// GLSL.
pub fn shader_consts(text: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for line in text.lines() {
        if let Some(rest) = line.trim().strip_prefix("pub const ") {
            let (name, rest) = rest.split_once(':').expect("const NAME: type = value;");
            let value = rest.split_once('=').expect("= value").1.trim().trim_end_matches(';').trim();
            out.push((name.trim().to_string(), value.to_string()));
        }
    }
    out
}

/// The values of [`shader_consts`]' constants (a value may name the constants before it).
pub fn const_values(consts: &[(String, String)]) -> Result<HashMap<String, u32>, String> {
    let mut values = HashMap::new();
    for (k, v) in consts {
        let value = eval(v, &values).map_err(|e| format!("src/shader_consts.rs: {k}: {e}"))?;
        values.insert(k.clone(), value);
    }
    Ok(values)
}

/// One field: its GLSL type, name, array length (expression as GLSL reads it, and its value), offset and doc.
pub struct Field {
    pub glsl_type: String,
    pub name: String,
    pub array: Option<(String, u32)>,
    pub offset: u32,
    /// Bytes of one element (of the array, if any).
    pub elem_size: u32,
    pub doc: Vec<String>,
}

pub struct Struct {
    pub name: String,
    pub rust_path: String,
    pub doc: Vec<String>,
    pub fields: Vec<Field>,
    /// Bytes in Rust: where its last field ends (GLSL rounds it up to `align` where it is an array element or a
    /// member of another struct; [`parse`] refuses those uses unless it is a multiple already).
    pub size: u32,
    /// The largest member alignment std430 gives it.
    pub align: u32,
}

/// (GLSL type, size, std430 alignment) of a Rust leaf type.
fn leaf(ty: &str) -> Option<(&'static str, u32, u32)> {
    Some(match ty {
        "f32" => ("float", 4, 4),
        "u32" => ("uint", 4, 4),
        "i32" => ("int", 4, 4),
        "[f32;2]" => ("vec2", 8, 8),
        "[u32;2]" => ("uvec2", 8, 8),
        "[i32;2]" => ("ivec2", 8, 8),
        "[f32;3]" => ("vec3", 12, 16),
        "[f32;4]" => ("vec4", 16, 16),
        "[u32;4]" => ("uvec4", 16, 16),
        "[i32;4]" => ("ivec4", 16, 16),
        "[f32;16]" => ("mat4", 64, 16),
        _ => return None,
    })
}

/// Evaluates an array length: integers, constants, `+ - * /`, parentheses, and `as usize` (ignored).
pub fn eval(expr: &str, consts: &HashMap<String, u32>) -> Result<u32, String> {
    let tokens: Vec<String> = {
        let mut t = Vec::new();
        let mut cur = String::new();
        for c in expr.chars() {
            if c.is_alphanumeric() || c == '_' {
                cur.push(c);
            } else {
                if !cur.is_empty() {
                    t.push(std::mem::take(&mut cur));
                }
                if !c.is_whitespace() {
                    t.push(c.to_string());
                }
            }
        }
        if !cur.is_empty() {
            t.push(cur);
        }
        // `as usize` converts, which here changes nothing.
        let mut out = Vec::new();
        let mut i = 0;
        while i < t.len() {
            if t[i] == "as" {
                i += 2;
            } else {
                out.push(t[i].clone());
                i += 1;
            }
        }
        out
    };
    fn sum(t: &[String], i: &mut usize, c: &HashMap<String, u32>) -> Result<u32, String> {
        let mut v = product(t, i, c)?;
        while let Some(op) = t.get(*i).filter(|s| *s == "+" || *s == "-").cloned() {
            *i += 1;
            let r = product(t, i, c)?;
            v = if op == "+" { v + r } else { v - r };
        }
        Ok(v)
    }
    fn product(t: &[String], i: &mut usize, c: &HashMap<String, u32>) -> Result<u32, String> {
        let mut v = atom(t, i, c)?;
        while let Some(op) = t.get(*i).filter(|s| *s == "*" || *s == "/").cloned() {
            *i += 1;
            let r = atom(t, i, c)?;
            v = if op == "*" { v * r } else { v / r };
        }
        Ok(v)
    }
    fn atom(t: &[String], i: &mut usize, c: &HashMap<String, u32>) -> Result<u32, String> {
        let tok = t.get(*i).ok_or("unexpected end")?.clone();
        *i += 1;
        if tok == "(" {
            let v = sum(t, i, c)?;
            if t.get(*i).map(String::as_str) != Some(")") {
                return Err("missing )".into());
            }
            *i += 1;
            Ok(v)
        } else if let Ok(n) = tok.parse::<u32>() {
            Ok(n)
        } else {
            c.get(&tok).copied().ok_or(format!("unknown constant {tok}"))
        }
    }
    let mut i = 0;
    let v = sum(&tokens, &mut i, consts)?;
    if i != tokens.len() {
        return Err(format!("cannot read `{expr}`"));
    }
    Ok(v)
}

/// The GLSL spelling of an array length written in Rust.
fn glsl_length(expr: &str) -> String {
    expr.replace(" as usize", "").trim().to_string()
}

/// Splits `[T; N]` into `T` and `N` (at the top level).
fn split_array(ty: &str) -> Option<(&str, &str)> {
    let inner = ty.strip_prefix('[')?.strip_suffix(']')?;
    let mut depth = 0;
    for (i, c) in inner.char_indices() {
        match c {
            '[' | '(' => depth += 1,
            ']' | ')' => depth -= 1,
            ';' if depth == 0 => return Some((inner[..i].trim(), inner[i + 1..].trim())),
            _ => {}
        }
    }
    None
}

fn round_up(x: u32, a: u32) -> u32 {
    x.div_ceil(a) * a
}

/// Parses the GPU structs of `text` (the Rust file `file`, whose module path is `module`).
pub fn parse(
    file: &str,
    module: &str,
    text: &str,
    consts: &HashMap<String, u32>,
    known: &mut Vec<Struct>,
) -> Result<(), String> {
    let mut doc: Vec<String> = Vec::new();
    let mut repr_c = false;
    let mut current: Option<Struct> = None;
    for (n, raw) in text.lines().enumerate() {
        let line = raw.trim();
        let at = |msg: String| format!("{file}:{}: {msg}", n + 1);
        if let Some(d) = line.strip_prefix("///") {
            doc.push(d.strip_prefix(' ').unwrap_or(d).to_string());
            continue;
        }
        if let Some(s) = current.as_mut() {
            if line == "}" {
                known.push(current.take().unwrap());
                doc.clear();
                continue;
            }
            if line.is_empty() || line.starts_with("//") {
                continue;
            }
            let body = line
                .strip_prefix("pub ")
                .and_then(|l| l.strip_suffix(','))
                .ok_or_else(|| at(format!("a GPU struct's field must read `pub name: Type,`: `{line}`")))?;
            let (name, ty) = body.split_once(':').ok_or_else(|| at(format!("no type in `{line}`")))?;
            let ty = ty.trim();
            let (elem, array) = match leaf(&ty.replace(' ', "")) {
                Some(_) => (ty.to_string(), None),
                None => match split_array(ty) {
                    Some((e, len)) => {
                        let v = eval(len, consts).map_err(|e| at(format!("array length `{len}`: {e}")))?;
                        (e.to_string(), Some((glsl_length(len), v)))
                    }
                    None => (ty.to_string(), None),
                },
            };
            let (glsl_type, elem_size, align) = match leaf(&elem.replace(' ', "")) {
                Some((g, size, align)) => (g.to_string(), size, align),
                None => {
                    let inner = known
                        .iter()
                        .find(|k| k.name == elem)
                        .ok_or_else(|| at(format!("`{elem}` is not a GPU type (declare it above, #[repr(C)])")))?;
                    if inner.size % inner.align != 0 {
                        return Err(at(format!(
                            "`{elem}` ends at byte {} but GLSL rounds it to {} bytes: pad it to use it inside another",
                            inner.size,
                            round_up(inner.size, inner.align)
                        )));
                    }
                    (inner.name.clone(), inner.size, inner.align)
                }
            };
            // std430: an array's stride is its element's size rounded to its alignment; Rust packs it at the size.
            if array.is_some() && elem_size % align != 0 {
                return Err(at(format!("`{name}`: an array of {glsl_type} has another stride in GLSL")));
            }
            if s.size % align != 0 {
                return Err(at(format!(
                    "`{}` would be at byte {} in Rust but aligned to {align} in GLSL: add padding before it",
                    name.trim(),
                    s.size
                )));
            }
            let count = array.as_ref().map_or(1, |a| a.1);
            s.fields.push(Field {
                glsl_type,
                name: name.trim().to_string(),
                array,
                offset: s.size,
                elem_size,
                doc: std::mem::take(&mut doc),
            });
            s.size += elem_size * count;
            s.align = s.align.max(align);
            continue;
        }
        if line == "#[repr(C)]" {
            repr_c = true;
            continue;
        }
        if line.starts_with("#[") {
            continue;
        }
        if let Some(rest) = line.strip_prefix("pub struct ") {
            if repr_c {
                let name = rest.trim_end_matches('{').trim().to_string();
                current = Some(Struct {
                    rust_path: format!("{module}::{name}"),
                    name,
                    doc: std::mem::take(&mut doc),
                    fields: Vec::new(),
                    size: 0,
                    align: 4,
                });
            }
        }
        repr_c = false;
        doc.clear();
    }
    Ok(())
}

/// The GPU structs that travel as `uvec4` words, in queues a pass may read as texels (a ray queue): build.rs writes
/// `T T_from_words(uvec4 w0, ...)` and `void T_to_words(T v, out uvec4 w0, ...)` for each, so that the packing
/// follows the one definition. Each must be a whole number of 16-byte words of 4-byte scalars and vectors.
pub const WORD_STRUCTS: &[&str] = &["GpuRay", "GpuRayMedium"];

/// The components of a field of a word struct: (the GLSL type of its bits, components, whether they are floats).
fn word_components(glsl_type: &str) -> Option<(&'static str, u32, bool)> {
    Some(match glsl_type {
        "float" => ("uint", 1, true),
        "uint" => ("uint", 1, false),
        "vec2" => ("uvec2", 2, true),
        "uvec2" => ("uvec2", 2, false),
        "vec3" => ("uvec3", 3, true),
        "vec4" => ("uvec4", 4, true),
        "uvec4" => ("uvec4", 4, false),
        _ => return None,
    })
}

/// The word packers of [`WORD_STRUCTS`] (GLSL), or why a struct cannot be one.
pub fn word_functions(s: &Struct) -> Result<String, String> {
    if !s.size.is_multiple_of(16) {
        return Err(format!("{}: {} bytes are not whole 16-byte words", s.name, s.size));
    }
    let words = s.size / 16;
    let word = |byte: u32| format!("w{}.{}", byte / 16, ["x", "y", "z", "w"][(byte % 16 / 4) as usize]);
    let params: Vec<String> = (0..words).map(|i| format!("uvec4 w{i}")).collect();
    let outs: Vec<String> = (0..words).map(|i| format!("out uvec4 w{i}")).collect();
    let mut from = format!(
        "{0} {0}_from_words({1}) {{
    {0} v;
",
        s.name,
        params.join(", ")
    );
    let mut to = format!(
        "void {}_to_words({} v, {}) {{
",
        s.name,
        s.name,
        outs.join(", ")
    );
    for i in 0..words {
        writeln!(to, "    w{i} = uvec4(0u);").unwrap();
    }
    for f in &s.fields {
        let (ctor, n, float) = word_components(&f.glsl_type)
            .filter(|_| f.array.is_none())
            .ok_or_else(|| format!("{}.{}: a word struct holds 4-byte scalars and vectors only", s.name, f.name))?;
        let parts: Vec<String> = (0..n).map(|c| word(f.offset + 4 * c)).collect();
        let bits = if n == 1 { parts[0].clone() } else { format!("{ctor}({})", parts.join(", ")) };
        let value = if float { format!("uintBitsToFloat({bits})") } else { bits };
        writeln!(from, "    v.{} = {value};", f.name).unwrap();
        for (c, part) in parts.iter().enumerate() {
            let comp = if n == 1 { format!("v.{}", f.name) } else { format!("v.{}[{c}]", f.name) };
            let comp = if float { format!("floatBitsToUint({comp})") } else { comp };
            writeln!(to, "    {part} = {comp};").unwrap();
        }
    }
    from.push_str(
        "    return v;
}
",
    );
    to.push_str(
        "}
",
    );
    Ok(format!("// {} as {words} uvec4 words (WORD_STRUCTS, build/structs.rs).\n{from}{to}", s.name))
}

/// The GLSL declarations of `structs`.
pub fn glsl(structs: &[Struct], sources: &[&str]) -> String {
    let mut out = format!(
        "// Generated by build.rs from {}: edit the Rust structs, not this file.\n\
         #ifndef GPU_STRUCTS_GLSL\n#define GPU_STRUCTS_GLSL\n",
        sources.join(" and ")
    );
    for s in structs {
        out.push('\n');
        for d in &s.doc {
            writeln!(out, "// {d}").unwrap();
        }
        writeln!(out, "struct {} {{  // {} bytes", s.name, s.size).unwrap();
        for f in &s.fields {
            for d in &f.doc {
                writeln!(out, "    // {d}").unwrap();
            }
            let array = f.array.as_ref().map(|(e, _)| format!("[{e}]")).unwrap_or_default();
            writeln!(out, "    {} {}{array};  // byte {}", f.glsl_type, f.name, f.offset).unwrap();
        }
        out.push_str("};\n");
        if WORD_STRUCTS.contains(&s.name.as_str()) {
            out.push_str(&word_functions(s).unwrap_or_else(|e| panic!("build/structs.rs WORD_STRUCTS: {e}")));
        }
    }
    out.push_str("#endif\n");
    out
}

/// Rust asserts of every offset and size.
pub fn rust_asserts(structs: &[Struct]) -> String {
    let mut out =
        String::from("// Generated by build.rs: the layouts gpu_structs.glsl was written for.\nconst _: () = {\n");
    for s in structs {
        writeln!(out, "    assert!(::std::mem::size_of::<{}>() == {});", s.rust_path, s.size).unwrap();
        for f in &s.fields {
            writeln!(out, "    assert!(::std::mem::offset_of!({}, {}) == {});", s.rust_path, f.name, f.offset).unwrap();
        }
    }
    out.push_str("};\n");
    out
}

/// Compares the struct layouts a compiled shader decorates with the Rust ones: every member's offset and every
/// array's stride, in each struct type named like a GPU struct (glslang keeps one per layout it is used in).
pub fn check_spirv(shader: &str, words: &[u32], structs: &[Struct]) -> Result<(), String> {
    let m = super::spirv::Module::parse(words).map_err(|e| format!("{shader}: {e}"))?;
    for (&id, members) in &m.struct_members {
        let Some(name) = m.names.get(&id) else { continue };
        let Some(s) = structs.iter().find(|s| &s.name == name) else { continue };
        let offsets = m.member_offsets.get(&id);
        if members.len() != s.fields.len() {
            return Err(format!(
                "{shader}: struct {name} has {} members in SPIR-V, {} in Rust",
                members.len(),
                s.fields.len()
            ));
        }
        let Some(offsets) = offsets else { continue };
        for (k, f) in s.fields.iter().enumerate() {
            if let Some(&o) = offsets.get(&(k as u32)) {
                if o != f.offset {
                    return Err(format!("{shader}: {name}.{} is at byte {o} in SPIR-V, {} in Rust", f.name, f.offset));
                }
            }
            if f.array.is_some() {
                if let Some(&stride) = m.array_strides.get(&members[k]) {
                    if stride != f.elem_size {
                        return Err(format!(
                            "{shader}: {name}.{} has an array stride of {stride} bytes in SPIR-V, {} in Rust \
                             (std140 rounds array elements up to 16 bytes)",
                            f.name, f.elem_size
                        ));
                    }
                }
            }
        }
    }
    Ok(())
}

/// Checks that every specialization constant of a GLSL source, `layout(constant_id = ...) const TYPE NAME`, takes
/// its ID from src/shader_consts.rs's `NAME_ID` (written so), by which the passes specialize it. (The SPIR-V's
/// names cannot tell: the optimizer renames a constant after a local it was copied into.)
pub fn check_spec_ids(file: &str, text: &str, consts: &HashMap<String, u32>) -> Result<(), String> {
    for (n, line) in text.lines().enumerate() {
        let Some(rest) = line.split("constant_id").nth(1) else { continue };
        let at = |msg: String| format!("{file}:{}: {msg}", n + 1);
        let id = rest.trim_start().trim_start_matches('=').split(')').next().unwrap_or("").trim();
        let name = rest.split(" const ").nth(1).and_then(|d| d.split_whitespace().nth(1)).unwrap_or("");
        if name.is_empty() {
            return Err(at(format!("cannot read the specialization constant in `{}`", line.trim())));
        }
        let want = format!("{name}_ID");
        if id != want || !consts.contains_key(&want) {
            return Err(at(format!(
                "specialization constant {name} must take constant_id = {want}, defined in src/shader_consts.rs \
                 (the passes specialize it by the same constant)"
            )));
        }
    }
    Ok(())
}

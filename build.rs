//! Compiles every GLSL shader in glsl/ to SPIR-V with shaderc (glslang) at build time.
//!
//! - `#include "common/x.glsl"` resolves against glsl/.
//! - Every constant of src/shader_consts.rs is passed as a macro, so Rust and GLSL share one definition.
//! - Some shaders are compiled in several variants with extra macros (see VARIANTS).
//! - A compile error fails the build with the file, the line and glslang's message.
//!
//! - Every binding is named by a constant of src/shader_consts.rs, and the shaders of one constant family agree on
//!   each binding's kind (build/layouts.rs); pipelines reflect their layouts from the SPIR-V (src/vk/pipeline.rs).
//! - The GPU structs are written once, in Rust (structs::SOURCES: src/gpu_types.rs, src/bvh/records.rs): build/structs.rs writes
//!   their GLSL (`#include "generated/gpu_structs.glsl"`) and asserts their offsets on both sides, in Rust and in
//!   every compiled shader's SPIR-V.
//!
//! The output is `$OUT_DIR/shaders.rs`, included by src/shaders.rs: one aligned `&[u32]` per shader variant, and
//! `$OUT_DIR/gpu_layout.rs`, included by src/gpu_types.rs.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

#[path = "build/layouts.rs"]
mod layouts;
#[path = "build/spirv.rs"]
mod spirv;
#[path = "build/structs.rs"]
mod structs;

#[allow(dead_code)]
mod consts {
    include!("src/shader_consts.rs");
}

/// A macro definition: (name, value).
type Define = (&'static str, &'static str);

/// (source file, variant suffix, extra macros).
const VARIANTS: &[(&str, &str, &[Define])] = &[
    ("water.comp", "bvh", &[("WATER_BVH", "1")]),
    ("morph.comp", "bvh", &[("MORPH_BVH", "1")]),
    ("traverse.comp", "max_error_wg1", &[("TRAVERSE_WG_SIDE", "1"), ("TRAVERSE_METRIC", "METRIC_MAX_ERROR")]),
    ("traverse.comp", "max_error_wg2", &[("TRAVERSE_WG_SIDE", "2"), ("TRAVERSE_METRIC", "METRIC_MAX_ERROR")]),
    ("traverse.comp", "max_error_wg4", &[("TRAVERSE_WG_SIDE", "4"), ("TRAVERSE_METRIC", "METRIC_MAX_ERROR")]),
    ("traverse.comp", "max_error_wg8", &[("TRAVERSE_WG_SIDE", "8"), ("TRAVERSE_METRIC", "METRIC_MAX_ERROR")]),
    ("traverse.comp", "max_error_wg16", &[("TRAVERSE_WG_SIDE", "16"), ("TRAVERSE_METRIC", "METRIC_MAX_ERROR")]),
    ("traverse.comp", "flux_error_wg1", &[("TRAVERSE_WG_SIDE", "1"), ("TRAVERSE_METRIC", "METRIC_FLUX_ERROR")]),
    ("traverse.comp", "flux_error_wg2", &[("TRAVERSE_WG_SIDE", "2"), ("TRAVERSE_METRIC", "METRIC_FLUX_ERROR")]),
    ("traverse.comp", "flux_error_wg4", &[("TRAVERSE_WG_SIDE", "4"), ("TRAVERSE_METRIC", "METRIC_FLUX_ERROR")]),
    ("traverse.comp", "flux_error_wg8", &[("TRAVERSE_WG_SIDE", "8"), ("TRAVERSE_METRIC", "METRIC_FLUX_ERROR")]),
    ("traverse.comp", "flux_error_wg16", &[("TRAVERSE_WG_SIDE", "16"), ("TRAVERSE_METRIC", "METRIC_FLUX_ERROR")]),
    (
        "traverse.comp",
        "max_error_coop",
        &[("TRAVERSE_WG_SIDE", "8"), ("TRAVERSE_METRIC", "METRIC_MAX_ERROR"), ("TRAVERSE_COOP", "1")],
    ),
    (
        "traverse.comp",
        "flux_error_coop",
        &[("TRAVERSE_WG_SIDE", "8"), ("TRAVERSE_METRIC", "METRIC_FLUX_ERROR"), ("TRAVERSE_COOP", "1")],
    ),
    ("traverse.comp", "max_level_wg1", &[("TRAVERSE_WG_SIDE", "1"), ("TRAVERSE_MAX_LEVEL", "1")]),
    ("traverse.comp", "max_level_wg2", &[("TRAVERSE_WG_SIDE", "2"), ("TRAVERSE_MAX_LEVEL", "1")]),
    ("traverse.comp", "max_level_wg4", &[("TRAVERSE_WG_SIDE", "4"), ("TRAVERSE_MAX_LEVEL", "1")]),
    ("traverse.comp", "max_level_wg8", &[("TRAVERSE_WG_SIDE", "8"), ("TRAVERSE_MAX_LEVEL", "1")]),
    ("traverse.comp", "max_level_wg16", &[("TRAVERSE_WG_SIDE", "16"), ("TRAVERSE_MAX_LEVEL", "1")]),
    ("wave.comp", "single", &[("BVH_LAYOUT_SINGLE", "1")]),
    ("wave.comp", "threaded", &[("BVH_LAYOUT_THREADED", "1")]),
    ("wave.comp", "wide", &[("BVH_LAYOUT_WIDE", "1")]),
    ("splat.comp", "tiled", &[("SPLAT_TILED", "1")]),
    ("resolve.comp", "texels", &[("RESOLVE_TEXELS", "1")]),
    ("geometry.frag", "aux", &[("WITH_AUX", "1")]),
    ("geometry.frag", "albedo", &[("WITH_ALBEDO", "1")]),
    ("geometry.vert", "albedo", &[("WITH_ALBEDO", "1")]),
    ("eye_shade.comp", "aovs", &[("WITH_AOVS", "1")]),
    ("composite.comp", "exact", &[("EXACT_EYE", "1")]),
    ("composite.comp", "single", &[("SINGLE_SAMPLE", "1")]),
    ("composite.comp", "exact_single", &[("EXACT_EYE", "1"), ("SINGLE_SAMPLE", "1")]),
    ("glass.comp", "wide", &[("BVH_LAYOUT_WIDE", "1")]),
    ("geometry.vert", "aux", &[("WITH_AUX", "1")]),
    ("geometry.vert", "depth", &[("DEPTH_ONLY", "1")]),
];

/// Sources that are compiled only in their VARIANTS.
const VARIANTS_ONLY: &[&str] = &["traverse.comp"];

/// Sources each of whose builds is compiled once more walking the wide BVH layout (suffix `_WIDE`, with
/// BVH_LAYOUT_WIDE): the traversal checks trace the layout the waves trace.
const WIDE_TOO: &[&str] = &["traverse.comp"];

fn shared_macros() -> Vec<(String, String)> {
    let text = std::fs::read_to_string("src/shader_consts.rs").expect("read src/shader_consts.rs");
    let out = structs::shader_consts(&text);
    // Sanity: the parsed values must match the compiled-in constants.
    assert!(out.iter().any(|(n, v)| n == "TRAVERSE_WG" && v.parse::<u32>().ok() == Some(consts::TRAVERSE_WG)));
    out
}

/// Parses the GPU structs and writes their Rust asserts (`$OUT_DIR/gpu_layout.rs`) and their GLSL (returned, and
/// written to `$OUT_DIR/gpu_structs.glsl` for a reader).
fn gpu_structs(consts: &HashMap<String, u32>, out_dir: &Path) -> (Vec<structs::Struct>, String) {
    let mut found = Vec::new();
    for (file, module) in structs::SOURCES {
        let text = std::fs::read_to_string(file).unwrap_or_else(|e| panic!("read {file}: {e}"));
        if let Err(e) = structs::parse(file, module, &text, consts, &mut found) {
            panic!("GPU structs: {e}");
        }
    }
    std::fs::write(out_dir.join("gpu_layout.rs"), structs::rust_asserts(&found)).expect("write gpu_layout.rs");
    let sources: Vec<&str> = structs::SOURCES.iter().map(|s| s.0).collect();
    let glsl = structs::glsl(&found, &sources);
    std::fs::write(out_dir.join("gpu_structs.glsl"), &glsl).expect("write gpu_structs.glsl");
    (found, glsl)
}

fn kind_of(path: &Path) -> Option<shaderc::ShaderKind> {
    match path.extension()?.to_str()? {
        "comp" => Some(shaderc::ShaderKind::Compute),
        "vert" => Some(shaderc::ShaderKind::Vertex),
        "frag" => Some(shaderc::ShaderKind::Fragment),
        _ => None,
    }
}

fn ident(name: &str) -> String {
    name.replace(['.', '-'], "_").to_uppercase()
}

fn main() {
    let glsl = PathBuf::from("glsl");
    println!("cargo:rerun-if-changed=glsl");
    println!("cargo:rerun-if-changed=src/shader_consts.rs");
    println!("cargo:rerun-if-changed=build");
    for (file, _) in structs::SOURCES {
        println!("cargo:rerun-if-changed={file}");
    }
    let out_dir = PathBuf::from(std::env::var("OUT_DIR").expect("OUT_DIR"));
    let macros = shared_macros();
    let consts = structs::const_values(&macros).unwrap_or_else(|e| panic!("{e}"));
    let (structs, generated_glsl) = gpu_structs(&consts, &out_dir);

    let mut sources: Vec<PathBuf> = std::fs::read_dir(&glsl)
        .expect("glsl/ directory")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| kind_of(p).is_some())
        .collect();
    sources.sort();
    for entry in walk(&glsl) {
        println!("cargo:rerun-if-changed={}", entry.display());
        let text = std::fs::read_to_string(&entry).unwrap_or_default();
        if let Err(e) = structs::check_spec_ids(&entry.display().to_string(), &text, &consts) {
            panic!("{e}");
        }
        if let Err(e) = layouts::binding_names(&entry.display().to_string(), &text, &consts) {
            panic!("{e}");
        }
    }

    // Every (source, static name, extra macros) to compile, in a fixed order.
    let mut jobs: Vec<(&PathBuf, String, Vec<Define>)> = Vec::new();
    for src in &sources {
        let file = src.file_name().unwrap().to_string_lossy().into_owned();
        // A source compiled only in its variants (traverse.comp's work-group sides and metrics) has no plain build.
        let plain = !VARIANTS_ONLY.contains(&file.as_str());
        let mut variants: Vec<(String, Vec<Define>)> = if plain { vec![(ident(&file), vec![])] } else { Vec::new() };
        for (f, suffix, extra) in VARIANTS {
            if *f == file {
                variants.push((format!("{}_{}", ident(&file), suffix.to_uppercase()), extra.to_vec()));
            }
        }
        if WIDE_TOO.contains(&file.as_str()) {
            let wide: Vec<_> = variants
                .iter()
                .map(|(name, extra)| {
                    let mut extra = extra.clone();
                    extra.push(("BVH_LAYOUT_WIDE", "1"));
                    (format!("{name}_WIDE"), extra)
                })
                .collect();
            variants.extend(wide);
        }
        jobs.extend(variants.into_iter().map(|(name, extra)| (src, name, extra)));
    }

    let results = compile_all(&jobs, &glsl, &generated_glsl, &macros);

    // The binding family each source names, read once for all its variants.
    let family_of: HashMap<&PathBuf, Result<Option<String>, String>> = sources
        .iter()
        .map(|src| {
            let text = layouts::with_includes(&glsl, src, &mut Vec::new());
            (src, layouts::family_of(&src.display().to_string(), &text, &consts))
        })
        .collect();
    let mut families = layouts::Families::default();
    let mut generated = String::from("// Generated by build.rs: SPIR-V of every shader in glsl/.\n");
    let mut errors = Vec::new();
    for ((src, name, _), result) in jobs.iter().zip(results) {
        match result.expect("every job compiled") {
            Ok(words) => {
                let spv_words: Vec<u32> =
                    words.chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
                let shader = format!("{} ({name})", src.display());
                if let Err(e) = structs::check_spirv(&shader, &spv_words, &structs) {
                    errors.push(e);
                    continue;
                }
                let checked =
                    family_of[src].clone().and_then(|f| f.map_or(Ok(()), |f| families.check(&shader, &f, &spv_words)));
                if let Err(e) = checked {
                    errors.push(e);
                    continue;
                }
                let spv = out_dir.join(format!("{name}.spv"));
                std::fs::write(&spv, words).expect("write spv");
                writeln!(
                    generated,
                    "pub static {name}: &Spv = &Spv(*include_bytes!(concat!(env!(\"OUT_DIR\"), \"/{name}.spv\")));"
                )
                .unwrap();
            }
            Err(e) => errors.push(format!("{} ({name}):\n{e}", src.display())),
        }
    }
    if !errors.is_empty() {
        for e in &errors {
            for line in e.lines() {
                println!("cargo:warning={line}");
            }
        }
        panic!("GLSL compilation or its checks failed:\n{}", errors.join("\n"));
    }
    std::fs::write(out_dir.join("shaders.rs"), generated).expect("write shaders.rs");
}

/// Compiles every job on every core (glslang's optimizer is most of a build's shader time), the results in job
/// order.
fn compile_all(
    jobs: &[(&PathBuf, String, Vec<Define>)],
    glsl: &Path,
    generated_glsl: &str,
    macros: &[(String, String)],
) -> Vec<Option<Result<Vec<u8>, String>>> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).min(jobs.len().max(1));
    let next = std::sync::atomic::AtomicUsize::new(0);
    let mut results: Vec<Option<Result<Vec<u8>, String>>> = (0..jobs.len()).map(|_| None).collect();
    std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                scope.spawn(|| {
                    let compiler = shaderc::Compiler::new().expect("shaderc compiler");
                    let mut done = Vec::new();
                    loop {
                        let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some((src, _, extra)) = jobs.get(i) else { break };
                        let result = compile(&compiler, glsl, generated_glsl, macros, src, extra);
                        done.push((i, result));
                    }
                    done
                })
            })
            .collect();
        for w in workers {
            for (i, r) in w.join().expect("shader compile thread") {
                results[i] = Some(r);
            }
        }
    });
    results
}

/// One shader build: SPIR-V bytes, or glslang's message.
fn compile(
    compiler: &shaderc::Compiler,
    glsl: &Path,
    generated: &str,
    macros: &[(String, String)],
    src: &Path,
    extra: &[Define],
) -> Result<Vec<u8>, String> {
    let mut options = shaderc::CompileOptions::new().expect("shaderc options");
    // Vulkan 1.2 target: 1.3 would emit LocalSizeId, which needs maintenance4.
    options.set_target_env(shaderc::TargetEnv::Vulkan, shaderc::EnvVersion::Vulkan1_2 as u32);
    options.set_optimization_level(shaderc::OptimizationLevel::Performance);
    options.set_generate_debug_info();
    for (k, v) in macros {
        options.add_macro_definition(k, Some(v));
    }
    for (k, v) in extra {
        options.add_macro_definition(k, Some(v));
    }
    let root = glsl.to_path_buf();
    let generated = generated.to_string();
    options.set_include_callback(move |requested, _ty, requester, _depth| {
        if requested == "generated/gpu_structs.glsl" {
            return Ok(shaderc::ResolvedInclude { resolved_name: requested.to_string(), content: generated.clone() });
        }
        let path = root.join(requested);
        std::fs::read_to_string(&path)
            .map(|content| shaderc::ResolvedInclude { resolved_name: path.display().to_string(), content })
            .map_err(|e| format!("{requester}: cannot include {requested}: {e}"))
    });
    let text = std::fs::read_to_string(src).expect("read shader");
    let kind = kind_of(src).unwrap();
    compiler
        .compile_into_spirv(&text, kind, &src.display().to_string(), "main", Some(&options))
        .map(|art| art.as_binary_u8().to_vec())
        .map_err(|e| e.to_string())
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                out.extend(walk(&p));
            } else {
                out.push(p);
            }
        }
    }
    out
}

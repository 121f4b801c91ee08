//! Tests of the build's GPU-struct generator and its SPIR-V check (build/structs.rs, build/spirv.rs): that a
//! layout GLSL would read differently from Rust is refused, in the Rust source or in a compiled shader.

use crate::vk::spirv;
#[path = "../build/layouts.rs"]
mod layouts;
#[path = "../build/structs.rs"]
mod structs;

use std::collections::HashMap;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn consts() -> HashMap<String, u32> {
    let text = std::fs::read_to_string(format!("{ROOT}/src/shader_consts.rs")).unwrap();
    structs::const_values(&structs::shader_consts(&text)).unwrap()
}

fn parse(text: &str) -> Result<Vec<structs::Struct>, String> {
    let mut found = Vec::new();
    structs::parse("test.rs", "crate::test", text, &consts(), &mut found)?;
    Ok(found)
}

fn real_structs(replace: Option<(&str, &str)>) -> Vec<structs::Struct> {
    let mut found = Vec::new();
    for &(file, module) in structs::SOURCES {
        let mut text = std::fs::read_to_string(format!("{ROOT}/{file}")).unwrap();
        if let Some((a, b)) = replace {
            text = text.replace(a, b);
        }
        structs::parse(file, module, &text, &consts(), &mut found).unwrap();
    }
    found
}

#[test]
fn the_real_structs_parse_with_the_offsets_rust_gives_them() {
    let found = real_structs(None);
    let frame = found.iter().find(|s| s.name == "FrameData").unwrap();
    assert_eq!(frame.size as usize, std::mem::size_of::<crate::gpu_types::FrameData>());
    let light = frame.fields.iter().find(|f| f.name == "light").unwrap();
    assert_eq!(light.offset as usize, std::mem::offset_of!(crate::gpu_types::FrameData, light));
    let pass = found.iter().find(|s| s.name == "PassUniforms").unwrap();
    let sky = pass.fields.iter().find(|f| f.name == "sky").unwrap();
    assert_eq!(sky.offset as usize, std::mem::offset_of!(crate::gpu_types::PassUniforms, sky));
    // A vec3 and the scalar in its last four bytes.
    let light = found.iter().find(|s| s.name == "LightUniforms").unwrap();
    let intensity = light.fields.iter().find(|f| f.name == "light_intensity").unwrap();
    assert_eq!((intensity.offset, light.size, frame.size), (332, 368, 720));
    assert!(found.iter().any(|s| s.name == "GpuInstance" && s.size == 192));
    let asserts = structs::rust_asserts(&found);
    assert!(
        asserts.contains("assert!(::std::mem::offset_of!(crate::gpu_types::LightUniforms, light_intensity) == 332);")
    );
}

#[test]
fn a_field_glsl_would_align_elsewhere_is_refused_with_its_line() {
    let e = parse("#[repr(C)]\npub struct A {\n    pub a: u32,\n    pub b: [f32; 4],\n}\n").err().unwrap();
    assert!(e.starts_with("test.rs:4:") && e.contains("`b`") && e.contains("padding"), "{e}");
    // A struct whose size GLSL rounds up cannot sit inside another.
    let text = "#[repr(C)]\npub struct A {\n    pub a: [f32; 4],\n    pub b: u32,\n}\n#[repr(C)]\npub struct B {\n    pub a: [A; 2],\n}\n";
    let e = parse(text).err().unwrap();
    assert!(e.starts_with("test.rs:8:") && e.contains("rounds it to 32"), "{e}");
    let e = parse("#[repr(C)]\npub struct A {\n    pub a: [f64; 2],\n}\n").err().unwrap();
    assert!(e.contains("not a GPU type"), "{e}");
    // An array of vec3 has a 16-byte stride in GLSL, 12 in Rust.
    let e = parse("#[repr(C)]\npub struct A {\n    pub a: [[f32; 3]; 2],\n}\n").err().unwrap();
    assert!(e.contains("another stride"), "{e}");
    let e = parse("#[repr(C)]\npub struct A {\n    pub a: [f64; 2],\n}\n").err().unwrap();
    assert!(e.contains("not a GPU type"), "{e}");
    let e = parse("#[repr(C)]\npub struct A {\n    pub a: [u32; NO_SUCH + 1],\n}\n").err().unwrap();
    assert!(e.contains("unknown constant NO_SUCH"), "{e}");
}

#[test]
fn the_generated_glsl_carries_the_docs_and_constant_lengths() {
    let glsl = structs::glsl(&real_structs(None), &["src/gpu_types.rs"]);
    assert!(glsl.contains("struct TraversalState {"));
    assert!(glsl.contains("    LevelCounters levels[MAX_LEVELS];"));
    assert!(glsl.contains("    // The eye.\n    GpuView camera;  // byte 0"));
    assert!(glsl.contains("    // The pass's light.\n    LightUniforms light;  // byte 336"));
}

#[test]
fn a_shader_that_reads_a_struct_with_another_layout_fails_the_check() {
    let words = crate::shaders::COMPOSITE_COMP.words();
    let name = "composite.comp";
    structs::check_spirv(name, words, &real_structs(None)).unwrap();
    // std140 (the frame's uniform buffer) strides an array of uvec2 by 16 bytes, Rust by 8.
    let pyramid = "pub pyramid: [[u32; 4]; (MAX_PYRAMID_MIPS / 4) as usize],";
    let wrong = real_structs(Some((pyramid, "pub pyramid: [[u32; 2]; (MAX_PYRAMID_MIPS / 2) as usize],")));
    let e = structs::check_spirv(name, words, &wrong).unwrap_err();
    assert!(e.contains("FrameUniforms.pyramid has an array stride of 16 bytes in SPIR-V, 8 in Rust"), "{e}");
    // A member the shader does not have.
    let last =
        "    pub sky: f32,\n    /// To a multiple of 16 bytes, as std140 places the struct.\n    pub pad: [u32; 2],\n}";
    let more = "    pub sky: f32,\n    pub pad: u32,\n    pub more: u32,\n}";
    let wrong = real_structs(Some((last, more)));
    let e = structs::check_spirv(name, words, &wrong).unwrap_err();
    assert!(e.contains("struct PassUniforms has 3 members in SPIR-V, 4 in Rust"), "{e}");
    // The build's own check of such a struct is stricter: compiled from it, std140 would stride the array by 16
    // bytes where Rust packs it in 4, and the build fails there. Against these shaders, the members no longer
    // match.
    let scalars = "    pub light_spectrum_c0: f32,\n    pub light_spectrum_c1: f32,\n    pub light_spectrum_c2: f32,";
    let wrong = real_structs(Some((scalars, "    pub light_spectrum: [f32; 3],")));
    let e = structs::check_spirv(name, words, &wrong).unwrap_err();
    assert!(e.contains("struct LightUniforms has 12 members in SPIR-V, 10 in Rust"), "{e}");
}

#[test]
fn the_descriptors_a_shader_declares_are_read() {
    let m = spirv::Module::parse(crate::shaders::COVERAGE_COMP.words()).unwrap();
    assert!(!m.bindings.is_empty());
    assert!(m.bindings.values().any(|(kind, _)| *kind == spirv::Descriptor::Uniform));
}

#[test]
fn the_bindings_a_shader_may_write_are_those_it_does_not_declare_readonly() {
    use crate::shaders::consts::*;
    let writable = |words: &[u32]| spirv::Module::parse(words).unwrap().writable;
    // Buffers: a block without `readonly` (atomics on the traversal state), a `writeonly` one, a `readonly` one.
    let wave = writable(crate::shaders::WAVE_COMP.words());
    assert!(wave.contains(&(0, PB_STATE)) && wave.contains(&(0, PB_RAYS_OUT)), "{wave:?}");
    assert!(!wave.contains(&(0, PB_RAYS_IN)) && !wave.contains(&(0, PB_BVH_PAIR)), "{wave:?}");
    // Texel buffers and sampled images are read only; the wide wave reads its rays and photons as texels.
    let wide = writable(crate::shaders::WAVE_COMP_WIDE.words());
    assert!(!wide.contains(&(0, PB_RAYS_IN)) && !wide.contains(&(0, PB_PHOTONS)) && !wide.contains(&(0, PB_FRONT)));
    // Storage images: the glass pass writes the glass image, the composite reads it (`readonly`).
    assert!(writable(crate::shaders::GLASS_COMP.words()).contains(&(0, CB_GLASS)));
    let composite = writable(crate::shaders::COMPOSITE_COMP.words());
    assert!(!composite.contains(&(0, CB_GLASS)) && composite.contains(&(0, CB_BEAUTY)), "{composite:?}");
}

#[test]
fn a_specialization_constant_takes_its_id_from_the_shared_constants() {
    let c = consts();
    let ok = "layout(constant_id = WAVE_PRIMARY_ID) const bool WAVE_PRIMARY = false;";
    structs::check_spec_ids("x.comp", ok, &c).unwrap();
    let e = structs::check_spec_ids("x.comp", "\nlayout(constant_id = 0) const bool WAVE_PRIMARY = false;", &c)
        .unwrap_err();
    assert!(e.starts_with("x.comp:2:") && e.contains("constant_id = WAVE_PRIMARY_ID"), "{e}");
    let e = structs::check_spec_ids("x.comp", "layout(constant_id = NEW_ID) const uint NEW = 1u;", &c).unwrap_err();
    assert!(e.contains("src/shader_consts.rs"), "{e}");
}

#[test]
fn the_shaders_of_a_binding_family_declare_each_binding_with_one_kind() {
    let mut families = layouts::Families::default();
    for (name, words) in [
        ("wave", crate::shaders::WAVE_COMP.words()),
        ("wave wide (texels)", crate::shaders::WAVE_COMP_WIDE.words()),
        ("splat", crate::shaders::SPLAT_COMP.words()),
        ("splat.vert", crate::shaders::SPLAT_VERT.words()),
        ("trace", crate::shaders::TRACE_COMP.words()),
    ] {
        families.check(name, "PB_", words).unwrap();
    }
    // The resolve's binding 1 is a sampled image; the photon passes' is a storage buffer (the traversal state).
    let e = families.check("resolve", "PB_", crate::shaders::RESOLVE_COMP.words()).unwrap_err();
    assert!(e.contains("`t_flux` is binding 1 of PB_ as a Sampled descriptor") && e.contains("as Storage"), "{e}");
    // Its texel variant reads that binding through a texel view: the one difference a family allows.
    let mut resolve = layouts::Families::default();
    resolve.check("resolve", "RS_", crate::shaders::RESOLVE_COMP.words()).unwrap();
    resolve.check("resolve texels", "RS_", crate::shaders::RESOLVE_COMP_TEXELS.words()).unwrap();
    // The family a source binds by follows from the constants it (or an include) names.
    let glsl = std::path::Path::new(ROOT).join("glsl");
    let text = layouts::with_includes(&glsl, &glsl.join("wave.comp"), &mut Vec::new());
    assert_eq!(layouts::family_of("wave.comp", &text, &consts()).unwrap().as_deref(), Some("PB_"));
    let mixed =
        "layout(binding = PB_FRAME) uniform Frame { uint a; };\nlayout(binding = CB_HDR) uniform Hdr { uint b; };";
    let e = layouts::family_of("x.comp", mixed, &consts()).unwrap_err();
    assert!(e.contains("two families, PB_ and CB_"), "{e}");
}

#[test]
fn a_binding_is_named_by_a_shader_constant_never_a_number() {
    let c = consts();
    let ok = "layout(std430, set = 0, binding = WA_HEIGHTS) readonly buffer Heights { float heights[]; };";
    assert_eq!(layouts::binding_names("x.comp", ok, &c).unwrap(), [(1, "WA_HEIGHTS".to_string())]);
    let e = layouts::binding_names("x.comp", "\nlayout(set = 0, binding = 3) buffer B { uint b[]; };", &c).unwrap_err();
    assert!(e.starts_with("x.comp:2:") && e.contains("`binding = 3`"), "{e}");
    let e = layouts::binding_names("x.comp", "layout(binding = WA_NO_SUCH) buffer B { uint b[]; };", &c).unwrap_err();
    assert!(e.contains("`WA_NO_SUCH` is not a constant"), "{e}");
    // Two bindings swapped on the shader's side: each constant declares the other's resource.
    let water = std::fs::read_to_string(format!("{ROOT}/glsl/water.comp")).unwrap();
    let swapped = water
        .replace("binding = WA_HEIGHTS)", "binding = WA_SWAP)")
        .replace("binding = WA_OBJECT_VERTICES)", "binding = WA_HEIGHTS)")
        .replace("binding = WA_SWAP)", "binding = WA_OBJECT_VERTICES)");
    let e = layouts::binding_names("glsl/water.comp", &swapped, &c).unwrap_err();
    assert!(e.contains("binding `WA_HEIGHTS` (src/shader_consts.rs) declares `ObjectVertices`"), "{e}");
    // A declaration may abbreviate and pluralize as the shaders do; a different word is refused.
    assert!(layouts::names_agree("PB_RECEIVERS", "t_recv"));
    assert!(layouts::names_agree("CB_RECEIVERS1", "t_recv1"));
    assert!(layouts::names_agree("PB_BVH_INSTANCES", "bvh_instance_texels"));
    assert!(layouts::names_agree("PB_FLUX_TEXELS", "FluxBuf"));
    assert!(layouts::names_agree("CB_FRAME", "FrameUbo"));
    assert!(!layouts::names_agree("CB_FRONT", "t_front_aux"));
    assert!(!layouts::names_agree("CB_IRRADIANCE1", "t_irradiance2"));
    // Comments are not declarations.
    assert!(layouts::binding_names("x.comp", "// binding = 3 is the old one", &c).unwrap().is_empty());
    // Every shader of the repository names its bindings.
    let glsl = std::path::Path::new(ROOT).join("glsl");
    let mut named = 0;
    for dir in [glsl.clone(), glsl.join("common")] {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            let text = std::fs::read_to_string(&path).unwrap_or_default();
            named += layouts::binding_names(&path.display().to_string(), &text, &c).unwrap().len();
        }
    }
    assert!(named > 100, "{named} named bindings");
}

#[test]
fn a_word_struct_packs_each_field_into_its_bytes_and_refuses_what_does_not_fill_words() {
    let ok = parse(
        "#[repr(C)]\npub struct W {\n    pub a: [f32; 3],\n    pub b: u32,\n    pub c: [u32; 2],\n    pub d: [f32; 2],\n}\n",
    )
    .unwrap();
    let f = structs::word_functions(&ok[0]).unwrap();
    for line in [
        "W W_from_words(uvec4 w0, uvec4 w1) {",
        "    v.a = uintBitsToFloat(uvec3(w0.x, w0.y, w0.z));",
        "    v.b = w0.w;",
        "    v.c = uvec2(w1.x, w1.y);",
        "    v.d = uintBitsToFloat(uvec2(w1.z, w1.w));",
        "    w1.z = floatBitsToUint(v.d[0]);",
    ] {
        assert!(f.lines().any(|l| l == line), "{line}\n{f}");
    }
    let short = parse("#[repr(C)]\npub struct S {\n    pub a: [f32; 3],\n}\n").unwrap();
    let e = structs::word_functions(&short[0]).unwrap_err();
    assert!(e.contains("12 bytes are not whole 16-byte words"), "{e}");
}

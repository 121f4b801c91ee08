//! Property tests over everything a user types or points at: the TOML scene parser (arbitrary text, mutated
//! scenes, and well-formed scenes with random values), the OBJ loader (arbitrary bytes and random OBJ lines), and
//! the CLI's size and settings checks. Arbitrary input gives an error, never a panic, a hang or a runaway
//! allocation; what parses satisfies the invariants the renderer relies on (finite geometry, indices in range,
//! no degenerate triangles, a light and camera the views can be fitted to). Case counts are kept small so that
//! the file runs in seconds; `PROPTEST_CASES=N` raises them for a longer hunt.
//!
//! The CLI half runs the binary on random bad sizes and levels and expects exit code 2 with a message.

mod common;
use caustics::scene::{mesh, CameraView, Scene};
use caustics::settings::{
    parse_size, DeviceClass, Driven, Method, Metric, Quality, ResolvedSettings, Settings, Transport, Tuning,
    MAX_BATCH_PHOTONS,
};
use caustics::Views;
use proptest::prelude::*;
use proptest::test_runner::Config;
use std::path::{Path, PathBuf};

const BASE: &str = r#"[[light]]
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
up = [0.0, 0.0, -1.0]
half_height = 1.0

[[camera]]
name = "main"
kind = "perspective"
position = [1.6, 1.5, 2.2]
target = [0.0, 0.4, 0.0]
fov_deg = 40.0

[[object]]
name = "floor"
shape = "plane"
size = [2.0, 2.0]
material = { kind = "diffuse", albedo = 0.8 }

[[object]]
name = "glass"
shape = "sphere"
radius = 0.3
subdivisions = 2
translate = [0.0, 0.5, 0.0]
rotate_deg = [10.0, 20.0, 30.0]
scale = 1.0
material = { kind = "dielectric", ior = 1.5 }
"#;

fn config(cases: u32) -> Config {
    let cases = std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(cases);
    Config { cases, failure_persistence: None, ..Config::default() }
}

fn dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fuzz").join(name);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// What a parsed scene must satisfy: finite world-space geometry with in-range indices and no zero-area
/// triangle, a usable light and cameras, and light views that can be fitted without panicking.
fn check_scene(scene: &Scene) {
    assert_eq!(scene.lights.len().min(1), 1);
    for o in &scene.objects {
        let m = &o.mesh;
        assert!(!m.indices.is_empty() && m.indices.len() % 3 == 0, "{}", o.name);
        assert_eq!(m.normals.len(), m.positions.len(), "{}", o.name);
        assert!(m.positions.iter().all(|p| p.is_finite() && p.abs().max_element() <= mesh::MAX_COORDINATE));
        assert!(m.normals.iter().all(|n| n.is_finite()));
        assert!(m.indices.iter().all(|&i| (i as usize) < m.positions.len()));
    }
    for l in &scene.lights {
        assert!(l.position.is_finite() && l.target.is_finite() && (l.target - l.position).length() > 0.0);
        assert!((l.target - l.position).normalize().is_finite());
    }
    let settings = ResolvedSettings { gbuffer_res: 64, caustic_res: 64, ..ResolvedSettings::default() };
    for c in &scene.cameras {
        let view = CameraView::new(c, 64, 48, scene.bounds());
        for e in caustics::emitters(scene).into_iter().flatten() {
            let _ = Views::new(scene, &settings, &view, e);
        }
    }
}

/// A number as TOML text: mostly ordinary, sometimes a special value or out of f32's range.
fn num() -> impl Strategy<Value = String> {
    prop_oneof![
        90 => (-5.0f32..5.0).prop_map(|x| format!("{x:?}")),
        30 => (0.0f32..100.0).prop_map(|x| format!("{x:?}")),
        3 => prop::sample::select(vec![
            "nan", "inf", "-inf", "-0.0", "0.0", "0", "1", "-1", "1e39", "-1e39", "3.4028235e38", "1e-45", "1e10",
            "-2e9", "9223372036854775807", "1e308", "\"x\"", "[]", "true",
        ])
        .prop_map(String::from),
        2 => any::<f32>().prop_map(|x| if x.is_finite() { format!("{x:?}") } else { "nan".into() }),
    ]
}

/// A number for a field that must be positive: mostly in (0, 10), else anything [`num`] gives.
fn pos() -> impl Strategy<Value = String> {
    prop_oneof![6 => (0.01f32..10.0).prop_map(|x| format!("{x:?}")), 1 => num()]
}

/// A number in [0, 1] (albedo), mostly.
fn unit() -> impl Strategy<Value = String> {
    prop_oneof![6 => (0.0f32..=1.0).prop_map(|x| format!("{x:?}")), 1 => num()]
}

fn vec3() -> impl Strategy<Value = String> {
    prop_oneof![
        40 => (num(), num(), num()).prop_map(|(a, b, c)| format!("[{a}, {b}, {c}]")),
        1 => prop::collection::vec(num(), 0..5).prop_map(|v| format!("[{}]", v.join(", "))),
    ]
}

fn word(options: &'static [&'static str]) -> impl Strategy<Value = String> {
    prop_oneof![40 => prop::sample::select(options).prop_map(String::from), 1 => "[a-z]{0,6}"]
}

/// A structurally valid scene whose values are random.
fn random_scene() -> impl Strategy<Value = String> {
    // Spot lights mostly above the scene, pointing down, with a cone (directional ones mostly without).
    let light = (
        word(&["spot", "directional"]),
        prop_oneof![
            3 => (-1.0f32..1.0, 1.5f32..4.0, -1.0f32..1.0).prop_map(|(x, y, z)| format!("[{x:?}, {y:?}, {z:?}]")),
            1 => vec3(),
        ],
        prop_oneof![3 => Just("[0.0, 0.3, 0.0]".to_string()), 1 => vec3()],
        prop_oneof![4 => (1.0f32..89.0).prop_map(|c| Some(format!("{c:?}"))), 1 => prop::option::of(num())],
        pos(),
    );
    let camera = (word(&["orthographic", "perspective"]), vec3(), vec3(), prop::option::of(vec3()), pos());
    let object = (
        word(&["sphere", "cube", "plane"]),
        pos(),
        prop::sample::select(vec!["-1", "0", "1", "2", "3", "9", "1000000000000"]),
        prop_oneof![pos(), (pos(), pos(), pos()).prop_map(|(a, b, c)| format!("[{a}, {b}, {c}]")), vec3()],
        prop::option::of(vec3()),
        prop::option::of(vec3()),
        prop::option::of(prop_oneof![pos(), vec3()]),
        (word(&["diffuse", "dielectric"]), prop::option::of(unit()), prop::option::of(pos())),
    );
    (light, camera, object).prop_map(|(l, c, o)| {
        let mut s =
            format!("[[light]]\nkind = \"{}\"\nposition = {}\ntarget = {}\nintensity = {}\n", l.0, l.1, l.2, l.4);
        if let Some(cone) = l.3.filter(|c| l.0 != "directional" || c.len() % 5 == 0) {
            s += &format!("cone_deg = {cone}\n");
        }
        let proj = if c.0 == "perspective" { "fov_deg" } else { "half_height" };
        s += &format!(
            "\n[[camera]]\nname = \"c\"\nkind = \"{}\"\nposition = {}\ntarget = {}\n{proj} = {}\n",
            c.0, c.1, c.2, c.4
        );
        if let Some(up) = c.3 {
            s += &format!("up = {up}\n");
        }
        s += &format!("\n[[object]]\nname = \"o\"\nshape = \"{}\"\n", o.0);
        match o.0.as_str() {
            "sphere" => s += &format!("radius = {}\nsubdivisions = {}\n", o.1, o.2),
            _ => s += &format!("size = {}\n", o.3),
        }
        if let Some(t) = o.4 {
            s += &format!("translate = {t}\n");
        }
        if let Some(r) = o.5 {
            s += &format!("rotate_deg = {r}\n");
        }
        if let Some(sc) = o.6 {
            s += &format!("scale = {sc}\n");
        }
        let (kind, mut albedo, mut ior) = o.7;
        // Mostly the field the material takes; sometimes the other one too.
        if kind == "dielectric" && albedo.as_ref().is_some_and(|a| a.len() % 4 != 0) {
            albedo = None;
        }
        if kind == "diffuse" && ior.as_ref().is_some_and(|a| a.len() % 4 != 0) {
            ior = None;
        }
        s += &format!("material = {{ kind = \"{kind}\"");
        if let Some(a) = albedo {
            s += &format!(", albedo = {a}");
        }
        if let Some(i) = ior {
            s += &format!(", ior = {i}");
        }
        s += " }\n";
        s
    })
}

/// An edit of the canonical scene: delete, insert or replace a span, or replace one value.
#[derive(Clone, Debug)]
enum Edit {
    Delete(usize, usize),
    Insert(usize, String),
    Value(usize, String),
    Duplicate(usize),
}

fn edit() -> impl Strategy<Value = Edit> {
    let len = BASE.len();
    prop_oneof![
        (0..len, 0usize..40).prop_map(|(a, n)| Edit::Delete(a, n)),
        (0..len, prop_oneof!["\\PC{0,8}", "[\\[\\]{}=,\"'#\n .]{1,4}", Just("\u{feff}é✓\u{0}".to_string())])
            .prop_map(|(a, s)| Edit::Insert(a, s)),
        (0usize..64, num()).prop_map(|(i, v)| Edit::Value(i, v)),
        (0usize..64).prop_map(Edit::Duplicate),
    ]
}

fn apply(text: &str, e: &Edit) -> String {
    let floor = |mut i: usize| {
        i = i.min(text.len());
        while !text.is_char_boundary(i) {
            i -= 1;
        }
        i
    };
    match e {
        Edit::Delete(a, n) => {
            let (a, b) = (floor(*a), floor(a + n));
            format!("{}{}", &text[..a], &text[b..])
        }
        Edit::Insert(a, s) => {
            let a = floor(*a);
            format!("{}{s}{}", &text[..a], &text[a..])
        }
        Edit::Value(i, v) => {
            // Replace the i-th number-looking token.
            let mut out = String::new();
            let mut k = 0;
            let mut rest = text;
            while let Some(p) = rest.find(|c: char| c.is_ascii_digit() || c == '-') {
                let end = rest[p..]
                    .find(|c: char| !(c.is_ascii_alphanumeric() || ".-+".contains(c)))
                    .map_or(rest.len(), |q| p + q);
                out += &rest[..p];
                out += if k == *i % 40 { v } else { &rest[p..end] };
                rest = &rest[end..];
                k += 1;
            }
            out + rest
        }
        Edit::Duplicate(i) => {
            let lines: Vec<&str> = text.lines().collect();
            let i = i % lines.len();
            let mut out = lines[..=i].join("\n");
            out += "\n";
            out += &lines[i..].join("\n");
            out
        }
    }
}

/// Random OBJ text: a few ordinary vertices and faces over them, then up to four odd lines inserted anywhere.
fn obj_text() -> impl Strategy<Value = String> {
    let vertices = prop::collection::vec((-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0), 3..12);
    let faces = prop::collection::vec((1u32..12, 1u32..12, 1u32..12), 1..24);
    let odd = prop::collection::vec((any::<prop::sample::Index>(), obj_line()), 0..5);
    (vertices, faces, odd).prop_map(|(v, f, odd)| {
        let n = v.len() as u32;
        let mut lines: Vec<String> = v.iter().map(|(x, y, z)| format!("v {x} {y} {z}")).collect();
        lines
            .extend(f.iter().map(|(a, b, c)| format!("f {} {} {}", (a - 1) % n + 1, (b - 1) % n + 1, (c - 1) % n + 1)));
        for (at, line) in odd {
            let i = at.index(lines.len() + 1);
            lines.insert(i, line);
        }
        lines.join("\n")
    })
}

#[test]
fn base_scene_parses() {
    check_scene(&Scene::parse(BASE, Path::new("base.toml")).unwrap());
}

proptest! {
    #![proptest_config(config(256))]

    /// Arbitrary text (and arbitrary bytes, read as the loader would: lossy UTF-8) is an error, not a panic.
    #[test]
    fn scene_parse_arbitrary_text(text in "\\PC{0,200}", bytes in prop::collection::vec(any::<u8>(), 0..200)) {
        if let Ok(s) = Scene::parse(&text, Path::new("x.toml")) {
            check_scene(&s);
        }
        let _ = Scene::parse(&String::from_utf8_lossy(&bytes), Path::new("x.toml"));
    }

    /// The canonical scene with up to four random edits: either an error that names the file, or a scene that
    /// satisfies the invariants.
    #[test]
    fn scene_parse_mutated(edits in prop::collection::vec(edit(), 1..5)) {
        let mut text = BASE.to_string();
        for e in &edits {
            text = apply(&text, e);
        }
        match Scene::parse(&text, Path::new("m.toml")) {
            Ok(s) => check_scene(&s),
            Err(e) => prop_assert!(e.to_string().starts_with("m.toml:"), "{e}"),
        }
    }
}

proptest! {
    #![proptest_config(config(384))]

    /// Well-formed scenes with random values: every value outside its domain is a `file:line: field` error. The
    /// work a scene asks for is bounded by the format (an icosphere has at most 20·4^8 triangles), not by a clock.
    #[test]
    fn scene_random_values(text in random_scene()) {
        match Scene::parse(&text, Path::new("r.toml")) {
            Ok(s) => {
                check_scene(&s);
                let most = s.objects.iter().map(|o| o.mesh.indices.len() / 3).max().unwrap_or(0);
                prop_assert!(most <= 20 * 4usize.pow(8), "an object of {most} triangles:\n{text}");
            }
            Err(e) => {
                let e = e.to_string();
                prop_assert!(e.starts_with("r.toml:"), "{e}");
                prop_assert!(!e.contains("NaN") || e.contains("nan") || e.contains("got NaN"), "{e}");
            }
        }
    }
}

/// A line of an OBJ file: vertices with odd coordinates, faces with odd indices, and garbage.
fn obj_line() -> impl Strategy<Value = String> {
    let coord = prop_oneof![
        8 => (-3.0f32..3.0).prop_map(|x| format!("{x}")),
        2 => prop::sample::select(vec!["0", "1", "-1", "0.5"]).prop_map(String::from),
        1 => prop::sample::select(vec!["nan", "NaN", "inf", "-inf", "1e39", "1e20", "x", "", "1e-45", "+"])
            .prop_map(String::from),
    ];
    let index = prop_oneof![
        8 => (1i64..10).prop_map(|i| i.to_string()),
        2 => (-10i64..0).prop_map(|i| i.to_string()),
        1 => prop::sample::select(vec!["0", "4294967296", "4294967295", "9223372036854775807", "-9223372036854775808", "x", "1/", "1//", "/1"])
            .prop_map(String::from),
    ];
    prop_oneof![
        6 => (coord.clone(), coord.clone(), coord.clone()).prop_map(|(x, y, z)| format!("v {x} {y} {z}")),
        1 => prop::collection::vec(coord.clone(), 0..6).prop_map(|c| format!("v {}", c.join(" "))),
        2 => (coord.clone(), coord.clone(), coord).prop_map(|(x, y, z)| format!("vn {x} {y} {z}")),
        6 => prop::collection::vec(index.clone(), 3..5).prop_map(|i| format!("f {}", i.join(" "))),
        1 => prop::collection::vec(index.clone(), 0..8).prop_map(|i| format!("f {}", i.join(" "))),
        1 => prop::collection::vec(index, 3..5)
            .prop_map(|i| format!("f {}", i.iter().map(|x| format!("{x}//{x}")).collect::<Vec<_>>().join(" "))),
        1 => prop::sample::select(vec!["o a", "g b", "s 1", "mtllib /etc/passwd", "usemtl m", "l 1 2", "p 1", "#", "vt 0 0"])
            .prop_map(String::from),
        1 => "\\PC{0,16}",
    ]
}

fn obj_scene(dir: &Path, obj: &[u8], dielectric: bool) -> Result<Scene, String> {
    std::fs::write(dir.join("m.obj"), obj).unwrap();
    let material = if dielectric { "{ kind = \"dielectric\", ior = 1.5 }" } else { "{ kind = \"diffuse\" }" };
    let text = BASE
        .replace("shape = \"sphere\"\nradius = 0.3\nsubdivisions = 2", "shape = \"mesh\"\npath = \"m.obj\"")
        .replace("{ kind = \"dielectric\", ior = 1.5 }", material);
    Scene::parse(&text, &dir.join("s.toml")).map_err(|e| e.to_string())
}

proptest! {
    #![proptest_config(config(384))]

    /// Random OBJ files: an error naming the object (`object[1] "glass".path`), or a valid mesh.
    #[test]
    fn obj_random_lines(
        text in prop_oneof![obj_text(), prop::collection::vec(obj_line(), 0..40).prop_map(|l| l.join("\n"))],
        dielectric in any::<bool>(),
    ) {
        let d = dir("obj_lines");
        match obj_scene(&d, text.as_bytes(), dielectric) {
            Ok(s) => {
                check_scene(&s);
                // At most a fan of 6 triangles per line (a face names at most 8 vertices here).
                let triangles = s.objects[1].mesh.indices.len() / 3;
                prop_assert!(triangles <= 6 * text.lines().count(), "{triangles} triangles from:\n{text}");
            }
            Err(e) => prop_assert!(e.contains("object[1] \"glass\".path") && e.contains("m.obj"), "{e}"),
        }
    }

    /// Arbitrary bytes as an OBJ file.
    #[test]
    fn obj_arbitrary_bytes(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        let d = dir("obj_bytes");
        match obj_scene(&d, &bytes, true) {
            Ok(s) => check_scene(&s),
            Err(e) => prop_assert!(e.contains("object[1] \"glass\".path"), "{e}"),
        }
    }
}

proptest! {
    #![proptest_config(config(512))]

    /// Any string: an error naming the flag, or a size within 1..=16384.
    #[test]
    fn parse_size_arbitrary(s in prop_oneof!["\\PC{0,24}", "[0-9xX -]{0,12}", "[0-9]{1,12}[xX][0-9]{1,12}"]) {
        match parse_size(&s, "--size") {
            Ok((w, h)) => prop_assert!((1..=16384).contains(&w) && (1..=16384).contains(&h)),
            Err(e) => prop_assert!(e.to_string().starts_with("--size `"), "{e}"),
        }
    }

    /// Every WxH in range parses to itself (with spaces around the numbers, either `x`).
    #[test]
    fn parse_size_roundtrip(w in 1u32..=16384, h in 1u32..=16384, upper in any::<bool>()) {
        let s = format!(" {w} {} {h} ", if upper { 'X' } else { 'x' });
        prop_assert_eq!(parse_size(&s, "--size").unwrap(), (w, h));
    }

    /// Settings::validate on random values never panics, and what it accepts the renderer can size.
    #[test]
    fn settings_validate(
        level in 0u32..40,
        gbuffer_res in prop_oneof![Just(64u32), Just(1024), Just(16384), any::<u32>()],
        caustic_res in prop_oneof![Just(16u32), Just(8192), any::<u32>()],
        budget in prop_oneof![Just(64.0f64), Just(1e-300), Just(f64::NAN), Just(-1.0), Just(f64::INFINITY), 0.0f64..100.0],
        error_bound in prop_oneof![Just(f32::NAN), Just(0.0f32), any::<f32>()],
        flux_threshold in prop_oneof![Just(1.0f32), Just(-0.0f32), any::<f32>(), 0.0f32..1.0],
        weak_branches in prop_oneof![Just(1.0f32), Just(f32::NAN), any::<f32>(), 0.0f32..1.0],
        traverse_wg in 0u32..20,
        batch_slots in prop_oneof![Just(0u32), any::<u32>()],
        debug_photons in prop_oneof![Just(0u32), any::<u32>()],
        dense in any::<bool>(), exact in any::<bool>(), max_error in any::<bool>(),
    ) {
        let s = Settings {
            quality: Quality {
                transport: if exact { Transport::Exact } else { Transport::TwoInterface },
                method: if dense { Method::Dense } else { Method::Adaptive },
                metric: if max_error { Metric::MaxError } else { Metric::MaxLevel },
                level: Some(level), caustic_res, photon_budget_mib: budget,
                ..Quality::default()
            },
            tuning: Tuning {
                driven: Driven::Gpu, gbuffer_res, error_bound, flux_threshold, traverse_wg, batch_slots, debug_photons,
                weak_branches,
                ..Tuning::default()
            },
        };
        match s.resolve_with(DeviceClass::Cpu, 128 << 20, 2 << 30) {
            Ok(s) => {
                prop_assert!(s.photon_capacity() >= 8 && s.photon_capacity() <= 8 << 20);
                let batch = s.batch_photons(s.photon_capacity());
                prop_assert!((8..=s.photon_capacity()).contains(&batch) && batch <= MAX_BATCH_PHOTONS);
                prop_assert!(s.gbuffer_res.is_power_of_two() && s.gbuffer_level() < 16);
                prop_assert!(budget.is_finite() && error_bound.is_finite() && flux_threshold.is_finite());
                prop_assert!((0.0..1.0).contains(&weak_branches));
            }
            // A bad value is named by its field (the CLI prints its flag).
            Err(e) => prop_assert!(matches!(e, caustics::Error::Setting { .. }), "{e}"),
        }
    }
}

/// The binary on random bad `--size` and `--level` values: exit code 2, a message naming the flag, no panic.
/// (Each run stops before opening a device.)
#[test]
fn cli_bad_size_and_level_exit_2() {
    use proptest::strategy::ValueTree;
    use proptest::test_runner::TestRunner;
    let d = common::out_dir("fuzz_cli");
    let out = d.join("o.exr");
    let mut runner = TestRunner::new(config(12));
    let sizes = prop_oneof![
        "[0-9]{0,3}",
        "0[xX][0-9]{1,3}",
        "[0-9]{1,3}x0",
        "[1-9][0-9]{5,9}x[1-9]",
        "-[0-9]{1,3}x[0-9]{1,3}",
        "\\PC{0,10}[a-w]",
    ];
    for i in 0..runner.config().cases {
        let size = sizes.new_tree(&mut runner).unwrap().current();
        let o = common::caustics(&[
            "render",
            "--aov",
            "caustics",
            "--out",
            out.to_str().unwrap(),
            &format!("--size={size}"),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "--size {size:?} (case {i}):\n{err}");
        assert!(err.contains("--size") && !err.contains("panicked"), "--size {size:?}:\n{err}");
        common::assert_no_output(&out);
    }
    let levels = prop_oneof!["1[7-9]|[2-9][0-9]", "[0-9]{10,12}", "-[1-9]", "[a-z.]{1,3}"];
    for i in 0..runner.config().cases {
        let level = levels.new_tree(&mut runner).unwrap().current();
        let o = common::caustics(&[
            "render",
            "--aov",
            "caustics",
            "--out",
            out.to_str().unwrap(),
            &format!("--level={level}"),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "--level {level:?} (case {i}):\n{err}");
        assert!(err.contains("--level") && !err.contains("panicked"), "--level {level:?}:\n{err}");
        common::assert_no_output(&out);
    }
}

//! Mesh pathologies, each with a defined behaviour:
//!
//! | pathology | behaviour |
//! |---|---|
//! | NaN or infinite vertex coordinate, or beyond ±1e9 | error at load (exit 2): `scene.toml:LINE: object[i] "name".path: FILE.obj:LINE: vertex N ...` |
//! | zero-area triangle (repeated corner, collinear corners) | removed, with a warning |
//! | duplicated triangle (same corners, either winding) | removed, with a warning |
//! | triangles whose winding disagrees with their neighbours | re-oriented (the majority wins), with a warning |
//! | a closed mesh wound inside out (negative volume) | every winding reversed, with a warning |
//! | an open mesh (boundary edges) | rendered as surfaces; a warning for glass |
//! | a non-manifold edge (more than two triangles) | rendered as surfaces; a warning for glass |
//! | no triangle left | error at load (exit 2) |
//!
//! The repairs give the same caustic as the clean mesh (rendered in process, on both transports, with the warnings
//! the library logs), no pathology panics at render time, and a NaN vertex exits with code 2 through the binary.

mod common;
use caustics::scene::mesh::{self, MeshReport};
use caustics::scene::{Material, Scene};
use caustics::settings::{Metric, Transport};
use common::*;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A 0.4 m cube's 8 corners (OBJ indices 1..8).
const CUBE_V: &str = "v -0.2 -0.2 -0.2\nv 0.2 -0.2 -0.2\nv 0.2 0.2 -0.2\nv -0.2 0.2 -0.2\n\
                      v -0.2 -0.2 0.2\nv 0.2 -0.2 0.2\nv 0.2 0.2 0.2\nv -0.2 0.2 0.2\n";
/// Its 12 triangles, counter-clockwise seen from outside.
const CUBE_F: [[u32; 3]; 12] = [
    [1, 4, 3],
    [1, 3, 2],
    [5, 6, 7],
    [5, 7, 8],
    [1, 2, 6],
    [1, 6, 5],
    [4, 8, 7],
    [4, 7, 3],
    [1, 5, 8],
    [1, 8, 4],
    [2, 3, 7],
    [2, 7, 6],
];

fn faces(f: &[[u32; 3]]) -> String {
    f.iter().map(|[a, b, c]| format!("f {a} {b} {c}\n")).collect()
}

fn cube_obj() -> String {
    format!("{CUBE_V}{}", faces(&CUBE_F))
}

fn inverted() -> String {
    format!("{CUBE_V}{}", faces(&CUBE_F.map(|[a, b, c]| [a, c, b])))
}

fn one_flipped() -> String {
    let mut f = CUBE_F;
    f[5] = [f[5][0], f[5][2], f[5][1]];
    f[9] = [f[9][0], f[9][2], f[9][1]];
    format!("{CUBE_V}{}", faces(&f))
}

fn with_degenerate_and_duplicates() -> String {
    // Two extra collinear points (9, 10) on the cube's bottom edge, a repeated-corner face, a collinear face, the
    // same face twice, and once more in the other winding.
    format!("{CUBE_V}v 0.0 -0.2 -0.2\nv 0.1 -0.2 -0.2\n{}f 1 1 2\nf 1 9 10\nf 1 4 3\nf 3 4 1\n", faces(&CUBE_F))
}

fn open() -> String {
    format!("{CUBE_V}{}", faces(&CUBE_F[2..]))
}

fn non_manifold() -> String {
    // A fin on the edge 1-2: three triangles share it.
    format!("{CUBE_V}v 0.0 -0.5 -0.4\n{}f 1 2 9\n", faces(&CUBE_F))
}

fn load(name: &str, text: &str) -> Result<(mesh::Mesh, MeshReport), String> {
    let dir = out_dir(&format!("mesh_{name}"));
    let p = dir.join(format!("{name}.obj"));
    std::fs::write(&p, text).unwrap();
    mesh::load_obj_report(&p)
}

fn volume(m: &mesh::Mesh) -> f64 {
    m.indices
        .chunks_exact(3)
        .map(|t| {
            let [a, b, c] = [0, 1, 2].map(|k| m.positions[t[k] as usize].as_dvec3());
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

#[test]
fn clean_cube_is_untouched() {
    let (m, r) = load("clean", &cube_obj()).unwrap();
    assert_eq!(r, MeshReport::default());
    assert!(r.findings().is_empty());
    assert_eq!(m.triangle_count(), 12);
    assert!((volume(&m) - 0.064).abs() < 1e-6);
}

#[test]
fn inside_out_cube_is_turned_outward() {
    let (m, r) = load("inverted", &inverted()).unwrap();
    assert!(r.inverted && r.closed() && r.reoriented == 0, "{r:?}");
    assert!((volume(&m) - 0.064).abs() < 1e-6);
    // The recomputed normals point outward.
    for (p, n) in m.positions.iter().zip(&m.normals) {
        assert!(p.dot(*n) > 0.0);
    }
}

#[test]
fn flipped_faces_follow_their_neighbours() {
    let (m, r) = load("flipped", &one_flipped()).unwrap();
    assert_eq!((r.reoriented, r.inverted, r.inconsistent_edges), (2, false, 0), "{r:?}");
    assert!((volume(&m) - 0.064).abs() < 1e-6);
}

#[test]
fn degenerate_and_duplicated_faces_are_removed() {
    let (m, r) = load("degenerate", &with_degenerate_and_duplicates()).unwrap();
    assert_eq!((r.degenerate_removed, r.duplicate_removed), (2, 2), "{r:?}");
    assert!(r.closed(), "{r:?}");
    assert_eq!(m.triangle_count(), 12);
    assert!((volume(&m) - 0.064).abs() < 1e-6);
}

#[test]
fn open_and_non_manifold_meshes_are_reported() {
    let (m, r) = load("open", &open()).unwrap();
    assert_eq!((r.boundary_edges, r.nonmanifold_edges), (4, 0), "{r:?}");
    assert_eq!(m.triangle_count(), 10);
    let (m, r) = load("nonmanifold", &non_manifold()).unwrap();
    assert_eq!((r.boundary_edges, r.nonmanifold_edges), (2, 1), "{r:?}");
    assert_eq!(m.triangle_count(), 13);
    assert!(r.findings().iter().any(|f| f.contains("non-manifold")));
}

#[test]
fn non_finite_and_huge_coordinates_name_the_line() {
    for (i, bad) in ["nan", "NaN", "inf", "-inf", "1e39", "2e9"].iter().enumerate() {
        let text = cube_obj().replace("v 0.2 -0.2 -0.2", &format!("v 0.2 {bad} -0.2"));
        let e = load(&format!("nan{i}"), &text).unwrap_err();
        assert!(e.contains(&format!("nan{i}.obj:2: vertex 2")), "{e}");
    }
}

#[test]
fn nothing_left_is_an_error() {
    let e = load("empty", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\n").unwrap_err();
    assert!(e.contains("no triangles with a non-zero area (2 degenerate)"), "{e}");
}

#[test]
fn shipped_meshes_are_clean_or_known_open() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/meshes");
    for (name, open) in [("bunny.obj", false), ("icosahedron_vertex_up.obj", false), ("dome_open.obj", true)] {
        let (_, r) = mesh::load_obj_report(&dir.join(name)).unwrap();
        assert_eq!(r.boundary_edges > 0, open, "{name}: {r:?}");
        assert_eq!(
            (r.nonmanifold_edges, r.reoriented, r.inverted, r.inconsistent_edges),
            (0, 0, false, 0),
            "{name}: {r:?}"
        );
    }
}

// Render each pathology over the floor and compare the caustic flux with the clean cube's.

fn scene_with(dir: &Path, obj: &str) -> PathBuf {
    std::fs::write(dir.join("m.obj"), obj).unwrap();
    let text = std::fs::read_to_string(scene("tilted_cube.toml"))
        .unwrap()
        .replace("shape = \"cube\"\nsize = 0.4", "shape = \"mesh\"\npath = \"m.obj\"");
    assert!(text.contains("path = \"m.obj\""));
    let p = dir.join("scene.toml");
    std::fs::write(&p, text).unwrap();
    p
}

std::thread_local! {
    /// The warning and error lines logged on this thread since [`logged`] began collecting them.
    static LOGGED: std::cell::RefCell<Option<String>> = const { std::cell::RefCell::new(None) };
}

/// The test binary's logger: every warning and error, printed as the CLI prints them (`warning: ...`,
/// `error: ...`; shown with a failing test's output) and collected for [`logged`] on the thread that logged them.
struct Collect;

impl log::Log for Collect {
    fn enabled(&self, m: &log::Metadata) -> bool {
        m.level() <= log::Level::Warn
    }

    fn log(&self, r: &log::Record) {
        if !self.enabled(r.metadata()) {
            return;
        }
        let line = match r.level() {
            log::Level::Error => format!("error: {}", r.args()),
            _ => format!("warning: {}", r.args()),
        };
        eprintln!("{line}");
        LOGGED.with(|l| {
            if let Some(text) = l.borrow_mut().as_mut() {
                text.push_str(&line);
                text.push('\n');
            }
        });
    }

    fn flush(&self) {}
}

/// Install [`Collect`] as the logger; before [`gpu`], which would install its own.
fn collect_logs() {
    static COLLECT: Collect = Collect;
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        log::set_logger(&COLLECT).expect("the collecting logger is installed before common::gpu installs another");
        log::set_max_level(log::LevelFilter::Warn);
    });
}

/// `f`'s result, or `None` when it panicked, with the warnings and errors this thread logged while it ran.
fn logged<T>(f: impl FnOnce() -> T) -> (Option<T>, String) {
    LOGGED.with(|l| *l.borrow_mut() = Some(String::new()));
    let out = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).ok();
    (out, LOGGED.with(|l| l.borrow_mut().take().unwrap_or_default()))
}

/// Render `obj` as the glass of [`scene_with`] in process on the shared device: the `top` camera's caustics AOV at
/// 64², level 1 (adaptive flux-error) under `transport`. Returns the caustic flux in W (or why the scene did not
/// load or render) and the warnings logged meanwhile; panics when it panicked.
fn render_obj(
    device: &Arc<caustics::gpu::Device>,
    test: &str,
    obj: &str,
    transport: Transport,
) -> (Result<f64, String>, String) {
    let dir = out_dir(test);
    let sc = scene_with(&dir, obj);
    let settings = with(adaptive(1, Metric::FluxError), |s| s.quality.transport = transport);
    let (out, log) = logged(|| -> Result<f64, String> {
        let scene = Scene::load(&sc).map_err(|e| e.to_string())?;
        let mut r = caustics::Renderer::new(device.clone(), scene, settings).map_err(|e| e.to_string())?;
        let camera = r.scene().camera(Some("top"))?.clone();
        // The texel's area, as the CLI's stats weigh `aov_flux_w`.
        let area = camera.pixel_area(64, 64).ok_or("the top camera is orthographic")?;
        let view = r.camera_view(&camera, 64, 64);
        let frame =
            r.render(&caustics::FrameDesc::new(&view, Some(caustics::Aov::Caustics))).map_err(|e| e.to_string())?;
        let Some(caustics::AovData::Float { rgba, .. }) = frame.image else { return Err("no float image".into()) };
        Ok(rgba.iter().map(|p| p[0] as f64).sum::<f64>() * area)
    });
    let out = out.unwrap_or_else(|| panic!("{test}: panicked; logged:\n{log}"));
    assert_eq!(caustics::gpu::validation_message_count(), 0, "{test}: validation messages");
    (out, log)
}

#[test]
fn pathologies_render_like_the_clean_mesh() {
    collect_logs();
    let (_gpu, device) = gpu();
    for transport in [Transport::TwoInterface, Transport::Exact] {
        let (clean, err) = render_obj(&device, &format!("mesh_render_clean_{transport:?}"), &cube_obj(), transport);
        let clean = clean.unwrap_or_else(|e| panic!("{e}\n{err}"));
        assert!(!err.contains("warning: "), "{err}");
        assert!(clean > 1e-3, "clean cube caustic flux {clean}");
        for (name, obj, needle) in [
            ("inverted", inverted(), "inside out"),
            ("flipped", one_flipped(), "reversed the winding of 2 triangles"),
            ("degenerate", with_degenerate_and_duplicates(), "removed 2 degenerate"),
        ] {
            let (flux, err) = render_obj(&device, &format!("mesh_render_{name}_{transport:?}"), &obj, transport);
            let flux = flux.unwrap_or_else(|e| panic!("{name}: {e}\n{err}"));
            assert!(err.contains("object[1] \"glass\".path") && err.contains(needle), "{name}: {err}");
            assert!((flux / clean - 1.0).abs() < 1e-3, "{name} ({transport:?}): flux {flux} W against {clean} W");
        }
    }
    // Open and non-manifold glass renders (as surfaces), with a warning.
    for (name, obj, needle) in
        [("open", open(), "open mesh: 4 boundary edges"), ("fin", non_manifold(), "non-manifold")]
    {
        for transport in [Transport::TwoInterface, Transport::Exact] {
            let (flux, err) = render_obj(&device, &format!("mesh_render_{name}_{transport:?}"), &obj, transport);
            let flux = flux.unwrap_or_else(|e| panic!("{name}: {e}\n{err}"));
            assert!(err.contains(needle), "{name}: {err}");
            assert!(flux.is_finite());
        }
    }
}

/// A NaN vertex through the binary: exit 2 naming the scene's line, the object, the OBJ file and its line.
#[test]
fn a_nan_vertex_exits_2_through_the_binary() {
    let dir = out_dir("bin_nan");
    let sc = scene_with(&dir, &cube_obj().replace("v 0.2 0.2 0.2", "v 0.2 nan 0.2"));
    let (out, stats) = (dir.join("c.exr"), dir.join("s.json"));
    let o = caustics(&[
        "render",
        "--scene",
        sc.to_str().unwrap(),
        "--camera",
        "top",
        "--aov",
        "caustics",
        "--transport",
        "two-interface",
        "--level",
        "1",
        "--size",
        "64x64",
        "--out",
        out.to_str().unwrap(),
        "--stats",
        stats.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("scene.toml:") && err.contains("object[1] \"glass\".path"), "{err}");
    assert!(err.contains("m.obj:7: vertex 7 has a non-finite coordinate `nan`"), "{err}");
}

/// [`scene_with`], the glass's material `{ kind = "mtl" }`: its OBJ's MTL files give it.
fn mtl_scene_with(dir: &Path, obj: &str, mtl: &str) -> PathBuf {
    std::fs::write(dir.join("m.mtl"), mtl).unwrap();
    let p = scene_with(dir, obj);
    let text = std::fs::read_to_string(&p)
        .unwrap()
        .replace("material = { kind = \"dielectric\", ior = 1.5 }", "material = { kind = \"mtl\" }");
    assert!(text.contains("kind = \"mtl\""));
    std::fs::write(&p, text).unwrap();
    p
}

/// A classic MTL, as 3ds Max and Maya write them: an amber glass (`illum 7`, `Ni`, `Tf`) on the cube's top half
/// and a chrome (`illum 5`) on its bottom, a veil (`d 0.5` with `illum 2`) and a textured tile (`map_Kd` with
/// `-o` and `-s`) on two faces: one object per material, each mapped as docs/scenes.md ("OBJ materials") says;
/// the amber half's caustic is its TOML twin's (the same triangles as a `dielectric` with the absorption that
/// keeps `Tf` across the cube's 0.4 m).
#[test]
fn mtl_materials_map_as_documented() {
    let dir = out_dir("mtl_classic");
    write_block_texture(&dir.join("tiles.png"));
    let mtl = "# exported by hand, as 3ds Max writes them\nnewmtl Amber\nKa 0 0 0\nKd 0.1 0.1 0.1\nKs 1 1 1\n\
               Ni 1.6\nd 1.0\nTf 0.9 0.6 0.3\nillum 7\n\nnewmtl Chrome\nKs 1 1 1\nillum 5\n\nnewmtl Veil\n\
               Kd 0.2 0.4 0.6\nd 0.5\nillum 2\n\nnewmtl Tile\nKd 1 1 1\nmap_Kd -o 0.25 0.5 -s 2 2 tiles.png\n";
    let mut obj = format!("mtllib m.mtl\n{CUBE_V}vt 0 0\nvt 1 0\nvt 1 1\n");
    let groups = [("Amber", 0..6), ("Chrome", 6..8), ("Veil", 8..10), ("Tile", 10..12)];
    for (name, range) in groups {
        obj.push_str(&format!("usemtl {name}\n"));
        for t in &CUBE_F[range] {
            obj.push_str(&format!("f {}/1 {}/2 {}/3\n", t[0], t[1], t[2]));
        }
    }
    let scene = Scene::load(&mtl_scene_with(&dir, &obj, mtl)).unwrap();
    let get = |n: &str| scene.objects.iter().find(|o| o.name == n).unwrap_or_else(|| panic!("{n}")).material;
    let tf = glam::Vec3::new(0.9, 0.6, 0.3);
    match get("glass/Amber") {
        Material::Dielectric { ior, absorption, abbe } => {
            assert_eq!((ior, abbe), (1.6, 0.0));
            // The amber half's box: its thinnest side, turned by the object's rotation, in world space.
            let o = scene.objects.iter().find(|o| o.name == "glass/Amber").unwrap();
            let (lo, hi) = o.mesh.bounds();
            let want = -tf.map(f32::ln) / (hi - lo).min_element();
            assert!((absorption - want).abs().max_element() < 1e-5, "{absorption} {want}");
        }
        m => panic!("Amber: {m:?}"),
    }
    assert_eq!(get("glass/Chrome"), Material::Mirror);
    assert_eq!(get("glass/Veil"), Material::diffuse(glam::Vec3::new(0.2, 0.4, 0.6)));
    match get("glass/Tile") {
        Material::Diffuse { albedo, map: Some(map) } => {
            assert_eq!(albedo, glam::Vec3::ONE);
            assert_eq!(map.uv_transform, [[2.0, 0.0, 0.25], [0.0, 2.0, 1.0 - 2.0 - 0.5]]);
        }
        m => panic!("Tile: {m:?}"),
    }
}

/// The amber half of [`mtl_materials_map_as_documented`] casts the caustic of its TOML twin: the same OBJ as a
/// `dielectric` with IOR 1.6 and the absorption that keeps `Tf` across the half's thinnest world-space side.
#[test]
fn mtl_glass_casts_as_its_toml_twin() {
    collect_logs();
    let (_gpu, device) = gpu();
    let dir = out_dir("mtl_twin");
    let mut obj = format!("mtllib m.mtl\n{CUBE_V}usemtl Amber\n");
    obj.push_str(&faces(&CUBE_F));
    let mtl = "newmtl Amber\nNi 1.6\nTf 0.9 0.6 0.3\nillum 7\n";
    let sc = mtl_scene_with(&dir, &obj, mtl);
    let scene = Scene::load(&sc).unwrap();
    let Material::Dielectric { absorption, .. } = scene.objects[1].material else { panic!("glass") };
    let twin = dir.join("twin.toml");
    let text = std::fs::read_to_string(&sc).unwrap().replace(
        "material = { kind = \"mtl\" }",
        &format!("material = {{ kind = \"dielectric\", ior = 1.6, absorption = {:?} }}", absorption.to_array()),
    );
    std::fs::write(&twin, text).unwrap();
    let settings = with(adaptive(2, Metric::FluxError), |s| s.quality.transport = Transport::Exact);
    let shot = |path: &Path| {
        let mut r = caustics::Renderer::new(device.clone(), Scene::load(path).unwrap(), settings.clone()).unwrap();
        top_aov(&mut r, 64, caustics::Aov::Caustics).0
    };
    let (a, b) = (shot(&sc), shot(&twin));
    let m = caustics::metrics::compare(&a, &b, 64, 4.0);
    assert!(m.rel_l1 < 1e-6, "{m:?}");
    let flux = |c: usize| a.data.iter().map(|p| p[c] as f64).sum::<f64>();
    assert!(flux(0) > 2.0 * flux(2) && flux(2) > 0.0, "amber: red {} blue {}", flux(0), flux(2));
    assert_eq!(caustics::gpu::validation_message_count(), 0);
}

/// Bad MTL input exits 2 naming the file, the line and the statement; what the renderer cannot show is warned of.
#[test]
fn bad_mtl_input_names_the_file_and_line() {
    let dir = out_dir("mtl_bad");
    let obj = format!("mtllib m.mtl\n{CUBE_V}usemtl A\n{}", faces(&CUBE_F));
    let mut uv_obj = format!("mtllib m.mtl\n{CUBE_V}vt 0 0\nvt 1 0\nvt 1 1\nusemtl A\n");
    for t in &CUBE_F {
        uv_obj.push_str(&format!("f {}/1 {}/2 {}/3\n", t[0], t[1], t[2]));
    }
    for (obj, mtl, needle) in [
        (&obj, "newmtl A\nNi 1.5\nTf 0.9 x 0.3\nillum 7\n", "m.mtl:3: `Tf`: expected 3 numbers"),
        (&uv_obj, "newmtl A\nillum 2\nmap_Kd missing.png\n", "m.mtl:1 `A`: `map_Kd`: texture file not found"),
        (&obj, "newmtl A\nmap_Kd t.png\n", "m.mtl:1 `A`: `map_Kd t.png`: the mesh has no texture coordinates"),
        (&obj, "Kd 1 1 1\n", "m.mtl:1: `Kd` before any `newmtl`"),
    ] {
        let sc = mtl_scene_with(&dir, obj, mtl);
        let e = Scene::load(&sc).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains("object[1] \"glass\".path") && e.contains(needle), "{mtl:?}: {e}");
    }
    std::fs::remove_file(dir.join("m.mtl")).unwrap();
    let sc = scene_with(&dir, &obj);
    let text = std::fs::read_to_string(&sc).unwrap();
    for (from, to, needle) in [
        ("\"dielectric\", ior = 1.5", "\"mtl\", ior = 1.5", "`ior` does not apply to `kind = \"mtl\"`"),
        ("\"dielectric\", ior = 1.5", "\"mtl\"", "m.obj:1: mtllib `m.mtl`: cannot read"),
    ] {
        std::fs::write(&sc, text.replace(from, to)).unwrap();
        let e = Scene::load(&sc).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains(needle), "{to}: {e}");
    }
    // Through the binary: exit 2, and the warning for a veil the renderer draws opaque.
    std::fs::write(dir.join("m.mtl"), "newmtl A\nd 0.5\nKe 1 0 0\n").unwrap();
    let o = caustics(&[
        "render",
        "--scene",
        sc.to_str().unwrap(),
        "--camera",
        "top",
        "--level",
        "1",
        "--size",
        "32x32",
        "--out",
        dir.join("o.png").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{err}");
    assert!(err.contains("`d 0.5`") && err.contains("`Ke 1 0 0` is not rendered"), "{err}");
    std::fs::write(dir.join("m.mtl"), "newmtl A\nNi -1\n").unwrap();
    let o = caustics(&["render", "--scene", sc.to_str().unwrap(), "--out", dir.join("o.png").to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("m.mtl:2: `Ni`: the index of refraction must be > 0"), "{err}");
}

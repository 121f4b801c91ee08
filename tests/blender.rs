//! glTF files written by Blender's own exporter (tests/data/blender, written by tools/blender_scenes with Blender
//! 3.4 from scenes built there): glass with a modifier, a parented animated rig, two animated objects, a shape-key
//! animation, a mirror beside a negatively scaled node, colored glass, a glass of water whose materials carry
//! their media's priorities, a textured floor, balls sharing one mesh (and the files gltfpack, glTF-Transform and
//! Blender's OBJ exporter make of them), and a skinned cylinder (skins are not
//! supported: it stands at its bind pose, which Blender's numbers give with the armature at rest). Each loads where Blender put everything
//! (tests/data/blender/blender.json: Blender's own evaluation of each object's bounds), each animation renders at
//! its frames as Blender's still export of that pose renders, and each renders what it must against the CPU
//! reference.

mod common;
use caustics::image_io::RgbImage;
use caustics::reference::{Aov as RefAov, Paths, RefParams};
use caustics::scene::{Material, Scene};
use caustics::settings::{Quality, Settings, Transport};
use caustics::{Aov, Renderer};
use common::*;
use glam::Vec3;
use std::path::{Path, PathBuf};

const FPS: f32 = 24.0;

fn fixture(name: &str) -> PathBuf {
    fixture_in("blender", name)
}

/// The two corpora: Blender 3.4's (Debian 12's) and the current release's (5.2, the `bpy` module), the same
/// scenes built by the same script.
const CORPORA: [&str; 2] = ["blender", "blender5"];

fn fixture_in(corpus: &str, name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(corpus).join(format!("{name}.glb"))
}

/// What Blender said of its scenes as it exported them.
fn facts() -> serde_json::Value {
    facts_in("blender")
}

fn facts_in(corpus: &str) -> serde_json::Value {
    read_json(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(corpus).join("blender.json"))
}

/// The bounds and triangle count of the objects named `name` (a mesh of several primitives is several objects,
/// `name#k`).
fn object_bounds(scene: &Scene, name: &str) -> Option<(Vec3, Vec3, usize)> {
    let parts: Vec<_> = scene
        .objects
        .iter()
        .filter(|o| o.name == name || o.name.strip_prefix(name).is_some_and(|r| r.starts_with('#')))
        .collect();
    (!parts.is_empty()).then(|| {
        parts.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY, 0), |(lo, hi, n), o| {
            let (a, b) = o.mesh.bounds();
            (lo.min(a), hi.max(b), n + o.mesh.triangle_count())
        })
    })
}

/// Every mesh object of every fixture of both Blenders stands where that Blender evaluated it, at every frame
/// exported (the animated file at frame/24 s, and the still export of that frame), with Blender's triangle count
/// (modifiers applied); every spot light has Blender's power (W / 4π sr). Measured: within 2e-6 m.
#[test]
fn every_object_stands_where_blender_put_it() {
    let mut checked = 0;
    for corpus in CORPORA {
        let facts = facts_in(corpus);
        let fixture = |name: &str| fixture_in(corpus, name);
        for (name, f) in facts.as_object().unwrap() {
            let scene = Scene::load(&fixture(name)).unwrap_or_else(|e| panic!("{corpus}/{name}: {e}"));
            for (frame, objects) in f["frames"].as_object().unwrap() {
                let t = frame.parse::<f32>().unwrap() / FPS;
                let at = scene.at_time(t);
                let still = fixture(&format!("{name}@{frame}"));
                let mut scenes = vec![("animated", at)];
                if still.is_file() {
                    scenes.push(("still", Scene::load(&still).unwrap()));
                }
                for (what, s) in &scenes {
                    for (obj, b) in objects.as_object().unwrap() {
                        let v = |k: &str| {
                            Vec3::from_slice(
                                &b[k]
                                    .as_array()
                                    .unwrap()
                                    .iter()
                                    .map(|x| x.as_f64().unwrap() as f32)
                                    .collect::<Vec<_>>(),
                            )
                        };
                        let (lo, hi, tris) =
                            object_bounds(s, obj).unwrap_or_else(|| panic!("{name} ({what}): no `{obj}`"));
                        let err = (lo - v("min")).abs().max_element().max((hi - v("max")).abs().max_element());
                        assert!(
                            err < 1e-4,
                            "{name} at frame {frame} ({what}): `{obj}` spans {lo}..{hi}, Blender {}..{}",
                            v("min"),
                            v("max")
                        );
                        assert_eq!(tris as u64, b["triangles"].as_u64().unwrap(), "{name} ({what}): `{obj}` triangles");
                        checked += 1;
                    }
                }
            }
            for (light, l) in f["lights"].as_object().unwrap() {
                assert_eq!(l["type"], "SPOT", "{name}: {light}");
                let watts = l["watts"].as_f64().unwrap() as f32;
                let i = scene.lights[0].intensity;
                assert!((i - watts / (4.0 * std::f32::consts::PI)).abs() < 1e-5 * i, "{name}: {i} W/sr from {watts} W");
            }
        }
    }
    assert!(checked >= 80, "{checked} objects checked");
}

fn settings(transport: Transport) -> Settings {
    Settings { quality: Quality { transport, level: Some(3), ..Quality::default() }, ..Settings::default() }
}

/// A frame of `r` through camera `camera` at 256x144 (the cameras' 16:9): the float AOV and the photon count.
fn frame(r: &mut Renderer, camera: &str, aov: Aov) -> (RgbImage, u64) {
    let (image, report) = camera_aov(r, camera, (256, 144), aov);
    (image, report.photons())
}

/// The caustics AOV from above (`Top`) and the linear beauty from the perspective `Camera`.
fn frames(r: &mut Renderer) -> [(RgbImage, u64); 2] {
    [frame(r, "Top", Aov::Caustics), frame(r, "Camera", Aov::BeautyHdr)]
}

fn rel_l1(a: &RgbImage, b: &RgbImage) -> f64 {
    caustics::metrics::compare(a, b, 256, 4.0).rel_l1
}

/// Each animated fixture at each frame Blender exported still renders as that still export (and the current
/// Blender's spot whose power, color and cone animate, with a zooming camera, through KHR_animation_pointer, as its
/// still exports, which hold each frame's values): placed at frame/24
/// as `render --time` places it, and played there by one renderer's scene update (as `render --sequence` and
/// the viewer play it; for the shape keys, the morph on the GPU), under exact transport, and placed under
/// two-interface transport at the middle frame. Blender's sampled animation and its still export differ by float
/// noise (1e-7 of a coordinate), which shifts the photon grid with the glass's bounds: the bound is 5e-4 (measured:
/// at most 1.0e-4), but 1e-2 for Suzanne's scene, whose light wanders through her many times (open eyes, thin
/// ears) and lands as a faint haze that any shift scatters elsewhere (measured: 6.1e-3 at frame 40, the haze
/// alone; the flux agrees to 1e-4).
#[test]
fn animations_render_as_blenders_still_poses() {
    let (_lock, device) = gpu();
    for (corpus, name, bound) in [
        ("blender", "two_objects", 1e-2),
        ("blender", "rig", 5e-4),
        ("blender", "shape_keys", 5e-4),
        ("blender5", "light_and_lens", 5e-4),
    ] {
        let facts = facts_in(corpus);
        let fixture = |name: &str| fixture_in(corpus, name);
        let scene = Scene::load(&fixture(name)).unwrap();
        let frames_of: Vec<u32> = {
            let mut v: Vec<u32> =
                facts[name]["frames"].as_object().unwrap().keys().map(|k| k.parse().unwrap()).collect();
            v.sort();
            v
        };
        let mut playing = Renderer::new(device.clone(), scene.clone(), settings(Transport::Exact)).unwrap();
        for (k, &f) in frames_of.iter().enumerate() {
            let t = f as f32 / FPS;
            let still = Scene::load(&fixture(&format!("{name}@{f}"))).unwrap();
            let mut transports = vec![Transport::Exact];
            if k == 1 {
                transports.push(Transport::TwoInterface);
            }
            for transport in transports {
                let want = frames(&mut Renderer::new(device.clone(), still.clone(), settings(transport)).unwrap());
                let placed = frames(&mut Renderer::new(device.clone(), scene.at_time(t), settings(transport)).unwrap());
                let mut runs = vec![("placed", placed)];
                if transport == Transport::Exact {
                    playing.set_time(t).unwrap();
                    runs.push(("played", frames(&mut playing)));
                }
                for (how, got) in runs {
                    for (i, aov) in ["caustics", "beauty"].iter().enumerate() {
                        let e = rel_l1(&got[i].0, &want[i].0);
                        let dp = got[i].1 as f64 / want[i].1 as f64 - 1.0;
                        eprintln!(
                            "{name} frame {f} {transport:?} {how} {aov}: rel-L1 {e:.2e}, photons {} / {}",
                            got[i].1, want[i].1
                        );
                        assert!(want[i].0.data.iter().any(|p| p[0] > 0.0), "{name}: a black still frame");
                        assert!(e <= bound, "{name} frame {f} {transport:?} {how} {aov}: rel-L1 {e:.3e}");
                        assert!(dp.abs() <= 1e-3, "{name} frame {f} {how}: photons {} against {}", got[i].1, want[i].1);
                    }
                }
            }
        }
    }
}

/// The CPU reference's caustics through the `Top` camera at 256x144 (cached).
fn reference(path: &Path, photons: u64) -> RgbImage {
    let p = RefParams {
        camera: Some("Top".into()),
        aov: RefAov::Caustics,
        paths: Paths::All,
        photons,
        width: 256,
        height: 144,
        ..RefParams::default()
    };
    let cache = Path::new(env!("CARGO_TARGET_TMPDIR")).join("reference-cache");
    caustics::reference::cached_in(&cache, path, &p).expect("reference")
}

/// The still fixtures' caustics against the CPU reference's (every path, 8M photons; the renderer's exact
/// transport at level 4): the subdivided glass Suzanne, the mirror's patch beside the mirrored prism, and the amber
/// ball. Measured (rel-L1 at 64², flux ratio): 0.021, 0.997; 0.016, 0.999; 0.016, 1.004.
#[test]
fn still_fixtures_render_their_caustics() {
    let (_lock, device) = gpu();
    let settings = Settings { quality: Quality { level: Some(4), ..Quality::default() }, ..Settings::default() };
    for (name, max_rel_l1) in [("glass_modifiers", 0.04), ("mirror", 0.03), ("colored_glass", 0.03)] {
        let path = fixture(name);
        let mut r = Renderer::new(device.clone(), Scene::load(&path).unwrap(), settings.clone()).unwrap();
        let (img, photons) = frame(&mut r, "Top", Aov::Caustics);
        let want = reference(&path, 8_000_000);
        let m = caustics::metrics::compare(&img, &want, 64, 4.0);
        eprintln!("{name}: {photons} photons, rel-L1 {:.4} at 64², flux ratio {:.4}", m.rel_l1, m.flux_ratio);
        assert!(m.rel_l1 <= max_rel_l1, "{name}: rel-L1 {:.4} against the reference", m.rel_l1);
        assert!((m.flux_ratio - 1.0).abs() <= 0.02, "{name}: flux ratio {:.4}", m.flux_ratio);
    }
}

/// A node mirrored by a negative scale renders as the same scene with the mirroring applied to the mesh (Blender's
/// Apply Scale): the prism's caustic and the mirror's patch alike. Measured: rel-L1 2.1e-5 (caustics), 2.6e-7
/// (beauty) at 256².
#[test]
fn a_mirrored_node_renders_as_its_mirror_applied() {
    let (_lock, device) = gpu();
    let s = settings(Transport::Exact);
    let mut a = Renderer::new(device.clone(), Scene::load(&fixture("mirror")).unwrap(), s.clone()).unwrap();
    let mut b = Renderer::new(device.clone(), Scene::load(&fixture("mirror_applied")).unwrap(), s).unwrap();
    let (fa, fb) = (frames(&mut a), frames(&mut b));
    for (i, aov) in ["caustics", "beauty"].iter().enumerate() {
        let e = rel_l1(&fa[i].0, &fb[i].0);
        eprintln!("mirror {aov}: rel-L1 {e:.2e}, photons {} / {}", fa[i].1, fb[i].1);
        assert!(e <= 1e-3, "{aov}: rel-L1 {e:.3e}");
    }
}

/// KHR_materials_volume as Blender writes it from a Volume Absorption node: absorption −ln(color) / distance per
/// channel, and an amber caustic (red over blue).
#[test]
fn colored_glass_absorbs_as_its_volume_says() {
    let scene = Scene::load(&fixture("colored_glass")).unwrap();
    let amber = scene.objects.iter().find(|o| o.name == "Amber").unwrap();
    let Material::Dielectric { absorption, ior, .. } = amber.material else { panic!("glass") };
    let want = Vec3::new(0.9f32.ln(), 0.55f32.ln(), 0.2f32.ln()) * -2.0;
    assert!((absorption - want).abs().max_element() < 1e-4, "{absorption} against {want}");
    assert!((ior - 1.5).abs() < 1e-6, "{ior}");
    let (_lock, device) = gpu();
    let mut r = Renderer::new(device.clone(), scene, settings(Transport::Exact)).unwrap();
    let (img, _) = frame(&mut r, "Top", Aov::Caustics);
    let sum = img.data.iter().fold([0.0f64; 3], |s, p| [s[0] + p[0] as f64, s[1] + p[1] as f64, s[2] + p[2] as f64]);
    eprintln!("amber caustic flux per channel: {sum:?}");
    assert!(sum[0] > sum[1] && sum[1] > 2.0 * sum[2], "an amber caustic: {sum:?}");
}

/// `render` with no --size takes the camera's authored aspect (Blender's 16:9 render resolution): 910x512; a
/// --size of another aspect is rendered as asked, with a warning.
#[test]
fn the_default_size_follows_the_cameras_aspect() {
    let dir = out_dir("blender_size");
    let scene = fixture("glass_modifiers");
    let scene = scene.to_str().unwrap();
    let (_, out) = render(&dir, "default", scene, &["--camera", "Top", "--aov", "caustics", "--level", "1"]);
    let img = caustics::image_io::read_exr(&out).unwrap();
    assert_eq!((img.width, img.height), (910, 512));
    let out = dir.join("square.exr");
    let stderr = ok(&[
        "render",
        "--scene",
        scene,
        "--camera",
        "Top",
        "--aov",
        "caustics",
        "--level",
        "1",
        "--size",
        "64x64",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        stderr.contains("--size 64x64 (aspect 1.000) differs from camera `Top`'s authored aspect 1.778"),
        "{stderr}"
    );
    let img = caustics::image_io::read_exr(&out).unwrap();
    assert_eq!((img.width, img.height), (64, 64));
}

/// Blender writes one animation per animated object, and they all play; `--animation` plays one alone (by name
/// or index): Suzanne's turn alone leaves the ball at its first pose, the slider's alone leaves Suzanne still, each
/// where Blender's frame puts what moves. An unknown one exits 2 naming the file's animations.
#[test]
fn one_animation_plays_alone_when_asked() {
    use caustics::scene::{AnimationChoice, LoadOptions};
    let facts = facts();
    let blender = |frame: &str, obj: &str| {
        let b = &facts["two_objects"]["frames"][frame][obj];
        let v = |k: &str| {
            Vec3::from_slice(&b[k].as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect::<Vec<_>>())
        };
        (v("min"), v("max"))
    };
    let at = |choice: AnimationChoice, obj: &str| {
        let s = Scene::load_with(&fixture("two_objects"), &LoadOptions { animation: choice }).unwrap();
        assert_eq!(s.animations, vec!["SuzanneAction".to_string(), "SliderAction".to_string()]);
        let (lo, hi, _) = object_bounds(&s.at_time(18.0 / FPS), obj).unwrap();
        (lo, hi)
    };
    let near =
        |a: (Vec3, Vec3), b: (Vec3, Vec3)| (a.0 - b.0).abs().max_element().max((a.1 - b.1).abs().max_element()) < 1e-4;
    for (choice, turns, slides) in [
        (AnimationChoice::All, true, true),
        (AnimationChoice::Index(0), true, false),
        (AnimationChoice::Name("SliderAction".into()), false, true),
    ] {
        let frame = |moves: bool| if moves { "18" } else { "1" };
        assert!(near(at(choice.clone(), "Suzanne"), blender(frame(turns), "Suzanne")), "{choice:?}: Suzanne");
        assert!(near(at(choice.clone(), "Ball"), blender(frame(slides), "Ball")), "{choice:?}: the ball");
    }
    let dir = out_dir("blender_animation_choice");
    let out = dir.join("x.png");
    let o = caustics(&[
        "render",
        "--scene",
        fixture("two_objects").to_str().unwrap(),
        "--animation",
        "Walk",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(
            "animation `Walk`: no animation has that name (the file has 0 \"SuzanneAction\", 1 \"SliderAction\")"
        ),
        "{stderr}"
    );
    assert_no_output(&out);
}

/// Media by priority from Blender (docs/scenes.md "Media"): a glass of water as an artist models it, the water a
/// cylinder reaching 1 cm into the glass's wall and base, each material with a custom property `priority` that the
/// exporter writes as its extras (the glass 2, the water 1). The file loads with those priorities, and its caustic
/// through the wall and the water matches the CPU reference's (every path, 4M photons; exact transport at level
/// 3): rel-L1 2.58% at 64², flux ratio 0.993. Read without the priorities (as from a tool that wrote none), the
/// water's side and base inside the glass become interfaces with air: 15.0%, 0.959.
#[test]
fn a_glass_of_water_from_blender_resolves_its_overlap_by_priority() {
    let path = fixture("glass_of_water");
    let scene = Scene::load(&path).unwrap();
    let priority = |name: &str| scene.objects.iter().find(|o| o.name == name).map(|o| o.priority);
    assert_eq!((priority("Glass"), priority("Water"), priority("Floor")), (Some(2), Some(1), Some(0)));
    let (_lock, device) = gpu();
    let settings = Settings { quality: Quality { level: Some(3), ..Quality::default() }, ..Settings::default() };
    let want = reference(&path, 4_000_000);
    let mut flat = scene.clone();
    flat.objects.iter_mut().for_each(|o| o.priority = 0);
    let score = |scene: Scene| {
        let mut r = Renderer::new(device.clone(), scene, settings.clone()).unwrap();
        let (img, _) = frame(&mut r, "Top", Aov::Caustics);
        caustics::metrics::compare(&img, &want, 64, 4.0)
    };
    let (m, without) = (score(scene), score(flat));
    eprintln!("glass of water: rel-L1 {:.4}, flux ratio {:.4}", m.rel_l1, m.flux_ratio);
    eprintln!("without its priorities: rel-L1 {:.4}, flux ratio {:.4}", without.rel_l1, without.flux_ratio);
    assert!(m.rel_l1 <= 0.05 && (m.flux_ratio - 1.0).abs() <= 0.02, "{m:?}");
    assert!(without.rel_l1 > 2.0 * m.rel_l1, "the priorities matter: {without:?} against {m:?}");
}

/// gltfpack 1.3 (npm) writes KHR_mesh_quantization by default (tests/data/gltfpack, written from the fixtures above
/// by tools/gltfpack_scenes): positions as 14-bit integers that the node's transform scales back, normals as 8-bit
/// normalized bytes, a morph target's displacements as shorts; `-c` adds EXT_meshopt_compression, and `-cc` its
/// filters. Each renders as its Blender source does (caustics from `Top` at 256x144, exact transport at level 3;
/// rel-L1 at 256), measured on lavapipe:
/// - unquantized (`-noq`, gltfpack's other rewrites alone): the same photon count, and the frame within float noise;
/// - 16-bit positions and normals: 0.28%, flux ratio 0.99991;
/// - the default: 6.0%, flux 0.9975. That is the 8-bit normals' bound (each normal within 0.5° of its source,
///   and a glass's caustic moves with its normals); 12-bit normals with the default positions give 0.75%
///   (`render --level 4`);
/// - compressed (`-c`): the same positions and normals as the default's uncompressed file, and the same triangles,
///   each starting at another corner where the index codec rotated it: the same photons, 6.3e-5 apart;
/// - compressed with filters, float positions through the exponential filter and 16-bit octahedral normals
///   (`-cc -vn 16 -vpf`): 0.23%, flux 0.99987;
/// - the shape keys by default, at t = 0.5 s (their morph on the GPU): 0.39%, flux 1.0003; with `-cc` (8-bit
///   octahedral normals): 0.76%, flux 1.0002.
///
/// glTF-Transform 4.5's `draco` (KHR_draco_mesh_compression at its defaults, 14-bit positions and 10-bit normals;
/// tests/data/gltf-transform, by tools/gltf_transform_scenes): the glass of water 2.2%, flux 0.9999; the shape keys
/// (their morph targets uncompressed beside the Draco stream) 0.24%, flux 0.9999.
#[test]
fn gltfpack_and_gltf_transform_files_render_as_their_sources() {
    let (_lock, device) = gpu();
    // A name with a `/` is a path under tests/data; the others are gltfpack's.
    let packed = |name: &str| {
        let under = if name.contains('/') { "tests/data".to_string() } else { "tests/data/gltfpack".to_string() };
        Path::new(env!("CARGO_MANIFEST_DIR")).join(under).join(format!("{name}.glb"))
    };
    let shot = |path: &Path, time: f32| {
        let scene = Scene::load(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut r = Renderer::new(device.clone(), scene, settings(Transport::Exact)).unwrap();
        r.set_time(time).unwrap();
        frame(&mut r, "Top", Aov::Caustics)
    };
    let (water, photons) = shot(&fixture("glass_of_water"), 0.0);
    let (keys, _) = shot(&fixture("shape_keys"), 0.5);
    let (quantized, quantized_photons) = shot(&packed("glass_of_water"), 0.0);
    for (name, want, want_photons) in
        [("glass_of_water_noq", &water, photons), ("glass_of_water_meshopt", &quantized, quantized_photons)]
    {
        let (img, n) = shot(&packed(name), 0.0);
        assert_eq!(n, want_photons, "{name}: photons");
        assert!(rel_l1(&img, want) < 2e-4, "{name}: rel-L1 {}", rel_l1(&img, want));
    }
    let cases = [
        ("glass_of_water_16bit", 0.0, &water, None, 0.005),
        ("glass_of_water", 0.0, &water, Some(&quantized), 0.07),
        ("glass_of_water_meshopt_filters", 0.0, &water, None, 0.005),
        ("shape_keys", 0.5, &keys, None, 0.007),
        ("shape_keys_meshopt", 0.5, &keys, None, 0.01),
        ("gltf-transform/glass_of_water_draco", 0.0, &water, None, 0.03),
        ("gltf-transform/shape_keys_draco", 0.5, &keys, None, 0.005),
    ];
    for (name, time, want, rendered, max_rel) in cases {
        let img = match rendered {
            Some(img) => img.clone(),
            None => shot(&packed(name), time).0,
        };
        let m = caustics::metrics::compare(&img, want, 256, 4.0);
        eprintln!("gltfpack {name}: rel-L1 {:.5}, flux ratio {:.5}", m.rel_l1, m.flux_ratio);
        assert!(m.rel_l1 < max_rel && (m.flux_ratio - 1.0).abs() < 0.005, "{name}: {m:?}");
    }
}

/// Blender's textured floor (an 8×8-block PNG, repeated twice along u by a Mapping node, which the exporter writes as
/// KHR_texture_transform) with its image re-encoded as WebP by glTF-Transform (EXT_texture_webp, required). The
/// lossy image decodes texel for texel as libwebp decodes it (tests/data/gltf-transform/textured_webp.libwebp.png,
/// written through sharp); the lossless one renders the same beauty as the PNG, the lossy one within the codec's
/// own error (libwebp's decode of it is 5.3% of the texels' sum from the PNG's: 64-pixel blocks of saturated
/// colors are hard on its 4:2:0 chroma). The texture shows: the beauty without it differs by far more. Measured
/// (rel-L1 at 256², linear beauty from the perspective camera): lossless 2e-9, lossy 0.040, untextured 1.6.
#[test]
fn webp_textures_render_as_their_png_sources() {
    let (_lock, device) = gpu();
    let shot = |scene: Scene| {
        let mut r = Renderer::new(device.clone(), scene, settings(Transport::Exact)).unwrap();
        frame(&mut r, "Camera", Aov::BeautyHdr).0
    };
    let load = |path: &Path| Scene::load(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let webp = |name: &str| Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gltf-transform").join(name);
    let lossy = load(&webp("textured_webp.glb"));
    let libwebp = caustics::scene::Texture::load(&webp("textured_webp.libwebp.png")).unwrap();
    assert_eq!(lossy.textures.len(), 1);
    let ours = &lossy.textures[0];
    assert_eq!((ours.width, ours.height), (libwebp.width, libwebp.height));
    let differ = ours.texels.iter().zip(&libwebp.texels).filter(|(a, b)| a[..3] != b[..3]).count();
    assert_eq!(differ, 0, "texels that differ from libwebp's decode");
    let png = load(&fixture("textured"));
    assert_eq!(png.textures.len(), 1, "the floor's texture");
    let mut untextured = png.clone();
    for o in &mut untextured.objects {
        if let Material::Diffuse { map, .. } = &mut o.material {
            *map = None;
        }
    }
    let want = shot(png);
    for (name, scene, max_rel) in
        [("lossless", load(&webp("textured_webp_lossless.glb")), 1e-6), ("lossy", lossy, 0.05)]
    {
        let got = rel_l1(&shot(scene), &want);
        eprintln!("{name} WebP: rel-L1 {got:.2e}");
        assert!(got <= max_rel, "{name} WebP: rel-L1 {got}");
    }
    let bare = rel_l1(&shot(untextured), &want);
    eprintln!("untextured: rel-L1 {bare:.3}");
    assert!(bare > 0.2, "the texture is not what the beauty shows: {bare}");
}

/// Blender's four glass balls sharing one mesh, written as one node drawing it at four placements
/// (EXT_mesh_gpu_instancing) by gltfpack (`-mi`, unquantized and quantized) and glTF-Transform (`instance`): each
/// ball stands where Blender put it, the four share one BVH mesh with the floor's beside it, and the caustics are
/// the source's. gltfpack reorders the mesh's triangles, which moves a few photons; its default quantization
/// writes 8-bit normals, whose error shows as the glass of water's does (measured: unquantized 3 photons of
/// 67,874 apart, rel-L1 4.4e-4 at 256²; glTF-Transform's the same photons, 1.2e-4; quantized 58 photons apart,
/// 0.035; flux within 2e-4).
#[test]
fn instanced_files_render_as_their_sources() {
    let (_lock, device) = gpu();
    let facts = facts();
    let balls = &facts["instances"]["frames"]["1"];
    let mut want_bounds: Vec<(Vec3, Vec3)> = ["Ball", "Ball.001", "Ball.002", "Ball.003"]
        .iter()
        .map(|n| {
            let v = |k: &str| {
                Vec3::from_slice(
                    &balls[n][k].as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect::<Vec<_>>(),
                )
            };
            (v("min"), v("max"))
        })
        .collect();
    let by_x = |a: &(Vec3, Vec3), b: &(Vec3, Vec3)| (a.0.x, a.0.z).partial_cmp(&(b.0.x, b.0.z)).unwrap();
    want_bounds.sort_by(by_x);
    let shot = |path: &Path| {
        let scene = Scene::load(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut r = Renderer::new(device.clone(), scene, settings(Transport::Exact)).unwrap();
        let (img, photons) = frame(&mut r, "Top", Aov::Caustics);
        let bvh = &r.scene_buffers().bvh;
        (img, photons, bvh.triangle_count, bvh.instance_count)
    };
    let (want, want_photons, tris, instances) = shot(&fixture("instances"));
    assert_eq!((tris, instances), (2 + 960, 5), "the source: the floor and one ball mesh, five instances");
    for (name, tolerance, max_photons, max_rel) in [
        ("gltfpack/instances_noq", 1e-5, 1e-4, 2e-3),
        ("gltf-transform/instances", 1e-5, 0.0, 1e-3),
        ("gltfpack/instances", 2e-3, 2e-3, 0.05),
    ] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/data/{name}.glb"));
        let scene = Scene::load(&path).unwrap();
        let mut got: Vec<(Vec3, Vec3)> =
            scene.objects.iter().filter(|o| o.mesh.triangle_count() == 960).map(|o| o.mesh.bounds()).collect();
        got.sort_by(by_x);
        assert_eq!(got.len(), 4, "{name}: four balls");
        for (g, w) in got.iter().zip(&want_bounds) {
            let err = (g.0 - w.0).abs().max_element().max((g.1 - w.1).abs().max_element());
            assert!(err < tolerance, "{name}: a ball spans {:?}, Blender's {:?}", g, w);
        }
        let (img, photons, tris, instances) = shot(&path);
        assert_eq!((tris, instances), (2 + 960, 5), "{name}: one ball mesh, five instances");
        let m = caustics::metrics::compare(&img, &want, 256, 4.0);
        eprintln!(
            "{name}: {photons} photons ({want_photons}), rel-L1 {:.2e}, flux ratio {:.5}",
            m.rel_l1, m.flux_ratio
        );
        let dp = (photons as f64 / want_photons as f64 - 1.0).abs();
        assert!(dp <= max_photons, "{name}: {photons} photons, the source {want_photons}");
        assert!(m.rel_l1 <= max_rel && (m.flux_ratio - 1.0).abs() < 0.005, "{name}: {m:?}");
    }
}

/// A scene of one OBJ whose materials come from its MTL (`kind = "mtl"`), the OBJ at `obj` (absolute), with a
/// placeholder light and camera (the tests give it the glTF export's).
fn obj_scene(dir: &Path, obj: &Path) -> Scene {
    let text = r#"
[[light]]
kind = "spot"
position = [0.0, 2.0, 0.0]
target = [0.0, 0.0, 0.0]
cone_deg = 40.0
intensity = 1.0

[[camera]]
name = "c"
kind = "perspective"
position = [0.0, 1.0, 2.0]
target = [0.0, 0.0, 0.0]
fov_deg = 40.0

[[object]]
name = "obj"
shape = "mesh"
path = "OBJ"
material = { kind = "mtl" }
"#;
    let path = dir.join("obj.toml");
    std::fs::write(&path, text.replace("OBJ", &obj.display().to_string())).unwrap();
    Scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Blender's OBJ exports (its exporter's defaults, with the MTL and the texture copied beside them) render as its
/// glTF exports of the same scenes: the textured floor (`map_Kd -s 2 1 1 blocks.png`: the texture where the glTF's
/// KHR_texture_transform puts it, OBJ's upward v flipped) and the mirror (`illum 3`) beside the prism. Blender's
/// OBJ exporter writes glass as an opaque surface (`illum 2`, `d 1`), so the test gives the glass parts the glTF's
/// glass. Each material is one object, `obj/NAME`. Measured (rel-L1 at 256²): the textured floor's beauty
/// 3.8e-5 from the perspective camera, the mirror scene's caustics 1.1e-3 from above (the two exporters number the
/// prism's vertices differently).
#[test]
fn blenders_obj_exports_render_as_its_gltf_exports() {
    let (_lock, device) = gpu();
    let dir = out_dir("blender_obj");
    for (name, camera, aov, max_rel) in
        [("textured", "Camera", Aov::BeautyHdr, 5e-4), ("mirror_applied", "Top", Aov::Caustics, 5e-3)]
    {
        let gltf = Scene::load(&fixture(name)).unwrap();
        let mut obj = obj_scene(&dir, &fixture(name).with_extension("obj"));
        obj.lights = gltf.lights.clone();
        obj.cameras = gltf.cameras.clone();
        let mut names: Vec<&str> = obj.objects.iter().map(|o| o.name.as_str()).collect();
        names.sort();
        let want: &[&str] = match name {
            "textured" => &["obj/Ball", "obj/Floor"],
            _ => &["obj/Floor", "obj/Glass", "obj/Mirror", "obj/Wall"],
        };
        assert_eq!(names, want, "{name}: one object per material");
        let glass = gltf.objects.iter().find(|o| matches!(o.material, Material::Dielectric { .. })).unwrap().material;
        for o in &mut obj.objects {
            match o.name.as_str() {
                "obj/Ball" | "obj/Glass" => {
                    assert!(matches!(o.material, Material::Diffuse { .. }), "Blender's OBJ glass is opaque");
                    o.material = glass;
                }
                "obj/Mirror" => assert_eq!(o.material, Material::Mirror, "{name}: illum 3"),
                "obj/Floor" if name == "textured" => {
                    assert!(matches!(o.material, Material::Diffuse { map: Some(_), .. }), "map_Kd");
                }
                _ => assert!(matches!(o.material, Material::Diffuse { map: None, .. }), "{}", o.name),
            }
        }
        let shot = |scene: Scene| {
            let mut r = Renderer::new(device.clone(), scene, settings(Transport::Exact)).unwrap();
            frame(&mut r, camera, aov).0
        };
        let m = caustics::metrics::compare(&shot(obj), &shot(gltf), 256, 4.0);
        eprintln!("{name}: OBJ against glTF: rel-L1 {:.2e}, flux ratio {:.5}", m.rel_l1, m.flux_ratio);
        assert!(m.rel_l1 <= max_rel && (m.flux_ratio - 1.0).abs() < 0.005, "{name}: {m:?}");
    }
}

/// The current Blender's exports (5.2, through the `bpy` module: tests/data/blender5, written by the same script
/// as 3.4's) render as Blender 3.4's of the same scenes: every file, animated ones at 0.5 s, the caustics from
/// above and the beauty from the perspective camera, with the same photons within 0.1%. Both exporters write the
/// same geometry up to float noise and vertex order, which scatter the faint haze of light wandering through
/// Suzanne (as in [`animations_render_as_blenders_still_poses`]). Measured (rel-L1 at 256²): Suzanne's scenes'
/// caustics at most 1.6e-2, the others' 1.3e-3; every beauty 4.0e-4; flux within 6e-4.
#[test]
fn the_current_blenders_exports_render_as_blender_34s() {
    let (_lock, device) = gpu();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/blender5");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "glb"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert!(names.len() >= 20, "{names:?}");
    let mut worst = (0.0f64, String::new());
    for name in names.iter().filter(|n| fixture(n).is_file()) {
        let shots = CORPORA.map(|corpus| {
            let scene = Scene::load(&fixture_in(corpus, name)).unwrap_or_else(|e| panic!("{corpus}/{name}: {e}"));
            let mut r = Renderer::new(device.clone(), scene, settings(Transport::Exact)).unwrap();
            r.set_time(if name.contains('@') { 0.0 } else { 0.5 }).unwrap();
            frames(&mut r)
        });
        for (k, what) in ["caustics from above", "beauty"].iter().enumerate() {
            let ((old, old_photons), (new, new_photons)) = (&shots[0][k], &shots[1][k]);
            let m = caustics::metrics::compare(new, old, 256, 4.0);
            eprintln!(
                "{name} {what}: rel-L1 {:.2e}, flux ratio {:.5}, photons {new_photons} ({old_photons})",
                m.rel_l1, m.flux_ratio
            );
            if m.rel_l1 > worst.0 {
                worst = (m.rel_l1, format!("{name} {what}"));
            }
            let dp = (*new_photons as f64 / *old_photons as f64 - 1.0).abs();
            assert!(dp <= 1e-3, "{name}: {new_photons} photons, 3.4's {old_photons}");
            let suzanne = name.starts_with("two_objects") || name.starts_with("glass_modifiers");
            let bound = match (k, suzanne) {
                (0, true) => 0.025,
                (0, false) => 3e-3,
                _ => 1e-3,
            };
            assert!(m.rel_l1 <= bound && (m.flux_ratio - 1.0).abs() < 2e-3, "{name} {what}: {m:?}");
        }
    }
    eprintln!("worst: {:.2e} ({})", worst.0, worst.1);
}

/// `--frame N` is Blender's frame N: N / `--frame-rate` seconds (24 by default, Blender's), the frame `render
/// --time` renders there, in `render` and `reference` alike; with `--time`, or a rate that is not positive, it
/// exits 2.
#[test]
fn frame_n_is_blenders_frame_n() {
    let dir = out_dir("blender_frame");
    let file = fixture("two_objects");
    let render = |extra: &[&str], name: &str| {
        let (out, stats) = (dir.join(format!("{name}.exr")), dir.join(format!("{name}.json")));
        let mut args = vec!["render", "--scene", file.to_str().unwrap(), "--camera", "Top", "--aov", "caustics"];
        args.extend_from_slice(&["--level", "1", "--size", "32x18", "--out", out.to_str().unwrap()]);
        args.extend_from_slice(&["--stats", stats.to_str().unwrap()]);
        args.extend_from_slice(extra);
        let o = caustics(&args);
        (o, out, stats)
    };
    let pixels = |path: &Path| caustics::image_io::read_exr(path).unwrap();
    let mut images = Vec::new();
    for (extra, name) in [
        (&["--time", "0.75"][..], "time"),
        (&["--frame", "18"], "frame"),
        (&["--frame", "36", "--frame-rate", "48"], "rate"),
        (&["--time", "0.5"], "other"),
    ] {
        let (o, out, _) = render(extra, name);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        images.push(pixels(&out));
    }
    // The same frame up to the splat's float sums, which the GPU adds in any order.
    let apart = |k: usize| caustics::metrics::compare(&images[k], &images[0], 32, 4.0).rel_l1;
    assert!(apart(1) < 1e-5, "frame 18 at 24 fps is 0.75 s: {}", apart(1));
    assert!(apart(2) < 1e-5, "frame 36 at 48 fps is 0.75 s: {}", apart(2));
    assert!(apart(3) > 0.05, "the glass moves between 0.5 s and 0.75 s: {}", apart(3));
    for (extra, needle) in [
        (&["--frame", "18", "--time", "0.5"][..], "--time"),
        (&["--frame", "18", "--frame-rate", "0"][..], "--frame-rate 0"),
    ] {
        let (o, _, _) = render(extra, "bad");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {err}");
        assert!(err.contains(needle), "{extra:?}: {err}");
    }
    let out = dir.join("reference.exr");
    let o = caustics(&[
        "reference",
        "--scene",
        file.to_str().unwrap(),
        "--camera",
        "Top",
        "--aov",
        "caustics",
        "--photons",
        "20000",
        "--size",
        "32x18",
        "--frame",
        "18",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

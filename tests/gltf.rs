//! glTF 2.0 import: a glTF file built here from the same meshes as a TOML scene loads into the same Scene and
//! renders the same caustic flux; GLB carries the same data; bad files exit with code 2 and never panic.

mod common;
use caustics::scene::{mesh, LightKind, Material, Projection, Scene};
use caustics::settings::{Metric, Transport};
use common::gltf_doc::*;
use common::*;
use glam::Vec3;
use serde_json::{json, Value};
use std::path::Path;
use std::sync::Arc;

/// The TOML twin of [`gltf_scene`]: the sphere scene's floor, light and `top` camera, with a 0.4 m glass cube.
const TOML: &str = r#"[[light]]
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

[[object]]
name = "floor"
shape = "plane"
size = [2.0, 2.0]
material = { kind = "diffuse", albedo = 0.8 }

[[object]]
name = "glass"
shape = "cube"
size = 0.4
translate = [0.0, 0.5, 0.0]
material = { kind = "dielectric", ior = 1.5 }
"#;

/// The glTF twin of [`TOML`] as JSON, and its binary buffer (not yet attached).
fn gltf_scene() -> (Value, Vec<u8>) {
    let mut bin = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut push = |bytes: Vec<u8>, acc: Value, bin: &mut Vec<u8>| -> usize {
        views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len()}));
        bin.extend_from_slice(&bytes);
        let mut acc = acc;
        acc["bufferView"] = json!(views.len() - 1);
        accessors.push(acc);
        accessors.len() - 1
    };
    let mut meshes = Vec::new();
    for (name, m, material) in [("floor", mesh::plane(2.0, 2.0), 0), ("glass", mesh::cube(Vec3::splat(0.4)), 1)] {
        let (lo, hi) = m.bounds();
        let p = push(
            bytemuck::cast_slice(&m.positions).to_vec(),
            json!({"componentType": 5126, "count": m.positions.len(), "type": "VEC3",
                   "min": lo.to_array(), "max": hi.to_array()}),
            &mut bin,
        );
        let n = push(
            bytemuck::cast_slice(&m.normals).to_vec(),
            json!({"componentType": 5126, "count": m.normals.len(), "type": "VEC3"}),
            &mut bin,
        );
        let i = push(
            bytemuck::cast_slice(&m.indices).to_vec(),
            json!({"componentType": 5125, "count": m.indices.len(), "type": "SCALAR"}),
            &mut bin,
        );
        meshes.push(json!({"name": name, "primitives": [
            {"attributes": {"POSITION": p, "NORMAL": n}, "indices": i, "material": material}]}));
    }
    // Rotation by -90° about x: the node's -Z (its view / beam axis) becomes world -y and its +Y becomes -z.
    let down = [-std::f32::consts::FRAC_1_SQRT_2, 0.0, 0.0, std::f32::consts::FRAC_1_SQRT_2];
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_transmission", "KHR_materials_ior",
                           "KHR_materials_volume", "KHR_materials_dispersion", "EXT_made_up",
                           "KHR_materials_clearcoat"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 3]}],
        "nodes": [
            {"name": "floor", "mesh": 0},
            {"name": "glass", "mesh": 1, "translation": [0.0, 0.5, 0.0]},
            {"name": "top", "camera": 0, "translation": [0.0, 3.0, 0.0], "rotation": down},
            {"name": "spot", "translation": [0.0, 2.0, 0.0], "rotation": down,
             "extensions": {"KHR_lights_punctual": {"light": 0}}}
        ],
        "meshes": meshes,
        "materials": [
            {"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0}},
            {"name": "glass", "extensions": {
                "KHR_materials_transmission": {"transmissionFactor": 1.0},
                "KHR_materials_ior": {"ior": 1.5},
                "KHR_materials_volume": {"thicknessFactor": 0.4, "attenuationDistance": 1.0},
                "KHR_materials_dispersion": {"dispersion": 0.0}}}
        ],
        "cameras": [{"type": "orthographic", "orthographic": {"xmag": 1.0, "ymag": 1.0, "znear": 0.01, "zfar": 10.0}}],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "spot", "intensity": 683.0, "color": [1.0, 1.0, 1.0],
             "spot": {"innerConeAngle": 0.0, "outerConeAngle": 40f32.to_radians()}}
        ]}},
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": views,
        "accessors": accessors,
    });
    (doc, bin)
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-5
}

/// The loaded glTF scene matches the TOML scene: objects, triangles, materials, light and camera.
fn assert_same(g: &Scene, t: &Scene) {
    assert_eq!(g.objects.len(), t.objects.len());
    assert_eq!(g.triangle_count(), t.triangle_count());
    for (a, b) in g.objects.iter().zip(&t.objects) {
        assert_eq!(a.name, b.name);
        assert_eq!(a.material, b.material, "{}", a.name);
        assert_eq!(a.mesh.triangle_count(), b.mesh.triangle_count(), "{}", a.name);
        let ((alo, ahi), (blo, bhi)) = (a.mesh.bounds(), b.mesh.bounds());
        assert!(close(alo, blo) && close(ahi, bhi), "{}: bounds {alo} {ahi} vs {blo} {bhi}", a.name);
        for (p, q) in a.mesh.positions.iter().zip(&b.mesh.positions) {
            assert!(close(*p, *q), "{}: {p} vs {q}", a.name);
        }
        for (p, q) in a.mesh.normals.iter().zip(&b.mesh.normals) {
            assert!(close(*p, *q), "{}: normal {p} vs {q}", a.name);
        }
    }
    assert_eq!(g.lights.len(), 1);
    let (gl, tl) = (&g.lights[0], &t.lights[0]);
    assert_eq!(gl.kind, LightKind::Spot);
    assert!(close(gl.position, tl.position), "{} vs {}", gl.position, tl.position);
    let dir = |l: &caustics::scene::Light| (l.target - l.position).normalize();
    assert!(close(dir(gl), dir(tl)));
    assert!((gl.intensity - tl.intensity).abs() < 1e-5, "{} vs {}", gl.intensity, tl.intensity);
    assert!((gl.cone - tl.cone).abs() < 1e-5, "{} vs {}", gl.cone, tl.cone);
    assert!(close(gl.color, tl.color));
    let (gc, tc) = (g.camera(Some("top")).unwrap(), t.camera(Some("top")).unwrap());
    assert_eq!(gc.projection, Projection::Orthographic { half_height: 1.0 });
    assert_eq!(gc.projection, tc.projection);
    assert!(close(gc.position, tc.position));
    assert!(close((gc.target - gc.position).normalize(), (tc.target - tc.position).normalize()));
    assert!(close(gc.up, tc.up), "{} vs {}", gc.up, tc.up);
}

#[test]
fn gltf_and_glb_load_like_toml() {
    let dir = out_dir("gltf_load");
    let toml = Scene::load(&write(&dir, "twin.toml", TOML)).unwrap();
    let (doc, bin) = gltf_scene();
    let g = Scene::load(&write(&dir, "twin.gltf", embedded(doc.clone(), &bin))).unwrap();
    assert_same(&g, &toml);
    // The volume has no attenuation color (white): no absorption; dispersion 0: none.
    assert!(matches!(g.objects[1].material, Material::Dielectric { ior, absorption, abbe }
        if ior == 1.5 && absorption == Vec3::ZERO && abbe == 0.0));
    // KHR_materials_volume: attenuationColor reached at attenuationDistance, Beer–Lambert per channel.
    let mut tinted = doc.clone();
    tinted["materials"][1]["extensions"]["KHR_materials_volume"]["attenuationDistance"] = json!(0.5);
    tinted["materials"][1]["extensions"]["KHR_materials_volume"]["attenuationColor"] = json!([0.5, 0.25, 1.0]);
    // KHR_materials_dispersion: dispersion = 20 / V_d.
    tinted["materials"][1]["extensions"]["KHR_materials_dispersion"]["dispersion"] = json!(0.5);
    let t = Scene::load(&write(&dir, "tinted.gltf", embedded(tinted.clone(), &bin))).unwrap();
    let Material::Dielectric { absorption, abbe, .. } = t.objects[1].material else { panic!("glass") };
    let ln2 = std::f32::consts::LN_2;
    assert!(close(absorption, Vec3::new(2.0 * ln2, 4.0 * ln2, 0.0)), "absorption {absorption} /m");
    assert_eq!(abbe, 40.0);
    let mut negative = tinted;
    negative["materials"][1]["extensions"]["KHR_materials_volume"]["attenuationDistance"] = json!(-1.0);
    let e = Scene::load(&write(&dir, "negative.gltf", embedded(negative, &bin))).unwrap_err().to_string();
    assert!(e.contains("attenuationDistance") && e.contains("> 0"), "{e}");
    // A glass material's extras.priority makes its objects volumes by priority; a bad one names its path.
    let mut nested = doc.clone();
    nested["materials"][1]["extras"] = json!({"priority": 3});
    let n = Scene::load(&write(&dir, "nested.gltf", embedded(nested.clone(), &bin))).unwrap();
    assert_eq!((n.objects[1].priority, n.objects[0].priority), (3, 0));
    nested["materials"][1]["extras"] = json!({"priority": 1.5});
    let e = Scene::load(&write(&dir, "nested_bad.gltf", embedded(nested, &bin))).unwrap_err().to_string();
    assert!(e.contains("materials[1].extras.priority") && e.contains("integer in 1..=255"), "{e}");
    // GLB: the same JSON with the buffer in the BIN chunk.
    let b = Scene::load(&write(&dir, "twin.glb", glb(&doc, &bin))).unwrap();
    assert_same(&b, &toml);
    // An external .bin next to the file, and normals left out (computed: the cube's are flat per face).
    let mut ext = doc.clone();
    ext["buffers"][0]["uri"] = json!("twin.bin");
    write(&dir, "twin.bin", &bin);
    let e = Scene::load(&write(&dir, "ext.gltf", serde_json::to_string(&ext).unwrap())).unwrap();
    assert_same(&e, &toml);
    let mut no_normals = doc.clone();
    no_normals["meshes"][0]["primitives"][0]["attributes"].as_object_mut().unwrap().remove("NORMAL");
    let n = Scene::load(&write(&dir, "nn.gltf", embedded(no_normals, &bin))).unwrap();
    assert!(n.objects[0].mesh.normals.iter().all(|v| close(*v, Vec3::Y)));
    // Mirror and diffuse mappings; a directional light's lux → W/m².
    let mut m = doc.clone();
    m["materials"][1] = json!({"pbrMetallicRoughness": {"metallicFactor": 1.0, "roughnessFactor": 0.0}});
    m["extensions"]["KHR_lights_punctual"]["lights"][0] = json!({"type": "directional", "intensity": 1366.0});
    let s = Scene::load(&write(&dir, "mirror.gltf", embedded(m, &bin))).unwrap();
    assert_eq!(s.objects[1].material, Material::Mirror);
    assert_eq!(s.lights[0].kind, LightKind::Directional);
    assert!((s.lights[0].intensity - 2.0).abs() < 1e-6);
    // A perspective camera: yfov → fov; unnamed node and camera → `camera<k>`; an identity node looks down -z.
    let mut p = doc.clone();
    p["cameras"].as_array_mut().unwrap().push(json!({"type": "perspective",
        "perspective": {"yfov": 0.7, "znear": 0.01, "aspectRatio": 1.5}}));
    p["nodes"].as_array_mut().unwrap().push(json!({"camera": 1, "translation": [0.0, 0.5, 3.0]}));
    p["scenes"][0]["nodes"] = json!([0, 1, 2, 3, 4]);
    let s = Scene::load(&write(&dir, "persp.gltf", embedded(p, &bin))).unwrap();
    let c = s.camera(Some("camera1")).unwrap();
    assert_eq!(c.projection, Projection::Perspective { fov: 0.7 });
    assert!(close(c.position, Vec3::new(0.0, 0.5, 3.0)) && close(c.up, Vec3::Y));
    assert!(close((c.target - c.position).normalize(), Vec3::NEG_Z));
    assert_eq!(s.camera(None).unwrap().name, "top");
}

/// The caustics AOV's flux in W of `scene`'s `top` camera at 64², level 1 (adaptive flux-error), under
/// `transport` (`None`: the default): what `render --camera top --aov caustics --size 64x64 --level 1
/// [--transport T]` reports as `aov_flux_w`, rendered in process on the shared device; validation stayed silent.
fn top_flux(device: &Arc<caustics::gpu::Device>, scene: &Path, transport: Option<Transport>) -> f64 {
    let settings = with(adaptive(1, Metric::FluxError), |s| {
        if let Some(t) = transport {
            s.quality.transport = t;
        }
    });
    let shot = shot_at(device, scene.to_str().unwrap(), settings, 0.0, caustics::Aov::Caustics, 64);
    shot.aov_flux
}

#[test]
fn gltf_renders_the_same_flux_as_toml() {
    let (_gpu, device) = gpu();
    let dir = out_dir("gltf_render");
    let (doc, bin) = gltf_scene();
    let g = write(&dir, "twin.gltf", embedded(doc, &bin));
    let t = write(&dir, "twin.toml", TOML);
    let args = ["--camera", "top", "--aov", "caustics", "--size", "64x64", "--level", "1"];
    let ft = top_flux(&device, &t, None);
    // Through the CLI by hand, to see its warnings.
    let (out, stats) = (dir.join("gltf.exr"), dir.join("gltf.json"));
    let mut a = vec!["render", "--scene", g.to_str().unwrap(), "--out", out.to_str().unwrap()];
    a.extend_from_slice(&["--stats", stats.to_str().unwrap()]);
    a.extend_from_slice(&args);
    let stderr = ok(&a);
    assert!(!stderr.contains("KHR_materials_dispersion"), "dispersion is supported now: {stderr}");
    assert!(stderr.contains("EXT_made_up"), "{stderr}");
    assert!(stderr.contains("`KHR_materials_clearcoat`: no clear coat is rendered"), "{stderr}");
    let gs = read_json(&stats);
    assert_validation_clean(&gs);
    let fg = gs["aov_flux_w"].as_f64().unwrap();
    assert!(ft > 0.01, "the TOML twin has a caustic: {ft}");
    assert!(((fg - ft) / ft).abs() < 1e-4, "glTF {fg} W vs TOML {ft} W");
    // The default transport (exact: every path) agrees too.
    let (fg, ft) = (top_flux(&device, &g, Some(Transport::Exact)), top_flux(&device, &t, Some(Transport::Exact)));
    assert!(ft > 0.01 && ((fg - ft) / ft).abs() < 1e-4, "exact: glTF {fg} W vs TOML {ft} W");
    // A directional light (683 lux = 1 W/m²) on a node at the origin, inside the scene: the glTF light is at
    // infinity, so its beam must still light the whole scene, like the TOML light 2 m up.
    let (mut doc, bin) = gltf_scene();
    doc["extensions"]["KHR_lights_punctual"]["lights"][0] = json!({"type": "directional", "intensity": 683.0});
    doc["nodes"][3]["translation"] = json!([0.0, 0.0, 0.0]);
    let g = write(&dir, "dir.gltf", embedded(doc, &bin));
    let t = write(&dir, "dir.toml", TOML.replace("\"spot\"", "\"directional\"").replace("cone_deg = 40.0\n", ""));
    let (fg, ft) = (top_flux(&device, &g, None), top_flux(&device, &t, None));
    assert!(ft > 0.01 && ((fg - ft) / ft).abs() < 1e-4, "directional: glTF {fg} W vs TOML {ft} W");
}

/// [`gltf_scene`] with its floor textured: the block texture (tests/common) embedded as a PNG data URI in
/// `baseColorTexture`, read through TEXCOORD_0 (the plane's uvs) with KHR_texture_transform scaling u by 2.
fn textured_gltf(dir: &Path) -> String {
    let (mut doc, mut bin) = gltf_scene();
    let png = dir.join("blocks.png");
    write_block_texture(&png);
    let uvs = mesh::plane(2.0, 2.0).uvs;
    let view = doc["bufferViews"].as_array().unwrap().len();
    doc["bufferViews"]
        .as_array_mut()
        .unwrap()
        .push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": uvs.len() * 8}));
    bin.extend_from_slice(bytemuck::cast_slice(&uvs));
    doc["buffers"][0]["byteLength"] = json!(bin.len());
    let acc = doc["accessors"].as_array().unwrap().len();
    doc["accessors"]
        .as_array_mut()
        .unwrap()
        .push(json!({"bufferView": view, "componentType": 5126, "count": uvs.len(), "type": "VEC2"}));
    doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(acc);
    let data = std::fs::read(&png).unwrap();
    doc["images"] = json!([{"uri": format!("data:image/png;base64,{}", b64(&data))}]);
    doc["samplers"] = json!([{}]);
    doc["textures"] = json!([{"source": 0, "sampler": 0}]);
    doc["materials"][0]["pbrMetallicRoughness"] = json!({"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0,
        "baseColorTexture": {"index": 0, "texCoord": 0, "extensions": {"KHR_texture_transform": {"scale": [2.0, 1.0]}}}});
    doc["extensionsUsed"].as_array_mut().unwrap().push(json!("KHR_texture_transform"));
    embedded(doc, &bin)
}

/// A glTF floor with a `baseColorTexture` (an embedded PNG, TEXCOORD_0, KHR_texture_transform) renders the same
/// linear beauty as its TOML twin (`albedo_texture` with `uv_scale`): rel-L1 at most 1e-4 over the image
/// (measured: 3.6e-7, the worst pixel 9.5e-5 relative: caustic photons land in another order); both see the texture
/// (the beauty varies across the floor as the blocks do).
#[test]
fn gltf_base_color_texture_renders_like_toml() {
    let (_gpu, device) = gpu();
    let dir = out_dir("gltf_texture");
    let g = write(&dir, "textured.gltf", textured_gltf(&dir));
    let toml = TOML.replace(
        r#"material = { kind = "diffuse", albedo = 0.8 }"#,
        r#"material = { kind = "diffuse", albedo_texture = "blocks.png", uv_scale = [2.0, 1.0] }"#,
    );
    let t = write(&dir, "textured.toml", toml);
    // The sky's radiance given: the automatic one follows the light's distance to its target, which a glTF light
    // (a direction, no target) does not share with its TOML twin. The linear beauty of the `top` camera at 96²,
    // level 1 (adaptive flux-error), two-interface transport, one sample a pixel, in process.
    let settings = with(adaptive(1, Metric::FluxError), |s| {
        s.quality.transport = Transport::TwoInterface;
        s.quality.aa = 1;
        s.quality.sky = Some(0.02);
    });
    let beauty = |scene: &Path| {
        let mut r = renderer(&device, scene.to_str().unwrap(), settings.clone());
        let (img, _) = top_aov(&mut r, 96, caustics::Aov::BeautyHdr);
        img
    };
    let (bg, bt) = (beauty(&g), beauty(&t));
    let (mut worst, mut diff, mut total) = (0.0f64, 0.0f64, 0.0f64);
    for (a, b) in bg.data.iter().zip(&bt.data) {
        for c in 0..3 {
            let d = (a[c] as f64 - b[c] as f64).abs();
            worst = worst.max(d / (b[c] as f64).abs().max(1e-6));
            diff += d;
            total += (b[c] as f64).abs();
        }
    }
    let rel_l1 = diff / total;
    eprintln!("glTF against TOML: rel-L1 {rel_l1:.2e}, worst pixel {worst:.2e}");
    assert!(rel_l1 <= 1e-4, "glTF and TOML beauty differ: rel-L1 {rel_l1}");
    let reds: std::collections::BTreeSet<u32> = bt.data.iter().map(|p| (p[0] * 1e4) as u32).collect();
    assert!(reds.len() > 8, "the texture shows ({} distinct red values)", reds.len());
    let s = Scene::load(&g).expect("load");
    assert_eq!(s.textures.len(), 1);
    assert!(matches!(s.objects[0].material, Material::Diffuse { map: Some(_), .. }));
}

/// Out-of-range and wrong-typed values anywhere in the buffers, views, accessors, nodes and meshes: each load is
/// an error or a scene, never a panic.
#[test]
fn mutated_gltf_never_panics() {
    let dir = out_dir("gltf_mutated");
    let (doc, bin) = gltf_scene();
    let wild = [json!(-1), json!(0), json!(3), json!(4294967295u64), json!(1e300), json!("x"), json!(null), json!([])];
    let mut targets: Vec<(String, Vec<String>)> = Vec::new();
    for (list, keys) in [
        ("accessors", &["bufferView", "byteOffset", "componentType", "count", "type", "min"][..]),
        ("bufferViews", &["buffer", "byteOffset", "byteLength", "byteStride"][..]),
        ("nodes", &["mesh", "camera", "children", "translation", "rotation", "scale", "matrix"][..]),
        ("buffers", &["byteLength"][..]),
    ] {
        for i in 0..doc[list].as_array().unwrap().len() {
            targets.push((format!("{list}/{i}"), keys.iter().map(|k| k.to_string()).collect()));
        }
    }
    let mut loads = 0;
    for (at, keys) in &targets {
        for k in keys {
            for w in &wild {
                let mut d = doc.clone();
                let mut v = &mut d;
                for part in at.split('/') {
                    v = match part.parse::<usize>() {
                        Ok(i) => &mut v[i],
                        Err(_) => &mut v[part],
                    };
                }
                v[k.as_str()] = w.clone();
                let p = write(&dir, "m.gltf", embedded(d, &bin));
                let r = std::panic::catch_unwind(|| Scene::load(&p).map(|s| s.triangle_count()));
                assert!(r.is_ok(), "{at}.{k} = {w}: panicked");
                loads += 1;
            }
        }
    }
    // Truncations of the GLB at every 16th byte.
    let g = glb(&doc, &bin);
    for n in (0..g.len()).step_by(16) {
        let p = write(&dir, "m.glb", &g[..n]);
        let r = std::panic::catch_unwind(|| Scene::load(&p).map(|s| s.triangle_count()));
        assert!(r.is_ok(), "GLB cut at {n}: panicked");
        loads += 1;
    }
    assert!(loads > 300, "{loads}");
}

/// Load `text` through the CLI and expect exit code 2, every needle in stderr, and no panic.
/// A second KHR_lights_punctual light on a node becomes the scene's second light (in node order).
#[test]
fn gltf_two_lights_load() {
    let dir = out_dir("gltf_two_lights");
    let (mut d, bin) = gltf_scene();
    let lights = d["extensions"]["KHR_lights_punctual"]["lights"].as_array_mut().unwrap();
    lights.push(json!({"type": "directional", "intensity": 683.0, "color": [1.0, 0.5, 0.25]}));
    let nodes = d["nodes"].as_array_mut().unwrap();
    let n = nodes.len();
    nodes.push(json!({"extensions": {"KHR_lights_punctual": {"light": 1}}}));
    d["nodes"][3]["children"] = json!([n]);
    let s = Scene::load(&write(&dir, "two.gltf", embedded(d, &bin))).unwrap();
    assert_eq!(s.lights.len(), 2);
    assert_eq!(s.lights[1].kind, LightKind::Directional);
    assert!((s.lights[1].intensity - 1.0).abs() < 1e-6, "683 lux → 1 W/m²: {}", s.lights[1].intensity);
    assert_eq!(s.lights[1].color, Vec3::new(1.0, 0.5, 0.25));
}

/// A KHR_lights_punctual point light: isotropic, candela / 683 → W/sr, its maps aimed at the glass's center.
#[test]
fn gltf_point_light_loads() {
    let dir = out_dir("gltf_point");
    let (mut d, bin) = gltf_scene();
    d["extensions"]["KHR_lights_punctual"]["lights"][0] = json!({"type": "point", "intensity": 683.0});
    let s = Scene::load(&write(&dir, "point.gltf", embedded(d, &bin))).unwrap();
    let l = &s.lights[0];
    assert_eq!(l.kind, LightKind::Point);
    assert!((l.intensity - 1.0).abs() < 1e-6);
    assert!(close(l.position, Vec3::new(0.0, 2.0, 0.0)) && close(l.target, Vec3::new(0.0, 0.5, 0.0)), "{l:?}");
}

fn expect_bad(dir: &Path, name: &str, data: impl AsRef<[u8]>, needles: &[&str]) {
    let scene = write(dir, name, data);
    let out = dir.join(format!("{name}.exr"));
    let o =
        caustics(&["render", "--scene", scene.to_str().unwrap(), "--aov", "caustics", "--out", out.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{name}: exit code; stderr:\n{stderr}");
    for n in needles {
        assert!(stderr.contains(n), "{name}: stderr lacks `{n}`:\n{stderr}");
    }
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_no_output(&out);
}

#[test]
fn bad_gltf_exits_2() {
    let dir = out_dir("gltf_bad");
    let (doc, bin) = gltf_scene();
    let good = embedded(doc.clone(), &bin);

    let mut d = doc.clone();
    d["extensionsRequired"] = json!(["KHR_lights_punctual", "EXT_teleport"]);
    expect_bad(&dir, "required.gltf", embedded(d, &bin), &["extensionsRequired[1]", "EXT_teleport"]);
    // KTX2 textures with no fallback: what to do instead.
    let mut d = doc.clone();
    d["extensionsRequired"] = json!(["KHR_texture_basisu"]);
    expect_bad(&dir, "basisu.gltf", embedded(d, &bin), &["extensionsRequired[0]", "KTX2", "PNG, JPEG or WebP"]);

    // A point light at the center of the glass it would aim its maps at.
    let mut d = doc.clone();
    d["extensions"]["KHR_lights_punctual"]["lights"][0] = json!({"type": "point", "intensity": 683.0});
    d["nodes"][3]["translation"] = json!([0.0, 0.5, 0.0]);
    expect_bad(&dir, "point.gltf", embedded(d, &bin), &["point light 0", "center of the glass"]);

    let mut d = doc.clone();
    d["meshes"][1]["primitives"][0]["mode"] = json!(1);
    expect_bad(&dir, "lines.gltf", embedded(d, &bin), &["meshes[1].primitives[0].mode", "\"glass\"", "triangles"]);

    // Corrupt: truncated JSON, a truncated GLB, an index out of range, a buffer too short for its accessors.
    expect_bad(&dir, "truncated.gltf", &good[..good.len() / 2], &["truncated.gltf:"]);
    expect_bad(&dir, "truncated.glb", &glb(&doc, &bin)[..200], &["truncated.glb", "GLB"]);
    let mut d = doc.clone();
    d["nodes"][1]["mesh"] = json!(7);
    expect_bad(&dir, "index.gltf", embedded(d, &bin), &["nodes[1].mesh", "index out of bounds"]);
    let mut d = doc.clone();
    d["buffers"][0]["byteLength"] = json!(64);
    expect_bad(&dir, "short.gltf", embedded(d, &bin[..64]), &["outside"]);
    expect_bad(&dir, "garbage.glb", b"glTF\x02\0\0\0\xff\xff\xff\xff not really", &["garbage.glb"]);

    // Five lights on nodes: the renderer handles up to four.
    let mut d = doc.clone();
    let lights = d["extensions"]["KHR_lights_punctual"]["lights"].as_array_mut().unwrap();
    lights.push(json!({"type": "directional", "intensity": 683.0}));
    let nodes = d["nodes"].as_array_mut().unwrap();
    let first = nodes.len();
    for _ in 0..4 {
        nodes.push(json!({"extensions": {"KHR_lights_punctual": {"light": 1}}}));
    }
    d["nodes"][3]["children"] = json!((first..first + 4).collect::<Vec<_>>());
    expect_bad(&dir, "five_lights.gltf", embedded(d, &bin), &["5 lights", "at most 4"]);
}

const GALLERY: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/gallery.gltf");

/// assets/scenes/gallery.gltf is what tools/gltf_scenes writes (so the script and the file cannot drift).
#[test]
fn gallery_gltf_is_the_tools_output() {
    let dir = out_dir("gltf_gallery_tool");
    let out = dir.join("gallery.gltf");
    let tool = concat!(env!("CARGO_MANIFEST_DIR"), "/tools/gltf_scenes");
    let o = std::process::Command::new("python3").arg(tool).arg(&out).output().expect("python3");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(std::fs::read(&out).unwrap() == std::fs::read(GALLERY).unwrap(), "regenerate: tools/gltf_scenes");
}

/// The glTF gallery (two colored spot lights, dispersive amber glass, a mirror) on the GPU against the CPU
/// reference of every path (48M photons), exact transport, level 4, 64² luminance; both trace spectral photons.
/// Measured on lavapipe: rel-L1 2.45% (two 48M references differ by 2.2%, two 6M ones by 6.2%: a wavelength's RGB
/// has negative lobes; at level 3 the GPU's one wavelength a photon gives 4.1%), flux ratio 0.998;
/// the test allows rel-L1 0.045 and flux within 1%.
#[test]
fn gallery_gltf_matches_reference() {
    use caustics::metrics::compare;
    use caustics::reference::{Aov, Paths};
    let (_gpu, device) = gpu();
    // The `top` camera's caustics AOV at 256², exact transport, level 4 (adaptive flux-error), in process.
    let s = shot(&device, GALLERY, with(adaptive(4, Metric::FluxError), |s| s.quality.transport = Transport::Exact));
    assert_eq!(s.passes(), ["spectral", "spectral"], "two lights, one pass of spectral photons each");
    let r = top_reference(GALLERY, Aov::Caustics, Paths::All, 48_000_000, 256);
    let m = compare(&s.img, &r, 64, 2.0);
    eprintln!("gallery.gltf vs reference: {m:?}");
    assert!((m.flux_ratio - 1.0).abs() < 0.01, "flux ratio {}", m.flux_ratio);
    assert!(m.rel_l1 < 0.045, "rel-L1 {}", m.rel_l1);
}

/// `doc` and `bin` with one more accessor holding `data` (floats, `kind` SCALAR / VEC3 / VEC4); its index.
/// The glTF twin with its glass node animated: a linear translation, a step rotation and a cubic-spline scale.
fn animated_gltf() -> (Value, Vec<u8>) {
    let (mut doc, mut bin) = gltf_scene();
    let times = add_accessor(&mut doc, &mut bin, &[0.0, 1.0], "SCALAR");
    let moves = add_accessor(&mut doc, &mut bin, &[0.0, 0.5, 0.0, 0.3, 0.6, 0.0], "VEC3");
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let turns = add_accessor(&mut doc, &mut bin, &[0.0, 0.0, 0.0, 1.0, 0.0, h, 0.0, h], "VEC4");
    // (in tangent, value, out tangent) per keyframe: zero tangents, from scale 1 to 2.
    let scales = add_accessor(
        &mut doc,
        &mut bin,
        &[0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.0, 2.0, 2.0, 0.0, 0.0, 0.0],
        "VEC3",
    );
    doc["animations"] = json!([{
        "channels": [
            {"sampler": 0, "target": {"node": 1, "path": "translation"}},
            {"sampler": 1, "target": {"node": 1, "path": "rotation"}},
            {"sampler": 2, "target": {"node": 1, "path": "scale"}}
        ],
        "samplers": [
            {"input": times, "output": moves, "interpolation": "LINEAR"},
            {"input": times, "output": turns, "interpolation": "STEP"},
            {"input": times, "output": scales, "interpolation": "CUBICSPLINE"}
        ]
    }]);
    (doc, bin)
}

/// Node animation channels place the glass as the glTF interpolations say: linear translation, step rotation,
/// and a cubic Hermite scale (with zero tangents, 1 + smoothstep at half time: 1.5), holding the last pose past
/// the end (as Blender holds an action's last frame); the renderer and the reference evaluate the same placement
/// (Scene::set_time).
#[test]
fn gltf_animation_places_the_glass() {
    let dir = out_dir("gltf_animation");
    let (doc, bin) = animated_gltf();
    let path = write(&dir, "animated.gltf", embedded(doc, &bin));
    let scene = Scene::load(&path).unwrap();
    assert!(scene.is_animated() && scene.duration() == 1.0);
    let glass = |s: &Scene| s.objects.iter().find(|o| o.name == "glass").unwrap().mesh.bounds();
    let (lo, hi) = glass(&scene);
    assert!(close((lo + hi) * 0.5, Vec3::new(0.0, 0.5, 0.0)) && close(hi - lo, Vec3::splat(0.4)), "{lo} {hi}");
    let half = scene.at_time(0.5);
    let (lo, hi) = glass(&half);
    // At 0.5 s: translated halfway and scaled 1.5.
    assert!(close((lo + hi) * 0.5, Vec3::new(0.15, 0.55, 0.0)), "{lo} {hi}");
    assert!(close(hi - lo, Vec3::splat(0.6)), "{lo} {hi}");
    // Past the end, the last keyframe's pose: translated by (0.3, 0.1, 0), scaled 2.
    let (lo, hi) = glass(&scene.at_time(1.5));
    assert!(close((lo + hi) * 0.5, Vec3::new(0.3, 0.6, 0.0)) && close(hi - lo, Vec3::splat(0.8)), "{lo} {hi}");
    let o = half.objects.iter().find(|o| o.name == "glass").unwrap();
    let a = o.animation.as_ref().unwrap().animation.as_ref().unwrap();
    // The step rotation holds its first keyframe (no turn) until the second.
    assert!(a.transform_at(0.99).transform_vector3(Vec3::Z).x.abs() < 1e-5, "no turn before the second keyframe");
    assert!((a.transform_at(1.0).transform_vector3(Vec3::Z).x.abs() - 2.0).abs() < 1e-5, "a quarter turn at 1 s");
}

#[test]
fn bad_gltf_animations_exit_2() {
    let dir = out_dir("gltf_animation_bad");
    let (doc, bin) = animated_gltf();
    let mut d = doc.clone();
    d["animations"][0]["channels"][0]["target"]["node"] = json!(9);
    expect_bad(
        &dir,
        "missing_node.gltf",
        embedded(d, &bin),
        &["animations[0].channels[0].target.node", "index out of bounds"],
    );
    // Times that do not increase.
    let (mut d, mut b) = gltf_scene();
    let times = add_accessor(&mut d, &mut b, &[1.0, 0.5], "SCALAR");
    let moves = add_accessor(&mut d, &mut b, &[0.0, 0.5, 0.0, 0.3, 0.6, 0.0], "VEC3");
    d["animations"] = json!([{"channels": [{"sampler": 0, "target": {"node": 1, "path": "translation"}}],
                              "samplers": [{"input": times, "output": moves}]}]);
    expect_bad(&dir, "times.gltf", embedded(d, &b), &["animations[0].samplers[0].input", "must increase"]);
    // A NaN value.
    let (mut d, mut b) = gltf_scene();
    let times = add_accessor(&mut d, &mut b, &[0.0, 1.0], "SCALAR");
    let moves = add_accessor(&mut d, &mut b, &[0.0, f32::NAN, 0.0, 0.3, 0.6, 0.0], "VEC3");
    d["animations"] = json!([{"channels": [{"sampler": 0, "target": {"node": 1, "path": "translation"}}],
                              "samplers": [{"input": times, "output": moves}]}]);
    expect_bad(&dir, "nan.gltf", embedded(d, &b), &["animations[0].samplers[0].output", "finite"]);
}

/// The Khronos glTF validator (tools/setup installs it) finds no error in any glTF file the project writes or
/// keeps: the gallery (tools/gltf_scenes), both Blenders' fixtures (tools/blender_scenes) and their gltfpack and
/// glTF-Transform copies (tools/gltfpack_scenes, tools/gltf_transform_scenes), and the files these tests and the
/// animation tests write.
#[test]
fn the_khronos_validator_finds_no_error() {
    let dir = out_dir("gltf_validator");
    let mut files = vec![std::path::PathBuf::from(scene("gallery.gltf"))];
    // Blender's fixtures, and gltfpack's and glTF-Transform's files made from them.
    let mut glbs: Vec<_> = ["blender", "blender5", "gltfpack", "gltf-transform"]
        .iter()
        .flat_map(|d| std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(d)).unwrap())
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "glb"))
        .collect();
    glbs.sort();
    assert!(glbs.len() >= 50, "the fixtures: {glbs:?}");
    files.extend(glbs);
    let (doc, bin) = gltf_scene();
    files.push(write(&dir, "twin.gltf", embedded(doc.clone(), &bin)));
    files.push(write(&dir, "twin.glb", glb(&doc, &bin)));
    files.push(write(&dir, "textured.gltf", textured_gltf(&dir)));
    let (doc, bin) = animated_gltf();
    files.push(write(&dir, "animated.gltf", embedded(doc, &bin)));
    let (rig, poses) = common::rig::write_rigs(&dir);
    files.push(rig);
    files.extend(poses);
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/validate_gltf.cjs");
    let out = std::process::Command::new("node")
        .arg(&script)
        .args(&files)
        .output()
        .expect("run node (tools/setup installs Node.js and the glTF validator)");
    let text = String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    eprintln!("{text}");
    assert!(out.status.success(), "the glTF validator found errors:\n{text}");
    assert_eq!(text.matches(": 0 errors").count(), files.len(), "every file validated:\n{text}");
}

/// The twin with what exporters write beyond the basics: a glass cube stored interleaved (positions and normals
/// in one byteStride-24 view) with u8 indices; the same cube raised by a sparse accessor; raised again by a
/// morph target whose displacements are a sparse accessor with no bufferView, at a still weight of 1; the cube
/// placed by a `matrix`; mirrored by a negative scale; skinned (its node's own transform is ignored); a light with
/// a `range`; a second scene that the file's `scene` picks.
fn exporters_gltf() -> (Value, Vec<u8>) {
    let (mut doc, mut bin) = gltf_scene();
    let cube = mesh::cube(Vec3::splat(0.2));
    let interleaved: Vec<f32> = cube
        .positions
        .iter()
        .zip(&cube.normals)
        .flat_map(|(p, n)| p.to_array().into_iter().chain(n.to_array()))
        .collect();
    let view = add_view(&mut doc, &mut bin, bytemuck::cast_slice(&interleaved), Some(24));
    let (lo, hi) = cube.bounds();
    let n = cube.positions.len();
    let pos = push_accessor(
        &mut doc,
        json!({"bufferView": view, "componentType": 5126, "count": n, "type": "VEC3",
        "min": lo.to_array(), "max": hi.to_array()}),
    );
    let nrm = push_accessor(
        &mut doc,
        json!({"bufferView": view, "byteOffset": 12, "componentType": 5126, "count": n, "type": "VEC3"}),
    );
    let idx8: Vec<u8> = cube.indices.iter().map(|&i| i as u8).collect();
    let iv = add_view(&mut doc, &mut bin, &idx8, None);
    let idx = push_accessor(
        &mut doc,
        json!({"bufferView": iv, "componentType": 5121, "count": idx8.len(), "type": "SCALAR"}),
    );
    // The top face's vertices, raised 0.1 m (sparse: u16 indices, then the values).
    let top: Vec<u16> = (0..n as u16).filter(|&k| cube.positions[k as usize].y > 0.0).collect();
    let si = add_view(&mut doc, &mut bin, bytemuck::cast_slice(&top), None);
    let raised: Vec<f32> = top.iter().flat_map(|&k| (cube.positions[k as usize] + Vec3::Y * 0.1).to_array()).collect();
    let sv = add_view(&mut doc, &mut bin, bytemuck::cast_slice(&raised), None);
    let sparse = |values: usize| {
        json!({"count": top.len(), "indices": {"bufferView": si, "componentType": 5123},
        "values": {"bufferView": values}})
    };
    let up = push_accessor(
        &mut doc,
        json!({"bufferView": view, "componentType": 5126, "count": n, "type": "VEC3",
        "min": lo.to_array(), "max": (hi + Vec3::Y * 0.1).to_array(), "sparse": sparse(sv)}),
    );
    let lift: Vec<f32> = top.iter().flat_map(|_| [0.0, 0.1, 0.0]).collect();
    let lv = add_view(&mut doc, &mut bin, bytemuck::cast_slice(&lift), None);
    let delta = push_accessor(
        &mut doc,
        json!({"componentType": 5126, "count": n, "type": "VEC3",
        "min": [0.0, 0.0, 0.0], "max": [0.0, 0.1, 0.0], "sparse": sparse(lv)}),
    );
    let prim = |p: usize| json!({"attributes": {"POSITION": p, "NORMAL": nrm}, "indices": idx, "material": 1});
    let mut morphing = prim(pos);
    morphing["targets"] = json!([{"POSITION": delta}]);
    let meshes = doc["meshes"].as_array_mut().unwrap();
    meshes.push(json!({"name": "interleaved", "primitives": [prim(pos)]}));
    meshes.push(json!({"name": "sparse", "primitives": [prim(up)]}));
    meshes.push(json!({"name": "morphed", "primitives": [morphing], "weights": [1.0]}));
    // Column-major: scale 0.5, a turn of 90° about y, then (0.4, 0.5, 0.4).
    let m = glam::Mat4::from_scale_rotation_translation(
        Vec3::splat(0.5),
        glam::Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
        Vec3::new(0.4, 0.5, 0.4),
    );
    let ibm = add_view(
        &mut doc,
        &mut bin,
        bytemuck::cast_slice(&glam::Mat4::from_translation(-Vec3::Y * 0.5).to_cols_array()),
        None,
    );
    let ibm = push_accessor(&mut doc, json!({"bufferView": ibm, "componentType": 5126, "count": 1, "type": "MAT4"}));
    doc["skins"] = json!([{"joints": [10], "inverseBindMatrices": ibm}]);
    let nodes = doc["nodes"].as_array_mut().unwrap();
    nodes.extend([
        json!({"name": "interleaved", "mesh": 2, "translation": [-0.4, 0.5, -0.4]}),
        json!({"name": "sparse", "mesh": 3, "translation": [0.4, 0.5, -0.4]}),
        json!({"name": "morphed", "mesh": 4, "translation": [-0.4, 0.5, 0.4]}),
        json!({"name": "matrix", "mesh": 2, "matrix": m.to_cols_array()}),
        json!({"name": "mirrored", "mesh": 2, "translation": [0.0, 0.8, 0.0], "scale": [-1.0, 1.0, 1.0]}),
        json!({"name": "skinned", "mesh": 2, "skin": 0, "translation": [5.0, 5.0, 5.0]}),
        json!({"name": "joint", "translation": [0.0, 0.5, 0.0]}),
    ]);
    doc["scenes"] = json!([{"nodes": [0, 2, 3]}, {"nodes": [0, 2, 3, 4, 5, 6, 7, 8, 9, 10]}]);
    doc["scene"] = json!(1);
    doc["extensions"]["KHR_lights_punctual"]["lights"][0]["range"] = json!(10.0);
    (doc, bin)
}

/// What exporters write, as the glTF 2.0 spec means it: interleaved vertex data and u8 indices, sparse accessors
/// (with and without a bufferView), still morph weights, `matrix` nodes, mirrored nodes, skins (a warning naming
/// the node; the mesh at its bind pose), a light's `range` (a warning), several scenes (the file's `scene`), and
/// a `.glb` whose texture is an image in a bufferView. The file renders, and the warnings reach the user.
#[test]
fn what_exporters_write_loads_as_the_spec_says() {
    let (_gpu, device) = gpu();
    let dir = out_dir("gltf_exporters");
    let (doc, bin) = exporters_gltf();
    let path = write(&dir, "exporters.glb", glb(&doc, &bin));
    let s = Scene::load(&path).unwrap();
    let bounds =
        |name: &str| s.objects.iter().find(|o| o.name == name).unwrap_or_else(|| panic!("{name}")).mesh.bounds();
    let cube = |at: Vec3, top: f32| (at - Vec3::splat(0.1), at + Vec3::new(0.1, 0.1 + top, 0.1));
    let same = |a: (Vec3, Vec3), b: (Vec3, Vec3)| close(a.0, b.0) && close(a.1, b.1);
    assert!(same(bounds("interleaved"), cube(Vec3::new(-0.4, 0.5, -0.4), 0.0)), "{:?}", bounds("interleaved"));
    assert!(same(bounds("sparse"), cube(Vec3::new(0.4, 0.5, -0.4), 0.1)), "{:?}", bounds("sparse"));
    assert!(same(bounds("morphed"), cube(Vec3::new(-0.4, 0.5, 0.4), 0.1)), "{:?}", bounds("morphed"));
    let (lo, hi) = bounds("matrix");
    assert!(close(lo, Vec3::new(0.35, 0.45, 0.35)) && close(hi, Vec3::new(0.45, 0.55, 0.45)), "{lo} {hi}");
    // Mirrored: the cube (symmetric) where it was, its triangles still wound outward (positive volume).
    let mirrored = &s.objects.iter().find(|o| o.name == "mirrored").unwrap().mesh;
    let volume: f32 = mirrored
        .indices
        .chunks(3)
        .map(|t| {
            let p = |k: usize| mirrored.positions[t[k] as usize];
            p(0).dot(p(1).cross(p(2))) / 6.0
        })
        .sum();
    assert!((volume - 0.008).abs() < 1e-5, "mirrored cube's volume {volume}");
    // Skinned: at its bind pose, the joint (0, 0.5, 0) times its inverse bind matrix: the mesh where it was
    // modelled, the node's own (5, 5, 5) ignored.
    assert!(same(bounds("skinned"), cube(Vec3::ZERO, 0.0)), "{:?}", bounds("skinned"));
    assert_eq!(s.objects.len(), 7, "scene 1: the floor and six cubes (scene 0 has no glass)");
    // A GLB whose base color texture is a PNG in a bufferView.
    let (mut doc, mut bin) = gltf_scene();
    let png = dir.join("blocks.png");
    write_block_texture(&png);
    let image = add_view(&mut doc, &mut bin, &std::fs::read(&png).unwrap(), None);
    let uvs = add_view(&mut doc, &mut bin, bytemuck::cast_slice(&mesh::plane(2.0, 2.0).uvs), None);
    let uv = push_accessor(&mut doc, json!({"bufferView": uvs, "componentType": 5126, "count": 4, "type": "VEC2"}));
    doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(uv);
    doc["images"] = json!([{"bufferView": image, "mimeType": "image/png"}]);
    doc["textures"] = json!([{"source": 0}]);
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    let t = Scene::load(&write(&dir, "textured.glb", glb(&doc, &bin))).unwrap();
    assert_eq!(t.textures.len(), 1);
    assert_eq!((t.textures[0].width, t.textures[0].height), (64, 64));
    // The file renders (in process: its beauty through the default camera at 64², level 2, adaptive flux-error,
    // exact transport), ...
    let mut r = renderer(&device, path.to_str().unwrap(), adaptive(2, Metric::FluxError));
    let camera = r.scene().camera(None).unwrap_or_else(|e| panic!("{e}")).clone();
    let view = r.camera_view(&camera, 64, 64);
    let frame = r.render(&caustics::FrameDesc::new(&view, Some(caustics::Aov::Beauty))).expect("frame");
    assert_eq!(caustics::gpu::validation_message_count(), 0, "validation messages");
    assert!(frame.report.photons() > 10_000, "{}", frame.report.photons());
    // One bottom-level BVH per distinct mesh, however many nodes instance it: the floor, the cube (four nodes),
    // and the raised cube (the sparse one and the morphed one hold the same triangles).
    let bvh = &r.scene_buffers().bvh;
    assert_eq!(bvh.triangle_count, 2 + 12 + 12, "{} instances", bvh.instance_count);
    // ... and through the CLI, with each warning on one line.
    let o = caustics(&[
        "render",
        "--scene",
        path.to_str().unwrap(),
        "--level",
        "1",
        "--size",
        "32x32",
        "--out",
        dir.join("w.png").to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    for needle in [
        "nodes[9] \"skinned\": skins are not supported: mesh \"skinned\" stands at its bind pose",
        "lights[0].range: range 10 m is ignored",
        "the file has 2 scenes: scenes[1] (the file's `scene`) is loaded",
        "extension `EXT_made_up` is not supported and is ignored",
    ] {
        assert_eq!(stderr.matches(needle).count(), 1, "`{needle}` once in:\n{stderr}");
    }
}

/// Files from gltfpack and glTF-Transform (tests/data): the quantized glass of water (KHR_mesh_quantization's
/// integer positions and normalized-byte normals), its compressed copy with filters (EXT_meshopt_compression), its
/// Draco copy (KHR_draco_mesh_compression), the textured floor as WebP (EXT_texture_webp) and the quantized
/// instanced balls (EXT_mesh_gpu_instancing), their accessors' encodings and layouts mutated, the compressed views',
/// WebP textures' and instanced nodes' fields too, and bytes of their buffers
/// overwritten: every load is a scene or an error that names the file, never a panic.
#[test]
fn mutated_pipeline_files_never_panic() {
    let dir = out_dir("gltf_pipeline_mutated");
    let mut loads = 0;
    let mut errors = 0;
    for name in [
        "gltfpack/glass_of_water",
        "gltfpack/glass_of_water_meshopt_filters",
        "gltf-transform/glass_of_water_draco",
        "gltf-transform/textured_webp",
        "gltfpack/instances",
    ] {
        let src = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/data/{name}.glb"));
        let bytes = std::fs::read(&src).unwrap();
        // The GLB's two chunks: JSON, then BIN.
        let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap()) as usize;
        let json_len = u32_at(12);
        let doc: Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
        let bin_at = 20 + json_len;
        let bin = bytes[bin_at + 8..bin_at + 8 + u32_at(bin_at)].to_vec();
        assert!(Scene::load(&src).is_ok(), "{name} loads");
        let mut check = |d: Value, bin: &[u8], what: &str| {
            let p = write(&dir, "q.glb", glb(&d, bin));
            match std::panic::catch_unwind(|| Scene::load(&p).map(|s| s.triangle_count())) {
                Err(_) => panic!("{name}: {what}: panicked"),
                Ok(Err(e)) => {
                    let m = e.to_string();
                    assert!(m.contains("q.glb"), "{name}: {what}: the message names no file: {m}");
                    errors += 1;
                }
                Ok(Ok(_)) => {}
            }
            loads += 1;
        };
        let wild =
            [json!(5120), json!(5121), json!(5122), json!(5123), json!(5125), json!(5126), json!(true), json!(-1)];
        for i in 0..doc["accessors"].as_array().unwrap().len() {
            for key in ["componentType", "normalized", "type", "byteOffset", "count"] {
                for w in &wild {
                    let mut d = doc.clone();
                    d["accessors"][i][key] = w.clone();
                    check(d, &bin, &format!("accessors[{i}].{key} = {w}"));
                }
            }
        }
        let ext_wild =
            [json!(0), json!(1), json!(3), json!(12), json!(100000), json!("TRIANGLES"), json!("X"), json!(-1)];
        for i in 0..doc["bufferViews"].as_array().unwrap().len() {
            for w in [json!(1), json!(2), json!(6), json!(255)] {
                let mut d = doc.clone();
                d["bufferViews"][i]["byteStride"] = w.clone();
                check(d, &bin, &format!("bufferViews[{i}].byteStride = {w}"));
            }
            if doc["bufferViews"][i]["extensions"]["EXT_meshopt_compression"].is_null() {
                continue;
            }
            for key in ["buffer", "byteOffset", "byteLength", "byteStride", "count", "mode", "filter"] {
                for w in &ext_wild {
                    let mut d = doc.clone();
                    d["bufferViews"][i]["extensions"]["EXT_meshopt_compression"][key] = w.clone();
                    check(d, &bin, &format!("bufferViews[{i}] EXT_meshopt_compression.{key} = {w}"));
                }
            }
        }
        for i in 0..doc["textures"].as_array().map_or(0, |t| t.len()) {
            for w in &ext_wild {
                let mut d = doc.clone();
                d["textures"][i]["extensions"]["EXT_texture_webp"]["source"] = w.clone();
                check(d, &bin, &format!("textures[{i}] EXT_texture_webp.source = {w}"));
            }
            let mut d = doc.clone();
            d["textures"][i]["extensions"] = json!({});
            check(d, &bin, &format!("textures[{i}] without EXT_texture_webp"));
        }
        for i in 0..doc["nodes"].as_array().unwrap().len() {
            if doc["nodes"][i]["extensions"]["EXT_mesh_gpu_instancing"].is_null() {
                continue;
            }
            for key in ["TRANSLATION", "ROTATION", "SCALE", "_ID"] {
                for w in &ext_wild {
                    let mut d = doc.clone();
                    d["nodes"][i]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"][key] = w.clone();
                    check(d, &bin, &format!("nodes[{i}] EXT_mesh_gpu_instancing {key} = {w}"));
                }
            }
            let mut d = doc.clone();
            d["nodes"][i]["extensions"]["EXT_mesh_gpu_instancing"] = json!({"attributes": 3});
            check(d, &bin, &format!("nodes[{i}] EXT_mesh_gpu_instancing without attributes"));
        }
        // The buffer's bytes overwritten, a stretch at a time: compressed streams, positions, normals and indices
        // out of their ranges; and single bytes flipped all along it.
        for at in (0..bin.len()).step_by(bin.len() / 64 + 1) {
            let mut b = bin.clone();
            b[at..(at + 64).min(bin.len())].iter_mut().for_each(|x| *x = 0xFF);
            check(doc.clone(), &b, &format!("bytes {at}.. overwritten"));
        }
        for at in (0..bin.len()).step_by(bin.len() / 256 + 1) {
            let mut b = bin.clone();
            b[at] ^= 0x5A;
            check(doc.clone(), &b, &format!("byte {at} flipped"));
        }
    }
    eprintln!("{loads} loads, {errors} errors");
    assert!(loads > 1500 && errors > 300, "{loads} loads, {errors} errors");
}

/// The twin with KHR_animation_pointer channels (no `node`): the spot's intensity from 683 to 2049 cd and its
/// color from white to red, its cone from 40° to 20° (as the spec writes the pointer, and as Blender 5.2 does,
/// `spot.outerConeAngle`), the orthographic camera's ymag from 1 to 2, a node's translation by pointer, the glass's
/// IOR from 1.5 to 1.3, and its attenuation distance, which is warned of.
fn pointer_gltf() -> (Value, Vec<u8>) {
    let (mut doc, mut bin) = gltf_scene();
    let times = add_accessor(&mut doc, &mut bin, &[0.0, 1.0], "SCALAR");
    let intensity = add_accessor(&mut doc, &mut bin, &[683.0, 2049.0], "SCALAR");
    let color = add_accessor(&mut doc, &mut bin, &[1.0, 1.0, 1.0, 1.0, 0.0, 0.0], "VEC3");
    let cone = add_accessor(&mut doc, &mut bin, &[40f32.to_radians(), 20f32.to_radians()], "SCALAR");
    let ymag = add_accessor(&mut doc, &mut bin, &[1.0, 2.0], "SCALAR");
    let moves = add_accessor(&mut doc, &mut bin, &[0.0, 0.5, 0.0, 0.3, 0.5, 0.0], "VEC3");
    let ior = add_accessor(&mut doc, &mut bin, &[1.5, 1.3], "SCALAR");
    let pointer = |s: usize, p: &str| json!({"sampler": s, "target": {"path": "pointer", "extensions": {"KHR_animation_pointer": {"pointer": p}}}});
    doc["extensionsUsed"].as_array_mut().unwrap().push(json!("KHR_animation_pointer"));
    doc["animations"] = json!([{
        "channels": [
            pointer(0, "/extensions/KHR_lights_punctual/lights/0/intensity"),
            pointer(1, "/extensions/KHR_lights_punctual/lights/0/color"),
            pointer(2, "/extensions/KHR_lights_punctual/lights/0/spot/outerConeAngle"),
            pointer(3, "/cameras/0/orthographic/ymag"),
            pointer(4, "/nodes/1/translation"),
            pointer(5, "/materials/1/extensions/KHR_materials_ior/ior"),
            pointer(5, "/materials/1/extensions/KHR_materials_volume/attenuationDistance"),
        ],
        "samplers": [
            {"input": times, "output": intensity}, {"input": times, "output": color},
            {"input": times, "output": cone}, {"input": times, "output": ymag},
            {"input": times, "output": moves}, {"input": times, "output": ior}
        ]
    }]);
    (doc, bin)
}

/// KHR_animation_pointer sets the light's intensity, color and cone, the camera's size and the glass's IOR over
/// time, as the renderer and the reference read them (Scene::set_time), and a node's translation by pointer moves
/// it; an animated attenuation is warned of; a pointer past the file's lights exits 2 naming the channel.
#[test]
fn animation_pointers_set_light_and_camera_properties() {
    let (_gpu, device) = gpu();
    let dir = out_dir("gltf_pointer");
    let (doc, bin) = pointer_gltf();
    let path = write(&dir, "pointer.gltf", embedded(doc.clone(), &bin));
    let scene = Scene::load(&path).unwrap();
    assert!(scene.is_animated() && scene.duration() == 1.0);
    let half = scene.at_time(0.5);
    let l = &half.lights[0];
    assert!((l.intensity - 2.0).abs() < 1e-5, "1366 cd at 0.5 s: {}", l.intensity);
    assert!((l.color - Vec3::new(1.0, 0.5, 0.5)).abs().max_element() < 1e-6, "{}", l.color);
    assert!((l.cone - 30f32.to_radians()).abs() < 1e-6, "{}", l.cone.to_degrees());
    assert!(
        matches!(half.cameras[0].projection, Projection::Orthographic { half_height } if (half_height - 1.5).abs() < 1e-6)
    );
    let glass = |s: &Scene| s.objects.iter().find(|o| o.name == "glass").unwrap().mesh.bounds();
    let ior = half.objects.iter().find(|o| o.name == "glass").unwrap().material;
    assert!(matches!(ior, Material::Dielectric { ior, .. } if (ior - 1.4).abs() < 1e-6), "{ior:?}");
    let (lo, hi) = glass(&half);
    assert!(close((lo + hi) * 0.5, Vec3::new(0.15, 0.5, 0.0)), "{lo} {hi}");
    // Rendered at 1 s: the red spot lights nothing in green, and its caustic has three times the red flux of the
    // same file whose intensity does not animate (its pointer aimed at the light's `range`, which is ignored).
    let settings = adaptive(2, Metric::FluxError);
    let shot = |p: &Path| shot_at(&device, p.to_str().unwrap(), settings.clone(), 1.0, caustics::Aov::Caustics, 64);
    let mut d = doc.clone();
    d["animations"][0]["channels"][0]["target"]["extensions"]["KHR_animation_pointer"]["pointer"] =
        json!("/extensions/KHR_lights_punctual/lights/0/range");
    let (end, still) = (shot(&path), shot(&write(&dir, "still.gltf", embedded(d, &bin))));
    assert!(end.img.data.iter().all(|p| p[1] == 0.0), "a red light puts no green anywhere");
    let ratio = end.aov_flux / still.aov_flux;
    assert!(
        still.aov_flux > 1e-3 && (ratio - 3.0).abs() < 1e-3,
        "{} W, not animated {} W",
        end.aov_flux,
        still.aov_flux
    );
    // Through the CLI: the IOR's animation is warned of, once.
    let o = caustics(&[
        "render",
        "--scene",
        path.to_str().unwrap(),
        "--level",
        "1",
        "--size",
        "32x32",
        "--out",
        dir.join("p.png").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert_eq!(err.matches("not a material property the renderer animates").count(), 1, "{err}");
    let mut d = doc.clone();
    d["animations"][0]["channels"][0]["target"]["extensions"]["KHR_animation_pointer"]["pointer"] =
        json!("/extensions/KHR_lights_punctual/lights/3/intensity");
    expect_bad(&dir, "far.gltf", embedded(d, &bin), &["animations[0].channels[0]", "the file has 1 lights"]);
    let mut d = doc;
    d["animations"][0]["channels"][2]["target"]["extensions"]["KHR_animation_pointer"]["pointer"] =
        json!("/extensions/KHR_lights_punctual/lights/0/spot.outerConeAngle");
    let s = Scene::load(&write(&dir, "blender_cone.gltf", embedded(d, &bin))).unwrap();
    assert!((s.at_time(1.0).lights[0].cone - 20f32.to_radians()).abs() < 1e-6, "Blender's spot.outerConeAngle");
}

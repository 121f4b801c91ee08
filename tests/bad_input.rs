//! Bad input exits with code 2 and a message naming the file, the line and the field, and leaves no output
//! file behind. No Vulkan device exits with code 1 and the install hint.

mod common;
use common::*;
use std::path::Path;

const SCENE: &str = r#"[[light]]
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
shape = "sphere"
radius = 0.3
translate = [0.0, 0.5, 0.0]
material = { kind = "dielectric", ior = 1.5 }
"#;

/// Write `text` as a scene, render it, and expect exit code 2 with every `needles` in stderr.
fn expect_bad(test: &str, text: &str, extra: &[&str], needles: &[&str]) {
    let dir = out_dir(test);
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out.exr");
    let mut args =
        vec!["render", "--scene", scene.to_str().unwrap(), "--aov", "caustics", "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = caustics(&args);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "exit code; stderr:\n{stderr}");
    for n in needles {
        let n = n.replace("{scene}", scene.to_str().unwrap());
        assert!(stderr.contains(&n), "stderr lacks `{n}`:\n{stderr}");
    }
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_no_output(&out);
}

#[test]
fn malformed_toml() {
    let text = SCENE.replace("intensity = 1.0", "intensity = = 1.0");
    expect_bad("malformed_toml", &text, &[], &["{scene}:6:"]);
}

#[test]
fn unknown_key() {
    let text = SCENE.replace("radius = 0.3", "radius = 0.3\nradios = 2.0");
    expect_bad("unknown_key", &text, &[], &["{scene}:26:", "unknown field `radios`"]);
}

#[test]
fn missing_mesh() {
    let text = SCENE.replace("shape = \"sphere\"\nradius = 0.3", "shape = \"mesh\"\npath = \"../meshes/nope.obj\"");
    expect_bad("missing_mesh", &text, &[], &["{scene}:25: object[1] \"glass\".path", "nope.obj", "not found"]);
}

#[test]
fn ior_not_positive_or_nan() {
    for (i, bad) in ["ior = 0.0", "ior = -1.5", "ior = nan"].iter().enumerate() {
        let text = SCENE.replace("ior = 1.5", bad);
        expect_bad(
            &format!("ior_{i}"),
            &text,
            &[],
            &["{scene}:27: object[1] \"glass\".material.ior", "index of refraction"],
        );
    }
}

#[test]
fn cone_outside_range() {
    // 1e-45: a cone too narrow for a frustum in f32, which once reached the light view's fit and panicked there.
    let bad = ["cone_deg = 0.0", "cone_deg = 90.0", "cone_deg = -5.0", "cone_deg = 120.0", "cone_deg = 1e-45"];
    for (i, bad) in bad.iter().enumerate() {
        let text = SCENE.replace("cone_deg = 40.0", bad);
        expect_bad(&format!("cone_{i}"), &text, &[], &["{scene}:5: light[0].cone_deg", "[0.1, 90)"]);
    }
}

#[test]
fn unknown_camera() {
    expect_bad("unknown_camera", SCENE, &["--camera", "nope"], &["{scene}", "--camera", "nope", "top"]);
}

#[test]
fn bad_size() {
    for (i, bad) in ["0x100", "100", "axb", "100x-3", "99999x10"].iter().enumerate() {
        expect_bad(&format!("size_{i}"), SCENE, &["--size", bad], &["--size", "WxH"]);
    }
}

#[test]
fn wrong_output_extension() {
    let dir = out_dir("wrong_ext");
    let out = dir.join("c.png");
    let o = caustics(&["render", "--aov", "caustics", "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains(".exr"));
    assert_no_output(&out);
}

#[test]
fn missing_scene_file() {
    let dir = out_dir("missing_scene");
    let out = dir.join("c.exr");
    let o = caustics(&[
        "render",
        "--scene",
        "/nonexistent/scene.toml",
        "--aov",
        "caustics",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("/nonexistent/scene.toml"));
    assert_no_output(&out);
}

#[test]
fn no_vulkan_device_exits_1_with_hint() {
    let dir = out_dir("no_device");
    let out = dir.join("c.exr");
    let o = caustics_env(
        &["render", "--aov", "caustics", "--out", out.to_str().unwrap()],
        &[
            ("VK_DRIVER_FILES", "/nonexistent/icd.json"),
            ("VK_ICD_FILENAMES", "/nonexistent/icd.json"),
            ("CAUSTICS_VALIDATION", "0"),
        ],
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("tools/setup"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_no_output(&out);
    assert!(!Path::new(&out).exists());
}

#[test]
fn unknown_light_kind_is_reported_before_missing_fields() {
    let text = SCENE.replace("kind = \"spot\"", "kind = \"area\"").replace("intensity = 1.0\n", "");
    expect_bad("light_kind_first", &text, &[], &["{scene}:2: light[0].kind", "unknown light kind `area`"]);
}

/// A file that is neither TOML nor glTF given as `--scene` is refused by its type, naming the accepted ones (not
/// with a TOML parse error): an OBJ gets the hint to reference it from a TOML scene.
#[test]
fn a_scene_of_the_wrong_file_type_names_the_accepted_types() {
    let dir = out_dir("wrong_scene_type");
    let out = dir.join("c.exr");
    let bunny = format!("{}/assets/meshes/bunny.obj", env!("CARGO_MANIFEST_DIR"));
    let text = dir.join("scene.txt");
    std::fs::write(&text, SCENE).unwrap();
    for (scene, needles) in [
        (bunny.as_str(), vec!["not a scene file", ".toml", ".gltf, .glb", "found .obj", "shape = \"mesh\""]),
        (text.to_str().unwrap(), vec!["not a scene file", ".toml", ".gltf, .glb", "found .txt"]),
    ] {
        let o = caustics(&["render", "--scene", scene, "--aov", "caustics", "--out", out.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{scene}: {stderr}");
        for n in needles {
            assert!(stderr.contains(n), "{scene}: stderr lacks `{n}`:\n{stderr}");
        }
        assert!(!stderr.contains("expected") && !stderr.contains("panicked"), "{stderr}");
        assert_no_output(&out);
    }
}

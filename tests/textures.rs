//! Textured receivers and the environment map (docs/design.md "Textures", "Environment"): the linear beauty on
//! a textured floor is albedo(uv)·(E_direct + E_caustics)/π with the texture where its uv puts it; an
//! environment map lights the receivers by its irradiance and stays out of the caustics AOV; bad textures and
//! maps exit 2 naming the file.

mod common;
use caustics::image_io::RgbImage;
use caustics::scene::EnvironmentMap;
use caustics::settings::{Settings, Transport};
use common::*;
use glam::{Vec2, Vec3};
use std::path::Path;

/// The sphere scene with its floor textured by the block texture (repeated twice along u) and, optionally, an
/// `[environment]` section.
fn textured_scene(dir: &Path, environment: &str) -> String {
    write_block_texture(&dir.join("blocks.png"));
    let text = std::fs::read_to_string(SPHERE).expect("sphere scene").replace(
        r#"material = { kind = "diffuse", albedo = 0.8 }"#,
        r#"material = { kind = "diffuse", albedo_texture = "blocks.png", uv_scale = [2.0, 1.0] }"#,
    );
    assert!(text.contains("blocks.png"));
    let path = dir.join("textured.toml");
    std::fs::write(&path, format!("{text}\n{environment}")).expect("write scene");
    path.to_str().unwrap().to_string()
}

/// The frame's float AOV `aov` (the linear beauty, caustics or direct) from the top camera at 128² (two-interface,
/// level 2, one sample a pixel), with the settings changed by `f`, as RGB, rendered in process on the shared
/// device; validation stayed silent.
fn top(
    device: &std::sync::Arc<caustics::gpu::Device>,
    scene: &str,
    aov: caustics::Aov,
    f: impl FnOnce(&mut Settings),
) -> RgbImage {
    let settings = with(Settings::default(), |s| {
        s.quality.level = Some(2);
        s.quality.transport = Transport::TwoInterface;
        s.quality.aa = 1;
        f(s);
    });
    let (img, _) = top_aov(&mut renderer(device, scene, settings), 128, aov);
    img
}

/// The floor point under pixel (x, y) of the top camera at 128² (columns +x, rows +z over [-1, 1]²), and its
/// texture coordinates through the material's uv scale (2, 1).
fn floor_at(x: u32, y: u32) -> (Vec2, Vec2) {
    let p = Vec2::new((x as f32 + 0.5) / 128.0 * 2.0 - 1.0, (y as f32 + 0.5) / 128.0 * 2.0 - 1.0);
    let uv = Vec2::new(p.x * 0.5 + 0.5, p.y * 0.5 + 0.5);
    (p, uv * Vec2::new(2.0, 1.0))
}

/// The floor pixels the texture tests check: those the top camera sees directly (outside the sphere's disk,
/// with a margin) and well inside a block of the texture (a sixth of a block, 2.7 pixels, from its edges, where
/// filtering sees one color), with their uv (through the uv scale) and the block's albedo.
fn checked_floor() -> Vec<(u32, u32, Vec2, Vec3)> {
    let mut out = Vec::new();
    for y in 0..128 {
        for x in 0..128 {
            let (p, uv) = floor_at(x, y);
            let (albedo, inside) = block_albedo(uv, 1.0 / 6.0);
            if p.length() >= 0.4 && inside {
                out.push((x, y, uv, albedo));
            }
        }
    }
    out
}

/// On every floor pixel the top camera sees directly (outside the sphere's disk, with a margin) and well inside a
/// block of the texture (a sixth of a block, 2.7 pixels, from its edges, where filtering sees one color), the
/// linear beauty is albedo(uv)·(E_direct + E_caustics)/π, the albedo the texel the uv transform puts there.
/// Measured on lavapipe: agreement to 1.4e-7 relative; the bound is 1e-4 (the texture and the eye g-buffer hold the
/// albedo in 16 bits, 8e-5 of the darkest block's value). A texture
/// mirrored in u or v, transposed or without its uv scale would put other blocks there (they differ by 0.27 in
/// a channel).
#[test]
fn textured_floor_beauty_is_albedo_times_irradiance() {
    let (_gpu, device) = gpu();
    let dir = out_dir("textures_floor");
    let scene = textured_scene(&dir, "");
    let off = |s: &mut Settings| s.quality.sky = Some(0.0);
    let beauty = top(&device, &scene, caustics::Aov::BeautyHdr, off);
    let direct = top(&device, &scene, caustics::Aov::Direct, off);
    let caustics = top(&device, &scene, caustics::Aov::Caustics, off);
    let (mut n, mut worst, mut lit) = (0, 0.0f64, 0);
    let mut blocks = std::collections::HashSet::new();
    for (x, y, uv, albedo) in checked_floor() {
        let i = (y * 128 + x) as usize;
        for c in 0..3 {
            let e = direct.data[i][c] as f64 + caustics.data[i][c] as f64;
            let want = albedo[c] as f64 / std::f64::consts::PI * e;
            let got = beauty.data[i][c] as f64;
            let err = (got - want).abs() / want.max(1e-6);
            worst = worst.max(err);
            assert!(err <= 1e-4, "pixel ({x}, {y}) channel {c}: beauty {got}, albedo(uv) E/pi {want}");
        }
        lit += (direct.data[i][0] > 0.0) as usize;
        blocks.insert(((uv.x * 4.0).floor() as i32 % 4, (uv.y * 4.0).floor() as i32));
        n += 1;
    }
    eprintln!("{n} floor pixels ({lit} lit), worst relative error {worst:.2e}, {} blocks seen", blocks.len());
    assert!(n > 5000 && lit > 2000, "{n} floor pixels checked, {lit} lit");
    assert_eq!(blocks.len(), 16, "every block of the texture is checked");
}

/// The environment map lights the floor by its irradiance: with the sphere scene's light, E_env on the floor is
/// the beauty's excess over albedo·(E_direct + E_caustics)/π, and it matches the brute-force integral of the map
/// (every texel, L cos dω, over the floor's hemisphere) within 1% on every floor pixel the top camera sees outside
/// the sphere (measured: 3.7e-7; the irradiance map's first row is the zenith's exact value, and its interpolation
/// elsewhere is the unit test's 0.74% at worst); the caustics AOV is the same with and without the map (measured:
/// rel-L1 2e-8 to 2e-7, the order in which photons land; the bound is 1e-6).
#[test]
fn environment_map_lights_the_receivers_by_its_irradiance() {
    let (_gpu, device) = gpu();
    let dir = out_dir("textures_environment");
    let sky = EnvironmentMap::procedural_sky(256);
    sky.write_hdr(&dir.join("sky.hdr")).expect("write map");
    let intensity = 0.05f32;
    let lit = textured_scene(&dir, &format!("[environment]\npath = \"sky.hdr\"\nintensity = {intensity}\n"));
    // The file holds RGBE: integrate what was written.
    let map = EnvironmentMap::load(&dir.join("sky.hdr")).expect("read map back");
    let want_e = map.irradiance(Vec3::Y) * intensity;
    let beauty = top(&device, &lit, caustics::Aov::BeautyHdr, |_| ());
    let direct = top(&device, &lit, caustics::Aov::Direct, |_| ());
    let caustics = top(&device, &lit, caustics::Aov::Caustics, |_| ());
    let unlit = textured_scene(&dir, "");
    let caustics_without = top(&device, &unlit, caustics::Aov::Caustics, |_| ());
    let (mut diff, mut total) = (0.0f64, 0.0f64);
    for (a, b) in caustics.data.iter().zip(&caustics_without.data) {
        for c in 0..3 {
            diff += (a[c] as f64 - b[c] as f64).abs();
            total += b[c] as f64;
        }
    }
    eprintln!("caustics AOV with and without the map: rel-L1 {:.2e}", diff / total);
    assert!(
        total > 0.0 && diff <= 1e-6 * total,
        "the environment stays out of the caustics AOV: rel-L1 {}",
        diff / total
    );
    let (mut n, mut worst) = (0, 0.0f64);
    for (x, y, _, albedo) in checked_floor() {
        let i = (y * 128 + x) as usize;
        for c in 0..3 {
            let a = albedo[c] as f64 / std::f64::consts::PI;
            let e_env = beauty.data[i][c] as f64 / a - direct.data[i][c] as f64 - caustics.data[i][c] as f64;
            let err = (e_env - want_e[c] as f64).abs() / want_e[c] as f64;
            worst = worst.max(err);
            assert!(err <= 0.01, "pixel ({x}, {y}) channel {c}: E_env {e_env} W/m², the map's {}", want_e[c]);
        }
        n += 1;
    }
    eprintln!("{n} floor pixels: E_env {want_e} W/m², worst relative error {worst:.2e}");
    assert!(n > 5000);
}

/// A textured receiver's texture and an environment map that cannot be used are bad input: exit 2 and a message
/// that names the file (and, for a scene field, its line and field), no output written.
#[test]
fn bad_textures_and_maps_exit_2() {
    let dir = out_dir("textures_bad");
    let base = std::fs::read_to_string(SPHERE).unwrap();
    std::fs::write(dir.join("not_an_image.png"), b"this is text").unwrap();
    let mut nan = EnvironmentMap::procedural_sky(16);
    nan.texels[5] = [f32::NAN, 0.0, 0.0];
    // RGBE cannot hold a NaN: write the map as EXR.
    let img = RgbImage { width: 16, height: 8, data: nan.texels.clone() };
    caustics::image_io::write_exr(&dir.join("nan.exr"), &img).expect("write exr");
    let square = RgbImage { width: 16, height: 16, data: vec![[1.0; 3]; 256] };
    caustics::image_io::write_exr(&dir.join("square.exr"), &square).expect("write exr");
    let floor = r#"material = { kind = "diffuse", albedo = 0.8 }"#;
    let cases: [(&str, String, &[&str]); 5] = [
        (
            "missing",
            base.replace(floor, r#"material = { kind = "diffuse", albedo_texture = "nowhere.png" }"#),
            &["nowhere.png", "not found", "albedo_texture"],
        ),
        (
            "not_image",
            base.replace(floor, r#"material = { kind = "diffuse", albedo_texture = "not_an_image.png" }"#),
            &["not_an_image.png", "not a PNG, JPEG or WebP"],
        ),
        ("nan", format!("{base}\n[environment]\npath = \"nan.exr\"\n"), &["nan.exr", "texel (5, 0)", "finite"]),
        ("square", format!("{base}\n[environment]\npath = \"square.exr\"\n"), &["square.exr", "twice as wide"]),
        (
            "glass_texture",
            base.replace(
                r#"material = { kind = "dielectric", ior = 1.5 }"#,
                r#"material = { kind = "dielectric", ior = 1.5, checker = { squares = 4, albedo = 0.1 } }"#,
            ),
            &["checker", "only a diffuse material"],
        ),
    ];
    for (name, text, needles) in cases {
        let scene = dir.join(format!("{name}.toml"));
        std::fs::write(&scene, text).unwrap();
        let out = dir.join(format!("{name}.png"));
        let r = caustics(&["render", "--scene", scene.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{name}: exit code ({stderr})");
        let file = format!("{name}.toml");
        for needle in needles.iter().copied().chain([file.as_str()]) {
            assert!(stderr.contains(needle), "{name}: `{needle}` not in: {stderr}");
        }
        assert_no_output(&out);
    }
}

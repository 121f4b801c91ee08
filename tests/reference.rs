//! The CPU reference against the analytic figures of docs/design.md ("Ground truth and error"), its energy account,
//! determinism and convergence.
//!
//! Tolerances come from measurement: the spreads quoted below are the standard deviations over 6–8 seeds of
//! release runs with the same photon counts (`caustics reference --seed S --stats ...`), and the biases are those
//! of the mean. Russian roulette at each interface makes the caustic flux a sum of Bernoulli outcomes, so its
//! noise is ~sd(p)/√N whatever the stratification; the direct flux has no roulette and is far more precise.
//! Each test runs on fixed seeds, so it is deterministic; the margins are there so that a change of random stream
//! does not flip it, while a real error (a wrong Fresnel term, a lost interface, a leak) moves the figures by
//! more than the tolerance.

use caustics::error::Error;
use caustics::image_io::RgbImage;
use caustics::metrics::compare;
use caustics::reference::{trace, Aov, Paths, RefOutput, RefParams};
use caustics::scene::Scene;
use glam::Vec3;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes").join(name)
}

fn load(name: &str) -> Scene {
    Scene::load(&scene_path(name)).unwrap()
}

fn sphere() -> &'static Scene {
    static S: OnceLock<Scene> = OnceLock::new();
    S.get_or_init(|| load("sphere.toml"))
}

fn params(photons: u64, seed: u64, aov: Aov, paths: Paths, size: u32) -> RefParams {
    RefParams { photons, seed, aov, paths, width: size, height: size, ..RefParams::default() }
}

/// Σ E · pixel area over the image, channel 0 (white light): the `top` camera covers the 2 m x 2 m floor.
fn image_flux(img: &RgbImage) -> f64 {
    let pixel_area = 4.0 / (img.width as f64 * img.height as f64);
    img.data.iter().map(|p| p[0] as f64).sum::<f64>() * pixel_area
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The energy account of every run: it must close, and no photon may be lost to a numerical dead end.
fn check_account(name: &str, out: &RefOutput) {
    let a = &out.stats.energy_account;
    assert!(a.residual_rel < 1e-6, "{name}: energy account residual {} ({a:?})", a.residual_rel);
    assert_eq!(out.stats.counts.photons_lost, 0, "{name}: photons lost");
    let sum = a.deposited_caustics + a.deposited_direct + a.escaped + a.cut_by_bounce_cap + a.filtered_by_paths;
    assert!(rel(sum, a.emitted) < 1e-6, "{name}: {sum} vs emitted {}", a.emitted);
    // The image holds exactly the flux binned into it (f32 pixels round at ~1e-7 relative).
    assert!(rel(image_flux(&out.image), a.image_integral) < 1e-5, "{name}: image integral");
}

/// All paths, sphere scene, seeds 1 and 2 at 200k photons and 50k photons (128² image).
fn sphere_all(seed: u64, photons: u64) -> &'static RefOutput {
    static CELLS: [OnceLock<RefOutput>; 4] = [const { OnceLock::new() }; 4];
    let i = match (seed, photons) {
        (1, 200_000) => 0,
        (2, 200_000) => 1,
        (1, 50_000) => 2,
        (2, 50_000) => 3,
        _ => unreachable!(),
    };
    CELLS[i].get_or_init(|| trace(sphere(), &params(photons, seed, Aov::Caustics, Paths::All, 128)).unwrap())
}

#[test]
fn all_paths_caustic_flux_matches_the_analytic_figure() {
    // docs/design.md: all paths through or off the glass put 0.111370 W on the floor.
    // Measured (release, 8 seeds x 200k): sd 0.125% per run, mean bias -0.03% (the tessellated sphere); the two
    // runs averaged here have sd ~0.09%, so 0.5% is > 5 sd.
    let (a, b) = (sphere_all(1, 200_000), sphere_all(2, 200_000));
    check_account("all paths, seed 1", a);
    check_account("all paths, seed 2", b);
    let flux = 0.5 * (image_flux(&a.image) + image_flux(&b.image));
    println!("all paths: {flux:.6} W (seeds: {:.6}, {:.6})", image_flux(&a.image), image_flux(&b.image));
    assert!(rel(flux, 0.111370) < 0.005, "all-paths caustic flux {flux} vs 0.111370");
    // The sampled sub-cone is the sphere's tangent cone, 2π(1 − cos 11.537°) = 0.126946 sr at 1 W/sr, and lies
    // inside the 40° spot: every photon carries flux and the emitted flux is exactly I·Ω (the cone gets a 1e-7 rad
    // margin: 1e-6 relative).
    let s = &a.stats;
    assert_eq!(s.lights[0].sampling, "refractor sub-cone");
    assert_eq!(s.counts.photons_outside_cone, 0);
    assert!(rel(s.energy_account.emitted, 0.126946) < 1e-5, "emitted {}", s.energy_account.emitted);
    // Everything that reaches the floor is inside the `top` image, and the floor is perpendicular to the camera.
    assert!(rel(s.energy_account.aov_in_image, s.energy_account.deposited_caustics) < 1e-12);
}

/// Two refractions only, sphere, 300k photons, with the radial profile around the floor center.
fn sphere_two() -> &'static RefOutput {
    static C: OnceLock<RefOutput> = OnceLock::new();
    C.get_or_init(|| {
        let mut p = params(300_000, 1, Aov::Caustics, Paths::TwoRefractions, 128);
        p.radial_center = Some(Vec3::ZERO);
        trace(sphere(), &p).unwrap()
    })
}

#[test]
fn two_refraction_flux_and_radii_match_the_analytic_figures() {
    let out = sphere_two();
    check_account("two refractions", out);
    let flux = image_flux(&out.image);
    let radial = out.radial.as_ref().unwrap();
    let (r50, r90) = (radial.radius_containing(0.5).unwrap(), radial.radius_containing(0.9).unwrap());
    println!("two refractions: {flux:.6} W, r50 {r50:.6} m, r90 {r90:.6} m");
    // docs/design.md: 0.105980 W. Measured (6 seeds x 300k): sd 0.106%, bias -0.02%.
    assert!(rel(flux, 0.105980) < 0.005, "two-refraction flux {flux} vs 0.105980");
    // The radial profile counts the same photons as the image.
    assert!(rel(radial.total_flux(), out.stats.energy_account.deposited_caustics) < 1e-9);
    // docs/design.md: half within r = 0.0188 m, 90% within 0.1373 m (both given to 3-4 digits). Measured (6 seeds x
    // 300k): r50 0.018796 m, sd 0.04%; r90 0.137366 m, sd 0.39% (the 90% radius lies in the sparse outer tail).
    // Tolerances: r50 1% (the figure's own rounding is ±0.27%), r90 2.5% (> 6 sd).
    assert!(rel(r50, 0.0188) < 0.01, "r50 {r50} vs 0.0188");
    assert!(rel(r90, 0.1373) < 0.025, "r90 {r90} vs 0.1373");
    // The filtered photons are exactly the other caustic paths: with them the all-paths figure comes back.
    // Measured (6 seeds x 300k): sd 0.097%, bias -0.01%.
    let all = out.stats.energy_account.deposited_caustics + out.stats.energy_account.filtered_by_paths;
    assert!(rel(all, 0.111370) < 0.005, "two refractions + filtered {all} vs 0.111370");
}

#[test]
fn direct_flux_outside_the_shadow_matches_the_analytic_figure() {
    // docs/design.md: 0.678486 W of direct light on the floor outside the sphere's shadow (40° cone). No roulette is
    // involved, so stratification works fully: measured (6 seeds x 100k) sd 0.028%, bias +0.01%. Tolerance 0.2%.
    let out = trace(sphere(), &params(100_000, 1, Aov::Direct, Paths::All, 64)).unwrap();
    check_account("direct", &out);
    let flux = image_flux(&out.image);
    println!("direct: {flux:.6} W");
    assert!(rel(flux, 0.678486) < 0.002, "direct flux {flux} vs 0.678486");
    // The whole 40° cone is sampled for the direct AOV: 2π(1 − cos 40°) sr at 1 W/sr (the cone angle is an f32).
    let cone = 2.0 * std::f64::consts::PI * (1.0 - 40f64.to_radians().cos());
    assert_eq!(out.stats.lights[0].sampling, "spot cone");
    assert!(rel(out.stats.energy_account.emitted, cone) < 1e-6, "emitted {}", out.stats.energy_account.emitted);
}

#[test]
fn ior_2_4_matches_the_analytic_figures() {
    // docs/design.md, IOR 2.4: two refractions 0.071958 W, all paths 0.081566 W. One two-refractions run gives both
    // (all = deposited + filtered, see `all_paths_equal_two_refractions_plus_filtered`). Measured (6 seeds x
    // 300k): two refractions sd 0.143%, bias +0.09%; all paths sd 0.185%, bias +0.09%. At 600k photons here the
    // sd is ~0.1% and ~0.13%, so 0.5% is ~4 sd beyond the bias.
    let out = trace(&load("ior24.toml"), &params(600_000, 1, Aov::Caustics, Paths::TwoRefractions, 64)).unwrap();
    check_account("ior 2.4", &out);
    let two = image_flux(&out.image);
    let all = out.stats.energy_account.deposited_caustics + out.stats.energy_account.filtered_by_paths;
    println!("ior 2.4: two refractions {two:.6} W, all paths {all:.6} W");
    assert!(rel(two, 0.071958) < 0.005, "IOR 2.4 two-refraction flux {two} vs 0.071958");
    assert!(rel(all, 0.081566) < 0.005, "IOR 2.4 all-paths flux {all} vs 0.081566");
}

#[test]
fn all_paths_equal_two_refractions_plus_filtered() {
    // Same seed, same photons, same roulette: `--paths two-refractions` only moves photons from deposited to
    // filtered.
    let a = trace(sphere(), &params(20_000, 3, Aov::Caustics, Paths::All, 64)).unwrap();
    let t = trace(sphere(), &params(20_000, 3, Aov::Caustics, Paths::TwoRefractions, 64)).unwrap();
    check_account("all (20k)", &a);
    check_account("two (20k)", &t);
    let (ea, et) = (&a.stats.energy_account, &t.stats.energy_account);
    assert_eq!(ea.filtered_by_paths, 0.0);
    assert!(et.filtered_by_paths > 0.0);
    assert!(rel(et.deposited_caustics + et.filtered_by_paths, ea.deposited_caustics) < 1e-12);
    assert_eq!(a.stats.counts.photons_caustics, t.stats.counts.photons_caustics + t.stats.counts.photons_filtered);
    assert_eq!(ea.escaped, et.escaped);
    assert_eq!(a.stats.counts.refractions, t.stats.counts.refractions);
}

#[test]
fn same_seed_is_bit_identical_on_any_thread_count() {
    let run = |threads, seed| {
        let mut p = params(20_000, seed, Aov::Caustics, Paths::All, 64);
        p.threads = Some(threads);
        trace(sphere(), &p).unwrap()
    };
    let bits = |o: &RefOutput| o.image.data.iter().flat_map(|p| p.map(f32::to_bits)).collect::<Vec<u32>>();
    let one = run(1, 7);
    for threads in [2, 3] {
        let other = run(threads, 7);
        assert_eq!(other.stats.threads, threads);
        assert!(bits(&one) == bits(&other), "{threads} threads changed the image");
        assert_eq!(one.stats.counts, other.stats.counts, "{threads} threads changed the counts");
    }
    let reseeded = run(2, 8);
    assert!(bits(&one) != bits(&reseeded), "the seed must change the image");
}

#[test]
fn noise_falls_like_one_over_sqrt_n() {
    // rel-L1 at 64² between two seeds, at N = 50k and 4N = 200k. For independent noise it is proportional to the
    // per-pixel standard deviation, so it should halve. Measured (release, two seed pairs each): 0.0882 and 0.0864
    // at 50k, 0.0446 and 0.0447 at 200k: ratio 1.95-1.98 (2.02 and 1.98 for 100k→400k and 200k→800k; at 25k→100k it
    // drops to 1.83 as many 64² cells hold only a few photons). Pair-to-pair spread of each rel-L1 is ~1.5%, so
    // the ratio is good to ~±0.05. Band: [1.8, 2.2]. A sampler whose strata or roulette did not decorrelate with N
    // would fall like N^-0.75 (ratio 2.8) or not at all.
    let small = compare(&sphere_all(1, 50_000).image, &sphere_all(2, 50_000).image, 64, 2.0).rel_l1;
    let large = compare(&sphere_all(1, 200_000).image, &sphere_all(2, 200_000).image, 64, 2.0).rel_l1;
    println!("rel-L1 between seeds: {small:.5} at 50k, {large:.5} at 200k, ratio {:.3}", small / large);
    assert!(small > 0.0 && large > 0.0);
    let ratio = small / large;
    assert!((1.8..=2.2).contains(&ratio), "rel-L1 ratio {ratio} for 4x the photons (want ~2)");
}

#[test]
fn directional_light_over_the_sphere() {
    // A 1 W/m² directional light straight down over the sphere scene: the sphere intercepts E·πR² = 0.282743 W
    // (the 81,920-triangle icosphere's silhouette is a hair smaller), and the 2 m x 2 m floor receives
    // 4 − πR² = 3.717257 W of direct light.
    let text = std::fs::read_to_string(scene_path("sphere.toml")).unwrap().replace(
        "kind = \"spot\"\nposition = [0.0, 2.0, 0.0]\ntarget = [0.0, 0.5, 0.0]\ncone_deg = 40.0\nintensity = 1.0          # W/sr",
        "kind = \"directional\"\nposition = [0.0, 2.0, 0.0]\ntarget = [0.0, 0.5, 0.0]\nintensity = 1.0",
    );
    let scene = Scene::parse(&text, &scene_path("sphere.toml")).unwrap();
    assert_eq!(scene.lights[0].kind, caustics::scene::LightKind::Directional);
    let intercepted = std::f64::consts::PI * 0.09;
    // Direct: no roulette; measured 3.7171 W at 40k photons.
    let d = trace(&scene, &params(40_000, 1, Aov::Direct, Paths::All, 64)).unwrap();
    check_account("directional, direct", &d);
    assert_eq!(d.stats.lights[0].sampling, "beam over scene");
    let direct = image_flux(&d.image);
    assert!(rel(direct, 4.0 - intercepted) < 0.002, "directional direct flux {direct} vs {}", 4.0 - intercepted);
    // Caustics: the beam rectangle covers the sphere; what does not hit it lands on the floor as direct light, so
    // emitted − direct = intercepted (stratified, no roulette before the first hit).
    let c = trace(&scene, &params(40_000, 1, Aov::Caustics, Paths::All, 64)).unwrap();
    check_account("directional, caustics", &c);
    assert_eq!(c.stats.lights[0].sampling, "beam over refractors");
    let a = &c.stats.energy_account;
    let hit = a.emitted - a.deposited_direct;
    assert!(rel(hit, intercepted) < 0.003, "directional: sphere intercepts {hit} vs {intercepted}");
    assert!(a.deposited_caustics > 0.8 * intercepted && a.deposited_caustics < intercepted);
}

#[test]
fn hard_case_scenes_trace_and_close_their_account() {
    for name in ["ior24.toml", "oblique.toml", "tilted_cube.toml", "vertex_above.toml", "thin.toml", "open_mesh.toml"] {
        let out = trace(&load(name), &params(8_000, 1, Aov::Caustics, Paths::All, 32)).unwrap();
        check_account(name, &out);
        let a = &out.stats.energy_account;
        assert!(a.deposited_caustics > 0.1 * a.emitted, "{name}: caustic flux {}", a.deposited_caustics);
        if name == "tilted_cube.toml" {
            assert!(out.stats.counts.total_internal_reflections > 100, "{name}: no total internal reflection");
        }
    }
}

#[test]
fn perspective_and_unknown_cameras_are_bad_input() {
    let e = trace(sphere(), &RefParams { camera: Some("main".into()), ..RefParams::default() }).unwrap_err();
    let perspective =
        |r: &str| r.contains("`main`") && r.contains("perspective") && r.contains("orthographic cameras: top");
    assert!(matches!(&e, Error::Setting { field: "RefParams::camera", rule, .. } if perspective(rule)), "{e}");
    assert_eq!(e.exit_code(), 2);
    let e = trace(sphere(), &RefParams { camera: Some("nope".into()), ..RefParams::default() }).unwrap_err();
    assert!(matches!(&e, Error::Setting { value, rule, .. } if value == "nope" && rule.contains("cameras: ")), "{e}");
}

fn cli(args: &[&str]) -> (i32, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_caustics")).arg("reference").args(args).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    (out.status.code().unwrap_or(-1), text)
}

#[test]
fn cli_writes_the_image_and_stats_and_rejects_bad_flags() {
    let dir = std::env::temp_dir().join(format!("caustics-reference-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let exr = dir.join("c.exr");
    let json = dir.join("c.json");
    let scene = scene_path("sphere.toml");
    let (s, e, j) = (scene.to_str().unwrap(), exr.to_str().unwrap(), json.to_str().unwrap());

    for (flag, value) in [("--size", "12x"), ("--size", "0x10"), ("--aov", "beauty"), ("--paths", "three")] {
        let (code, text) = cli(&["--scene", s, "--photons", "100", flag, value, "--out", e]);
        assert_eq!(code, 2, "{flag} {value}: {text}");
        assert!(text.contains(flag), "{flag} {value}: {text}");
        assert!(!exr.exists(), "no output after bad input");
    }
    let (code, text) = cli(&["--scene", s, "--camera", "main", "--photons", "100", "--out", e]);
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("main"), "{text}");

    let (code, text) =
        cli(&["--scene", s, "--photons", "3000", "--size", "32x24", "--out", e, "--stats", j, "--seed", "5"]);
    assert_eq!(code, 0, "{text}");
    let img = caustics::image_io::read_exr(&exr).unwrap();
    assert_eq!((img.width, img.height), (32, 24));
    let stats: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(stats["seed"], 5);
    assert_eq!(stats["photons_per_light"], 3000);
    assert!(stats["energy_account"]["residual_rel"].as_f64().unwrap() < 1e-6);
    assert!(stats["photons_per_s"].as_f64().unwrap() > 0.0);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn receivers_hide_receivers_but_refractors_do_not() {
    // No refractor: a 1 W/m² directional light at 45° (direction (1, −1, 0)/√2) over the floor and a 0.5 m square
    // diffuse shelf at y = 0.3 above its center. Both receive E·cos 45° = 0.7071 W/m². The shelf's shadow on the
    // floor is shifted by 0.3 m along +x (x ∈ [0.05, 0.55]); the top camera cannot see the floor under the shelf
    // (x ∈ [−0.25, 0.25]). Lit floor: 4 − 0.25 m² (shadow); of it, 0.25 − 0.1 = 0.15 m² is hidden under the shelf.
    // So the image holds (4 − 0.25 − 0.15 + 0.25)·0.7071 = 2.722361 W, and 0.15·0.7071 = 0.106066 W is deposited but
    // hidden. Stratified, no roulette: only the edges of the shadow and of the hidden square are noisy.
    let text = r#"
[[light]]
kind = "directional"
position = [-1.0, 1.0, 0.0]
target = [0.0, 0.0, 0.0]
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
name = "shelf"
shape = "plane"
size = [0.5, 0.5]
translate = [0.0, 0.3, 0.0]
material = { kind = "diffuse", albedo = 0.8 }
"#;
    let scene = Scene::parse(text, Path::new("shelf.toml")).unwrap();
    let out = trace(&scene, &params(40_000, 1, Aov::Direct, Paths::All, 64)).unwrap();
    check_account("shelf", &out);
    let c = std::f64::consts::FRAC_1_SQRT_2;
    let a = &out.stats.energy_account;
    let in_image = image_flux(&out.image);
    println!("shelf: image {in_image:.6} W, hidden {:.6} W", a.deposited_direct - a.aov_in_image);
    assert!(rel(in_image, 3.85 * c) < 0.003, "visible direct flux {in_image} vs {}", 3.85 * c);
    assert!(rel(a.deposited_direct - a.aov_in_image, 0.15 * c) < 0.02, "hidden flux");
    assert!(rel(a.deposited_direct, 4.0 * c) < 0.002, "all receivers get E·cos 45° over 4 m²");
}

#[test]
fn cache_traces_once_and_keys_on_the_scene_contents() {
    let dir = std::env::temp_dir().join(format!("caustics-reference-cache-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // A copy of the vertex-above scene (small mesh) and its OBJ, so the test can edit both.
    let scenes = dir.join("scenes");
    let meshes = dir.join("meshes");
    std::fs::create_dir_all(&scenes).unwrap();
    std::fs::create_dir_all(&meshes).unwrap();
    let mesh = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/meshes/icosahedron_vertex_up.obj");
    std::fs::copy(&mesh, meshes.join("icosahedron_vertex_up.obj")).unwrap();
    let scene = scenes.join("v.toml");
    std::fs::copy(scene_path("vertex_above.toml"), &scene).unwrap();
    let cache = dir.join("cache");
    let p = params(5_000, 1, Aov::Caustics, Paths::All, 32);

    let key = caustics::reference::cache_key(&scene, &p).unwrap();
    let first = caustics::reference::cached_in(&cache, &scene, &p).unwrap();
    let exr = cache.join(format!("{key}.exr"));
    assert!(exr.is_file() && cache.join(format!("{key}.json")).is_file());
    // A second call reads the entry: make it recognizable and check that it comes back.
    let mut marked = first.clone();
    marked.data[0] = [123.0; 3];
    caustics::image_io::write_exr(&exr, &marked).unwrap();
    assert_eq!(caustics::reference::cached_in(&cache, &scene, &p).unwrap().data[0], [123.0; 3]);
    // The key follows the parameters, the scene text and the mesh file's contents.
    assert_ne!(key, caustics::reference::cache_key(&scene, &RefParams { seed: 2, ..p.clone() }).unwrap());
    assert_ne!(
        key,
        caustics::reference::cache_key(&scene, &RefParams { paths: Paths::TwoRefractions, ..p.clone() }).unwrap()
    );
    let text = std::fs::read_to_string(&scene).unwrap();
    std::fs::write(&scene, text.replace("ior = 1.5", "ior = 1.6")).unwrap();
    let key2 = caustics::reference::cache_key(&scene, &p).unwrap();
    assert_ne!(key, key2);
    let obj = std::fs::read_to_string(meshes.join("icosahedron_vertex_up.obj")).unwrap();
    std::fs::write(meshes.join("icosahedron_vertex_up.obj"), obj + "# edited\n").unwrap();
    assert_ne!(key2, caustics::reference::cache_key(&scene, &p).unwrap());
    // Traced again after the change: not the marked image.
    assert_ne!(caustics::reference::cached_in(&cache, &scene, &p).unwrap().data[0], [123.0; 3]);
    let _ = std::fs::remove_dir_all(&dir);
}

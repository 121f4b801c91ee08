//! The command line keeps its word: range messages for negative numbers, device selection by exact index or
//! unique name, warnings for ignored options, camera errors that name the usable cameras, the stats layout, and
//! the bench's JSON and tables.

mod common;
use common::*;
use std::path::{Path, PathBuf};
use std::process::Output;

fn stderr_of(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `caustics render --aov caustics --out <dir>/x.exr` with `args`: it must exit with code 2 before writing any
/// output. Returns its stderr.
fn render_refused(dir: &std::path::Path, args: &[&str]) -> String {
    let out = dir.join("x.exr");
    let mut a = vec!["render", "--aov", "caustics", "--out", out.to_str().unwrap()];
    a.extend_from_slice(args);
    let o = caustics(&a);
    let e = stderr_of(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
    assert_no_output(&out);
    e
}

#[test]
fn negative_numbers_get_the_range_message() {
    let dir = out_dir("cli_negative");
    for (flag, needle) in [
        ("--level", "must be an integer in 0..="),
        ("--check-level", "must be an integer in 0..="),
        ("--photon-budget", "must be > 0 MiB"),
        ("--error-bound", "must be > 0 texels"),
        ("--flux-threshold", "must lie in [0, 1)"),
        ("--weak-branches", "must lie in [0, 1)"),
    ] {
        let e = render_refused(&dir, &[flag, "-1"]);
        assert!(e.contains(needle) && !e.contains("unexpected argument"), "{flag} -1: {e}");
    }
}

/// `--weak-block`: 2, 4 or 0 under every method; else exit code 2 naming the flag, before any output.
#[test]
fn weak_block_is_checked() {
    let dir = out_dir("cli_weak_block");
    for (args, needle) in [
        (vec!["--weak-block", "3"], "--weak-block 3: must be 2, 4 or 0"),
        (vec!["--weak-block", "8", "--metric", "flux-error"], "--weak-block 8: must be 2, 4 or 0"),
        (vec!["--weak-block", "1", "--method", "dense"], "--weak-block 1: must be 2, 4 or 0"),
    ] {
        let e = render_refused(&dir, &args);
        assert!(e.contains(needle), "{args:?}: {e}");
    }
}

fn device_error(hint: &str) -> (Option<i32>, String) {
    let dir = out_dir(&format!("cli_device_{hint}"));
    let out = dir.join("x.exr");
    let o = caustics_env(
        &["render", "--aov", "caustics", "--size", "64x64", "--level", "1", "--out", out.to_str().unwrap()],
        &[("CAUSTICS_DEVICE", hint)],
    );
    (o.status.code(), stderr_of(&o))
}

#[test]
fn device_indices_are_never_matched_against_names() {
    // lavapipe's name ("llvmpipe (LLVM 15.0.6, 256 bits)") holds the digits 1 and 5; an index must not match it.
    for hint in ["5", "7", "15"] {
        let (code, e) = device_error(hint);
        assert_eq!(code, Some(1), "CAUSTICS_DEVICE={hint}: {e}");
        assert!(e.contains(&format!("no device has index {hint}")) && e.contains("0: "), "{e}");
    }
    let (code, e) = device_error("no-such-device");
    assert_eq!(code, Some(1), "{e}");
    assert!(e.contains("no device name contains"), "{e}");
}

#[test]
fn gpu_renders_where_there_is_one_and_gives_the_right_advice_where_there_is_none() {
    // The device list (an index no device has) says which kinds this machine has.
    let (_, list) = device_error("99");
    let has_gpu = list.contains("(GPU)");
    assert!(has_gpu || list.contains("(CPU)"), "{list}");
    let (code, e) = device_error("gpu");
    if has_gpu {
        assert_eq!(code, Some(0), "this machine lists a GPU, yet CAUSTICS_DEVICE=gpu failed: {e}");
    } else {
        assert_eq!(code, Some(1), "{e}");
        assert!(e.contains("no Vulkan GPU") && e.contains("CAUSTICS_DEVICE=cpu"), "{e}");
        assert!(!e.contains("install Mesa's lavapipe"), "lavapipe is installed: {e}");
    }
}

#[test]
fn dense_warns_about_adaptive_options_and_stats_keep_gpu_time_apart() {
    let dir = out_dir("cli_dense_warn");
    let (stats, _) = render(
        &dir,
        "dense",
        SPHERE,
        &["--camera", "top", "--size", "64x64", "--level", "1", "--aov", "caustics", "--method", "dense"]
            .iter()
            .chain(&["--metric", "max-error", "--driven", "cpu"])
            .copied()
            .collect::<Vec<_>>(),
    );
    let gpu = stats["gpu_ms"].as_object().unwrap();
    assert!(gpu.contains_key("gpu_total"), "{gpu:?}");
    for host in ["frame_wall", "cpu_record"] {
        assert!(!gpu.contains_key(host), "gpu_ms holds the host entry {host}");
    }
    for key in ["wall_ms", "cpu_ms"] {
        assert!(stats[key]["median"].as_f64().unwrap() >= 0.0, "{key}: {}", stats[key]);
    }
    // The warnings go to stderr: run again, capturing it.
    let out = dir.join("again.exr");
    let o = caustics(&[
        "render",
        "--camera",
        "top",
        "--size",
        "64x64",
        "--level",
        "1",
        "--aov",
        "caustics",
        "--method",
        "dense",
        "--metric",
        "max-error",
        "--driven",
        "cpu",
        "--out",
        out.to_str().unwrap(),
    ]);
    let e = stderr_of(&o);
    assert!(o.status.success(), "{e}");
    assert!(e.contains("warning: --metric applies to --method adaptive only"), "{e}");
    assert!(e.contains("warning: --driven applies to --method adaptive only"), "{e}");
}

#[test]
fn reference_with_a_perspective_camera_names_the_usable_ones() {
    let dir = out_dir("cli_ref_camera");
    let out = dir.join("r.exr");
    let o = caustics(&["reference", "--camera", "main", "--photons", "1000", "--out", out.to_str().unwrap()]);
    let e = stderr_of(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("--camera main: ") && e.contains("perspective") && e.contains("orthographic cameras: top"),
        "{e}"
    );
}

/// `caustics bench` at level 1 under two-interface transport, one frame of 64×64, writing `NAME.json` and `NAME.md`
/// into `dir`, with `extra` arguments.
fn small_bench(dir: &Path, name: &str, extra: &[&str]) -> (Output, PathBuf, PathBuf) {
    let (json, md) = (dir.join(format!("{name}.json")), dir.join(format!("{name}.md")));
    let base = ["bench", "--transports", "two-interface", "--levels", "1", "--frames", "1", "--warmup-s", "0"];
    let out = [json.to_str().unwrap(), md.to_str().unwrap()];
    let files = ["--size", "64x64", "--json", out[0], "--markdown", out[1]];
    (caustics(&[&base[..], &files, extra].concat()), json, md)
}

/// The bench measures its reference's noise (half the rel-L1 between the reference's two independent halves) and
/// reports it with every row and under the table. Noise falls as 1/sqrt(photons): 4× the photons halves it
/// (measured on the sphere's two-refraction caustic, a 64×64 image: 1.44% and 0.74% for 0.25M and 1M photons, a
/// ratio of 1.94; bounds 1.6 to 2.5, 2 expected). It warns when the noise is over 30% of the scene's smallest error:
/// at 0.25M photons it is 42% of dense level 1's 3.47%, at 1M 24% of 3.14%.
#[test]
fn bench_reports_its_reference_noise() {
    let dir = out_dir("cli_bench_noise");
    let mut noise = Vec::new();
    for photons in ["250000", "1000000"] {
        let (o, json, md) =
            // The two-interface model's own reference (its paths), named: the default is every path.
            small_bench(
                &dir,
                &format!("b{photons}"),
                &["--methods", "dense", "--reference-photons", photons, "--paths", "two-refractions"],
            );
        let e = stderr_of(&o);
        assert!(o.status.success(), "{e}");
        let warned = e.contains("warning: sphere: the reference's noise");
        assert_eq!(warned, photons == "250000", "{photons} photons: {e}");
        let row = &read_json(&json)["rows"][0];
        let n = row["extra"]["reference_noise"]["rel_l1_64"].as_f64().unwrap_or(f64::NAN);
        assert!(n > 0.0 && n < 0.05, "{photons} photons: noise {n}");
        // The noise is part of what every row's error measures.
        assert!(
            n < row["rel_l1_64"].as_f64().unwrap(),
            "{photons}: noise {n} above the row's error {}",
            row["rel_l1_64"]
        );
        let table = std::fs::read_to_string(&md).unwrap();
        assert!(
            table.contains(&format!(
                "Reference noise, rel-L1 64² (half the difference of the reference's two halves): sphere {:.4}%",
                100.0 * n
            )),
            "{table}"
        );
        assert!(
            table.contains(
                "Errors (rel-L1, flux ratio, peak offset) are against the CPU reference of light refracted exactly twice"
            ),
            "the report names its reference first:\n{table}"
        );
        // 64×64 images carry no 256² comparison: the column is empty, not a filtered-up number.
        assert!(row["rel_l1_256"].is_null(), "{row}");
        noise.push(n);
    }
    let ratio = noise[0] / noise[1];
    assert!((1.6..=2.5).contains(&ratio), "noise {noise:?}: ratio {ratio} for 4x the photons");
}

#[test]
fn bench_json_args_are_structured_and_missing_values_print_as_dashes() {
    let dir = out_dir("cli_bench");
    let (o, json, md) = small_bench(
        &dir,
        "b",
        &[
            "--no-reference",
            "--methods",
            "dense,flux-error,max-level",
            "--target-errors",
            "0.001,0.01",
            "--gbuffer-res",
            "256",
            "--caustic-res",
            "256",
            "--check-level",
            "1",
            "--traverse-wg",
            "4,8",
        ],
    );
    let e = stderr_of(&o);
    assert!(o.status.success(), "{e}");
    let doc = read_json(&json);
    assert!(doc["args"].is_object(), "args: {}", doc["args"]);
    assert_eq!(doc["args"]["check_level"], 1);
    assert_eq!(doc["args"]["levels"], "1");
    // The bench scores against every light path unless told otherwise.
    assert_eq!(doc["args"]["paths"], "all");
    // Flux-error rows: one per target error, with its tau and, max-level having run too (after them), the error
    // merging added over max-level's image.
    let rows = doc["rows"].as_array().unwrap();
    for target in [0.001, 0.01] {
        let label = format!("flux-error@{target}");
        let row = rows.iter().find(|r| r["metric"] == label.as_str()).unwrap_or_else(|| panic!("no {label} row"));
        assert_eq!(row["extra"]["target_error"].as_f64().unwrap() as f32, target as f32, "{row}");
        assert!(row["extra"]["tau"].as_f64().unwrap() > 0.0, "{row}");
        assert!(row["extra"]["added_rel_l1_64"].as_f64().unwrap() <= target, "{row}");
    }
    let table = std::fs::read_to_string(&md).unwrap();
    assert!(!table.contains("NaN") && !table.contains("-0.0"), "{table}");
    assert!(table.contains("| wg |") && table.contains("| 4x4 |") && table.contains("| 8x8 |"), "{table}");
    assert!(!e.contains("NaN"), "{e}");
}

#[test]
fn render_and_reference_write_exr_metadata_and_compare_checks_it() {
    let dir = out_dir("cli_exr_meta");
    let common = ["--size", "64x64", "--level", "1", "--aov", "caustics"];
    let (_, top) = render(&dir, "top", SPHERE, &[&["--camera", "top"][..], &common].concat());
    let (_, main) = render(&dir, "main", SPHERE, &[&["--camera", "main"][..], &common].concat());
    let reference = dir.join("ref.exr");
    ok(&[
        "reference",
        "--camera",
        "top",
        "--size",
        "64x64",
        "--photons",
        "20000",
        "--out",
        reference.to_str().unwrap(),
    ]);
    let (_, m) = caustics::image_io::read_exr_meta(&top).unwrap();
    assert_eq!(m["camera"], "top");
    assert_eq!(m["camera_kind"], "orthographic");
    assert_eq!(m["aov"], "caustics");
    assert_eq!(m["units"], "W/m^2");
    assert_eq!(m["transport"], "exact", "the default transport");
    assert_eq!(m["level"], "1");
    assert_eq!(m["scene_hash"].len(), 16);
    let (_, r) = caustics::image_io::read_exr_meta(&reference).unwrap();
    assert_eq!((r["camera"].as_str(), r["transport"].as_str()), ("top", "reference"));
    assert_eq!(r["scene_hash"], m["scene_hash"]);
    let o = caustics(&["compare", top.to_str().unwrap(), reference.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr_of(&o));
    assert!(!stderr_of(&o).contains("warning"), "{}", stderr_of(&o));
    // A perspective render against the orthographic reference: refused.
    let o = caustics(&["compare", main.to_str().unwrap(), reference.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr_of(&o));
    assert!(stderr_of(&o).contains("camera `main`"), "{}", stderr_of(&o));
}

/// `profile`'s table under exact transport ends with the bounce waves in two lines, each wave's median ms and its
/// rays (from wave 1; wave 0 is `transport_primary`), the empty waves at the end in one sum. The rays fall from
/// wave to wave after the first few (sphere, level 1: 19,301 at wave 1, 3 at wave 20).
#[test]
fn profile_prints_the_waves_with_their_rays() {
    let out = caustics(&["profile", "--transport", "exact", "--level", "1", "--frames", "1", "--warmup", "0"]);
    assert!(out.status.success(), "{}", stderr_of(&out));
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let lines: Vec<&str> = text.lines().collect();
    let at = lines.iter().position(|l| l.starts_with("  transport_bounces waves 1-")).expect("the waves' line");
    let numbers = |l: &str| -> Vec<f64> { l.split_whitespace().map(|x| x.parse().unwrap()).collect() };
    let ms = numbers(lines[at + 1]);
    assert_eq!(lines[at + 2], "  rays:", "{text}");
    let rays = numbers(lines[at + 3]);
    assert_eq!(ms.len(), rays.len(), "{text}");
    assert!(rays.len() >= 4 && rays.iter().all(|&n| n > 0.0), "{text}");
    assert!(rays[rays.len() - 1] < rays[1], "the waves thin out: {rays:?}");
    assert!(!text.contains("transport_bounces.wave_"), "no line per wave: {text}");
}

/// `profile --plot` writes its SVG report: a bar per timed frame with a rectangle per stage it ran, and a legend
/// line per stage with the median that `--json` reports for it.
#[test]
fn profile_plots_each_frame_s_stages() {
    let dir = out_dir("cli_profile_plot");
    let svg = dir.join("profile.svg");
    let args = ["profile", "--level", "1", "--frames", "3", "--warmup", "0", "--size", "64x64", "--json"];
    let out = caustics(&[&args[..], &["--plot", svg.to_str().unwrap()]].concat());
    assert!(out.status.success(), "{}", stderr_of(&out));
    let stats: serde_json::Value = serde_json::from_slice(&out.stdout).expect("profile --json");
    let text = std::fs::read_to_string(&svg).expect("the report");
    let stages: Vec<(&String, f64)> = stats["gpu_ms"]
        .as_object()
        .unwrap()
        .iter()
        .filter(|(k, _)| !["gpu_total", "frame_wall", "cpu_record"].contains(&k.as_str()))
        .map(|(k, v)| (k, v["median"].as_f64().unwrap()))
        .collect();
    assert!(stages.len() >= 5, "{}", stats["gpu_ms"]);
    for (stage, median) in &stages {
        let line = format!("{stage}  {median:.2} ms");
        assert!(text.contains(&line), "no legend line `{line}` in the report");
    }
    // Each frame ran every stage (profile reuses nothing): a rectangle each, and one a legend entry.
    let rects = text.matches("<rect").count();
    assert!(rects >= 4 * stages.len(), "{rects} rectangles for {} stages over 3 frames", stages.len());
}

/// `render --accumulate`: N photon sets (or seconds), averaged into the written picture; its stats say how many.
/// A count of 0, a malformed value, or a combination with --frames or --no-reuse exits 2 before any output.
#[test]
fn accumulate_averages_photon_sets_and_checks_its_value() {
    let dir = out_dir("cli_accumulate");
    for (args, needle) in [
        (vec!["--accumulate", "0"], "give a number of photon sets"),
        (vec!["--accumulate", "5x"], "give a number of photon sets"),
        (vec!["--accumulate", "-3s"], "give a number of photon sets"),
        (vec!["--accumulate", "3", "--frames", "2"], "--accumulate averages photon sets"),
        (vec!["--accumulate", "3", "--no-reuse"], "--accumulate averages photon sets"),
    ] {
        let e = render_refused(&dir, &args);
        assert!(e.contains(needle), "{args:?}: {e}");
    }
    let (out, stats) = (dir.join("c.exr"), dir.join("c.json"));
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/sphere.toml");
    let o = caustics(&[
        "render",
        "--scene",
        scene,
        "--camera",
        "top",
        "--aov",
        "caustics",
        "--size",
        "32x32",
        "--level",
        "0",
        "--accumulate",
        "3",
        "--out",
        out.to_str().unwrap(),
        "--stats",
        stats.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr_of(&o));
    assert!(stderr_of(&o).contains("averaged 3 photon sets"), "{}", stderr_of(&o));
    let v = read_json(&stats);
    assert_eq!((v["photon_sets"].as_u64(), v["frames"].as_u64()), (Some(3), Some(3)), "{v}");
}

//! caustics as another crate's dependency, built from its package alone:
//!
//! 1. `cargo package` packs the crate (what a registry would get);
//! 2. the `.crate` is unpacked into a directory outside this repository, where this repository's
//!    `.cargo/config.toml`, if any, does not apply: only the user's cargo configuration does (tools/setup adds the
//!    shaderc link fix to it);
//! 3. a new crate beside it depends on it by path with `default-features = false`: its `main` is the README's
//!    library snippet, word for word, and its second binary is the package's own `examples/headless.rs`;
//! 4. both run on lavapipe with validation on. The snippet's frame must hold the photons that the same frame
//!    rendered here in-process holds, and the example must write its images;
//! 5. the package's API docs build with warnings denied.
//!
//! The build goes to target/dependent (not this test's own target directory, which the running `cargo test` holds
//! locked): the first run builds every dependency again, about 3 minutes on two cores.

mod common;
use std::path::{Path, PathBuf};
use std::process::Command;

const README_SNIPPET: &str = "<!-- library-snippet -->";

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Run `cmd`, failing the test with its output when it fails; returns stdout.
fn run(cmd: &mut Command, what: &str) -> String {
    let out = cmd.output().unwrap_or_else(|e| panic!("{what}: cannot start: {e}"));
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{what} failed ({:?}):\n{text}", out.status.code());
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The README's library snippet: the ```rust block after the marker.
fn readme_snippet() -> String {
    let readme = std::fs::read_to_string(repo().join("README.md")).expect("README.md");
    let after = readme.split_once(README_SNIPPET).map(|(_, a)| a).expect("the README's library-snippet marker");
    let block = after.split_once("```rust\n").map(|(_, b)| b).expect("a ```rust block after the marker");
    block.split_once("```").map(|(code, _)| code.to_string()).expect("the block's end")
}

/// A scratch directory outside the repository (and outside any directory with a .cargo/config.toml of ours).
fn scratch() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("caustics-dependent-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch directory");
    assert!(!dir.starts_with(repo()), "{} is inside the repository", dir.display());
    dir
}

/// `cargo package` the crate, unpack it into `into`, and return the unpacked directory.
fn package(target: &Path, into: &Path) -> PathBuf {
    let cargo = env!("CARGO");
    run(
        Command::new(cargo)
            .current_dir(repo())
            .args(["package", "--no-verify", "--allow-dirty", "--offline", "--target-dir"])
            .arg(target),
        "cargo package",
    );
    let name = format!("caustics-{}", env!("CARGO_PKG_VERSION"));
    let crate_file = target.join("package").join(format!("{name}.crate"));
    // `-m`: the files take the time of unpacking. The .crate gives every file one fixed old date, and cargo, which
    // judges a path dependency's freshness by file times, would reuse the last run's build script in this target
    // directory whatever the package now holds.
    run(Command::new("tar").arg("-xzmf").arg(&crate_file).arg("-C").arg(into), "unpack the .crate");
    let unpacked = into.join(&name);
    assert!(unpacked.join("Cargo.toml").is_file(), "{} holds no Cargo.toml", unpacked.display());
    unpacked
}

#[test]
fn a_crate_that_depends_on_the_package_builds_and_renders() {
    let target = repo().join("target").join("dependent");
    let dir = scratch();
    let package = package(&target, &dir);

    // The dependent crate: the README's snippet as its main, the package's headless example as a second binary.
    let app = dir.join("app");
    std::fs::create_dir_all(app.join("src/bin")).expect("app/src/bin");
    let manifest = format!(
        "[package]\nname = \"app\"\nversion = \"0.1.0\"\nedition = \"2021\"\npublish = false\n\n[dependencies]\n\
         caustics = {{ path = \"{}\", default-features = false }}\n",
        package.display()
    );
    std::fs::write(app.join("Cargo.toml"), manifest).expect("app/Cargo.toml");
    // The versions this repository is tested with (and no registry query).
    std::fs::copy(repo().join("Cargo.lock"), app.join("Cargo.lock")).expect("Cargo.lock");
    let main = format!(
        "fn main() -> Result<(), caustics::Error> {{\n{}println!(\"photons {{}}\", frame.report.photons());\nOk(())\n}}\n",
        readme_snippet()
    );
    std::fs::write(app.join("src/main.rs"), main).expect("app/src/main.rs");
    std::fs::copy(package.join("examples/headless.rs"), app.join("src/bin/headless.rs")).expect("headless.rs");

    run(
        Command::new(env!("CARGO"))
            .current_dir(&app)
            .args(["build", "--offline", "--bins", "--target-dir"])
            .arg(&target)
            // Cargo's own variables of this test's build would leak into the scratch crate's.
            .env_remove("CARGO_MANIFEST_DIR")
            .env_remove("CARGO_PKG_VERSION"),
        "cargo build of the dependent crate",
    );
    let bin = |name: &str| {
        let mut c = Command::new(target.join("debug").join(name));
        c.env("CAUSTICS_VALIDATION", "1").env("RUST_LOG", "warn");
        c
    };
    // The snippet loads assets/scenes/sphere.toml relative to its working directory: the package's.
    let out = run(bin("app").current_dir(&package), "the README's snippet");
    let photons: u64 = out
        .lines()
        .find_map(|l| l.strip_prefix("photons "))
        .and_then(|n| n.trim().parse().ok())
        .unwrap_or_else(|| panic!("no photon count in {out:?}"));

    // The same frame in-process.
    let (_lock, device) = common::gpu();
    let mut renderer = common::renderer(&device, &common::scene("sphere.toml"), Default::default());
    let scene = caustics::scene::Scene::load(Path::new(&common::scene("sphere.toml"))).expect("scene");
    let camera = scene.camera(Some("top")).expect("top camera").clone();
    let view = renderer.camera_view(&camera, 256, 256);
    let frame = renderer.render(&caustics::FrameDesc::new(&view, Some(caustics::Aov::Caustics))).expect("frame");
    assert!(photons > 0);
    assert_eq!(photons, frame.report.photons(), "the snippet's frame against the same frame here");

    let images = dir.join("headless-out");
    let scene_path = package.join("assets/scenes/sphere.toml");
    let out = run(bin("headless").arg(&scene_path).arg(&images), "the package's headless example");
    assert!(out.contains("photons"), "{out}");
    for f in ["caustics.exr", "beauty.png"] {
        assert!(images.join(f).is_file(), "the example wrote no {f}: {out}");
    }

    // The package's API docs build without a warning.
    run(
        Command::new(env!("CARGO"))
            .current_dir(&package)
            .args(["doc", "--no-deps", "--lib", "--no-default-features", "--offline", "--target-dir"])
            .arg(&target)
            .env("RUSTDOCFLAGS", "-D warnings"),
        "cargo doc of the package",
    );
    let _ = std::fs::remove_dir_all(&dir);
}

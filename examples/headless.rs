//! Render a scene headless and write its caustics (an OpenEXR of irradiance in W/m²) and its beauty image (PNG).
//!
//! ```sh
//! cargo run --release --example headless -- [SCENE.toml|.gltf] [OUT_DIR]
//! ```
//!
//! The device comes from the environment as the CLI's does (`CAUSTICS_DEVICE`, `CAUSTICS_VALIDATION`).

use caustics::image_io::{self, RgbImage};
use caustics::scene::Scene;
use caustics::settings::Settings;
use caustics::{gpu, Aov, AovData, FrameDesc, Renderer};
use std::path::PathBuf;

fn main() -> Result<(), caustics::Error> {
    let mut args = std::env::args().skip(1);
    let scene_path = PathBuf::from(
        args.next().unwrap_or_else(|| concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/sphere.toml").into()),
    );
    let out_dir = PathBuf::from(args.next().unwrap_or_else(|| "target/headless-example".into()));
    std::fs::create_dir_all(&out_dir).map_err(|e| caustics::Error::Io(format!("{}: {e}", out_dir.display())))?;

    // A device of our own (the renderer can also import a host's: see examples/embed.rs).
    let context = gpu::Context::headless(&gpu::ContextDesc::from_env())?;
    let scene = Scene::load(&scene_path)?;
    let top = scene.camera(Some("top")).map_err(caustics::Error::BadInput)?.clone();
    let main = scene.camera(None).map_err(caustics::Error::BadInput)?.clone();
    let mut renderer = Renderer::new(context.device, scene, Settings::default())?;

    // The caustics seen from the orthographic `top` camera: irradiance on the floor, W/m².
    let view = renderer.camera_view(&top, 256, 256);
    let frame = renderer.render(&FrameDesc::new(&view, Some(Aov::Caustics)))?;
    if let Some(AovData::Float { width, height, rgba }) = frame.image {
        let img = RgbImage { width, height, data: rgba.iter().map(|p| [p[0], p[1], p[2]]).collect() };
        let pixel_area = (2.0 / width as f64) * (2.0 / height as f64);
        let flux: f64 = img.data.iter().map(|p| p[0] as f64).sum::<f64>() * pixel_area;
        image_io::write_exr(&out_dir.join("caustics.exr"), &img)?;
        println!(
            "caustics: {} photons, {:.1} ms on the GPU, {flux:.4} W on the floor -> {}",
            frame.report.photons(),
            frame.report.gpu_ms,
            out_dir.join("caustics.exr").display()
        );
    }

    // The beauty image from the scene's first camera (the caustic maps are reused: only the eye view runs).
    let view = renderer.camera_view(&main, 480, 360);
    let frame = renderer.render(&FrameDesc::new(&view, Some(Aov::Beauty)))?;
    if let Some(AovData::Rgba8 { width, height, rgba }) = frame.image {
        image_io::write_png(&out_dir.join("beauty.png"), width, height, &rgba)?;
        println!(
            "beauty: {:.1} ms on the GPU (caustics reused: {}) -> {}",
            frame.report.gpu_ms,
            frame.report.reused,
            out_dir.join("beauty.png").display()
        );
    }
    let messages = gpu::validation_message_count();
    if messages > 0 {
        return Err(caustics::Error::Failed(format!("{messages} Vulkan validation messages")));
    }
    Ok(())
}

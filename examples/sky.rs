//! Write the project's own environment map, `assets/environments/sky.hdr` (CC0): the procedural sky of
//! `EnvironmentMap::procedural_sky` (a gradient with a sun, distant hills and a tiled ground), 1024 × 512.
//!
//! ```text
//! cargo run --release --example sky [-- OUT.hdr [WIDTH]]
//! ```

fn main() {
    let mut args = std::env::args().skip(1);
    let out = args.next().unwrap_or_else(|| "assets/environments/sky.hdr".into());
    let width = match args.next().map(|w| w.parse::<u32>()) {
        None => 1024,
        Some(Ok(w)) if (8..=8192).contains(&w) => w,
        Some(_) => {
            eprintln!("sky: WIDTH must be a whole number in 8..=8192");
            std::process::exit(2);
        }
    };
    let map = caustics::scene::EnvironmentMap::procedural_sky(width);
    if let Some(dir) = std::path::Path::new(&out).parent() {
        let _ = std::fs::create_dir_all(dir);
    }
    if let Err(e) = map.write_hdr(std::path::Path::new(&out)) {
        eprintln!("sky: {e}");
        std::process::exit(1);
    }
    println!("wrote {out} ({}x{})", map.width, map.height);
}

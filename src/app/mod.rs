//! The command-line applications on the library's public API: `render` and `profile` (commands/), `reference`,
//! `compare`, `bench` (with its report), `view` (the windowed viewer), `temporal` and the hidden `soak`.

pub mod bench;
pub mod bench_report;
pub mod commands;
pub mod compare;
pub mod flags;
pub mod heap;
pub mod profiler;
pub mod reference_cmd;
pub mod soak;
pub mod temporal;
pub mod viewer;

/// A progress bar on stderr: the bar `make` makes, styled by `template`, where stderr is a terminal; else a hidden
/// one.
pub fn stderr_bar(make: impl FnOnce() -> indicatif::ProgressBar, template: &str) -> indicatif::ProgressBar {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = make();
    if let Ok(style) = indicatif::ProgressStyle::with_template(template) {
        bar.set_style(style);
    }
    bar
}

/// A light's orbit, as `temporal` and `soak` move the scene's first light: around the vertical through its target,
/// at its distance, tilted 25° first when it stands straight above (so that the orbit moves it).
pub struct LightOrbit {
    target: glam::Vec3,
    arm: glam::Vec3,
}

impl LightOrbit {
    pub fn of(light: &caustics::scene::Light) -> Self {
        let mut arm = light.position - light.target;
        if arm.normalize().dot(glam::Vec3::Y).abs() > 0.99 {
            arm = glam::Quat::from_rotation_z(-25f32.to_radians()) * arm;
        }
        LightOrbit { target: light.target, arm }
    }

    /// The light's position at `angle` (radians) along the orbit.
    pub fn at(&self, angle: f32) -> glam::Vec3 {
        self.target + glam::Quat::from_rotation_y(angle) * self.arm
    }
}

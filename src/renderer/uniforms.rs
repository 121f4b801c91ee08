//! The uniforms of one pass (`FrameData`, src/gpu_types.rs): its light's views and power, the camera, the settings the
//! shaders read, and the exposure.

use super::{Emitter, Views};
use crate::gpu_types::{FrameData, FrameUniforms, GpuView, LightUniforms, PassUniforms};
use crate::scene::view::{CameraView, LightView};
use crate::scene::Projection;
use crate::scene::{LightKind, Material, Scene};
use crate::scene_gpu::SceneBuffers;
use crate::settings::{CarriedColor, Footprint, ResolvedSettings, Transport};
use crate::shaders::consts::*;
use crate::targets::Targets;
use glam::Vec3;

/// The uniforms of every pass, light-view-major: `nc` color passes per light view (`views` per emitter).
pub(crate) fn pass_data(
    scene: &Scene,
    scene_buffers: &SceneBuffers,
    s: &ResolvedSettings,
    emitters: &[Emitter],
    views: &[Views],
    targets: &Targets,
    nc: usize,
) -> Vec<FrameData> {
    // One gray pass, one pass of color photons, or a pass per channel.
    let channel = |c: usize| match (s.carried_color, nc) {
        (CarriedColor::Wavelength, _) => CHANNEL_SPECTRAL,
        (CarriedColor::Tint, _) => CHANNEL_RGB,
        (CarriedColor::None, 1) => 0,
        _ => c as u32 + 1,
    };
    (0..views.len() * nc)
        .map(|p| {
            let v = p / nc;
            let mut d = frame_data(scene, scene_buffers, s, &views[v], targets, emitters[v].light, channel(p % nc));
            // The environment's light is added once, by the frame's first light view.
            if v > 0 {
                d.pass.sky = 0.0;
            }
            d
        })
        .collect()
}

/// The uniforms of one pass: a view of light `index` (its views and power; the exposure follows the first light)
/// and color `channel` (0: one gray pass; 1, 2, 3: red, green, blue; CHANNEL_RGB: color photons; CHANNEL_SPECTRAL:
/// spectral photons).
pub(crate) fn frame_data(
    scene: &Scene,
    scene_buffers: &SceneBuffers,
    s: &ResolvedSettings,
    views: &Views,
    targets: &Targets,
    index: usize,
    channel: u32,
) -> FrameData {
    let light = &scene.lights[index];
    let light0 = &scene.lights[0];
    let (lo, hi) = scene.bounds();
    let (rlo, rhi) = scene
        .refractors()
        .map(|o| o.mesh.bounds())
        .fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(a, b), (c, d)| (a.min(c), b.max(d)));
    let diameter = if scene.has_refractors() { (rhi - rlo).length() } else { 0.0 };
    let power = light.color * light.intensity;
    // Exposure: the diffuse radiance of the brightest albedo under the light at its target maps to ~0.6.
    let e_ref = match light0.kind {
        LightKind::Spot | LightKind::Point => light0.intensity / (light0.target - light0.position).length_squared(),
        LightKind::Directional => light0.intensity,
    } * light0.color.max_element().max(1e-6);
    let albedo = scene
        .receivers()
        .map(|o| match o.material {
            Material::Diffuse { albedo, .. } => albedo.max_element(),
            _ => 0.0,
        })
        .fold(0.0f32, f32::max)
        .max(0.05);
    let l_ref = (albedo / std::f32::consts::PI * e_ref).max(1e-12);
    let mut pyramid = [[0u32; 4]; (MAX_PYRAMID_MIPS / 4) as usize];
    for (m, off) in targets.photon.pyramid_offsets.iter().enumerate() {
        pyramid[m / 4][m % 4] = *off;
    }
    let photon_view = views.photon.unwrap_or(views.receiver);
    // With a map, the radiance per map unit: `--sky` when given, else the scene's intensity.
    let sky = match &scene.environment {
        Some(e) => s.sky.unwrap_or(e.intensity),
        None => s.sky.unwrap_or(crate::settings::SKY_AUTO * l_ref),
    };
    // The eye buffers hold `aa`×`aa` samples per output pixel: the same image plane, a finer grid.
    let mut camera = GpuView::from_camera(&views.camera);
    let aa = targets.aa as f32;
    camera.extent = [camera.extent[0] * aa, camera.extent[1] * aa, camera.extent[2] / aa, camera.extent[3] / aa];
    let light_spectrum = match channel {
        CHANNEL_SPECTRAL => crate::spectrum::RgbSpectrum::fit_f32(light.color.to_array()).coeffs_f32(),
        _ => [0.0; 3],
    };
    let frame = FrameUniforms {
        camera,
        scene_min: lo.to_array(),
        refractor_diameter: diameter,
        scene_max: hi.to_array(),
        exposure: 0.6 / l_ref * s.exposure_ev.exp2(),
        pyramid,
        gbuffer_res: s.gbuffer_side(),
        gbuffer_level: s.gbuffer_level(),
        caustic_res: s.caustic_res,
        max_level: s.level,
        batching: s.batching as u32,
        check_level: s.check_level,
        batch_photons: s.batch_photons(targets.photon.capacity),
        exact: (s.transport == Transport::Exact) as u32,
        queue_rays: s.ray_queue_capacity(),
        record_capacity: targets.photon.capacity,
        differential: (s.footprint == Footprint::Differential) as u32,
        error_bound: s.error_bound,
        shadow_bias: s.shadow_bias,
        flux_threshold: s.flux_threshold,
        tau: s.tau,
        eye_depth: s.eye_depth as f32,
        disperses: scene.disperses() as u32 as f32,
        environment: scene.environment.is_some() as u32 as f32,
        shared_ior: scene_buffers.shared_ior.unwrap_or(0.0),
        weak_fraction: s.weak_branches,
        weak_block: s.weak_block as f32,
        eye_deposit: targets.eye_deposit(s) as u32,
        sample_index: 0,
        refine: s.refine.code(),
    };
    // Where a light with size aims each cell's rays: through the cell at the glass's middle, along the axis (a
    // beam) or from the light (a sphere).
    let to_glass = 0.5 * (rlo + rhi) - photon_view.origin;
    let pivot = match light.kind {
        LightKind::Directional => to_glass.dot(photon_view.forward),
        _ => to_glass.length(),
    };
    let pivot = if pivot.is_finite() { pivot.max(0.0) } else { 0.0 };
    let light = LightUniforms {
        photon_view: GpuView::from_light(&photon_view, s.gbuffer_side()),
        receiver_view: GpuView::from_light(&views.receiver, s.caustic_res),
        light_power: power.to_array(),
        light_intensity: light.intensity,
        light_spectrum_c0: light_spectrum[0],
        light_spectrum_c1: light_spectrum[1],
        light_spectrum_c2: light_spectrum[2],
        beam_spread: match light.kind {
            LightKind::Directional => light.angular_radius.tan(),
            _ => light.radius / pivot.max(light.radius).max(1e-6),
        },
        beam_pivot: pivot,
        light_radius: if light.kind == LightKind::Directional { 0.0 } else { light.radius },
        pad1: 0,
        pad2: 0,
    };
    // The environment's light is added once: by the first light's eye shading (and the composite, which reads the
    // first pass's uniforms).
    let pass = PassUniforms { channel, sky: if index == 0 { sky } else { 0.0 }, pad: [0; 2] };
    FrameData { frame, light, pass }
}

// How the scene's views fill the GPU's (src/gpu_types.rs holds only the data).

fn v4(v: Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

fn extent(w: u32, h: u32) -> [f32; 4] {
    [w as f32, h as f32, 1.0 / w as f32, 1.0 / h as f32]
}

impl GpuView {
    pub fn from_light(v: &LightView, resolution: u32) -> Self {
        let (ortho, domain) = v.emitter_kind().lanes(v.cos_cone);
        GpuView {
            view_proj: v.view_proj().to_cols_array(),
            origin: v4(v.origin, ortho),
            right: v4(v.right, domain),
            down: v4(v.down, v.near),
            forward: v4(v.forward, v.far),
            window: [v.window.x0, v.window.y0, v.window.w, v.window.w],
            extent: extent(resolution, resolution),
        }
    }

    pub fn from_camera(c: &CameraView) -> Self {
        let h = c.half_extents();
        let ortho = matches!(c.projection, Projection::Orthographic { .. });
        GpuView {
            view_proj: c.view_proj().to_cols_array(),
            origin: v4(c.position, if ortho { 1.0 } else { 0.0 }),
            right: v4(c.right, -1.0),
            down: v4(-c.up, c.near),
            forward: v4(c.forward, c.far),
            window: [-h.x, -h.y, 2.0 * h.x, 2.0 * h.y],
            extent: extent(c.width, c.height),
        }
    }
}

/// A progressive accumulation's photon set `set` (0: a new average) in every pass's uniforms.
pub(super) fn set_photon_set(data: &mut [FrameData], set: u32) {
    for d in data {
        d.frame.sample_index = set;
    }
}

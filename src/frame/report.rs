//! What a frame reports once it has completed: its GPU timings, its traversal and transport state, and the AOV
//! it read back.

use crate::error::{Error, Result};
use crate::gpu_types::{TransportState, TraversalState};
use crate::scene::view::LightView;
use crate::settings::{Method, ResolvedSettings, Transport};
use crate::targets::{Targets, CANARY, PHOTON_GUARD};
use crate::vk::Buffer;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
/// An output of a frame.
pub enum Aov {
    /// The tone-mapped beauty image (8-bit, sRGB-encoded), written as PNG.
    Beauty,
    /// The beauty image before exposure and tone mapping: linear radiance, W/(m²·sr) (written as EXR).
    BeautyHdr,
    /// Caustic irradiance on the receivers, W/m² (RGB: the lights' colors).
    Caustics,
    /// Direct irradiance on the receivers, W/m².
    Direct,
}

impl std::str::FromStr for Aov {
    type Err = Error;
    fn from_str(s: &str) -> Result<Aov> {
        match s {
            "beauty" => Ok(Aov::Beauty),
            "caustics" => Ok(Aov::Caustics),
            "direct" => Ok(Aov::Direct),
            _ => Err(Error::BadInput(format!("AOV `{s}`: expected beauty, caustics or direct"))),
        }
    }
}

/// One pass of a frame: one light, in one color channel (or the only, gray one).
#[derive(Clone, Debug, Default)]
pub struct LightReport {
    /// The light's index in the scene.
    pub light: usize,
    /// Its cube face, for a point light with a view per face (docs/design.md "Lights that shine every way").
    pub face: Option<u8>,
    /// 0: the gray pass; 1, 2, 3: red, green, blue; `CHANNEL_RGB`, `CHANNEL_SPECTRAL`: photons that carry their
    /// color or a wavelength ([`LightReport::channel_name`]).
    pub channel: u32,
    /// Whether this light's caustic stages ran (a refractor lies in its light).
    pub caustics: bool,
    /// Its traversal state and exact transport's account (kept from the last frame when reused).
    pub state: Option<TraversalState>,
    /// Its exact transport's wave counts and energy account.
    pub transport: Option<TransportState>,
    /// GPU ms of its light-side stages (light view, coverage, photons, resolve); its eye shading is in `eye`.
    pub gpu_ms: f64,
    /// Index of its first timed interval in the frame's segments.
    pub first_segment: usize,
}

impl LightReport {
    /// The pass's channel in words: `gray`, `red`, `green`, `blue`, `rgb` (photons that carry their color) or
    /// `spectral` (photons that carry a wavelength).
    pub fn channel_name(&self) -> &'static str {
        // CHANNEL_RGB, CHANNEL_SPECTRAL after the three channels.
        ["gray", "red", "green", "blue", "rgb", "spectral"][self.channel.min(5) as usize]
    }
}

/// One photon of a debug run's dump (`Tuning::debug_photons`), decoded from its `GpuDebugPhoton`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DebugPhoton {
    /// Its cell's column at its level.
    pub x: u32,
    /// Its cell's row at its level.
    pub y: u32,
    /// Its level.
    pub level: u32,
    /// Its status code.
    pub status: u32,
    /// Its splat radius (texels).
    pub radius: u32,
    /// Its flux's first channel.
    pub flux_r: f32,
    /// The cell center's light-view texture coordinates, as the GPU computed them.
    pub uv: [f32; 2],
    /// Where it lands in the caustic map (texels).
    pub map_px: [f32; 2],
    /// Where it landed (m, world space).
    pub hit: [f32; 3],
}

/// A frame's scene update: the objects it moved on the GPU, and what the host did to the scene's buffers before it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SceneUpdateReport {
    /// Objects whose vertices the frame's scene update placed (rigid moves since the last frame).
    pub moved_objects: u32,
    /// Bytes of BVH instance records the frame's commands wrote (its transforms and world bounds).
    pub instance_bytes: u64,
    /// Bottom-level BVHs built for this frame (on the host: a new mesh, or the BVH's first frame).
    pub blas_builds: u32,
    /// Bottom-level BVHs refit on the GPU in this frame (deforming meshes; rigid motion needs none).
    pub blas_refits: u32,
    /// Water objects the frame displaced to its time.
    pub deformed_objects: u32,
    /// The scene's buffers were rebuilt and uploaded before this frame (an object or a material was added or
    /// changed, or a new scene was set).
    pub rebuilt: bool,
    /// Uploads and other submissions the host waited for while preparing this frame.
    pub blocking_submits: u64,
    /// `vkDeviceWaitIdle` calls while preparing this frame.
    pub wait_idles: u64,
}

impl SceneUpdateReport {
    /// Count `next`'s work in with this one's (a frame's further submissions; several frames' totals).
    pub fn add(&mut self, next: &SceneUpdateReport) {
        self.moved_objects += next.moved_objects;
        self.instance_bytes += next.instance_bytes;
        self.blas_builds += next.blas_builds;
        self.blas_refits += next.blas_refits;
        self.deformed_objects += next.deformed_objects;
        self.rebuilt |= next.rebuilt;
        self.blocking_submits += next.blocking_submits;
        self.wait_idles += next.wait_idles;
    }
}

/// What one frame did, read back after it completed.
#[derive(Clone, Debug, Default)]
pub struct FrameReport {
    /// GPU milliseconds per stage, in order (intervals with the same label summed).
    pub stages: Vec<(&'static str, f64)>,
    /// GPU milliseconds of the parts of a stage timed on their own (`light_gbuffer.front`, ...), in order.
    pub substages: Vec<(&'static str, f64)>,
    /// Every timed interval: (label, start ms from the frame's first timestamp, duration ms).
    pub segments: Vec<(&'static str, f64, f64)>,
    /// The frame's first timestamp in the device's ticks (its clock, masked to the queue's valid bits): where
    /// `segments` start on the GPU's clock (the Tracy zones place them there).
    pub gpu_start_tick: Option<u64>,
    /// Sum of the stages (excluding host round trips of the CPU-driven traversal).
    pub gpu_ms: f64,
    /// Wall-clock time from the start of recording until the results were available.
    pub frame_ms: f64,
    /// CPU time spent recording commands.
    pub record_ms: f64,
    /// Pipeline barriers (`vkCmdPipelineBarrier2` calls) the frame's declared accesses needed.
    pub barrier_batches: u64,
    /// Further submissions that traced the tiles the first one's batch slots left (see [`crate::Renderer::render`]).
    pub continuations: u32,
    /// Whether the caustic passes were recorded (the scene has a refractor inside the light).
    pub caustics: bool,
    /// Whether the records were splatted by the compute pass (else drawn as points).
    pub compute_splat: bool,
    /// The light-view stages, the photons and the caustic map were reused from the last frame (nothing they
    /// depend on changed); only the eye and composite passes ran.
    pub reused: bool,
    /// The photon sets the frame's caustic maps average (progressive accumulation,
    /// [`crate::Renderer::set_accumulation`]): 1 for a frame that traced afresh, k + 1 for one that added the k-th
    /// set of unchanged inputs, and the count its maps hold for a frame that reused them.
    pub photon_sets: u32,
    /// The photon level this frame rendered (below the chosen one while the viewer refines progressively).
    pub level: u32,
    /// A viewer preview: one eye sample per pixel (glass traced as in a still under exact transport).
    pub preview: bool,
    /// Nothing the eye view depends on changed since the last frame (camera, lights, settings, the caustic map):
    /// its beauty image was presented again, and no eye or composite pass was recorded.
    pub eye_reused: bool,
    /// The light view of the photon grid (None without caustic passes).
    pub photon_view: Option<LightView>,
    /// The first pass's traversal state (photons, batches, per-level counts).
    pub state: Option<TraversalState>,
    /// Exact transport's wave counts and energy account.
    pub transport: Option<TransportState>,
    /// Host round trips inside the frame (0 when GPU-driven; the CPU-driven baseline reads each level back).
    pub host_readbacks: u32,
    /// What changed in the scene before this frame, and what it cost the host.
    pub scene: SceneUpdateReport,
    /// Each pass (light-major; one per light, or three with color), in order (`state` and `transport` above are
    /// the first pass's).
    pub lights: Vec<LightReport>,
    /// Batch slots recorded (GPU-driven adaptive) or bands (dense).
    pub batch_slots: u32,
    /// Tiles still pending when the frame ended (GPU-driven batching ran out of slots).
    pub unfinished_tiles: u32,
    /// The debug photon dump, as the GPU wrote it ([`FrameReport::debug_photons`] decodes it).
    pub(crate) debug_rows: Vec<crate::gpu_types::GpuDebugPhoton>,
    /// Debug runs: whether the photon buffer's guard region kept its canary.
    pub guard_intact: Option<bool>,
}

impl FrameReport {
    /// Take in a continuation of this frame (`passes`: the passes it continued): their states, their times and
    /// its stages. The continued passes' states are cumulative (restored, then continued).
    pub(crate) fn absorb(&mut self, next: FrameReport, passes: &[bool]) {
        for ((l, n), &p) in self.lights.iter_mut().zip(&next.lights).zip(passes) {
            if p {
                l.state = n.state;
                l.transport = n.transport;
                l.gpu_ms += n.gpu_ms;
            }
        }
        self.state = self.lights.first().and_then(|l| l.state);
        self.transport = self.lights.first().and_then(|l| l.transport);
        let merge = |into: &mut Vec<(&'static str, f64)>, from: &[(&'static str, f64)]| {
            for &(label, ms) in from {
                match into.iter_mut().find(|(l, _)| *l == label) {
                    Some(e) => e.1 += ms,
                    None => into.push((label, ms)),
                }
            }
        };
        merge(&mut self.stages, &next.stages);
        merge(&mut self.substages, &next.substages);
        let end = self.segments.last().map_or(0.0, |&(_, at, ms)| at + ms);
        self.segments.extend(next.segments.iter().map(|&(l, at, ms)| (l, end + at, ms)));
        self.gpu_ms += next.gpu_ms;
        self.record_ms += next.record_ms;
        self.barrier_batches += next.barrier_batches;
        // The host waited for the first submission and read its states back before recording the next.
        self.host_readbacks += 1 + next.host_readbacks;
        self.batch_slots += next.batch_slots;
        self.unfinished_tiles = next.unfinished_tiles;
        self.continuations += 1 + next.continuations;
        self.eye_reused = false;
        self.scene.add(&next.scene);
        // The debug dump grows across the submissions: the last one's holds every row.
        if next.guard_intact.is_some() {
            self.debug_rows = next.debug_rows;
            self.guard_intact = next.guard_intact;
        }
    }

    /// The photons a debug run dumped (`Tuning::debug_photons`), in the order the GPU wrote them.
    pub fn debug_photons(&self) -> Vec<DebugPhoton> {
        self.debug_rows
            .iter()
            .map(|r| DebugPhoton {
                x: r.x,
                y: r.y,
                level: r.level_status_radius & 0xFF,
                status: (r.level_status_radius >> 8) & 0xFF,
                radius: r.level_status_radius >> 16,
                flux_r: r.flux,
                uv: r.uv,
                map_px: r.map_px,
                hit: [r.hit[0], r.hit[1], r.hit[2]],
            })
            .collect()
    }

    /// Photons the frame emitted, summed over its lights (and color passes).
    pub fn photons(&self) -> u64 {
        self.lights.iter().filter_map(|l| l.state.map(|s| s.photons_total as u64)).sum()
    }
}

/// Whether a frame traversed every tile (see [`crate::Renderer::adapt_batch_slots`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SlotVerdict {
    /// Every tile was traversed.
    Complete,
    /// Tiles were left over; the next frame records more slots.
    Incomplete,
    /// Tiles were left over with the most slots a frame records (`MAX_BATCHES`): raise the photon budget.
    OutOfSlots,
}

/// A float or 8-bit image read back from the GPU.
#[derive(Debug)]
pub enum AovData {
    /// A float image (the caustics, direct and linear beauty AOVs), row-major from the top-left.
    Float {
        /// Its width in pixels.
        width: u32,
        /// Its height in pixels.
        height: u32,
        /// Its pixels.
        rgba: Vec<[f32; 4]>,
    },
    /// An 8-bit RGBA image (the tone-mapped beauty), row-major from the top-left.
    Rgba8 {
        /// Its width in pixels.
        width: u32,
        /// Its height in pixels.
        height: u32,
        /// Its bytes, four per pixel.
        rgba: Vec<u8>,
    },
}

/// Each light's state from the readback buffer (lights that ran their caustic stages this frame).
pub(crate) fn read_results(
    t: &Targets,
    readback: &Buffer,
    s: &ResolvedSettings,
    report: &mut FrameReport,
) -> Result<()> {
    let layout = Targets::readback_layout(s, 16 * t.width as u64 * t.height as u64);
    if report.reused {
        return Ok(());
    }
    for (i, l) in report.lights.iter_mut().enumerate() {
        if !l.caustics {
            continue;
        }
        let i = i as u64;
        let st =
            readback.read::<TraversalState>(layout.state + i * std::mem::size_of::<TraversalState>() as u64, 1)?[0];
        l.state = Some(st);
        if s.transport == Transport::Exact {
            let at = layout.transport + i * std::mem::size_of::<TransportState>() as u64;
            l.transport = Some(readback.read::<TransportState>(at, 1)?[0]);
        }
    }
    if s.method == Method::Adaptive {
        report.unfinished_tiles = report.lights.iter().filter_map(|l| l.state.map(|st| st.stack_size)).sum();
    }
    if report.lights[0].caustics && s.debug_photons > 0 {
        let header = readback.read::<[u32; 4]>(layout.debug, 1)?[0];
        let n = header[0].min(s.debug_photons) as usize;
        report.debug_rows = readback.read::<crate::gpu_types::GpuDebugPhoton>(layout.debug + 16, n)?;
        let guard = readback.read::<u32>(layout.guard, 2 * PHOTON_GUARD as usize)?;
        report.guard_intact = Some(guard.iter().all(|&w| w == CANARY));
    }
    Ok(())
}

pub(crate) fn read_aov(
    t: &Targets,
    readback: &Buffer,
    s: &ResolvedSettings,
    aov: Option<Aov>,
) -> Result<Option<AovData>> {
    let layout = Targets::readback_layout(s, 16 * t.width as u64 * t.height as u64);
    let n = (t.width * t.height) as usize;
    Ok(match aov {
        None => None,
        Some(Aov::Beauty) => {
            Some(AovData::Rgba8 { width: t.width, height: t.height, rgba: readback.read::<u8>(layout.aov, 4 * n)? })
        }
        Some(_) => {
            Some(AovData::Float { width: t.width, height: t.height, rgba: readback.read::<[f32; 4]>(layout.aov, n)? })
        }
    })
}

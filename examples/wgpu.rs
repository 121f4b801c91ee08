//! Caustics in a wgpu application: wgpu, on its Vulkan backend, owns the instance, the device, the queue and the
//! texture; caustics imports the device through wgpu's HAL interop and records each frame into a wgpu command
//! encoder, copying its beauty image into the wgpu texture.
//!
//! ```sh
//! cargo run --release --example wgpu              # a window that shows the texture (wgpu copies it into the
//!                                                 # window's surface), the light orbiting
//! cargo run --release --example wgpu -- --headless [SCENE.toml]
//! ```
//!
//! Headless, it reads the texture back through wgpu and compares it with what `Renderer::render` gives for the same
//! frame on the renderer's own path: they must be the same bytes. With `CAUSTICS_VALIDATION=1`, wgpu turns on the
//! Khronos validation layer (set `VK_LAYER_ENABLES=VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT` for
//! synchronization validation too), and any message it reports fails the run.
//!
//! Who owns what, and how the frames are ordered:
//! - wgpu creates the device, with what caustics needs added by [`wgpu::hal::vulkan::Adapter::open_with_callback`]:
//!   `VK_KHR_push_descriptor`, synchronization2, dynamic rendering and, where offered, `VK_EXT_shader_atomic_float`.
//! - caustics allocates its own buffers and images on that device and frees them when the renderer is dropped,
//!   which must happen before the wgpu device is.
//! - [`Renderer::record`] writes into a wgpu command encoder's Vulkan command buffer. It leaves the texture in the
//!   layout wgpu last left it in, and wgpu does not see the recorded commands: so the recording gets an encoder (and
//!   a submission) of its own, between wgpu's uses of the texture, and the texture's first wgpu use is a write
//!   (wgpu would otherwise clear it, taking it for uninitialized).
//! - After the submission finishes (`Device::poll`), [`Renderer::complete`] collects the frame's report.

use ash::vk;
use caustics::scene::Scene;
use caustics::settings::Settings;
use caustics::{gpu, Aov, AovData, FrameDesc, RecordTarget, Renderer};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use wgpu::hal::api::Vulkan;

type Res<T> = Result<T, Box<dyn std::error::Error>>;

/// The headless frame: 192 × 128 (a texture row of 768 bytes, as wgpu's 256-byte copy alignment asks).
const WIDTH: u32 = 192;
const HEIGHT: u32 = 128;

/// Counts the validation layer's messages, which wgpu reports through the `log` crate, and prints every warning.
struct Log;
static VALIDATION_MESSAGES: AtomicUsize = AtomicUsize::new(0);

impl log::Log for Log {
    fn enabled(&self, metadata: &log::Metadata) -> bool {
        metadata.level() <= log::Level::Warn
    }
    fn log(&self, record: &log::Record) {
        if !self.enabled(record.metadata()) {
            return;
        }
        if record.target().starts_with("wgpu_hal::vulkan::instance") {
            VALIDATION_MESSAGES.fetch_add(1, Ordering::Relaxed);
        }
        eprintln!("{} {}: {}", record.level(), record.target(), record.args());
    }
    fn flush(&self) {}
}

/// wgpu's device, with caustics' requirements added when wgpu creates it, and caustics' context on it.
struct Gpu {
    adapter: wgpu::Adapter,
    device: wgpu::Device,
    queue: wgpu::Queue,
    context: gpu::Context,
}

fn open(instance: &wgpu::Instance, surface: Option<&wgpu::Surface>) -> Res<Gpu> {
    let options = wgpu::RequestAdapterOptions { compatible_surface: surface, ..Default::default() };
    let adapter = pollster::block_on(instance.request_adapter(&options))?;
    let features = adapter.features() & wgpu::Features::VERTEX_WRITABLE_STORAGE;
    let limits = wgpu::Limits::default().using_resolution(adapter.limits());
    let memory_hints = wgpu::MemoryHints::Performance;
    let (open, float_atomic_add) = {
        let hal = unsafe { adapter.as_hal::<Vulkan>() }.ok_or("the adapter is not a Vulkan one")?;
        let (raw, physical) = (hal.shared_instance().raw_instance(), hal.raw_physical_device());
        let mut atomics = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default();
        let mut query = vk::PhysicalDeviceFeatures2::default().push_next(&mut atomics);
        unsafe { raw.get_physical_device_features2(physical, &mut query) };
        let float_atomic_add =
            hal.physical_device_capabilities().supports_extension(ash::ext::shader_atomic_float::NAME)
                && atomics.shader_buffer_float32_atomic_add != 0
                && atomics.shader_shared_float32_atomic_add != 0;
        // What caustics needs beyond wgpu's own choice (see caustics::gpu::Imported).
        let mut sync2 = vk::PhysicalDeviceSynchronization2Features::default().synchronization2(true);
        let mut dynamic = vk::PhysicalDeviceDynamicRenderingFeatures::default().dynamic_rendering(true);
        let mut float_add = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default()
            .shader_buffer_float32_atomic_add(true)
            .shader_shared_float32_atomic_add(true);
        let (sync2, dynamic, float_add) = (&mut sync2, &mut dynamic, &mut float_add);
        let add: Box<wgpu::hal::vulkan::CreateDeviceCallback<'_>> = Box::new(move |args| {
            args.extensions.push(ash::khr::push_descriptor::NAME);
            let mut info = std::mem::take(args.create_info).push_next(sync2).push_next(dynamic);
            if float_atomic_add {
                args.extensions.push(ash::ext::shader_atomic_float::NAME);
                info = info.push_next(float_add);
            }
            *args.create_info = info;
        });
        let open = unsafe { hal.open_with_callback(features, &limits, &memory_hints, Some(add)) }?;
        (open, float_atomic_add)
    };
    let desc = wgpu::DeviceDescriptor {
        label: Some("wgpu example"),
        required_features: features,
        required_limits: limits,
        memory_hints,
        ..Default::default()
    };
    let (device, queue) = unsafe { adapter.create_device_from_hal(open, &desc) }?;
    let imported = {
        let hal = unsafe { device.as_hal::<Vulkan>() }.ok_or("the device is not a Vulkan one")?;
        let shared = hal.shared_instance();
        gpu::Imported {
            entry: shared.entry().clone(),
            instance: shared.raw_instance().clone(),
            physical: hal.raw_physical_device(),
            device: hal.raw_device().clone(),
            queue: hal.raw_queue(),
            queue_family: hal.queue_family_index(),
            float_atomic_add,
        }
    };
    let context = gpu::Context::import(imported)?;
    Ok(Gpu { adapter, device, queue, context })
}

/// The texture caustics copies its beauty image into: written once by wgpu first, so that wgpu takes it for
/// initialized and knows its layout (transfer destination).
fn caustics_texture(g: &Gpu, width: u32, height: u32, format: wgpu::TextureFormat) -> wgpu::Texture {
    let texture = g.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("caustics beauty"),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let zeros = vec![0u8; (4 * width * height) as usize];
    let layout = wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(4 * width), rows_per_image: None };
    let size = wgpu::Extent3d { width, height, depth_or_array_layers: 1 };
    g.queue.write_texture(texture.as_image_copy(), &zeros, layout, size);
    g.queue.submit([]);
    texture
}

/// Record a caustics frame into an encoder of its own, submit it, wait, and complete it. `layout` is the texture's
/// layout as wgpu left it (caustics leaves it so).
fn record(
    g: &Gpu,
    renderer: &mut Renderer,
    desc: &FrameDesc,
    texture: &wgpu::Texture,
    layout: vk::ImageLayout,
) -> Res<caustics::Frame> {
    let image =
        unsafe { texture.as_hal::<Vulkan>() }.map(|t| unsafe { t.raw_handle() }).ok_or("not a Vulkan texture")?;
    let target = RecordTarget {
        image,
        extent: vk::Extent2D { width: texture.width(), height: texture.height() },
        old_layout: layout,
        new_layout: layout,
    };
    let mut encoder = g.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("caustics") });
    let recorded = unsafe {
        encoder.as_hal_mut::<Vulkan, _, _>(|e| {
            let cmd = e.ok_or("not a Vulkan encoder")?.raw_handle();
            renderer.record(cmd, desc, Some(&target)).map_err(|e| e.to_string())
        })
    }?;
    g.queue.submit([encoder.finish()]);
    g.device.poll(wgpu::PollType::wait_indefinitely())?;
    Ok(renderer.complete(recorded)?)
}

/// Read a texture back through wgpu (rows of `4 * width` bytes, a multiple of 256).
fn read_back(g: &Gpu, texture: &wgpu::Texture) -> Res<Vec<u8>> {
    let (width, height) = (texture.width(), texture.height());
    let bytes = (4 * width * height) as u64;
    let buffer = g.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: bytes,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = g.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("readback") });
    let layout = wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(4 * width), rows_per_image: None };
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo { buffer: &buffer, layout },
        wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
    );
    g.queue.submit([encoder.finish()]);
    buffer.slice(..).map_async(wgpu::MapMode::Read, |_| {});
    g.device.poll(wgpu::PollType::wait_indefinitely())?;
    let pixels = buffer.slice(..).get_mapped_range()?.to_vec();
    Ok(pixels)
}

fn headless(scene_path: PathBuf, validation: bool) -> Res<()> {
    let instance = wgpu::Instance::new(instance_desc(validation));
    let g = open(&instance, None)?;
    let scene = Scene::load(&scene_path)?;
    let camera = scene.camera(None).map_err(caustics::Error::BadInput)?.clone();
    let mut renderer = Renderer::new(g.context.device.clone(), scene, Settings::default())?;
    // Each frame recomputes everything, so the two frames below do the same work.
    renderer.set_reuse(false);
    let view = renderer.camera_view(&camera, WIDTH, HEIGHT);
    let texture = caustics_texture(&g, WIDTH, HEIGHT, wgpu::TextureFormat::Rgba8Unorm);
    let frame =
        record(&g, &mut renderer, &FrameDesc::new(&view, None), &texture, vk::ImageLayout::TRANSFER_DST_OPTIMAL)?;
    let pixels = read_back(&g, &texture)?;

    let own = renderer.render(&FrameDesc::new(&view, Some(Aov::Beauty)))?;
    let Some(AovData::Rgba8 { rgba, .. }) = own.image else { return Err("no beauty image".into()) };
    let differing = pixels.iter().zip(&rgba).filter(|(a, b)| a != b).count();
    let lit = pixels.chunks_exact(4).filter(|p| p[..3].iter().any(|&c| c > 0)).count();
    println!(
        "wgpu frame: {} photons, {:.1} ms on the GPU; {lit} of {} pixels of the wgpu texture lit; {differing} of {} \
         bytes differ from Renderer::render",
        frame.report.photons(),
        frame.report.gpu_ms,
        WIDTH * HEIGHT,
        pixels.len()
    );
    drop(renderer);
    drop(g);
    let messages = VALIDATION_MESSAGES.load(Ordering::Relaxed);
    if messages > 0 {
        return Err(format!("{messages} Vulkan validation messages").into());
    }
    if differing > 0 || lit == 0 || frame.report.photons() == 0 {
        return Err("the frame in the wgpu texture differs from Renderer::render's (or is empty)".into());
    }
    Ok(())
}

fn instance_desc(validation: bool) -> wgpu::InstanceDescriptor {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::VULKAN;
    desc.flags = if validation {
        wgpu::InstanceFlags::VALIDATION | wgpu::InstanceFlags::DEBUG
    } else {
        wgpu::InstanceFlags::empty()
    };
    desc
}

fn main() {
    let _ = log::set_logger(&Log).map(|()| log::set_max_level(log::LevelFilter::Warn));
    let args: Vec<String> = std::env::args().skip(1).collect();
    let is_headless = args.iter().any(|a| a == "--headless");
    let scene_path = args
        .iter()
        .find(|a| !a.starts_with("--"))
        .map(PathBuf::from)
        .unwrap_or_else(|| concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/sphere.toml").into());
    let validation = gpu::ContextDesc::from_env().validation;
    let result = if is_headless { headless(scene_path, validation) } else { window::run(scene_path, validation) };
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

/// The windowed application: wgpu copies the caustics texture into its surface's texture and presents it.
mod window {
    use super::*;
    use std::sync::Arc;
    use winit::application::ApplicationHandler;
    use winit::event::WindowEvent;
    use winit::event_loop::{ActiveEventLoop, EventLoop};
    use winit::window::{Window, WindowId};

    struct Shown {
        window: Arc<Window>,
        surface: wgpu::Surface<'static>,
        config: wgpu::SurfaceConfiguration,
        texture: Option<wgpu::Texture>,
        /// The caustics texture's layout as wgpu left it: a transfer destination until wgpu first copies from it.
        layout: vk::ImageLayout,
        renderer: Renderer,
        g: Gpu,
        started: std::time::Instant,
        /// The first light's target and its offset from it, as the scene has them.
        light0: (glam::Vec3, glam::Vec3),
    }

    struct App {
        scene_path: PathBuf,
        validation: bool,
        shown: Option<Shown>,
        error: Option<Box<dyn std::error::Error>>,
    }

    pub fn run(scene_path: PathBuf, validation: bool) -> Res<()> {
        let event_loop = EventLoop::new()?;
        let mut app = App { scene_path, validation, shown: None, error: None };
        event_loop.run_app(&mut app)?;
        match app.error {
            Some(e) => Err(e),
            None if VALIDATION_MESSAGES.load(Ordering::Relaxed) > 0 => Err("Vulkan validation messages".into()),
            None => Ok(()),
        }
    }

    impl App {
        fn start(&mut self, el: &ActiveEventLoop) -> Res<Shown> {
            let attrs = Window::default_attributes().with_title("caustics in wgpu");
            let window = Arc::new(el.create_window(attrs)?);
            let instance = wgpu::Instance::new(instance_desc(self.validation));
            let surface = instance.create_surface(window.clone())?;
            let g = open(&instance, Some(&surface))?;
            let size = window.inner_size();
            let mut config = surface
                .get_default_config(&g.adapter, size.width.max(1), size.height.max(1))
                .ok_or("the surface does not fit the adapter")?;
            // wgpu copies the caustics texture, in the surface's format without sRGB encoding (caustics' beauty
            // image is already encoded), into the surface's.
            config.format = config.format.remove_srgb_suffix();
            config.usage |= wgpu::TextureUsages::COPY_DST;
            surface.configure(&g.device, &config);
            let scene = Scene::load(&self.scene_path)?;
            let light0 =
                scene.lights.first().map_or((glam::Vec3::ZERO, glam::Vec3::Y), |l| (l.target, l.position - l.target));
            let renderer = Renderer::new(g.context.device.clone(), scene, Settings::default())?;
            Ok(Shown {
                light0,
                window,
                surface,
                config,
                texture: None,
                layout: vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                renderer,
                g,
                started: std::time::Instant::now(),
            })
        }
    }

    impl Shown {
        fn redraw(&mut self) -> Res<()> {
            let (w, h) = (self.config.width, self.config.height);
            if self.texture.as_ref().is_none_or(|t| (t.width(), t.height()) != (w, h)) {
                self.texture = Some(caustics_texture(&self.g, w, h, self.config.format));
                self.layout = vk::ImageLayout::TRANSFER_DST_OPTIMAL;
            }
            // The light orbits its target, a turn in 8 s (tilted 25° first when it stands straight above it).
            let mut scene = self.renderer.scene().clone();
            if let Some(light) = scene.lights.first_mut() {
                let (target, mut d) = self.light0;
                if d.normalize().dot(glam::Vec3::Y).abs() > 0.99 {
                    d = glam::Quat::from_rotation_z(-25f32.to_radians()) * d;
                }
                let angle = std::f32::consts::TAU * self.started.elapsed().as_secs_f32() / 8.0;
                light.position = target + glam::Quat::from_rotation_y(angle) * d;
            }
            self.renderer.set_scene(scene)?;
            let camera = self.renderer.scene().camera(None).map_err(caustics::Error::BadInput)?.clone();
            let view = self.renderer.camera_view(&camera, w, h);
            let Some(texture) = &self.texture else { return Ok(()) };
            record(&self.g, &mut self.renderer, &FrameDesc::new(&view, None), texture, self.layout)?;
            let frame = match self.surface.get_current_texture() {
                wgpu::CurrentSurfaceTexture::Success(f) | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
                wgpu::CurrentSurfaceTexture::Outdated => {
                    self.surface.configure(&self.g.device, &self.config);
                    self.window.request_redraw();
                    return Ok(());
                }
                wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                    self.window.request_redraw();
                    return Ok(());
                }
                _ => return Err("the window's surface was lost".into()),
            };
            let mut encoder = self.g.device.create_command_encoder(&Default::default());
            encoder.copy_texture_to_texture(
                texture.as_image_copy(),
                frame.texture.as_image_copy(),
                wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
            );
            self.g.queue.submit([encoder.finish()]);
            self.window.pre_present_notify();
            self.g.queue.present(frame);
            // wgpu copied from the texture: that is its layout now.
            self.layout = vk::ImageLayout::TRANSFER_SRC_OPTIMAL;
            self.window.request_redraw();
            Ok(())
        }
    }

    impl ApplicationHandler for App {
        fn resumed(&mut self, el: &ActiveEventLoop) {
            if self.shown.is_none() {
                match self.start(el) {
                    Ok(s) => {
                        s.window.request_redraw();
                        self.shown = Some(s);
                    }
                    Err(e) => {
                        self.error = Some(e);
                        el.exit();
                    }
                }
            }
        }

        fn window_event(&mut self, el: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
            let Some(s) = self.shown.as_mut() else { return };
            match event {
                WindowEvent::CloseRequested => el.exit(),
                WindowEvent::Resized(size) if size.width > 0 && size.height > 0 => {
                    s.config.width = size.width;
                    s.config.height = size.height;
                    s.surface.configure(&s.g.device, &s.config);
                }
                WindowEvent::RedrawRequested => {
                    if let Err(e) = s.redraw() {
                        self.error = Some(e);
                        el.exit();
                    }
                }
                _ => {}
            }
        }
    }
}

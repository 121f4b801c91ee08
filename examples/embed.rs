//! Embed the renderer in a host's own Vulkan device: the host creates the instance, the device, an image and a
//! command buffer; caustics records a frame into that command buffer and copies its beauty image into the host's
//! image; the host submits and waits, reads its image back, and compares it with what `Renderer::render` gives on
//! the renderer's own path (they must be the same bytes).
//!
//! ```sh
//! cargo run --release --example embed -- [SCENE.toml]
//! ```
//!
//! With `CAUSTICS_VALIDATION=1` the host enables the Khronos validation layer with synchronization validation and
//! chains caustics' messenger, so that any message fails the run. Exits 0 when the images agree, 1 otherwise.

use ash::vk;
use caustics::scene::Scene;
use caustics::settings::Settings;
use caustics::{gpu, Aov, AovData, FrameDesc, RecordTarget, Renderer};
use std::ffi::{c_char, CStr};
use std::path::PathBuf;

const WIDTH: u32 = 160;
const HEIGHT: u32 = 120;

type Res<T> = Result<T, Box<dyn std::error::Error>>;

/// The host's Vulkan objects (destroyed in reverse order when dropped, after the renderer is gone).
struct Host {
    _entry: ash::Entry,
    instance: ash::Instance,
    physical: vk::PhysicalDevice,
    device: ash::Device,
    queue: vk::Queue,
    family: u32,
    float_atomics: bool,
}

impl Drop for Host {
    fn drop(&mut self) {
        unsafe {
            let _ = self.device.device_wait_idle();
            self.device.destroy_device(None);
            self.instance.destroy_instance(None);
        }
    }
}

fn has(list: &[vk::ExtensionProperties], name: &CStr) -> bool {
    list.iter().any(|e| e.extension_name_as_c_str().ok() == Some(name))
}

/// A host as an engine would make one: Vulkan 1.3, one graphics+compute queue, and what caustics asks for
/// (see `caustics::gpu::Imported`).
fn create_host(validation: bool) -> Res<Host> {
    let entry = unsafe { ash::Entry::load()? };
    let app = vk::ApplicationInfo::default().application_name(c"embed example").api_version(vk::API_VERSION_1_3);
    let layers: Vec<*const c_char> = if validation { vec![c"VK_LAYER_KHRONOS_validation".as_ptr()] } else { vec![] };
    let mut extensions: Vec<*const c_char> = Vec::new();
    let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
    // caustics' own messenger: every validation message is logged and counted (gpu::validation_message_count).
    let mut messenger = gpu::validation_messenger_info();
    let mut info = vk::InstanceCreateInfo::default().application_info(&app).enabled_layer_names(&layers);
    if validation {
        extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        extensions.push(ash::ext::validation_features::NAME.as_ptr());
        info = info.push_next(&mut features).push_next(&mut messenger);
    }
    let info = info.enabled_extension_names(&extensions);
    let instance = unsafe { entry.create_instance(&info, None)? };
    let physicals = unsafe { instance.enumerate_physical_devices()? };
    // The first device with a graphics+compute queue that has timestamps and offers push descriptors.
    let mut chosen = None;
    for &p in &physicals {
        let exts = unsafe { instance.enumerate_device_extension_properties(p)? };
        if !has(&exts, ash::khr::push_descriptor::NAME) {
            continue;
        }
        let families = unsafe { instance.get_physical_device_queue_family_properties(p) };
        if let Some(f) = families.iter().position(|f| {
            f.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE) && f.timestamp_valid_bits > 0
        }) {
            chosen = Some((p, f as u32, has(&exts, ash::ext::shader_atomic_float::NAME)));
            break;
        }
    }
    let Some((physical, family, atomic_ext)) = chosen else {
        unsafe { instance.destroy_instance(None) };
        return Err("no Vulkan device with a graphics+compute queue and VK_KHR_push_descriptor".into());
    };
    let supported = unsafe { instance.get_physical_device_features(physical) };
    let core = vk::PhysicalDeviceFeatures::default()
        .large_points(true)
        .vertex_pipeline_stores_and_atomics(supported.vertex_pipeline_stores_and_atomics != 0)
        .fragment_stores_and_atomics(supported.fragment_stores_and_atomics != 0)
        .shader_int64(supported.shader_int64 != 0);
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default().synchronization2(true).dynamic_rendering(true);
    let float_atomics = atomic_ext && {
        let mut fa = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default();
        let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut fa);
        unsafe { instance.get_physical_device_features2(physical, &mut f2) };
        fa.shader_buffer_float32_atomic_add != 0 && fa.shader_shared_float32_atomic_add != 0
    };
    let mut fa = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default()
        .shader_buffer_float32_atomic_add(true)
        .shader_shared_float32_atomic_add(true);
    let mut f2 = vk::PhysicalDeviceFeatures2::default().features(core).push_next(&mut f13);
    let mut device_exts = vec![ash::khr::push_descriptor::NAME.as_ptr()];
    if float_atomics {
        device_exts.push(ash::ext::shader_atomic_float::NAME.as_ptr());
        f2 = f2.push_next(&mut fa);
    }
    let priorities = [1.0f32];
    let queues = [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priorities)];
    let info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queues)
        .enabled_extension_names(&device_exts)
        .push_next(&mut f2);
    let device = match unsafe { instance.create_device(physical, &info, None) } {
        Ok(d) => d,
        Err(e) => {
            unsafe { instance.destroy_instance(None) };
            return Err(e.into());
        }
    };
    let queue = unsafe { device.get_device_queue(family, 0) };
    Ok(Host { _entry: entry, instance, physical, device, queue, family, float_atomics })
}

fn memory_type(host: &Host, bits: u32, want: vk::MemoryPropertyFlags) -> Res<u32> {
    let props = unsafe { host.instance.get_physical_device_memory_properties(host.physical) };
    (0..props.memory_type_count)
        .find(|&i| bits & (1 << i) != 0 && props.memory_types[i as usize].property_flags.contains(want))
        .ok_or_else(|| "no suitable memory type".into())
}

/// The host's own resources for one frame: its target image, a host-visible buffer to read it back, a command
/// buffer and a fence.
struct Frame<'h> {
    host: &'h Host,
    image: vk::Image,
    image_memory: vk::DeviceMemory,
    buffer: vk::Buffer,
    buffer_memory: vk::DeviceMemory,
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
}

impl Drop for Frame<'_> {
    fn drop(&mut self) {
        let d = &self.host.device;
        unsafe {
            let _ = d.device_wait_idle();
            d.destroy_fence(self.fence, None);
            d.destroy_command_pool(self.pool, None);
            d.destroy_buffer(self.buffer, None);
            d.free_memory(self.buffer_memory, None);
            d.destroy_image(self.image, None);
            d.free_memory(self.image_memory, None);
        }
    }
}

fn host_frame(host: &Host) -> Res<Frame<'_>> {
    let d = &host.device;
    let image_info = vk::ImageCreateInfo::default()
        .image_type(vk::ImageType::TYPE_2D)
        .format(vk::Format::R8G8B8A8_UNORM)
        .extent(vk::Extent3D { width: WIDTH, height: HEIGHT, depth: 1 })
        .mip_levels(1)
        .array_layers(1)
        .samples(vk::SampleCountFlags::TYPE_1)
        .tiling(vk::ImageTiling::OPTIMAL)
        .usage(vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC)
        .initial_layout(vk::ImageLayout::UNDEFINED);
    unsafe {
        let image = d.create_image(&image_info, None)?;
        let req = d.get_image_memory_requirements(image);
        let alloc = vk::MemoryAllocateInfo::default().allocation_size(req.size).memory_type_index(memory_type(
            host,
            req.memory_type_bits,
            vk::MemoryPropertyFlags::DEVICE_LOCAL,
        )?);
        let image_memory = d.allocate_memory(&alloc, None)?;
        d.bind_image_memory(image, image_memory, 0)?;
        let size = 4 * WIDTH as u64 * HEIGHT as u64;
        let buffer = d.create_buffer(
            &vk::BufferCreateInfo::default().size(size).usage(vk::BufferUsageFlags::TRANSFER_DST),
            None,
        )?;
        let req = d.get_buffer_memory_requirements(buffer);
        let visible = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
        let alloc = vk::MemoryAllocateInfo::default().allocation_size(req.size).memory_type_index(memory_type(
            host,
            req.memory_type_bits,
            visible,
        )?);
        let buffer_memory = d.allocate_memory(&alloc, None)?;
        d.bind_buffer_memory(buffer, buffer_memory, 0)?;
        let pool =
            d.create_command_pool(&vk::CommandPoolCreateInfo::default().queue_family_index(host.family), None)?;
        let cmd = d.allocate_command_buffers(
            &vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(1),
        )?[0];
        let fence = d.create_fence(&vk::FenceCreateInfo::default(), None)?;
        Ok(Frame { host, image, image_memory, buffer, buffer_memory, pool, cmd, fence })
    }
}

fn main() -> Res<()> {
    let scene_path = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/sphere.toml").into()),
    );
    let validation = gpu::ContextDesc::from_env().validation;
    let host = create_host(validation)?;
    let frame = host_frame(&host)?;
    let d = &host.device;

    // The renderer on the host's device and queue.
    let context = gpu::Context::import(gpu::Imported {
        entry: unsafe { ash::Entry::load()? },
        instance: host.instance.clone(),
        physical: host.physical,
        device: host.device.clone(),
        queue: host.queue,
        queue_family: host.family,
        float_atomic_add: host.float_atomics,
    })?;
    let scene = Scene::load(&scene_path)?;
    let camera = scene.camera(None).map_err(caustics::Error::BadInput)?.clone();
    let mut renderer = Renderer::new(context.device.clone(), scene, Settings::default())?;
    // Each frame recomputes everything, so the two frames below do the same work.
    renderer.set_reuse(false);
    let view = renderer.camera_view(&camera, WIDTH, HEIGHT);
    let desc = FrameDesc::new(&view, None);

    // Record into the host's command buffer: caustics' frame, its copy into the host's image, then the host's own
    // copy of that image into its readback buffer.
    let target = RecordTarget {
        image: frame.image,
        extent: vk::Extent2D { width: WIDTH, height: HEIGHT },
        old_layout: vk::ImageLayout::UNDEFINED,
        new_layout: vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
    };
    unsafe {
        d.begin_command_buffer(frame.cmd, &vk::CommandBufferBeginInfo::default())?;
    }
    let recorded = renderer.record(frame.cmd, &desc, Some(&target))?;
    let region = vk::BufferImageCopy::default()
        .image_subresource(vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        })
        .image_extent(vk::Extent3D { width: WIDTH, height: HEIGHT, depth: 1 });
    unsafe {
        d.cmd_copy_image_to_buffer(
            frame.cmd,
            frame.image,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            frame.buffer,
            &[region],
        );
        let to_host = [vk::BufferMemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)
            .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::HOST)
            .dst_access_mask(vk::AccessFlags2::HOST_READ)
            .buffer(frame.buffer)
            .size(vk::WHOLE_SIZE)];
        d.cmd_pipeline_barrier2(frame.cmd, &vk::DependencyInfo::default().buffer_memory_barriers(&to_host));
        d.end_command_buffer(frame.cmd)?;
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(frame.cmd)];
        d.queue_submit2(host.queue, &[vk::SubmitInfo2::default().command_buffer_infos(&cmds)], frame.fence)?;
        d.wait_for_fences(&[frame.fence], true, u64::MAX)?;
    }
    let embedded = renderer.complete(recorded)?;
    let bytes = (4 * WIDTH * HEIGHT) as usize;
    let host_pixels = unsafe {
        let ptr = d.map_memory(frame.buffer_memory, 0, bytes as u64, vk::MemoryMapFlags::empty())? as *const u8;
        let v = std::slice::from_raw_parts(ptr, bytes).to_vec();
        d.unmap_memory(frame.buffer_memory);
        v
    };

    // The same frame on the renderer's own path.
    let own = renderer.render(&FrameDesc::new(&view, Some(Aov::Beauty)))?;
    let Some(AovData::Rgba8 { rgba, .. }) = own.image else { return Err("no beauty image".into()) };
    let differing = host_pixels.iter().zip(&rgba).filter(|(a, b)| a != b).count();
    let lit = host_pixels.chunks_exact(4).filter(|p| p[..3].iter().any(|&c| c > 0)).count();
    println!(
        "embedded frame: {} photons, {:.1} ms on the GPU; {lit} of {} host pixels lit; {differing} of {bytes} bytes differ \
         from Renderer::render",
        embedded.report.photons(),
        embedded.report.gpu_ms,
        WIDTH * HEIGHT
    );
    drop(renderer);
    drop(context);
    let messages = gpu::validation_message_count();
    if messages > 0 {
        eprintln!("error: {messages} Vulkan validation messages");
        std::process::exit(1);
    }
    if differing > 0 || lit == 0 || embedded.report.photons() == 0 {
        eprintln!("error: the embedded frame differs from Renderer::render's (or is empty)");
        std::process::exit(1);
    }
    Ok(())
}

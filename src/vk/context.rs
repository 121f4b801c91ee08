//! Instance and device creation: validation (with synchronization validation), device selection, the queue and
//! the memory allocator. Everything else holds an `Arc<Device>`, so the device outlives every resource.

use super::debug::messenger_info;
use super::error::{Check, VkError, VkResult};
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::ffi::{c_char, CStr};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// How to create the Vulkan context.
#[derive(Clone, Debug, Default)]
pub struct ContextDesc {
    /// Enable the Khronos validation layer with synchronization validation.
    pub validation: bool,
    /// Pick a device: "cpu"/"lavapipe"/"llvmpipe", "gpu", an index (digits only, never matched against names),
    /// or a device's name or a substring of exactly one device's name (case-insensitive).
    pub device_hint: Option<String>,
    /// Extra instance extensions (window-system surfaces).
    pub instance_extensions: Vec<&'static CStr>,
    /// The device must support `VK_KHR_swapchain`.
    pub swapchain: bool,
}

impl ContextDesc {
    /// Validation defaults to on in debug builds and off in release; `CAUSTICS_VALIDATION=0|1` overrides it.
    /// The device comes from `CAUSTICS_DEVICE` when set.
    pub fn from_env() -> Self {
        let validation = match std::env::var("CAUSTICS_VALIDATION").ok().as_deref() {
            Some("0") | Some("false") | Some("off") => false,
            Some(_) => true,
            None => cfg!(debug_assertions),
        };
        ContextDesc {
            validation,
            device_hint: std::env::var("CAUSTICS_DEVICE").ok().filter(|s| !s.is_empty()),
            ..Default::default()
        }
    }
}

/// The Vulkan instance (with the validation layer's messenger when validation is on), or a host's.
pub struct Instance {
    /// The loader's entry points.
    pub entry: ash::Entry,
    /// The instance.
    pub raw: ash::Instance,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// Whether the Khronos validation layer (with synchronization validation) is on.
    pub validation: bool,
    /// Created here (destroyed with this), or a host's (left to it).
    owned: bool,
}

impl Instance {
    /// Create an instance as `desc` asks (validation, instance extensions).
    pub fn new(desc: &ContextDesc) -> VkResult<Arc<Self>> {
        let entry = unsafe { ash::Entry::load()? };
        let layers =
            unsafe { entry.enumerate_instance_layer_properties() }.check("vkEnumerateInstanceLayerProperties")?;
        let has_validation =
            layers.iter().any(|l| l.layer_name_as_c_str().map(|n| n == VALIDATION_LAYER).unwrap_or(false));
        if desc.validation && !has_validation {
            return Err(VkError::NoValidationLayer);
        }
        let available = unsafe { entry.enumerate_instance_extension_properties(None) }
            .check("vkEnumerateInstanceExtensionProperties")?;
        let has_ext =
            |name: &CStr| available.iter().any(|e| e.extension_name_as_c_str().map(|n| n == name).unwrap_or(false));
        let mut extensions: Vec<*const c_char> = desc.instance_extensions.iter().map(|e| e.as_ptr()).collect();
        let debug_utils = has_ext(ash::ext::debug_utils::NAME);
        if debug_utils {
            extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        if desc.validation {
            extensions.push(ash::ext::validation_features::NAME.as_ptr());
        }
        let layer_names: Vec<*const c_char> = if desc.validation { vec![VALIDATION_LAYER.as_ptr()] } else { vec![] };
        let app = vk::ApplicationInfo::default()
            .application_name(c"caustics")
            .engine_name(c"caustics")
            .api_version(vk::API_VERSION_1_3);
        // Synchronization validation is off by default in the layer; it must be enabled explicitly.
        let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
        let mut messenger = messenger_info();
        let mut info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layer_names)
            .enabled_extension_names(&extensions);
        if desc.validation {
            info = info.push_next(&mut features);
        }
        if debug_utils {
            // Chained so that instance creation and destruction are covered too.
            info = info.push_next(&mut messenger);
        }
        let raw = match unsafe { entry.create_instance(&info, None) } {
            Ok(raw) => raw,
            Err(vk::Result::ERROR_INCOMPATIBLE_DRIVER) => {
                return Err(VkError::NoDevice(
                    "the Vulkan loader found no driver (vkCreateInstance: ERROR_INCOMPATIBLE_DRIVER)".into(),
                ))
            }
            Err(e) => return Err(VkError::Call { call: "vkCreateInstance", result: e }),
        };
        let debug = if debug_utils {
            let loader = ash::ext::debug_utils::Instance::new(&entry, &raw);
            match unsafe { loader.create_debug_utils_messenger(&messenger_info(), None) } {
                Ok(m) => Some((loader, m)),
                Err(e) => {
                    unsafe { raw.destroy_instance(None) };
                    return Err(VkError::Call { call: "vkCreateDebugUtilsMessengerEXT", result: e });
                }
            }
        } else {
            None
        };
        Ok(Arc::new(Instance { entry, raw, debug, validation: desc.validation, owned: true }))
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        unsafe {
            if let Some((loader, messenger)) = self.debug.take() {
                loader.destroy_debug_utils_messenger(messenger, None);
            }
            if self.owned {
                self.raw.destroy_instance(None);
            }
        }
    }
}

/// Facts about the chosen physical device that the renderer needs.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    /// The device's name.
    pub name: String,
    /// The driver's name and version.
    pub driver: String,
    /// Discrete, integrated, virtual GPU, or CPU.
    pub kind: vk::PhysicalDeviceType,
    /// The Vulkan version it offers.
    pub api_version: u32,
    /// Its limits.
    pub limits: vk::PhysicalDeviceLimits,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period: f32,
    /// Valid bits of the queue's timestamps.
    pub timestamp_valid_bits: u32,
    /// VK_EXT_shader_atomic_float with shaderBufferFloat32AtomicAdd and shaderSharedFloat32AtomicAdd (the compute
    /// splats need them).
    pub float_atomic_add: bool,
    /// Size of the largest device-local memory heap (bytes).
    pub device_local_bytes: u64,
    /// The least subgroup size a compute shader may run with (Vulkan 1.3's minSubgroupSize; at least 1).
    pub min_subgroup_size: u32,
    /// VK_KHR_push_descriptor's maxPushDescriptors: the most bindings a pipeline's (push-descriptor) layout may
    /// have.
    pub max_push_descriptors: u32,
    /// VK_EXT_calibrated_timestamps with the device's time domain: the device's clock can be read from the host
    /// ([`Device::calibrated`]; the Tracy zones calibrate with it).
    pub calibrated_timestamps: bool,
}

impl DeviceInfo {
    /// A CPU device (lavapipe): the `auto` settings' rules pick differently there than on GPUs.
    pub fn is_cpu(&self) -> bool {
        self.kind == vk::PhysicalDeviceType::CPU
    }

    /// The bits of a timestamp that count (`timestamp_valid_bits` of the queue's family).
    pub fn timestamp_mask(&self) -> u64 {
        let bits = self.timestamp_valid_bits;
        if bits >= 64 {
            u64::MAX
        } else {
            (1u64 << bits) - 1
        }
    }
}

/// What [`Device::allocation_report`] returns.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AllocationTotals {
    /// Live allocations.
    pub allocations: usize,
    /// Bytes allocated.
    pub allocated_bytes: u64,
    /// Bytes of the memory blocks behind them.
    pub capacity_bytes: u64,
}

/// The logical device, its one queue, and the allocator. Derefs to `ash::Device`.
pub struct Device {
    /// The instance it was created from.
    pub instance: Arc<Instance>,
    raw: ash::Device,
    /// The physical device.
    pub physical: vk::PhysicalDevice,
    /// What the renderer needs to know of it.
    pub info: DeviceInfo,
    /// The queue every submission goes to (graphics and compute, with timestamps).
    pub queue: vk::Queue,
    /// Its family.
    pub queue_family: u32,
    /// VK_KHR_push_descriptor's entry points (every pass binds its resources with push descriptors).
    pub push_descriptor: ash::khr::push_descriptor::Device,
    /// VK_EXT_debug_utils' device entry points, for object names, when the instance has the extension.
    pub debug_utils: Option<ash::ext::debug_utils::Device>,
    /// VK_EXT_calibrated_timestamps' entry points, where [`DeviceInfo::calibrated_timestamps`] says so.
    pub calibrated: Option<ash::ext::calibrated_timestamps::Device>,
    allocator: ManuallyDrop<Mutex<Allocator>>,
    /// Created here (destroyed with this), or a host's (left to it).
    owned: bool,
    /// vkDeviceWaitIdle calls made through [`Device::wait_idle`] (the stats count the stalls a frame caused).
    wait_idles: std::sync::atomic::AtomicU64,
    /// The barrier trackers' lists of destroyed buffers and images ([`Device::retired_ids`]).
    retired: Mutex<Vec<std::sync::Weak<Mutex<Vec<u64>>>>>,
    /// What the users of this device share while one of them holds it, one object per type ([`Device::shared`]).
    shared: Mutex<Vec<std::sync::Weak<dyn std::any::Any + Send + Sync>>>,
}

impl std::ops::Deref for Device {
    type Target = ash::Device;
    fn deref(&self) -> &ash::Device {
        &self.raw
    }
}

struct Candidate {
    physical: vk::PhysicalDevice,
    info: DeviceInfo,
    queue_family: u32,
}

/// What the renderer needs to know of a physical device. `atomic_float_ext`: it offers
/// VK_EXT_shader_atomic_float (its float-add features are then queried).
fn describe(
    raw: &ash::Instance,
    physical: vk::PhysicalDevice,
    props: &vk::PhysicalDeviceProperties,
    timestamp_valid_bits: u32,
    atomic_float_ext: bool,
) -> DeviceInfo {
    let name = props.device_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let float_atomic_add = atomic_float_ext && {
        let mut fa = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default();
        let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut fa);
        unsafe { raw.get_physical_device_features2(physical, &mut f2) };
        fa.shader_buffer_float32_atomic_add != 0 && fa.shader_shared_float32_atomic_add != 0
    };
    let mut driver_props = vk::PhysicalDeviceDriverProperties::default();
    let mut size_control = vk::PhysicalDeviceSubgroupSizeControlProperties::default();
    let mut push = vk::PhysicalDevicePushDescriptorPropertiesKHR::default();
    let mut p2 = vk::PhysicalDeviceProperties2::default()
        .push_next(&mut driver_props)
        .push_next(&mut size_control)
        .push_next(&mut push);
    unsafe { raw.get_physical_device_properties2(physical, &mut p2) };
    let min_subgroup_size = size_control.min_subgroup_size.max(1);
    let driver = format!(
        "{} {}",
        driver_props.driver_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default(),
        driver_props.driver_info_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
    );
    let memory = unsafe { raw.get_physical_device_memory_properties(physical) };
    let device_local_bytes = memory
        .memory_heaps_as_slice()
        .iter()
        .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
        .map(|h| h.size)
        .max()
        .unwrap_or(0);
    DeviceInfo {
        name,
        driver: driver.trim().to_string(),
        kind: props.device_type,
        api_version: props.api_version,
        limits: props.limits,
        timestamp_period: props.limits.timestamp_period,
        timestamp_valid_bits,
        float_atomic_add,
        device_local_bytes,
        min_subgroup_size,
        max_push_descriptors: push.max_push_descriptors,
        calibrated_timestamps: false,
    }
}

/// Whether compute shaders may use subgroup arithmetic (the waves sum their energy account per subgroup,
/// glsl/wave.comp): Vulkan 1.1 requires only the basic subgroup operations.
fn subgroup_arithmetic(raw: &ash::Instance, physical: vk::PhysicalDevice) -> bool {
    let mut sub = vk::PhysicalDeviceSubgroupProperties::default();
    let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut sub);
    unsafe { raw.get_physical_device_properties2(physical, &mut p2) };
    let ops = vk::SubgroupFeatureFlags::BASIC | vk::SubgroupFeatureFlags::ARITHMETIC;
    sub.supported_stages.contains(vk::ShaderStageFlags::COMPUTE) && sub.supported_operations.contains(ops)
}

fn rank(kind: vk::PhysicalDeviceType) -> u32 {
    match kind {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

impl Device {
    /// Create a device. `present` filters queue families that can present to a surface (windowed use).
    pub fn new(
        instance: Arc<Instance>,
        desc: &ContextDesc,
        present: Option<&dyn Fn(vk::PhysicalDevice, u32) -> bool>,
    ) -> VkResult<Arc<Self>> {
        let candidates = Self::candidates(&instance, desc, present)?;
        let chosen = Self::choose(candidates, desc.device_hint.as_deref())?;
        Self::create(instance, chosen, desc)
    }

    fn candidates(
        instance: &Instance,
        desc: &ContextDesc,
        present: Option<&dyn Fn(vk::PhysicalDevice, u32) -> bool>,
    ) -> VkResult<Vec<Candidate>> {
        let raw = &instance.raw;
        let physicals = unsafe { raw.enumerate_physical_devices() }.check("vkEnumeratePhysicalDevices")?;
        let mut out = Vec::new();
        for physical in physicals {
            let props = unsafe { raw.get_physical_device_properties(physical) };
            let name = props.device_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            if vk::api_version_minor(props.api_version) < 3 && vk::api_version_major(props.api_version) == 1 {
                log::info!("skipping {name}: Vulkan 1.3 required");
                continue;
            }
            let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
            let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f13);
            unsafe { raw.get_physical_device_features2(physical, &mut f2) };
            let core = f2.features;
            if f13.synchronization2 == 0 || f13.dynamic_rendering == 0 || core.large_points == 0 {
                log::info!("skipping {name}: needs synchronization2, dynamicRendering and largePoints");
                continue;
            }
            if !subgroup_arithmetic(raw, physical) {
                log::info!("skipping {name}: needs subgroup arithmetic in compute shaders");
                continue;
            }
            let exts = unsafe { raw.enumerate_device_extension_properties(physical) }
                .check("vkEnumerateDeviceExtensionProperties")?;
            let has = |n: &CStr| exts.iter().any(|e| e.extension_name_as_c_str().map(|x| x == n).unwrap_or(false));
            if !has(ash::khr::push_descriptor::NAME) || (desc.swapchain && !has(ash::khr::swapchain::NAME)) {
                log::info!("skipping {name}: missing VK_KHR_push_descriptor or VK_KHR_swapchain");
                continue;
            }
            let families = unsafe { raw.get_physical_device_queue_family_properties(physical) };
            let wanted = vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE;
            let family = families.iter().enumerate().position(|(i, f)| {
                f.queue_flags.contains(wanted)
                    && f.timestamp_valid_bits > 0
                    && present.map(|p| p(physical, i as u32)).unwrap_or(true)
            });
            let Some(family) = family else {
                log::info!("skipping {name}: no graphics+compute queue with timestamps");
                continue;
            };
            let mut info = describe(
                raw,
                physical,
                &props,
                families[family].timestamp_valid_bits,
                has(ash::ext::shader_atomic_float::NAME),
            );
            info.calibrated_timestamps = has(ash::ext::calibrated_timestamps::NAME) && {
                let ext = ash::ext::calibrated_timestamps::Instance::new(&instance.entry, raw);
                let domains = unsafe { ext.get_physical_device_calibrateable_time_domains(physical) };
                domains.is_ok_and(|d| d.contains(&vk::TimeDomainEXT::DEVICE))
            };
            out.push(Candidate { physical, info, queue_family: family as u32 });
        }
        Ok(out)
    }

    fn choose(mut candidates: Vec<Candidate>, hint: Option<&str>) -> VkResult<Candidate> {
        if candidates.is_empty() {
            return Err(VkError::NoDevice("no Vulkan 1.3 device with graphics and compute was found".into()));
        }
        candidates.sort_by_key(|c| rank(c.info.kind));
        let names = || candidates.iter().map(|c| c.info.name.clone()).collect::<Vec<_>>().join(", ");
        let Some(hint) = hint else {
            return Ok(candidates.remove(0));
        };
        let listing = || {
            candidates
                .iter()
                .enumerate()
                .map(|(i, c)| format!("{i}: {} ({})", c.info.name, kind_name(c.info.kind)))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let h = hint.trim().to_ascii_lowercase();
        let is_cpu = |c: &Candidate| c.info.is_cpu();
        let pos = match h.as_str() {
            "cpu" | "lavapipe" | "llvmpipe" => match candidates.iter().position(is_cpu) {
                Some(i) => i,
                None => {
                    return Err(VkError::NoSuchDevice(format!(
                        "CAUSTICS_DEVICE={hint}: there is no CPU (lavapipe) device. Run `tools/setup` to install \
                         Mesa's lavapipe, or pick one of: {}",
                        listing()
                    )))
                }
            },
            "gpu" => match candidates.iter().position(|c| !is_cpu(c)) {
                Some(i) => i,
                None => {
                    return Err(VkError::NoSuchDevice(format!(
                        "CAUSTICS_DEVICE={hint}: this machine has no Vulkan GPU, only {}. Unset CAUSTICS_DEVICE or set \
                         CAUSTICS_DEVICE=cpu to use it; a GPU needs its vendor's Vulkan driver",
                        names()
                    )))
                }
            },
            // An index selects by position only: digits are never matched against device names.
            _ if h.chars().all(|c| c.is_ascii_digit()) => match h.parse::<usize>() {
                Ok(i) if i < candidates.len() => i,
                _ => {
                    return Err(VkError::NoSuchDevice(format!(
                        "CAUSTICS_DEVICE={hint}: no device has index {hint} (devices: {})",
                        listing()
                    )))
                }
            },
            _ => {
                let lower = |c: &Candidate| c.info.name.to_ascii_lowercase();
                let matches: Vec<usize> = match candidates.iter().position(|c| lower(c) == h) {
                    Some(i) => vec![i],
                    None => (0..candidates.len()).filter(|&i| lower(&candidates[i]).contains(&h)).collect(),
                };
                match matches.as_slice() {
                    [i] => *i,
                    [] => {
                        return Err(VkError::NoSuchDevice(format!(
                            "CAUSTICS_DEVICE={hint}: no device name contains `{hint}` (devices: {})",
                            listing()
                        )))
                    }
                    _ => {
                        return Err(VkError::NoSuchDevice(format!(
                        "CAUSTICS_DEVICE={hint}: `{hint}` matches several devices ({}); use an index or a longer name",
                        matches.iter().map(|&i| candidates[i].info.name.clone()).collect::<Vec<_>>().join(", ")
                    )))
                    }
                }
            }
        };
        Ok(candidates.remove(pos))
    }

    fn create(instance: Arc<Instance>, c: Candidate, desc: &ContextDesc) -> VkResult<Arc<Self>> {
        let raw_instance = &instance.raw;
        let supported = unsafe { raw_instance.get_physical_device_features(c.physical) };
        let core = vk::PhysicalDeviceFeatures::default()
            .large_points(true)
            .vertex_pipeline_stores_and_atomics(supported.vertex_pipeline_stores_and_atomics != 0)
            .fragment_stores_and_atomics(supported.fragment_stores_and_atomics != 0)
            .shader_int64(supported.shader_int64 != 0);
        let mut f13 = vk::PhysicalDeviceVulkan13Features::default().synchronization2(true).dynamic_rendering(true);
        let mut fa = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default()
            .shader_buffer_float32_atomic_add(true)
            .shader_shared_float32_atomic_add(true);
        let mut f2 = vk::PhysicalDeviceFeatures2::default().features(core).push_next(&mut f13);
        let mut extensions = vec![ash::khr::push_descriptor::NAME.as_ptr()];
        if c.info.float_atomic_add {
            extensions.push(ash::ext::shader_atomic_float::NAME.as_ptr());
            f2 = f2.push_next(&mut fa);
        }
        if desc.swapchain {
            extensions.push(ash::khr::swapchain::NAME.as_ptr());
        }
        if c.info.calibrated_timestamps {
            extensions.push(ash::ext::calibrated_timestamps::NAME.as_ptr());
        }
        let priorities = [1.0f32];
        let queues =
            [vk::DeviceQueueCreateInfo::default().queue_family_index(c.queue_family).queue_priorities(&priorities)];
        let info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_extension_names(&extensions)
            .push_next(&mut f2);
        let raw = unsafe { raw_instance.create_device(c.physical, &info, None) }.check("vkCreateDevice")?;
        let queue = unsafe { raw.get_device_queue(c.queue_family, 0) };
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: raw_instance.clone(),
            device: raw.clone(),
            physical_device: c.physical,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        })
        .map_err(|source| {
            unsafe { raw.destroy_device(None) };
            VkError::Alloc { what: "allocator".into(), source }
        })?;
        let push_descriptor = ash::khr::push_descriptor::Device::new(raw_instance, &raw);
        let debug_utils = instance.debug.as_ref().map(|_| ash::ext::debug_utils::Device::new(raw_instance, &raw));
        let calibrated =
            c.info.calibrated_timestamps.then(|| ash::ext::calibrated_timestamps::Device::new(raw_instance, &raw));
        log::info!("device: {} ({}), driver {}", c.info.name, kind_name(c.info.kind), c.info.driver);
        Ok(Arc::new(Device {
            instance,
            raw,
            physical: c.physical,
            info: c.info,
            queue,
            queue_family: c.queue_family,
            push_descriptor,
            debug_utils,
            calibrated,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            owned: true,
            wait_idles: Default::default(),
            retired: Default::default(),
            shared: Default::default(),
        }))
    }

    /// The `T` that a user of this device made and still holds, or a new one from `make`, which later callers get
    /// for as long as some holder keeps it (the renderers' pipelines: a second renderer compiles nothing). Held
    /// weakly: the objects hold the device, and a device that held them would never be dropped.
    pub(crate) fn shared<T: std::any::Any + Send + Sync>(
        &self,
        make: impl FnOnce() -> VkResult<T>,
    ) -> VkResult<Arc<T>> {
        let mut list = self.shared.lock().unwrap_or_else(|e| e.into_inner());
        list.retain(|w| w.strong_count() > 0);
        if let Some(t) = list.iter().filter_map(|w| w.upgrade()?.downcast::<T>().ok()).next() {
            return Ok(t);
        }
        let t = Arc::new(make()?);
        let any: Arc<dyn std::any::Any + Send + Sync> = t.clone();
        list.push(Arc::downgrade(&any));
        Ok(t)
    }

    pub(crate) fn allocator(&self) -> std::sync::MutexGuard<'_, Allocator> {
        // A poisoned lock only means another thread panicked mid-allocation; the allocator itself is still usable.
        self.allocator.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The allocator's live allocations: count, bytes, and the bytes of the memory blocks behind them.
    pub fn allocation_report(&self) -> AllocationTotals {
        let r = self.allocator().generate_report();
        AllocationTotals {
            allocations: r.allocations.len(),
            allocated_bytes: r.total_allocated_bytes,
            capacity_bytes: r.total_capacity_bytes,
        }
    }

    /// Wait until the device is idle.
    pub fn wait_idle(&self) -> VkResult<()> {
        self.wait_idles.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        unsafe { self.raw.device_wait_idle() }.check("vkDeviceWaitIdle")
    }

    /// A list that receives the id of every buffer and image of this device destroyed from now on, for a barrier
    /// tracker to drop their histories.
    pub fn retired_ids(&self) -> std::sync::Arc<Mutex<Vec<u64>>> {
        let list = std::sync::Arc::new(Mutex::new(Vec::new()));
        let mut lists = self.retired.lock().unwrap_or_else(|e| e.into_inner());
        lists.retain(|l| l.strong_count() > 0);
        lists.push(std::sync::Arc::downgrade(&list));
        list
    }

    /// A buffer or image with this id was destroyed: every tracker that asked ([`Device::retired_ids`]) hears of it.
    pub(crate) fn retire(&self, id: u64) {
        let lists = self.retired.lock().unwrap_or_else(|e| e.into_inner());
        for list in lists.iter().filter_map(std::sync::Weak::upgrade) {
            list.lock().unwrap_or_else(|e| e.into_inner()).push(id);
        }
    }

    /// How many times [`Device::wait_idle`] has been called.
    pub fn wait_idle_count(&self) -> u64 {
        self.wait_idles.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Give an object a name in validation messages and debuggers.
    pub fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        if let Some(d) = &self.debug_utils {
            if let Ok(name) = std::ffi::CString::new(name) {
                let info = vk::DebugUtilsObjectNameInfoEXT::default().object_handle(handle).object_name(&name);
                // Naming is best effort: failure only loses a label in validation messages.
                let _ = unsafe { d.set_debug_utils_object_name(&info) };
            }
        }
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        unsafe {
            let _ = self.raw.device_wait_idle();
            ManuallyDrop::drop(&mut self.allocator);
            if self.owned {
                self.raw.destroy_device(None);
            }
        }
    }
}

/// A device type in words.
pub fn kind_name(kind: vk::PhysicalDeviceType) -> &'static str {
    match kind {
        vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
        vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
        vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
        vk::PhysicalDeviceType::CPU => "CPU",
        _ => "other",
    }
}

/// Instance plus device: what a renderer needs.
pub struct Context {
    /// The device (it holds the instance).
    pub device: Arc<Device>,
}

/// A host's Vulkan objects for [`Context::import`]. The host keeps them alive while the context and every renderer
/// on it live, and destroys them itself afterwards.
///
/// The device must have been created with Vulkan 1.3's `synchronization2` and `dynamicRendering` (and, where the
/// device offers them, `vertexPipelineStoresAndAtomics`, `fragmentStoresAndAtomics` and `shaderInt64`), and the
/// `VK_KHR_push_descriptor` extension. With `VK_EXT_shader_atomic_float`'s `shaderBufferFloat32AtomicAdd` and
/// `shaderSharedFloat32AtomicAdd` enabled too, the compute splats run (say so with `float_atomic_add`); without
/// them the photons are drawn as points, which needs the core `largePoints` feature (a wgpu device cannot have it:
/// give it the float atomics, as examples/wgpu.rs does). The queue must support graphics, compute and
/// timestamps; every frame the renderer submits goes to it, and frames recorded into the host's command buffers
/// must be submitted to it.
pub struct Imported {
    /// The loader's entry points.
    pub entry: ash::Entry,
    /// The host's instance.
    pub instance: ash::Instance,
    /// The physical device the host's device was created on.
    pub physical: vk::PhysicalDevice,
    /// The host's device.
    pub device: ash::Device,
    /// The queue the renderer submits to.
    pub queue: vk::Queue,
    /// Its family.
    pub queue_family: u32,
    /// Whether the float-atomic features above are enabled on the device.
    pub float_atomic_add: bool,
}

impl Context {
    /// Create an instance and a device (see [`ContextDesc`]) for headless rendering.
    pub fn headless(desc: &ContextDesc) -> VkResult<Self> {
        let instance = Instance::new(desc)?;
        let device = Device::new(instance, desc, None)?;
        Ok(Context { device })
    }

    /// Wrap a host's instance, device and queue: the renderer allocates its own memory on the host's device and
    /// submits to the host's queue, and leaves the host's objects alone when it is dropped.
    pub fn import(host: Imported) -> VkResult<Self> {
        let Imported { entry, instance, physical, device, queue, queue_family, float_atomic_add } = host;
        let props = unsafe { instance.get_physical_device_properties(physical) };
        if vk::api_version_major(props.api_version) == 1 && vk::api_version_minor(props.api_version) < 3 {
            return Err(VkError::Unsupported("the imported device offers Vulkan 1.2 or older; 1.3 is required".into()));
        }
        if !subgroup_arithmetic(&instance, physical) {
            return Err(VkError::Unsupported(
                "the imported device has no subgroup arithmetic in compute shaders".into(),
            ));
        }
        let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
        let bits = families.get(queue_family as usize).map(|f| f.timestamp_valid_bits).unwrap_or(0);
        if bits == 0 {
            return Err(VkError::Unsupported(format!("queue family {queue_family} has no timestamps")));
        }
        let mut info = describe(&instance, physical, &props, bits, float_atomic_add);
        info.float_atomic_add = float_atomic_add && info.float_atomic_add;
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        })
        .map_err(|source| VkError::Alloc { what: "allocator".into(), source })?;
        let push_descriptor = ash::khr::push_descriptor::Device::new(&instance, &device);
        let instance = Arc::new(Instance { entry, raw: instance, debug: None, validation: false, owned: false });
        log::info!("imported device: {} ({}), driver {}", info.name, kind_name(info.kind), info.driver);
        let device = Arc::new(Device {
            instance,
            raw: device,
            physical,
            info,
            queue,
            queue_family,
            push_descriptor,
            debug_utils: None,
            calibrated: None,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            owned: false,
            wait_idles: Default::default(),
            retired: Default::default(),
            shared: Default::default(),
        });
        Ok(Context { device })
    }
}

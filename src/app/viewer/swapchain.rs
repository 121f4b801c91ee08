//! Window surface and swapchain (VK_KHR_surface, VK_KHR_swapchain): the surface format and present mode, image
//! acquisition and presentation, and recreation with `old_swapchain`.
//!
//! Both are RAII: a [`Swapchain`] holds an `Arc` of its [`Surface`], which holds the instance, so they are
//! destroyed in the right order. Every swapchain and its images are counted while they live ([`live_counts`]), so
//! tests can prove that retired swapchains are destroyed.

use ash::vk;
use caustics::gpu::{Check, VkError, VkResult};
use caustics::gpu::{Device, Instance, COLOR_RANGE};
use raw_window_handle::{RawDisplayHandle, RawWindowHandle};
use std::ffi::CStr;
use std::sync::atomic::{AtomicI64, AtomicU64, Ordering};
use std::sync::Arc;

static LIVE_SWAPCHAINS: AtomicI64 = AtomicI64::new(0);
static LIVE_IMAGES: AtomicI64 = AtomicI64::new(0);
static MAX_LIVE_IMAGES: AtomicI64 = AtomicI64::new(0);
static CREATED_SWAPCHAINS: AtomicU64 = AtomicU64::new(0);

/// Swapchains and swapchain images alive in this process (created and not yet destroyed).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct LiveCounts {
    pub swapchains: i64,
    pub images: i64,
    /// The most images ever alive at once (a recreation briefly holds the retired swapchain and the new one).
    pub max_images: i64,
    /// Swapchains created so far.
    pub created: u64,
}

pub fn live_counts() -> LiveCounts {
    LiveCounts {
        swapchains: LIVE_SWAPCHAINS.load(Ordering::SeqCst),
        images: LIVE_IMAGES.load(Ordering::SeqCst),
        max_images: MAX_LIVE_IMAGES.load(Ordering::SeqCst),
        created: CREATED_SWAPCHAINS.load(Ordering::SeqCst),
    }
}

/// The instance extensions that a surface for this display needs.
pub fn required_instance_extensions(display: RawDisplayHandle) -> VkResult<Vec<&'static CStr>> {
    let names =
        ash_window::enumerate_required_extensions(display).check("ash_window::enumerate_required_extensions")?;
    // ash-window returns pointers to its own 'static extension-name constants.
    Ok(names.iter().map(|&p| unsafe { CStr::from_ptr(p) }).collect())
}

/// A window's surface. The window must outlive it.
pub struct Surface {
    _instance: Arc<Instance>,
    pub loader: ash::khr::surface::Instance,
    pub raw: vk::SurfaceKHR,
}

impl Surface {
    /// # Safety
    /// The handles must belong to a live window that outlives the returned surface.
    pub unsafe fn new(
        instance: &Arc<Instance>,
        display: RawDisplayHandle,
        window: RawWindowHandle,
    ) -> VkResult<Arc<Self>> {
        let raw = ash_window::create_surface(&instance.entry, &instance.raw, display, window, None)
            .check("vkCreate*SurfaceKHR")?;
        let loader = ash::khr::surface::Instance::new(&instance.entry, &instance.raw);
        Ok(Arc::new(Surface { _instance: instance.clone(), loader, raw }))
    }

    /// Whether queue family `family` of `physical` can present to this surface.
    pub fn supports(&self, physical: vk::PhysicalDevice, family: u32) -> bool {
        unsafe { self.loader.get_physical_device_surface_support(physical, family, self.raw) }.unwrap_or(false)
    }

    pub fn capabilities(&self, physical: vk::PhysicalDevice) -> VkResult<vk::SurfaceCapabilitiesKHR> {
        unsafe { self.loader.get_physical_device_surface_capabilities(physical, self.raw) }
            .check("vkGetPhysicalDeviceSurfaceCapabilitiesKHR")
    }
}

impl Drop for Surface {
    fn drop(&mut self) {
        unsafe { self.loader.destroy_surface(self.raw, None) };
    }
}

/// What the caller wants from a swapchain.
#[derive(Clone, Copy, Debug)]
pub struct SwapchainDesc {
    /// The window's size in pixels; used where the surface leaves the extent to the swapchain.
    pub extent: vk::Extent2D,
    /// FIFO (true), or MAILBOX, else IMMEDIATE, where available (false).
    pub vsync: bool,
    /// Testing: rank sRGB formats before UNORM ones (to exercise the sRGB presentation path).
    pub prefer_srgb: bool,
}

/// The 8-bit formats the viewer can fill, UNORM first: the frame's beauty image is already sRGB-encoded, so a
/// UNORM swapchain takes its bytes as they are.
const FORMATS: [vk::Format; 6] = [
    vk::Format::B8G8R8A8_UNORM,
    vk::Format::R8G8B8A8_UNORM,
    vk::Format::A8B8G8R8_UNORM_PACK32,
    vk::Format::B8G8R8A8_SRGB,
    vk::Format::R8G8B8A8_SRGB,
    vk::Format::A8B8G8R8_SRGB_PACK32,
];

pub fn is_srgb(format: vk::Format) -> bool {
    matches!(format, vk::Format::B8G8R8A8_SRGB | vk::Format::R8G8B8A8_SRGB | vk::Format::A8B8G8R8_SRGB_PACK32)
}

/// The UNORM format with the same bytes as `format` (a copy between the two moves bits unchanged).
pub fn unorm_twin(format: vk::Format) -> vk::Format {
    match format {
        vk::Format::B8G8R8A8_SRGB => vk::Format::B8G8R8A8_UNORM,
        vk::Format::R8G8B8A8_SRGB => vk::Format::R8G8B8A8_UNORM,
        vk::Format::A8B8G8R8_SRGB_PACK32 => vk::Format::A8B8G8R8_UNORM_PACK32,
        f => f,
    }
}

/// Whether texels of `format` are stored B, G, R, A in memory (else R, G, B, A).
pub fn is_bgra(format: vk::Format) -> bool {
    matches!(format, vk::Format::B8G8R8A8_UNORM | vk::Format::B8G8R8A8_SRGB)
}

fn choose_format(available: &[vk::SurfaceFormatKHR], prefer_srgb: bool) -> Option<vk::SurfaceFormatKHR> {
    let rank = |f: vk::Format| {
        let i = FORMATS.iter().position(|&x| x == f)?;
        Some(if prefer_srgb { (i + 3) % FORMATS.len() } else { i })
    };
    available
        .iter()
        .filter(|f| f.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR)
        .filter_map(|f| rank(f.format).map(|r| (r, *f)))
        .min_by_key(|(r, _)| *r)
        .map(|(_, f)| f)
}

fn choose_present_mode(available: &[vk::PresentModeKHR], vsync: bool) -> vk::PresentModeKHR {
    // FIFO is the only mode every implementation must support.
    if vsync {
        return vk::PresentModeKHR::FIFO;
    }
    [vk::PresentModeKHR::MAILBOX, vk::PresentModeKHR::IMMEDIATE]
        .into_iter()
        .find(|m| available.contains(m))
        .unwrap_or(vk::PresentModeKHR::FIFO)
}

/// The result of an acquire.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Acquired {
    /// The image index; `suboptimal` asks for a recreation after this frame.
    Image { index: u32, suboptimal: bool },
    /// The swapchain no longer matches the surface: recreate it; no semaphore was signalled.
    OutOfDate,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Presented {
    Optimal,
    /// Presented, but the swapchain should be recreated.
    Suboptimal,
    /// Not presented: the swapchain must be recreated.
    OutOfDate,
}

/// The most frames the viewer keeps in flight (one acquire semaphore each).
pub const MAX_FRAMES_IN_FLIGHT: usize = 3;

/// How long an acquire may block before it is reported as an error rather than waited on forever.
pub const ACQUIRE_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(10);

pub struct Swapchain {
    device: Arc<Device>,
    pub surface: Arc<Surface>,
    loader: ash::khr::swapchain::Device,
    pub raw: vk::SwapchainKHR,
    pub images: Vec<vk::Image>,
    /// A view of each image where the overlay can be drawn into it (COLOR_ATTACHMENT usage, a UNORM format), else
    /// none: the overlay is drawn into the presenter's intermediate image.
    pub views: Vec<vk::ImageView>,
    pub format: vk::SurfaceFormatKHR,
    pub extent: vk::Extent2D,
    pub present_mode: vk::PresentModeKHR,
    pub usage: vk::ImageUsageFlags,
    /// Signalled by an acquire, waited on by the frame's submit: one per frame in flight. The caller acquires with
    /// slot `s`'s semaphore only after the frame that last used slot `s` has finished (its fence), so the semaphore
    /// has no pending wait when it is signalled again.
    pub acquire_semaphores: Vec<vk::Semaphore>,
    /// One per image, signalled by the frame's submit and waited on by the present: a present's wait is known to
    /// be over only when its image is acquired again.
    pub render_done: Vec<vk::Semaphore>,
    desc: SwapchainDesc,
}

impl Swapchain {
    /// Create a swapchain, or None when the surface has a zero extent (a minimized window).
    pub fn new(device: &Arc<Device>, surface: &Arc<Surface>, desc: SwapchainDesc) -> VkResult<Option<Self>> {
        Self::create(device, surface, desc, vk::SwapchainKHR::null())
    }

    /// The extent a swapchain would get now, or None when it would be zero.
    pub fn current_extent(
        device: &Device,
        surface: &Surface,
        window: vk::Extent2D,
    ) -> VkResult<Option<(vk::Extent2D, vk::SurfaceCapabilitiesKHR)>> {
        let caps = surface.capabilities(device.physical)?;
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: window.width.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: window.height.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        Ok((extent.width > 0 && extent.height > 0).then_some((extent, caps)))
    }

    fn create(
        device: &Arc<Device>,
        surface: &Arc<Surface>,
        desc: SwapchainDesc,
        old: vk::SwapchainKHR,
    ) -> VkResult<Option<Self>> {
        let Some((extent, caps)) = Self::current_extent(device, surface, desc.extent)? else {
            return Ok(None);
        };
        let formats = unsafe { surface.loader.get_physical_device_surface_formats(device.physical, surface.raw) }
            .check("vkGetPhysicalDeviceSurfaceFormatsKHR")?;
        let format = choose_format(&formats, desc.prefer_srgb).ok_or_else(|| {
            VkError::Unsupported(format!(
                "the window surface offers no 8-bit RGBA/BGRA format in the sRGB color space (offered: {:?})",
                formats.iter().map(|f| (f.format, f.color_space)).collect::<Vec<_>>()
            ))
        })?;
        let modes = unsafe { surface.loader.get_physical_device_surface_present_modes(device.physical, surface.raw) }
            .check("vkGetPhysicalDeviceSurfacePresentModesKHR")?;
        let present_mode = choose_present_mode(&modes, desc.vsync);
        if !caps.supported_usage_flags.contains(vk::ImageUsageFlags::TRANSFER_DST) {
            return Err(VkError::Unsupported(
                "swapchain images do not support TRANSFER_DST (needed for the blit)".into(),
            ));
        }
        // TRANSFER_SRC lets screenshots copy the presented image itself; COLOR_ATTACHMENT, the overlay draw into it.
        let optional = vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::COLOR_ATTACHMENT;
        let usage = vk::ImageUsageFlags::TRANSFER_DST | (caps.supported_usage_flags & optional);
        let mut count = caps.min_image_count.max(2);
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let alpha = [
            vk::CompositeAlphaFlagsKHR::OPAQUE,
            vk::CompositeAlphaFlagsKHR::INHERIT,
            vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED,
            vk::CompositeAlphaFlagsKHR::POST_MULTIPLIED,
        ]
        .into_iter()
        .find(|a| caps.supported_composite_alpha.contains(*a))
        .unwrap_or(vk::CompositeAlphaFlagsKHR::OPAQUE);
        let transform = if caps.supported_transforms.contains(vk::SurfaceTransformFlagsKHR::IDENTITY) {
            vk::SurfaceTransformFlagsKHR::IDENTITY
        } else {
            caps.current_transform
        };
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(surface.raw)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(transform)
            .composite_alpha(alpha)
            .present_mode(present_mode)
            .clipped(true)
            .old_swapchain(old);
        let loader = ash::khr::swapchain::Device::new(&device.instance.raw, device);
        let raw = unsafe { loader.create_swapchain(&info, None) }.check("vkCreateSwapchainKHR")?;
        let images = match unsafe { loader.get_swapchain_images(raw) } {
            Ok(images) => images,
            Err(e) => {
                unsafe { loader.destroy_swapchain(raw, None) };
                return Err(e).check("vkGetSwapchainImagesKHR");
            }
        };
        LIVE_SWAPCHAINS.fetch_add(1, Ordering::SeqCst);
        CREATED_SWAPCHAINS.fetch_add(1, Ordering::SeqCst);
        let live = LIVE_IMAGES.fetch_add(images.len() as i64, Ordering::SeqCst) + images.len() as i64;
        MAX_LIVE_IMAGES.fetch_max(live, Ordering::SeqCst);
        // From here on, Drop cleans up whatever was created (null semaphores are skipped).
        let mut swapchain = Swapchain {
            device: device.clone(),
            surface: surface.clone(),
            loader,
            raw,
            images,
            views: Vec::new(),
            format,
            extent,
            present_mode,
            usage,
            acquire_semaphores: Vec::new(),
            render_done: Vec::new(),
            desc,
        };
        for (i, image) in swapchain.images.iter().enumerate() {
            device.set_name(*image, &format!("swapchain image {i}"));
        }
        if usage.contains(vk::ImageUsageFlags::COLOR_ATTACHMENT) && !is_srgb(format.format) {
            for i in 0..swapchain.images.len() {
                let info = vk::ImageViewCreateInfo::default()
                    .image(swapchain.images[i])
                    .view_type(vk::ImageViewType::TYPE_2D)
                    .format(format.format)
                    .subresource_range(COLOR_RANGE);
                let view = unsafe { device.create_image_view(&info, None) }.check("vkCreateImageView")?;
                swapchain.views.push(view);
            }
        }
        for slot in 0..MAX_FRAMES_IN_FLIGHT {
            let s = swapchain.semaphore(&format!("acquire {slot}"))?;
            swapchain.acquire_semaphores.push(s);
        }
        for i in 0..swapchain.images.len() {
            let s = swapchain.semaphore(&format!("render done {i}"))?;
            swapchain.render_done.push(s);
        }
        Ok(Some(swapchain))
    }

    fn semaphore(&self, name: &str) -> VkResult<vk::Semaphore> {
        let s = unsafe { self.device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }
            .check("vkCreateSemaphore")?;
        self.device.set_name(s, name);
        Ok(s)
    }

    /// Replace this swapchain by a new one for the surface's current extent, passing this one as
    /// `old_swapchain`; the retired one is destroyed (after the device is idle). Returns false, keeping this
    /// swapchain, when the extent is zero.
    pub fn recreate(&mut self, window: vk::Extent2D) -> VkResult<bool> {
        let desc = SwapchainDesc { extent: window, ..self.desc };
        if Self::current_extent(&self.device, &self.surface, window)?.is_none() {
            return Ok(false);
        }
        // Nothing of this frame's may still use the retired swapchain's images or semaphores when it is destroyed.
        self.device.wait_idle()?;
        match Self::create(&self.device, &self.surface, desc, self.raw)? {
            Some(new) => {
                drop(std::mem::replace(self, new));
                Ok(true)
            }
            None => Ok(false),
        }
    }

    /// Acquire the next image for the frame in flight `slot`, signalling its semaphore
    /// (`acquire_semaphores[slot]`).
    pub fn acquire(&self, slot: usize) -> VkResult<Acquired> {
        let timeout = ACQUIRE_TIMEOUT.as_nanos() as u64;
        let semaphore = self.acquire_semaphores[slot % self.acquire_semaphores.len()];
        match unsafe { self.loader.acquire_next_image(self.raw, timeout, semaphore, vk::Fence::null()) } {
            Ok((index, suboptimal)) => Ok(Acquired::Image { index, suboptimal }),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Acquired::OutOfDate),
            Err(vk::Result::TIMEOUT) | Err(vk::Result::NOT_READY) => Err(VkError::Unsupported(format!(
                "no swapchain image became available within {} s (the presentation engine is stuck)",
                ACQUIRE_TIMEOUT.as_secs()
            ))),
            Err(e) => Err(e).check("vkAcquireNextImageKHR"),
        }
    }

    /// Present image `index` once its `render_done` semaphore is signalled.
    pub fn present(&self, index: u32) -> VkResult<Presented> {
        let waits = [self.render_done[index as usize]];
        let swapchains = [self.raw];
        let indices = [index];
        let info =
            vk::PresentInfoKHR::default().wait_semaphores(&waits).swapchains(&swapchains).image_indices(&indices);
        match unsafe { self.loader.queue_present(self.device.queue, &info) } {
            Ok(false) => Ok(Presented::Optimal),
            Ok(true) => Ok(Presented::Suboptimal),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Presented::OutOfDate),
            Err(e) => Err(e).check("vkQueuePresentKHR"),
        }
    }
}

impl Drop for Swapchain {
    fn drop(&mut self) {
        unsafe {
            // A present may still wait on the semaphores, and the images may still be read or written.
            let _ = self.device.wait_idle();
            for s in self.render_done.drain(..).chain(self.acquire_semaphores.drain(..)) {
                if s != vk::Semaphore::null() {
                    self.device.destroy_semaphore(s, None);
                }
            }
            for v in self.views.drain(..) {
                self.device.destroy_image_view(v, None);
            }
            self.loader.destroy_swapchain(self.raw, None);
        }
        LIVE_SWAPCHAINS.fetch_sub(1, Ordering::SeqCst);
        LIVE_IMAGES.fetch_sub(self.images.len() as i64, Ordering::SeqCst);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f(format: vk::Format) -> vk::SurfaceFormatKHR {
        vk::SurfaceFormatKHR { format, color_space: vk::ColorSpaceKHR::SRGB_NONLINEAR }
    }

    #[test]
    fn unorm_is_preferred_and_srgb_on_request() {
        let offered = [f(vk::Format::B8G8R8A8_SRGB), f(vk::Format::B8G8R8A8_UNORM)];
        assert_eq!(choose_format(&offered, false).unwrap().format, vk::Format::B8G8R8A8_UNORM);
        assert_eq!(choose_format(&offered, true).unwrap().format, vk::Format::B8G8R8A8_SRGB);
        assert_eq!(choose_format(&offered[..1], false).unwrap().format, vk::Format::B8G8R8A8_SRGB);
        assert!(choose_format(&[f(vk::Format::R16G16B16A16_SFLOAT)], false).is_none());
    }

    #[test]
    fn present_modes() {
        use vk::PresentModeKHR as M;
        let all = [M::IMMEDIATE, M::MAILBOX, M::FIFO, M::FIFO_RELAXED];
        assert_eq!(choose_present_mode(&all, true), M::FIFO);
        assert_eq!(choose_present_mode(&all, false), M::MAILBOX);
        assert_eq!(choose_present_mode(&[M::FIFO, M::IMMEDIATE], false), M::IMMEDIATE);
        assert_eq!(choose_present_mode(&[M::FIFO], false), M::FIFO);
    }
}

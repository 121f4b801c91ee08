//! Pipelines with one push-descriptor set (VK_KHR_push_descriptor) and a push-constant block, both reflected from
//! the pipeline's SPIR-V: the shaders are the layout's only source. A pass binds a [`Use`](super::Use) per binding,
//! in the order of the binding constants both sides name (src/shader_consts.rs; [`ordered`]), and each use is
//! checked against what the shaders declare there.

use super::buffer::Buffer;
use super::context::Device;
use super::error::{Check, VkError, VkResult};
use super::image::{Image, Sampler};
use ash::vk;
use std::sync::Arc;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BindKind {
    Uniform,
    Storage,
    /// Combined image sampler.
    Sampled,
    StorageImage,
    /// Uniform texel buffer: a buffer read through its texel view ([`crate::vk::Buffer::with_texel_view`]).
    Texels,
}

impl BindKind {
    fn descriptor_type(self) -> vk::DescriptorType {
        match self {
            BindKind::Uniform => vk::DescriptorType::UNIFORM_BUFFER,
            BindKind::Storage => vk::DescriptorType::STORAGE_BUFFER,
            BindKind::Sampled => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            BindKind::StorageImage => vk::DescriptorType::STORAGE_IMAGE,
            BindKind::Texels => vk::DescriptorType::UNIFORM_TEXEL_BUFFER,
        }
    }
}

/// Whether a binding list names its bindings 0, 1, 2, ... in order: the lists in src/passes/ pair each entry with its
/// index constant (src/shader_consts.rs, the same macro the GLSL declares it with), and a const assertion holds
/// the order, so that Rust and GLSL cannot drift.
pub const fn bindings_in_order<T>(entries: &[(u32, T)]) -> bool {
    let mut i = 0;
    while i < entries.len() {
        if entries[i].0 != i as u32 {
            return false;
        }
        i += 1;
    }
    true
}

/// The binds of a list in binding order, checked against its index constants.
pub fn ordered<T, const N: usize>(entries: [(u32, T); N]) -> [T; N] {
    assert!(bindings_in_order(&entries), "a binding list out of its index order");
    entries.map(|(_, b)| b)
}

/// A resource bound at record time.
#[derive(Clone, Copy)]
pub enum Bind<'a> {
    Uniform(&'a Buffer),
    Storage(&'a Buffer),
    /// Sampled image in SHADER_READ_ONLY_OPTIMAL.
    Sampled(&'a Image, &'a Sampler),
    /// Storage image in GENERAL.
    StorageImage(&'a Image),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blend {
    None,
    /// dst += src: flux accumulation in the caustic map.
    Additive,
    /// Nothing written (an empty write mask): a depth-only draw inside a pass that has color targets.
    Masked,
    /// Premultiplied color over the target: dst = src + (1 − src.a) dst (the viewer's overlay).
    Over,
}

#[derive(Clone, Copy, Debug)]
pub struct ColorTarget {
    pub format: vk::Format,
    pub blend: Blend,
}

pub struct GraphicsDesc<'a> {
    pub vertex: &'a [u32],
    pub fragment: &'a [u32],
    /// Interleaved vertex attributes, as (format, offset); stride in `vertex_stride`. Empty: no vertex buffer.
    pub vertex_attributes: &'a [(vk::Format, u32)],
    pub vertex_stride: u32,
    pub topology: vk::PrimitiveTopology,
    pub cull: vk::CullModeFlags,
    pub depth: Option<(vk::Format, vk::CompareOp, bool)>,
    pub colors: &'a [ColorTarget],
}

pub struct Pipeline {
    pub(super) device: Arc<Device>,
    pub raw: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    pub bind_point: vk::PipelineBindPoint,
    /// What its shaders declare: each binding's kind, whether they write it and its name, and the push block.
    pub(super) iface: Interface,
    /// Its name in messages.
    pub(super) name: String,
    push_stages: vk::ShaderStageFlags,
}

struct Module<'a> {
    device: &'a Device,
    raw: vk::ShaderModule,
}

impl<'a> Module<'a> {
    fn new(device: &'a Device, spv: &[u32]) -> VkResult<Self> {
        let info = vk::ShaderModuleCreateInfo::default().code(spv);
        let raw = unsafe { device.create_shader_module(&info, None) }.check("vkCreateShaderModule")?;
        Ok(Module { device, raw })
    }
}

impl Drop for Module<'_> {
    fn drop(&mut self) {
        unsafe { self.device.destroy_shader_module(self.raw, None) };
    }
}

/// Layout objects that clean up after themselves if pipeline creation fails part-way.
struct Layouts<'a> {
    device: &'a Device,
    set: vk::DescriptorSetLayout,
    pipeline: vk::PipelineLayout,
}

/// What a pipeline's shaders declare, reflected from their SPIR-V: the layout's only source.
pub(super) struct Interface {
    /// Per binding of set 0, its kind, or `None` where no shader declares it.
    pub(super) kinds: Vec<Option<BindKind>>,
    /// Per binding, whether one of the shaders' code writes it (stores, atomics, image writes through it, read from
    /// the SPIR-V as the validation layers read it; a binding declared `readonly` never is).
    pub(super) written: Vec<bool>,
    /// Per binding, the name the shaders give it (the variable, or a block without an instance name).
    pub(super) names: Vec<String>,
    /// The push-constant block the shaders share, if any.
    pub(super) push: Option<super::spirv::PushBlock>,
}

/// Reflects a pipeline's layout from its shaders and checks it against the device's limits. Every descriptor is in
/// set 0 and is of a kind this crate binds; shaders of one pipeline that declare a binding or the push block
/// differently are refused. A mismatch is this crate's defect, and the error names the pipeline and the binding;
/// the device's limit is named by its Vulkan name.
fn reflect(device: &Device, name: &str, shaders: &[&[u32]]) -> VkResult<Interface> {
    use super::spirv::{Descriptor, Module};
    let fail = |m: String| VkError::Interface(format!("pipeline {name}: {m}"));
    let mut me = Interface { kinds: Vec::new(), written: Vec::new(), names: Vec::new(), push: None };
    for words in shaders {
        let module = Module::parse(words).map_err(fail)?;
        for (&(set, binding), (declared, var)) in &module.bindings {
            let kind = match declared {
                Descriptor::Uniform => BindKind::Uniform,
                Descriptor::Storage => BindKind::Storage,
                Descriptor::Sampled => BindKind::Sampled,
                Descriptor::StorageImage => BindKind::StorageImage,
                Descriptor::UniformTexel => BindKind::Texels,
                Descriptor::StorageTexel => {
                    return Err(fail(format!("`{var}` (binding {binding}) is a storage texel buffer: not bound here")))
                }
            };
            if set != 0 {
                return Err(fail(format!("`{var}` is in set {set}: every binding is in set 0")));
            }
            let b = binding as usize;
            if me.kinds.len() <= b {
                me.kinds.resize(b + 1, None);
                me.written.resize(b + 1, false);
                me.names.resize(b + 1, String::new());
            }
            if me.kinds[b].is_some_and(|k| k != kind) {
                return Err(fail(format!(
                    "its shaders declare binding {binding} as {:?} (`{}`) and as {kind:?} (`{var}`)",
                    me.kinds[b].unwrap_or(kind),
                    me.names[b]
                )));
            }
            me.kinds[b] = Some(kind);
            me.written[b] |= module.written.contains(&(set, binding));
            me.names[b] = var.clone();
        }
        if let Some(push) = module.push {
            if me.push.as_ref().is_some_and(|p| *p != push) {
                return Err(fail(format!("its shaders declare push blocks {:?} and {push:?}", me.push)));
            }
            me.push = Some(push);
        }
    }
    let limits = &device.info.limits;
    let count = me.kinds.iter().flatten().count();
    if count as u32 > device.info.max_push_descriptors {
        return Err(VkError::Unsupported(format!(
            "pipeline {name}: its layout binds {count} push descriptors; {} allows {} (maxPushDescriptors)",
            device.info.name, device.info.max_push_descriptors
        )));
    }
    let push_size = me.push_size();
    if push_size > limits.max_push_constants_size {
        return Err(VkError::Unsupported(format!(
            "pipeline {name}: {push_size} bytes of push constants; {} allows {} (maxPushConstantsSize)",
            device.info.name, limits.max_push_constants_size
        )));
    }
    Ok(me)
}

impl<'a> Layouts<'a> {
    fn new(
        device: &'a Device,
        kinds: &[Option<BindKind>],
        stages: vk::ShaderStageFlags,
        push_size: u32,
    ) -> VkResult<Self> {
        let bindings: Vec<_> = kinds
            .iter()
            .enumerate()
            .filter_map(|(i, k)| k.map(|k| (i, k)))
            .map(|(i, k)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(i as u32)
                    .descriptor_type(k.descriptor_type())
                    .descriptor_count(1)
                    .stage_flags(stages)
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default()
            .flags(vk::DescriptorSetLayoutCreateFlags::PUSH_DESCRIPTOR_KHR)
            .bindings(&bindings);
        let set = unsafe { device.create_descriptor_set_layout(&info, None) }.check("vkCreateDescriptorSetLayout")?;
        let mut me = Layouts { device, set, pipeline: vk::PipelineLayout::null() };
        let sets = [set];
        let ranges = [vk::PushConstantRange { stage_flags: stages, offset: 0, size: push_size }];
        let mut info = vk::PipelineLayoutCreateInfo::default().set_layouts(&sets);
        if push_size > 0 {
            info = info.push_constant_ranges(&ranges);
        }
        me.pipeline = unsafe { device.create_pipeline_layout(&info, None) }.check("vkCreatePipelineLayout")?;
        Ok(me)
    }

    fn release(mut self) -> (vk::DescriptorSetLayout, vk::PipelineLayout) {
        let out = (self.set, self.pipeline);
        self.set = vk::DescriptorSetLayout::null();
        self.pipeline = vk::PipelineLayout::null();
        out
    }
}

impl Drop for Layouts<'_> {
    fn drop(&mut self) {
        unsafe {
            if self.pipeline != vk::PipelineLayout::null() {
                self.device.destroy_pipeline_layout(self.pipeline, None);
            }
            if self.set != vk::DescriptorSetLayout::null() {
                self.device.destroy_descriptor_set_layout(self.set, None);
            }
        }
    }
}

impl Pipeline {
    pub fn compute(device: &Arc<Device>, name: &str, spv: &[u32]) -> VkResult<Self> {
        Self::compute_specialized(device, name, spv, &[])
    }

    /// A compute pipeline whose specialization constants take the values `spec` gives, as (constant_id, value)
    /// pairs (32-bit each: a `bool` constant takes 0 or 1). The driver folds them before it compiles, so a branch
    /// on one costs nothing, not even on a CPU driver that runs both sides of every branch under a mask.
    pub fn compute_specialized(device: &Arc<Device>, name: &str, spv: &[u32], spec: &[(u32, u32)]) -> VkResult<Self> {
        let stages = vk::ShaderStageFlags::COMPUTE;
        let iface = reflect(device, name, &[spv])?;
        let layouts = Layouts::new(device, &iface.kinds, stages, iface.push_size())?;
        let module = Module::new(device, spv)?;
        let entries: Vec<vk::SpecializationMapEntry> = (0..spec.len() as u32)
            .map(|i| vk::SpecializationMapEntry { constant_id: spec[i as usize].0, offset: 4 * i, size: 4 })
            .collect();
        let values: Vec<u32> = spec.iter().map(|&(_, v)| v).collect();
        let spec_info = vk::SpecializationInfo::default().map_entries(&entries).data(bytemuck::cast_slice(&values));
        let mut stage = vk::PipelineShaderStageCreateInfo::default().stage(stages).module(module.raw).name(c"main");
        if !spec.is_empty() {
            stage = stage.specialization_info(&spec_info);
        }
        let info = vk::ComputePipelineCreateInfo::default().stage(stage).layout(layouts.pipeline);
        let raw = unsafe { device.create_compute_pipelines(vk::PipelineCache::null(), &[info], None) }
            .map_err(|(_, e)| e)
            .check("vkCreateComputePipelines")?[0];
        device.set_name(raw, name);
        let (set_layout, layout) = layouts.release();
        Ok(Pipeline {
            device: device.clone(),
            raw,
            layout,
            set_layout,
            bind_point: vk::PipelineBindPoint::COMPUTE,
            iface,
            name: name.to_string(),
            push_stages: stages,
        })
    }

    pub fn graphics(device: &Arc<Device>, name: &str, desc: &GraphicsDesc) -> VkResult<Self> {
        let stages = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT;
        let iface = reflect(device, name, &[desc.vertex, desc.fragment])?;
        let layouts = Layouts::new(device, &iface.kinds, stages, iface.push_size())?;
        let vs = Module::new(device, desc.vertex)?;
        let fs = Module::new(device, desc.fragment)?;
        let shader_stages = [
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::VERTEX)
                .module(vs.raw)
                .name(c"main"),
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::FRAGMENT)
                .module(fs.raw)
                .name(c"main"),
        ];
        let vb = [vk::VertexInputBindingDescription {
            binding: 0,
            stride: desc.vertex_stride,
            input_rate: vk::VertexInputRate::VERTEX,
        }];
        let attrs: Vec<_> = desc
            .vertex_attributes
            .iter()
            .enumerate()
            .map(|(i, (format, offset))| vk::VertexInputAttributeDescription {
                location: i as u32,
                binding: 0,
                format: *format,
                offset: *offset,
            })
            .collect();
        let mut vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
        if !attrs.is_empty() {
            vertex_input = vertex_input.vertex_binding_descriptions(&vb).vertex_attribute_descriptions(&attrs);
        }
        let assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(desc.topology);
        let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(desc.cull)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let multisample =
            vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let (depth_format, depth_state) = match desc.depth {
            Some((format, op, write)) => (
                format,
                vk::PipelineDepthStencilStateCreateInfo::default()
                    .depth_test_enable(true)
                    .depth_write_enable(write)
                    .depth_compare_op(op),
            ),
            None => (vk::Format::UNDEFINED, vk::PipelineDepthStencilStateCreateInfo::default()),
        };
        let blends: Vec<_> = desc
            .colors
            .iter()
            .map(|c| {
                let b =
                    vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA);
                match c.blend {
                    Blend::None => b,
                    Blend::Masked => b.color_write_mask(vk::ColorComponentFlags::empty()),
                    Blend::Additive => b
                        .blend_enable(true)
                        .src_color_blend_factor(vk::BlendFactor::ONE)
                        .dst_color_blend_factor(vk::BlendFactor::ONE)
                        .color_blend_op(vk::BlendOp::ADD)
                        .src_alpha_blend_factor(vk::BlendFactor::ONE)
                        .dst_alpha_blend_factor(vk::BlendFactor::ONE)
                        .alpha_blend_op(vk::BlendOp::ADD),
                    Blend::Over => b
                        .blend_enable(true)
                        .src_color_blend_factor(vk::BlendFactor::ONE)
                        .dst_color_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
                        .color_blend_op(vk::BlendOp::ADD)
                        .src_alpha_blend_factor(vk::BlendFactor::ONE)
                        .dst_alpha_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
                        .alpha_blend_op(vk::BlendOp::ADD),
                }
            })
            .collect();
        let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blends);
        let dynamic = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic_state = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic);
        let color_formats: Vec<_> = desc.colors.iter().map(|c| c.format).collect();
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(&color_formats)
            .depth_attachment_format(depth_format);
        let info = vk::GraphicsPipelineCreateInfo::default()
            .stages(&shader_stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth_state)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic_state)
            .layout(layouts.pipeline)
            .push_next(&mut rendering);
        let raw = unsafe { device.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None) }
            .map_err(|(_, e)| e)
            .check("vkCreateGraphicsPipelines")?[0];
        device.set_name(raw, name);
        let (set_layout, layout) = layouts.release();
        Ok(Pipeline {
            device: device.clone(),
            raw,
            layout,
            set_layout,
            bind_point: vk::PipelineBindPoint::GRAPHICS,
            iface,
            name: name.to_string(),
            push_stages: stages,
        })
    }

    /// [`Pipeline::bind`], after checking that every buffer bound to a texel-buffer binding has its texel view (an
    /// error names the one that has none).
    pub fn bind_checked(&self, cmd: vk::CommandBuffer, binds: &[Bind]) -> VkResult<()> {
        for (b, kind) in binds.iter().zip(&self.iface.kinds) {
            if let (Bind::Uniform(buf) | Bind::Storage(buf), Some(BindKind::Texels)) = (b, kind) {
                buf.texel_view()?;
            }
        }
        self.bind(cmd, binds);
        Ok(())
    }

    /// Bind the pipeline and push its descriptors (binding i = binds[i]; a binding no shader of the pipeline
    /// declares is left out). A buffer bound where the shaders declare a texel buffer (a variant that reads it as
    /// texels, where the others read it as storage) is bound through its texel view.
    pub fn bind(&self, cmd: vk::CommandBuffer, binds: &[Bind]) {
        let kinds = &self.iface.kinds;
        assert!(binds.len() >= kinds.len(), "pipeline {}: binding {} has nothing bound", self.name, binds.len());
        let mut buffer_infos = Vec::with_capacity(binds.len());
        let mut image_infos = Vec::with_capacity(binds.len());
        let mut texel_views = Vec::with_capacity(binds.len());
        let present: Vec<(usize, &Bind, BindKind)> =
            binds.iter().zip(kinds).enumerate().filter_map(|(i, (b, k))| k.map(|k| (i, b, k))).collect();
        for &(_, b, kind) in &present {
            match b {
                Bind::Uniform(buf) | Bind::Storage(buf) if kind == BindKind::Texels => {
                    debug_assert!(buf.texels != vk::BufferView::null(), "buffer `{}` has no texel view", buf.name);
                    texel_views.push(buf.texels)
                }
                Bind::Uniform(buf) | Bind::Storage(buf) => {
                    buffer_infos.push(vk::DescriptorBufferInfo { buffer: buf.raw, offset: 0, range: vk::WHOLE_SIZE })
                }
                Bind::Sampled(img, sampler) => image_infos.push(vk::DescriptorImageInfo {
                    sampler: sampler.raw,
                    image_view: img.view,
                    image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                }),
                Bind::StorageImage(img) => image_infos.push(vk::DescriptorImageInfo {
                    sampler: vk::Sampler::null(),
                    image_view: img.view,
                    image_layout: vk::ImageLayout::GENERAL,
                }),
            }
        }
        let (mut bi, mut ii, mut ti) = (0, 0, 0);
        let writes: Vec<_> = present
            .iter()
            .map(|&(i, b, kind)| {
                let w = vk::WriteDescriptorSet::default().dst_binding(i as u32).descriptor_type(kind.descriptor_type());
                match b {
                    Bind::Uniform(_) | Bind::Storage(_) if kind == BindKind::Texels => {
                        ti += 1;
                        w.texel_buffer_view(std::slice::from_ref(&texel_views[ti - 1]))
                    }
                    Bind::Uniform(_) | Bind::Storage(_) => {
                        bi += 1;
                        w.buffer_info(std::slice::from_ref(&buffer_infos[bi - 1]))
                    }
                    Bind::Sampled(..) | Bind::StorageImage(_) => {
                        ii += 1;
                        w.image_info(std::slice::from_ref(&image_infos[ii - 1]))
                    }
                }
            })
            .collect();
        unsafe {
            self.device.cmd_bind_pipeline(cmd, self.bind_point, self.raw);
            if !writes.is_empty() {
                self.device.push_descriptor.cmd_push_descriptor_set(cmd, self.bind_point, self.layout, 0, &writes);
            }
        }
    }

    /// Push `data` as the pipeline's push constants: a value of the Rust struct the shaders' push block holds
    /// (src/gpu_types.rs, from which the build generates the GLSL struct), checked by its name and size.
    pub fn push<T: bytemuck::Pod>(&self, cmd: vk::CommandBuffer, data: &T) {
        let ty = std::any::type_name::<T>().rsplit("::").next().unwrap_or_default();
        let push = self.iface.push.as_ref();
        assert!(
            push.is_some_and(|p| p.name == ty && p.size as usize == std::mem::size_of::<T>()),
            "pipeline {}: pushes a {ty} of {} bytes; its shaders' push block is {push:?}",
            self.name,
            std::mem::size_of::<T>()
        );
        unsafe { self.device.cmd_push_constants(cmd, self.layout, self.push_stages, 0, bytemuck::bytes_of(data)) };
    }
}

impl Pipeline {
    /// The bindings its shaders' code writes (stores, atomics, image writes), as the SPIR-V says: every other
    /// binding it declares, it only reads.
    #[cfg(test)]
    pub fn writes(&self) -> Vec<u32> {
        (0..self.iface.written.len() as u32).filter(|&b| self.iface.written[b as usize]).collect()
    }
}

impl Interface {
    fn push_size(&self) -> u32 {
        self.push.as_ref().map_or(0, |p| p.size)
    }
}

impl Drop for Pipeline {
    fn drop(&mut self) {
        unsafe {
            self.device.destroy_pipeline(self.raw, None);
            self.device.destroy_pipeline_layout(self.layout, None);
            self.device.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

/// A pipeline built the first time a frame needs it: a renderer holds every variant it might run (traversal per
/// metric and work-group side, the waves per BVH layout, the splats, the composites), and a frame runs a few.
pub struct LazyPipeline {
    cell: std::sync::OnceLock<Pipeline>,
    make: Box<dyn Fn() -> VkResult<Pipeline> + Send + Sync>,
}

impl LazyPipeline {
    pub fn new(make: impl Fn() -> VkResult<Pipeline> + Send + Sync + 'static) -> Self {
        LazyPipeline { cell: std::sync::OnceLock::new(), make: Box::new(make) }
    }

    /// A compute pipeline of `spv` (its layout reflected from it).
    pub fn compute(device: &Arc<Device>, name: &str, spv: &'static [u32]) -> Self {
        Self::compute_specialized(device, name, spv, &[])
    }

    /// The same with specialization constants ([`Pipeline::compute_specialized`]).
    pub fn compute_specialized(device: &Arc<Device>, name: &str, spv: &'static [u32], spec: &[(u32, u32)]) -> Self {
        let (device, name, spec) = (device.clone(), name.to_string(), spec.to_vec());
        Self::new(move || Pipeline::compute_specialized(&device, &name, spv, &spec))
    }

    /// The pipeline, built now if no frame has needed it yet.
    pub fn get(&self) -> VkResult<&Pipeline> {
        if let Some(p) = self.cell.get() {
            return Ok(p);
        }
        let p = (self.make)()?;
        built_pipelines().fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        Ok(self.cell.get_or_init(|| p))
    }
}

/// Pipelines built lazily in this process so far (start-up measurements).
pub fn built_pipelines() -> &'static std::sync::atomic::AtomicUsize {
    static BUILT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    &BUILT
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shaders;

    #[test]
    fn a_pipeline_takes_its_layout_and_push_block_from_its_shaders() {
        let desc = crate::vk::ContextDesc { validation: true, ..crate::vk::ContextDesc::from_env() };
        let device = crate::vk::Context::headless(&desc).expect("a Vulkan device").device;
        let p = Pipeline::compute(&device, "resolve", shaders::RESOLVE_COMP.words()).expect("pipeline");
        let sampled = Some(BindKind::Sampled);
        assert_eq!(p.iface.kinds, [Some(BindKind::Uniform), sampled, sampled, Some(BindKind::StorageImage)]);
        assert_eq!(p.iface.names[1], "t_flux");
        assert_eq!(p.iface.written, [false, false, false, true]);
        let push = p.iface.push.as_ref().expect("a push block");
        assert_eq!((push.name.as_str(), push.size), ("ResolvePush", 8));
        // The texel variant reads binding 1 as a texel buffer (a `samplerBuffer`).
        let texels = Pipeline::compute(&device, "resolve, texels", shaders::RESOLVE_COMP_TEXELS.words()).unwrap();
        assert_eq!(texels.iface.kinds[1], Some(BindKind::Texels));
        let step = Pipeline::compute(&device, "water step", shaders::WATER_STEP_COMP.words()).unwrap();
        let size = std::mem::size_of::<crate::gpu_types::WaterStepPush>() as u32;
        assert_eq!((step.iface.kinds.len(), step.iface.push.as_ref().map(|p| p.size)), (1, Some(size)));
        // Push constants of another type, or of another size, are refused with the block named.
        let cmd = vk::CommandBuffer::null();
        let e = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| p.push(cmd, &1u32))).expect_err("refused");
        let message = e.downcast_ref::<String>().expect("a message");
        assert!(message.contains("pushes a u32 of 4 bytes") && message.contains("ResolvePush"), "{message}");
        let e = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            p.push(cmd, &crate::gpu_types::ShadePush { add: 1 })
        }))
        .expect_err("refused");
        let message = e.downcast_ref::<String>().expect("a message");
        assert!(message.contains("pushes a ShadePush"), "{message}");
        // A shader's push block's size is read from the SPIR-V's offsets and types.
        let wave = Pipeline::compute(&device, "wave", shaders::WAVE_COMP.words()).unwrap();
        let size = std::mem::size_of::<crate::gpu_types::WavePush>() as u32;
        assert_eq!(wave.iface.push, Some(crate::vk::spirv::PushBlock { name: "WavePush".into(), size }));
        let g = crate::gpu_types::GeometryPush::default();
        let size = std::mem::size_of_val(&g) as u32;
        let words = [shaders::GEOMETRY_VERT_ALBEDO.words(), shaders::GEOMETRY_FRAG_ALBEDO.words()];
        let eye = reflect(&device, "eye g-buffer", &words).unwrap();
        assert_eq!(eye.push, Some(crate::vk::spirv::PushBlock { name: "GeometryPush".into(), size }));
        assert_eq!(eye.kinds, [sampled]);
        assert_eq!(crate::vk::validation_message_count(), 0);
    }
}

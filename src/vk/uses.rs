//! A pass's one declaration of what it uses. A compute pass lists a [`Use`] per binding; a raster pass adds its
//! attachments and its vertex and index buffers ([`Raster`]). From that one list come both the descriptors the pass
//! pushes and the accesses it declares to the [`Tracker`], which places the barriers before it: no pass lists its
//! bindings in one place and its accesses in another.

use super::buffer::Buffer;
use super::image::{Image, Sampler};
use super::pipeline::{Bind, BindKind, Pipeline};
use super::sync::Access;
use super::{Device, Tracker, VkResult};
use ash::vk;

/// A resource a pass binds, with how the pass uses it.
///
/// A buffer is declared by what the pass does with it (read, write); how a pipeline reaches it follows from that
/// pipeline's layout: where the layout binds a texel buffer, the pass reads the buffer through its texel view (a
/// variant that gathers through texels what the others load as storage), and the access is declared as such.
#[derive(Clone, Copy)]
pub enum Use<'a> {
    /// A uniform buffer, written by the host before the submission (ordered by it: no barrier).
    Uniform(&'a Buffer),
    /// A storage buffer the pass reads.
    Read(&'a Buffer),
    /// A storage buffer the pass writes, or reads and writes (atomics included).
    Write(&'a Buffer),
    /// A storage buffer that holds the arguments of the pass's indirect dispatch or draw, and that a compute pass
    /// also writes (a raster pass only draws from it).
    Indirect(&'a Buffer),
    /// An image the pass samples.
    Sampled(&'a Image, &'a Sampler),
    /// A storage image the pass reads.
    ImageRead(&'a Image),
    /// A storage image the pass writes, or reads and writes, keeping what it held.
    ImageWrite(&'a Image),
    /// A storage image the pass writes whole: what it held before does not matter (no layout to keep).
    ImageOverwrite(&'a Image),
    /// A resource no frame writes (a scene texture, uploaded once; its upload's barrier made it readable): bound
    /// with no barrier.
    Fixed(Bind<'a>),
    /// A resource the pipeline's layout binds because the pass shares that layout with passes that use it, and
    /// this pass's shaders do not access (synchronization validation reports an access it does not order): bound
    /// with no barrier.
    Unused(Bind<'a>),
}

/// Where a pipeline's shaders run, for the stages its accesses are declared at.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Stages {
    Compute,
    /// The vertex and fragment shaders of a raster pass.
    Graphics,
}

impl<'a> Use<'a> {
    /// The descriptor.
    pub fn bind(self) -> Bind<'a> {
        match self {
            Use::Uniform(b) => Bind::Uniform(b),
            Use::Read(b) | Use::Write(b) | Use::Indirect(b) => Bind::Storage(b),
            Use::Sampled(i, s) => Bind::Sampled(i, s),
            Use::ImageRead(i) | Use::ImageWrite(i) | Use::ImageOverwrite(i) => Bind::StorageImage(i),
            Use::Fixed(b) | Use::Unused(b) => b,
        }
    }

    /// The same resource, bound but not accessed (a pass that shares a layout and reads less of it).
    pub fn unused(self) -> Use<'a> {
        Use::Unused(self.bind())
    }

    /// Declare the use to `sync`, as a binding of `kind` in a pipeline whose shaders run at `stages`.
    fn declare(self, sync: &mut Tracker, kind: BindKind, stages: Stages) {
        use Access::*;
        let graphics = stages == Stages::Graphics;
        let writes_in_raster = "a raster pass writes only its attachments";
        match self {
            Use::Uniform(_) | Use::Fixed(_) | Use::Unused(_) => {}
            // A texel binding only reads (a uniform texel buffer).
            Use::Read(b) | Use::Write(b) if kind == BindKind::Texels => {
                assert!(!graphics, "texel buffers are read by compute passes");
                sync.buffer(b, &[ComputeTexels]);
            }
            Use::Indirect(b) if kind == BindKind::Texels => {
                assert!(!graphics, "texel buffers are read by compute passes");
                sync.buffer(b, &[ComputeTexels, IndirectRead]);
            }
            Use::Read(b) if graphics => {
                sync.buffer(b, &[VertexRead, FragmentRead]);
            }
            Use::Read(b) => {
                sync.buffer(b, &[ComputeRead]);
            }
            Use::Write(b) => {
                assert!(!graphics, "{writes_in_raster}");
                sync.buffer(b, &[ComputeWrite]);
            }
            // A raster pass reads its draw's arguments.
            Use::Indirect(b) if graphics => {
                sync.buffer(b, &[IndirectRead]);
            }
            Use::Indirect(b) => {
                sync.buffer(b, &[ComputeWrite, IndirectRead]);
            }
            Use::Sampled(i, _) if graphics => {
                sync.image(i, &[VertexSampled, FragmentSampled]);
            }
            Use::Sampled(i, _) => {
                sync.image(i, &[ComputeSampled]);
            }
            Use::ImageRead(i) | Use::ImageWrite(i) | Use::ImageOverwrite(i) if graphics => {
                panic!("a raster pass binds no storage image ({})", i.name);
            }
            Use::ImageRead(i) => {
                sync.image(i, &[ComputeRead]);
            }
            Use::ImageWrite(i) => {
                sync.image(i, &[ComputeWrite]);
            }
            Use::ImageOverwrite(i) => {
                sync.discard(i, &[ComputeWrite]);
            }
        }
    }

    /// Whether the use reads only (a pass that declares it so gets no barrier before the next pass's read).
    fn reads_only(self) -> bool {
        matches!(self, Use::Read(_) | Use::Sampled(..) | Use::ImageRead(_))
    }

    /// Whether the use fits a binding of `kind` (a buffer where the layout binds a buffer, and so on).
    fn fits(self, kind: BindKind) -> bool {
        matches!(
            (self.bind(), kind),
            (Bind::Uniform(_), BindKind::Uniform)
                | (Bind::Storage(_), BindKind::Storage | BindKind::Texels)
                | (Bind::Sampled(..), BindKind::Sampled)
                | (Bind::StorageImage(_), BindKind::StorageImage)
        )
    }
}

impl Pipeline {
    /// Declare `uses` (binding i = uses[i]) to `sync` as this pipeline's shaders make them. A use that does not
    /// fit its binding, a read of a binding the pipeline's shaders write (a store, an atomic or an image write in
    /// the SPIR-V), or a binding without a use, is this crate's defect: the barriers would not cover what the
    /// shaders do. A write of a binding the shaders only read is declared as a read, and a binding they do not
    /// declare is not declared (the read of an indirect command's arguments excepted).
    fn declare_uses(&self, sync: &mut Tracker, uses: &[Use]) {
        let iface = &self.iface;
        assert!(uses.len() >= iface.kinds.len(), "pipeline {}: binding {} has no use", self.name, uses.len());
        let stages = if self.bind_point == vk::PipelineBindPoint::COMPUTE { Stages::Compute } else { Stages::Graphics };
        for (i, u) in uses.iter().enumerate() {
            let kind = iface.kinds.get(i).copied().flatten();
            // A binding no shader of this pipeline declares is neither bound nor accessed by a shader; the
            // arguments of the pass's indirect command are still read.
            let Some(kind) = kind else {
                if let Use::Indirect(b) = u {
                    sync.buffer(b, &[Access::IndirectRead]);
                }
                continue;
            };
            let var = &iface.names[i];
            assert!(
                u.fits(kind),
                "pipeline {}: binding {i} (`{var}`), a use that does not fit its {kind:?} binding",
                self.name
            );
            assert!(
                !(iface.written[i] && u.reads_only()),
                "pipeline {}: binding {i} (`{var}`) is declared read, but a shader writes it",
                self.name
            );
            // What the shaders only read is declared as read, whatever the list says: passes that share one list
            // (the photon stage) each declare the accesses their SPIR-V makes, as synchronization validation
            // reads them.
            match *u {
                Use::Write(b) if !iface.written[i] => Use::Read(b).declare(sync, kind, stages),
                Use::ImageWrite(img) if !iface.written[i] => Use::ImageRead(img).declare(sync, kind, stages),
                Use::Indirect(b) if !iface.written[i] && stages == Stages::Compute && kind == BindKind::Storage => {
                    sync.buffer(b, &[Access::ComputeRead, Access::IndirectRead]);
                }
                u => u.declare(sync, kind, stages),
            }
        }
    }

    /// A compute pass's one declaration of its resources: declare each use to `sync` (binding i = uses[i]), record
    /// the barriers they need, then bind the pipeline and push the descriptors the same uses name.
    pub fn bind_uses(&self, cmd: vk::CommandBuffer, sync: &mut Tracker, uses: &[Use]) -> VkResult<()> {
        assert_eq!(self.bind_point, vk::PipelineBindPoint::COMPUTE, "a raster pass begins with begin_raster");
        self.declare_uses(sync, uses);
        sync.flush(&self.device, cmd);
        let binds: Vec<Bind> = uses.iter().map(|u| u.bind()).collect();
        self.bind_checked(cmd, &binds)
    }

    /// Begin the raster pass `raster` with this pipeline: declare its uses, attachments, vertex and index buffers to
    /// `sync` and record the barriers they need (a render pass cannot hold them), begin rendering on the
    /// attachments (a viewport and scissor over them), then bind the pipeline, its descriptors and the buffers.
    /// The pass ends with [`Raster::end`].
    pub fn begin_raster(&self, cmd: vk::CommandBuffer, sync: &mut Tracker, raster: &Raster) -> VkResult<()> {
        assert_eq!(self.bind_point, vk::PipelineBindPoint::GRAPHICS, "a compute pass binds with bind_uses");
        self.declare_uses(sync, raster.uses);
        for t in raster.colors {
            t.declare(sync, Access::ColorAttachment);
        }
        if let Some(t) = raster.depth {
            t.declare(sync, Access::DepthAttachment);
        }
        if let Some(v) = raster.vertices {
            sync.buffer(v, &[Access::VertexInput]);
        }
        if let Some(i) = raster.indices {
            sync.buffer(i, &[Access::IndexInput]);
        }
        sync.flush(&self.device, cmd);
        raster.begin_rendering(&self.device, cmd);
        self.bind_raster(cmd, raster)
    }

    /// Bind this pipeline to the raster pass `raster` already begun (another pipeline of the same pass, which reads
    /// what the declaration names): its descriptors, vertex and index buffers.
    pub fn bind_raster(&self, cmd: vk::CommandBuffer, raster: &Raster) -> VkResult<()> {
        let binds: Vec<Bind> = raster.uses.iter().map(|u| u.bind()).collect();
        self.bind_checked(cmd, &binds)?;
        let d = &self.device;
        unsafe {
            if let Some(v) = raster.vertices {
                d.cmd_bind_vertex_buffers(cmd, 0, &[v.raw], &[0]);
            }
            if let Some(i) = raster.indices {
                d.cmd_bind_index_buffer(cmd, i.raw, 0, vk::IndexType::UINT32);
            }
        }
        Ok(())
    }
}

/// A raster pass's attachment, with whether the pass keeps what it held.
#[derive(Clone, Copy)]
pub enum Target<'a> {
    /// Cleared as the pass begins (color to zero, depth to 1): what it held does not matter.
    Clear(&'a Image),
    /// Loaded: the pass adds to what it holds (blending, or a depth test against earlier draws).
    Load(&'a Image),
}

impl<'a> Target<'a> {
    fn image(self) -> &'a Image {
        match self {
            Target::Clear(i) | Target::Load(i) => i,
        }
    }

    fn declare(self, sync: &mut Tracker, access: Access) {
        match self {
            Target::Clear(i) => sync.discard(i, &[access]),
            Target::Load(i) => sync.image(i, &[access]),
        };
    }

    fn info(self, layout: vk::ImageLayout, clear: vk::ClearValue) -> vk::RenderingAttachmentInfo<'static> {
        let load = match self {
            Target::Clear(_) => vk::AttachmentLoadOp::CLEAR,
            Target::Load(_) => vk::AttachmentLoadOp::LOAD,
        };
        vk::RenderingAttachmentInfo::default()
            .image_view(self.image().view)
            .image_layout(layout)
            .load_op(load)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(clear)
    }
}

/// A raster pass's one declaration: its color and depth attachments, the vertex and index buffers its draws read
/// (u32 indices), and a [`Use`] per binding of its pipelines' layout. [`Pipeline::begin_raster`] declares them,
/// begins the pass and binds them; [`Raster::end`] ends it.
pub struct Raster<'a> {
    pub colors: &'a [Target<'a>],
    pub depth: Option<Target<'a>>,
    pub vertices: Option<&'a Buffer>,
    pub indices: Option<&'a Buffer>,
    pub uses: &'a [Use<'a>],
}

impl Raster<'_> {
    /// The attachments' extent (they share it).
    fn extent(&self) -> vk::Extent2D {
        let mut images = self.colors.iter().chain(&self.depth).map(|t| t.image().extent);
        let extent = images.next().expect("a raster pass has an attachment");
        assert!(images.all(|e| e == extent), "a raster pass's attachments share their extent");
        extent
    }

    fn begin_rendering(&self, device: &Device, cmd: vk::CommandBuffer) {
        let extent = self.extent();
        let zero = vk::ClearValue { color: vk::ClearColorValue { float32: [0.0; 4] } };
        let far = vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } };
        let colors: Vec<_> =
            self.colors.iter().map(|t| t.info(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, zero)).collect();
        let depth = self.depth.map(|t| t.info(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, far));
        let area = vk::Rect2D { offset: vk::Offset2D::default(), extent };
        let mut info = vk::RenderingInfo::default().render_area(area).layer_count(1).color_attachments(&colors);
        if let Some(d) = depth.as_ref() {
            info = info.depth_attachment(d);
        }
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: extent.width as f32,
            height: extent.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        unsafe {
            device.cmd_begin_rendering(cmd, &info);
            device.cmd_set_viewport(cmd, 0, &[viewport]);
            device.cmd_set_scissor(cmd, 0, &[area]);
        }
    }

    /// End the pass.
    pub fn end(&self, device: &Device, cmd: vk::CommandBuffer) {
        unsafe { device.cmd_end_rendering(cmd) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vk::Pipeline;

    /// The scene update's placement reads object-space buffers (`readonly`) and writes world-space ones
    /// (`writeonly`): a pass that declared a world-space buffer as read would get no barrier before the next
    /// reader, and is refused where it declares, naming the pipeline and the binding.
    #[test]
    fn a_read_of_a_binding_the_shader_writes_is_refused() {
        let desc = crate::vk::ContextDesc { validation: true, ..crate::vk::ContextDesc::from_env() };
        let device = crate::vk::Context::headless(&desc).expect("a Vulkan device").device;
        let words = crate::shaders::SCENE_UPDATE_COMP.words();
        let p = Pipeline::compute(&device, "scene update", words).expect("pipeline");
        assert_eq!(p.iface.written, [false, true, false, true]);
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let b: Vec<Buffer> = (0..4)
            .map(|i| {
                Buffer::new(&device, &format!("b{i}"), 64, usage, gpu_allocator::MemoryLocation::GpuOnly)
                    .expect("buffer")
            })
            .collect();
        let mut sync = Tracker::new(&device);
        p.declare_uses(&mut sync, &[Use::Read(&b[0]), Use::Write(&b[1]), Use::Read(&b[2]), Use::Write(&b[3])]);
        let wrong = [Use::Read(&b[0]), Use::Read(&b[1]), Use::Read(&b[2]), Use::Write(&b[3])];
        let e = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| p.declare_uses(&mut sync, &wrong)))
            .expect_err("a read of a written binding");
        let message = e.downcast_ref::<String>().expect("a message");
        assert!(message.contains("pipeline scene update: binding 1 (`WorldVertices`) is declared read"), "{message}");
        // A use of another kind than its binding is refused the same way.
        let img = [Use::Read(&b[0]), Use::Uniform(&b[1]), Use::Read(&b[2]), Use::Write(&b[3])];
        let e = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| p.declare_uses(&mut sync, &img)))
            .expect_err("a uniform where the layout binds storage");
        let message = e.downcast_ref::<String>().expect("a message");
        assert!(
            message.contains("binding 1 (`WorldVertices`), a use that does not fit its Storage binding"),
            "{message}"
        );
        // A list that leaves a binding out is refused.
        let short = [Use::Read(&b[0]), Use::Write(&b[1])];
        let e = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| p.declare_uses(&mut sync, &short)))
            .expect_err("a binding without a use");
        let message = e.downcast_ref::<String>().expect("a message");
        assert!(message.contains("binding 2 has no use"), "{message}");
    }
}

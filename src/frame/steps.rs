//! The steps around the photons: the light-view g-buffers (1), coverage (2), the resolve (6), the eye view (7), the
//! composite (8) and the readback. Each pass declares its uses as it binds them, and each transfer its accesses;
//! the tracker places the barriers.

use super::deposit::Deposit;
use super::{Aov, Ctx, Rec};
use crate::gpu_types::{ResolvePush, TransportState, TraversalState};
use crate::passes::composite::{CompositeInputs, LightMaps};
use crate::passes::coverage::CoverageInputs;
use crate::passes::eye::{EyeGbuffer, EyeInputs};
use crate::passes::geometry::GeometryTarget;
use crate::passes::resolve::FluxSource;
use crate::settings::Transport;
use crate::targets::{Targets, DEBUG_PHOTON_BYTES, PHOTON_GUARD};
use crate::vk::{Access, Image, VkResult};
use ash::vk;

impl Ctx<'_> {
    /// Step 1: light-view g-buffers.
    /// `receivers`: also the receiver g-buffer and the shadow map (a light's first color pass draws them).
    pub(super) fn light_gbuffers(&self, rec: &mut Rec, caustics: bool, receivers: bool) -> VkResult<()> {
        let (t, g) = (self.t, &self.p.geometry);
        rec.ts.mark(rec.cmd, "light_gbuffer.front");
        let photon_view = &self.data.light.photon_view;
        let receiver_view = &self.data.light.receiver_view;
        if caustics {
            // The IOR buffer is drawn only when the refractors' IORs differ (else the shaders read the uniform).
            let ior = self.sb.shared_ior.is_none().then_some(&t.light.front_aux);
            g.record_front(rec.cmd, rec.sync, self.sb, &t.light.front, ior, &t.light.depth, photon_view)?;
            // Exact transport reads only the front buffer (coverage); the back surface is the two-interface
            // trace's.
            if self.s.transport == Transport::TwoInterface {
                rec.ts.mark(rec.cmd, "light_gbuffer.back");
                // The depth buffer is reused (cleared) by the back-face pass.
                let back = GeometryTarget {
                    colors: &[&t.light.back],
                    depth: &t.light.depth,
                    view: photon_view,
                    ranges: &[self.sb.refractors],
                };
                g.record(rec.cmd, rec.sync, &g.back, self.sb, &back)?;
            }
        }
        if receivers {
            // The receivers' g-buffer and the shadow map, in one pass.
            rec.ts.mark(rec.cmd, "light_gbuffer.receivers");
            g.record_receivers(rec.cmd, rec.sync, self.sb, &self.r.geo, &self.r.shadow, receiver_view)?;
        }
        // Each pass that samples them declares it (and moves them out of the attachment layout).
        Ok(())
    }

    /// A frame that reuses the caustic map, the receiver g-buffer and the shadow map of the last one (the passes
    /// that read them declare their reads, which the tracker orders after the last frame's writes).
    pub(super) fn reuse_caustics(&self, rec: &mut Rec) {
        rec.ts.mark(rec.cmd, "reused");
    }

    /// Step 2: the coverage pyramid.
    pub(super) fn coverage(&self, rec: &mut Rec) -> VkResult<()> {
        let t = self.t;
        rec.ts.mark(rec.cmd, "coverage");
        let mips = self.s.gbuffer_level() + 1;
        let inputs = CoverageInputs {
            ubo: self.ubo,
            coverage: &t.photon.coverage,
            front: &t.light.front,
            recv: &self.r.geo,
            sampler: self.nearest,
            mips,
        };
        self.p.coverage.record(rec.cmd, rec.sync, &inputs)
    }

    /// Step 6: caustic flux → irradiance. `add`: add to the map (a continuation's remaining batches).
    /// Step 6 into the pass's irradiance map. `add`: the rest of a frame's batches, added to what the map holds;
    /// else this frame's photon set, which a progressive accumulation's k-th set averages into the k before it.
    pub(super) fn resolve(&self, rec: &mut Rec, add: bool) -> VkResult<()> {
        rec.ts.mark(rec.cmd, "resolve");
        let flux = if !self.resolve_texels {
            FluxSource::Image(&self.r.flux)
        } else if self.s.carried_color.carried() {
            FluxSource::ColorTexels(&self.r.flux_texels)
        } else {
            FluxSource::Texels(&self.r.flux_texels)
        };
        let weight = self.data.frame.set_weight();
        let blend = ResolvePush { keep: if add { 1.0 } else { 1.0 - weight }, scale: weight };
        // A light's later color passes write their channel and keep the earlier ones.
        let keep = self.channel != 0 || blend.keep != 0.0;
        let r = &self.r;
        self.p.resolve.record(rec.cmd, rec.sync, self.ubo, flux, &r.geo, &r.irradiance, self.nearest, keep, blend)
    }

    /// No refractor: the irradiance map is zero (no caustic pass is recorded).
    pub(super) fn clear_irradiance(&self, rec: &mut Rec) {
        let img = &self.r.irradiance;
        rec.sync.discard(img, &[Access::TransferDst]);
        rec.flush(self.d);
        unsafe {
            self.d.cmd_clear_color_image(
                rec.cmd,
                img.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &vk::ClearColorValue { float32: [0.0; 4] },
                &[img.range()],
            )
        };
    }

    /// Step 7a: the eye view of the receivers under this light: the first light draws their eye g-buffer, then
    /// each light's shading writes (the first) or adds to (the others) the radiance, and the caustics and direct
    /// AOVs when the frame reads one back, so the AOVs are the sums over lights.
    /// `gbuffer`: the first light draws the receivers' eye g-buffer (else the eye deposit drew it before the
    /// photons).
    pub(super) fn eye_receivers(&self, rec: &mut Rec, gbuffer: bool) -> VkResult<()> {
        let e = &self.t.eye;
        let first = self.light == 0;
        let out: &[&Image] = if self.eye_aovs { &[&e.radiance, &e.caustics, &e.direct] } else { &[&e.radiance] };
        let g = EyeGbuffer { geo: &e.recv, albedo: &e.albedo, depth: &e.depth };
        if first {
            // The g-buffer does not depend on the light: drawn once, before the first light's shading.
            if gbuffer {
                self.eye_gbuffer(rec)?;
            }
            rec.ts.mark(rec.cmd, "eye.shade");
        }
        let inputs = EyeInputs {
            ubo: self.ubo,
            shadow: &self.r.shadow,
            irradiance: &self.r.irradiance,
            recv: &self.r.geo,
            nearest: self.nearest,
            linear: self.linear,
            images: &self.sb.images,
            eye_flux: &e.flux,
        };
        self.p.eye.record_shade(rec.cmd, rec.sync, &inputs, &g, out, !first)
    }

    /// The receivers' eye g-buffer (normal and distance, albedo, depth), once a frame whatever the lights.
    pub(super) fn eye_gbuffer(&self, rec: &mut Rec) -> VkResult<()> {
        let e = &self.t.eye;
        let g = EyeGbuffer { geo: &e.recv, albedo: &e.albedo, depth: &e.depth };
        self.p.eye.record_gbuffer(rec.cmd, rec.sync, self.sb, &self.data.frame.camera, &g)
    }

    /// Before the lights' passes: zero a frame-scoped deposit's store (the eye deposit's flux, docs/design.md "The
    /// eye deposit"). A light map's store is its view's own, which its photons' first batch clears.
    pub(super) fn clear_deposit(&self, rec: &mut Rec, deposit: Deposit) {
        let store = match deposit {
            Deposit::Eye => &self.t.eye.flux,
            Deposit::LightMap => return,
        };
        rec.sync.buffer(store, &[Access::TransferDst]);
        rec.flush(self.d);
        unsafe { self.d.cmd_fill_buffer(rec.cmd, store.raw, 0, vk::WHOLE_SIZE, 0) };
    }

    /// Step 7b: the eye view of the refractors: front and back g-buffers for the composite.
    pub(super) fn eye_refractors(&self, rec: &mut Rec) -> VkResult<()> {
        let e = &self.t.eye;
        let g = &self.p.geometry;
        let cam = &self.data.frame.camera;
        // The exact composite traces the glass through the BVH: it needs only where the front surface is.
        let exact = self.exact_eye();
        let ior = (!exact && self.sb.shared_ior.is_none()).then_some(&e.front_aux);
        g.record_front(rec.cmd, rec.sync, self.sb, &e.front, ior, &e.refr_depth, cam)?;
        if exact {
            return Ok(());
        }
        // The depth buffer is reused (cleared) by the back-face pass.
        let back =
            GeometryTarget { colors: &[&e.back], depth: &e.refr_depth, view: cam, ranges: &[self.sb.refractors] };
        g.record(rec.cmd, rec.sync, &g.back, self.sb, &back)
    }

    /// The composite traces eye rays through the BVH under exact transport, previews too (at their resolution and
    /// one sample, so that a preview is coarser than a still, never wrong); else it refracts through the eye's
    /// front and back buffers, whose two surfaces miss what lies between (a pool's water block is one front
    /// surface over a floor that stands in it).
    pub(super) fn exact_eye(&self) -> bool {
        self.s.transport == Transport::Exact
    }

    fn composite_inputs<'b>(&'b self, more_lights: &'b [LightMaps<'b>]) -> CompositeInputs<'b> {
        let e = &self.t.eye;
        CompositeInputs {
            ubo: self.ubo,
            radiance: &e.radiance,
            front: &e.front,
            front_aux: &e.front_aux,
            back: &e.back,
            beauty: &e.beauty,
            hdr: &e.hdr,
            shadow: &self.r.shadow,
            irradiance: &self.r.irradiance,
            recv: &self.r.geo,
            bvh: &self.sb.bvh,
            images: &self.sb.images,
            nearest: self.nearest,
            linear: self.linear,
            glass: &e.glass,
            eye_flux: &e.flux,
            more_lights,
            exact: self.exact_eye(),
            wide: self.s.bvh_layout == crate::bvh::BvhLayout::Wide,
            dispersive: self.data.frame.disperses > 0.5,
            environment: self.data.frame.environment > 0.5,
            media: self.s.media,
        }
    }

    /// Step 7c, exact transport: the glass under this light and `more_lights` (at most two more). Each eye
    /// sample that meets glass first is traced through it (every interface, Fresnel-split) to the receivers, each
    /// shaded with these lights' shadow and caustic maps (and the environment, with the first light's uniforms),
    /// and its radiance written (`add` false) or added into the glass image.
    pub(super) fn eye_glass(&self, rec: &mut Rec, more_lights: &[LightMaps], add: bool) -> VkResult<()> {
        if !add {
            rec.ts.mark(rec.cmd, "eye.glass");
        }
        self.p.composite.record_glass(rec.cmd, rec.sync, &self.composite_inputs(more_lights), add)
    }

    /// Step 8: the glass (read from the glass passes under exact transport; else deferred refraction), supersample
    /// resolve, tone mapping.
    pub(super) fn composite(&self, rec: &mut Rec) -> VkResult<()> {
        let e = &self.t.eye;
        rec.ts.mark(rec.cmd, "composite");
        self.p.composite.record(rec.cmd, rec.sync, &self.composite_inputs(&[]))?;
        rec.sync.image(&e.beauty, &[Access::TransferSrc]);
        rec.sync.image(&e.hdr, &[Access::TransferSrc]);
        rec.flush(self.d);
        Ok(())
    }

    /// Copy the requested AOV to the readback buffer, and make the buffer visible to the host.
    pub(super) fn readback(&self, rec: &mut Rec, aov: Option<Aov>) -> Option<Aov> {
        let (t, d) = (self.t, self.d);
        let layout = Targets::readback_layout(self.s, 16 * t.width as u64 * t.height as u64);
        let image: Option<&Image> = aov.map(|a| match a {
            Aov::Beauty => &t.eye.beauty,
            Aov::BeautyHdr => &t.eye.hdr,
            Aov::Caustics => &t.eye.caustics,
            Aov::Direct => &t.eye.direct,
        });
        // After the lights' state copies: other ranges of the same buffer.
        rec.sync.buffer(self.readback, &[Access::TransferDst]);
        if let Some(img) = image {
            rec.sync.image(img, &[Access::TransferSrc]);
        }
        rec.flush(d);
        if let Some(img) = image {
            let region = vk::BufferImageCopy::default()
                .buffer_offset(layout.aov)
                .image_subresource(vk::ImageSubresourceLayers {
                    aspect_mask: vk::ImageAspectFlags::COLOR,
                    mip_level: 0,
                    base_array_layer: 0,
                    layer_count: 1,
                })
                .image_extent(vk::Extent3D { width: t.width, height: t.height, depth: 1 });
            unsafe {
                d.cmd_copy_image_to_buffer(
                    rec.cmd,
                    img.raw,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    self.readback.raw,
                    &[region],
                )
            };
        }
        rec.sync.buffer(self.readback, &[Access::HostRead]);
        rec.flush(d);
        aov
    }

    /// Copy this light's traversal and transport state (and, for the first light, the debug dump and the guard)
    /// to its slot of the readback buffer, before the next light's photons reset them.
    pub(super) fn copy_light_state(&self, rec: &mut Rec) {
        let (t, d) = (self.t, self.d);
        let layout = Targets::readback_layout(self.s, 16 * t.width as u64 * t.height as u64);
        let i = self.pass as u64;
        let state = std::mem::size_of::<TraversalState>() as u64;
        let transport = std::mem::size_of::<TransportState>() as u64;
        let debug = self.s.debug_photons > 0 && self.pass == 0;
        rec.sync.buffer(self.readback, &[Access::TransferDst]);
        rec.sync.buffer(&t.photon.state, &[Access::TransferSrc]);
        rec.sync.buffer(&t.photon.transport, &[Access::TransferSrc]);
        if debug {
            rec.sync.buffer(&t.photon.debug, &[Access::TransferSrc]);
            rec.sync.buffer(&t.photon.photons, &[Access::TransferSrc]);
        }
        rec.flush(d);
        let cmd = rec.cmd;
        unsafe {
            let copies = [vk::BufferCopy { src_offset: 0, dst_offset: layout.state + i * state, size: state }];
            d.cmd_copy_buffer(cmd, t.photon.state.raw, self.readback.raw, &copies);
            let copies =
                [vk::BufferCopy { src_offset: 0, dst_offset: layout.transport + i * transport, size: transport }];
            d.cmd_copy_buffer(cmd, t.photon.transport.raw, self.readback.raw, &copies);
            if debug {
                let bytes = 16 + DEBUG_PHOTON_BYTES * self.s.debug_photons as u64;
                d.cmd_copy_buffer(
                    cmd,
                    t.photon.debug.raw,
                    self.readback.raw,
                    &[vk::BufferCopy { src_offset: 0, dst_offset: layout.debug, size: bytes }],
                );
                let guard = vk::BufferCopy {
                    src_offset: 8 * t.photon.capacity as u64,
                    dst_offset: layout.guard,
                    size: 8 * PHOTON_GUARD as u64,
                };
                d.cmd_copy_buffer(cmd, t.photon.photons.raw, self.readback.raw, &[guard]);
            }
        }
    }
}

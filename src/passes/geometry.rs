//! Rasterize triangles into view-space g-buffers: refractor front and back surfaces (from the light and from
//! the eye), receivers from the light, and the shadow map.

use super::{AUX_FORMAT, DEPTH_FORMAT, GEO_FORMAT};
use crate::gpu_types::{GeometryPush, GpuView, Vertex};
use crate::scene_gpu::{DrawRange, SceneBuffers};
use crate::shaders;
use crate::vk::{Blend, ColorTarget, Device, GraphicsDesc, Image, Pipeline, Raster, Target, Tracker, VkResult};
use ash::vk;
use std::sync::Arc;

pub struct GeometryPass {
    device: Arc<Device>,
    /// Nearest front faces: normal + distance, and the index of refraction.
    pub front: Pipeline,
    /// Nearest front faces: normal + distance alone (the eye view under exact transport).
    pub front_only: Pipeline,
    /// Nearest back faces: normal + distance.
    pub back: Pipeline,
    /// Both faces (receivers): normal + distance.
    pub surfaces: Pipeline,
    /// Depth only, inside the receiver pass (color writes masked): the refractors' share of the shadow map.
    pub occluders: Pipeline,
}

/// What to draw and where.
pub struct GeometryTarget<'a> {
    pub colors: &'a [&'a Image],
    pub depth: &'a Image,
    pub view: &'a GpuView,
    pub ranges: &'a [DrawRange],
}

impl GeometryPass {
    pub fn new(device: &Arc<Device>) -> VkResult<Self> {
        // Each variant declares only the attributes its vertex shader reads: position, normal, material.
        let all = [
            (vk::Format::R32G32B32A32_SFLOAT, 0),
            (vk::Format::R32G32B32A32_SFLOAT, 16),
            (vk::Format::R32G32B32A32_SFLOAT, 32),
        ];
        let geo = ColorTarget { format: GEO_FORMAT, blend: Blend::None };
        let aux = ColorTarget { format: AUX_FORMAT, blend: Blend::None };
        let make = |name: &str, vert: &[u32], frag: &[u32], cull: vk::CullModeFlags, colors: &[ColorTarget]| {
            let attrs = match colors.iter().filter(|c| c.blend != Blend::Masked).count() {
                0 => &all[..1],
                1 => &all[..2],
                _ => &all[..],
            };
            Pipeline::graphics(
                device,
                name,
                &GraphicsDesc {
                    vertex: vert,
                    fragment: frag,
                    vertex_attributes: attrs,
                    vertex_stride: std::mem::size_of::<Vertex>() as u32,
                    topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                    cull,
                    depth: Some((DEPTH_FORMAT, vk::CompareOp::LESS, true)),
                    colors,
                },
            )
        };
        Ok(GeometryPass {
            device: device.clone(),
            front: make(
                "geometry front",
                shaders::GEOMETRY_VERT_AUX.words(),
                shaders::GEOMETRY_FRAG_AUX.words(),
                vk::CullModeFlags::BACK,
                &[geo, aux],
            )?,
            front_only: make(
                "geometry front (no aux)",
                shaders::GEOMETRY_VERT.words(),
                shaders::GEOMETRY_FRAG.words(),
                vk::CullModeFlags::BACK,
                &[geo],
            )?,
            back: make(
                "geometry back",
                shaders::GEOMETRY_VERT.words(),
                shaders::GEOMETRY_FRAG.words(),
                vk::CullModeFlags::FRONT,
                &[geo],
            )?,
            surfaces: make(
                "geometry surfaces",
                shaders::GEOMETRY_VERT.words(),
                shaders::GEOMETRY_FRAG.words(),
                vk::CullModeFlags::NONE,
                &[geo],
            )?,
            occluders: make(
                "shadow occluders",
                shaders::GEOMETRY_VERT_DEPTH.words(),
                shaders::DEPTH_ONLY_FRAG.words(),
                vk::CullModeFlags::NONE,
                &[ColorTarget { format: GEO_FORMAT, blend: Blend::Masked }],
            )?,
        })
    }

    /// Draw `t.ranges` with `pipeline` into `t`'s targets, cleared first.
    pub fn record(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        pipeline: &Pipeline,
        scene: &SceneBuffers,
        t: &GeometryTarget,
    ) -> VkResult<()> {
        let colors: Vec<Target> = t.colors.iter().map(|&img| Target::Clear(img)).collect();
        let raster = Self::raster(scene, &colors, t.depth);
        pipeline.begin_raster(cmd, sync, &raster)?;
        self.draw(cmd, pipeline, t.view, t.ranges);
        raster.end(&self.device, cmd);
        Ok(())
    }

    /// A pass over the scene's vertices into `colors` and `depth` (cleared first); the geometry pipelines bind no
    /// descriptors.
    fn raster<'a>(scene: &'a SceneBuffers, colors: &'a [Target<'a>], depth: &'a Image) -> Raster<'a> {
        Raster {
            colors,
            depth: Some(Target::Clear(depth)),
            vertices: Some(&scene.vertices),
            indices: Some(&scene.indices),
            uses: &[],
        }
    }

    /// The refractors' nearest front faces from `view` into `front` (normal and distance) and, when given, their
    /// index of refraction into `ior` (needed only where the refractors differ in it and a pass reads it).
    #[allow(clippy::too_many_arguments)]
    pub fn record_front(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        scene: &SceneBuffers,
        front: &Image,
        ior: Option<&Image>,
        depth: &Image,
        view: &GpuView,
    ) -> VkResult<()> {
        let ranges = [scene.refractors];
        let (pipeline, colors): (_, &[&Image]) = match ior {
            Some(ior) => (&self.front, &[front, ior]),
            None => (&self.front_only, &[front]),
        };
        self.record(cmd, sync, pipeline, scene, &GeometryTarget { colors, depth, view, ranges: &ranges })
    }

    /// The receiver pass: the receivers' g-buffer and, in the same depth target, the shadow map. The receivers are
    /// drawn first (color and depth), then the refractors with color writes masked, so the color target holds
    /// the receivers the light sees through the glass and the depth target the nearest of every object.
    pub fn record_receivers(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        scene: &SceneBuffers,
        geo: &Image,
        shadow: &Image,
        view: &GpuView,
    ) -> VkResult<()> {
        let colors = [Target::Clear(geo)];
        let raster = Self::raster(scene, &colors, shadow);
        self.surfaces.begin_raster(cmd, sync, &raster)?;
        self.draw(cmd, &self.surfaces, view, &[scene.receivers]);
        self.occluders.bind_raster(cmd, &raster)?;
        self.draw(cmd, &self.occluders, view, &[scene.refractors]);
        raster.end(&self.device, cmd);
        Ok(())
    }

    /// Draw `ranges` of the bound index buffer with `pipeline` (bound) from `view`.
    fn draw(&self, cmd: vk::CommandBuffer, pipeline: &Pipeline, view: &GpuView, ranges: &[DrawRange]) {
        pipeline.push(cmd, &GeometryPush::from_view(view));
        for r in ranges {
            if r.index_count > 0 {
                unsafe { self.device.cmd_draw_indexed(cmd, r.index_count, 1, r.first_index, 0, 0) };
            }
        }
    }
}

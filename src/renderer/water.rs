//! Simulated water on the GPU: each frame's scene update steps every simulated surface from where the GPU's
//! heights stand to the frame's time (src/scene/water.rs defines the scheme; glsl/water_step.comp runs it), with
//! the scene's drops, the drops asked for since the last frame ([`Renderer::drop_into_water`]), and the objects
//! moving through the water. Nothing is read back: the host only counts steps.

use super::Renderer;
use crate::error::{Error, Result};
use crate::frame::SceneUpdate;
use crate::gpu_types::WaterStepPush;
use crate::scene::water::{self, Drop, Simulation, StepCoefficients};
use crate::scene_gpu::{Deformer, SimulationState};
use crate::shaders::consts::{WATER_DROP, WATER_STEP};
use glam::{Mat4, Vec3};
use std::collections::BTreeSet;

/// What the renderer keeps between frames to step its water: the bodies' spheres (object space, per scene
/// object; none for water), each object's transform when the surfaces were last stepped, and the drops asked for.
#[derive(Default)]
pub(super) struct WaterSims {
    /// The scene generation the spheres were computed for.
    generation: Option<u64>,
    spheres: Vec<Option<(Vec3, f32)>>,
    /// Each object's transform when the surfaces were last stepped.
    last: Option<Vec<Mat4>>,
    /// Drops asked for, per water object, not yet recorded.
    drops: Vec<(usize, Drop)>,
    /// Drops recorded so far (part of the caustic maps' key: a drop changes the surface at the same time).
    pub(super) events: u64,
}

impl WaterSims {
    /// A step job of water `k` on heights from `base`, `slot` holding its heights now.
    fn job(k: &StepCoefficients, base: u32, slot: u32, size: glam::Vec2) -> WaterStepPush {
        WaterStepPush {
            base,
            nodes: k.nodes,
            slot,
            keep: k.keep,
            cx: k.cx,
            cz: k.cz,
            limit: k.limit,
            size_x: size.x,
            size_z: size.y,
            depth: k.depth,
            ..WaterStepPush::default()
        }
    }

    fn drop_job(k: &StepCoefficients, base: u32, slot: u32, size: glam::Vec2, d: &Drop) -> WaterStepPush {
        WaterStepPush { mode: WATER_DROP, drop: [d.at.x, d.at.y, d.radius, d.depth], ..Self::job(k, base, slot, size) }
    }
}

impl Renderer {
    /// Drop into the first simulated water surface (at rest) that the ray from `origin` along `direction` (world
    /// space) meets: a dimple `radius` m wide and `depth` m deep, landing before the next frame's steps (the
    /// viewer's click). Returns the water object's index, or None where the ray meets no simulated surface.
    pub fn drop_into_water(&mut self, origin: Vec3, direction: Vec3, radius: f32, depth: f32) -> Result<Option<usize>> {
        if !(origin.is_finite() && direction.is_finite() && direction != Vec3::ZERO)
            || !(radius.is_finite() && radius > 0.0 && depth.is_finite() && depth > 0.0)
        {
            return Err(Error::BadInput(format!(
                "drop from {origin} along {direction} (radius {radius} m, depth {depth} m): the ray must be finite and \
                 not zero, and both sizes > 0"
            )));
        }
        let mut hit: Option<(f32, usize, glam::Vec2)> = None;
        for (i, o) in self.scene.objects.iter().enumerate() {
            let Some(w) = o.animation.as_ref().and_then(|a| a.water.as_ref()) else { continue };
            if w.simulation.is_none() {
                continue;
            }
            let m = self.instances.transform_of(i);
            let inv = m.inverse();
            let (o, d) = (inv.transform_point3(origin), inv.transform_vector3(direction));
            let t = -o.y / d.y;
            let p = o + d * t;
            let dist = (m.transform_point3(p) - origin).length();
            if t > 0.0 && p.x.abs() <= w.size.x * 0.5 && p.z.abs() <= w.size.y * 0.5 && hit.is_none_or(|h| dist < h.0) {
                hit = Some((dist, i, glam::Vec2::new(p.x, p.z)));
            }
        }
        let Some((_, i, at)) = hit else { return Ok(None) };
        self.water.drops.push((i, Drop { time: self.scene.time, at, radius, depth }));
        self.instances.mark_deformed(i);
        Ok(Some(i))
    }

    /// Step every simulated surface to the scene's time in `up` (its drops and steps; back to rest first when the
    /// time went back), and add each one stepped to `deformed`.
    pub(super) fn step_water(&mut self, up: &mut SceneUpdate, deformed: &mut BTreeSet<usize>) {
        let sb = &mut self.scene_buffers;
        if sb.simulations.iter().all(|s| s.is_none()) {
            return;
        }
        let n = self.scene.objects.len();
        if self.water.generation != Some(self.scene_generation) {
            // Each object that is not water may disturb the water as its mesh's sphere, placed.
            self.water.spheres = (0..n)
                .map(|i| {
                    let water = matches!(sb.deformers[i], Some(Deformer::Water(_)));
                    (!water).then(|| water::bounding_sphere(self.instances.mesh_at(self.instances.mesh_of(i))))
                })
                .collect();
            self.water.generation = Some(self.scene_generation);
            self.water.last = None;
        }
        let time = self.scene.time;
        let now: Vec<Mat4> = (0..n).map(|i| self.instances.transform_of(i)).collect();
        let before = self.water.last.take().unwrap_or_else(|| now.clone());
        for w in 0..n {
            let (Some(Deformer::Water(range)), Some(state)) = (sb.deformers[w], sb.simulations[w].as_mut()) else {
                continue;
            };
            let Some((base, k)) = range.simulation else { continue };
            let Some(wd) = self.scene.objects[w].animation.as_ref().and_then(|a| a.water.as_ref()) else { continue };
            let Some(sim) = wd.simulation.as_ref() else { continue };
            let asked: Vec<Drop> = self.water.drops.iter().filter(|(i, _)| *i == w).map(|(_, d)| *d).collect();
            let target = Simulation::steps_at(k.rate, time);
            if target == state.steps && asked.is_empty() {
                continue;
            }
            deformed.insert(w);
            if target < state.steps {
                up.water_rest.push((base, 2 * k.nodes * k.nodes));
                *state = SimulationState::default();
            }
            for d in &asked {
                up.water_steps.push(WaterSims::drop_job(&k, base, state.slot, wd.size, d));
                self.water.events += 1;
            }
            let first = state.steps;
            let object_from_world = now[w].inverse();
            for s in first..target {
                for d in sim.drops_in(k.rate, s) {
                    up.water_steps.push(WaterSims::drop_job(&k, base, state.slot, wd.size, d));
                }
                let (t0, t1) = (s as f32 / k.rate as f32, (s + 1) as f32 / k.rate as f32);
                // Where each other object stands at a time of this frame's steps: on its keyframes when it follows
                // them (as the CPU reference places it), else between where it stood at the last step and now.
                let at = |i: usize, t: f32, f: f32| -> Option<(Vec3, f32)> {
                    let sphere = self.water.spheres[i]?;
                    let keyed = self.scene.objects[i].animation.as_ref().filter(|a| a.animation.is_some());
                    if let Some(a) = keyed.filter(|a| a.transform_at(time) == now[i]) {
                        return Some(water::place_sphere(sphere, a.transform_at(t)));
                    }
                    let (a, b) = (water::place_sphere(sphere, before[i]), water::place_sphere(sphere, now[i]));
                    Some((a.0.lerp(b.0, f), b.1))
                };
                let span = (target - first) as f32;
                let (f0, f1) = ((s - first) as f32 / span, (s + 1 - first) as f32 / span);
                let moving = (0..n).filter(|&i| i != w).filter_map(|i| Some((at(i, t0, f0)?, at(i, t1, f1)?)));
                let bodies = water::bodies_in(wd, object_from_world, moving);
                let mut job = WaterSims::job(&k, base, state.slot, wd.size);
                job.mode = WATER_STEP;
                job.body_count = bodies.len() as u32;
                for (b, body) in bodies.iter().enumerate() {
                    job.bodies[2 * b] = body.from.0.extend(body.from.1).to_array();
                    job.bodies[2 * b + 1] = body.to.0.extend(body.to.1).to_array();
                }
                up.water_steps.push(job);
                state.slot ^= 1;
                state.steps += 1;
            }
        }
        self.water.drops.clear();
        self.water.last = Some(now);
    }

    /// The first float of simulated water object `i`'s heights now in `SceneBuffers::heights` (None: it has no
    /// simulated surface).
    pub(super) fn heights_now(&self, i: usize) -> Option<u32> {
        let sb = &self.scene_buffers;
        let (Some(Deformer::Water(range)), Some(state)) = (sb.deformers[i], sb.simulations[i]) else { return None };
        let (base, k) = range.simulation?;
        Some(base + state.slot * k.nodes * k.nodes)
    }
}

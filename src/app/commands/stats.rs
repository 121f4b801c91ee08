//! The stats JSON of `render` and `profile`: the frame reports, the settings and the device, as
//! docs/cli.md documents them.

use super::*;

pub(super) fn level_rows(report: &FrameReport, max_level: u32) -> Vec<Value> {
    let Some(st) = report.state.as_ref() else {
        return Vec::new();
    };
    (0..=max_level.min(MAX_LEVELS - 1))
        .map(|l| {
            let c = st.levels[l as usize];
            json!({
                "level": l, "grid": LEVEL0_RES << l, "candidates": c.candidates, "refined": c.refined,
                "emitted": c.emitted, "dropped": c.dropped, "checks_skipped": c.checks_skipped,
                "unchecked": c.unchecked,
            })
        })
        .collect()
}

/// The stats JSON of docs/cli.md, over `frames` (the per-frame counts are the last frame's).
pub fn stats_json(session: &Session, frames: &[FrameReport], extra: Value) -> Value {
    let r = &session.renderer;
    let s = r.config();
    let last = frames.last().cloned().unwrap_or_default();
    let st = last.state;
    let info = &session.device().info;
    // Every light's photons (each light emits its own).
    let photons: u32 = last.lights.iter().filter_map(|l| l.state.map(|x| x.photons_total)).sum();
    let summaries = profiler::stage_summaries(frames);
    let stage = |name: &str| summaries.iter().find(|(l, _)| l == name).map(|(_, v)| *v).unwrap_or_default();
    let mut v = json!({
        "device": {"name": info.name, "driver": info.driver, "kind": caustics::gpu::kind_name(info.kind)},
        "validation": {"enabled": session.validation, "messages": caustics::gpu::validation_message_count()},
        "scene": session.scene_path.display().to_string(),
        "camera": session.camera.name,
        "size": [session.width, session.height],
        "method": s.method,
        "metric": if s.method == Method::Adaptive { json!(s.metric) } else { Value::Null },
        "target_error": flux_error(s).then_some(s.target_error),
        "tau": flux_error(s).then(|| s.tau()),
        "level": s.level,
        "check_level": (s.method == Method::Adaptive && s.metric != Metric::MaxLevel).then(|| s.check_level()),
        "equivalent_resolution": LEVEL0_RES << s.level,
        "driven": if s.method == Method::Adaptive { json!(s.driven) } else { Value::Null },
        "settings": s,
        "caustic_passes": last.caustics,
        "photons_splatted": photons,
        "host_readbacks_per_frame": last.host_readbacks,
        "scene_update": scene_update_json(frames),
        "continuations": last.continuations,
        "barrier_batches": last.barrier_batches,
        "photon_buffer_bytes": st.map(|x| 8 * x.peak_used as u64).unwrap_or(0),
        "photon_buffer_capacity_bytes": 8 * s.photon_capacity() as u64,
        "levels": level_rows(&last, s.level),
        "batches": st.map(|x| x.batches_committed).unwrap_or(0),
        "batch_slots": last.batch_slots,
        "overflow_events": st.map(|x| x.batches_aborted + (x.overflow_dropped > 0) as u32).unwrap_or(0),
        "overflow_dropped_entries": st.map(|x| x.overflow_dropped).unwrap_or(0),
        "unfinished_tiles": last.unfinished_tiles,
        "gpu_ms": profiler::gpu_json(&summaries),
        "gpu_substages_ms": profiler::summaries_json(&profiler::substage_summaries(frames)),
        "photons_per_ms": profiler::throughput_json(&summaries, photons as u64),
        "wall_ms": profiler::summary_json(&summaries, "frame_wall"),
        "cpu_ms": profiler::summary_json(&summaries, "cpu_record"),
        "gpu_total_ms": stage("gpu_total"),
        "frame_ms": stage("frame_wall"),
        "cpu_record_ms": stage("cpu_record"),
        "frames": frames.len(),
        "caustics_reused": last.reused,
        "photon_sets": last.photon_sets,
        "reused_frames": frames.iter().filter(|f| f.reused).count(),
        "eye_reused_frames": frames.iter().filter(|f| f.eye_reused).count(),
        "lights": light_rows(&session.renderer, &last),
        "transport": s.transport,
        "splat": s.splat.resolve(info),
        "footprint": s.footprint,
        "exact_transport": transport_json(session, &last),
        "photon_view": last.photon_view.map(|v| json!({
            "origin": v.origin.to_array(), "right": v.right.to_array(), "down": v.down.to_array(),
            "forward": v.forward.to_array(), "window": [v.window.x0, v.window.y0, v.window.w],
        })),
    });
    if let (Value::Object(m), Value::Object(e)) = (&mut v, extra) {
        m.extend(e);
    }
    v
}

/// Exact transport's stats: the BVH (with its host build time), the waves, and the energy account in W with its
/// residual (docs/design.md, "Exact transport's energy account").
pub(super) fn transport_json(session: &Session, report: &FrameReport) -> Value {
    let r = &session.renderer;
    if r.config().transport != Transport::Exact {
        return Value::Null;
    }
    let bvh = &r.scene_buffers().bvh;
    let queues = r.scene_settings();
    let mut v = json!({
        "bvh": {
            "layout": r.config().bvh_layout,
            "build_ms": bvh.build_ms,
            "triangles": bvh.triangle_count,
            "instances": bvh.instance_count,
            "nodes": bvh.node_count(r.config().bvh_layout),
        },
        "flux_threshold": r.config().flux_threshold,
        "weak_branches": r.config().weak_branches,
        "weak_block": r.config().weak_block(),
        "max_interactions": MAX_INTERACTIONS,
        // The queues as the frames size them.
        "ray_queue_capacity": queues.ray_queue_capacity(),
        "ray_bytes": queues.ray_bytes(),
        "media": queues.media,
    });
    if let Some(ts) = report.transport {
        if let Value::Object(m) = &mut v {
            m.insert("energy".into(), Value::Object(ts.account_json(r.scene().lights[0].intensity as f64)));
            m.insert("rays_traced".into(), json!(ts.rays_traced));
            m.insert("splat_records".into(), json!(ts.records_total));
            m.insert("waves".into(), json!(ts.waves));
            m.insert("wave_rays".into(), json!(ts.wave_rays()));
            m.insert("max_depth".into(), json!(ts.max_depth));
            m.insert("queue_overflows".into(), json!(ts.overflows));
        }
    }
    v
}

/// The scene updates of the frames: the last frame's, and every frame's summed (`render --frames` with a moving
/// object counts every move).
pub(super) fn scene_update_json(frames: &[caustics::FrameReport]) -> Value {
    let row = |u: &caustics::SceneUpdateReport| {
        json!({
            "moved_objects": u.moved_objects,
            "instance_bytes": u.instance_bytes,
            "blas_builds": u.blas_builds,
            "blas_refits": u.blas_refits,
            "deformed_objects": u.deformed_objects,
            "rebuilt": u.rebuilt,
            "blocking_submits": u.blocking_submits,
            "wait_idles": u.wait_idles,
        })
    };
    let mut all = caustics::SceneUpdateReport::default();
    for f in frames {
        all.add(&f.scene);
    }
    let last = frames.last().map(|f| f.scene).unwrap_or_default();
    json!({"last_frame": row(&last), "all_frames": row(&all)})
}

/// One row per pass (per light, or per light and color channel when some glass needs color): the light's kind
/// and power, the channel, whether its caustic stages ran, its photons, the GPU ms of its light-side stages in the
/// last frame and, under exact transport, its energy account.
pub(super) fn light_rows(r: &Renderer, last: &FrameReport) -> Value {
    let rows: Vec<Value> = last
        .lights
        .iter()
        .map(|rep| {
            let l = &r.scene().lights[rep.light];
            let channel = rep.channel_name();
            let mut row = json!({
                "light": rep.light,
                "face": rep.face,
                "channel": channel,
                "kind": format!("{:?}", l.kind).to_lowercase(),
                "intensity": l.intensity,
                "color": l.color.to_array(),
                "caustics": rep.caustics,
                "photons": rep.state.map(|x| x.photons_total).unwrap_or(0),
                "gpu_ms": rep.gpu_ms,
            });
            if let (Some(ts), Value::Object(m)) = (rep.transport, &mut row) {
                m.insert("energy".into(), Value::Object(ts.account_json(l.intensity as f64)));
                m.insert("rays_traced".into(), json!(ts.rays_traced));
            }
            row
        })
        .collect();
    Value::Array(rows)
}

pub(super) fn debug_photons_json(photons: &[caustics::DebugPhoton]) -> Value {
    let list: Vec<Value> = photons
        .iter()
        .map(|p| {
            json!({
                "x": p.x, "y": p.y, "level": p.level, "status": p.status, "radius": p.radius,
                "flux_r": p.flux_r, "uv": p.uv, "uv_bits": p.uv.map(f32::to_bits),
                "map_px": p.map_px,
                "hit": p.hit,
            })
        })
        .collect();
    Value::Array(list)
}

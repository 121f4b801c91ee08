//! The TOML scene format's water: a water object's block, waves, and simulated surface with its drops.

use super::*;

/// A water object's simulated surface and its drops (docs/scenes.md, "simulation"): drops alone simulate with
/// the defaults.
pub(super) fn simulation_def(
    cx: &Ctx,
    d: &ObjectDef,
    f: &dyn Fn(&str) -> String,
) -> Result<Option<water::Simulation>, SceneError> {
    let sim = d.simulation.as_ref();
    if sim.is_none() && d.drops.is_empty() {
        return Ok(None);
    }
    let get = |v: Option<&S<f32>>, field: &str, default: f32, ok: &dyn Fn(f32) -> bool, rule: &str| match v {
        Some(v) if !ok(*v.get_ref()) => {
            Err(cx.err(v.span(), f(&format!("simulation.{field}")), format!("{rule} (got {})", v.get_ref())))
        }
        Some(v) => Ok(*v.get_ref()),
        None => Ok(default),
    };
    let s = sim.map(|s| s.get_ref());
    let speed = get(s.and_then(|s| s.speed.as_ref()), "speed", 0.4, &|v| v.is_finite() && v > 0.0, "must be > 0 m/s")?;
    let damping =
        get(s.and_then(|s| s.damping.as_ref()), "damping", 0.5, &|v| v.is_finite() && v >= 0.0, "must be >= 0 per s")?;
    let limit = get(s.and_then(|s| s.limit.as_ref()), "limit", 0.05, &|v| v.is_finite() && v > 0.0, "must be > 0 m")?;
    let mut drops = Vec::new();
    let mut last = f32::NEG_INFINITY;
    for (k, dd) in d.drops.iter().enumerate() {
        let df = |field: &str| f(&format!("drops[{k}].{field}"));
        let dd = dd.get_ref();
        let t = *dd.time.get_ref();
        if !(t.is_finite() && t >= last && t >= 0.0) {
            return Err(cx.err(
                dd.time.span(),
                df("time"),
                format!("must be finite, >= 0 and not before the drop before it (got {t})"),
            ));
        }
        last = t;
        let at = *dd.at.get_ref();
        if !at.iter().all(|v| v.is_finite()) {
            return Err(cx.err(dd.at.span(), df("at"), FINITE));
        }
        let pos = |v: Option<&S<f32>>, field: &str, default: f32| match v {
            Some(v) if !(v.get_ref().is_finite() && *v.get_ref() > 0.0) => {
                Err(cx.err(v.span(), df(field), format!("must be > 0 m (got {})", v.get_ref())))
            }
            Some(v) => Ok(*v.get_ref()),
            None => Ok(default),
        };
        let radius = pos(dd.radius.as_ref(), "radius", 0.06)?;
        let depth = pos(dd.depth.as_ref(), "depth", 0.01)?;
        drops.push(water::Drop { time: t, at: glam::Vec2::from(at), radius, depth });
    }
    Ok(Some(water::Simulation { speed, damping, limit, drops }))
}

/// A water object's block and waves (docs/scenes.md, "waves").
pub(super) fn water_def(cx: &Ctx, o: &S<ObjectDef>, f: &dyn Fn(&str) -> String) -> Result<water::Water, SceneError> {
    let d = o.get_ref();
    let s = d.size.as_ref().ok_or_else(|| cx.err(o.span(), f("size"), "water needs `size = [x, z]`"))?;
    let size = positive_size(cx, f("size"), s, 2)?;
    let depth = match &d.depth {
        Some(v) if !(v.get_ref().is_finite() && *v.get_ref() > 0.0) => {
            return Err(cx.err(v.span(), f("depth"), format!("must be > 0 m (got {})", v.get_ref())))
        }
        Some(v) => *v.get_ref(),
        None => 0.3,
    };
    let grid = match &d.grid {
        Some(v) => {
            let g = *v.get_ref();
            if !(1..=water::MAX_GRID as i64).contains(&g) {
                return Err(cx.err(
                    v.span(),
                    f("grid"),
                    format!("must lie in 1..={} cells per side (got {g})", water::MAX_GRID),
                ));
            }
            g as u32
        }
        None => 64,
    };
    if d.waves.len() > water::MAX_WAVES {
        return Err(cx.err(
            d.waves[water::MAX_WAVES].span(),
            f(&format!("waves[{}]", water::MAX_WAVES)),
            format!("at most {} waves", water::MAX_WAVES),
        ));
    }
    let mut waves = Vec::new();
    for (k, w) in d.waves.iter().enumerate() {
        let wf = |field: &str| f(&format!("waves[{k}].{field}"));
        let w = w.get_ref();
        let a = *w.amplitude.get_ref();
        if !(a.is_finite() && a >= 0.0) {
            return Err(cx.err(w.amplitude.span(), wf("amplitude"), format!("must be finite and >= 0 m (got {a})")));
        }
        let l = *w.wavelength.get_ref();
        if !(l.is_finite() && l > 0.0) {
            return Err(cx.err(w.wavelength.span(), wf("wavelength"), format!("must be > 0 m (got {l})")));
        }
        let dir = match &w.direction_deg {
            Some(v) if !v.get_ref().is_finite() => return Err(cx.err(v.span(), wf("direction_deg"), FINITE)),
            Some(v) => v.get_ref().to_radians(),
            None => 0.0,
        };
        let speed = match &w.speed {
            Some(v) if !v.get_ref().is_finite() => return Err(cx.err(v.span(), wf("speed"), FINITE)),
            Some(v) => *v.get_ref(),
            None => water::Wave::deep_water_speed(l),
        };
        waves.push(water::Wave {
            amplitude: a,
            wavelength: l,
            direction: glam::Vec2::new(dir.cos(), dir.sin()),
            speed,
        });
    }
    let simulation = simulation_def(cx, d, f)?;
    let w = water::Water { size: glam::Vec2::new(size.x, size.z), depth, grid, waves, simulation };
    if w.max_height() >= depth {
        let span = d.waves.first().map_or(o.span(), |v| v.span());
        return Err(cx.err(
            span,
            f("waves"),
            format!("the amplitudes add up to {} m: they must stay below the depth, {depth} m", w.max_height()),
        ));
    }
    Ok(w)
}

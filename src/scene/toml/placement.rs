//! The TOML scene format's placement: an object's transform and its keyframes.

use super::*;

/// An object's `[[object.keyframe]]` tables as its animation (None without any), each keyframe's missing
/// components taken from the object's own `translate`, `rotate_deg` and `scale` (`rest`).
pub(super) fn keyframes(
    cx: &Ctx,
    d: &ObjectDef,
    f: &dyn Fn(&str) -> String,
    rest: (Vec3, Quat, Vec3),
) -> Result<Option<animation::Animation>, SceneError> {
    use animation::{Animation, Interpolation, Motion, Repeat, Track};
    if d.keyframe.is_empty() {
        for (field, span) in [
            ("interpolation", d.interpolation.as_ref().map(|v| v.span())),
            ("repeat", d.repeat.as_ref().map(|v| v.span())),
        ] {
            if let Some(span) = span {
                return Err(cx.err(span, f(field), format!("`{field}` needs keyframes ([[object.keyframe]])")));
            }
        }
        return Ok(None);
    }
    let interpolation = match d.interpolation.as_ref() {
        None => Interpolation::Linear,
        Some(v) => match v.get_ref().as_str() {
            "linear" => Interpolation::Linear,
            "step" => Interpolation::Step,
            other => {
                return Err(cx.err(
                    v.span(),
                    f("interpolation"),
                    format!("unknown interpolation `{other}` (expected \"linear\" or \"step\")"),
                ))
            }
        },
    };
    let repeat = match d.repeat.as_ref() {
        None => Repeat::Clamp,
        Some(v) => match v.get_ref().as_str() {
            "clamp" => Repeat::Clamp,
            "loop" => Repeat::Loop,
            other => {
                return Err(cx.err(
                    v.span(),
                    f("repeat"),
                    format!("unknown repeat `{other}` (expected \"clamp\" or \"loop\")"),
                ))
            }
        },
    };
    let (mut times, mut tr, mut rot, mut sc): (Vec<f32>, Vec<Vec3>, Vec<Quat>, Vec<Vec3>) = Default::default();
    for (k, key) in d.keyframe.iter().enumerate() {
        let key = key.get_ref();
        let kf = |field: &str| f(&format!("keyframe[{k}].{field}"));
        let t = *key.time.get_ref();
        if !(t.is_finite() && t >= 0.0) {
            return Err(cx.err(key.time.span(), kf("time"), format!("must be finite and >= 0 s (got {t})")));
        }
        if let Some(&last) = times.last() {
            if t <= last {
                return Err(cx.err(
                    key.time.span(),
                    kf("time"),
                    format!("keyframe times must increase: {t} s follows {last} s"),
                ));
            }
        }
        let translate = match &key.translate {
            Some(v) if !finite3(*v.get_ref()) => return Err(cx.err(v.span(), kf("translate"), FINITE)),
            Some(v) => Vec3::from(*v.get_ref()),
            None => rest.0,
        };
        let rotate = match &key.rotate_deg {
            Some(v) if !finite3(*v.get_ref()) => return Err(cx.err(v.span(), kf("rotate_deg"), FINITE)),
            Some(v) => animation::euler_deg(Vec3::from(*v.get_ref())),
            None => rest.1,
        };
        let scale = match &key.scale {
            Some(v) => {
                let x = Vec3::from(v.get_ref().to_array());
                if !x.is_finite() || x.abs().min_element() < 1e-9 {
                    return Err(cx.err(v.span(), kf("scale"), "must be finite and non-zero"));
                }
                x
            }
            None => rest.2,
        };
        if let Some(&last) = sc.last() {
            // Between keyframes the scale is interpolated: through zero, the object would collapse.
            if (scale * last).min_element() < 0.0 {
                let span = key.scale.as_ref().map_or(key.time.span(), |v| v.span());
                return Err(cx.err(span, kf("scale"), "each component must keep its sign from keyframe to keyframe"));
            }
        }
        times.push(t);
        tr.push(translate);
        rot.push(rotate);
        sc.push(scale);
    }
    let motion = Motion {
        translation: Some(Track::new(times.clone(), tr, interpolation)),
        rotation: Some(Track::new(times.clone(), rot, interpolation)),
        scale: Some(Track::new(times, sc, interpolation)),
        ..Motion::rest(rest)
    };
    Ok(Some(Animation::single(motion, repeat)))
}

/// Places the object's mesh: its `translate`, `rotate_deg` and `scale`, and its keyframes (with its water, its
/// animation). Returns the mesh at time 0 in world space, and the animation.
pub(super) fn placement(
    cx: &Ctx,
    o: &S<ObjectDef>,
    f: &dyn Fn(&str) -> String,
    mesh: Mesh,
    water: Option<water::Water>,
) -> Result<(Mesh, Option<std::sync::Arc<ObjectAnimation>>), SceneError> {
    let d = o.get_ref();
    let shape = d.shape.get_ref().as_str();
    let mut transform = Mat4::IDENTITY;
    let translate = match &d.translate {
        Some(t) if !finite3(*t.get_ref()) => return Err(cx.err(t.span(), f("translate"), FINITE)),
        Some(t) => Vec3::from(*t.get_ref()),
        None => Vec3::ZERO,
    };
    let rotate = match &d.rotate_deg {
        Some(r) if !finite3(*r.get_ref()) => return Err(cx.err(r.span(), f("rotate_deg"), FINITE)),
        Some(r) => Vec3::from(*r.get_ref()),
        None => Vec3::ZERO,
    };
    let scale = match &d.scale {
        Some(s) => {
            let v = Vec3::from(s.get_ref().to_array());
            if !v.is_finite() || v.abs().min_element() < 1e-9 {
                return Err(cx.err(s.span(), f("scale"), "must be finite and non-zero"));
            }
            v
        }
        None => Vec3::ONE,
    };
    if d.translate.is_some() || d.rotate_deg.is_some() || d.scale.is_some() {
        // Scale, then rotate about x, then y, then z, then translate.
        transform = Mat4::from_scale_rotation_translation(scale, animation::euler_deg(rotate), translate);
    }
    let keyed = keyframes(cx, d, &f, (translate, animation::euler_deg(rotate), scale))?;
    let animation = (keyed.is_some() || water.is_some()).then(|| {
        std::sync::Arc::new(ObjectAnimation {
            mesh: mesh.clone(),
            animation: keyed,
            placement: transform,
            water: water.clone(),
            morph: None,
        })
    });
    if let Some(a) = &animation {
        transform = a.transform_at(0.0);
        // Every keyframe's placement lands within the coordinates' range (interpolation stays between them).
        for (k, key) in d.keyframe.iter().enumerate() {
            let m = a.transform_at(*key.get_ref().time.get_ref());
            if let Some(p) = a.mesh.positions.iter().map(|p| m.transform_point3(*p)).find(|p| !finite3(p.to_array())) {
                return Err(cx.err(
                    key.span(),
                    f(&format!("keyframe[{k}]")),
                    format!("a vertex lands at {p} in world space; coordinates must be finite (within ±1e9 m)"),
                ));
            }
        }
    }
    let mesh = match &animation {
        Some(a) => a.mesh_at(0.0),
        None if transform == Mat4::IDENTITY => mesh,
        None => mesh.transformed(transform),
    };
    if let Some(p) = mesh.positions.iter().find(|p| !finite3(p.to_array())) {
        let (field, span) = match (&d.scale, &d.translate) {
            (Some(s), _) => ("scale", s.span()),
            (None, Some(t)) => ("translate", t.span()),
            _ => match shape {
                "sphere" => ("radius", d.radius.as_ref().map_or(o.span(), |r| r.span())),
                "mesh" => ("path", d.path.as_ref().map_or(o.span(), |r| r.span())),
                _ => ("size", d.size.as_ref().map_or(o.span(), |r| r.span())),
            },
        };
        return Err(cx.err(
            span,
            f(field),
            format!("a vertex lands at {p} in world space; coordinates must be finite (within ±1e9 m)"),
        ));
    }
    Ok((mesh, animation))
}

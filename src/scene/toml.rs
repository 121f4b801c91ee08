//! The TOML scene format (docs/scenes.md): its parser, with the file, line and field of every error.

use super::schema::*;
use super::*;

struct Ctx<'a> {
    file: String,
    text: &'a str,
    dir: PathBuf,
}

impl Ctx<'_> {
    fn line(&self, offset: usize) -> usize {
        self.text[..offset.min(self.text.len())].bytes().filter(|&b| b == b'\n').count() + 1
    }
    fn err(&self, span: std::ops::Range<usize>, field: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError::Field {
            file: self.file.clone(),
            line: self.line(span.start),
            field: field.into(),
            message: message.into(),
        }
    }
}

/// Finite, and within ±[`mesh::MAX_COORDINATE`] (differences and squared lengths of such points stay finite).
fn finite3(v: [f32; 3]) -> bool {
    v.iter().all(|x| x.is_finite() && x.abs() <= mesh::MAX_COORDINATE)
}

/// Parses scene text; `path` locates the file for messages and relative mesh paths.
pub(super) fn parse(text: &str, path: &Path) -> Result<Scene, SceneError> {
    let cx =
        Ctx { file: path.display().to_string(), text, dir: path.parent().map(Path::to_path_buf).unwrap_or_default() };
    let file: SceneFile = ::toml::from_str(text).map_err(|e| {
        let start = e.span().map(|s| s.start).unwrap_or(0);
        let line = cx.line(start);
        let column = start - text[..start.min(text.len())].rfind('\n').map(|i| i + 1).unwrap_or(0) + 1;
        SceneError::Syntax { file: cx.file.clone(), line, column, message: e.message().trim().to_string() }
    })?;
    let lights = file.light.iter().enumerate().map(|(i, l)| light(&cx, i, l)).collect::<Result<Vec<_>, _>>()?;
    if lights.is_empty() {
        return Err(cx.err(0..0, "light", "the scene needs at least one [[light]]"));
    }
    if lights.len() > MAX_LIGHTS {
        let extra = &file.light[MAX_LIGHTS];
        return Err(cx.err(
            extra.span(),
            format!("light[{MAX_LIGHTS}]"),
            format!("the scene has {} lights; at most {MAX_LIGHTS} are supported", lights.len()),
        ));
    }
    let mut cameras = Vec::new();
    for (i, c) in file.camera.iter().enumerate() {
        let cam = camera(&cx, i, c)?;
        if cameras.iter().any(|o: &Camera| o.name == cam.name) {
            return Err(cx.err(
                c.get_ref().name.span(),
                format!("camera[{i}].name"),
                format!("duplicate camera name `{}`", cam.name),
            ));
        }
        cameras.push(cam);
    }
    let mut objects = Vec::new();
    let mut textures = Textures::default();
    // An object whose OBJ's materials split it (`kind = "mtl"`) is its first part here, the others after every
    // object, so that `objects[i]` is `file.object[i]` for `media`.
    let mut parts: Vec<Object> = Vec::new();
    for (i, o) in file.object.iter().enumerate() {
        for (k, obj) in object(&cx, i, o, &mut textures)?.into_iter().enumerate() {
            if objects.iter().chain(&parts).any(|x: &Object| x.name == obj.name) {
                return Err(cx.err(
                    o.get_ref().name.span(),
                    format!("object[{i}].name"),
                    format!("duplicate object name `{}`", obj.name),
                ));
            }
            if k == 0 {
                objects.push(obj);
            } else {
                parts.push(obj);
            }
        }
    }
    if objects.is_empty() {
        return Err(cx.err(0..0, "object", "the scene needs at least one [[object]]"));
    }
    media(&cx, &file.object, &mut objects)?;
    objects.extend(parts);
    let environment = match &file.environment {
        Some(e) => Some(environment_def(&cx, e)?),
        None => None,
    };
    let mut scene = Scene {
        path: path.to_path_buf(),
        lights,
        cameras,
        objects,
        time: 0.0,
        textures: textures.list,
        environment,
        movers: Vec::new(),
        animations: Vec::new(),
        playing: None,
        properties: Vec::new(),
    };
    scene.aim_point_lights();
    for (i, l) in scene.lights.iter().enumerate() {
        if (l.target - l.position).length() < 1e-6 {
            return Err(cx.err(
                file.light[i].span(),
                format!("light[{i}].target"),
                "a point light without `target` aims at the center of the glass, which is where it stands: give a `target`",
            ));
        }
    }
    Ok(scene)
}

fn light(cx: &Ctx, i: usize, l: &S<LightDef>) -> Result<Light, SceneError> {
    let d = l.get_ref();
    let f = |name: &str| format!("light[{i}].{name}");
    let kind = match d.kind.get_ref().as_str() {
        "spot" => LightKind::Spot,
        "directional" | "sun" => LightKind::Directional,
        "point" => LightKind::Point,
        other => {
            return Err(cx.err(
                d.kind.span(),
                f("kind"),
                format!("unknown light kind `{other}` (expected \"spot\", \"directional\", \"sun\" or \"point\")"),
            ))
        }
    };
    let angular_radius = angular_radius(cx, i, d)?;
    let radius = match (&d.radius, kind) {
        (None, _) => 0.0,
        (Some(r), LightKind::Directional) => {
            return Err(cx.err(
                r.span(),
                f("radius"),
                "a directional light has no radius (a sun's size is its `angular_diameter_deg`)",
            ))
        }
        (Some(r), _) => {
            let v = *r.get_ref();
            if !(v.is_finite() && v >= 0.0) {
                return Err(cx.err(r.span(), f("radius"), format!("must be finite and >= 0 (got {v})")));
            }
            v
        }
    };
    let required = |v: Option<S<[f32; 3]>>, name: &str| {
        v.ok_or_else(|| cx.err(l.span(), f(name), format!("a light needs `{name}` (missing field `{name}`)")))
    };
    let position_s = required(d.position.clone(), "position")?;
    // A point light's target only aims its maps: by default, the center of the glass (set once the objects are
    // known; NaN marks it here).
    let target_s = match (kind, d.target.clone()) {
        (LightKind::Point, None) => S::new(0..0, [f32::NAN; 3]),
        (_, t) => required(t, "target")?,
    };
    let intensity_s = d
        .intensity
        .clone()
        .ok_or_else(|| cx.err(l.span(), f("intensity"), "a light needs `intensity` (missing field `intensity`)"))?;
    let position = *position_s.get_ref();
    let target = *target_s.get_ref();
    if !finite3(position) {
        return Err(cx.err(position_s.span(), f("position"), FINITE));
    }
    let default_target = kind == LightKind::Point && d.target.is_none();
    if !default_target && !finite3(target) {
        return Err(cx.err(target_s.span(), f("target"), FINITE));
    }
    if !default_target && (Vec3::from(target) - Vec3::from(position)).length() < 1e-6 {
        return Err(cx.err(target_s.span(), f("target"), "must differ from the position"));
    }
    let cone = match (kind, &d.cone_deg) {
        (LightKind::Spot, Some(c)) => {
            let v = *c.get_ref();
            if !(v > 0.0 && v < 90.0) {
                return Err(cx.err(
                    c.span(),
                    f("cone_deg"),
                    format!("cone half-angle must lie in (0, 90) degrees (got {v})"),
                ));
            }
            v.to_radians()
        }
        (LightKind::Spot, None) => return Err(cx.err(l.span(), f("cone_deg"), "a spot light needs `cone_deg`")),
        (LightKind::Directional, Some(c)) => {
            return Err(cx.err(c.span(), f("cone_deg"), "a directional light has no cone"));
        }
        (LightKind::Directional, None) => 0.0,
        (LightKind::Point, Some(c)) => {
            return Err(cx.err(c.span(), f("cone_deg"), "a point light has no cone (it shines every way)"));
        }
        (LightKind::Point, None) => std::f32::consts::PI,
    };
    let intensity = *intensity_s.get_ref();
    if !(intensity.is_finite() && intensity >= 0.0) {
        return Err(cx.err(intensity_s.span(), f("intensity"), format!("must be finite and >= 0 (got {intensity})")));
    }
    let color = match &d.color {
        Some(c) => {
            let v = *c.get_ref();
            if !v.iter().all(|x| x.is_finite() && *x >= 0.0) {
                return Err(cx.err(c.span(), f("color"), "components must be finite and >= 0"));
            }
            Vec3::from(v)
        }
        None => Vec3::ONE,
    };
    Ok(Light { kind, position: position.into(), target: target.into(), cone, intensity, color, angular_radius, radius })
}

/// The Sun's mean angular diameter seen from the Earth, degrees: a `sun`'s by default.
pub const SUN_DIAMETER_DEG: f32 = 0.53;

/// A directional light's angular radius (radians) from `angular_diameter_deg`: a `sun`'s 0.53° by default, a
/// `directional` light's 0 (parallel rays); no other kind has one.
fn angular_radius(cx: &Ctx, i: usize, d: &LightDef) -> Result<f32, SceneError> {
    let name = format!("light[{i}].angular_diameter_deg");
    let kind = d.kind.get_ref().as_str();
    let deg = match (&d.angular_diameter_deg, kind) {
        (None, "sun") => SUN_DIAMETER_DEG,
        (None, _) => 0.0,
        (Some(a), "sun" | "directional") => *a.get_ref(),
        (Some(a), _) => {
            return Err(cx.err(
                a.span(),
                name,
                format!("a {kind} light has no angular diameter (a sun or a directional light has)"),
            ))
        }
    };
    if !(0.0..=20.0).contains(&deg) {
        let span = d.angular_diameter_deg.as_ref().map_or(d.kind.span(), |a| a.span());
        return Err(cx.err(span, name, format!("must lie in [0, 20] degrees (got {deg})")));
    }
    Ok(0.5 * deg.to_radians())
}

fn camera(cx: &Ctx, i: usize, c: &S<CameraDef>) -> Result<Camera, SceneError> {
    let d = c.get_ref();
    let f = |name: &str| format!("camera[{i}].{name}");
    let name = d.name.get_ref().clone();
    if name.is_empty() {
        return Err(cx.err(d.name.span(), f("name"), "must not be empty"));
    }
    let position = Vec3::from(*d.position.get_ref());
    let target = Vec3::from(*d.target.get_ref());
    if !finite3(position.to_array()) || !finite3(target.to_array()) || (target - position).length() < 1e-6 {
        return Err(cx.err(d.target.span(), f("target"), "position and target must be finite and distinct"));
    }
    let up = d.up.as_ref().map(|u| Vec3::from(*u.get_ref())).unwrap_or(Vec3::Y);
    let forward = (target - position).normalize();
    if !up.is_finite() || up.length() < 1e-6 || forward.cross(up.normalize()).length() < 1e-4 {
        let span = d.up.as_ref().map(|u| u.span()).unwrap_or(c.span());
        return Err(cx.err(span, f("up"), "must be a non-zero vector not parallel to the view direction"));
    }
    let projection = match d.kind.get_ref().as_str() {
        "orthographic" => {
            if let Some(v) = &d.fov_deg {
                return Err(cx.err(
                    v.span(),
                    f("fov_deg"),
                    "an orthographic camera takes `half_height`, not `fov_deg`",
                ));
            }
            let h = d
                .half_height
                .as_ref()
                .ok_or_else(|| cx.err(c.span(), f("half_height"), "an orthographic camera needs `half_height`"))?;
            let v = *h.get_ref();
            if !(v.is_finite() && v > 0.0) {
                return Err(cx.err(h.span(), f("half_height"), format!("must be > 0 (got {v})")));
            }
            Projection::Orthographic { half_height: v }
        }
        "perspective" => {
            if let Some(v) = &d.half_height {
                return Err(cx.err(
                    v.span(),
                    f("half_height"),
                    "a perspective camera takes `fov_deg`, not `half_height`",
                ));
            }
            let h = d
                .fov_deg
                .as_ref()
                .ok_or_else(|| cx.err(c.span(), f("fov_deg"), "a perspective camera needs `fov_deg`"))?;
            let v = *h.get_ref();
            if !(v > 0.0 && v < 180.0) {
                return Err(cx.err(h.span(), f("fov_deg"), format!("must lie in (0, 180) degrees (got {v})")));
            }
            Projection::Perspective { fov: v.to_radians() }
        }
        other => {
            return Err(cx.err(
                d.kind.span(),
                f("kind"),
                format!("unknown camera kind `{other}` (expected \"orthographic\" or \"perspective\")"),
            ))
        }
    };
    Ok(Camera { name, projection, position, target, up: up.normalize(), aspect: None })
}

fn positive_size(cx: &Ctx, field: String, v: &S<::toml::Value>, n: usize) -> Result<Vec3, SceneError> {
    let bad =
        || cx.err(v.span(), field.clone(), format!("must be a positive number or an array of {n} positive numbers"));
    let num = |x: &::toml::Value| match x {
        ::toml::Value::Float(f) => Some(*f as f32),
        ::toml::Value::Integer(i) => Some(*i as f32),
        _ => None,
    };
    let vals: Vec<f32> = match v.get_ref() {
        ::toml::Value::Array(a) if a.len() == n => a.iter().map(num).collect::<Option<Vec<_>>>().ok_or_else(bad)?,
        x => vec![num(x).ok_or_else(bad)?; n],
    };
    if !vals.iter().all(|x| x.is_finite() && *x > 0.0) {
        return Err(bad());
    }
    Ok(if n == 2 { Vec3::new(vals[0], 0.0, vals[1]) } else { Vec3::new(vals[0], vals[1], vals[2]) })
}

/// A water object's simulated surface and its drops (docs/scenes.md, "simulation"): drops alone simulate with
/// the defaults.
fn simulation_def(
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
fn water_def(cx: &Ctx, o: &S<ObjectDef>, f: &dyn Fn(&str) -> String) -> Result<water::Water, SceneError> {
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

/// An object's `[[object.keyframe]]` tables as its animation (None without any), each keyframe's missing
/// components taken from the object's own `translate`, `rotate_deg` and `scale` (`rest`).
fn keyframes(
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

fn environment_def(cx: &Ctx, e: &S<EnvironmentDef>) -> Result<Environment, SceneError> {
    let d = e.get_ref();
    let full = cx.dir.join(d.path.get_ref());
    let map = EnvironmentMap::load(&full).map_err(|m| cx.err(d.path.span(), "environment.path", m))?;
    let intensity = match &d.intensity {
        Some(i) => {
            let v = *i.get_ref();
            if !(v.is_finite() && v >= 0.0) {
                return Err(cx.err(i.span(), "environment.intensity", format!("must be finite and >= 0 (got {v})")));
            }
            v
        }
        None => 1.0,
    };
    Ok(Environment { map: std::sync::Arc::new(map), intensity })
}

/// The textures a scene file's materials have named so far, each file (or checker) loaded once.
#[derive(Default)]
struct Textures {
    list: Vec<std::sync::Arc<Texture>>,
    by_key: std::collections::HashMap<String, usize>,
}

impl Textures {
    fn get_or(&mut self, key: String, make: impl FnOnce() -> Result<Texture, String>) -> Result<usize, String> {
        if let Some(&i) = self.by_key.get(&key) {
            return Ok(i);
        }
        self.list.push(std::sync::Arc::new(make()?));
        self.by_key.insert(key, self.list.len() - 1);
        Ok(self.list.len() - 1)
    }

    /// The image file at `full` (a scene's `albedo_texture`, an MTL's `map_Kd`), decoded once.
    fn file(&mut self, full: &Path) -> Result<usize, String> {
        self.get_or(format!("file:{}", full.display()), || {
            if !full.is_file() {
                return Err(format!("texture file not found: {}", full.display()));
            }
            Texture::load(full)
        })
    }
}

/// A diffuse material's albedo map from `albedo_texture` or `checker`, and `uv_scale` (None: neither given), and
/// the albedo factor it multiplies (`albedo` is the checker's first color, and the texture's factor, default 1).
fn albedo_map(
    cx: &Ctx,
    m: &MaterialDef,
    mf: &dyn Fn(&str) -> String,
    textures: &mut Textures,
    albedo: Option<Vec3>,
) -> Result<Option<(AlbedoMap, Vec3)>, SceneError> {
    let in_unit = |a: &S<ScalarOr3>, field: &str| {
        let v = Vec3::from(a.get_ref().to_array());
        if !v.is_finite() || v.min_element() < 0.0 || v.max_element() > 1.0 {
            return Err(cx.err(a.span(), mf(field), "must lie in [0, 1]"));
        }
        Ok(v)
    };
    let map = match (&m.albedo_texture, &m.checker) {
        (Some(_), Some(c)) => {
            return Err(cx.err(c.span(), mf("checker"), "give `albedo_texture` or `checker`, not both"));
        }
        (Some(p), None) => {
            let i = textures.file(&cx.dir.join(p.get_ref())).map_err(|e| cx.err(p.span(), mf("albedo_texture"), e))?;
            (AlbedoMap::new(i), albedo.unwrap_or(Vec3::ONE))
        }
        (None, Some(c)) => {
            let squares = *c.get_ref().squares.get_ref();
            if !(1..=128).contains(&squares) {
                return Err(cx.err(c.get_ref().squares.span(), mf("checker.squares"), "must lie in 1..=128"));
            }
            let a = albedo.unwrap_or(Vec3::splat(0.8));
            let b = in_unit(&c.get_ref().albedo, "checker.albedo")?;
            let key = format!("checker:{squares}:{a}:{b}");
            let i = textures
                .get_or(key, || Ok(Texture::checker(a, b, squares as u32)))
                .map_err(|e| cx.err(c.span(), mf("checker"), e))?;
            (AlbedoMap::new(i), Vec3::ONE)
        }
        (None, None) => {
            if let Some(s) = &m.uv_scale {
                return Err(cx.err(s.span(), mf("uv_scale"), "`uv_scale` needs `albedo_texture` or `checker`"));
            }
            return Ok(None);
        }
    };
    let scale = match &m.uv_scale {
        Some(s) => {
            let v = match *s.get_ref() {
                ScalarOr2::Scalar(x) => glam::Vec2::splat(x),
                ScalarOr2::Vec2(v) => glam::Vec2::from(v),
            };
            if !(v.is_finite() && v.abs().min_element() > 0.0) {
                return Err(cx.err(s.span(), mf("uv_scale"), "must be finite and non-zero"));
            }
            v
        }
        None => glam::Vec2::ONE,
    };
    Ok(Some((map.0.scaled(scale), map.1)))
}

/// The object (or, for a mesh with `kind = "mtl"`, one per material its faces use).
fn object(cx: &Ctx, i: usize, o: &S<ObjectDef>, textures: &mut Textures) -> Result<Vec<Object>, SceneError> {
    let d = o.get_ref();
    let name = d.name.get_ref().clone();
    let f = |field: &str| format!("object[{i}] \"{name}\".{field}");
    if name.is_empty() {
        return Err(cx.err(d.name.span(), format!("object[{i}].name"), "must not be empty"));
    }
    if d.material.get_ref().kind.get_ref() == "mtl" {
        return mtl_objects(cx, o, &f, textures);
    }
    let (mesh, water) = shape(cx, o, &f)?;
    let (mesh, animation) = placement(cx, o, &f, mesh, water)?;
    let material = material(cx, o, &f, textures, &mesh)?;
    Ok(vec![Object { name, material, mesh, animation, outside: None, priority: 0 }])
}

/// A `mesh` whose material is `{ kind = "mtl" }`: one object per MTL material its faces use (named
/// `NAME/MATERIAL` when there are several), each placed as the object says (docs/scenes.md, "OBJ materials").
fn mtl_objects(
    cx: &Ctx,
    o: &S<ObjectDef>,
    f: &dyn Fn(&str) -> String,
    textures: &mut Textures,
) -> Result<Vec<Object>, SceneError> {
    let d = o.get_ref();
    let m = d.material.get_ref();
    let mf = |field: &str| f(&format!("material.{field}"));
    let others = [
        ("albedo", m.albedo.as_ref().map(|x| x.span())),
        ("ior", m.ior.as_ref().map(|x| x.span())),
        ("absorption", m.absorption.as_ref().map(|x| x.span())),
        ("abbe", m.abbe.as_ref().map(|x| x.span())),
        ("outside", m.outside.as_ref().map(|x| x.span())),
        ("inside", m.inside.as_ref().map(|x| x.span())),
        ("priority", m.priority.as_ref().map(|x| x.span())),
        ("albedo_texture", m.albedo_texture.as_ref().map(|x| x.span())),
        ("checker", m.checker.as_ref().map(|x| x.span())),
        ("uv_scale", m.uv_scale.as_ref().map(|x| x.span())),
    ];
    if let Some((field, Some(span))) = others.into_iter().find(|(_, s)| s.is_some()) {
        return Err(cx.err(
            span,
            mf(field),
            format!("`{field}` does not apply to `kind = \"mtl\"`: the MTL file gives it"),
        ));
    }
    if d.shape.get_ref() != "mesh" {
        return Err(cx.err(
            m.kind.span(),
            mf("kind"),
            "`mtl` reads the materials of an OBJ file: only shape \"mesh\" has one",
        ));
    }
    shape_fields(cx, o, f)?;
    let (full, span) = obj_path(cx, o, f)?;
    let obj = mesh::load_obj_parts(&full).map_err(|e| cx.err(span.clone(), f("path"), e))?;
    let several = obj.parts.len() > 1;
    let mut out = Vec::new();
    for (k, part, report) in obj.parts {
        let mtl = k.map(|k| &obj.materials[k]);
        let label = mtl.map_or("(none)", |m| m.name.as_str());
        let name = if several { format!("{}/{label}", d.name.get_ref()) } else { d.name.get_ref().clone() };
        let (mesh, animation) = placement(cx, o, f, part, None)?;
        let material = mtl_material(mtl, textures, &mesh)
            .map_err(|e| cx.err(span.clone(), f("path"), format!("{}: {e}", full.display())))?;
        let glass = matches!(material, Material::Dielectric { .. });
        warn_findings(cx, &span, f, &format!("{}: material `{label}`", full.display()), &report, glass);
        out.push(Object { name, material, mesh, animation, outside: None, priority: 0 });
    }
    Ok(out)
}

/// An MTL material as the renderer's (docs/scenes.md, "OBJ materials"); `mesh` is its part, in world space (its
/// uvs for a texture, its box for `Tf`). None: faces without a material, diffuse gray. Errors and warnings start
/// with the material's `FILE:LINE`.
fn mtl_material(mtl: Option<&mtl::MtlMaterial>, textures: &mut Textures, mesh: &Mesh) -> Result<Material, String> {
    let Some(m) = mtl else {
        log::warn!(
            "faces without an MTL material (no `usemtl`, or one naming no material of the files) are diffuse gray"
        );
        return Ok(Material::diffuse(Vec3::splat(0.8)));
    };
    let at = format!("{} `{}`", m.at, m.name);
    if let Some(ke) = m.ke.filter(|k| k.max_element() > 0.0) {
        log::warn!("{at}: `Ke {} {} {}` is not rendered: surfaces do not emit light here", ke.x, ke.y, ke.z);
    }
    if let Some(d) = m.dissolve.filter(|&d| d < 1.0 && m.kind() != mtl::Kind::Glass) {
        log::warn!(
            "{at}: `d {d}` with `illum {}` is drawn opaque: the renderer has no partly dissolved surfaces (`illum` 4, 6, \
             7 or 9 makes glass)",
            m.illum.unwrap_or(2)
        );
    }
    match m.kind() {
        mtl::Kind::Glass => {
            let ior = m.ni.unwrap_or(1.5);
            // Tf: what a ray keeps crossing the part's thinnest extent (the format gives no distance).
            let mut absorption = Vec3::ZERO;
            if let Some(tf) = m.tf.filter(|t| t.min_element() < 1.0) {
                let (lo, hi) = mesh.bounds();
                let thin = (hi - lo).min_element();
                if thin > 0.0 {
                    absorption = -tf.max(Vec3::splat(1e-6)).map(f32::ln) / thin;
                }
            }
            Ok(Material::Dielectric { ior, absorption, abbe: 0.0 })
        }
        mtl::Kind::Mirror => Ok(Material::Mirror),
        mtl::Kind::Diffuse => {
            let Some((file, scale, offset)) = &m.map_kd else {
                return Ok(Material::diffuse(m.kd.unwrap_or(Vec3::splat(0.8))));
            };
            if mesh.uvs.len() != mesh.positions.len() {
                return Err(format!(
                    "{at}: `map_Kd {file}`: the mesh has no texture coordinates (`vt` on every vertex)"
                ));
            }
            let full = Path::new(&m.file).parent().unwrap_or(Path::new("")).join(file);
            let i = textures.file(&full).map_err(|e| format!("{at}: `map_Kd`: {e}"))?;
            // -s and -o act on OBJ's uv (v up); the mesh's v runs down: v' = s·v + (1 − s − o) in its terms.
            let mut map = AlbedoMap::new(i);
            map.uv_transform = [[scale.x, 0.0, offset.x], [0.0, scale.y, 1.0 - scale.y - offset.y]];
            Ok(Material::Diffuse { albedo: m.kd.unwrap_or(Vec3::ONE), map: Some(map) })
        }
    }
}

/// The object's mesh in its own space, as its shape and the shape's fields say (and its water, for a water
/// surface). A field that does not apply to the shape is refused, so that a typo'd scene never silently ignores a
/// value.
fn shape(cx: &Ctx, o: &S<ObjectDef>, f: &dyn Fn(&str) -> String) -> Result<(Mesh, Option<water::Water>), SceneError> {
    let d = o.get_ref();
    let shape = shape_fields(cx, o, f)?;
    let water = if shape == "water" { Some(water_def(cx, o, f)?) } else { None };
    let mesh = match shape {
        "water" => water.as_ref().expect("water").rest_mesh(),
        "plane" => {
            let s = d.size.as_ref().ok_or_else(|| cx.err(o.span(), f("size"), "a plane needs `size = [x, z]`"))?;
            let v = positive_size(cx, f("size"), s, 2)?;
            mesh::plane(v.x, v.z)
        }
        "cube" => {
            let s = d.size.as_ref().ok_or_else(|| cx.err(o.span(), f("size"), "a cube needs `size`"))?;
            mesh::cube(positive_size(cx, f("size"), s, 3)?)
        }
        "room" => room_mesh(cx, o, f)?,
        "lathe" => lathe_mesh(cx, o, f)?,
        "sphere" => sphere_mesh(cx, o, f)?,
        _ => obj_mesh(cx, o, f)?,
    };
    Ok((mesh, water))
}

/// The object's shape, once each field it has applies to it.
fn shape_fields<'a>(cx: &Ctx, o: &'a S<ObjectDef>, f: &dyn Fn(&str) -> String) -> Result<&'a str, SceneError> {
    let d = o.get_ref();
    let shape = d.shape.get_ref().as_str();
    let allowed: &[&str] = match shape {
        "plane" => &["size"],
        "sphere" => &["radius", "subdivisions"],
        "cube" => &["size"],
        "mesh" => &["path"],
        "water" => &["size", "depth", "grid", "waves", "simulation", "drops"],
        "room" => &["size", "open"],
        "lathe" => &["profile", "segments"],
        other => {
            return Err(cx.err(
                d.shape.span(),
                f("shape"),
                format!("unknown shape `{other}` (expected plane, sphere, cube, room, lathe, mesh or water)"),
            ))
        }
    };
    let present: [(&str, Option<std::ops::Range<usize>>); 12] = [
        ("open", d.open.as_ref().map(|v| v.span())),
        ("profile", d.profile.as_ref().map(|v| v.span())),
        ("segments", d.segments.as_ref().map(|v| v.span())),
        ("size", d.size.as_ref().map(|v| v.span())),
        ("radius", d.radius.as_ref().map(|v| v.span())),
        ("subdivisions", d.subdivisions.as_ref().map(|v| v.span())),
        ("path", d.path.as_ref().map(|v| v.span())),
        ("depth", d.depth.as_ref().map(|v| v.span())),
        ("grid", d.grid.as_ref().map(|v| v.span())),
        ("waves", d.waves.first().map(|v| v.span())),
        ("simulation", d.simulation.as_ref().map(|v| v.span())),
        ("drops", d.drops.first().map(|v| v.span())),
    ];
    for (field, span) in present {
        if let Some(span) = span {
            if !allowed.contains(&field) {
                return Err(cx.err(span, f(field), format!("`{field}` does not apply to shape `{shape}`")));
            }
        }
    }
    Ok(shape)
}

fn room_mesh(cx: &Ctx, o: &S<ObjectDef>, f: &dyn Fn(&str) -> String) -> Result<Mesh, SceneError> {
    let d = o.get_ref();
    let s = d.size.as_ref().ok_or_else(|| cx.err(o.span(), f("size"), "a room needs `size = [x, y, z]`"))?;
    let size = positive_size(cx, f("size"), s, 3)?;
    let open: Vec<&str> = match &d.open {
        Some(v) => {
            for side in v.get_ref() {
                if !mesh::ROOM_SIDES.contains(&side.as_str()) {
                    return Err(cx.err(
                        v.span(),
                        f("open"),
                        format!("unknown side `{side}` (expected some of {})", mesh::ROOM_SIDES.join(", ")),
                    ));
                }
            }
            v.get_ref().iter().map(|x| x.as_str()).collect()
        }
        None => vec!["+z"],
    };
    if open.len() == 6 {
        return Err(cx.err(d.open.as_ref().map_or(o.span(), |v| v.span()), f("open"), "a room needs a side"));
    }
    Ok(mesh::room(size, &open))
}

fn lathe_mesh(cx: &Ctx, o: &S<ObjectDef>, f: &dyn Fn(&str) -> String) -> Result<Mesh, SceneError> {
    let d = o.get_ref();
    let p = d
        .profile
        .as_ref()
        .ok_or_else(|| cx.err(o.span(), f("profile"), "a lathe needs `profile = [[radius, height], ...]`"))?;
    let pts: Vec<glam::Vec2> = p.get_ref().iter().map(|q| glam::Vec2::from(*q)).collect();
    if pts.len() < 2 {
        return Err(cx.err(p.span(), f("profile"), "needs at least two points"));
    }
    if let Some(q) = pts.iter().find(|q| !(q.is_finite() && q.x >= 0.0 && q.abs().max_element() <= 1e6)) {
        return Err(cx.err(
            p.span(),
            f("profile"),
            format!("point {q}: radii must be >= 0 and coordinates finite (within ±1e6 m)"),
        ));
    }
    if pts.windows(2).any(|w| (w[1] - w[0]).length() < 1e-7) {
        return Err(cx.err(p.span(), f("profile"), "two consecutive points coincide"));
    }
    let segments = match &d.segments {
        Some(s) => {
            let v = *s.get_ref();
            if !(3..=4096).contains(&v) {
                return Err(cx.err(s.span(), f("segments"), format!("must lie in 3..=4096 (got {v})")));
            }
            v as u32
        }
        None => 96,
    };
    let m = mesh::lathe(&pts, segments);
    if m.indices.is_empty() {
        return Err(cx.err(p.span(), f("profile"), "the profile sweeps no area (every point on the axis?)"));
    }
    Ok(m)
}

fn sphere_mesh(cx: &Ctx, o: &S<ObjectDef>, f: &dyn Fn(&str) -> String) -> Result<Mesh, SceneError> {
    let d = o.get_ref();
    let r = d.radius.as_ref().ok_or_else(|| cx.err(o.span(), f("radius"), "a sphere needs `radius`"))?;
    let radius = *r.get_ref();
    if !(radius.is_finite() && radius > 0.0) {
        return Err(cx.err(r.span(), f("radius"), format!("must be > 0 (got {radius})")));
    }
    let subdivisions = match &d.subdivisions {
        Some(s) => {
            let v = *s.get_ref();
            if !(0..=8).contains(&v) {
                return Err(cx.err(
                    s.span(),
                    f("subdivisions"),
                    format!("must lie in 0..=8 (got {v}; 20*4^s triangles)"),
                ));
            }
            v as u32
        }
        None => 6,
    };
    let mut m = mesh::icosphere(radius, subdivisions);
    let mat = d.material.get_ref();
    if mat.albedo_texture.is_some() || mat.checker.is_some() {
        mesh::spherical_uvs(&mut m);
    }
    Ok(m)
}

/// A `mesh` shape: its OBJ file, with a warning for each defect that matters for its material.
fn obj_mesh(cx: &Ctx, o: &S<ObjectDef>, f: &dyn Fn(&str) -> String) -> Result<Mesh, SceneError> {
    let (full, span) = obj_path(cx, o, f)?;
    let (mesh, report) = mesh::load_obj_report(&full).map_err(|e| cx.err(span.clone(), f("path"), e))?;
    let dielectric = o.get_ref().material.get_ref().kind.get_ref() == "dielectric";
    warn_findings(cx, &span, f, &full.display().to_string(), &report, dielectric);
    Ok(mesh)
}

/// A `mesh` object's OBJ file (its `path`, relative to the scene file), which must exist, and the span of `path`.
fn obj_path(
    cx: &Ctx,
    o: &S<ObjectDef>,
    f: &dyn Fn(&str) -> String,
) -> Result<(PathBuf, std::ops::Range<usize>), SceneError> {
    let p = o.get_ref().path.as_ref().ok_or_else(|| cx.err(o.span(), f("path"), "a mesh needs `path`"))?;
    let full = cx.dir.join(p.get_ref());
    if !full.is_file() {
        return Err(cx.err(p.span(), f("path"), format!("mesh file not found: {}", full.display())));
    }
    Ok((full, p.span()))
}

/// Warn of each defect [`mesh::sanitize`] found in an OBJ mesh that matters for its material (`what` names the
/// file, or the file and material), at the object's `path`: an open or non-manifold receiver is an ordinary
/// surface; only glass needs a closed volume.
fn warn_findings(
    cx: &Ctx,
    span: &std::ops::Range<usize>,
    f: &dyn Fn(&str) -> String,
    what: &str,
    report: &mesh::MeshReport,
    glass: bool,
) {
    for finding in report.findings() {
        let topology = finding.starts_with("open") || finding.starts_with("non-");
        if glass || !topology {
            log::warn!("{}", cx.err(span.clone(), f("path"), format!("{what}: {finding}")));
        }
    }
}

/// Places the object's mesh: its `translate`, `rotate_deg` and `scale`, and its keyframes (with its water, its
/// animation). Returns the mesh at time 0 in world space, and the animation.
fn placement(
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

/// The object's material; `mesh` (for a texture: it needs texture coordinates).
fn material(
    cx: &Ctx,
    o: &S<ObjectDef>,
    f: &dyn Fn(&str) -> String,
    textures: &mut Textures,
    mesh: &Mesh,
) -> Result<Material, SceneError> {
    let m = o.get_ref().material.get_ref();
    let mf = |field: &str| f(&format!("material.{field}"));
    if m.kind.get_ref() != "dielectric" {
        let media_fields = [
            ("outside", m.outside.as_ref().map(|x| x.span())),
            ("inside", m.inside.as_ref().map(|x| x.span())),
            ("priority", m.priority.as_ref().map(|x| x.span())),
        ];
        if let Some((field, Some(span))) = media_fields.into_iter().find(|(_, s)| s.is_some()) {
            return Err(cx.err(span, mf(field), format!("only a dielectric's surface has `{field}`")));
        }
    }
    if m.kind.get_ref() != "diffuse" {
        let texture_fields = [
            ("albedo_texture", m.albedo_texture.as_ref().map(|x| x.span())),
            ("checker", m.checker.as_ref().map(|x| x.span())),
            ("uv_scale", m.uv_scale.as_ref().map(|x| x.span())),
        ];
        if let Some((field, Some(span))) = texture_fields.into_iter().find(|(_, s)| s.is_some()) {
            return Err(cx.err(span, mf(field), format!("only a diffuse material has `{field}`")));
        }
    }
    match m.kind.get_ref().as_str() {
        "diffuse" => diffuse(cx, o, &mf, textures, mesh),
        "dielectric" => dielectric(cx, o, &mf),
        "mirror" => {
            if let Some(x) = &m.absorption {
                return Err(cx.err(x.span(), mf("absorption"), "a mirror has no `absorption`"));
            }
            if let Some(x) = &m.albedo {
                return Err(cx.err(x.span(), mf("albedo"), "a mirror has no `albedo` (it reflects all light)"));
            }
            if let Some(x) = &m.ior {
                return Err(cx.err(x.span(), mf("ior"), "a mirror has no `ior`"));
            }
            if let Some(x) = &m.abbe {
                return Err(cx.err(x.span(), mf("abbe"), "a mirror has no `abbe`"));
            }
            Ok(Material::Mirror)
        }
        other => Err(cx.err(
            m.kind.span(),
            mf("kind"),
            format!(
                "unknown material `{other}` (expected \"diffuse\", \"dielectric\", \"mirror\", or \"mtl\" on a mesh)"
            ),
        )),
    }
}

fn diffuse(
    cx: &Ctx,
    o: &S<ObjectDef>,
    mf: &dyn Fn(&str) -> String,
    textures: &mut Textures,
    mesh: &Mesh,
) -> Result<Material, SceneError> {
    let m = o.get_ref().material.get_ref();
    if let Some(x) = &m.absorption {
        return Err(cx.err(x.span(), mf("absorption"), "a diffuse material has no `absorption`"));
    }
    if let Some(x) = &m.ior {
        return Err(cx.err(x.span(), mf("ior"), "a diffuse material has no `ior`"));
    }
    if let Some(x) = &m.abbe {
        return Err(cx.err(x.span(), mf("abbe"), "a diffuse material has no `abbe`"));
    }
    let albedo = match &m.albedo {
        Some(a) => {
            let v = Vec3::from(a.get_ref().to_array());
            if !v.is_finite() || v.min_element() < 0.0 || v.max_element() > 1.0 {
                return Err(cx.err(a.span(), mf("albedo"), "must lie in [0, 1]"));
            }
            Some(v)
        }
        None => None,
    };
    Ok(match albedo_map(cx, m, mf, textures, albedo)? {
        Some((map, albedo)) => {
            if mesh.uvs.len() != mesh.positions.len() {
                let span = m.albedo_texture.as_ref().map_or_else(|| o.span(), |t| t.span());
                return Err(cx.err(
                    span,
                    mf("albedo_texture"),
                    "the mesh has no texture coordinates (an OBJ needs `vt` on every vertex)",
                ));
            }
            Material::Diffuse { albedo, map: Some(map) }
        }
        None => Material::Diffuse { albedo: albedo.unwrap_or(Vec3::splat(0.8)), map: None },
    })
}

/// The media on either side of each dielectric surface (docs/scenes.md "Media"): `inside` takes the named
/// object's dielectric, `outside` names the object whose medium lies beyond the surface. Each name must be another
/// object of the file, a dielectric whose own medium is its own (`inside` does not chain).
fn media(cx: &Ctx, defs: &[S<ObjectDef>], objects: &mut [Object]) -> Result<(), SceneError> {
    let find = |i: usize, field: &str, name: &S<String>| -> Result<usize, SceneError> {
        let f = format!("object[{i}] \"{}\".material.{field}", defs[i].get_ref().name.get_ref());
        let n = name.get_ref();
        let j = defs
            .iter()
            .position(|o| o.get_ref().name.get_ref() == n)
            .ok_or_else(|| cx.err(name.span(), f.clone(), format!("no object is named `{n}`")))?;
        let m = defs[j].get_ref().material.get_ref();
        if j == i {
            return Err(cx.err(name.span(), f, "names the object itself"));
        }
        if m.kind.get_ref() != "dielectric" || m.inside.is_some() {
            return Err(cx.err(
                name.span(),
                f,
                format!("`{n}` must be a dielectric with a medium of its own (an `ior`, no `inside`)"),
            ));
        }
        Ok(j)
    };
    for (i, d) in defs.iter().enumerate() {
        let m = d.get_ref().material.get_ref();
        if let Some(name) = &m.inside {
            let j = find(i, "inside", name)?;
            objects[i].material = objects[j].material;
        }
        if let Some(name) = &m.outside {
            objects[i].outside = Some(find(i, "outside", name)?);
        }
        if let Some(p) = &m.priority {
            let f = format!("object[{i}] \"{}\".material.priority", d.get_ref().name.get_ref());
            let v = *p.get_ref();
            if !(1..=MAX_PRIORITY as i64).contains(&v) {
                return Err(cx.err(p.span(), f, format!("must lie in 1..={MAX_PRIORITY} (got {v})")));
            }
            if m.outside.is_some() || m.inside.is_some() {
                let why = "a volume with a `priority` finds the medium beyond it by overlap: no `outside` or `inside`";
                return Err(cx.err(p.span(), f, why));
            }
            objects[i].priority = v as u32;
        }
    }
    Ok(())
}

fn dielectric(cx: &Ctx, o: &S<ObjectDef>, mf: &dyn Fn(&str) -> String) -> Result<Material, SceneError> {
    let d = o.get_ref();
    let m = d.material.get_ref();
    if let Some(x) = &m.albedo {
        return Err(cx.err(x.span(), mf("albedo"), "a dielectric material has no `albedo`"));
    }
    if m.inside.is_some() {
        // Its medium is another object's (resolved by `media` once every object is read).
        let own = [
            ("ior", m.ior.as_ref().map(|x| x.span())),
            ("absorption", m.absorption.as_ref().map(|x| x.span())),
            ("abbe", m.abbe.as_ref().map(|x| x.span())),
        ];
        if let Some((field, Some(span))) = own.into_iter().find(|(_, s)| s.is_some()) {
            return Err(cx.err(span, mf(field), format!("a surface with `inside` takes `{field}` from that object")));
        }
        return Ok(Material::Dielectric { ior: 1.0, absorption: Vec3::ZERO, abbe: 0.0 });
    }
    let ior = m.ior.as_ref().ok_or_else(|| cx.err(d.material.span(), mf("ior"), "a dielectric needs `ior`"))?;
    let v = *ior.get_ref();
    if !(v.is_finite() && v > 0.0) {
        return Err(cx.err(ior.span(), mf("ior"), format!("index of refraction must be finite and > 0 (got {v})")));
    }
    let absorption = match &m.absorption {
        Some(a) => {
            let x = Vec3::from(a.get_ref().to_array());
            if !(x.is_finite() && x.min_element() >= 0.0) {
                return Err(cx.err(
                    a.span(),
                    mf("absorption"),
                    format!("absorption coefficients must be finite and >= 0 (1/m; got {x})"),
                ));
            }
            x
        }
        None => Vec3::ZERO,
    };
    let abbe = match &m.abbe {
        Some(a) => {
            let x = *a.get_ref();
            if !(x.is_finite() && (5.0..=200.0).contains(&x)) {
                return Err(cx.err(
                    a.span(),
                    mf("abbe"),
                    format!("Abbe number must lie in [5, 200] (crown glass ~60, flint ~30, diamond 55; got {x})"),
                ));
            }
            x
        }
        None => 0.0,
    };
    Ok(Material::Dielectric { ior: v, absorption, abbe })
}

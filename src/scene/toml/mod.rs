//! The TOML scene format (docs/scenes.md): its parser, with the file, line and field of every error.

use super::schema::*;
use super::*;

mod materials;
mod placement;
mod shapes;
mod water_def;

use materials::*;
use placement::*;
use shapes::*;
use water_def::*;

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
            if !(crate::scene::MIN_CONE_DEG..90.0).contains(&v) {
                return Err(cx.err(
                    c.span(),
                    f("cone_deg"),
                    format!("cone half-angle must lie in [{}, 90) degrees (got {v})", crate::scene::MIN_CONE_DEG),
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

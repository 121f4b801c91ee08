//! glTF animations: node channels, morph weights and KHR_animation_pointer tracks, as the scene's movers.

use super::*;

/// The light and camera properties the playing animations' pointers set (docs/scenes.md, "glTF scenes"): a light's
/// `intensity` (candela or lux → W/sr or W/m²), `color` and spot `outerConeAngle` (Blender 5.2 writes
/// `spot.outerConeAngle`), a camera's `yfov` or `ymag`. Pointers to anything else are warned of and ignored.
pub(super) fn pointer_tracks(
    cx: &Cx,
    document: &gltf::Document,
    buffers: &[Vec<u8>],
    pointers: &[PointerChannel],
    sources: &Sources,
    objects: &[Material],
    chosen: Option<usize>,
) -> Result<Vec<crate::scene::PropertyTrack>, SceneError> {
    use crate::scene::PropertyTrack as P;
    use Pointee as T;
    let mut out = Vec::new();
    let mut owner: std::collections::HashMap<&str, usize> = Default::default();
    for p in pointers.iter().filter(|p| chosen.is_none_or(|c| c == p.animation)) {
        let at = format!("animations[{}].channels[{}]", p.animation, p.channel);
        let warn = |what: &str| cx.warn(&at, &format!("`{}`: {what}", p.pointer));
        let Some(target) = pointer_target(cx, document, p)? else { continue };
        if let Some(&first) = owner.get(p.pointer.as_str()) {
            warn(&format!("animations[{first}] animates it too and plays it"));
            continue;
        }
        owner.insert(&p.pointer, p.animation);
        let Some(sampler) = document.animations().nth(p.animation).and_then(|a| a.samplers().nth(p.sampler)) else {
            continue;
        };
        let s_at = format!("animations[{}].samplers[{}]", p.animation, p.sampler);
        let width = if matches!(target, T::Color(_)) { 3 } else { 1 };
        let k = keyframes(cx, &sampler, &s_at, buffers, width, width, "the property")?;
        let scalar = |f: &dyn Fn(f32) -> f32, ok: &dyn Fn(f32) -> bool, rule: &str| {
            if let Some(v) = k.values.iter().find(|v| !ok(**v)) {
                return Err(cx.err(format!("{s_at}.output"), format!("`{}`: {v} {rule}", p.pointer)));
            }
            let (values, tangents) = split(k.values.iter().map(|v| f(*v)).collect(), k.per_key);
            Ok(Track { times: k.times.clone(), values, tangents, interpolation: k.interpolation })
        };
        let (of_light, of_camera) = (&sources.lights, &sources.cameras);
        // The scene lights (cameras) made from glTF light (camera) `i`: one per node that holds it.
        let each = |of: &[usize], i: usize| -> Vec<usize> {
            of.iter().enumerate().filter(|(_, &g)| g == i).map(|(k, _)| k).collect()
        };
        match target {
            T::Intensity(i) => {
                // Blender's exporter (5.2) writes a spot's or point's animated intensity 4π times its still one (it
                // leaves out the watts' spread over the sphere): where the file is Blender's and a keyframe is 4π
                // times the light's own intensity, the track is read as Blender means it.
                let light = document.lights().and_then(|mut l| l.nth(i));
                let still = light.as_ref().map_or(0.0, |l| l.intensity());
                let spread = std::f32::consts::PI * 4.0;
                let blender = document.as_json().asset.generator.as_deref().is_some_and(|g| g.contains("Blender"));
                let point = light.is_some_and(|l| !matches!(l.kind(), gltf::khr_lights_punctual::Kind::Directional));
                let too_bright = still > 0.0
                    && k.values.iter().step_by(k.per_key).any(|v| ((v / still) / spread - 1.0).abs() < 1e-4);
                let divide = if blender && point && too_bright {
                    warn(&format!(
                        "read as {spread:.4} times less: Blender's exporter writes an animated spot or point light's \
                         intensity without dividing its watts by 4π (its still intensity {still} cd is a keyframe's \
                         / 4π)"
                    ));
                    spread * LUMENS_PER_WATT
                } else {
                    LUMENS_PER_WATT
                };
                let track = scalar(&|v| v / divide, &|v| v >= 0.0, "must be >= 0")?;
                out.extend(each(of_light, i).into_iter().map(|k| P::LightIntensity(k, track.clone())));
            }
            T::Cone(i) => {
                let track = scalar(&|v| v, &|v| crate::scene::spot_cone_ok(v), "must lie in [0.1°, π/2)")?;
                out.extend(each(of_light, i).into_iter().map(|k| P::LightCone(k, track.clone())));
            }
            T::Fov(i) => {
                let track = scalar(&|v| v, &|v| v > 0.0 && v < std::f32::consts::PI, "must lie in (0, π)")?;
                out.extend(each(of_camera, i).into_iter().map(|k| P::CameraFov(k, track.clone())));
            }
            T::HalfHeight(i) => {
                let track = scalar(&|v| v, &|v| v > 0.0, "must be > 0")?;
                out.extend(each(of_camera, i).into_iter().map(|k| P::CameraHalfHeight(k, track.clone())));
            }
            T::Ior(i) => {
                let track = scalar(&|v| v, &|v| v > 0.0, "must be > 0")?;
                let of: Vec<usize> = sources.materials.iter().map(|m| m.unwrap_or(usize::MAX)).collect();
                let glass = each(&of, i).into_iter().filter(|&k| matches!(objects[k], Material::Dielectric { .. }));
                out.extend(glass.map(|k| P::ObjectIor(k, track.clone())));
            }
            T::Color(i) => {
                if k.values.iter().any(|v| *v < 0.0) && k.per_key == 1 {
                    return Err(cx.err(format!("{s_at}.output"), format!("`{}`: components must be >= 0", p.pointer)));
                }
                let v: Vec<Vec3> = k.values.chunks_exact(3).map(Vec3::from_slice).collect();
                let (values, tangents) = split(v, k.per_key);
                let track = Track { times: k.times.clone(), values, tangents, interpolation: k.interpolation };
                out.extend(each(of_light, i).into_iter().map(|k| P::LightColor(k, track.clone())));
            }
        }
    }
    Ok(out)
}

/// What a pointer channel sets: a light's intensity, color or cone, or a camera's yfov or ymag (by the file's light
/// and camera indices). None (with a warning): what the renderer does not animate.
#[derive(Clone, Copy)]
pub(super) enum Pointee {
    Intensity(usize),
    Color(usize),
    Cone(usize),
    Fov(usize),
    HalfHeight(usize),
    Ior(usize),
}

pub(super) fn pointer_target(
    cx: &Cx,
    document: &gltf::Document,
    p: &PointerChannel,
) -> Result<Option<Pointee>, SceneError> {
    use Pointee as T;
    let at = format!("animations[{}].channels[{}]", p.animation, p.channel);
    let warn = |what: &str| {
        cx.warn(&at, &format!("`{}`: {what}", p.pointer));
        Ok(None)
    };
    let (lights, cameras) = (document.lights().map_or(0, |l| l.len()), document.cameras().len());
    let index = |s: &str, n: usize, what: &str| {
        s.parse::<usize>().ok().filter(|&i| i < n).ok_or_else(|| {
            cx.err(
                format!("{at}.target.extensions.{POINTER}.pointer"),
                format!("`{}`: the file has {n} {what}", p.pointer),
            )
        })
    };
    let parts: Vec<&str> = p.pointer.trim_start_matches('/').split('/').collect();
    Ok(Some(match parts[..] {
        ["extensions", "KHR_lights_punctual", "lights", i, ref rest @ ..] => {
            let i = index(i, lights, "lights")?;
            match rest {
                ["intensity"] => T::Intensity(i),
                ["color"] => T::Color(i),
                ["spot", "outerConeAngle"] | ["spot.outerConeAngle"] => T::Cone(i),
                ["spot", "innerConeAngle"] | ["spot.innerConeAngle"] => {
                    return warn("the spot's edge is drawn hard at its outer angle: its inner angle is not animated")
                }
                _ => return warn("not a light property the renderer has: ignored"),
            }
        }
        ["cameras", i, "perspective", "yfov"] => T::Fov(index(i, cameras, "cameras")?),
        ["cameras", i, "orthographic", "ymag"] => T::HalfHeight(index(i, cameras, "cameras")?),
        ["materials", i, "extensions", "KHR_materials_ior", "ior"] => {
            T::Ior(index(i, document.materials().len(), "materials")?)
        }
        ["materials", ..] => {
            return warn("not a material property the renderer animates (only a glass's IOR): ignored")
        }
        _ => return warn("not a property the renderer animates: ignored"),
    }))
}

/// A sampler's keyframes: its times, its interpolation, its values (`comps` floats an element, `width` a keyframe
/// value, three keyframe values a keyframe for cubic splines: in tangent, value, out tangent), and how many
/// keyframe values a keyframe holds.
pub(super) struct Keyframes {
    pub(super) times: Vec<f32>,
    pub(super) interpolation: Interpolation,
    pub(super) values: Vec<f32>,
    pub(super) per_key: usize,
}

/// The animation `choice` names: None for all of them; an index or name the file lacks is an error listing what it
/// has.
fn chosen_animation(cx: &Cx, names: &[String], choice: &AnimationChoice) -> Result<Option<usize>, SceneError> {
    let listing = || {
        let all: Vec<String> = names.iter().enumerate().map(|(i, n)| format!("{i} \"{n}\"")).collect();
        if all.is_empty() {
            "the file has none".to_string()
        } else {
            format!("the file has {}", all.join(", "))
        }
    };
    Ok(match choice {
        AnimationChoice::All => None,
        AnimationChoice::Index(i) if *i < names.len() => Some(*i),
        AnimationChoice::Index(i) => {
            return Err(cx.err("animations", format!("animation {i}: no animation has that index ({})", listing())))
        }
        AnimationChoice::Name(n) => match names.iter().position(|x| x == n) {
            Some(i) => Some(i),
            None => {
                return Err(cx.err("animations", format!("animation `{n}`: no animation has that name ({})", listing())))
            }
        },
    })
}

/// A channel's keyframes as node `t`'s track of `property` (`width`: the values per keyframe, the targets for
/// morph weights; `s_at`: the sampler, for messages).
fn set_track(
    cx: &Cx,
    t: &mut NodeTracks,
    property: gltf::animation::Property,
    kf: Keyframes,
    s_at: &str,
    width: usize,
) -> Result<(), SceneError> {
    use gltf::animation::Property;
    let Keyframes { times, interpolation, values, per_key } = kf;
    match property {
        Property::Translation | Property::Scale => {
            let v: Vec<Vec3> = values.chunks_exact(3).map(Vec3::from_slice).collect();
            let (values, tangents) = split(v, per_key);
            let scale = property == Property::Scale;
            if scale && values.iter().any(|x| x.abs().min_element() < 1e-9) {
                return Err(cx.err(format!("{s_at}.output"), "scales must be non-zero"));
            }
            let track = Some(Track { times, values, tangents, interpolation });
            if scale {
                t.scale = track;
            } else {
                t.translation = track;
            }
        }
        Property::Rotation => {
            let v: Vec<Quat> = values.chunks_exact(4).map(Quat::from_slice).collect();
            if per_key == 1 && v.iter().any(|q| q.length() < 1e-6) {
                return Err(cx.err(format!("{s_at}.output"), "rotations must be non-zero quaternions"));
            }
            let (values, tangents) = split(v, per_key);
            if values.iter().any(|q| q.length() < 1e-6) {
                return Err(cx.err(format!("{s_at}.output"), "rotations must be non-zero quaternions"));
            }
            let values = values.into_iter().map(unit).collect();
            t.rotation = Some(Track { times, values, tangents, interpolation });
        }
        Property::MorphTargetWeights => {
            // Keyframe-major: per keyframe (and per spline part) one weight per target.
            let per_target = (0..width).map(|k| {
                let v: Vec<f32> = values.iter().skip(k).step_by(width).copied().collect();
                let (values, tangents) = split(v, per_key);
                Track { times: times.clone(), values, tangents, interpolation }
            });
            t.weights = Some(per_target.collect());
        }
    }
    Ok(())
}

/// Read and check a sampler's keyframes ([`Keyframes`]): times finite and increasing, at least one; values finite,
/// as many as the keyframes need. `what` names the property in messages.
pub(super) fn keyframes(
    cx: &Cx,
    sampler: &gltf::animation::Sampler,
    s_at: &str,
    buffers: &[Vec<u8>],
    comps: usize,
    width: usize,
    what: &str,
) -> Result<Keyframes, SceneError> {
    use gltf::animation::Interpolation as GI;
    let times = read_floats(cx, &sampler.input(), &format!("{s_at}.input"), buffers, 1)?;
    if times.is_empty() || times.iter().any(|t| !t.is_finite()) {
        return Err(cx.err(format!("{s_at}.input"), "keyframe times must be finite, and there must be one"));
    }
    if let Some(k) = times.windows(2).position(|w| w[1] <= w[0]) {
        return Err(cx.err(
            format!("{s_at}.input"),
            format!("keyframe times must increase: {} s follows {} s", times[k + 1], times[k]),
        ));
    }
    let interpolation = match sampler.interpolation() {
        GI::Linear => Interpolation::Linear,
        GI::Step => Interpolation::Step,
        GI::CubicSpline => Interpolation::Cubic,
    };
    let per_key = if interpolation == Interpolation::Cubic { 3 } else { 1 };
    let values = read_floats(cx, &sampler.output(), &format!("{s_at}.output"), buffers, comps)?;
    // The accessor's elements, and how many each keyframe needs.
    let (elements, per_keyframe) = (values.len() / comps, per_key * width / comps);
    if elements != times.len() * per_keyframe {
        return Err(cx.err(
            format!("{s_at}.output"),
            format!(
                "{elements} values for {} keyframes (a {interpolation:?} sampler of {what} needs {per_keyframe} each)",
                times.len()
            ),
        ));
    }
    if values.iter().any(|v| !v.is_finite()) {
        return Err(cx.err(format!("{s_at}.output"), "values must be finite"));
    }
    Ok(Keyframes { times, interpolation, values, per_key })
}

/// (in tangent, value, out tangent) per keyframe for cubic splines (`per_key` 3); the values alone otherwise.
pub(super) fn split<T: Copy>(v: Vec<T>, per_key: usize) -> (Vec<T>, Vec<(T, T)>) {
    if per_key == 1 {
        return (v, Vec::new());
    }
    let values = v.chunks_exact(3).map(|c| c[1]).collect();
    let tangents = v.chunks_exact(3).map(|c| (c[0], c[2])).collect();
    (values, tangents)
}

/// A node's animated components.
#[derive(Clone, Default)]
pub(super) struct NodeTracks {
    pub(super) translation: Option<Track<Vec3>>,
    pub(super) rotation: Option<Track<Quat>>,
    pub(super) scale: Option<Track<Vec3>>,
    /// Morph-target weights: one track per target.
    pub(super) weights: Option<Vec<Track<f32>>>,
}

impl NodeTracks {
    /// Whether its transform animates.
    pub(super) fn moves(&self) -> bool {
        self.translation.is_some() || self.rotation.is_some() || self.scale.is_some()
    }
}

/// What the animations that play do.
pub(super) struct Played {
    /// Per node: its tracks.
    pub(super) tracks: Vec<NodeTracks>,
    /// The last keyframe time of them all (s).
    pub(super) period: f32,
    /// Every animation's name (`animations[i]` for one without).
    pub(super) names: Vec<String>,
    /// The one chosen (None: all).
    pub(super) chosen: Option<usize>,
}

/// The animations that play (`choice`), per node. Times must be finite and increase, values be finite, and a cubic-spline sampler
/// hold three values (in tangent, value, out tangent) per keyframe. Two animations that play and animate the same
/// property of a node: the first listed wins, with a warning (`--animation` picks one).
pub(super) fn animations(
    cx: &Cx,
    document: &gltf::Document,
    buffers: &[Vec<u8>],
    choice: &AnimationChoice,
) -> Result<Played, SceneError> {
    let mut tracks = vec![NodeTracks::default(); document.nodes().len()];
    let names: Vec<String> = document
        .animations()
        .map(|a| match a.name() {
            Some(n) if !n.is_empty() => n.to_string(),
            _ => format!("animations[{}]", a.index()),
        })
        .collect();
    let chosen = chosen_animation(cx, &names, choice)?;
    let mut period = 0.0f32;
    // Per node and property: the animation that animates it.
    let mut owner: std::collections::HashMap<(usize, &'static str), usize> = Default::default();
    for anim in document.animations().filter(|a| chosen.is_none_or(|c| c == a.index())) {
        for ch in anim.channels() {
            let s_at = format!("animations[{}].samplers[{}]", anim.index(), ch.sampler().index());
            let node = ch.target().node();
            let n = node.index();
            use gltf::animation::Property;
            let property = ch.target().property();
            let (key, width) = match property {
                Property::Translation => ("translation", 3),
                Property::Rotation => ("rotation", 4),
                Property::Scale => ("scale", 3),
                Property::MorphTargetWeights => {
                    let targets =
                        node.mesh().and_then(|m| m.primitives().next()).map_or(0, |p| p.morph_targets().len());
                    if targets == 0 {
                        cx.warn(
                            &format!("animations[{}].channels[{}]", anim.index(), ch.index()),
                            &format!(
                                "animates the morph weights of nodes[{n}], whose mesh has no morph targets: ignored"
                            ),
                        );
                        continue;
                    }
                    ("weights", targets)
                }
            };
            if let Some(&first) = owner.get(&(n, key)) {
                cx.warn(
                    &format!("animations[{}]", anim.index()),
                    &format!(
                        "\"{}\" animates the {key} of nodes[{n}] as \"{}\" does: \"{}\" plays it (choose one animation to play the other)",
                        names[anim.index()],
                        names[first],
                        names[first]
                    ),
                );
                continue;
            }
            owner.insert((n, key), anim.index());
            // Weights are SCALAR, one per target per keyframe; the TRS properties one VEC3 or VEC4 per keyframe.
            let comps = if key == "weights" { 1 } else { width };
            let kf = keyframes(cx, &ch.sampler(), &s_at, buffers, comps, width, key)?;
            period = period.max(*kf.times.last().unwrap_or(&0.0));
            set_track(cx, &mut tracks[n], property, kf, &s_at, width)?;
        }
    }
    Ok(Played { tracks, period, names, chosen })
}

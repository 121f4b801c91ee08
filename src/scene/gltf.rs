//! glTF 2.0 import (`.gltf` and `.glb`): meshes baked to world space with their node transforms, cameras, one
//! KHR_lights_punctual spot or directional light, and the materials the renderer has (docs/scenes.md, "glTF scenes").
//!
//! Every error is a [`SceneError::Gltf`] naming the file and the JSON path (`meshes[0].primitives[1].mode`);
//! the CLI reports it with exit code 2. The file is validated before use and accessors are bounds-checked here,
//! so a corrupt file is an error, never a panic.

use super::animation::{Animation, Interpolation, Motion, Repeat, Track};
use super::morph::{Morph, MorphTarget};
use super::{
    AlbedoMap, AnimationChoice, Camera, Light, LightKind, LoadOptions, Material, Mesh, Moved, Mover, Object,
    Projection, Scene, SceneError, Texture, MAX_LIGHTS,
};
use glam::{Mat4, Quat, Vec3};
use gltf::json::validation::{Error as VError, Validate};
use std::path::Path;

/// Luminous efficacy used to turn photometric glTF units into radiometric ones: candela → W/sr, lux → W/m².
pub const LUMENS_PER_WATT: f32 = 683.0;

/// Extensions whose data is read (or, for lights, read and refused where the renderer lacks the kind).
const SUPPORTED: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_volume",
    "KHR_materials_dispersion",
    "KHR_mesh_quantization",
    "KHR_texture_transform",
    WEBP,
    INSTANCING,
    super::meshopt::EXTENSION,
    super::draco::EXTENSION,
    POINTER,
];

/// Animation channels that target a property by its JSON pointer.
const POINTER: &str = "KHR_animation_pointer";

/// Extensions a file may use that the renderer reads nothing from, with what that means for the picture (each is
/// warned of once, in these words).
const IGNORED: &[(&str, &str)] = &[
    ("KHR_materials_emissive_strength", "surfaces do not emit light here: emission and its strength are not rendered"),
    (
        "KHR_materials_specular",
        "diffuse surfaces have no specular lobe here and glass reflects by Fresnel at its IOR: the specular factor \
         and color are ignored",
    ),
    ("KHR_materials_clearcoat", "no clear coat is rendered: the material beneath it is"),
    ("KHR_materials_variants", "each primitive's default material is rendered (the variants' mappings are ignored)"),
    ("KHR_texture_basisu", "KTX2 images are not decoded: each texture's PNG, JPEG or WebP fallback is used"),
];

/// A node's mesh drawn at many placements, each given by the node's per-instance TRS attributes.
const INSTANCING: &str = "EXT_mesh_gpu_instancing";

/// A texture's WebP image (its `source` then a PNG or JPEG fallback, or absent).
const WEBP: &str = "EXT_texture_webp";

/// The deepest node hierarchy accepted (the traversal is recursive).
const MAX_DEPTH: usize = 256;

pub(super) struct Cx {
    file: String,
}

impl Cx {
    pub(super) fn err(&self, path: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError::Gltf { file: self.file.clone(), path: path.into(), message: message.into() }
    }
    fn warn(&self, path: &str, message: &str) {
        log::warn!("{}: {path}: {message}", self.file);
    }
}

pub fn is_gltf(path: &Path) -> bool {
    matches!(
        path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref(),
        Some("gltf") | Some("glb")
    )
}

pub fn load(path: &Path, options: &LoadOptions) -> Result<Scene, SceneError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path)
        .map_err(|e| SceneError::Io { file: file.clone(), message: format!("cannot read scene: {e}") })?;
    parse(&bytes, path, options)
}

/// A KHR_animation_pointer channel, which the gltf crate cannot hold (it has no `node`): taken out of the JSON
/// before the crate reads it. A pointer to a node's translation, rotation, scale or weights stays in as the
/// ordinary channel it means.
struct PointerChannel {
    animation: usize,
    /// Its index in the file's `channels`.
    channel: usize,
    sampler: usize,
    pointer: String,
}

/// The file's document and its animation-pointer channels (see [`PointerChannel`]).
fn read_document(cx: &Cx, bytes: &[u8]) -> Result<(gltf::Gltf, Vec<PointerChannel>), SceneError> {
    let syntax = |j: serde_json::Error| SceneError::Syntax {
        file: cx.file.clone(),
        line: j.line(),
        column: j.column(),
        message: format!("not valid glTF JSON: {j}"),
    };
    let glb_error = |b| cx.err("(GLB container)", format!("not a valid GLB file: {b}"));
    if !bytes.windows(POINTER.len()).any(|w| w == POINTER.as_bytes()) {
        let gltf = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| match e {
            gltf::Error::Deserialize(j) => syntax(j),
            gltf::Error::Binary(b) => glb_error(b),
            other => cx.err("(file)", format!("not a valid glTF file: {other}")),
        })?;
        return Ok((gltf, Vec::new()));
    }
    let (json, blob) = if bytes.starts_with(b"glTF") {
        let glb = gltf::binary::Glb::from_slice(bytes).map_err(|e| match e {
            gltf::Error::Binary(b) => glb_error(b),
            other => cx.err("(GLB container)", format!("not a valid GLB file: {other}")),
        })?;
        (glb.json.into_owned(), glb.bin.map(|b| b.into_owned()))
    } else {
        (bytes.to_vec(), None)
    };
    let mut value: serde_json::Value = serde_json::from_slice(&json).map_err(syntax)?;
    let mut pointers = Vec::new();
    if let Some(animations) = value.get_mut("animations").and_then(|a| a.as_array_mut()) {
        for (a, anim) in animations.iter_mut().enumerate() {
            let samplers = anim.get("samplers").and_then(|s| s.as_array()).map_or(0, |s| s.len());
            let Some(channels) = anim.get_mut("channels").and_then(|c| c.as_array_mut()) else { continue };
            let mut kept = Vec::new();
            for (c, mut ch) in std::mem::take(channels).into_iter().enumerate() {
                let target = &ch["target"];
                if target.get("path").and_then(|p| p.as_str()) != Some("pointer") {
                    kept.push(ch);
                    continue;
                }
                let at = format!("animations[{a}].channels[{c}]");
                let pointer = target["extensions"][POINTER]["pointer"].as_str().ok_or_else(|| {
                    cx.err(format!("{at}.target"), format!("a `pointer` channel needs extensions.{POINTER}.pointer"))
                })?;
                let sampler =
                    ch["sampler"].as_u64().map(|s| s as usize).filter(|&s| s < samplers).ok_or_else(|| {
                        cx.err(format!("{at}.sampler"), format!("must be one of the animation's {samplers} samplers"))
                    })?;
                // A node's own properties are ordinary channels.
                let parts: Vec<&str> = pointer.trim_start_matches('/').split('/').collect();
                if let ["nodes", n, path @ ("translation" | "rotation" | "scale" | "weights")] = parts[..] {
                    if let Ok(n) = n.parse::<u64>() {
                        ch["target"] = serde_json::json!({"node": n, "path": path});
                        kept.push(ch);
                        continue;
                    }
                }
                pointers.push(PointerChannel { animation: a, channel: c, sampler, pointer: pointer.to_string() });
            }
            *channels = kept;
        }
    }
    let root: gltf::json::Root =
        serde_json::from_value(value).map_err(|e| cx.err("(file)", format!("not valid glTF JSON: {e}")))?;
    Ok((gltf::Gltf { document: gltf::Document::from_json_without_validation(root), blob }, pointers))
}

/// Per scene light and camera, the glTF light and camera it was made from (animation pointers name those).
#[derive(Default)]
struct Sources {
    lights: Vec<usize>,
    cameras: Vec<usize>,
    /// Per scene object, its glTF material.
    materials: Vec<Option<usize>>,
}

/// The light and camera properties the playing animations' pointers set (docs/scenes.md, "glTF scenes"): a light's
/// `intensity` (candela or lux → W/sr or W/m²), `color` and spot `outerConeAngle` (Blender 5.2 writes
/// `spot.outerConeAngle`), a camera's `yfov` or `ymag`. Pointers to anything else are warned of and ignored.
fn pointer_tracks(
    cx: &Cx,
    document: &gltf::Document,
    buffers: &[Vec<u8>],
    pointers: &[PointerChannel],
    sources: &Sources,
    objects: &[Material],
    chosen: Option<usize>,
) -> Result<Vec<super::PropertyTrack>, SceneError> {
    use super::PropertyTrack as P;
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
        let quarter = std::f32::consts::FRAC_PI_2;
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
                let track = scalar(&|v| v, &|v| v > 0.0 && v < quarter, "must lie in (0, π/2)")?;
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
enum Pointee {
    Intensity(usize),
    Color(usize),
    Cone(usize),
    Fov(usize),
    HalfHeight(usize),
    Ior(usize),
}

fn pointer_target(cx: &Cx, document: &gltf::Document, p: &PointerChannel) -> Result<Option<Pointee>, SceneError> {
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
struct Keyframes {
    times: Vec<f32>,
    interpolation: Interpolation,
    values: Vec<f32>,
    per_key: usize,
}

/// Read and check a sampler's keyframes ([`Keyframes`]): times finite and increasing, at least one; values finite,
/// as many as the keyframes need. `what` names the property in messages.
fn keyframes(
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
fn split<T: Copy>(v: Vec<T>, per_key: usize) -> (Vec<T>, Vec<(T, T)>) {
    if per_key == 1 {
        return (v, Vec::new());
    }
    let values = v.chunks_exact(3).map(|c| c[1]).collect();
    let tangents = v.chunks_exact(3).map(|c| (c[0], c[2])).collect();
    (values, tangents)
}

/// Refuse a required extension this renderer does not support; warn of a used one it ignores.
fn check_extensions(cx: &Cx, root: &gltf::json::Root) -> Result<(), SceneError> {
    let known = |e: &str| SUPPORTED.contains(&e);
    for (i, e) in root.extensions_required.iter().enumerate() {
        if e == "KHR_texture_basisu" {
            return Err(cx.err(
                format!("extensionsRequired[{i}]"),
                "the file's textures are KTX2 (Basis Universal) images without a fallback, which this renderer does \
                 not decode: write them as PNG, JPEG or WebP (gltfpack without -tc; glTF-Transform's `webp` rather \
                 than `etc1s` or `uastc`)",
            ));
        }
        if !known(e) {
            return Err(cx.err(
                format!("extensionsRequired[{i}]"),
                format!(
                    "the file requires extension `{e}`, which is not supported (supported: {})",
                    SUPPORTED.join(", ")
                ),
            ));
        }
    }
    for (i, e) in root.extensions_used.iter().enumerate() {
        if let Some((_, what)) = IGNORED.iter().find(|(name, _)| name == e) {
            cx.warn(&format!("extensionsUsed[{i}]"), &format!("`{e}`: {what}"));
        } else if !known(e) {
            cx.warn(&format!("extensionsUsed[{i}]"), &format!("extension `{e}` is not supported and is ignored"));
        }
    }
    Ok(())
}

/// Parse glTF JSON or GLB bytes; `path` locates the file for messages and external buffers.
pub fn parse(bytes: &[u8], path: &Path, options: &LoadOptions) -> Result<Scene, SceneError> {
    let cx = Cx { file: path.display().to_string() };
    let (gltf::Gltf { document, blob }, pointers) = read_document(&cx, bytes)?;
    let root = document.as_json();

    // Extensions first: a required extension we cannot honor makes everything else meaningless.
    check_extensions(&cx, root)?;

    // The crate's validation: indices in range, required fields present, enums valid. Required extensions were
    // checked above (the crate does not know the ones we ignore).
    // A Draco primitive's accessors have no bufferView: the decoded data gives them one (src/scene/draco.rs).
    let draco = super::draco::accessors(root);
    let mut problems = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |p: &dyn Fn() -> gltf::json::Path, e: VError| {
        let p = p().to_string();
        let unsupported = p.starts_with("extensionsRequired") && matches!(e, VError::Unsupported);
        let draco_view =
            matches!(e, VError::Missing) && draco.iter().any(|a| p == format!("accessors[{a}].bufferView"));
        // A texture with a WebP image needs no other (texture_image checks that it has one).
        let webp_only = matches!(e, VError::Missing)
            && root.textures.iter().enumerate().any(|(t, tex)| {
                p == format!("textures[{t}].source")
                    && tex.extensions.as_ref().is_some_and(|x| x.others.contains_key(WEBP))
            });
        if !(unsupported || draco_view || webp_only) {
            problems.push((p, e));
        }
    });
    if let Some((p, e)) = problems.into_iter().next() {
        return Err(cx.err(p, e.to_string().to_lowercase()));
    }
    // The crate leaves animation targets unchecked (and would panic on one out of range).
    for (a, anim) in root.animations.iter().enumerate() {
        for (c, ch) in anim.channels.iter().enumerate() {
            if ch.target.node.value() >= root.nodes.len() {
                return Err(cx.err(
                    format!("animations[{a}].channels[{c}].target.node"),
                    format!("index out of bounds: the file has {} nodes", root.nodes.len()),
                ));
            }
        }
    }

    let mut buffers = load_buffers(&cx, &document, blob, path)?;
    super::meshopt::decode_views(&cx, &document, &mut buffers)?;
    let document = super::draco::inflate(&cx, &document, &mut buffers)?.unwrap_or(document);

    // Materials, converted once (and warned about once), with the textures their base colors name; per material,
    // the TEXCOORD set its texture reads.
    let mut textures = Textures::new(&document);
    let (materials, tex_coords): (Vec<Material>, Vec<Option<u32>>) = document
        .materials()
        .map(|m| material(&cx, &m, &buffers, path, &mut textures))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .unzip();
    // Per material: the priority of a glass volume (`extras.priority`; 0: none).
    let priorities = document.materials().map(|m| priority(&cx, &m, &materials)).collect::<Result<Vec<_>, _>>()?;
    // The glTF default material: white, metallic 1, roughness 1 → diffuse white.
    let default_material = Material::diffuse(Vec3::ONE);

    let scene = document.default_scene().or_else(|| document.scenes().next());
    if let Some(sc) = &scene {
        let n = document.scenes().len();
        if n > 1 {
            let which = if document.default_scene().is_some() { "the file's `scene`" } else { "the first" };
            cx.warn("scenes", &format!("the file has {n} scenes: scenes[{}] ({which}) is loaded", sc.index()));
        }
    }
    let roots: Vec<gltf::Node> = match &scene {
        Some(s) => s.nodes().collect(),
        None => {
            // No scene: every node that is nobody's child is a root.
            let mut child = vec![false; document.nodes().len()];
            for n in document.nodes() {
                for c in n.children() {
                    child[c.index()] = true;
                }
            }
            document.nodes().filter(|n| !child[n.index()]).collect()
        }
    };

    let mut out = Scene::new(Vec::new(), Vec::new());
    out.path = path.to_path_buf();
    out.textures = textures.list;
    let mut visiting = vec![false; document.nodes().len()];
    let Played { tracks, period, names, chosen } = animations(&cx, &document, &buffers, &options.animation)?;
    out.animations = names;
    out.playing = chosen;
    // Only skins stand where their joints are at rest.
    let rest_world = if document.skins().len() > 0 { rest_worlds(&document) } else { Vec::new() };
    let g = Globals {
        document: &document,
        sources: Default::default(),
        buffers: &buffers,
        materials: &materials,
        tex_coords: &tex_coords,
        priorities: &priorities,
        default_material,
        tracks: &tracks,
        period,
        rest_world: &rest_world,
    };
    for n in roots {
        visit(&cx, &n, &Placement::root(), &g, &mut visiting, &mut out)?;
    }
    let object_materials: Vec<Material> = out.objects.iter().map(|o| o.material).collect();
    out.properties =
        pointer_tracks(&cx, &document, &buffers, &pointers, &g.sources.borrow(), &object_materials, chosen)?;
    out.place_properties();
    if out.lights.is_empty() {
        return Err(cx.err(
            "extensions.KHR_lights_punctual",
            "the scene needs a light: a KHR_lights_punctual spot or directional light on a node",
        ));
    }
    out.aim_point_lights();
    if let Some(i) = out.lights.iter().position(|l| (l.target - l.position).length() < 1e-6) {
        return Err(cx.err(
            "extensions.KHR_lights_punctual",
            format!("point light {i} stands at the center of the glass it would aim at: its maps have no direction"),
        ));
    }
    if out.lights.len() > MAX_LIGHTS {
        return Err(cx.err(
            "extensions.KHR_lights_punctual",
            format!("the scene has {} lights on its nodes; at most {MAX_LIGHTS} are supported", out.lights.len()),
        ));
    }
    if out.objects.is_empty() {
        return Err(cx.err("meshes", "the scene has no triangle meshes"));
    }
    out.place_directional_lights();
    Ok(out)
}

fn load_buffers(
    cx: &Cx,
    document: &gltf::Document,
    mut blob: Option<Vec<u8>>,
    path: &Path,
) -> Result<Vec<Vec<u8>>, SceneError> {
    let mut out = Vec::new();
    for b in document.buffers() {
        let at = format!("buffers[{}]", b.index());
        let data = match b.source() {
            // EXT_meshopt_compression's fallback without data: its views are decoded into it.
            gltf::buffer::Source::Bin if super::meshopt::is_fallback(&b) => {
                if b.length() > 1 << 31 {
                    return Err(cx.err(format!("{at}.byteLength"), "is too large"));
                }
                vec![0; b.length()]
            }
            gltf::buffer::Source::Bin => {
                blob.take().ok_or_else(|| cx.err(&at, "has no `uri` and the file has no GLB binary chunk"))?
            }
            gltf::buffer::Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let (_, payload) = rest
                        .split_once(";base64,")
                        .ok_or_else(|| cx.err(format!("{at}.uri"), "a data URI must be base64 (`data:...;base64,`)"))?;
                    base64_decode(payload)
                        .ok_or_else(|| cx.err(format!("{at}.uri"), "the data URI is not valid base64"))?
                } else {
                    let full = path.parent().unwrap_or(Path::new("")).join(percent_decode(uri));
                    std::fs::read(&full)
                        .map_err(|e| cx.err(format!("{at}.uri"), format!("cannot read {}: {e}", full.display())))?
                }
            }
        };
        if data.len() < b.length() {
            return Err(cx.err(
                format!("{at}.byteLength"),
                format!("says {} bytes but the data has {}", b.length(), data.len()),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            // Bytes, not `&s[..]`: a `%` before a multi-byte character must not split it.
            if let Some(v) = std::str::from_utf8(&b[i + 1..i + 3]).ok().and_then(|h| u8::from_str_radix(h, 16).ok()) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn base64_decode(s: &str) -> Option<Vec<u8>> {
    let val = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        } as u32)
    };
    let digits: Vec<u8> = s.bytes().filter(|c| !c.is_ascii_whitespace()).collect();
    let digits = digits.strip_suffix(b"==").or_else(|| digits.strip_suffix(b"=")).unwrap_or(&digits);
    if digits.len() % 4 == 1 {
        return None;
    }
    let mut out = Vec::with_capacity(digits.len() * 3 / 4);
    for chunk in digits.chunks(4) {
        let mut acc = 0u32;
        for (k, &c) in chunk.iter().enumerate() {
            acc |= val(c)? << (18 - 6 * k);
        }
        let bytes = acc.to_be_bytes();
        out.extend_from_slice(&bytes[1..chunk.len()]);
    }
    Some(out)
}

/// The images the materials' base colors have named, each decoded once: (image index → scene texture).
struct Textures<'a> {
    document: &'a gltf::Document,
    list: Vec<std::sync::Arc<Texture>>,
    by_image: std::collections::HashMap<usize, usize>,
}

impl<'a> Textures<'a> {
    fn new(document: &'a gltf::Document) -> Self {
        Textures { document, list: Vec::new(), by_image: Default::default() }
    }
}

/// The image a texture shows: EXT_texture_webp's `source` where the texture has that extension (the WebP image,
/// preferred to the fallback), else its own `source`.
fn texture_image<'a>(
    cx: &Cx,
    document: &'a gltf::Document,
    texture: &gltf::Texture,
) -> Result<gltf::image::Image<'a>, SceneError> {
    let at = format!("textures[{}]", texture.index());
    let images = document.images().len();
    let (index, field) = match texture.extension_value(WEBP) {
        Some(v) => {
            let field = format!("{at}.extensions.{WEBP}.source");
            let i = v.get("source").and_then(|s| s.as_u64()).ok_or_else(|| {
                cx.err(field.clone(), "must be an image's index (the texture's WebP image)".to_string())
            })?;
            (usize::try_from(i).unwrap_or(usize::MAX), field)
        }
        None => (document.as_json().textures[texture.index()].source.value(), format!("{at}.source")),
    };
    document
        .images()
        .nth(index)
        .ok_or_else(|| cx.err(field, format!("index out of bounds: the file has {images} images")))
}

/// Decode glTF image `img` (a data URI, a file beside the glTF, or a bufferView) as an albedo texture.
fn image(cx: &Cx, img: &gltf::image::Image, buffers: &[Vec<u8>], path: &Path) -> Result<Texture, SceneError> {
    let at = format!("images[{}]", img.index());
    let (bytes, name) = match img.source() {
        gltf::image::Source::View { view, .. } => {
            let buf = &buffers[view.buffer().index()];
            let bytes = view
                .offset()
                .checked_add(view.length())
                .and_then(|end| buf.get(view.offset()..end))
                .ok_or_else(|| cx.err(format!("{at}.bufferView"), "the bufferView lies outside its buffer"))?;
            (bytes.to_vec(), format!("{} {at}", cx.file))
        }
        gltf::image::Source::Uri { uri, .. } => {
            if let Some(rest) = uri.strip_prefix("data:") {
                let (_, payload) = rest
                    .split_once(";base64,")
                    .ok_or_else(|| cx.err(format!("{at}.uri"), "a data URI must be base64 (`data:...;base64,`)"))?;
                let bytes = base64_decode(payload)
                    .ok_or_else(|| cx.err(format!("{at}.uri"), "the data URI is not valid base64"))?;
                (bytes, format!("{} {at}", cx.file))
            } else {
                let full = path.parent().unwrap_or(Path::new("")).join(percent_decode(uri));
                let bytes = std::fs::read(&full)
                    .map_err(|e| cx.err(format!("{at}.uri"), format!("cannot read {}: {e}", full.display())))?;
                (bytes, full.display().to_string())
            }
        }
    };
    Texture::decode(&name, &bytes).map_err(|e| cx.err(at, e))
}

/// A base color texture's albedo map and the TEXCOORD set it reads: its image, and KHR_texture_transform's
/// offset, rotation and scale (uv' = T · R · S · uv) with its texCoord override.
fn base_color_map(
    cx: &Cx,
    at: &str,
    info: &gltf::texture::Info,
    buffers: &[Vec<u8>],
    path: &Path,
    textures: &mut Textures,
) -> Result<(AlbedoMap, u32), SceneError> {
    let img = texture_image(cx, textures.document, &info.texture())?;
    let k = match textures.by_image.get(&img.index()) {
        Some(&k) => k,
        None => {
            textures.list.push(std::sync::Arc::new(image(cx, &img, buffers, path)?));
            textures.by_image.insert(img.index(), textures.list.len() - 1);
            textures.list.len() - 1
        }
    };
    let mut map = AlbedoMap::new(k);
    let mut set = info.tex_coord();
    if let Some(t) = info.texture_transform() {
        let (o, r, s) = (t.offset(), t.rotation(), t.scale());
        if !(o.iter().chain(s.iter()).all(|x| x.is_finite()) && r.is_finite()) {
            return Err(cx.err(
                format!("{at}.pbrMetallicRoughness.baseColorTexture.extensions.KHR_texture_transform"),
                "offset, rotation and scale must be finite",
            ));
        }
        let (c, sn) = (r.cos(), r.sin());
        map.uv_transform = [[c * s[0], sn * s[1], o[0]], [-sn * s[0], c * s[1], o[1]]];
        if let Some(tc) = t.tex_coord() {
            set = tc;
        }
    }
    Ok((map, set))
}

/// A glass material's medium priority (docs/scenes.md "Media"): glTF has none of its own, so the material's
/// `extras.priority` (a Blender material's custom property `priority`, exported with the exporter's "Custom
/// Properties") carries it: an integer in 1..=MAX_PRIORITY, on a transmissive material. 0 when absent.
fn priority(cx: &Cx, m: &gltf::Material, materials: &[Material]) -> Result<u32, SceneError> {
    let i = m.index().unwrap_or(0);
    let Some(extras) = m.extras() else { return Ok(0) };
    let value: serde_json::Value = serde_json::from_str(extras.get()).unwrap_or(serde_json::Value::Null);
    let Some(p) = value.get("priority") else { return Ok(0) };
    let at = format!("materials[{i}].extras.priority");
    let v = p.as_f64().filter(|v| v.fract() == 0.0 && (1.0..=super::MAX_PRIORITY as f64).contains(v));
    let max = super::MAX_PRIORITY;
    let v = v.ok_or_else(|| cx.err(at.clone(), format!("must be an integer in 1..={max} (got {p})")))?;
    if !matches!(materials[i], Material::Dielectric { .. }) {
        cx.warn(&at, "only a transmissive (glass) material is a volume with a priority: ignored");
        return Ok(0);
    }
    Ok(v as u32)
}

fn material(
    cx: &Cx,
    m: &gltf::Material,
    buffers: &[Vec<u8>],
    path: &Path,
    textures: &mut Textures,
) -> Result<(Material, Option<u32>), SceneError> {
    let i = m.index().unwrap_or(0);
    let at = format!("materials[{i}]");
    let label = match m.name() {
        Some(n) => format!("{at} \"{n}\""),
        None => at.clone(),
    };
    let pbr = m.pbr_metallic_roughness();
    if m.transmission().is_some_and(|t| t.transmission_factor() > 0.0) {
        // What glTF's transmission has and this glass does not: a tint at each surface, and roughness.
        let c = pbr.base_color_factor();
        if c[..3].iter().any(|&x| x < 1.0) {
            cx.warn(
                &label,
                &format!(
                    "baseColorFactor ({}, {}, {}) tints transmitted light at each surface in glTF; this glass is clear \
                     (KHR_materials_volume's attenuation colors it)",
                    c[0], c[1], c[2]
                ),
            );
        }
        if pbr.roughness_factor() > 0.0 {
            cx.warn(&label, &format!("roughnessFactor {}: the glass is rendered smooth", pbr.roughness_factor()));
        }
        let ior = m.ior().unwrap_or(1.5);
        if !(ior.is_finite() && ior > 0.0) {
            return Err(cx.err(
                format!("{at}.extensions.KHR_materials_ior.ior"),
                format!("index of refraction must be finite and > 0 (got {ior})"),
            ));
        }
        // KHR_materials_volume: Beer–Lambert with attenuationColor reached at attenuationDistance, per channel:
        // sigma = -ln(color) / distance.
        let mut absorption = Vec3::ZERO;
        if let Some(v) = m.volume() {
            let (d, c) = (v.attenuation_distance(), v.attenuation_color());
            if d.is_nan() || d <= 0.0 {
                return Err(cx.err(
                    format!("{at}.extensions.KHR_materials_volume.attenuationDistance"),
                    format!("attenuation distance must be > 0 (got {d})"),
                ));
            }
            if c.iter().any(|x| !(x.is_finite() && *x > 0.0 && *x <= 1.0)) {
                return Err(cx.err(
                    format!("{at}.extensions.KHR_materials_volume.attenuationColor"),
                    format!("attenuation color must lie in (0, 1] (got {c:?})"),
                ));
            }
            if d.is_finite() {
                absorption = Vec3::new(-c[0].ln() / d, -c[1].ln() / d, -c[2].ln() / d).max(Vec3::ZERO);
            }
        }
        // KHR_materials_dispersion: `dispersion` = 20 / V_d (the Abbe number); 0 for none.
        let mut abbe = 0.0;
        if let Some(v) = m.extension_value("KHR_materials_dispersion") {
            let at = format!("{at}.extensions.KHR_materials_dispersion.dispersion");
            let x = v.get("dispersion").and_then(|x| x.as_f64()).unwrap_or(0.0) as f32;
            if !(x.is_finite() && x >= 0.0) {
                return Err(cx.err(at, format!("dispersion must be finite and >= 0 (got {x})")));
            }
            if x > 0.0 {
                abbe = (20.0 / x).clamp(5.0, 200.0);
                if (abbe - 20.0 / x).abs() > 1e-3 {
                    cx.warn(&label, &format!("KHR_materials_dispersion {x}: Abbe number clamped to {abbe}"));
                }
            }
        }
        return Ok((Material::Dielectric { ior, absorption, abbe }, None));
    }
    if pbr.metallic_factor() == 1.0 && pbr.roughness_factor() == 0.0 {
        return Ok((Material::Mirror, None));
    }
    let c = pbr.base_color_factor();
    let albedo = Vec3::new(c[0], c[1], c[2]);
    if !albedo.is_finite() {
        return Err(cx.err(format!("{at}.pbrMetallicRoughness.baseColorFactor"), "must be finite"));
    }
    let albedo = albedo.clamp(Vec3::ZERO, Vec3::ONE);
    match pbr.base_color_texture() {
        Some(info) => {
            let (map, set) = base_color_map(cx, &at, &info, buffers, path, textures)?;
            Ok((Material::Diffuse { albedo, map: Some(map) }, Some(set)))
        }
        None => Ok((Material::diffuse(albedo), None)),
    }
}

/// What every node's visit reads: the buffers, the materials, the animation tracks and the nodes' rest placement.
struct Globals<'a> {
    document: &'a gltf::Document,
    /// The glTF light and camera each scene light and camera comes from, as the nodes are visited.
    sources: std::cell::RefCell<Sources>,
    buffers: &'a [Vec<u8>],
    materials: &'a [Material],
    /// Per material: the TEXCOORD set its base color texture reads (None: untextured).
    tex_coords: &'a [Option<u32>],
    /// Per material: its medium priority (`Object::priority`; 0: none).
    priorities: &'a [u32],
    default_material: Material,
    /// Per node: its tracks, from the animations that play.
    tracks: &'a [NodeTracks],
    /// The last keyframe time of the animations that play (s).
    period: f32,
    /// Per node: its world transform at rest (a skinned mesh stands where its joints place it at rest); empty
    /// when the file has no skins.
    rest_world: &'a [Mat4],
}

/// A node's animated components.
#[derive(Clone, Default)]
struct NodeTracks {
    translation: Option<Track<Vec3>>,
    rotation: Option<Track<Quat>>,
    scale: Option<Track<Vec3>>,
    /// Morph-target weights: one track per target.
    weights: Option<Vec<Track<f32>>>,
}

impl NodeTracks {
    /// Whether its transform animates.
    fn moves(&self) -> bool {
        self.translation.is_some() || self.rotation.is_some() || self.scale.is_some()
    }
}

/// Where a node stands: its world transform at time 0, and, when it or an ancestor animates, the chain of
/// motions from the outermost animated node down to it, under that node's parent's world transform.
#[derive(Clone)]
struct Placement {
    world: Mat4,
    chain: Vec<Motion>,
    chain_parent: Mat4,
}

impl Placement {
    fn root() -> Placement {
        Placement { world: Mat4::IDENTITY, chain: Vec::new(), chain_parent: Mat4::IDENTITY }
    }

    /// An instance placed by `local` (translation, rotation, scale) in this placement's space.
    fn instanced(&self, local: Trs) -> Placement {
        let mut p = self.clone();
        // An animated placement composes the instance after its chain; a still one only multiplies.
        if !p.chain.is_empty() {
            p.chain.push(Motion::rest(local));
        }
        p.world *= Mat4::from_scale_rotation_translation(local.2, local.1, local.0);
        p
    }

    /// Its transform over time (None: it stands still).
    fn animation(&self, period: f32) -> Option<Animation> {
        (!self.chain.is_empty()).then(|| Animation {
            chain: self.chain.clone(),
            parent: self.chain_parent,
            repeat: Repeat::Clamp,
            period,
        })
    }
}

/// What the animations that play do.
struct Played {
    /// Per node: its tracks.
    tracks: Vec<NodeTracks>,
    /// The last keyframe time of them all (s).
    period: f32,
    /// Every animation's name (`animations[i]` for one without).
    names: Vec<String>,
    /// The one chosen (None: all).
    chosen: Option<usize>,
}

/// The animations that play (`choice`), per node. Times must be finite and increase, values be finite, and a cubic-spline sampler
/// hold three values (in tangent, value, out tangent) per keyframe. Two animations that play and animate the same
/// property of a node: the first listed wins, with a warning (`--animation` picks one).
fn animations(
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
    let listing = || {
        let all: Vec<String> = names.iter().enumerate().map(|(i, n)| format!("{i} \"{n}\"")).collect();
        if all.is_empty() {
            "the file has none".to_string()
        } else {
            format!("the file has {}", all.join(", "))
        }
    };
    let chosen = match choice {
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
    };
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
            let Keyframes { times, interpolation, values, per_key } =
                keyframes(cx, &ch.sampler(), &s_at, buffers, comps, width, key)?;
            period = period.max(*times.last().unwrap_or(&0.0));
            let t = &mut tracks[n];
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
        }
    }
    Ok(Played { tracks, period, names, chosen })
}

/// Every node's world transform at rest (its nodes' `matrix` or TRS, no animation), through its parents: what a
/// skin's joints stand at. A node in a cycle (an error the scene traversal reports) keeps its own transform.
fn rest_worlds(document: &gltf::Document) -> Vec<Mat4> {
    let n = document.nodes().len();
    let mut parent = vec![usize::MAX; n];
    for node in document.nodes() {
        for c in node.children() {
            parent[c.index()] = node.index();
        }
    }
    let local: Vec<Mat4> = document.nodes().map(|node| node_local(&node).1).collect();
    (0..n)
        .map(|i| {
            let mut m = local[i];
            let mut p = parent[i];
            let mut steps = 0;
            while p != usize::MAX && steps < MAX_DEPTH {
                m = local[p] * m;
                p = parent[p];
                steps += 1;
            }
            m
        })
        .collect()
}

/// A node's own transform: its TRS (the rotation a unit quaternion), and its matrix, composed from the TRS as an
/// animated node's is (so that a pose written into a file renders exactly as the animation placing it), or its
/// `matrix` as it is.
fn node_local(node: &gltf::Node) -> ((Vec3, Quat, Vec3), Mat4) {
    let (translation, rotation, scale) = node.transform().decomposed();
    let rest = (Vec3::from(translation), unit(Quat::from_array(rotation)), Vec3::from(scale));
    let local = match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => Mat4::from_cols_array_2d(&matrix),
        gltf::scene::Transform::Decomposed { .. } => Mat4::from_scale_rotation_translation(rest.2, rest.1, rest.0),
    };
    (rest, local)
}

/// A rotation as a unit quaternion: as written when it is one to float precision (then a pose written from an
/// animation's value renders exactly as the animation does), else normalized.
fn unit(q: Quat) -> Quat {
    if (q.length_squared() - 1.0).abs() <= 1e-5 {
        q
    } else {
        q.normalize()
    }
}

/// A node's label in messages: `nodes[i] "name"`.
fn node_label(node: &gltf::Node) -> String {
    match node.name() {
        Some(n) if !n.is_empty() => format!("nodes[{}] \"{n}\"", node.index()),
        _ => format!("nodes[{}]", node.index()),
    }
}

fn visit(
    cx: &Cx,
    node: &gltf::Node,
    parent: &Placement,
    g: &Globals,
    visiting: &mut Vec<bool>,
    out: &mut Scene,
) -> Result<(), SceneError> {
    let tracks = &g.tracks[node.index()];
    let at = format!("nodes[{}]", node.index());
    if visiting.iter().filter(|&&v| v).count() >= MAX_DEPTH {
        return Err(cx.err(at, format!("the node hierarchy is deeper than {MAX_DEPTH} levels")));
    }
    if visiting[node.index()] {
        return Err(cx.err(format!("{at}.children"), "the node hierarchy has a cycle"));
    }
    visiting[node.index()] = true;
    let (rest, local) = node_local(node);
    if !local.is_finite() {
        return Err(cx.err(at, "the node's transform is not finite"));
    }
    if tracks.moves() && matches!(node.transform(), gltf::scene::Transform::Matrix { .. }) {
        cx.warn(
            &at,
            "an animated node must be written as TRS, not `matrix` (glTF 2.0 §5.25): its matrix is decomposed",
        );
    }
    let motion = Motion {
        translation: tracks.translation.clone(),
        rotation: tracks.rotation.clone(),
        scale: tracks.scale.clone(),
        rest,
        still: local,
    };
    let mut place = parent.clone();
    if place.chain.is_empty() && !motion.is_animated() {
        place.world = parent.world * local;
    } else {
        if place.chain.is_empty() {
            place.chain_parent = parent.world;
        }
        place.chain.push(motion);
    }
    let animation = place.animation(g.period);
    if let Some(a) = &animation {
        place.world = a.transform_at(0.0);
    }
    let world = place.world;
    if !world.is_finite() {
        return Err(cx.err(at, "the node's transform is not finite"));
    }

    node_mesh(cx, node, &place, g, out)?;

    let origin = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    if let Some(cam) = node.camera() {
        let cam_at = format!("cameras[{}]", cam.index());
        let (projection, aspect) = match cam.projection() {
            gltf::camera::Projection::Perspective(p) => {
                let fov = p.yfov();
                if !(fov > 0.0 && fov < std::f32::consts::PI) {
                    return Err(cx.err(format!("{cam_at}.perspective.yfov"), format!("must lie in (0, π) (got {fov})")));
                }
                let aspect = p.aspect_ratio();
                if let Some(a) = aspect.filter(|a| !(a.is_finite() && *a > 0.0)) {
                    return Err(cx.err(format!("{cam_at}.perspective.aspectRatio"), format!("must be > 0 (got {a})")));
                }
                (Projection::Perspective { fov }, aspect)
            }
            gltf::camera::Projection::Orthographic(o) => {
                let (w, h) = (o.xmag(), o.ymag());
                if !(h.is_finite() && h > 0.0) {
                    return Err(cx.err(format!("{cam_at}.orthographic.ymag"), format!("must be > 0 (got {h})")));
                }
                if !(w.is_finite() && w > 0.0) {
                    return Err(cx.err(format!("{cam_at}.orthographic.xmag"), format!("must be > 0 (got {w})")));
                }
                (Projection::Orthographic { half_height: h }, Some(w / h))
            }
        };
        let up = world.transform_vector3(Vec3::Y);
        if forward == Vec3::ZERO || !up.is_finite() || forward.cross(up.normalize_or_zero()).length() < 1e-4 {
            return Err(cx.err(at.clone(), "the camera node's transform is degenerate"));
        }
        let mut name = node
            .name()
            .or(cam.name())
            .filter(|n| !n.is_empty())
            .map(str::to_string)
            .unwrap_or_else(|| format!("camera{}", out.cameras.len()));
        if out.cameras.iter().any(|c| c.name == name) {
            let mut k = 2;
            while out.cameras.iter().any(|c| c.name == format!("{name}-{k}")) {
                k += 1;
            }
            cx.warn(&at, &format!("camera name `{name}` is taken; this camera is `{name}-{k}`"));
            name = format!("{name}-{k}");
        }
        if let Some(a) = &animation {
            out.movers.push(Mover { what: Moved::Camera(out.cameras.len()), animation: a.clone() });
        }
        g.sources.borrow_mut().cameras.push(cam.index());
        out.cameras.push(Camera {
            name,
            projection,
            position: origin,
            target: origin + forward,
            up: up.normalize(),
            aspect,
        });
    }

    if let Some(light) = node.light() {
        let l_at = format!("extensions.KHR_lights_punctual.lights[{}]", light.index());
        let c = light.color();
        let color = Vec3::new(c[0], c[1], c[2]);
        if !color.is_finite() || color.min_element() < 0.0 {
            return Err(cx.err(format!("{l_at}.color"), "components must be finite and >= 0"));
        }
        let raw = light.intensity();
        if !(raw.is_finite() && raw >= 0.0) {
            return Err(cx.err(format!("{l_at}.intensity"), format!("must be finite and >= 0 (got {raw})")));
        }
        let intensity = raw / LUMENS_PER_WATT;
        if forward == Vec3::ZERO {
            return Err(cx.err(at, "the light node's transform is degenerate"));
        }
        if let Some(r) = light.range() {
            cx.warn(
                &format!("{l_at}.range"),
                &format!("range {r} m is ignored: the light falls off as 1/d² with no cutoff (a hint the spec allows to ignore)"),
            );
        }
        let (kind, cone) = match light.kind() {
            gltf::khr_lights_punctual::Kind::Point => (LightKind::Point, std::f32::consts::PI),
            gltf::khr_lights_punctual::Kind::Directional => (LightKind::Directional, 0.0),
            gltf::khr_lights_punctual::Kind::Spot { outer_cone_angle, inner_cone_angle } => {
                let deg = outer_cone_angle.to_degrees();
                if !(deg > 0.0 && deg < 90.0) {
                    return Err(cx.err(
                        format!("{l_at}.spot.outerConeAngle"),
                        format!("the cone half-angle must lie in (0, π/2) (got {outer_cone_angle})"),
                    ));
                }
                if inner_cone_angle < outer_cone_angle * 0.999 {
                    cx.warn(
                        &format!("{l_at}.spot"),
                        &format!(
                            "the spot's soft edge from {:.1}° to {deg:.1}° is drawn hard at {deg:.1}° (innerConeAngle is ignored)",
                            inner_cone_angle.to_degrees()
                        ),
                    );
                }
                (LightKind::Spot, outer_cone_angle)
            }
        };
        // A point light shines every way; its maps aim at the glass (Scene::aim_point_lights, once loaded).
        let target = if kind == LightKind::Point { Vec3::NAN } else { origin + forward };
        if let Some(a) = &animation {
            out.movers.push(Mover { what: Moved::Light(out.lights.len()), animation: a.clone() });
        }
        g.sources.borrow_mut().lights.push(light.index());
        out.lights.push(Light::punctual(kind, origin, target, cone, intensity, color));
    }

    for c in node.children() {
        visit(cx, &c, &place, g, visiting, out)?;
    }
    visiting[node.index()] = false;
    Ok(())
}

/// The objects of the node's mesh, placed by the node, or once per instance (EXT_mesh_gpu_instancing).
fn node_mesh(cx: &Cx, node: &gltf::Node, place: &Placement, g: &Globals, out: &mut Scene) -> Result<(), SceneError> {
    if let Some(mesh) = node.mesh() {
        let places = match instances(cx, node, g)? {
            Some(locals) => locals.into_iter().map(|local| place.instanced(local)).collect(),
            None => vec![place.clone()],
        };
        mesh_objects(cx, node, &mesh, &places, g, out)?;
    } else if node.extension_value(INSTANCING).is_some() {
        let at = format!("nodes[{}].extensions.{INSTANCING}", node.index());
        cx.warn(&at, "the node has no mesh to instance: ignored");
    }
    Ok(())
}

/// The most instances one node may draw (EXT_mesh_gpu_instancing): each is an object of the scene, holding its
/// triangles in world space on the host (the GPU's BVH holds the mesh once).
pub const MAX_INSTANCES: usize = 1 << 14;

/// The most triangles one node's instances may hold together.
pub const MAX_INSTANCED_TRIANGLES: usize = 1 << 24;

/// A placement as translation, rotation and scale.
type Trs = (Vec3, Quat, Vec3);

/// A node's EXT_mesh_gpu_instancing placements in its own space (translation, rotation, scale), each attribute's
/// absent components the identity's; None without the extension. TRANSLATION and SCALE are VEC3 of FLOAT (or, as
/// KHR_mesh_quantization allows, of bytes or shorts), ROTATION a unit VEC4 of FLOAT or normalized bytes or shorts;
/// all of one count.
fn instances(cx: &Cx, node: &gltf::Node, g: &Globals) -> Result<Option<Vec<Trs>>, SceneError> {
    use gltf::accessor::Dimensions;
    let Some(ext) = node.extension_value(INSTANCING) else { return Ok(None) };
    let at = format!("nodes[{}].extensions.{INSTANCING}", node.index());
    let attributes = ext
        .get("attributes")
        .and_then(|a| a.as_object())
        .ok_or_else(|| cx.err(format!("{at}.attributes"), "must be an object of accessor indices"))?;
    let mut count = None;
    let mut read = |name: &str, dims: Dimensions, ints: &[(gltf::accessor::DataType, bool)]| {
        let Some(v) = attributes.get(name) else { return Ok(None) };
        let a_at = format!("{at}.attributes.{name}");
        let a = v
            .as_u64()
            .and_then(|i| g.document.accessors().nth(usize::try_from(i).ok()?))
            .ok_or_else(|| cx.err(a_at.clone(), format!("must be an accessor's index (got {v})")))?;
        if *count.get_or_insert(a.count()) != a.count() {
            return Err(cx.err(a_at, format!("holds {} instances where another attribute holds {count:?}", a.count())));
        }
        let values = read_attribute(cx, &a, &a_at, g.buffers, dims, ints)?;
        if values.iter().any(|x| !x.is_finite()) {
            return Err(cx.err(a_at, "must be finite"));
        }
        Ok(Some(values))
    };
    let translation = read("TRANSLATION", Dimensions::Vec3, quantized::DELTA)?;
    let rotation = read("ROTATION", Dimensions::Vec4, quantized::NORMAL)?;
    let scale = read("SCALE", Dimensions::Vec3, quantized::DELTA)?;
    let n = count.unwrap_or(0);
    if n == 0 {
        return Err(cx.err(format!("{at}.attributes"), "needs TRANSLATION, ROTATION or SCALE with instances"));
    }
    if n > MAX_INSTANCES {
        return Err(cx.err(format!("{at}.attributes"), format!("{n} instances: at most {MAX_INSTANCES} are supported")));
    }
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let t = translation.as_ref().map_or(Vec3::ZERO, |v| Vec3::from_slice(&v[3 * k..]));
        let s = scale.as_ref().map_or(Vec3::ONE, |v| Vec3::from_slice(&v[3 * k..]));
        let q = rotation.as_ref().map_or(Quat::IDENTITY, |v| Quat::from_slice(&v[4 * k..]));
        let q = unit(q);
        if !q.is_finite() || s.cmpeq(Vec3::ZERO).any() {
            return Err(cx.err(
                format!("{at}.attributes"),
                format!("instance {k}: its rotation must be a non-zero quaternion and its scale non-zero"),
            ));
        }
        out.push((t, q, s));
    }
    Ok(Some(out))
}

/// A skinned mesh's placement: its vertices are placed by its joints, not by its node (glTF 2.0 §3.7.3.3). At rest
/// a skin's joint transforms times their inverse bind matrices are the mesh's bind placement; it stays there (with
/// a warning). None: the node has no skin (or its bind placement is degenerate).
fn skin_placement(cx: &Cx, node: &gltf::Node, g: &Globals, base_name: &str) -> Result<Option<Placement>, SceneError> {
    let Some(skin) = node.skin() else { return Ok(None) };
    let joint = skin.joints().next();
    let ibm = match (skin.inverse_bind_matrices(), &joint) {
        (Some(a), Some(_)) => {
            let m = read_floats(cx, &a, &format!("skins[{}].inverseBindMatrices", skin.index()), g.buffers, 16)?;
            m.get(..16).map_or(Mat4::IDENTITY, Mat4::from_cols_slice)
        }
        _ => Mat4::IDENTITY,
    };
    let bind = joint.map_or(Mat4::IDENTITY, |j| g.rest_world[j.index()]) * ibm;
    cx.warn(
        &node_label(node),
        &format!(
            "skins are not supported: mesh \"{base_name}\" stands at its bind pose (skins[{}] and its joints' animation are ignored)",
            skin.index()
        ),
    );
    let ok = bind.is_finite() && glam::Mat3::from_mat4(bind).determinant().abs() > 1e-12;
    Ok(ok.then(|| Placement { world: bind, chain: Vec::new(), chain_parent: Mat4::IDENTITY }))
}

/// The objects of `node`'s mesh, one per primitive and placement: placed by the node (animated or not; one
/// placement, or one per EXT_mesh_gpu_instancing instance), a skinned mesh at its bind pose, with its morph
/// targets weighted (static weights baked in; animated ones kept for the GPU).
fn mesh_objects(
    cx: &Cx,
    node: &gltf::Node,
    mesh: &gltf::Mesh,
    places: &[Placement],
    g: &Globals,
    out: &mut Scene,
) -> Result<(), SceneError> {
    let (buffers, materials) = (g.buffers, g.materials);
    let tracks = &g.tracks[node.index()];
    let at = format!("nodes[{}]", node.index());
    let mesh_at = format!("meshes[{}]", mesh.index());
    let base_name = node.name().or(mesh.name()).map(str::to_string).unwrap_or_else(|| format!("mesh{}", mesh.index()));
    let places = match skin_placement(cx, node, g, &base_name)? {
        Some(bind) => vec![bind],
        None => places.to_vec(),
    };
    let count = mesh.primitives().len();
    let targets_of = |p: &gltf::Primitive| p.morph_targets().len();
    let n_targets = mesh.primitives().next().map_or(0, |p| targets_of(&p));
    if let Some(p) = mesh.primitives().find(|p| targets_of(p) != n_targets) {
        return Err(cx.err(
            format!("{mesh_at}.primitives[{}].targets", p.index()),
            format!(
                "{} morph targets where the mesh's first primitive has {n_targets}: every primitive needs the same",
                targets_of(&p)
            ),
        ));
    }
    // The weights: the node's, else the mesh's, else zero.
    let weights: Vec<f32> = match node.weights().or(mesh.weights()) {
        Some(w) => w.to_vec(),
        None => vec![0.0; n_targets],
    };
    if weights.len() != n_targets || weights.iter().any(|w| !w.is_finite()) {
        let field = if node.weights().is_some() { format!("{at}.weights") } else { format!("{mesh_at}.weights") };
        return Err(cx.err(field, format!("needs one finite weight per morph target ({n_targets})")));
    }
    for p in mesh.primitives() {
        let p_at = format!("{mesh_at}.primitives[{}]", p.index());
        let name = if count > 1 { format!("{base_name}#{}", p.index()) } else { base_name.clone() };
        if p.mode() != gltf::mesh::Mode::Triangles {
            return Err(cx.err(
                format!("{p_at}.mode"),
                format!("mesh \"{base_name}\": only triangles are supported (this primitive is {:?})", p.mode()),
            ));
        }
        let (mut m, computed_normals) = primitive(cx, &p, &p_at, buffers)?;
        if m.triangle_count() == 0 {
            cx.warn(&p_at, &format!("mesh \"{base_name}\" has no triangles and is skipped"));
            continue;
        }
        let (material, priority) =
            p.material().index().map_or((g.default_material, 0), |i| (materials[i], g.priorities[i]));
        // A textured material reads its TEXCOORD set (the texture coordinates are not transformed with the node).
        if let Some(set) = p.material().index().and_then(|i| g.tex_coords[i]) {
            let a = p.get(&gltf::Semantic::TexCoords(set)).ok_or_else(|| {
                cx.err(
                    format!("{p_at}.attributes"),
                    format!("its material's base color texture reads TEXCOORD_{set}, which the primitive lacks"),
                )
            })?;
            let uvs = read_uvs(cx, &a, &format!("{p_at}.attributes.TEXCOORD_{set}"), buffers)?;
            if uvs.len() != m.positions.len() {
                return Err(cx.err(format!("{p_at}.attributes.TEXCOORD_{set}"), "needs one uv per position"));
            }
            m.uvs = uvs;
        }
        // Still weights are baked into the mesh; animated ones deform it on the GPU.
        let mut morph = None;
        if n_targets > 0 {
            let k = Morph {
                targets: morph_targets(cx, &p, &p_at, buffers, m.positions.len())?,
                weights: weights.clone(),
                tracks: tracks.weights.clone().unwrap_or_default(),
                period: g.period,
            };
            if k.is_animated() {
                morph = Some(k);
            } else if k.weights.iter().any(|&w| w != 0.0) {
                m = k.apply(&m, &k.weights);
            }
        }
        // The same repairs as an OBJ mesh's (docs/cli.md, "Input checks"): an open or non-manifold receiver
        // is an ordinary surface, so only glass hears about its topology.
        let report = super::mesh::sanitize(&mut m, computed_normals);
        if report.normals_negated {
            for t in morph.iter_mut().flat_map(|k| k.targets.iter_mut()) {
                t.normals.iter_mut().for_each(|n| *n = -*n);
            }
        }
        let glass = matches!(material, Material::Dielectric { .. });
        for finding in report.findings() {
            let topology = finding.starts_with("open") || finding.starts_with("non-");
            if glass || !topology {
                cx.warn(&p_at, &format!("mesh \"{base_name}\": {finding}"));
            }
        }
        // The mesh stays in its node's space, placed by the node's world transform (an instance of it: the
        // renderer's BVH holds it in that space), animated or not, so that a still pose and an animation reaching
        // it render alike; and it is deformed at the scene's time when its morph weights animate. An instanced
        // node's mesh is one object per instance (`name[k]`), all of them sharing one BVH.
        if places.len() > 1 && places.len() * m.triangle_count() > MAX_INSTANCED_TRIANGLES {
            return Err(cx.err(
                format!("{at}.extensions.{INSTANCING}"),
                format!(
                    "{} instances of mesh \"{base_name}\" ({} triangles) make more than {MAX_INSTANCED_TRIANGLES} \
                     triangles",
                    places.len(),
                    m.triangle_count()
                ),
            ));
        }
        for (k, place) in places.iter().enumerate() {
            let anim = std::sync::Arc::new(super::ObjectAnimation {
                mesh: m.clone(),
                animation: place.animation(g.period),
                placement: place.world,
                water: None,
                morph: morph.clone(),
            });
            let placed = anim.mesh_at(0.0);
            if placed.positions.iter().any(|v| !v.is_finite()) {
                return Err(cx.err(at.clone(), format!("mesh \"{base_name}\": world-space positions overflow")));
            }
            let name = if places.len() > 1 { format!("{name}[{k}]") } else { name.clone() };
            g.sources.borrow_mut().materials.push(p.material().index());
            out.objects.push(Object { animation: Some(anim), priority, ..Object::new(name, material, placed) });
        }
    }
    Ok(())
}

/// A primitive's morph targets: POSITION (and NORMAL) displacements, one per vertex. Tangent displacements are
/// ignored (the renderer has no tangents).
fn morph_targets(
    cx: &Cx,
    p: &gltf::Primitive,
    at: &str,
    buffers: &[Vec<u8>],
    vertices: usize,
) -> Result<Vec<MorphTarget>, SceneError> {
    let mut out = Vec::new();
    for (k, t) in p.morph_targets().enumerate() {
        let t_at = format!("{at}.targets[{k}]");
        let read = |a: Option<gltf::Accessor>, what: &str| -> Result<Vec<Vec3>, SceneError> {
            let Some(a) = a else { return Ok(Vec::new()) };
            let ints = if what == "POSITION" { quantized::DELTA } else { quantized::NORMAL };
            let v = read_vec3(cx, &a, &format!("{t_at}.{what}"), buffers, ints)?;
            if v.len() != vertices || v.iter().any(|x| !x.is_finite()) {
                return Err(
                    cx.err(format!("{t_at}.{what}"), format!("needs one finite displacement per vertex ({vertices})"))
                );
            }
            Ok(v)
        };
        let positions = read(t.positions(), "POSITION")?;
        let positions = if positions.is_empty() { vec![Vec3::ZERO; vertices] } else { positions };
        out.push(MorphTarget { positions, normals: read(t.normals(), "NORMAL")? });
    }
    Ok(out)
}

/// A primitive's triangles, and whether its normals were computed (the file has none).
fn primitive(cx: &Cx, p: &gltf::Primitive, at: &str, buffers: &[Vec<u8>]) -> Result<(Mesh, bool), SceneError> {
    let pos = p
        .get(&gltf::Semantic::Positions)
        .ok_or_else(|| cx.err(format!("{at}.attributes"), "a primitive needs a POSITION attribute"))?;
    let positions = read_vec3(cx, &pos, &format!("{at}.attributes.POSITION"), buffers, quantized::POSITION)?;
    if positions.iter().any(|v| !v.is_finite()) {
        return Err(cx.err(format!("{at}.attributes.POSITION"), "positions must be finite"));
    }
    let indices = match p.indices() {
        Some(a) => read_indices(cx, &a, &format!("{at}.indices"), buffers)?,
        None => (0..positions.len() as u32).collect(),
    };
    if indices.len() % 3 != 0 {
        return Err(
            cx.err(format!("{at}.indices"), format!("{} indices is not a whole number of triangles", indices.len()))
        );
    }
    if let Some(bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
        return Err(
            cx.err(format!("{at}.indices"), format!("index {bad} is out of range ({} vertices)", positions.len()))
        );
    }
    let mut mesh = Mesh { positions, normals: Vec::new(), indices, uvs: Vec::new() };
    match p.get(&gltf::Semantic::Normals) {
        Some(n) => {
            let normals = read_vec3(cx, &n, &format!("{at}.attributes.NORMAL"), buffers, quantized::NORMAL)?;
            if normals.len() != mesh.positions.len() || normals.iter().any(|v| !v.is_finite()) {
                return Err(cx.err(format!("{at}.attributes.NORMAL"), "needs one finite normal per position"));
            }
            mesh.normals = normals.into_iter().map(|v| v.normalize_or_zero()).collect();
            Ok((mesh, false))
        }
        None => {
            mesh.compute_normals();
            Ok((mesh, true))
        }
    }
}

/// An accessor's elements, densely packed (`count` × its element size): read from its bufferView through the
/// view's byteStride (interleaved attributes), or zeros without one, then with its sparse substitutions applied.
/// Everything is bounds-checked.
fn dense(cx: &Cx, a: &gltf::Accessor, at: &str, buffers: &[Vec<u8>]) -> Result<Vec<u8>, SceneError> {
    let acc_at = format!("accessors[{}]", a.index());
    let ctx = |m: &str| cx.err(format!("{at} ({acc_at})"), m.to_string());
    let view_bytes = |view: &gltf::buffer::View| -> Result<&[u8], SceneError> {
        let buf = &buffers[view.buffer().index()];
        view.offset()
            .checked_add(view.length())
            .and_then(|end| buf.get(view.offset()..end))
            .ok_or_else(|| ctx("the bufferView lies outside its buffer"))
    };
    let elem = a.size();
    let n = a.count();
    let total = n.checked_mul(elem).filter(|&t| t <= 1 << 31).ok_or_else(|| ctx("the accessor is too large"))?;
    let mut out = vec![0u8; total];
    if let Some(view) = a.view() {
        let stride = view.stride().unwrap_or(elem);
        if stride < elem {
            return Err(ctx("byteStride is smaller than the element"));
        }
        let bytes = view_bytes(&view)?;
        if n > 0 {
            let end =
                (n - 1).checked_mul(stride).and_then(|x| x.checked_add(elem)).and_then(|x| x.checked_add(a.offset()));
            if !matches!(end, Some(e) if e <= bytes.len()) {
                return Err(ctx("the accessor's data lies outside its bufferView"));
            }
        }
        for i in 0..n {
            let src = a.offset() + i * stride;
            out[i * elem..(i + 1) * elem].copy_from_slice(&bytes[src..src + elem]);
        }
    }
    if let Some(sparse) = a.sparse() {
        let k = sparse.count();
        let idx = sparse.indices();
        let isize = match idx.index_type() {
            gltf::accessor::sparse::IndexType::U8 => 1,
            gltf::accessor::sparse::IndexType::U16 => 2,
            gltf::accessor::sparse::IndexType::U32 => 4,
        };
        let ib = view_bytes(&idx.view())?;
        let ib = idx.offset().checked_add(k * isize).and_then(|end| ib.get(idx.offset()..end));
        let ib = ib.ok_or_else(|| ctx("the sparse indices lie outside their bufferView"))?;
        let vals = sparse.values();
        let vb = view_bytes(&vals.view())?;
        let vb = vals.offset().checked_add(k * elem).and_then(|end| vb.get(vals.offset()..end));
        let vb = vb.ok_or_else(|| ctx("the sparse values lie outside their bufferView"))?;
        let mut last = None;
        for j in 0..k {
            let b = &ib[j * isize..(j + 1) * isize];
            let i = match isize {
                1 => b[0] as usize,
                2 => u16::from_le_bytes([b[0], b[1]]) as usize,
                _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize,
            };
            if i >= n || last.is_some_and(|l| i <= l) {
                return Err(ctx("sparse indices must increase and lie below the accessor's count"));
            }
            last = Some(i);
            out[i * elem..(i + 1) * elem].copy_from_slice(&vb[j * elem..(j + 1) * elem]);
        }
    }
    Ok(out)
}

/// An accessor of `width` components per element as floats: FLOAT, or normalized integers mapped as glTF 2.0
/// §3.11 says (c / 127 for signed bytes, c / 65535 for unsigned shorts, ...).
fn read_floats(
    cx: &Cx,
    a: &gltf::Accessor,
    at: &str,
    buffers: &[Vec<u8>],
    width: usize,
) -> Result<Vec<f32>, SceneError> {
    decode_floats(cx, a, at, buffers, width, false)
}

/// [`read_floats`], where `plain_ints` also takes integers that are not normalized as their values (the vertex
/// attributes of KHR_mesh_quantization: a position of shorts is scaled by its node's transform).
fn decode_floats(
    cx: &Cx,
    a: &gltf::Accessor,
    at: &str,
    buffers: &[Vec<u8>],
    width: usize,
    plain_ints: bool,
) -> Result<Vec<f32>, SceneError> {
    use gltf::accessor::DataType;
    let comps = a.dimensions().multiplicity();
    if comps != width {
        return Err(cx.err(
            format!("{at} (accessors[{}])", a.index()),
            format!("must have {width} components per element (got {:?})", a.dimensions()),
        ));
    }
    let bytes = dense(cx, a, at, buffers)?;
    let read: fn(&[u8]) -> f32 = match (a.data_type(), a.normalized()) {
        (DataType::F32, _) => |b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        (DataType::I8, true) => |b| (b[0] as i8 as f32 / 127.0).max(-1.0),
        (DataType::U8, true) => |b| b[0] as f32 / 255.0,
        (DataType::I16, true) => |b| (i16::from_le_bytes([b[0], b[1]]) as f32 / 32767.0).max(-1.0),
        (DataType::U16, true) => |b| u16::from_le_bytes([b[0], b[1]]) as f32 / 65535.0,
        (DataType::I8, false) if plain_ints => |b| b[0] as i8 as f32,
        (DataType::U8, false) if plain_ints => |b| b[0] as f32,
        (DataType::I16, false) if plain_ints => |b| i16::from_le_bytes([b[0], b[1]]) as f32,
        (DataType::U16, false) if plain_ints => |b| u16::from_le_bytes([b[0], b[1]]) as f32,
        (t, n) => {
            let n = if n { "normalized " } else { "" };
            return Err(cx.err(
                format!("{at} (accessors[{}])", a.index()),
                format!("must be FLOAT or normalized integers (got {n}{t:?})"),
            ));
        }
    };
    let size = a.data_type().size();
    // A matrix's columns are padded to 4 bytes (§3.6.2.4): only MAT2 and MAT3 of bytes or shorts differ, and no
    // accessor read here is one.
    Ok(bytes.chunks_exact(size).map(read).collect())
}

/// The component types a vertex attribute may have (glTF 2.0 §3.7.2.1 with KHR_mesh_quantization), each as
/// (type, normalized); FLOAT is always allowed.
mod quantized {
    use gltf::accessor::DataType::{self, I16, I8, U16, U8};
    pub const POSITION: &[(DataType, bool)] =
        &[(I8, false), (I8, true), (U8, false), (U8, true), (I16, false), (I16, true), (U16, false), (U16, true)];
    pub const NORMAL: &[(DataType, bool)] = &[(I8, true), (I16, true)];
    pub const TEXCOORD: &[(DataType, bool)] = POSITION;
    /// A morph target's POSITION displacements.
    pub const DELTA: &[(DataType, bool)] = &[(I8, false), (I8, true), (I16, false), (I16, true)];
}

/// A vertex attribute of `dims`, as floats: FLOAT, or one of the integer types in `ints` ([`quantized`]).
fn read_attribute(
    cx: &Cx,
    a: &gltf::Accessor,
    at: &str,
    buffers: &[Vec<u8>],
    dims: gltf::accessor::Dimensions,
    ints: &[(gltf::accessor::DataType, bool)],
) -> Result<Vec<f32>, SceneError> {
    use gltf::accessor::DataType;
    let (t, n) = (a.data_type(), a.normalized());
    if a.dimensions() != dims || !(t == DataType::F32 && !n || ints.contains(&(t, n))) {
        // glTF's own names: "normalized UNSIGNED_SHORT", "VEC3".
        let name = |t: DataType, n: bool| {
            let t = match t {
                DataType::I8 => "BYTE",
                DataType::U8 => "UNSIGNED_BYTE",
                DataType::I16 => "SHORT",
                DataType::U16 => "UNSIGNED_SHORT",
                DataType::U32 => "UNSIGNED_INT",
                DataType::F32 => "FLOAT",
            };
            format!("{}{t}", if n { "normalized " } else { "" })
        };
        let allowed: Vec<String> = ints.iter().map(|&(t, n)| name(t, n)).collect();
        let dims_name = |d: gltf::accessor::Dimensions| format!("{d:?}").to_uppercase();
        return Err(cx.err(
            format!("{at} (accessors[{}])", a.index()),
            format!(
                "must be {} of FLOAT, or (KHR_mesh_quantization) of {} (got {} of {})",
                dims_name(dims),
                allowed.join(", "),
                dims_name(a.dimensions()),
                name(t, n)
            ),
        ));
    }
    decode_floats(cx, a, at, buffers, dims.multiplicity(), true)
}

fn read_vec3(
    cx: &Cx,
    a: &gltf::Accessor,
    at: &str,
    buffers: &[Vec<u8>],
    ints: &[(gltf::accessor::DataType, bool)],
) -> Result<Vec<Vec3>, SceneError> {
    let v = read_attribute(cx, a, at, buffers, gltf::accessor::Dimensions::Vec3, ints)?;
    Ok(v.chunks_exact(3).map(Vec3::from_slice).collect())
}

/// TEXCOORD data: VEC2 of FLOAT, or of normalized unsigned bytes or shorts, or (KHR_mesh_quantization) of any
/// byte or short, which the texture's KHR_texture_transform scales; finite.
fn read_uvs(cx: &Cx, a: &gltf::Accessor, at: &str, buffers: &[Vec<u8>]) -> Result<Vec<glam::Vec2>, SceneError> {
    let uvs: Vec<glam::Vec2> =
        read_attribute(cx, a, at, buffers, gltf::accessor::Dimensions::Vec2, quantized::TEXCOORD)?
            .chunks_exact(2)
            .map(glam::Vec2::from_slice)
            .collect();
    if uvs.iter().any(|uv| !uv.is_finite()) {
        return Err(cx.err(at.to_string(), "texture coordinates must be finite"));
    }
    Ok(uvs)
}

fn read_indices(cx: &Cx, a: &gltf::Accessor, at: &str, buffers: &[Vec<u8>]) -> Result<Vec<u32>, SceneError> {
    use gltf::accessor::{DataType, Dimensions};
    if a.dimensions() != Dimensions::Scalar {
        return Err(cx.err(format!("{at} (accessors[{}])", a.index()), "indices must be SCALAR"));
    }
    let read: fn(&[u8]) -> u32 = match a.data_type() {
        DataType::U8 => |b| b[0] as u32,
        DataType::U16 => |b| u16::from_le_bytes([b[0], b[1]]) as u32,
        DataType::U32 => |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        t => {
            return Err(cx.err(
                format!("{at} (accessors[{}])", a.index()),
                format!("indices must be unsigned integers (got {t:?})"),
            ))
        }
    };
    let size = a.data_type().size();
    Ok(dense(cx, a, at, buffers)?.chunks_exact(size).map(read).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips() {
        assert_eq!(base64_decode("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(base64_decode("aGVsbG8h").unwrap(), b"hello!");
        assert_eq!(base64_decode("aGVsbA==").unwrap(), b"hell");
        assert!(base64_decode("a").is_none());
        assert!(base64_decode("a*==").is_none());
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.bin"), "a b.bin");
        assert_eq!(percent_decode("%aé%"), "%aé%");
        assert_eq!(percent_decode("%C3%A9"), "é");
    }
}

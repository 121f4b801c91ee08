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

mod accessors;
mod animations;
mod buffers;
mod draco;
mod materials;
mod meshopt;
mod nodes;

use accessors::*;
use animations::*;
use buffers::*;
use materials::*;
use nodes::*;

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
    meshopt::EXTENSION,
    draco::EXTENSION,
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

    validate(&cx, root)?;

    let mut buffers = load_buffers(&cx, &document, blob, path)?;
    meshopt::decode_views(&cx, &document, &mut buffers)?;
    let document = draco::inflate(&cx, &document, &mut buffers)?.unwrap_or(document);

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

    let roots = root_nodes(&cx, &document);

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
    check_lights_and_objects(&cx, &mut out)?;
    out.place_directional_lights();
    Ok(out)
}

/// The gltf crate's validation (indices in range, required fields present, enums valid), but for what this loader
/// reads itself (the extensions it checked, Draco's accessors, WebP-only textures), and the animation targets the
/// crate leaves unchecked.
fn validate(cx: &Cx, root: &gltf::json::Root) -> Result<(), SceneError> {
    // Required extensions were checked before (the crate does not know the ones we ignore).
    // A Draco primitive's accessors have no bufferView: the decoded data gives them one (src/scene/gltf/draco.rs).
    let draco = draco::accessors(root);
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
    Ok(())
}

/// The nodes the loaded scene holds: the default scene's (else the first scene's, with a warning when there are
/// several), else every node that is nobody's child.
fn root_nodes<'a>(cx: &Cx, document: &'a gltf::Document) -> Vec<gltf::Node<'a>> {
    let scene = document.default_scene().or_else(|| document.scenes().next());
    if let Some(sc) = &scene {
        let n = document.scenes().len();
        if n > 1 {
            let which = if document.default_scene().is_some() { "the file's `scene`" } else { "the first" };
            cx.warn("scenes", &format!("the file has {n} scenes: scenes[{}] ({which}) is loaded", sc.index()));
        }
    }
    match &scene {
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
    }
}

/// A loaded scene's lights and objects as the renderer needs them: a light at least, none at the center of what it
/// aims at, at most MAX_LIGHTS, and a triangle mesh (point lights are aimed here).
fn check_lights_and_objects(cx: &Cx, out: &mut Scene) -> Result<(), SceneError> {
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
    Ok(())
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

//! glTF 2.0 import (`.gltf` and `.glb`): meshes baked to world space with their node transforms, cameras, one
//! KHR_lights_punctual spot or directional light, and the materials the renderer has (docs/scenes.md, "glTF scenes").
//!
//! Every error is a [`SceneError::Gltf`] naming the file and the JSON path (`meshes[0].primitives[1].mode`);
//! the CLI reports it with exit code 2. The file is validated before use and accessors are bounds-checked here,
//! so a corrupt file is an error, never a panic.

use super::animation::{Animation, Interpolation, Repeat, Track};
use super::{
    AlbedoMap, Camera, Light, LightKind, Material, Mesh, Object, Projection, Scene, SceneError, Texture, MAX_LIGHTS,
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
    "KHR_texture_transform",
];

/// The deepest node hierarchy accepted (the traversal is recursive).
const MAX_DEPTH: usize = 256;

struct Cx {
    file: String,
}

impl Cx {
    fn err(&self, path: impl Into<String>, message: impl Into<String>) -> SceneError {
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

pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path)
        .map_err(|e| SceneError::Io { file: file.clone(), message: format!("cannot read scene: {e}") })?;
    parse(&bytes, path)
}

/// Parse glTF JSON or GLB bytes; `path` locates the file for messages and external buffers.
pub fn parse(bytes: &[u8], path: &Path) -> Result<Scene, SceneError> {
    let cx = Cx { file: path.display().to_string() };
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| match e {
        gltf::Error::Deserialize(j) => SceneError::Syntax {
            file: cx.file.clone(),
            line: j.line(),
            column: j.column(),
            message: format!("not valid glTF JSON: {j}"),
        },
        gltf::Error::Binary(b) => cx.err("(GLB container)", format!("not a valid GLB file: {b}")),
        other => cx.err("(file)", format!("not a valid glTF file: {other}")),
    })?;
    let root = document.as_json();

    // Extensions first: a required extension we cannot honor makes everything else meaningless.
    let known = |e: &str| SUPPORTED.contains(&e);
    for (i, e) in root.extensions_required.iter().enumerate() {
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
        if !known(e) {
            cx.warn(&format!("extensionsUsed[{i}]"), &format!("extension `{e}` is not supported and is ignored"));
        }
    }

    // The crate's validation: indices in range, required fields present, enums valid. Required extensions were
    // checked above (the crate does not know the ones we ignore).
    let mut problems = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |p: &dyn Fn() -> gltf::json::Path, e: VError| {
        let p = p().to_string();
        if !(p.starts_with("extensionsRequired") && matches!(e, VError::Unsupported)) {
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

    let buffers = load_buffers(&cx, &document, blob, path)?;

    // Materials, converted once (and warned about once), with the textures their base colors name; per material,
    // the TEXCOORD set its texture reads.
    let mut textures = Textures::default();
    let (materials, tex_coords): (Vec<Material>, Vec<Option<u32>>) = document
        .materials()
        .map(|m| material(&cx, &m, &buffers, path, &mut textures))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .unzip();
    // The glTF default material: white, metallic 1, roughness 1 → diffuse white.
    let default_material = Material::diffuse(Vec3::ONE);

    let scene = document.default_scene().or_else(|| document.scenes().next());
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
    let tracks = animations(&cx, &document, &buffers)?;
    let g = Globals {
        buffers: &buffers,
        materials: &materials,
        tex_coords: &tex_coords,
        default_material,
        tracks: &tracks,
    };
    for n in roots {
        visit(&cx, &n, Mat4::IDENTITY, &g, &mut visiting, &mut out)?;
    }
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
    // A glTF directional light is at infinity; ours starts its beam at `position`. Start it just outside the
    // scene's bounding sphere, up-beam, so that it lights everything.
    let (lo, hi) = out.bounds();
    let (center, radius) = ((lo + hi) * 0.5, (hi - lo).length() * 0.5);
    for l in out.lights.iter_mut().filter(|l| l.kind == LightKind::Directional) {
        let dir = (l.target - l.position).normalize();
        l.position = center - dir * (radius * 1.01 + 1e-3);
        l.target = l.position + dir;
    }
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
#[derive(Default)]
struct Textures {
    list: Vec<std::sync::Arc<Texture>>,
    by_image: std::collections::HashMap<usize, usize>,
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
    let img = info.texture().source();
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

#[allow(clippy::too_many_arguments)]
/// What every node's visit reads: the buffers, the materials and the animation tracks.
struct Globals<'a> {
    buffers: &'a [Vec<u8>],
    materials: &'a [Material],
    /// Per material: the TEXCOORD set its base color texture reads (None: untextured).
    tex_coords: &'a [Option<u32>],
    default_material: Material,
    /// Per node: its animation tracks (translation, rotation, scale), from the file's first animation.
    tracks: &'a [NodeTracks],
}

/// A node's animated components.
#[derive(Clone, Default)]
struct NodeTracks {
    translation: Option<Track<Vec3>>,
    rotation: Option<Track<Quat>>,
    scale: Option<Track<Vec3>>,
}

/// The file's first animation, per node (each node its own tracks). Times must be finite and increase, values be
/// finite, and a cubic-spline sampler hold three values (in tangent, value, out tangent) per keyframe. Morph-target
/// weights are not supported (a warning), nor further animations (a warning: only the first plays).
fn animations(cx: &Cx, document: &gltf::Document, buffers: &[Vec<u8>]) -> Result<Vec<NodeTracks>, SceneError> {
    let mut tracks = vec![NodeTracks::default(); document.nodes().len()];
    let mut all = document.animations();
    let Some(anim) = all.next() else { return Ok(tracks) };
    if all.next().is_some() {
        cx.warn("animations", "the file has several animations: only the first (animations[0]) plays");
    }
    for ch in anim.channels() {
        let at = format!("animations[{}].channels[{}]", anim.index(), ch.index());
        let s_at = format!("animations[{}].samplers[{}]", anim.index(), ch.sampler().index());
        let reader = ch.reader(|b: gltf::Buffer| buffers.get(b.index()).map(|d| d.as_slice()));
        let times: Vec<f32> =
            reader.read_inputs().ok_or_else(|| cx.err(format!("{s_at}.input"), "cannot be read"))?.collect();
        if times.is_empty() || times.iter().any(|t| !t.is_finite()) {
            return Err(cx.err(format!("{s_at}.input"), "keyframe times must be finite, and there must be one"));
        }
        if let Some(k) = times.windows(2).position(|w| w[1] <= w[0]) {
            return Err(cx.err(
                format!("{s_at}.input"),
                format!("keyframe times must increase: {} s follows {} s", times[k + 1], times[k]),
            ));
        }
        use gltf::animation::util::ReadOutputs;
        use gltf::animation::Interpolation as GI;
        let interpolation = match ch.sampler().interpolation() {
            GI::Linear => Interpolation::Linear,
            GI::Step => Interpolation::Step,
            GI::CubicSpline => Interpolation::Cubic,
        };
        let per_key = if interpolation == Interpolation::Cubic { 3 } else { 1 };
        let outputs = reader.read_outputs().ok_or_else(|| cx.err(format!("{s_at}.output"), "cannot be read"))?;
        let node = ch.target().node().index();
        let count_err = |n: usize| {
            cx.err(
                format!("{s_at}.output"),
                format!(
                    "{n} values for {} keyframes (a {:?} sampler needs {per_key} each)",
                    times.len(),
                    interpolation
                ),
            )
        };
        // (in tangent, value, out tangent) per keyframe for cubic splines; the values alone otherwise.
        fn split<T: Copy>(v: Vec<T>, per_key: usize) -> (Vec<T>, Vec<(T, T)>) {
            if per_key == 1 {
                return (v, Vec::new());
            }
            let values = v.chunks_exact(3).map(|c| c[1]).collect();
            let tangents = v.chunks_exact(3).map(|c| (c[0], c[2])).collect();
            (values, tangents)
        }
        match outputs {
            ReadOutputs::Translations(it) | ReadOutputs::Scales(it) => {
                let scale = matches!(ch.target().property(), gltf::animation::Property::Scale);
                let v: Vec<Vec3> = it.map(Vec3::from).collect();
                if v.len() != times.len() * per_key {
                    return Err(count_err(v.len()));
                }
                let (values, tangents) = split(v, per_key);
                let bad = |x: &Vec3| !x.is_finite();
                if values.iter().any(bad)
                    || tangents.iter().any(|(a, b)| bad(a) || bad(b))
                    || (scale && values.iter().any(|x| x.abs().min_element() < 1e-9))
                {
                    return Err(cx.err(format!("{s_at}.output"), "values must be finite (and scales non-zero)"));
                }
                let track = Track { times, values, tangents, interpolation };
                if scale {
                    tracks[node].scale = Some(track);
                } else {
                    tracks[node].translation = Some(track);
                }
            }
            ReadOutputs::Rotations(r) => {
                let v: Vec<Quat> = r.into_f32().map(Quat::from_array).collect();
                if v.len() != times.len() * per_key {
                    return Err(count_err(v.len()));
                }
                if v.iter().any(|q| !q.is_finite() || (per_key == 1 && q.length() < 1e-6)) {
                    return Err(cx.err(format!("{s_at}.output"), "rotations must be finite, non-zero quaternions"));
                }
                let (values, tangents) = split(v, per_key);
                let values = values.into_iter().map(|q| q.normalize()).collect();
                tracks[node].rotation = Some(Track { times, values, tangents, interpolation });
            }
            ReadOutputs::MorphTargetWeights(_) => {
                cx.warn(&at, "morph-target weights are not supported; the mesh keeps its base shape");
            }
        }
    }
    Ok(tracks)
}

fn visit(
    cx: &Cx,
    node: &gltf::Node,
    parent: Mat4,
    g: &Globals,
    visiting: &mut Vec<bool>,
    out: &mut Scene,
) -> Result<(), SceneError> {
    let (buffers, materials, default_material) = (g.buffers, g.materials, g.default_material);
    let tracks = &g.tracks[node.index()];
    let animated = tracks.translation.is_some() || tracks.rotation.is_some() || tracks.scale.is_some();
    let at = format!("nodes[{}]", node.index());
    if visiting.iter().filter(|&&v| v).count() >= MAX_DEPTH {
        return Err(cx.err(at, format!("the node hierarchy is deeper than {MAX_DEPTH} levels")));
    }
    if visiting[node.index()] {
        return Err(cx.err(format!("{at}.children"), "the node hierarchy has a cycle"));
    }
    visiting[node.index()] = true;
    let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
    if !world.is_finite() {
        return Err(cx.err(at, "the node's transform is not finite"));
    }
    let origin = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();

    if let Some(mesh) = node.mesh() {
        let mesh_at = format!("meshes[{}]", mesh.index());
        let base_name =
            node.name().or(mesh.name()).map(str::to_string).unwrap_or_else(|| format!("mesh{}", mesh.index()));
        let count = mesh.primitives().len();
        for p in mesh.primitives() {
            let p_at = format!("{mesh_at}.primitives[{}]", p.index());
            let name = if count > 1 { format!("{base_name}#{}", p.index()) } else { base_name.clone() };
            if p.mode() != gltf::mesh::Mode::Triangles {
                return Err(cx.err(
                    format!("{p_at}.mode"),
                    format!("mesh \"{base_name}\": only triangles are supported (this primitive is {:?})", p.mode()),
                ));
            }
            let (m, computed_normals) = primitive(cx, &p, &p_at, buffers)?;
            if m.triangle_count() == 0 {
                cx.warn(&p_at, &format!("mesh \"{base_name}\" has no triangles and is skipped"));
                continue;
            }
            // An animated node's mesh stays in its own space, placed by its animation at the scene's time.
            let mut m = if animated { m } else { m.transformed(world) };
            if m.positions.iter().any(|v| !v.is_finite()) {
                return Err(cx.err(at.clone(), format!("mesh \"{base_name}\": world-space positions overflow")));
            }
            let material = match p.material().index() {
                Some(i) => materials[i],
                None => default_material,
            };
            // A textured material reads its TEXCOORD set (the texture coordinates are not transformed with the
            // node).
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
            // The same repairs as an OBJ mesh's (docs/cli.md, "Input checks"): an open or non-manifold receiver
            // is an ordinary surface, so only glass hears about its topology.
            let report = super::mesh::sanitize(&mut m, computed_normals);
            let glass = matches!(material, Material::Dielectric { .. });
            for finding in report.findings() {
                let topology = finding.starts_with("open") || finding.starts_with("non-");
                if glass || !topology {
                    cx.warn(&p_at, &format!("mesh \"{base_name}\": {finding}"));
                }
            }
            if animated {
                let (scale, rotation, translation) = node.transform().decomposed();
                let animation = Animation {
                    translation: tracks.translation.clone(),
                    rotation: tracks.rotation.clone(),
                    scale: tracks.scale.clone(),
                    rest: (Vec3::from(translation), Quat::from_array(rotation).normalize(), Vec3::from(scale)),
                    parent,
                    repeat: Repeat::Loop,
                };
                let placed = m.clone().transformed(animation.transform_at(0.0));
                let anim = std::sync::Arc::new(super::ObjectAnimation {
                    mesh: m,
                    animation: Some(animation),
                    placement: Mat4::IDENTITY,
                    water: None,
                });
                out.objects.push(Object { animation: Some(anim), ..Object::new(name, material, placed) });
            } else {
                out.objects.push(Object::new(name, material, m));
            }
        }
    }
    if animated && node.children().len() > 0 {
        cx.warn(&at, "the node is animated; its children keep their rest placement (only a node's own meshes move)");
    }

    if let Some(cam) = node.camera() {
        let cam_at = format!("cameras[{}]", cam.index());
        let projection = match cam.projection() {
            gltf::camera::Projection::Perspective(p) => {
                let fov = p.yfov();
                if !(fov > 0.0 && fov < std::f32::consts::PI) {
                    return Err(cx.err(format!("{cam_at}.perspective.yfov"), format!("must lie in (0, π) (got {fov})")));
                }
                Projection::Perspective { fov }
            }
            gltf::camera::Projection::Orthographic(o) => {
                let h = o.ymag();
                if !(h.is_finite() && h > 0.0) {
                    return Err(cx.err(format!("{cam_at}.orthographic.ymag"), format!("must be > 0 (got {h})")));
                }
                Projection::Orthographic { half_height: h }
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
        out.cameras.push(Camera { name, projection, position: origin, target: origin + forward, up: up.normalize() });
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
        let (kind, cone) = match light.kind() {
            gltf::khr_lights_punctual::Kind::Point => (LightKind::Point, std::f32::consts::PI),
            gltf::khr_lights_punctual::Kind::Directional => (LightKind::Directional, 0.0),
            gltf::khr_lights_punctual::Kind::Spot { outer_cone_angle, .. } => {
                let deg = outer_cone_angle.to_degrees();
                if !(deg > 0.0 && deg < 90.0) {
                    return Err(cx.err(
                        format!("{l_at}.spot.outerConeAngle"),
                        format!("the cone half-angle must lie in (0, π/2) (got {outer_cone_angle})"),
                    ));
                }
                (LightKind::Spot, outer_cone_angle)
            }
        };
        // A point light shines every way; its maps aim at the glass (Scene::aim_point_lights, once loaded).
        let target = if kind == LightKind::Point { Vec3::NAN } else { origin + forward };
        out.lights.push(Light { kind, position: origin, target, cone, intensity, color });
    }

    for c in node.children() {
        visit(cx, &c, world, g, visiting, out)?;
    }
    visiting[node.index()] = false;
    Ok(())
}

/// A primitive's triangles, and whether its normals were computed (the file has none).
fn primitive(cx: &Cx, p: &gltf::Primitive, at: &str, buffers: &[Vec<u8>]) -> Result<(Mesh, bool), SceneError> {
    let pos = p
        .get(&gltf::Semantic::Positions)
        .ok_or_else(|| cx.err(format!("{at}.attributes"), "a primitive needs a POSITION attribute"))?;
    let positions = read_vec3(cx, &pos, &format!("{at}.attributes.POSITION"), buffers)?;
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
            let normals = read_vec3(cx, &n, &format!("{at}.attributes.NORMAL"), buffers)?;
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

/// The bytes of each element of a (non-sparse) accessor, bounds-checked.
fn elements<'b>(cx: &Cx, a: &gltf::Accessor, at: &str, buffers: &'b [Vec<u8>]) -> Result<Vec<&'b [u8]>, SceneError> {
    let acc_at = format!("accessors[{}]", a.index());
    let ctx = |m: &str| cx.err(format!("{at} ({acc_at})"), m.to_string());
    if a.sparse().is_some() {
        return Err(ctx("sparse accessors are not supported"));
    }
    let view = a.view().ok_or_else(|| ctx("an accessor without a bufferView is not supported"))?;
    let elem = a.size();
    let stride = view.stride().unwrap_or(elem);
    if stride < elem {
        return Err(ctx("byteStride is smaller than the element"));
    }
    let buf = &buffers[view.buffer().index()];
    let view_bytes = view
        .offset()
        .checked_add(view.length())
        .and_then(|end| buf.get(view.offset()..end))
        .ok_or_else(|| ctx("the bufferView lies outside its buffer"))?;
    let n = a.count();
    if n == 0 {
        return Ok(Vec::new());
    }
    let end = (n - 1).checked_mul(stride).and_then(|x| x.checked_add(elem)).and_then(|x| x.checked_add(a.offset()));
    if !matches!(end, Some(e) if e <= view_bytes.len()) {
        return Err(ctx("the accessor's data lies outside its bufferView"));
    }
    Ok((0..n).map(|i| &view_bytes[a.offset() + i * stride..a.offset() + i * stride + elem]).collect())
}

fn read_vec3(cx: &Cx, a: &gltf::Accessor, at: &str, buffers: &[Vec<u8>]) -> Result<Vec<Vec3>, SceneError> {
    use gltf::accessor::{DataType, Dimensions};
    if a.dimensions() != Dimensions::Vec3 || a.data_type() != DataType::F32 || a.normalized() {
        return Err(cx.err(
            format!("{at} (accessors[{}])", a.index()),
            format!(
                "must be VEC3 of FLOAT (got {:?} of {:?}; quantized meshes are not supported)",
                a.dimensions(),
                a.data_type()
            ),
        ));
    }
    let f = |b: &[u8], k: usize| f32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]]);
    Ok(elements(cx, a, at, buffers)?.into_iter().map(|b| Vec3::new(f(b, 0), f(b, 1), f(b, 2))).collect())
}

/// TEXCOORD data: VEC2 of FLOAT, or of normalized UNSIGNED_BYTE or UNSIGNED_SHORT; finite.
fn read_uvs(cx: &Cx, a: &gltf::Accessor, at: &str, buffers: &[Vec<u8>]) -> Result<Vec<glam::Vec2>, SceneError> {
    use gltf::accessor::{DataType, Dimensions};
    let bad = || {
        cx.err(
            format!("{at} (accessors[{}])", a.index()),
            format!(
                "must be VEC2 of FLOAT, or of normalized unsigned bytes or shorts (got {:?} of {:?})",
                a.dimensions(),
                a.data_type()
            ),
        )
    };
    if a.dimensions() != Dimensions::Vec2 {
        return Err(bad());
    }
    let read: fn(&[u8], usize) -> f32 = match (a.data_type(), a.normalized()) {
        (DataType::F32, false) => |b, k| f32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]]),
        (DataType::U8, true) => |b, k| b[k] as f32 / 255.0,
        (DataType::U16, true) => |b, k| u16::from_le_bytes([b[2 * k], b[2 * k + 1]]) as f32 / 65535.0,
        _ => return Err(bad()),
    };
    let uvs: Vec<glam::Vec2> =
        elements(cx, a, at, buffers)?.into_iter().map(|b| glam::Vec2::new(read(b, 0), read(b, 1))).collect();
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
    Ok(elements(cx, a, at, buffers)?.into_iter().map(read).collect())
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

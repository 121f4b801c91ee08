//! glTF materials and their textures (base color, WebP), as the renderer's materials.

use super::*;

/// The images the materials' base colors have named, each decoded once: (image index → scene texture).
pub(super) struct Textures<'a> {
    pub(super) document: &'a gltf::Document,
    pub(super) list: Vec<std::sync::Arc<Texture>>,
    pub(super) by_image: std::collections::HashMap<usize, usize>,
}

impl<'a> Textures<'a> {
    pub(super) fn new(document: &'a gltf::Document) -> Self {
        Textures { document, list: Vec::new(), by_image: Default::default() }
    }
}

/// The image a texture shows: EXT_texture_webp's `source` where the texture has that extension (the WebP image,
/// preferred to the fallback), else its own `source`.
pub(super) fn texture_image<'a>(
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
pub(super) fn image(
    cx: &Cx,
    img: &gltf::image::Image,
    buffers: &[Vec<u8>],
    path: &Path,
) -> Result<Texture, SceneError> {
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
pub(super) fn base_color_map(
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
pub(super) fn priority(cx: &Cx, m: &gltf::Material, materials: &[Material]) -> Result<u32, SceneError> {
    let i = m.index().unwrap_or(0);
    let Some(extras) = m.extras() else { return Ok(0) };
    let value: serde_json::Value = serde_json::from_str(extras.get()).unwrap_or(serde_json::Value::Null);
    let Some(p) = value.get("priority") else { return Ok(0) };
    let at = format!("materials[{i}].extras.priority");
    let v = p.as_f64().filter(|v| v.fract() == 0.0 && (1.0..=crate::scene::MAX_PRIORITY as f64).contains(v));
    let max = crate::scene::MAX_PRIORITY;
    let v = v.ok_or_else(|| cx.err(at.clone(), format!("must be an integer in 1..={max} (got {p})")))?;
    if !matches!(materials[i], Material::Dielectric { .. }) {
        cx.warn(&at, "only a transmissive (glass) material is a volume with a priority: ignored");
        return Ok(0);
    }
    Ok(v as u32)
}

pub(super) fn material(
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

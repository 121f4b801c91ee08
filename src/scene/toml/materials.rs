//! The TOML scene format's materials: diffuse (with its textures), dielectric and mirror materials, the media on
//! either side of each glass surface, and an OBJ mesh's MTL materials.

use super::*;

/// The textures a scene file's materials have named so far, each file (or checker) loaded once.
#[derive(Default)]
pub(super) struct Textures {
    pub(super) list: Vec<std::sync::Arc<Texture>>,
    by_key: std::collections::HashMap<String, usize>,
}

impl Textures {
    pub(super) fn get_or(
        &mut self,
        key: String,
        make: impl FnOnce() -> Result<Texture, String>,
    ) -> Result<usize, String> {
        if let Some(&i) = self.by_key.get(&key) {
            return Ok(i);
        }
        self.list.push(std::sync::Arc::new(make()?));
        self.by_key.insert(key, self.list.len() - 1);
        Ok(self.list.len() - 1)
    }

    /// The image file at `full` (a scene's `albedo_texture`, an MTL's `map_Kd`), decoded once.
    pub(super) fn file(&mut self, full: &Path) -> Result<usize, String> {
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
pub(super) fn albedo_map(
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

/// A `mesh` whose material is `{ kind = "mtl" }`: one object per MTL material its faces use (named
/// `NAME/MATERIAL` when there are several), each placed as the object says (docs/scenes.md, "OBJ materials").
pub(super) fn mtl_objects(
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
pub(super) fn mtl_material(
    mtl: Option<&mtl::MtlMaterial>,
    textures: &mut Textures,
    mesh: &Mesh,
) -> Result<Material, String> {
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

/// The object's material; `mesh` (for a texture: it needs texture coordinates).
pub(super) fn material(
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

pub(super) fn diffuse(
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
pub(super) fn media(cx: &Ctx, defs: &[S<ObjectDef>], objects: &mut [Object]) -> Result<(), SceneError> {
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

pub(super) fn dielectric(cx: &Ctx, o: &S<ObjectDef>, mf: &dyn Fn(&str) -> String) -> Result<Material, SceneError> {
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

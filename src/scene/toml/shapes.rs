//! The TOML scene format's shapes: each object's mesh from its `shape` and the fields that apply to it, and an OBJ
//! mesh's file with the warnings for its defects.

use super::*;

/// The object's mesh in its own space, as its shape and the shape's fields say (and its water, for a water
/// surface). A field that does not apply to the shape is refused, so that a typo'd scene never silently ignores a
/// value.
pub(super) fn shape(
    cx: &Ctx,
    o: &S<ObjectDef>,
    f: &dyn Fn(&str) -> String,
) -> Result<(Mesh, Option<water::Water>), SceneError> {
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
pub(super) fn shape_fields<'a>(
    cx: &Ctx,
    o: &'a S<ObjectDef>,
    f: &dyn Fn(&str) -> String,
) -> Result<&'a str, SceneError> {
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

pub(super) fn room_mesh(cx: &Ctx, o: &S<ObjectDef>, f: &dyn Fn(&str) -> String) -> Result<Mesh, SceneError> {
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

pub(super) fn lathe_mesh(cx: &Ctx, o: &S<ObjectDef>, f: &dyn Fn(&str) -> String) -> Result<Mesh, SceneError> {
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

pub(super) fn sphere_mesh(cx: &Ctx, o: &S<ObjectDef>, f: &dyn Fn(&str) -> String) -> Result<Mesh, SceneError> {
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
pub(super) fn obj_mesh(cx: &Ctx, o: &S<ObjectDef>, f: &dyn Fn(&str) -> String) -> Result<Mesh, SceneError> {
    let (full, span) = obj_path(cx, o, f)?;
    let (mesh, report) = mesh::load_obj_report(&full).map_err(|e| cx.err(span.clone(), f("path"), e))?;
    let dielectric = o.get_ref().material.get_ref().kind.get_ref() == "dielectric";
    warn_findings(cx, &span, f, &full.display().to_string(), &report, dielectric);
    Ok(mesh)
}

/// A `mesh` object's OBJ file (its `path`, relative to the scene file), which must exist, and the span of `path`.
pub(super) fn obj_path(
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
pub(super) fn warn_findings(
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

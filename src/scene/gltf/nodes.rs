//! The glTF node hierarchy: each node's placement, its meshes as objects (instanced, skinned, morphed), and its
//! primitives.

use super::*;

/// Where a node stands: its world transform at time 0, and, when it or an ancestor animates, the chain of
/// motions from the outermost animated node down to it, under that node's parent's world transform.
#[derive(Clone)]
pub(super) struct Placement {
    pub(super) world: Mat4,
    pub(super) chain: Vec<Motion>,
    pub(super) chain_parent: Mat4,
}

impl Placement {
    pub(super) fn root() -> Placement {
        Placement { world: Mat4::IDENTITY, chain: Vec::new(), chain_parent: Mat4::IDENTITY }
    }

    /// An instance placed by `local` (translation, rotation, scale) in this placement's space.
    pub(super) fn instanced(&self, local: Trs) -> Placement {
        let mut p = self.clone();
        // An animated placement composes the instance after its chain; a still one only multiplies.
        if !p.chain.is_empty() {
            p.chain.push(Motion::rest(local));
        }
        p.world *= Mat4::from_scale_rotation_translation(local.2, local.1, local.0);
        p
    }

    /// Its transform over time (None: it stands still).
    pub(super) fn animation(&self, period: f32) -> Option<Animation> {
        (!self.chain.is_empty()).then(|| Animation {
            chain: self.chain.clone(),
            parent: self.chain_parent,
            repeat: Repeat::Clamp,
            period,
        })
    }
}

/// Every node's world transform at rest (its nodes' `matrix` or TRS, no animation), through its parents: what a
/// skin's joints stand at. A node in a cycle (an error the scene traversal reports) keeps its own transform.
pub(super) fn rest_worlds(document: &gltf::Document) -> Vec<Mat4> {
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
pub(super) fn node_local(node: &gltf::Node) -> ((Vec3, Quat, Vec3), Mat4) {
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
pub(super) fn unit(q: Quat) -> Quat {
    if (q.length_squared() - 1.0).abs() <= 1e-5 {
        q
    } else {
        q.normalize()
    }
}

/// A node's label in messages: `nodes[i] "name"`.
pub(super) fn node_label(node: &gltf::Node) -> String {
    match node.name() {
        Some(n) if !n.is_empty() => format!("nodes[{}] \"{n}\"", node.index()),
        _ => format!("nodes[{}]", node.index()),
    }
}

pub(super) fn visit(
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

    if let Some(cam) = node.camera() {
        node_camera(cx, node, &cam, world, animation.as_ref(), g, out)?;
    }
    if let Some(light) = node.light() {
        node_light(cx, &light, &at, world, animation.as_ref(), g, out)?;
    }

    for c in node.children() {
        visit(cx, &c, &place, g, visiting, out)?;
    }
    visiting[node.index()] = false;
    Ok(())
}

/// The camera on `node` (glTF's `camera`), placed by its world transform and moved by its `animation`.
fn node_camera(
    cx: &Cx,
    node: &gltf::Node,
    cam: &gltf::Camera,
    world: Mat4,
    animation: Option<&Animation>,
    g: &Globals,
    out: &mut Scene,
) -> Result<(), SceneError> {
    let at = format!("nodes[{}]", node.index());
    let origin = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
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
    if let Some(a) = animation {
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
    Ok(())
}

/// The light on a node (KHR_lights_punctual), placed by the node's world transform and moved by its `animation`.
fn node_light(
    cx: &Cx,
    light: &gltf::khr_lights_punctual::Light,
    at: &str,
    world: Mat4,
    animation: Option<&Animation>,
    g: &Globals,
    out: &mut Scene,
) -> Result<(), SceneError> {
    let origin = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
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
            &format!(
                "range {r} m is ignored: the light falls off as 1/d² with no cutoff (a hint the spec allows to ignore)"
            ),
        );
    }
    let (kind, cone) = match light.kind() {
        gltf::khr_lights_punctual::Kind::Point => (LightKind::Point, std::f32::consts::PI),
        gltf::khr_lights_punctual::Kind::Directional => (LightKind::Directional, 0.0),
        gltf::khr_lights_punctual::Kind::Spot { outer_cone_angle, inner_cone_angle } => {
            let deg = outer_cone_angle.to_degrees();
            if !crate::scene::spot_cone_ok(outer_cone_angle) {
                return Err(cx.err(
                    format!("{l_at}.spot.outerConeAngle"),
                    format!(
                        "the cone half-angle must lie in [{}°, π/2) (got {outer_cone_angle})",
                        crate::scene::MIN_CONE_DEG
                    ),
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
    if let Some(a) = animation {
        out.movers.push(Mover { what: Moved::Light(out.lights.len()), animation: a.clone() });
    }
    g.sources.borrow_mut().lights.push(light.index());
    out.lights.push(Light::punctual(kind, origin, target, cone, intensity, color));
    Ok(())
}

/// The objects of the node's mesh, placed by the node, or once per instance (EXT_mesh_gpu_instancing).
pub(super) fn node_mesh(
    cx: &Cx,
    node: &gltf::Node,
    place: &Placement,
    g: &Globals,
    out: &mut Scene,
) -> Result<(), SceneError> {
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
pub(super) type Trs = (Vec3, Quat, Vec3);

/// A node's EXT_mesh_gpu_instancing placements in its own space (translation, rotation, scale), each attribute's
/// absent components the identity's; None without the extension. TRANSLATION and SCALE are VEC3 of FLOAT (or, as
/// KHR_mesh_quantization allows, of bytes or shorts), ROTATION a unit VEC4 of FLOAT or normalized bytes or shorts;
/// all of one count.
pub(super) fn instances(cx: &Cx, node: &gltf::Node, g: &Globals) -> Result<Option<Vec<Trs>>, SceneError> {
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
pub(super) fn skin_placement(
    cx: &Cx,
    node: &gltf::Node,
    g: &Globals,
    base_name: &str,
) -> Result<Option<Placement>, SceneError> {
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
pub(super) fn mesh_objects(
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
    let (n_targets, weights) = morph_weights(cx, node, mesh)?;
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
        primitive_uvs(cx, &p, &p_at, g, &mut m)?;
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
        let report = crate::scene::mesh::sanitize(&mut m, computed_normals);
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
            let anim = std::sync::Arc::new(crate::scene::ObjectAnimation {
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

/// The morph targets every primitive of `mesh` has (the same number, or an error naming the first that differs),
/// and the weights: the node's, else the mesh's, else zero, one finite weight per target.
fn morph_weights(cx: &Cx, node: &gltf::Node, mesh: &gltf::Mesh) -> Result<(usize, Vec<f32>), SceneError> {
    let at = format!("nodes[{}]", node.index());
    let mesh_at = format!("meshes[{}]", mesh.index());
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
    Ok((n_targets, weights))
}

/// A textured material's texture coordinates: the primitive's TEXCOORD set the material reads, one uv per position,
/// into `m` (the texture coordinates are not transformed with the node).
fn primitive_uvs(cx: &Cx, p: &gltf::Primitive, p_at: &str, g: &Globals, m: &mut Mesh) -> Result<(), SceneError> {
    if let Some(set) = p.material().index().and_then(|i| g.tex_coords[i]) {
        let a = p.get(&gltf::Semantic::TexCoords(set)).ok_or_else(|| {
            cx.err(
                format!("{p_at}.attributes"),
                format!("its material's base color texture reads TEXCOORD_{set}, which the primitive lacks"),
            )
        })?;
        let uvs = read_uvs(cx, &a, &format!("{p_at}.attributes.TEXCOORD_{set}"), g.buffers)?;
        if uvs.len() != m.positions.len() {
            return Err(cx.err(format!("{p_at}.attributes.TEXCOORD_{set}"), "needs one uv per position"));
        }
        m.uvs = uvs;
    }
    Ok(())
}

/// A primitive's morph targets: POSITION (and NORMAL) displacements, one per vertex. Tangent displacements are
/// ignored (the renderer has no tangents).
pub(super) fn morph_targets(
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
pub(super) fn primitive(
    cx: &Cx,
    p: &gltf::Primitive,
    at: &str,
    buffers: &[Vec<u8>],
) -> Result<(Mesh, bool), SceneError> {
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

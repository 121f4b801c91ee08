//! The views of a frame: each light's photon view (fitted to the refractors) and receiver view (over the
//! receivers: caustic map, receiver g-buffer and shadow map), and the eye camera.

use crate::error::{Error, Result};
use crate::scene::mesh::box_corners;
use crate::scene::view::{CameraView, LightView, Window, CUBE_FACES};
use crate::scene::{LightKind, Scene};
use crate::settings::ResolvedSettings;
use glam::Vec3;

/// One light view of a scene light, with its own photons and maps: the whole light (a spot, a directional light,
/// or a point light whose objects all lie in front of the plane through it facing its target), or one face of a
/// point light's cube (docs/design.md "Lights that shine every way").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Emitter {
    /// The light's index in the scene.
    pub light: usize,
    /// Its cube face (0..CUBE_FACES, [`LightView::cube_face`]), or None for the whole light.
    pub face: Option<u8>,
}

/// The image-plane points and depths of `objects` inside cube face `face`: their meshes, and a water block's
/// envelope (its displaced surface is not on the host: the GPU displaces it).
fn face_points<'s>(
    scene: &'s Scene,
    face: &LightView,
    objects: impl Iterator<Item = &'s crate::scene::Object>,
) -> Vec<(glam::Vec2, f32)> {
    const BOX: [u32; 36] =
        [0, 1, 3, 0, 3, 2, 4, 6, 7, 4, 7, 5, 0, 4, 5, 0, 5, 1, 2, 3, 7, 2, 7, 6, 0, 2, 6, 0, 6, 4, 1, 5, 7, 1, 7, 3];
    let mut out = Vec::new();
    for o in objects {
        face.face_points(&o.mesh.positions, &o.mesh.indices, &mut out);
        let a = o.animation.as_ref().filter(|a| a.water.is_some());
        if let Some((b, m)) = a.and_then(|a| Some((a.deform_bounds()?, a.transform_at(scene.time)))) {
            face.face_points(&box_corners(b).map(|c| m.transform_point3(c)), &BOX, &mut out);
        }
    }
    out
}

/// Whether some vertex of `o` lies on or behind the plane through `light` facing its target.
fn behind(light: &crate::scene::Light, o: &crate::scene::Object) -> bool {
    let axis = (light.target - light.position).normalize();
    o.mesh.positions.iter().any(|p| (*p - light.position).dot(axis) <= 1e-4)
}

/// Whether `p` lies inside the closed mesh of `o` (a ray's crossings are odd).
fn inside(o: &crate::scene::Object, p: Vec3) -> bool {
    let (lo, hi) = o.mesh.bounds();
    if p.cmplt(lo).any() || p.cmpgt(hi).any() {
        return false;
    }
    let d = Vec3::new(0.5773, 0.5774, 0.5773).normalize();
    let m = &o.mesh;
    let crossings = m.indices.chunks_exact(3).filter(|t| {
        let [a, b, c] = [0, 1, 2].map(|k| m.positions[t[k] as usize]);
        let (e1, e2) = (b - a, c - a);
        let q = d.cross(e2);
        let det = e1.dot(q);
        if det.abs() < 1e-12 {
            return false;
        }
        let s = p - a;
        let u = s.dot(q) / det;
        let r = s.cross(e1);
        let v = d.dot(r) / det;
        u >= 0.0 && v >= 0.0 && u + v <= 1.0 && e2.dot(r) / det > 0.0
    });
    crossings.count() % 2 == 1
}

/// The light views of the scene's lights, in order: one per light, or one per cube face that holds some object
/// for a point light with objects on every side. A point light inside glass is refused (its photons would
/// start in a medium).
pub fn emitters(scene: &Scene) -> Result<Vec<Emitter>> {
    let mut out = Vec::new();
    for (index, light) in scene.lights.iter().enumerate() {
        // Only a light with size scans the meshes (this runs every frame).
        let r2 = light.radius * light.radius;
        let reached =
            |o: &&crate::scene::Object| o.mesh.positions.iter().any(|p| p.distance_squared(light.position) < r2);
        if let Some(o) = scene.objects.iter().filter(|_| light.radius > 0.0).find(reached) {
            return Err(Error::BadInput(format!(
                "{}: light {index}'s sphere (radius {} m) reaches into `{}`; a light with size must stand clear of every object",
                scene.path.display(),
                light.radius,
                o.name
            )));
        }
        if light.kind != LightKind::Point || !scene.objects.iter().any(|o| behind(light, o)) {
            out.push(Emitter { light: index, face: None });
            continue;
        }
        if let Some(o) = scene.refractors().find(|o| inside(o, light.position)) {
            return Err(Error::BadInput(format!(
                "{}: point light {index} lies inside `{}`; a light must be outside glass and liquids (its photons start in air)",
                scene.path.display(),
                o.name
            )));
        }
        for k in 0..CUBE_FACES {
            let face = LightView::cube_face(light, k);
            if !face_points(scene, &face, scene.objects.iter()).is_empty() {
                out.push(Emitter { light: index, face: Some(k as u8) });
            }
        }
    }
    Ok(out)
}

/// The lights that light no receiver: a spot light whose cone no receiver reaches, or any light of a scene
/// without receivers. They light only glass, whose light may still land somewhere; the renderer warns of them.
pub fn lights_without_receivers(scene: &Scene) -> Vec<usize> {
    let reaches = |light: &crate::scene::Light, o: &crate::scene::Object| match light.kind {
        LightKind::Spot => LightView::spot_reaches(light, &o.mesh.positions, &o.mesh.indices),
        _ => true,
    };
    (0..scene.lights.len()).filter(|&i| !scene.receivers().any(|o| reaches(&scene.lights[i], o))).collect()
}

/// The light views of a frame and the eye camera.
#[derive(Clone, Copy, Debug)]
pub struct Views {
    /// Fitted to the refractors; None when there is nothing to refract (no dielectric, or none in the cone).
    pub photon: Option<LightView>,
    /// Over the receivers: caustic map, receiver g-buffer and shadow map.
    pub receiver: LightView,
    /// The eye camera.
    pub camera: CameraView,
}

impl Views {
    /// The views of emitter `e` ([`emitters`]).
    pub fn new(scene: &Scene, settings: &ResolvedSettings, camera: &CameraView, e: Emitter) -> Result<Views> {
        let (index, light) = (e.light, &scene.lights[e.light]);
        if let Some(k) = e.face {
            let face = LightView::cube_face(light, k as usize);
            // The refractors and the receivers partition the objects: each is clipped once.
            let refr = face_points(scene, &face, scene.refractors());
            let mut all = face_points(scene, &face, scene.receivers());
            all.extend_from_slice(&refr);
            let photon =
                (!refr.is_empty()).then(|| face.fit_face(&refr, &refr, settings.gbuffer_side(), 1.0)).flatten();
            let receiver = face.fit_face(&[], &all, settings.caustic_res, 1.0).unwrap_or(face);
            return Ok(Views { photon, receiver, camera: *camera });
        }
        // Water's displaced surface is not on the host (the GPU displaces it): its block's bounds stand in.
        let envelope = |o: &crate::scene::Object| {
            let a = o.animation.as_ref().filter(|a| a.water.is_some());
            let corners = a.and_then(|a| Some((a.deform_bounds()?, a.transform_at(scene.time))));
            corners.into_iter().flat_map(|(b, m)| box_corners(b).map(|c| m.transform_point3(c)))
        };
        let all = || scene.objects.iter().flat_map(|o| o.mesh.positions.iter().copied().chain(envelope(o)));
        let refr = || scene.refractors().flat_map(|o| o.mesh.positions.iter().copied().chain(envelope(o)));
        let recv = || scene.receivers().flat_map(|o| o.mesh.positions.iter().copied());
        if light.kind == LightKind::Spot {
            if let Some(o) = scene.refractors().find(|o| behind(light, o)) {
                return Err(Error::BadInput(format!(
                    "{}: object `{}` reaches behind the spot light's plane; a spot light must see every refractor in front of it",
                    scene.path.display(),
                    o.name
                )));
            }
        }
        if light.kind == LightKind::Point {
            if let Some(o) = scene.objects.iter().find(|o| behind(light, o)) {
                return Err(Error::BadInput(format!(
                    "{}: object `{}` reaches behind the plane through point light {index} facing its target; as one frustum, its maps need every object in front of that plane (`emitters` gives such a light a view per cube face)",
                    scene.path.display(),
                    o.name
                )));
            }
        }
        let photon = if scene.has_refractors() {
            LightView::fit(light, refr(), refr(), settings.gbuffer_side(), 1.0)
        } else {
            None
        };
        let receiver = LightView::fit(light, recv(), all(), settings.caustic_res, 1.0)
            .or_else(|| LightView::fit(light, all(), all(), settings.caustic_res, 1.0))
            .unwrap_or_else(|| {
                let mut v = LightView::fit(light, std::iter::once(light.target), all(), settings.caustic_res, 1.0)
                    .expect("the light's target lies on its axis");
                v.window = Window { x0: -1.0, y0: -1.0, w: 2.0 };
                v
            });
        Ok(Views { photon, receiver, camera: *camera })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    const SCENE: &str = r#"
[[light]]
kind = "spot"
position = [0.0, 1.6, 0.0]
target = [0.0, 0.5, 0.0]
cone_deg = 8.0
intensity = 1.0

[[object]]
name = "floor"
shape = "plane"
size = [2.0, 2.0]
material = { kind = "diffuse", albedo = 0.8 }

[[object]]
name = "glass"
shape = "sphere"
radius = 0.3
translate = [0.0, 0.5, 0.0]
material = { kind = "dielectric", ior = 1.5 }
"#;

    /// A narrow spot whose cone meets the floor only inside its two triangles (no vertex in the cone) reaches it;
    /// aimed up past the glass, it reaches no receiver.
    #[test]
    fn a_light_that_reaches_no_receiver_is_found() {
        let scene = Scene::parse(SCENE, Path::new("spot.toml")).unwrap();
        assert!(lights_without_receivers(&scene).is_empty());
        let up = SCENE.replace("position = [0.0, 1.6, 0.0]", "position = [0.0, 0.1, 0.0]");
        let up = up.replace("target = [0.0, 0.5, 0.0]", "target = [0.0, 1.0, 0.0]");
        let up = up.replace("translate = [0.0, 0.5, 0.0]", "translate = [0.0, 1.0, 0.0]");
        let scene = Scene::parse(&up, Path::new("up.toml")).unwrap();
        assert_eq!(lights_without_receivers(&scene), [0]);
    }

    /// A light's sphere that reaches into an object is refused, naming both.
    #[test]
    fn a_bulb_stands_clear_of_the_objects() {
        let clear = SCENE.replace("intensity = 1.0", "intensity = 1.0\nradius = 0.5");
        assert!(emitters(&Scene::parse(&clear, Path::new("clear.toml")).unwrap()).is_ok());
        let big = SCENE.replace("intensity = 1.0", "intensity = 1.0\nradius = 1.0");
        let e = emitters(&Scene::parse(&big, Path::new("big.toml")).unwrap()).unwrap_err().to_string();
        assert!(e.contains("light 0's sphere (radius 1 m) reaches into `glass`"), "{e}");
    }

    /// A point light with the floor behind it gets the faces that hold something; one inside the glass is refused.
    #[test]
    fn point_light_faces() {
        let point = SCENE.replace("kind = \"spot\"", "kind = \"point\"").replace("cone_deg = 8.0\n", "");
        let scene = Scene::parse(&point, Path::new("point.toml")).unwrap();
        assert_eq!(emitters(&scene).unwrap(), [Emitter { light: 0, face: None }]);
        let low = point.replace("position = [0.0, 1.6, 0.0]", "position = [0.0, 0.2, 0.9]");
        let scene = Scene::parse(&low, Path::new("low.toml")).unwrap();
        let faces: Vec<_> = emitters(&scene).unwrap().iter().map(|e| e.face).collect();
        // Every face but the one looking up (face 5, −down: the light's down axis points at the floor).
        assert_eq!(faces, [Some(0), Some(1), Some(2), Some(3), Some(4)]);
        let inside = point.replace("position = [0.0, 1.6, 0.0]", "position = [0.1, 0.5, 0.0]");
        let scene = Scene::parse(&inside, Path::new("inside.toml")).unwrap();
        let e = emitters(&scene).unwrap_err().to_string();
        assert!(e.contains("lies inside `glass`"), "{e}");
    }
}

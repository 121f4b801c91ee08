//! The views of a frame: each light's photon view (fitted to the refractors) and receiver view (over the
//! receivers: caustic map, receiver g-buffer and shadow map), and the eye camera.

use crate::error::{Error, Result};
use crate::scene::mesh::box_corners;
use crate::scene::view::{CameraView, LightView, Window};
use crate::scene::{LightKind, Scene};
use crate::settings::ResolvedSettings;

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
    /// The views of light `index`.
    pub fn new(scene: &Scene, settings: &ResolvedSettings, camera: &CameraView, index: usize) -> Result<Views> {
        let light = &scene.lights[index];
        // Water's displaced surface is not on the host (the GPU displaces it): its block's bounds stand in.
        let envelope = |o: &crate::scene::Object| {
            let a = o.animation.as_ref().filter(|a| a.water.is_some());
            let corners = a.and_then(|a| Some((a.deform_bounds()?, a.transform_at(scene.time))));
            corners.into_iter().flat_map(|(b, m)| box_corners(b).map(|c| m.transform_point3(c)))
        };
        let all = || scene.objects.iter().flat_map(|o| o.mesh.positions.iter().copied().chain(envelope(o)));
        let refr = || scene.refractors().flat_map(|o| o.mesh.positions.iter().copied().chain(envelope(o)));
        let recv = || scene.receivers().flat_map(|o| o.mesh.positions.iter().copied());
        let behind = |o: &&crate::scene::Object| {
            o.mesh
                .positions
                .iter()
                .any(|p| (*p - light.position).dot((light.target - light.position).normalize()) <= 1e-4)
        };
        if light.kind == LightKind::Spot {
            if let Some(o) = scene.refractors().find(behind) {
                return Err(Error::BadInput(format!(
                    "{}: object `{}` reaches behind the spot light's plane; a spot light must see every refractor in front of it",
                    scene.path.display(),
                    o.name
                )));
            }
        }
        if light.kind == LightKind::Point {
            if let Some(o) = scene.objects.iter().find(behind) {
                return Err(Error::BadInput(format!(
                    "{}: object `{}` reaches behind the plane through point light {index} facing its target; its shadow and caustic maps are one frustum, so every object must lie in front of that plane (move the light or its `target`)",
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

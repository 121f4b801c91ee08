//! Scenes: the TOML format of docs/design.md, validated into world-space meshes, lights and cameras.
//!
//! Errors name the file, the line and the field (`sphere.toml:23: object[1] "glass".material.ior: ...`), and are
//! reported by the CLI with exit code 2.

pub mod animation;
pub mod environment;
mod gltf;
pub mod mesh;
pub mod morph;
pub mod mtl;
mod schema;
pub mod texture;
mod toml;
pub mod view;
pub mod water;

use glam::{Mat4, Quat, Vec3};
use std::path::{Path, PathBuf};

pub use environment::{Environment, EnvironmentMap};
pub use mesh::Mesh;
pub use texture::{AlbedoMap, Texture};
pub use view::{CameraView, LightView, Window};

#[derive(Debug, thiserror::Error)]
/// A scene that cannot be read: the message names the file, and the line and field where there is one.
pub enum SceneError {
    /// The file cannot be read (or is not a scene file).
    #[error("{file}: {message}")]
    Io {
        /// The file.
        file: String,
        /// What went wrong.
        message: String,
    },
    /// The TOML does not parse.
    #[error("{file}:{line}:{column}: {message}")]
    Syntax {
        /// The file.
        file: String,
        /// The line (from 1).
        line: usize,
        /// The column (from 1).
        column: usize,
        /// The parser's message.
        message: String,
    },
    /// A field has a bad value.
    #[error("{file}:{line}: {field}: {message}")]
    Field {
        /// The file.
        file: String,
        /// The line (from 1).
        line: usize,
        /// The field's path (`object[1] "glass".material.ior`).
        field: String,
        /// What is wrong with it.
        message: String,
    },
    /// A glTF file: `path` is the JSON path (`meshes[0].primitives[1].mode`).
    #[error("{file}: {path}: {message}")]
    Gltf {
        /// The file.
        file: String,
        /// The JSON path of what is wrong.
        path: String,
        /// What is wrong with it.
        message: String,
    },
}

/// The most lights a scene may have: each gets its own light view, photons, caustic map and shadow map.
pub const MAX_LIGHTS: usize = 4;

/// The narrowest spot light, degrees of half-angle: narrower cones have no frustum in f32 (the cosine of a cone
/// under 0.02° rounds to 1), and a spot's light view is fitted to its cone.
pub const MIN_CONE_DEG: f32 = 0.1;

/// Whether a spot light's cone half-angle (radians) lies in [MIN_CONE_DEG, 90°).
pub fn spot_cone_ok(cone: f32) -> bool {
    (MIN_CONE_DEG.to_radians()..std::f32::consts::FRAC_PI_2).contains(&cone)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
/// What kind of light.
pub enum LightKind {
    /// A cone of uniform intensity (W/sr) of half-angle `cone`.
    Spot,
    /// Parallel light of irradiance `intensity` (W/m², across the beam) along `target - position`.
    Directional,
    /// Isotropic: the same intensity in every direction. Its maps are one frustum from the light toward its
    /// target, so its receivers and glass must lie in front of the plane through it facing the target.
    Point,
}

#[derive(Clone, Debug, PartialEq)]
/// A light of the scene.
pub struct Light {
    /// Spot, directional or point.
    pub kind: LightKind,
    /// Where it is (a directional light: where its beam starts).
    pub position: Vec3,
    /// What it points at (its axis runs from `position` to `target`).
    pub target: Vec3,
    /// Cone half-angle in radians (spot lights).
    pub cone: f32,
    /// W/sr for spot lights, W/m² (perpendicular to the beam) for directional lights.
    pub intensity: f32,
    /// RGB color multiplying its power per channel.
    pub color: Vec3,
    /// A directional light's angular radius, radians: its radiance is uniform over a disk of directions this wide
    /// around its axis (a sun; 0: parallel rays). `intensity` stays the irradiance across the beam.
    pub angular_radius: f32,
    /// A point or spot light's radius, m: a sphere of uniform radiance around `position`, whose intensity (W/sr)
    /// is `intensity` every way it shines (0: a point).
    pub radius: f32,
}

impl Light {
    /// A light without size (KHR_lights_punctual's): a point, or parallel rays.
    pub fn punctual(kind: LightKind, position: Vec3, target: Vec3, cone: f32, intensity: f32, color: Vec3) -> Light {
        Light { kind, position, target, cone, intensity, color, angular_radius: 0.0, radius: 0.0 }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
/// A camera's projection.
pub enum Projection {
    /// Parallel rays over a window `half_height` tall (m); the width follows the image's aspect ratio.
    Orthographic {
        /// Half the window's height, m.
        half_height: f32,
    },
    /// Vertical field of view in radians.
    Perspective {
        /// The vertical field of view, radians.
        fov: f32,
    },
}

#[derive(Clone, Debug, PartialEq)]
/// A camera of the scene.
pub struct Camera {
    /// Its name (`--camera` picks it).
    pub name: String,
    /// Orthographic or perspective.
    pub projection: Projection,
    /// Where it is.
    pub position: Vec3,
    /// What it looks at.
    pub target: Vec3,
    /// Which way is up in its image.
    pub up: Vec3,
    /// The image's width over its height as the file authored it (glTF `aspectRatio`, or `xmag / ymag`); the
    /// default output size follows it. None: any (TOML cameras).
    pub aspect: Option<f32>,
}

impl Camera {
    /// The area one pixel covers (m²) in an image `width`×`height` through an orthographic camera (the window's
    /// width follows the image's aspect): what turns an irradiance AOV's sum into flux. None for a perspective
    /// camera.
    pub fn pixel_area(&self, width: u32, height: u32) -> Option<f64> {
        match self.projection {
            Projection::Orthographic { half_height } => {
                let hh = half_height as f64;
                let hw = hh * width as f64 / height as f64;
                Some((2.0 * hw / width as f64) * (2.0 * hh / height as f64))
            }
            Projection::Perspective { .. } => None,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
/// What an object is made of.
pub enum Material {
    /// A diffuse receiver: it collects caustics and direct light.
    Diffuse {
        /// Its RGB reflectance (with a texture: the factor its texels are multiplied by).
        albedo: Vec3,
        /// Its albedo texture, if any: albedo(uv) = albedo × texture(uv).
        map: Option<AlbedoMap>,
    },
    /// Glass (or any dielectric): light refracts and reflects by Fresnel, and is absorbed inside.
    Dielectric {
        /// Index of refraction at the green channel's wavelength (587.6 nm, the Fraunhofer d line).
        ior: f32,
        /// Beer–Lambert absorption coefficients inside the glass, 1/m, per color channel (R, G, B).
        absorption: Vec3,
        /// Abbe number V_d (dispersion: a smaller number spreads the colors more); 0 for none.
        abbe: f32,
    },
    /// A perfect specular reflector (reflects all light; exact transport only).
    Mirror,
}

#[derive(Clone, Debug)]
/// An object of the scene: a mesh in world space and its material.
pub struct Object {
    /// Its name (messages name it).
    pub name: String,
    /// Its material.
    pub material: Material,
    /// Its triangles, in world space (at the scene's `time` when it animates).
    pub mesh: Mesh,
    /// Where it moves or how it deforms over time (None: it stands still).
    pub animation: Option<std::sync::Arc<ObjectAnimation>>,
    /// A dielectric's surface is an interface between two media (docs/design.md "Media"): its own inside, and
    /// outside it air (None) or the inside of the dielectric object at this index (`outside` in a scene file).
    pub outside: Option<usize>,
    /// 0: its surface is an explicit interface (above). 1 to [`MAX_PRIORITY`]: it is a volume of its medium that
    /// may overlap other such volumes, and where they overlap the higher priority's medium is the one there
    /// (Schmidt and Budge 2002; docs/design.md "Media").
    pub priority: u32,
}

/// The highest medium priority (`priority` in a scene file).
pub const MAX_PRIORITY: u32 = 255;

/// An object placed from its own space: its mesh there, its placement (keyframed, or fixed), and how it deforms
/// (water's waves, morph targets). A TOML object has one when it moves or is water; a glTF object always has one
/// (its node's world transform), so that its triangles are instanced in the node's space.
#[derive(Debug)]
pub struct ObjectAnimation {
    /// The mesh, in object space (water: at rest).
    pub mesh: Mesh,
    /// Object → world as a function of time (None: `placement`).
    pub animation: Option<animation::Animation>,
    /// Object → world when it has no keyframes.
    pub placement: Mat4,
    /// Its waves, when it is water.
    pub water: Option<water::Water>,
    /// Its morph targets and their weights over time (glTF), when their weights animate.
    pub morph: Option<morph::Morph>,
}

impl ObjectAnimation {
    /// Object → world at time `t`.
    pub fn transform_at(&self, t: f32) -> Mat4 {
        self.animation.as_ref().map_or(self.placement, |a| a.transform_at(t))
    }

    /// Its triangles in world space at time `t`.
    pub fn mesh_at(&self, t: f32) -> Mesh {
        self.local_mesh_at(t).transformed(self.transform_at(t))
    }

    /// Its triangles in object space at time `t`: the water displaced by its waves (a simulated surface is the
    /// scene's: [`Scene::set_time`] adds it), the morph targets weighted.
    pub fn local_mesh_at(&self, t: f32) -> Mesh {
        match (&self.water, &self.morph) {
            (Some(w), _) => w.displaced(&self.mesh, t, None),
            (None, Some(m)) => m.apply(&self.mesh, &m.weights_at(t)),
            (None, None) => self.mesh.clone(),
        }
    }

    /// Whether it changes with time: it moves, or it deforms.
    pub fn changes(&self) -> bool {
        self.animation.is_some() || self.deforms()
    }

    /// Whether its shape changes with time (water, animated morph weights): the renderer deforms it on the GPU and
    /// refits its BVH.
    pub fn deforms(&self) -> bool {
        self.water.is_some() || self.morph.as_ref().is_some_and(|m| m.is_animated())
    }

    /// The object-space box its deforming mesh stays in (None: it does not deform).
    pub fn deform_bounds(&self) -> Option<(Vec3, Vec3)> {
        match (&self.water, &self.morph) {
            (Some(w), _) => Some(w.bounds()),
            (None, Some(m)) if m.is_animated() => Some(m.bounds(&self.mesh)),
            _ => None,
        }
    }

    /// Its animation's duration (0 without keyframes).
    pub fn duration(&self) -> f32 {
        let morph = self.morph.as_ref().map_or(0.0, |m| m.duration());
        self.animation.as_ref().map_or(0.0, |a| a.duration()).max(morph)
    }
}

impl Object {
    /// A still object.
    pub fn new(name: impl Into<String>, material: Material, mesh: Mesh) -> Object {
        Object { name: name.into(), material, mesh, animation: None, outside: None, priority: 0 }
    }
}

/// Wavelengths (nm) that the red, green and blue channels trace when a scene needs color: the Fraunhofer C, d and
/// F lines, the three that define the Abbe number.
pub const CHANNEL_NM: [f32; 3] = [656.3, 587.6, 486.1];

impl Material {
    /// An untextured diffuse receiver of albedo `albedo`.
    pub fn diffuse(albedo: Vec3) -> Material {
        Material::Diffuse { albedo, map: None }
    }

    /// Index of refraction per color channel: n at the C, d and F lines from n_d and the Abbe number
    /// V_d = (n_d − 1) / (n_F − n_C), with Cauchy's n(λ) = A + B/λ² through n_d. Without dispersion, n_d thrice.
    pub fn ior_rgb(&self) -> [f32; 3] {
        match *self {
            Material::Dielectric { ior, abbe, .. } if abbe > 0.0 => {
                let inv2 = |nm: f32| 1.0 / (nm * nm);
                let b = (ior - 1.0) / (abbe * (inv2(CHANNEL_NM[2]) - inv2(CHANNEL_NM[0])));
                let a = ior - b * inv2(CHANNEL_NM[1]);
                CHANNEL_NM.map(|nm| a + b * inv2(nm))
            }
            Material::Dielectric { ior, .. } => [ior; 3],
            _ => [0.0; 3],
        }
    }

    /// Whether light through this material depends on the color channel (dispersion or colored absorption).
    pub fn needs_color(&self) -> bool {
        match *self {
            Material::Dielectric { absorption, abbe, .. } => {
                abbe > 0.0 || absorption.max_element() != absorption.min_element()
            }
            _ => false,
        }
    }
}

impl Object {
    /// A specular object: a dielectric or a mirror. Specular objects make caustics: the light-view frustum is
    /// fitted to them and their cells are the photons; everything else is a diffuse receiver.
    pub fn is_refractor(&self) -> bool {
        matches!(self.material, Material::Dielectric { .. } | Material::Mirror)
    }

    /// A perfect mirror.
    pub fn is_mirror(&self) -> bool {
        matches!(self.material, Material::Mirror)
    }

    /// Its Beer–Lambert absorption coefficients (1/m, R, G, B): a dielectric's, else none.
    pub fn absorption(&self) -> Vec3 {
        match self.material {
            Material::Dielectric { absorption, .. } => absorption,
            _ => Vec3::ZERO,
        }
    }
}

#[derive(Clone, Debug)]
/// A scene: lights, cameras and objects, in world space (SI units: meters, W/sr, W/m²).
pub struct Scene {
    /// The file it came from (`<code>` for a scene built in code); messages name it.
    pub path: PathBuf,
    /// 1 to [`MAX_LIGHTS`] lights.
    pub lights: Vec<Light>,
    /// Its cameras (`render` and `reference` need one).
    pub cameras: Vec<Camera>,
    /// Its objects.
    pub objects: Vec<Object>,
    /// The time (s) its animated objects stand at (0 as loaded).
    pub time: f32,
    /// The albedo textures its materials name ([`AlbedoMap::texture`] indexes them).
    pub textures: Vec<std::sync::Arc<Texture>>,
    /// Its environment map (None: the procedural sky).
    pub environment: Option<Environment>,
    /// The cameras and lights that animations move (glTF), placed at `time`.
    pub movers: Vec<Mover>,
    /// The file's animations by name (glTF; `animations[i]` for one without a name), and which of them play.
    pub animations: Vec<String>,
    /// The animation that plays (None: all of them, together).
    pub playing: Option<usize>,
    /// The light and camera properties that animations set (glTF's KHR_animation_pointer), set at `time`.
    pub properties: Vec<PropertyTrack>,
}

/// A light's or camera's property over time (glTF's KHR_animation_pointer), in the renderer's units.
#[derive(Clone, Debug, PartialEq)]
pub enum PropertyTrack {
    /// `lights[i].intensity`: W/sr (spot, point) or W/m² (directional).
    LightIntensity(usize, animation::Track<f32>),
    /// `lights[i].color`.
    LightColor(usize, animation::Track<Vec3>),
    /// `lights[i].cone`: a spot's half-angle, radians.
    LightCone(usize, animation::Track<f32>),
    /// `cameras[i]`'s vertical field of view (perspective), radians.
    CameraFov(usize, animation::Track<f32>),
    /// `cameras[i]`'s half height (orthographic), meters.
    CameraHalfHeight(usize, animation::Track<f32>),
    /// `objects[i]`'s IOR (a dielectric).
    ObjectIor(usize, animation::Track<f32>),
}

impl PropertyTrack {
    /// Its last keyframe's time (s).
    pub fn end(&self) -> f32 {
        match self {
            PropertyTrack::LightColor(_, t) => t.end(),
            PropertyTrack::LightIntensity(_, t)
            | PropertyTrack::LightCone(_, t)
            | PropertyTrack::CameraFov(_, t)
            | PropertyTrack::CameraHalfHeight(_, t)
            | PropertyTrack::ObjectIor(_, t) => t.end(),
        }
    }
}

/// What a [`Mover`] moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Moved {
    /// `Scene::cameras[i]`.
    Camera(usize),
    /// `Scene::lights[i]`.
    Light(usize),
}

/// A camera or light whose node an animation moves: it stands at the node's origin, looks (shines) down the
/// node's -Z, and a camera's up is the node's +Y.
#[derive(Clone, Debug)]
pub struct Mover {
    /// The camera or light.
    pub what: Moved,
    /// Its node's transform over time.
    pub animation: animation::Animation,
}

/// Which of a file's animations play (`--animation`).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum AnimationChoice {
    /// Every one, together (Blender writes one animation per animated object).
    #[default]
    All,
    /// The one at this index of the file's `animations`.
    Index(usize),
    /// The one of this name.
    Name(String),
}

impl std::str::FromStr for AnimationChoice {
    type Err = std::convert::Infallible;
    /// `all`, an index, or a name.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(match s {
            "all" => AnimationChoice::All,
            _ => match s.parse::<usize>() {
                Ok(i) => AnimationChoice::Index(i),
                Err(_) => AnimationChoice::Name(s.to_string()),
            },
        })
    }
}

/// How to load a scene file.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// glTF: which animations play.
    pub animation: AnimationChoice,
}

const FINITE: &str = "must be finite (within ±1e9)";

impl Scene {
    /// A scene built in code: its lights and cameras, and no objects yet (a renderer adds them as instances of
    /// meshes: [`crate::Renderer::add_mesh`], [`crate::Renderer::add_instance`]). Messages name it `<code>`.
    pub fn new(lights: Vec<Light>, cameras: Vec<Camera>) -> Scene {
        Scene {
            path: PathBuf::from("<code>"),
            lights,
            cameras,
            objects: Vec::new(),
            time: 0.0,
            textures: Vec::new(),
            environment: None,
            movers: Vec::new(),
            animations: Vec::new(),
            playing: None,
            properties: Vec::new(),
        }
    }

    /// Whether any object animates.
    pub fn is_animated(&self) -> bool {
        self.objects.iter().any(|o| o.animation.as_ref().is_some_and(|a| a.changes()))
            || !self.movers.is_empty()
            || !self.properties.is_empty()
    }

    /// The longest animation's duration (s; 0 for a still scene).
    pub fn duration(&self) -> f32 {
        let objects = self.objects.iter().filter_map(|o| o.animation.as_ref()).map(|a| a.duration());
        let properties = self.properties.iter().map(PropertyTrack::end);
        objects.chain(self.movers.iter().map(|m| m.animation.duration())).chain(properties).fold(0.0, f32::max)
    }

    /// Place every animated object, camera and light where it stands at time `t` (s), a simulated water surface
    /// stepped from rest to `t` with its drops and the objects moving through it.
    pub fn set_time(&mut self, t: f32) {
        for i in 0..self.objects.len() {
            let Some(a) = self.objects[i].animation.clone().filter(|a| a.changes()) else { continue };
            self.objects[i].mesh = match &a.water {
                Some(w) if w.simulation.is_some() => {
                    let spheres = self.body_spheres();
                    let field = w.simulate(t, &|t0, t1| self.water_bodies(i, t0, t1, &spheres));
                    w.displaced(&a.mesh, t, field.as_ref()).transformed(a.transform_at(t))
                }
                _ => a.mesh_at(t),
            };
        }
        self.time = t;
        self.place_movers();
    }

    /// Each object's sphere in its own space when it moves on keyframes and is not water (it may disturb water).
    pub fn body_spheres(&self) -> Vec<Option<(Vec3, f32)>> {
        let moves = |o: &Object| o.animation.as_ref().filter(|a| a.water.is_none() && a.animation.is_some()).cloned();
        self.objects.iter().map(|o| moves(o).map(|a| water::bounding_sphere(&a.mesh))).collect()
    }

    /// The bodies that disturb water object `w` in a step from `t0` to `t1` s: the other objects that move on
    /// keyframes, each as its bounding sphere (`spheres`, from [`Scene::body_spheres`]; [`water::bodies_in`]).
    pub fn water_bodies(&self, w: usize, t0: f32, t1: f32, spheres: &[Option<(Vec3, f32)>]) -> Vec<water::Body> {
        let Some(wa) = self.objects[w].animation.as_ref() else { return Vec::new() };
        let Some(water) = &wa.water else { return Vec::new() };
        let moving = self.objects.iter().zip(spheres).filter_map(|(o, s)| {
            let (a, s) = (o.animation.as_ref()?, (*s)?);
            Some((water::place_sphere(s, a.transform_at(t0)), water::place_sphere(s, a.transform_at(t1))))
        });
        water::bodies_in(water, wa.transform_at(t1).inverse(), moving)
    }

    /// The cameras and lights that animations move, placed at the scene's time (directional lights' beams start
    /// outside the scene's bounds there).
    pub fn place_movers(&mut self) {
        for k in 0..self.movers.len() {
            let m = self.movers[k].animation.transform_at(self.time);
            let origin = m.transform_point3(Vec3::ZERO);
            let forward = m.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
            match self.movers[k].what {
                Moved::Camera(i) => {
                    let up = m.transform_vector3(Vec3::Y).normalize_or_zero();
                    let c = &mut self.cameras[i];
                    // A degenerate pose (a scale through zero) keeps the last good one.
                    if forward != Vec3::ZERO && forward.cross(up).length() > 1e-4 {
                        (c.position, c.target, c.up) = (origin, origin + forward, up);
                    }
                }
                Moved::Light(i) => {
                    let l = &mut self.lights[i];
                    if forward == Vec3::ZERO {
                        continue;
                    }
                    l.position = origin;
                    if l.kind != LightKind::Point {
                        l.target = origin + forward;
                    }
                }
            }
        }
        if self.movers.iter().any(|m| matches!(m.what, Moved::Light(_))) {
            self.place_directional_lights();
        }
        self.place_properties();
    }

    /// The light and camera properties that animations set ([`PropertyTrack`]), at the scene's time, held in their
    /// ranges where a spline overshoots.
    pub fn place_properties(&mut self) {
        let t = self.time;
        for p in &self.properties {
            match p {
                PropertyTrack::LightIntensity(i, k) => self.lights[*i].intensity = k.at(t).max(0.0),
                PropertyTrack::LightColor(i, k) => self.lights[*i].color = k.at(t).max(Vec3::ZERO),
                PropertyTrack::LightCone(i, k) => {
                    self.lights[*i].cone = k.at(t).clamp(1e-4, std::f32::consts::FRAC_PI_2 - 1e-4)
                }
                PropertyTrack::CameraFov(i, k) => {
                    if let Projection::Perspective { fov } = &mut self.cameras[*i].projection {
                        *fov = k.at(t).clamp(1e-4, std::f32::consts::PI - 1e-3);
                    }
                }
                PropertyTrack::CameraHalfHeight(i, k) => {
                    if let Projection::Orthographic { half_height } = &mut self.cameras[*i].projection {
                        *half_height = k.at(t).max(1e-6);
                    }
                }
                PropertyTrack::ObjectIor(i, k) => {
                    if let Material::Dielectric { ior, .. } = &mut self.objects[*i].material {
                        *ior = k.at(t).max(1e-3);
                    }
                }
            }
        }
    }

    /// A glTF directional light is at infinity; ours starts its beam at `position`: start it just outside the
    /// scene's bounding sphere, up-beam, so that it lights everything.
    pub fn place_directional_lights(&mut self) {
        let (lo, hi) = self.bounds();
        let (center, radius) = ((lo + hi) * 0.5, (hi - lo).length() * 0.5);
        for l in self.lights.iter_mut().filter(|l| l.kind == LightKind::Directional) {
            let dir = (l.target - l.position).normalize();
            l.position = center - dir * (radius * 1.01 + 1e-3);
            l.target = l.position + dir;
        }
    }

    /// The scene at time `t` (s).
    pub fn at_time(&self, t: f32) -> Scene {
        let mut s = self.clone();
        s.set_time(t);
        s
    }

    /// Load a scene by its file type: TOML (`.toml`), or glTF 2.0 (`.gltf`, `.glb`). Any other file type is
    /// refused with the accepted ones named (an OBJ is a mesh: a TOML scene's `[[object]]` references it).
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        Scene::load_with(path, &LoadOptions::default())
    }

    /// [`Scene::load`] with options (glTF: which animations play).
    pub fn load_with(path: &Path, options: &LoadOptions) -> Result<Scene, SceneError> {
        if gltf::is_gltf(path) {
            return gltf::load(path, options);
        }
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        if ext.as_deref() != Some("toml") {
            let hint = match ext.as_deref() {
                Some("obj") => {
                    "; an OBJ is a mesh, not a scene: add it to a TOML scene as an [[object]] with shape = \"mesh\" \
                     and path = \"...\" (docs/scenes.md)"
                }
                _ => "",
            };
            return Err(SceneError::Io {
                file: path.display().to_string(),
                message: format!(
                    "not a scene file: scenes are TOML (.toml) or glTF 2.0 (.gltf, .glb), found {}{hint}",
                    ext.map_or("no extension".to_string(), |e| format!(".{e}"))
                ),
            });
        }
        let text = std::fs::read_to_string(path).map_err(|e| SceneError::Io {
            file: path.display().to_string(),
            message: format!("cannot read scene: {e}"),
        })?;
        Self::parse(&text, path)
    }

    /// Parse scene text; `path` locates the file for messages and relative mesh paths.
    pub fn parse(text: &str, path: &Path) -> Result<Scene, SceneError> {
        toml::parse(text, path)
    }

    /// The camera named `name`, or the first one; an error message lists the cameras there are.
    pub fn camera(&self, name: Option<&str>) -> Result<&Camera, String> {
        let names = || self.cameras.iter().map(|c| c.name.as_str()).collect::<Vec<_>>().join(", ");
        match name {
            Some(n) => self
                .cameras
                .iter()
                .find(|c| c.name == n)
                .ok_or_else(|| format!("{} has no camera named `{n}` (cameras: {})", self.path.display(), names())),
            None => self.cameras.first().ok_or_else(|| format!("{}: the scene has no [[camera]]", self.path.display())),
        }
    }

    /// The specular objects (dielectrics and mirrors): they make caustics.
    pub fn refractors(&self) -> impl Iterator<Item = &Object> {
        self.objects.iter().filter(|o| o.is_refractor())
    }

    /// The diffuse receivers.
    pub fn receivers(&self) -> impl Iterator<Item = &Object> {
        self.objects.iter().filter(|o| !o.is_refractor())
    }

    /// Point lights without a target aim at the center of the glass (or of the whole scene without glass).
    pub fn aim_point_lights(&mut self) {
        let bounds = |it: &mut dyn Iterator<Item = &Object>| {
            it.map(|o| o.mesh.bounds())
                .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), (c, d)| (a.min(c), b.max(d)))
        };
        let (lo, hi) = if self.has_refractors() {
            bounds(&mut self.objects.iter().filter(|o| o.is_refractor()))
        } else {
            bounds(&mut self.objects.iter())
        };
        let center = (lo + hi) * 0.5;
        for l in self.lights.iter_mut().filter(|l| l.kind == LightKind::Point && !l.target.is_finite()) {
            l.target = center;
        }
    }

    /// Whether any object is specular.
    pub fn has_refractors(&self) -> bool {
        self.refractors().next().is_some()
    }

    /// Color channels the photons are traced in: 3 (red, green, blue, each with its own IOR and absorption) when
    /// some glass disperses or absorbs colors unequally, else 1 (the light's color tints one gray caustic).
    pub fn color_channels(&self) -> usize {
        if self.objects.iter().any(|o| o.material.needs_color()) {
            3
        } else {
            1
        }
    }

    /// Whether light is absorbed along its way through some medium, or media overlap: each ray then carries the
    /// medium it travels in and the volumes it is inside (docs/design.md "Media"), so that a receiver standing in
    /// an absorbing liquid receives what is left, and an overlap's surfaces know which medium is on either side.
    pub fn has_media(&self) -> bool {
        self.objects.iter().any(|o| o.absorption().max_element() > 0.0 || o.priority > 0)
    }

    /// Object `i`'s `outside`, where it names another dielectric and `i` is one (None: air).
    pub fn outside_of(&self, i: usize) -> Option<usize> {
        let dielectric =
            |k: usize| self.objects.get(k).is_some_and(|x| matches!(x.material, Material::Dielectric { .. }));
        self.objects[i].outside.filter(|&j| j != i && dielectric(i) && dielectric(j))
    }

    /// An object whose `outside` names something other than another dielectric, or is not one itself (a scene
    /// built in code can; the parsers refuse it).
    pub fn bad_outside(&self) -> Option<usize> {
        (0..self.objects.len()).find(|&i| self.objects[i].outside.is_some() && self.outside_of(i).is_none())
    }

    /// World-space bounds of every object.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.objects
            .iter()
            .map(|o| o.mesh.bounds())
            .fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(lo, hi), (a, b)| {
                (lo.min(a), hi.max(b))
            })
    }

    /// The object a ray `origin + t·dir` (t > 0) hits first, with its t, among those `filter` accepts (the
    /// viewer picks the glass under the cursor with it; brute force over the triangles of the objects whose
    /// bounds the ray enters).
    pub fn pick(&self, origin: Vec3, dir: Vec3, filter: impl Fn(&Object) -> bool) -> Option<(usize, f32)> {
        let mut best: Option<(usize, f32)> = None;
        for (i, o) in self.objects.iter().enumerate().filter(|(_, o)| filter(o)) {
            let (lo, hi) = o.mesh.bounds();
            let inv = dir.recip();
            let (a, b) = ((lo - origin) * inv, (hi - origin) * inv);
            let (near, far) = (a.min(b).max_element().max(0.0), a.max(b).min_element());
            // (NaN bounds enter nothing.)
            let enters = matches!(near.partial_cmp(&far), Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal));
            if !enters || best.is_some_and(|(_, t)| near > t) {
                continue;
            }
            let m = &o.mesh;
            for tri in m.indices.chunks_exact(3) {
                let [p0, p1, p2] = [0, 1, 2].map(|k| m.positions[tri[k] as usize]);
                // Möller-Trumbore.
                let (e1, e2) = (p1 - p0, p2 - p0);
                let q = dir.cross(e2);
                let det = e1.dot(q);
                if det.abs() < 1e-12 {
                    continue;
                }
                let s = origin - p0;
                let u = s.dot(q) / det;
                let r = s.cross(e1);
                let v = dir.dot(r) / det;
                let t = e2.dot(r) / det;
                if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0 && best.is_none_or(|(_, b)| t < b) {
                    best = Some((i, t));
                }
            }
        }
        best
    }

    /// The index of refraction every refractor shares (a mirror counts as -1), or None when they differ or there
    /// is none: the renderer then draws no IOR buffer and passes this one in its uniforms.
    pub fn shared_ior(&self) -> Option<f32> {
        let ior = |m: &Material| match *m {
            Material::Dielectric { ior, .. } => ior,
            _ => -1.0,
        };
        let mut iors = self.refractors().map(|o| ior(&o.material));
        let first = iors.next()?;
        iors.all(|x| x == first).then_some(first)
    }

    /// Whether some glass disperses (an Abbe number): its channels take different paths.
    pub fn disperses(&self) -> bool {
        self.objects.iter().any(|o| matches!(o.material, Material::Dielectric { abbe, .. } if abbe > 0.0))
    }

    /// Triangles in all objects.
    pub fn triangle_count(&self) -> usize {
        self.objects.iter().map(|o| o.mesh.triangle_count()).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const BASE: &str = r#"
[[light]]
kind = "spot"
position = [0.0, 2.0, 0.0]
target = [0.0, 0.5, 0.0]
cone_deg = 40.0
intensity = 1.0

[[camera]]
name = "top"
kind = "orthographic"
position = [0.0, 3.0, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
half_height = 1.0

[[object]]
name = "floor"
shape = "plane"
size = [2.0, 2.0]
material = { kind = "diffuse", albedo = 0.8 }

[[object]]
name = "glass"
shape = "sphere"
radius = 0.3
subdivisions = 2
translate = [0.0, 0.5, 0.0]
material = { kind = "dielectric", ior = 1.5 }
"#;

    fn parse(s: &str) -> Result<Scene, SceneError> {
        Scene::parse(s, Path::new("test.toml"))
    }

    #[test]
    fn parses_the_canonical_scene() {
        let s = parse(BASE).unwrap();
        assert_eq!(s.objects.len(), 2);
        assert!(s.has_refractors());
        let (lo, hi) = s.objects[1].mesh.bounds();
        assert!((lo.y - 0.2).abs() < 1e-5 && (hi.y - 0.8).abs() < 1e-5);
    }

    #[test]
    fn bad_ior_names_line_and_field() {
        for bad in ["ior = -1.0", "ior = nan", "ior = 0.0"] {
            let text = BASE.replace("ior = 1.5", bad);
            let e = parse(&text).unwrap_err().to_string();
            assert!(e.starts_with("test.toml:29: object[1] \"glass\".material.ior"), "{e}");
        }
    }

    /// Media: `outside` and `inside` name another dielectric object of the file (before or after it); anything
    /// else is refused with the file, line and field.
    #[test]
    fn media_name_other_dielectrics() {
        let water = "\n[[object]]\nname = \"water\"\nshape = \"cube\"\nsize = 0.2\ntranslate = [0.0, 0.5, 0.0]\n";
        let scene = |m: &str| format!("{BASE}{water}material = {{ kind = \"dielectric\", {m} }}\n");
        let s = parse(&scene("ior = 1.33, absorption = 0.1, outside = \"glass\"")).unwrap();
        assert_eq!((s.objects[2].outside, s.outside_of(2), s.objects[1].outside), (Some(1), Some(1), None));
        assert!(s.has_media() && s.bad_outside().is_none());
        // `inside` takes the named object's medium: its IOR, absorption and dispersion.
        let s = parse(&scene("inside = \"glass\"")).unwrap();
        assert_eq!(s.objects[2].material, s.objects[1].material);
        let bad = [
            ("ior = 1.33, outside = \"nope\"", "material.outside", "no object is named `nope`"),
            ("ior = 1.33, outside = \"water\"", "material.outside", "names the object itself"),
            ("ior = 1.33, outside = \"floor\"", "material.outside", "`floor` must be a dielectric"),
            ("inside = \"glass\", ior = 1.2", "material.ior", "takes `ior` from that object"),
            ("inside = \"floor\"", "material.inside", "`floor` must be a dielectric"),
        ];
        let s = parse(&scene("ior = 1.33, priority = 3")).unwrap();
        assert_eq!((s.objects[2].priority, s.objects[1].priority), (3, 0));
        assert!(s.has_media());
        let bad = bad.into_iter().chain([
            ("ior = 1.33, priority = 0", "material.priority", "must lie in 1..=255"),
            ("ior = 1.33, priority = 2, outside = \"glass\"", "material.priority", "no `outside` or `inside`"),
        ]);
        for (m, field, message) in bad {
            let e = parse(&scene(m)).unwrap_err().to_string();
            assert!(
                e.starts_with(&format!("test.toml:36: object[2] \"water\".{field}")) && e.contains(message),
                "{m}: {e}"
            );
        }
        let e = parse(&BASE.replace("albedo = 0.8 }", "albedo = 0.8, outside = \"glass\" }")).unwrap_err().to_string();
        assert!(e.contains("object[0] \"floor\".material.outside") && e.contains("only a dielectric"), "{e}");
        // A chain of `inside` is refused: the medium must be the named object's own.
        let chained = format!("{}\n[[object]]\nname = \"ice\"\nshape = \"cube\"\nsize = 0.1\nmaterial = {{ kind = \"dielectric\", inside = \"water\" }}\n", scene("inside = \"glass\""));
        let e = parse(&chained).unwrap_err().to_string();
        assert!(
            e.contains("object[3] \"ice\".material.inside")
                && e.contains("`water` must be a dielectric with a medium of its own"),
            "{e}"
        );
    }

    #[test]
    fn unknown_key_is_an_error() {
        let e = parse(&BASE.replace("radius = 0.3", "radius = 0.3\nradiuss = 1")).unwrap_err().to_string();
        assert!(e.contains("test.toml:27:") && e.contains("unknown field `radiuss`"), "{e}");
    }

    #[test]
    fn unknown_light_kind_comes_before_missing_fields() {
        let text = BASE.replace("kind = \"spot\"", "kind = \"area\"").replace("intensity = 1.0\n", "");
        let e = parse(&text).unwrap_err().to_string();
        assert!(e.contains("light[0].kind") && e.contains("unknown light kind `area`"), "{e}");
        let e = parse(&BASE.replace("intensity = 1.0\n", "")).unwrap_err().to_string();
        assert!(e.contains("light[0].intensity") && e.contains("missing field `intensity`"), "{e}");
    }

    #[test]
    fn cone_out_of_range() {
        let e = parse(&BASE.replace("cone_deg = 40.0", "cone_deg = 90.0")).unwrap_err().to_string();
        assert!(e.contains("test.toml:6: light[0].cone_deg"), "{e}");
        // A cone too narrow for a frustum in f32 (the fuzz test's denormal once reached the light view's fit and
        // panicked there).
        for narrow in ["1e-45", "0.01"] {
            let e = parse(&BASE.replace("cone_deg = 40.0", &format!("cone_deg = {narrow}"))).unwrap_err().to_string();
            assert!(e.contains("test.toml:6: light[0].cone_deg") && e.contains("[0.1, 90)"), "{e}");
        }
        let narrowest = parse(&BASE.replace("cone_deg = 40.0", "cone_deg = 0.1")).unwrap();
        assert!(spot_cone_ok(narrowest.lights[0].cone));
    }

    /// A sun is a directional light 0.53° across unless it says otherwise; a spot has no angular size, and a sun's
    /// stays within [0, 20]°.
    #[test]
    fn a_sun_has_its_size() {
        let sun = BASE.replace("kind = \"spot\"", "kind = \"sun\"").replace("cone_deg = 40.0\n", "");
        let light = &parse(&sun).unwrap().lights[0];
        assert_eq!(light.kind, LightKind::Directional);
        assert!((light.angular_radius - 0.265f32.to_radians()).abs() < 1e-9);
        let wide = sun.replace("intensity = 1.0", "intensity = 1.0\nangular_diameter_deg = 2.0");
        assert!((parse(&wide).unwrap().lights[0].angular_radius - 1f32.to_radians()).abs() < 1e-9);
        let e = parse(&wide.replace("2.0", "25.0")).unwrap_err().to_string();
        assert!(e.contains("test.toml:7: light[0].angular_diameter_deg") && e.contains("[0, 20]"), "{e}");
        let spot = BASE.replace("intensity = 1.0", "intensity = 1.0\nangular_diameter_deg = 0.5");
        let e = parse(&spot).unwrap_err().to_string();
        assert!(
            e.contains("light[0].angular_diameter_deg") && e.contains("a spot light has no angular diameter"),
            "{e}"
        );
        // A spot's bulb; a sun has none (its size is an angle).
        let bulb = BASE.replace("intensity = 1.0", "intensity = 1.0\nradius = 0.05");
        assert_eq!(parse(&bulb).unwrap().lights[0].radius, 0.05);
        let e = parse(&bulb.replace("0.05", "-1.0")).unwrap_err().to_string();
        assert!(e.contains("light[0].radius") && e.contains(">= 0"), "{e}");
        let e = parse(&sun.replace("intensity = 1.0", "intensity = 1.0\nradius = 0.05")).unwrap_err().to_string();
        assert!(e.contains("light[0].radius") && e.contains("a directional light has no radius"), "{e}");
    }

    #[test]
    fn missing_mesh_is_an_error() {
        let text =
            BASE.replace("shape = \"sphere\"\nradius = 0.3\nsubdivisions = 2", "shape = \"mesh\"\npath = \"nope.obj\"");
        let e = parse(&text).unwrap_err().to_string();
        assert!(e.contains("object[1] \"glass\".path") && e.contains("nope.obj"), "{e}");
    }
}

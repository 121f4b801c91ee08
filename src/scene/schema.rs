//! The TOML schema, as written in scene files. Every field carries its span so that validation errors can name
//! the line. Unknown keys are rejected by serde.

use serde::Deserialize;
use toml::Spanned;

pub type S<T> = Spanned<T>;

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    #[serde(default)]
    pub light: Vec<S<LightDef>>,
    #[serde(default)]
    pub camera: Vec<S<CameraDef>>,
    #[serde(default)]
    pub object: Vec<S<ObjectDef>>,
    pub environment: Option<S<EnvironmentDef>>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentDef {
    /// An equirectangular `.hdr` or `.exr`, relative to the scene file.
    pub path: S<String>,
    /// W/(m²·sr) per unit of the map (default 1).
    pub intensity: Option<S<f32>>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct LightDef {
    pub kind: S<String>,
    // Optional here so that an unknown `kind` is reported before any missing field (checked after `kind`).
    pub position: Option<S<[f32; 3]>>,
    pub target: Option<S<[f32; 3]>>,
    pub cone_deg: Option<S<f32>>,
    pub intensity: Option<S<f32>>,
    pub color: Option<S<[f32; 3]>>,
    pub angular_diameter_deg: Option<S<f32>>,
    pub radius: Option<S<f32>>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct CameraDef {
    pub name: S<String>,
    pub kind: S<String>,
    pub position: S<[f32; 3]>,
    pub target: S<[f32; 3]>,
    pub up: Option<S<[f32; 3]>>,
    pub half_height: Option<S<f32>>,
    pub fov_deg: Option<S<f32>>,
}

/// A number or a 3-vector (scale, cube size, albedo).
#[derive(Deserialize, Debug, Clone, Copy)]
#[serde(untagged)]
pub enum ScalarOr3 {
    Scalar(f32),
    Vec3([f32; 3]),
}

impl ScalarOr3 {
    pub fn to_array(self) -> [f32; 3] {
        match self {
            ScalarOr3::Scalar(s) => [s; 3],
            ScalarOr3::Vec3(v) => v,
        }
    }
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct ObjectDef {
    pub name: S<String>,
    pub shape: S<String>,
    pub size: Option<S<toml::Value>>,
    pub radius: Option<S<f32>>,
    pub subdivisions: Option<S<i64>>,
    pub path: Option<S<String>>,
    pub depth: Option<S<f32>>,
    pub grid: Option<S<i64>>,
    #[serde(default)]
    pub waves: Vec<S<WaveDef>>,
    /// Water: a simulated surface.
    pub simulation: Option<S<SimulationDef>>,
    /// Water: drops into its simulated surface.
    #[serde(default)]
    pub drops: Vec<S<DropDef>>,
    /// A room's sides left out.
    pub open: Option<S<Vec<String>>>,
    /// A lathe's profile: (radius, height) points.
    pub profile: Option<S<Vec<[f32; 2]>>>,
    /// A lathe's steps around the axis.
    pub segments: Option<S<i64>>,
    pub translate: Option<S<[f32; 3]>>,
    pub rotate_deg: Option<S<[f32; 3]>>,
    pub scale: Option<S<ScalarOr3>>,
    pub material: S<MaterialDef>,
    /// `[[object.keyframe]]`: the object's placement over time.
    #[serde(default)]
    pub keyframe: Vec<S<KeyframeDef>>,
    pub interpolation: Option<S<String>>,
    pub repeat: Option<S<String>>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct WaveDef {
    pub amplitude: S<f32>,
    pub wavelength: S<f32>,
    pub direction_deg: Option<S<f32>>,
    pub speed: Option<S<f32>>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct SimulationDef {
    pub speed: Option<S<f32>>,
    pub damping: Option<S<f32>>,
    pub limit: Option<S<f32>>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct DropDef {
    pub time: S<f32>,
    pub at: S<[f32; 2]>,
    pub radius: Option<S<f32>>,
    pub depth: Option<S<f32>>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct KeyframeDef {
    pub time: S<f32>,
    pub translate: Option<S<[f32; 3]>>,
    pub rotate_deg: Option<S<[f32; 3]>>,
    pub scale: Option<S<ScalarOr3>>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct MaterialDef {
    pub kind: S<String>,
    pub albedo: Option<S<ScalarOr3>>,
    pub ior: Option<S<f32>>,
    pub absorption: Option<S<ScalarOr3>>,
    pub abbe: Option<S<f32>>,
    /// A dielectric's surface: the object whose medium lies outside it (default: air).
    pub outside: Option<S<String>>,
    /// A dielectric's surface: the object whose medium lies inside it, its IOR and absorption (default: its own).
    pub inside: Option<S<String>>,
    /// A dielectric volume that may overlap others: the higher priority's medium wins where they do.
    pub priority: Option<S<i64>>,
    /// A diffuse material's albedo image (PNG or JPEG, sRGB), relative to the scene file.
    pub albedo_texture: Option<S<String>>,
    /// A diffuse material's procedural checkerboard: `albedo` and this one's `albedo` alternate.
    pub checker: Option<S<CheckerDef>>,
    /// How many times the texture repeats across the mesh's uv [0, 1]: a number or [u, v].
    pub uv_scale: Option<S<ScalarOr2>>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct CheckerDef {
    /// Squares per side of uv [0, 1].
    pub squares: S<i64>,
    /// The second squares' albedo.
    pub albedo: S<ScalarOr3>,
}

/// A number or a 2-vector (uv scale).
#[derive(Deserialize, Debug, Clone, Copy)]
#[serde(untagged)]
pub enum ScalarOr2 {
    Scalar(f32),
    Vec2([f32; 2]),
}

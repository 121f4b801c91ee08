//! The animated rig of the glTF animation tests: nodes with non-identity rest transforms in a hierarchy (a moving,
//! turning parent; a child whose scale follows a cubic spline; a grandchild turned by steps; a mesh instanced by two
//! nodes; a moving camera and a tilting spot light), animated by three animations as Blender writes them; and the
//! same rig posed still at a time.
#![allow(dead_code)]

use super::gltf_doc::*;
use caustics::scene::animation::{Interpolation, Track};
use caustics::scene::mesh;
use glam::{Quat, Vec3};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// The times the rig is rendered at: its start, between keyframes, and past the end of its first animation.
pub const TIMES: [f32; 3] = [0.0, 0.375, 1.25];

/// One animation channel as written: node, property, interpolation, times, and the flat values.
pub struct Channel {
    pub node: usize,
    pub path: &'static str,
    pub interpolation: &'static str,
    pub times: Vec<f32>,
    pub values: Vec<f32>,
}

pub fn q(axis: Vec3, deg: f32) -> [f32; 4] {
    Quat::from_axis_angle(axis, deg.to_radians()).to_array()
}

/// The rig's three animations: "Rig" moves and turns the parent; "Glass" scales the child on a cubic spline, turns
/// the grandchild by steps, and slides the second instance of the cube (starting after 0 s); "Lights" moves the
/// main camera and tilts the spot light.
pub fn channels() -> Vec<Vec<Channel>> {
    let c = |node, path, interpolation, times: &[f32], values: Vec<f32>| Channel {
        node,
        path,
        interpolation,
        times: times.to_vec(),
        values,
    };
    let flat = |v: &[[f32; 4]]| v.iter().flatten().copied().collect::<Vec<f32>>();
    vec![
        vec![
            c(1, "translation", "LINEAR", &[0.0, 0.5, 1.0], vec![0.05, 0.7, -0.05, 0.25, 0.75, 0.05, -0.1, 0.65, 0.1]),
            c(1, "rotation", "LINEAR", &[0.0, 1.0], flat(&[q(Vec3::Y, 30.0), q(Vec3::Y, 100.0)])),
        ],
        vec![
            // (in tangent, value, out tangent) per keyframe.
            c(
                2,
                "scale",
                "CUBICSPLINE",
                &[0.0, 1.5],
                vec![0.0, 0.0, 0.0, 1.0, 0.8, 1.2, 0.2, 0.1, 0.0, 0.0, 0.0, 0.1, 1.2, 1.0, 1.1, 0.0, 0.0, 0.0],
            ),
            c(
                3,
                "rotation",
                "STEP",
                &[0.0, 0.25, 1.0],
                flat(&[[0.0, 0.0, 0.0, 1.0], q(Vec3::X, 45.0), q(Vec3::Y, 70.0)]),
            ),
            c(4, "translation", "LINEAR", &[0.25, 1.25], vec![-0.4, -0.15, 0.1, -0.3, -0.1, -0.2]),
        ],
        vec![
            // The main camera moves, and the spot light tilts by 8° about z.
            c(7, "translation", "LINEAR", &[0.0, 1.5], vec![1.6, 1.7, 2.0, 1.9, 1.5, 2.1]),
            c(6, "rotation", "LINEAR", &[0.0, 1.0], flat(&[q(Vec3::X, -90.0), tilted_down()])),
        ],
    ]
}

/// The spot's last orientation: down, then turned 8° about z.
fn tilted_down() -> [f32; 4] {
    (Quat::from_axis_angle(Vec3::Z, 8f32.to_radians()) * Quat::from_axis_angle(Vec3::X, -90f32.to_radians())).to_array()
}

/// The rig without its animations: a floor, the cube (glass) under a parent node, a bead (denser glass) under
/// the cube, the cube again under the parent (a second instance of the mesh), a spot light, an orthographic
/// `top` camera and a perspective `main` one.
pub fn still_rig() -> (Value, Vec<u8>) {
    let mut doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_transmission", "KHR_materials_ior"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 5, 6, 7]}],
        "meshes": [],
        "materials": [
            {"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0}},
            {"extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}}},
            {"extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                            "KHR_materials_ior": {"ior": 1.7}}}
        ],
        "cameras": [
            {"type": "orthographic", "orthographic": {"xmag": 1.0, "ymag": 1.0, "znear": 0.01, "zfar": 10.0}},
            {"type": "perspective", "perspective": {"yfov": 0.75, "aspectRatio": 1.0, "znear": 0.01}}
        ],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "spot", "intensity": 683.0, "spot": {"innerConeAngle": 0.6, "outerConeAngle": 0.7}}
        ]}},
        "buffers": [{"byteLength": 0}],
        "bufferViews": [],
        "accessors": [],
    });
    let mut bin = Vec::new();
    add_mesh(&mut doc, &mut bin, "floor", &mesh::plane(2.0, 2.0), 0);
    add_mesh(&mut doc, &mut bin, "cube", &mesh::cube(Vec3::splat(0.3)), 1);
    add_mesh(&mut doc, &mut bin, "bead", &mesh::icosphere(0.08, 2), 2);
    // The main camera at (1.6, 1.7, 2.0), looking at (0, 0.3, 0).
    let eye = Vec3::new(1.6, 1.7, 2.0);
    let look = Quat::from_mat3(&glam::Mat3::from_cols(
        Vec3::Y.cross(eye - Vec3::new(0.0, 0.3, 0.0)).normalize(),
        (eye - Vec3::new(0.0, 0.3, 0.0)).normalize().cross(Vec3::Y.cross(eye - Vec3::new(0.0, 0.3, 0.0)).normalize()),
        (eye - Vec3::new(0.0, 0.3, 0.0)).normalize(),
    ));
    let down = q(Vec3::X, -90.0);
    doc["nodes"] = json!([
        {"name": "floor", "mesh": 0},
        {"name": "rig", "translation": [0.05, 0.7, -0.05], "rotation": q(Vec3::Y, 30.0), "scale": [1.1, 1.1, 1.1],
         "children": [2, 4]},
        {"name": "glass", "mesh": 1, "translation": [0.2, -0.05, 0.05], "rotation": q(Vec3::X, 20.0),
         "scale": [1.0, 0.8, 1.2], "children": [3]},
        {"name": "bead", "mesh": 2, "translation": [0.0, 0.0, 0.35]},
        {"name": "twin", "mesh": 1, "translation": [-0.4, -0.15, 0.1], "rotation": q(Vec3::Z, 15.0),
         "scale": [0.6, 0.6, 0.6]},
        {"name": "top", "camera": 0, "translation": [0.0, 3.0, 0.0], "rotation": down},
        {"name": "spot", "translation": [0.0, 2.0, 0.0], "rotation": down,
         "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"name": "main", "camera": 1, "translation": eye.to_array(), "rotation": look.to_array()}
    ]);
    (doc, bin)
}

/// The rig with its three animations.
pub fn animated_rig() -> (Value, Vec<u8>) {
    let (mut doc, mut bin) = still_rig();
    let mut animations = Vec::new();
    for (a, chans) in channels().into_iter().enumerate() {
        let (mut list, mut samplers) = (Vec::new(), Vec::new());
        for ch in chans {
            let input = add_accessor(&mut doc, &mut bin, &ch.times, "SCALAR");
            let kind = if ch.path == "rotation" { "VEC4" } else { "VEC3" };
            let output = add_accessor(&mut doc, &mut bin, &ch.values, kind);
            list.push(json!({"sampler": samplers.len(), "target": {"node": ch.node, "path": ch.path}}));
            samplers.push(json!({"input": input, "output": output, "interpolation": ch.interpolation}));
        }
        let name = ["Rig", "Glass", "Lights"][a];
        animations.push(json!({"name": name, "channels": list, "samplers": samplers}));
    }
    doc["animations"] = json!(animations);
    (doc, bin)
}

/// The still rig with every animated node's TRS at time `t` written in (the animations' values there, each
/// track clamped to its keyframes).
pub fn posed_rig(t: f32) -> (Value, Vec<u8>) {
    let (mut doc, bin) = still_rig();
    for ch in channels().into_iter().flatten() {
        let interpolation = match ch.interpolation {
            "LINEAR" => Interpolation::Linear,
            "STEP" => Interpolation::Step,
            _ => Interpolation::Cubic,
        };
        let per_key = if interpolation == Interpolation::Cubic { 3 } else { 1 };
        let value: Vec<f32> = if ch.path == "rotation" {
            let qs: Vec<Quat> = ch.values.chunks(4).map(Quat::from_slice).collect();
            Track { times: ch.times, values: qs, tangents: Vec::new(), interpolation }.at(t).to_array().to_vec()
        } else {
            let vs: Vec<Vec3> = ch.values.chunks(3).map(Vec3::from_slice).collect();
            let (values, tangents) = if per_key == 3 {
                (vs.chunks(3).map(|c| c[1]).collect(), vs.chunks(3).map(|c| (c[0], c[2])).collect())
            } else {
                (vs, Vec::new())
            };
            Track { times: ch.times, values, tangents, interpolation }.at(t).to_array().to_vec()
        };
        doc["nodes"][ch.node][ch.path] = json!(value);
    }
    (doc, bin)
}

pub fn write_rig(dir: &Path, name: &str, (doc, bin): (Value, Vec<u8>)) -> PathBuf {
    write(dir, name, embedded(doc, &bin))
}

/// The animated rig (`rig.gltf`) and its poses at [`TIMES`] (`rig@T.gltf`), written to `dir`.
pub fn write_rigs(dir: &Path) -> (PathBuf, Vec<PathBuf>) {
    let animated = write_rig(dir, "rig.gltf", animated_rig());
    let stills = TIMES.iter().map(|&t| write_rig(dir, &format!("rig@{t}.gltf"), posed_rig(t))).collect();
    (animated, stills)
}

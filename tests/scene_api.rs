//! The scene in code (the library's scene API): a scene built with `Scene::new`, `add_mesh` and `add_instance`
//! renders the same caustic as the same scene read from its file; `set_transform` and `set_material` change it as
//! editing the file would; bad meshes and transforms are refused with the scene unchanged. In process, on the
//! shared device, under validation. The frames run exact transport, dense level 3 (named: dense emits the same
//! photons for the same geometry, so the images compare to float rounding).

mod common;
use caustics::image_io::RgbImage;
use caustics::metrics::compare;
use caustics::scene::{mesh, Material, Mesh, Scene};
use caustics::settings::{Method, Quality, Settings, Transport};
use caustics::{FrameDesc, InstanceId, Renderer, SceneUpdateReport};
use glam::{Mat4, Vec3};
use std::path::Path;

fn settings() -> Settings {
    let quality = Quality { transport: Transport::Exact, method: Method::Dense, level: Some(3), ..Quality::default() };
    Settings { quality, ..Settings::default() }
}

fn caustics(r: &mut Renderer) -> RgbImage {
    common::top_caustics(r, 128).0
}

/// The sphere scene's file with the glass moved to `at` and given `ior`.
fn file_scene(dir: &Path, at: [f32; 3], ior: f32) -> String {
    let placement = format!("translate = [{:?}, {:?}, {:?}]", at[0], at[1], at[2]);
    placed_file(dir, &format!("sphere_{}_{}_{}_{ior}", at[0], at[1], at[2]), &placement, ior)
}

/// The sphere scene's file with the glass's `translate` line replaced by `placement` and its IOR `ior`.
fn placed_file(dir: &Path, name: &str, placement: &str, ior: f32) -> String {
    let text = std::fs::read_to_string(common::SPHERE).unwrap();
    let edited = text.replace("translate = [0.0, 0.5, 0.0]", placement).replace("ior = 1.5", &format!("ior = {ior:?}"));
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, edited).unwrap();
    path.to_str().unwrap().to_string()
}

/// The sphere scene built in code: the floor, and the glass ball placed by `at`.
fn built_scene(device: &std::sync::Arc<caustics::gpu::Device>, s: Settings, at: Mat4) -> (Renderer, InstanceId) {
    let file = Scene::load(Path::new(common::SPHERE)).unwrap();
    let mut r = Renderer::new(device.clone(), Scene::new(file.lights.clone(), file.cameras.clone()), s).unwrap();
    let floor = r.add_mesh(mesh::plane(2.0, 2.0)).unwrap();
    r.add_instance(floor, "floor", Material::diffuse(Vec3::splat(0.8)), Mat4::IDENTITY).unwrap();
    let ball = r.add_mesh(mesh::icosphere(0.3, 6)).unwrap();
    let glass_material = Material::Dielectric { ior: 1.5, absorption: Vec3::ZERO, abbe: 0.0 };
    let glass = r.add_instance(ball, "glass", glass_material, at).unwrap();
    (r, glass)
}

fn same(a: &RgbImage, b: &RgbImage, what: &str) {
    let m = compare(a, b, 128, 2.0);
    // The same triangles and photons: the order of the splat's float additions differs, and a record whose ray
    // differentials differ in their last bits can take another of the footprint's discrete choices (a step of the
    // lattice reduction, a 1/255 step of the shear, a rounded radius): measured 4.3e-5 on lavapipe, allowed 1e-4.
    assert!(m.rel_l1 <= 1e-4 && (m.flux_ratio - 1.0).abs() <= 1e-5, "{what}: {m:?}");
}

/// Placed on the GPU against baked on the host: the same triangles up to float rounding of the transform, traced in
/// the mesh's space instead of world space, within `rel_l1` (and the flux within 1e-4).
fn close(a: &RgbImage, b: &RgbImage, rel_l1: f64, what: &str) {
    let m = compare(a, b, 128, 2.0);
    eprintln!("{what}: rel_l1 {:.3e}, flux ratio {:.8}", m.rel_l1, m.flux_ratio);
    assert!(m.rel_l1 <= rel_l1 && (m.flux_ratio - 1.0).abs() <= 1e-4, "{what}: {m:?}");
}

#[test]
fn a_scene_built_in_code_renders_as_its_file_and_moves_as_edited() {
    let (_gpu, device) = common::gpu();
    let dir = common::out_dir("scene_api");
    let file = Scene::load(Path::new(common::SPHERE)).unwrap();
    let mut r = Renderer::new(device.clone(), Scene::new(file.lights.clone(), file.cameras.clone()), settings())
        .expect("a renderer on a scene with no objects yet");
    let floor = r.add_mesh(mesh::plane(2.0, 2.0)).unwrap();
    r.add_instance(floor, "floor", Material::diffuse(Vec3::splat(0.8)), Mat4::IDENTITY).unwrap();
    let ball = r.add_mesh(mesh::icosphere(0.3, 6)).unwrap();
    let glass_material = Material::Dielectric { ior: 1.5, absorption: Vec3::ZERO, abbe: 0.0 };
    let at = |x: f32| Mat4::from_translation(Vec3::new(x, 0.5, 0.0));
    let glass = r.add_instance(ball, "glass", glass_material, at(0.0)).unwrap();
    let built = caustics(&mut r);
    let mut loaded = common::renderer(&device, common::SPHERE, settings());
    let from_file = caustics(&mut loaded);
    same(&built, &from_file, "the scene in code against its file");

    // Moving the glass is the file with its translate edited; the caustic moves with it.
    r.set_transform(glass, at(0.2)).unwrap();
    assert_eq!(r.transform(glass).unwrap(), at(0.2));
    let moved = caustics(&mut r);
    let mut edited = common::renderer(&device, &file_scene(&dir, [0.2, 0.5, 0.0], 1.5), settings());
    same(&moved, &caustics(&mut edited), "moved against the edited file");
    let m = compare(&moved, &built, 64, 2.0);
    assert!(m.rel_l1 > 0.5 && m.peak_offset_m > 0.15, "the caustic moves with the glass: {m:?}");

    // Another material, the same way. The scene's buffers and BVH are rebuilt, from both meshes' kept trees.
    r.set_material(glass, Material::Dielectric { ior: 1.33, absorption: Vec3::ZERO, abbe: 0.0 }).unwrap();
    let (water, report) = common::top_caustics(&mut r, 128);
    assert!(report.scene.rebuilt && report.scene.blas_builds == 0, "a new material: {:?}", report.scene);
    let mut edited = common::renderer(&device, &file_scene(&dir, [0.2, 0.5, 0.0], 1.33), settings());
    same(&water, &caustics(&mut edited), "IOR 1.33 against the edited file");

    // Bad input is refused, and the scene keeps what it had.
    let objects = r.scene().objects.len();
    let mut nan = mesh::plane(1.0, 1.0);
    nan.positions[0].x = f32::NAN;
    assert!(r.add_mesh(nan).unwrap_err().to_string().contains("must be finite"));
    let loose =
        Mesh { positions: vec![Vec3::ZERO; 3], normals: vec![Vec3::Y; 3], indices: vec![0, 1, 5], uvs: Vec::new() };
    assert!(r.add_mesh(loose).unwrap_err().to_string().contains("past the 3 positions"));
    assert!(r.set_transform(glass, Mat4::ZERO).unwrap_err().to_string().contains("invertible"));
    let mut two_interface = r.settings().clone();
    two_interface.quality.transport = Transport::TwoInterface;
    r.set_settings(two_interface).unwrap();
    let e = r.add_instance(floor, "mirror", Material::Mirror, at(-0.5)).unwrap_err().to_string();
    assert!(
        e.contains("mirror") && e.contains("Quality::transport = two-interface") && e.contains("exact transport"),
        "{e}"
    );
    assert_eq!(r.scene().objects.len(), objects, "a refused instance leaves the scene as it was");
    assert_eq!(caustics::gpu::validation_message_count(), 0, "validation messages");
}

/// A placement the file format writes as scale, then rotation about x, y and z, then translation.
struct Placement {
    scale: Vec3,
    rotate_deg: Vec3,
    translate: Vec3,
}

impl Placement {
    fn matrix(&self) -> Mat4 {
        let r = self.rotate_deg.to_array().map(f32::to_radians);
        let q = glam::Quat::from_euler(glam::EulerRot::ZYX, r[2], r[1], r[0]);
        Mat4::from_scale_rotation_translation(self.scale, q, self.translate)
    }

    fn toml(&self) -> String {
        let v = |v: Vec3| format!("[{:?}, {:?}, {:?}]", v.x, v.y, v.z);
        format!("translate = {}\nrotate_deg = {}\nscale = {}", v(self.translate), v(self.rotate_deg), v(self.scale))
    }
}

/// Moving an instance on the GPU (its vertices placed by the frame's scene update, its BVH instance record written
/// in the frame) renders what the file with that placement renders, under both transports, and costs no rebuild, no
/// upload the host waits for, no wait_idle and no readback; moves between frames in flight are ordered by the
/// frames' barriers (validation, synchronization included, would report a hazard).
#[test]
fn a_moved_instance_renders_as_placed_and_rebuilds_nothing() {
    let (_gpu, device) = common::gpu();
    let dir = common::out_dir("scene_api_moves");
    let still = Mat4::from_translation(Vec3::new(0.0, 0.5, 0.0));
    let (mut r, glass) = built_scene(&device, settings(), still);
    let (_, first) = common::top_caustics(&mut r, 128);
    assert!(
        first.scene.rebuilt && first.scene.blas_builds == 2,
        "the first frame builds both meshes' BVHs: {:?}",
        first.scene
    );

    // A tilted ellipsoid, mirrored in x (a negative determinant: the raster winding and the BVH's normals must
    // both follow it).
    let tilted = Placement {
        scale: Vec3::new(-1.2, 0.7, 0.9),
        rotate_deg: Vec3::new(10.0, 30.0, 25.0),
        translate: Vec3::new(0.15, 0.55, -0.1),
    };
    r.set_transform(glass, tilted.matrix()).unwrap();
    let (moved, report) = common::top_caustics(&mut r, 128);
    // Both objects' BvhInstance records (192 bytes each, glsl/common/bvh_types.glsl).
    let instance_bytes = 2 * 192;
    let expected =
        SceneUpdateReport { moved_objects: 1, instance_bytes, blas_builds: 0, ..SceneUpdateReport::default() };
    assert_eq!(report.scene, expected, "a rigid move rebuilds, uploads and waits for nothing");
    assert_eq!(report.host_readbacks, 0);
    assert!(!report.reused, "a moved object's caustic is computed again");
    let file = placed_file(&dir, "tilted", &tilted.toml(), 1.5);
    let from_file = caustics(&mut common::renderer(&device, &file, settings()));
    // Measured 1.5e-3: under a non-uniform scale the BVH interpolates the object-space vertex normals and then
    // transforms them, where the file's baked mesh interpolates the transformed ones (the two differ slightly).
    close(&moved, &from_file, 3e-3, "exact transport, tilted mirrored ellipsoid against its file");

    // A still frame after it reuses the maps and updates nothing.
    let (_, again) = common::top_caustics(&mut r, 128);
    assert!(again.reused && again.scene == SceneUpdateReport::default(), "{:?}", again.scene);

    // The two-interface model rasterizes the placed vertices (front and back faces).
    let mut two = settings();
    two.quality.transport = Transport::TwoInterface;
    r.set_settings(two.clone()).unwrap();
    // (The new transport's targets are allocated, after a wait_idle, by the frame that first renders it.)
    let _ = common::top_caustics(&mut r, 128);
    let turned = Placement { rotate_deg: Vec3::new(-20.0, 0.0, 40.0), ..tilted };
    r.set_transform(glass, turned.matrix()).unwrap();
    let (moved, report) = common::top_caustics(&mut r, 128);
    // (The BVH the exact frames built is kept up to date too.)
    assert_eq!(report.scene, expected);
    let file = placed_file(&dir, "turned", &turned.toml(), 1.5);
    // Measured 4.4e-6: the same world-space vertices to rounding.
    close(&moved, &caustics(&mut common::renderer(&device, &file, two)), 2e-5, "two-interface, turned ellipsoid");

    // Frames in flight: each frame moves the glass while the one before may still read it.
    r.set_settings(settings()).unwrap();
    r.set_frames_in_flight(2).unwrap();
    let top = r.scene().camera(Some("top")).unwrap().clone();
    let view = r.camera_view(&top, 64, 64);
    r.submit(&FrameDesc::new(&view, None), None, &Default::default()).unwrap();
    r.finish_frames().unwrap();
    r.take_completed();
    for k in 0..6 {
        let x = -0.3 + 0.1 * k as f32;
        r.set_transform(glass, Mat4::from_translation(Vec3::new(x, 0.5, 0.0))).unwrap();
        r.submit(&FrameDesc::new(&view, None), None, &Default::default()).unwrap();
    }
    r.finish_frames().unwrap();
    let reports = r.take_completed();
    assert_eq!(reports.len(), 6);
    for rep in &reports {
        assert_eq!((rep.scene.moved_objects, rep.scene.wait_idles, rep.scene.blocking_submits), (1, 0, 0));
        assert_eq!((rep.host_readbacks, rep.scene.blas_builds), (0, 0));
    }
    r.set_frames_in_flight(1).unwrap();
    let (last, _) = common::top_caustics(&mut r, 128);
    let file = file_scene(&dir, [0.2, 0.5, 0.0], 1.5);
    // Measured 2.1e-5: a translation traced in the mesh's space.
    close(&last, &caustics(&mut common::renderer(&device, &file, settings())), 1e-4, "after frames in flight");
    assert_eq!(caustics::gpu::validation_message_count(), 0, "validation messages");
}

/// Textures in code: `add_texture` and a material naming it render as the same checker in a scene file; a material
/// naming a texture the scene lacks, or on a mesh without texture coordinates, is refused with the scene unchanged.
#[test]
fn textures_added_in_code_render_as_in_the_file() {
    let (_gpu, device) = common::gpu();
    let dir = common::out_dir("scene_api_texture");
    let s = Settings { quality: Quality { aa: 1, sky: Some(0.0), ..settings().quality }, ..settings() };
    let (mut r, _) = built_scene(&device, s.clone(), Mat4::from_translation(Vec3::new(0.0, 0.5, 0.0)));
    let floor = InstanceId::from_index(0);
    let checker = caustics::scene::Texture::checker(Vec3::splat(0.8), Vec3::splat(0.2), 8);
    let map = caustics::scene::AlbedoMap::new(1);
    let textured = Material::Diffuse { albedo: Vec3::ONE, map: Some(map) };
    assert!(r.set_material(floor, textured).is_err(), "no texture 1 yet");
    let t = r.add_texture(checker).unwrap();
    assert_eq!(t, 0);
    let textured = Material::Diffuse { albedo: Vec3::ONE, map: Some(caustics::scene::AlbedoMap::new(t)) };
    let loose = r.add_mesh(Mesh { uvs: Vec::new(), ..mesh::plane(1.0, 1.0) }).unwrap();
    assert!(r.add_instance(loose, "no uv", textured, Mat4::IDENTITY).is_err(), "a mesh without uv");
    assert_eq!(r.scene().objects.len(), 2);
    r.set_material(floor, textured).unwrap();
    let built = common::top_aov(&mut r, 128, caustics::Aov::BeautyHdr).0;
    let text = std::fs::read_to_string(common::SPHERE).unwrap().replace(
        r#"material = { kind = "diffuse", albedo = 0.8 }"#,
        r#"material = { kind = "diffuse", albedo = 0.8, checker = { squares = 8, albedo = 0.2 } }"#,
    );
    let path = dir.join("checker.toml");
    std::fs::write(&path, text).unwrap();
    let mut loaded = common::renderer(&device, path.to_str().unwrap(), s);
    let file = common::top_aov(&mut loaded, 128, caustics::Aov::BeautyHdr).0;
    let m = compare(&built, &file, 128, 2.0);
    eprintln!("texture in code against the file: {m:?}");
    assert!(m.rel_l1 <= 1e-5, "{m:?}");
    // The checker shows: two pixels mirrored about the light's axis (x = ±0.117 m, so lit alike) in neighboring
    // squares differ by the albedos' ratio, 0.8 / 0.2.
    let (a, b) = (built.data[8 * 128 + 56][0], built.data[8 * 128 + 71][0]);
    let ratio = a.max(b) / a.min(b);
    assert!(a.min(b) > 0.0 && (ratio - 4.0).abs() < 0.04, "checker squares {a} and {b}: ratio {ratio}");
}

/// Renderers on one device share one set of pipelines (`caustics::Pipelines`), whatever their scenes and
/// settings: a second renderer compiles nothing the first compiled. On a device of its own, a renderer gets its
/// own, and a holder keeps them for the renderers after it.
#[test]
fn renderers_on_one_device_share_their_pipelines() {
    let (_gpu, device) = common::gpu();
    let a = common::renderer(&device, common::SPHERE, settings());
    let b = common::renderer(&device, common::BUNNY, common::dense(1));
    assert_eq!(a.pipelines(), b.pipelines(), "two renderers on one device");
    assert_eq!(a.pipelines(), &caustics::Pipelines::new(&device).expect("pipelines"));
    let desc = caustics::gpu::ContextDesc { validation: true, ..caustics::gpu::ContextDesc::from_env() };
    let other = caustics::gpu::Context::headless(&desc).expect("a second device").device;
    let held = caustics::Pipelines::new(&other).expect("pipelines");
    assert_ne!(&held, a.pipelines(), "another device's");
    let c = common::renderer(&other, common::SPHERE, settings());
    assert_eq!(c.pipelines(), &held, "the held pipelines of that device");
}

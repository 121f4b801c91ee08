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
use caustics::{Aov, AovData, FrameDesc, Renderer};
use glam::{Mat4, Vec3};
use std::path::Path;

fn settings() -> Settings {
    let quality = Quality { transport: Transport::Exact, method: Method::Dense, level: Some(3), ..Quality::default() };
    Settings { quality, ..Settings::default() }
}

fn caustics(r: &mut Renderer) -> RgbImage {
    let top = r.scene().camera(Some("top")).unwrap().clone();
    let view = r.camera_view(&top, 128, 128);
    match r.render(&FrameDesc::new(&view, Some(Aov::Caustics))).expect("frame").image {
        Some(AovData::Float { width, height, rgba }) => {
            RgbImage { width, height, data: rgba.iter().map(|p| [p[0], p[1], p[2]]).collect() }
        }
        _ => panic!("a float AOV"),
    }
}

/// The sphere scene's file with the glass moved to `at` and given `ior`.
fn file_scene(dir: &Path, at: [f32; 3], ior: f32) -> String {
    let text = std::fs::read_to_string(common::SPHERE).unwrap();
    let edited = text
        .replace("translate = [0.0, 0.5, 0.0]", &format!("translate = [{:?}, {:?}, {:?}]", at[0], at[1], at[2]))
        .replace("ior = 1.5", &format!("ior = {ior:?}"));
    let path = dir.join(format!("sphere_{}_{}_{}_{ior}.toml", at[0], at[1], at[2]));
    std::fs::write(&path, edited).unwrap();
    path.to_str().unwrap().to_string()
}

fn same(a: &RgbImage, b: &RgbImage, what: &str) {
    let m = compare(a, b, 128, 2.0);
    // The same triangles and photons: only the order of the splat's float additions differs (measured below 1e-6).
    assert!(m.rel_l1 <= 1e-5 && (m.flux_ratio - 1.0).abs() <= 1e-5, "{what}: {m:?}");
}

#[test]
fn a_scene_built_in_code_renders_as_its_file_and_moves_as_edited() {
    let (_gpu, device) = common::gpu();
    let dir = common::out_dir("scene_api");
    let file = Scene::load(Path::new(common::SPHERE)).unwrap();
    let mut r = Renderer::new(device.clone(), Scene::new(file.lights.clone(), file.cameras.clone()), settings())
        .expect("a renderer on a scene with no objects yet");
    let floor = r.add_mesh(mesh::plane(2.0, 2.0)).unwrap();
    r.add_instance(floor, "floor", Material::Diffuse { albedo: Vec3::splat(0.8) }, Mat4::IDENTITY).unwrap();
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

    // Another material, the same way.
    r.set_material(glass, Material::Dielectric { ior: 1.33, absorption: Vec3::ZERO, abbe: 0.0 }).unwrap();
    let water = caustics(&mut r);
    let mut edited = common::renderer(&device, &file_scene(&dir, [0.2, 0.5, 0.0], 1.33), settings());
    same(&water, &caustics(&mut edited), "IOR 1.33 against the edited file");

    // Bad input is refused, and the scene keeps what it had.
    let objects = r.scene().objects.len();
    let mut nan = mesh::plane(1.0, 1.0);
    nan.positions[0].x = f32::NAN;
    assert!(r.add_mesh(nan).unwrap_err().to_string().contains("must be finite"));
    let loose = Mesh { positions: vec![Vec3::ZERO; 3], normals: vec![Vec3::Y; 3], indices: vec![0, 1, 5] };
    assert!(r.add_mesh(loose).unwrap_err().to_string().contains("past the 3 positions"));
    assert!(r.set_transform(glass, Mat4::ZERO).unwrap_err().to_string().contains("invertible"));
    let mut two_interface = r.settings().clone();
    two_interface.quality.transport = Transport::TwoInterface;
    r.set_settings(two_interface).unwrap();
    let e = r.add_instance(floor, "mirror", Material::Mirror, at(-0.5)).unwrap_err().to_string();
    assert!(e.contains("mirror") && e.contains("--transport exact"), "{e}");
    assert_eq!(r.scene().objects.len(), objects, "a refused instance leaves the scene as it was");
    assert_eq!(caustics::gpu::validation_message_count(), 0, "validation messages");
}

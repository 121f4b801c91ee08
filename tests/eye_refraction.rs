//! Eye-view deferred refraction against geometric optics, headless. A glass ball (R = 0.3 m, n = 1.5, center
//! 0.5 m above the floor) seen from straight above is a ball lens with focal length nR / (2(n - 1)) = 0.45 m from
//! its center: the floor 0.5 m below lies just beyond the focus, so the floor seen through the ball is inverted
//! and magnified (about 9x near the axis). A small black marker on the floor at (+2 cm, +1 cm), under the ball,
//! must therefore appear through the glass on the other side of the axis, several times farther out. The
//! expected image is computed by tracing the view rays through an exact sphere here, in f64.

mod common;
use caustics::settings::{Settings, Transport};
use common::*;

/// The tone-mapped beauty (8-bit sRGB RGBA, as the CLI writes it to a PNG) of the scene `text` (written as NAME.toml
/// in `dir`) through its `top` camera at `side`², level `level`, with the settings changed by `f`, rendered in
/// process on the shared device; validation stayed silent.
fn beauty(
    device: &std::sync::Arc<caustics::gpu::Device>,
    name: &str,
    text: &str,
    side: u32,
    level: u32,
    f: impl FnOnce(&mut Settings),
) -> (u32, u32, Vec<u8>) {
    let dir = out_dir(name);
    let scene = dir.join(format!("{name}.toml"));
    std::fs::write(&scene, text).unwrap();
    let settings = with(Settings::default(), |s| {
        s.quality.level = Some(level);
        f(s);
    });
    let mut r = renderer(device, scene.to_str().unwrap(), settings);
    camera_beauty(&mut r, "top", (side, side))
}

const SCENE: &str = r#"
# Lit from the side, so that the floor under the ball is in direct light (the ball's shadow falls near x = -1).
[[light]]
kind = "spot"
position = [3.0, 2.0, 0.0]
target = [0.0, 0.0, 0.0]
cone_deg = 30.0
intensity = 10.0

[[camera]]
name = "top"
kind = "orthographic"
position = [0.0, 3.0, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
half_height = 0.4

[[object]]
name = "floor"
shape = "plane"
size = [4.0, 4.0]
material = { kind = "diffuse", albedo = 0.8 }

[[object]]
name = "marker"
shape = "cube"
size = [0.01, 0.002, 0.01]
translate = [0.02, 0.001, 0.01]
material = { kind = "diffuse", albedo = 0.0 }

[[object]]
name = "ball"
shape = "sphere"
radius = 0.3
subdivisions = 6
translate = [0.0, 0.5, 0.0]
material = { kind = "dielectric", ior = 1.5 }
"#;

type V = [f64; 3];
fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn add(a: V, b: V, s: f64) -> V {
    [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]]
}
fn norm(a: V) -> V {
    let l = dot(a, a).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}
/// Refract d through normal n (facing d's origin side), eta = n_i / n_t.
fn refract(d: V, n: V, eta: f64) -> Option<V> {
    let c = -dot(d, n);
    let k = 1.0 - eta * eta * (1.0 - c * c);
    (k >= 0.0).then(|| norm(add([eta * d[0], eta * d[1], eta * d[2]], n, eta * c - k.sqrt())))
}

/// Where the vertical view ray at (x, z) lands on the floor after the exact ball; None if it misses the ball.
fn through_ball(x: f64, z: f64) -> Option<(f64, f64)> {
    let (c, r) = ([0.0, 0.5, 0.0], 0.3);
    let (o, d) = ([x, 3.0, z], [0.0, -1.0, 0.0]);
    let oc = add(o, c, -1.0);
    let b = dot(oc, d);
    let disc = b * b - (dot(oc, oc) - r * r);
    if disc <= 0.0 {
        return None;
    }
    let p1 = add(o, d, -b - disc.sqrt());
    let n1 = norm(add(p1, c, -1.0));
    let t1 = refract(d, n1, 1.0 / 1.5)?;
    // Second intersection from inside.
    let oc = add(p1, c, -1.0);
    let b = dot(oc, t1);
    let p2 = add(p1, t1, -b + (b * b - (dot(oc, oc) - r * r)).sqrt());
    let n2 = norm(add(p2, c, -1.0));
    let t2 = refract(t1, [-n2[0], -n2[1], -n2[2]], 1.5)?;
    if t2[1] >= 0.0 {
        return None;
    }
    let s = -p2[1] / t2[1];
    Some((p2[0] + s * t2[0], p2[2] + s * t2[2]))
}

#[test]
fn floor_seen_through_the_ball_is_inverted_and_magnified() {
    let (_gpu, device) = gpu();
    let (w, h, rgba) = beauty(&device, "eye_refraction", SCENE, 512, 3, |_| ());
    let (w, h) = (w as usize, h as usize);
    let m_per_px = 0.8 / w as f64; // the camera spans 0.8 m
    let pos = |i: usize, j: usize| ((i as f64 + 0.5) * m_per_px - 0.4, (j as f64 + 0.5) * m_per_px - 0.4);
    let lum = |i: usize, j: usize| {
        let p = &rgba[4 * (j * w + i)..];
        (p[0] as f64 + p[1] as f64 + p[2] as f64) / 3.0
    };
    // Expected: the screen points (inner 70% of the ball's disk) whose view ray lands on the marker.
    let inner = 0.7 * 0.3;
    let (mut ex, mut ez, mut en) = (0.0, 0.0, 0.0);
    let mut inside = Vec::new();
    for j in 0..h {
        for i in 0..w {
            let (x, z) = pos(i, j);
            if (x * x + z * z).sqrt() > inner {
                continue;
            }
            inside.push((i, j));
            if let Some((fx, fz)) = through_ball(x, z) {
                if (0.015..=0.025).contains(&fx) && (0.005..=0.015).contains(&fz) {
                    ex += x;
                    ez += z;
                    en += 1.0;
                }
            }
        }
    }
    assert!(en > 50.0, "the marker must be visible through the ball ({en} px)");
    let (ex, ez) = (ex / en, ez / en);
    // Observed: the dark pixels inside the disk (the marker has albedo 0; the lit floor around it is bright).
    let mut l: Vec<f64> = inside.iter().map(|&(i, j)| lum(i, j)).collect();
    l.sort_by(|a, b| a.total_cmp(b));
    let median = l[l.len() / 2];
    let (mut ox, mut oz, mut on) = (0.0, 0.0, 0.0);
    for &(i, j) in &inside {
        if lum(i, j) < 0.35 * median {
            let (x, z) = pos(i, j);
            ox += x;
            oz += z;
            on += 1.0;
        }
    }
    assert!(on > 0.0, "no dark marker image inside the ball");
    let (ox, oz) = (ox / on, oz / on);
    eprintln!("marker image: expected ({ex:.4}, {ez:.4}) m over {en} px, observed ({ox:.4}, {oz:.4}) m over {on} px");
    // Inverted: on the other side of the axis from the marker at (+0.02, +0.01).
    assert!(ox < 0.0 && oz < 0.0, "not inverted: ({ox}, {oz})");
    // Magnified: the image lies several times farther from the axis than the marker itself.
    assert!((ox * ox + oz * oz).sqrt() > 4.0 * (0.02f64.hypot(0.01)), "not magnified: ({ox}, {oz})");
    // Where the exact sphere puts it, to within 1 cm on screen (the ball is a tessellated, interpolated mesh
    // sampled through 512² eye-space buffers).
    assert!((ox - ex).hypot(oz - ez) < 0.01, "observed ({ox}, {oz}) vs expected ({ex}, {ez})");
    // And about as large: the area ratio of the dark region to the exact one within 40%.
    assert!((on / en - 1.0).abs() < 0.4, "image area {on} px vs expected {en} px");
}

/// Two glass balls in line (R = 0.12 m, n = 1.5, centers 0.7 m and 0.4 m above the floor), seen from straight
/// above: every view ray crosses four interfaces before it reaches the floor, which the two-surface deferred
/// refraction cannot follow. Exact transport traces the eye rays through the scene BVH; the marker's image must
/// lie where an exact trace through two exact spheres (here, in f64) puts it, within one pixel.
const TWO_BALLS: &str = r#"
[[light]]
kind = "spot"
position = [3.0, 2.0, 0.0]
target = [0.0, 0.0, 0.0]
cone_deg = 30.0
intensity = 10.0

[[camera]]
name = "top"
kind = "orthographic"
position = [0.0, 3.0, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
half_height = 0.15

[[object]]
name = "floor"
shape = "plane"
size = [4.0, 4.0]
material = { kind = "diffuse", albedo = 0.8 }

[[object]]
name = "marker"
shape = "cube"
size = [0.012, 0.002, 0.012]
translate = [0.02, 0.001, 0.01]
material = { kind = "diffuse", albedo = 0.0 }

[[object]]
name = "upper"
shape = "sphere"
radius = 0.12
subdivisions = 6
translate = [0.0, 0.7, 0.0]
material = { kind = "dielectric", ior = 1.5 }

[[object]]
name = "lower"
shape = "sphere"
radius = 0.12
subdivisions = 6
translate = [0.0, 0.4, 0.0]
material = { kind = "dielectric", ior = 1.5 }
"#;

/// Intersect the ray with a sphere: the entry (outside) or exit (inside) distance.
fn sphere_t(o: V, d: V, c: V, r: f64, inside: bool) -> Option<f64> {
    let oc = add(o, c, -1.0);
    let b = dot(oc, d);
    let disc = b * b - (dot(oc, oc) - r * r);
    if disc <= 0.0 {
        return None;
    }
    let t = if inside { -b + disc.sqrt() } else { -b - disc.sqrt() };
    (t > 1e-9).then_some(t)
}

/// Where the vertical view ray at (x, z) lands on the floor after both balls (refracted at all four interfaces).
fn through_two_balls(x: f64, z: f64) -> Option<(f64, f64)> {
    let (mut o, mut d) = ([x, 3.0, z], [0.0, -1.0, 0.0]);
    for c in [[0.0, 0.7, 0.0], [0.0, 0.4, 0.0]] {
        let r = 0.12;
        let p = add(o, d, sphere_t(o, d, c, r, false)?);
        d = refract(d, norm(add(p, c, -1.0)), 1.0 / 1.5)?;
        let q = add(p, d, sphere_t(p, d, c, r, true)?);
        let n = norm(add(q, c, -1.0));
        d = refract(d, [-n[0], -n[1], -n[2]], 1.5)?;
        o = q;
    }
    if d[1] >= 0.0 {
        return None;
    }
    let s = -o[1] / d[1];
    Some((o[0] + s * d[0], o[2] + s * d[2]))
}

#[test]
fn marker_through_two_balls_is_where_the_exact_trace_puts_it() {
    let (_gpu, device) = gpu();
    let size = 256usize;
    let (w, _, rgba) =
        beauty(&device, "eye_refraction_two_balls", TWO_BALLS, 256, 2, |s| s.quality.transport = Transport::Exact);
    assert_eq!(w as usize, size);
    let m_per_px = 0.3 / size as f64;
    let pos = |i: usize| (i as f64 + 0.5) * m_per_px - 0.15;
    let lum = |i: usize, j: usize| {
        let p = &rgba[4 * (j * size + i)..];
        (p[0] as f64 + p[1] as f64 + p[2] as f64) / 3.0
    };
    // The inner 70% of the balls' disk; the expected image samples each pixel 4x4 (the render's default
    // supersampling is 2x2: the centroids compare).
    let inner = 0.7 * 0.12;
    let (mut ex, mut ez, mut en) = (0.0, 0.0, 0.0);
    let mut inside = Vec::new();
    for j in 0..size {
        for i in 0..size {
            if pos(i).hypot(pos(j)) > inner {
                continue;
            }
            inside.push((i, j));
            for (si, sj) in (0..16).map(|k| (k % 4, k / 4)) {
                let x = pos(i) + (si as f64 - 1.5) / 4.0 * m_per_px;
                let z = pos(j) + (sj as f64 - 1.5) / 4.0 * m_per_px;
                if let Some((fx, fz)) = through_two_balls(x, z) {
                    if (0.014..=0.026).contains(&fx) && (0.004..=0.016).contains(&fz) {
                        ex += x;
                        ez += z;
                        en += 1.0 / 16.0;
                    }
                }
            }
        }
    }
    assert!(en > 30.0, "the marker must be visible through both balls ({en} px)");
    let (ex, ez) = (ex / 16.0 / en, ez / 16.0 / en);
    let mut l: Vec<f64> = inside.iter().map(|&(i, j)| lum(i, j)).collect();
    l.sort_by(|a, b| a.total_cmp(b));
    let median = l[l.len() / 2];
    // Darkness-weighted centroid of the marker's image (partly covered pixels count in part).
    let (mut ox, mut oz, mut on) = (0.0, 0.0, 0.0);
    for &(i, j) in &inside {
        let dark = ((median - lum(i, j)) / median).clamp(0.0, 1.0);
        if dark > 0.5 {
            ox += dark * pos(i);
            oz += dark * pos(j);
            on += dark;
        }
    }
    assert!(on > 0.0, "no dark marker image inside the balls");
    let (ox, oz) = (ox / on, oz / on);
    let err_px = (ox - ex).hypot(oz - ez) / m_per_px;
    eprintln!(
        "marker image: expected ({ex:.4}, {ez:.4}) m over {en:.1} px, observed ({ox:.4}, {oz:.4}) m over {on:.1} \
         px: {err_px:.2} px apart"
    );
    // Inverted by the pair (on the other side of the axis from the marker at (+0.02, +0.01)).
    assert!(ox < 0.0 && oz < 0.0, "not inverted: ({ox}, {oz})");
    assert!(err_px <= 1.0, "the marker's image is {err_px:.2} px from the exact trace's");
    assert!((on / en - 1.0).abs() < 0.4, "image area {on:.1} px vs expected {en:.1} px");
}

/// A caustic seen in a flat mirror is the caustic seen directly (assets/scenes/mirror_wall.toml): the `mirror`
/// camera's linear beauty where its rays meet the mirror first and, reflected, meet no glass, against the `behind`
/// camera's (its image in the mirror's plane) at the same points, in the scene without the mirror. The eye view
/// reaches the floor through the mirror in the glass pass, which reads the light's caustic map there; the direct
/// view shades it in the eye shading. Measured at 200×150, level 3 on lavapipe: rel-L1 0.27%, flux ratio 0.99905
/// over 3,858 pixels, whose brightest (the ring) are 10 times their median. Allowed: 2% and 1%.
#[test]
fn a_caustic_seen_in_a_mirror_is_the_caustic_seen_directly() {
    use caustics::settings::Metric;
    use glam::{Vec2, Vec3};
    const SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/mirror_wall.toml");
    let (w, h) = (200u32, 150u32);
    let dir = out_dir("mirror_wall");
    let text = std::fs::read_to_string(SCENE).unwrap();
    let without = dir.join("without.toml");
    std::fs::write(&without, &text[..text.rfind("[[object]]").unwrap()]).unwrap();
    let (_gpu, device) = gpu();
    let settings = || with(adaptive(3, Metric::FluxError), |s| s.quality.transport = Transport::Exact);
    let mut a = renderer(&device, SCENE, settings());
    let (img_a, _) = camera_aov(&mut a, "mirror", (w, h), caustics::Aov::BeautyHdr);
    let mut b = renderer(&device, without.to_str().unwrap(), settings());
    let (img_b, _) = camera_aov(&mut b, "behind", (w, h), caustics::Aov::BeautyHdr);
    let view_a = a.camera_view(&a.scene().camera(Some("mirror")).unwrap().clone(), w, h);
    let view_b = b.camera_view(&b.scene().camera(Some("behind")).unwrap().clone(), w, h);
    // The mirror: z = -0.9, |x| <= 0.8, 0 <= y <= 1, kept 3 cm from its edges; the ball, with 3 cm to spare.
    let (ball, r) = (Vec3::new(0.0, 0.5, 0.0), 0.33f32);
    let meets_ball = |o: Vec3, d: Vec3, t_max: f32| {
        let oc = o - ball;
        let (bq, c) = (oc.dot(d), oc.length_squared() - r * r);
        let disc = bq * bq - c;
        disc >= 0.0 && -bq + disc.sqrt() > 0.0 && -bq - disc.sqrt() < t_max
    };
    let seen_in_mirror = |px: Vec2| -> Option<Vec3> {
        let (o, d) = view_a.ray(px);
        let t = (-0.9 - o.z) / d.z;
        let p = o + d * t;
        let inside = t > 0.0 && p.x.abs() < 0.77 && p.y > 0.03 && p.y < 0.97;
        let reflected = Vec3::new(d.x, d.y, -d.z);
        (inside && !meets_ball(o, d, t) && !meets_ball(p, reflected, f32::INFINITY)).then_some(p)
    };
    let (mut diff, mut sum_a, mut sum_b, mut n) = (0.0f64, 0.0f64, 0.0f64, 0usize);
    let mut seen = Vec::new();
    for y in 0..h {
        for x in 0..w {
            // Every corner of the pixel, so that no pixel straddles an edge.
            let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)];
            if !corners.iter().all(|&(u, v)| seen_in_mirror(Vec2::new(x as f32 + u, y as f32 + v)).is_some()) {
                continue;
            }
            let p = seen_in_mirror(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)).unwrap();
            let q = view_b.project(p).expect("the mirror's plane lies in front of `behind`");
            let (qx, qy) = (q.x.floor() as i64, q.y.floor() as i64);
            if qx < 0 || qy < 0 || qx >= w as i64 || qy >= h as i64 {
                continue;
            }
            let pa = img_a.data[(y * w + x) as usize];
            let pb = img_b.data[(qy as u32 * w + qx as u32) as usize];
            seen.push(pb[1]);
            for c in 0..3 {
                diff += (pa[c] as f64 - pb[c] as f64).abs();
                sum_a += pa[c] as f64;
                sum_b += pb[c] as f64;
            }
            n += 1;
        }
    }
    let (rel, ratio) = (diff / sum_b, sum_a / sum_b);
    eprintln!("caustic in a mirror: rel-L1 {rel:.4}, flux ratio {ratio:.5} over {n} pixels");
    assert!(n > 3000, "{n} pixels see the floor in the mirror");
    // They hold the caustic: its ring is far brighter than the floor's median.
    seen.sort_by(f32::total_cmp);
    let (median, top) = (seen[seen.len() / 2], seen[seen.len() * 99 / 100]);
    eprintln!("the floor in the mirror: median {median}, 99th percentile {top}");
    assert!(top > 3.0 * median, "median {median}, 99th percentile {top}");
    assert!(rel < 0.02 && (ratio - 1.0).abs() < 0.01, "rel-L1 {rel}, flux ratio {ratio}");
}

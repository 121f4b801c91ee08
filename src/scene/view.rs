//! Light and camera views: the light-space parametrization that photons, the caustic map and the shadow map
//! share, and the eye camera. Everything the shaders compute from these comes from the same numbers (see
//! `glsl/common/view.glsl`), so the Rust and GLSL sides agree to float rounding.
//!
//! Light image coordinates: a spot light's image plane sits at distance 1 along its forward axis, so the point
//! (x, y) on it is the direction x·right + y·down + forward. A directional light's image coordinates are meters
//! across the beam. A square [`Window`] of that plane is mapped to uv ∈ [0, 1]², columns along `right` and rows
//! along `down`.

use super::{Camera, Light, LightKind, Projection};
use glam::{Mat4, Vec2, Vec3};

/// A square window of the light's image plane: [x0, x0 + w] × [y0, y0 + w].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    /// Left edge.
    pub x0: f32,
    /// Top edge.
    pub y0: f32,
    /// Side.
    pub w: f32,
}

#[derive(Clone, Copy, Debug)]
/// A light's view: its image plane at distance 1 and the window of it a map covers (a directional light's
/// is parallel).
pub struct LightView {
    /// The light's kind.
    pub kind: LightKind,
    /// The light's position.
    pub origin: Vec3,
    /// The image plane's right axis.
    pub right: Vec3,
    /// The image plane's down axis.
    pub down: Vec3,
    /// The light's axis.
    pub forward: Vec3,
    /// The window the map covers.
    pub window: Window,
    /// Near plane distance.
    pub near: f32,
    /// Far plane distance.
    pub far: f32,
    /// Cosine of the cone half-angle (spot); -1 for directional lights.
    pub cos_cone: f32,
    /// A face of a point light's cube ([`LightView::cube_face`]): the view's domain is the square |x|, |y| ≤ 1 of
    /// its image plane, and it lights, emits and deposits only there.
    pub face: bool,
}

/// What kind of emitter a light view is (glsl/common/emitter.glsl, docs/design.md "Emitters and deposits"): what
/// its photons' refinement domain, cell measure and rays are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmitterKind {
    /// A directional light: parallel rays over the window, a cell's measure its area across the beam (m²).
    Beam,
    /// A point light whose objects all lie in front of it: rays from its position over the whole window.
    Open,
    /// A spot light: rays from its position within its cone.
    Cone,
    /// A face of a point light's cube: rays from its position through the square |x|, |y| ≤ 1 of the image plane.
    Square,
}

impl EmitterKind {
    /// The GPU view's lanes that say the kind, as glsl/common/emitter.glsl's `emitter_kind` reads them:
    /// `origin.w` (1: orthographic) and `right.w` (the cone's cosine; -1: no cone; `VIEW_SQUARE_DOMAIN`: a face).
    pub fn lanes(self, cos_cone: f32) -> (f32, f32) {
        match self {
            EmitterKind::Beam => (1.0, -1.0),
            EmitterKind::Open => (0.0, -1.0),
            EmitterKind::Cone => (0.0, cos_cone),
            EmitterKind::Square => (0.0, crate::shaders::consts::VIEW_SQUARE_DOMAIN as f32),
        }
    }
}

/// The six faces of a point light's cube, in the light's frame (right, down, forward), each as the frame of a
/// 90° view (right', down', forward') with right' × down' = forward': +forward, −forward, +right, −right, +down,
/// −down.
pub const CUBE_FACES: usize = 6;

fn rows_to_mat(rows: [[f32; 4]; 4]) -> Mat4 {
    Mat4::from_cols_array_2d(&rows).transpose()
}

impl LightView {
    /// The emitter this view is.
    pub fn emitter_kind(&self) -> EmitterKind {
        match self.kind {
            LightKind::Directional => EmitterKind::Beam,
            _ if self.face => EmitterKind::Square,
            LightKind::Spot => EmitterKind::Cone,
            LightKind::Point => EmitterKind::Open,
        }
    }

    /// The light's orthonormal frame (right, down, forward), right-handed: right × down = forward.
    pub fn basis(light: &Light) -> (Vec3, Vec3, Vec3) {
        let f = (light.target - light.position).normalize();
        let hint = if f.dot(Vec3::Y).abs() > 0.99 { Vec3::NEG_Z } else { Vec3::Y };
        let right = f.cross(hint).normalize();
        let down = f.cross(right).normalize();
        (right, down, f)
    }

    fn frame(light: &Light) -> LightView {
        let (right, down, forward) = Self::basis(light);
        LightView {
            kind: light.kind,
            origin: light.position,
            right,
            down,
            forward,
            window: Window { x0: -1.0, y0: -1.0, w: 2.0 },
            near: 0.01,
            far: 100.0,
            cos_cone: if light.kind == LightKind::Spot { light.cone.cos() } else { -1.0 },
            face: false,
        }
    }

    /// Face `k` (0..[`CUBE_FACES`]) of point light `light`'s cube: a 90° view whose window is its whole square
    /// (near and far planes still to fit: [`LightView::fit_face`]).
    pub fn cube_face(light: &Light, k: usize) -> LightView {
        let (r, d, f) = Self::basis(light);
        let (right, down, forward) = [(r, d, f), (-r, d, -f), (d, f, r), (-d, f, -r), (f, r, d), (-f, r, -d)][k];
        LightView { right, down, forward, face: true, ..Self::frame(light) }
    }

    /// The parts of a mesh (`positions`, three `indices` per triangle) inside this face's frustum (|x|, |y| ≤ 1 on
    /// its image plane, in front of the light): the image-plane points and depths of the corners of the
    /// triangles clipped to it, appended to `out`. A mesh wholly inside adds its vertices; wholly outside one
    /// plane, nothing.
    pub fn face_points(&self, positions: &[Vec3], indices: &[u32], out: &mut Vec<(Vec2, f32)>) {
        self.pyramid_points(1.0, positions, indices, out)
    }

    /// Whether some triangle of a mesh reaches into spot light `light`'s cone (conservatively: the square pyramid
    /// around it).
    pub fn spot_reaches(light: &Light, positions: &[Vec3], indices: &[u32]) -> bool {
        let mut out = Vec::new();
        Self::frame(light).pyramid_points(light.cone.tan(), positions, indices, &mut out);
        !out.is_empty()
    }

    /// [`LightView::face_points`] for the pyramid |x|, |y| ≤ `half` of the image plane.
    fn pyramid_points(&self, half: f32, positions: &[Vec3], indices: &[u32], out: &mut Vec<(Vec2, f32)>) {
        let local = |p: Vec3| {
            let d = p - self.origin;
            Vec3::new(d.dot(self.right), d.dot(self.down), d.dot(self.forward))
        };
        // Inside where every one of these is >= 0 (the last keeps the depth positive).
        let planes = |v: Vec3| {
            let h = v.z * half;
            [h - v.x, h + v.x, h - v.y, h + v.y, v.z - 1e-6]
        };
        let project = |v: Vec3| (Vec2::new(v.x / v.z, v.y / v.z).clamp(Vec2::splat(-half), Vec2::splat(half)), v.z);
        let pts: Vec<Vec3> = positions.iter().map(|&p| local(p)).collect();
        let mut all_in = true;
        let mut out_of = [true; 5];
        for v in &pts {
            let g = planes(*v);
            all_in &= g.iter().all(|&x| x >= 0.0);
            for (o, x) in out_of.iter_mut().zip(g) {
                *o &= x < 0.0;
            }
        }
        if out_of.iter().any(|&o| o) {
            return;
        }
        if all_in {
            out.extend(pts.iter().map(|&v| project(v)));
            return;
        }
        let mut poly = Vec::with_capacity(9);
        let mut next = Vec::with_capacity(9);
        for t in indices.chunks_exact(3) {
            poly.clear();
            poly.extend(t.iter().map(|&i| pts[i as usize]));
            for k in 0..5 {
                next.clear();
                for (j, &a) in poly.iter().enumerate() {
                    let b = poly[(j + 1) % poly.len()];
                    let (ga, gb) = (planes(a)[k], planes(b)[k]);
                    if ga >= 0.0 {
                        next.push(a);
                    }
                    if (ga >= 0.0) != (gb >= 0.0) {
                        next.push(a + (b - a) * (ga / (ga - gb)));
                    }
                }
                std::mem::swap(&mut poly, &mut next);
                if poly.is_empty() {
                    break;
                }
            }
            out.extend(poly.iter().map(|&v| project(v)));
        }
    }

    /// This face with its window fitted around `points` (image-plane points and depths from
    /// [`LightView::face_points`]), padded by `pad_texels` texels of a `resolution`² map and kept inside the
    /// face's square, and near and far planes around `depths`. `points` empty: the whole square. None when
    /// `depths` is empty.
    pub fn fit_face(
        mut self,
        points: &[(Vec2, f32)],
        depths: &[(Vec2, f32)],
        resolution: u32,
        pad_texels: f32,
    ) -> Option<LightView> {
        let (dmin, dmax) = depths.iter().fold((f32::INFINITY, 0.0f32), |(a, b), &(_, c)| (a.min(c), b.max(c)));
        if depths.is_empty() || dmax <= 0.0 {
            return None;
        }
        if !points.is_empty() {
            let lo = points.iter().fold(Vec2::ONE, |a, &(p, _)| a.min(p));
            let hi = points.iter().fold(Vec2::NEG_ONE, |a, &(p, _)| a.max(p));
            let half = ((hi - lo) * 0.5).max_element().max(1e-6);
            let half = (half * (1.0 + 2.0 * pad_texels / resolution as f32) + 1e-7).min(1.0);
            let center = ((lo + hi) * 0.5).clamp(Vec2::splat(half - 1.0), Vec2::splat(1.0 - half));
            self.window = Window { x0: center.x - half, y0: center.y - half, w: 2.0 * half };
        }
        self.far = dmax * 1.05 + 1e-3;
        self.near = (dmin * 0.5).max(self.far * 1e-4);
        Some(self)
    }

    /// (x, y) on the image plane and the depth along `forward`.
    pub fn image_coords(&self, p: Vec3) -> (Vec2, f32) {
        let d = p - self.origin;
        let (a, b, c) = (d.dot(self.right), d.dot(self.down), d.dot(self.forward));
        match self.kind {
            LightKind::Spot | LightKind::Point => (Vec2::new(a / c, b / c), c),
            LightKind::Directional => (Vec2::new(a, b), c),
        }
    }

    /// Where `p` lies on the image plane.
    pub fn uv(&self, p: Vec3) -> Vec2 {
        let (xy, _) = self.image_coords(p);
        (xy - Vec2::new(self.window.x0, self.window.y0)) / self.window.w
    }

    /// The ray through uv: origin and unit direction.
    pub fn ray(&self, uv: Vec2) -> (Vec3, Vec3) {
        let x = self.window.x0 + uv.x * self.window.w;
        let y = self.window.y0 + uv.y * self.window.w;
        match self.kind {
            LightKind::Spot | LightKind::Point => {
                (self.origin, (self.right * x + self.down * y + self.forward).normalize())
            }
            LightKind::Directional => (self.origin + self.right * x + self.down * y, self.forward),
        }
    }

    /// World → clip (Vulkan conventions: NDC x, y ∈ [-1, 1] with +y = +v (down), z ∈ [0, 1]).
    pub fn view_proj(&self) -> Mat4 {
        let (u, v, f, l) = (self.right, self.down, self.forward, self.origin);
        let view = rows_to_mat([
            [u.x, u.y, u.z, -u.dot(l)],
            [v.x, v.y, v.z, -v.dot(l)],
            [f.x, f.y, f.z, -f.dot(l)],
            [0.0, 0.0, 0.0, 1.0],
        ]);
        let Window { x0, y0, w } = self.window;
        let (n, fa) = (self.near, self.far);
        let proj = match self.kind {
            LightKind::Spot | LightKind::Point => rows_to_mat([
                [2.0 / w, 0.0, -(2.0 * x0 + w) / w, 0.0],
                [0.0, 2.0 / w, -(2.0 * y0 + w) / w, 0.0],
                [0.0, 0.0, fa / (fa - n), -fa * n / (fa - n)],
                [0.0, 0.0, 1.0, 0.0],
            ]),
            LightKind::Directional => rows_to_mat([
                [2.0 / w, 0.0, 0.0, -(2.0 * x0 + w) / w],
                [0.0, 2.0 / w, 0.0, -(2.0 * y0 + w) / w],
                [0.0, 0.0, 1.0 / (fa - n), -n / (fa - n)],
                [0.0, 0.0, 0.0, 1.0],
            ]),
        };
        proj * view
    }

    /// The square bounding the spot cone on the image plane, if any.
    fn cone_square(&self) -> Option<(Vec2, Vec2)> {
        (self.kind == LightKind::Spot).then(|| {
            let t = self.cos_cone.acos().tan();
            (Vec2::splat(-t), Vec2::splat(t))
        })
    }

    /// Fit a square window around `points` (clipped to the cone), padded by `pad_texels` texels of a
    /// `resolution`² map, with near/far planes around `depth_points`. Points behind a spot light make the window
    /// the whole cone. Returns None when nothing of `points` lies inside the cone.
    pub fn fit(
        light: &Light,
        points: impl Iterator<Item = Vec3>,
        depth_points: impl Iterator<Item = Vec3>,
        resolution: u32,
        pad_texels: f32,
    ) -> Option<LightView> {
        let mut view = Self::frame(light);
        let mut lo = Vec2::splat(f32::INFINITY);
        let mut hi = Vec2::splat(f32::NEG_INFINITY);
        let mut behind = false;
        for p in points {
            let (xy, c) = view.image_coords(p);
            if view.kind != LightKind::Directional && c <= 1e-6 {
                behind = true;
                continue;
            }
            lo = lo.min(xy);
            hi = hi.max(xy);
        }
        if behind && view.kind == LightKind::Point {
            return None;
        }
        if let Some((clo, chi)) = view.cone_square() {
            if behind {
                lo = clo;
                hi = chi;
            }
            lo = lo.max(clo);
            hi = hi.min(chi);
        }
        if !(lo.x <= hi.x && lo.y <= hi.y) {
            return None;
        }
        let center = (lo + hi) * 0.5;
        let half = ((hi - lo) * 0.5).max_element().max(1e-6);
        let half = half * (1.0 + 2.0 * pad_texels / resolution as f32) + 1e-7;
        view.window = Window { x0: center.x - half, y0: center.y - half, w: 2.0 * half };
        let (mut dmin, mut dmax) = (f32::INFINITY, 0.0f32);
        for p in depth_points {
            let (_, c) = view.image_coords(p);
            dmin = dmin.min(c);
            dmax = dmax.max(c);
        }
        if !dmax.is_finite() || dmax <= 0.0 {
            dmax = 1.0;
        }
        view.far = dmax * 1.05 + 1e-3;
        view.near = match view.kind {
            LightKind::Spot | LightKind::Point => (dmin * 0.5).max(view.far * 1e-4),
            LightKind::Directional => dmin.min(0.0) - 1e-3,
        };
        Some(view)
    }
}

/// The eye camera for a given output size.
#[derive(Clone, Copy, Debug)]
pub struct CameraView {
    /// The camera's position.
    pub position: Vec3,
    /// Its right axis.
    pub right: Vec3,
    /// Its up axis.
    pub up: Vec3,
    /// Its viewing direction.
    pub forward: Vec3,
    /// Its projection.
    pub projection: Projection,
    /// Output width in pixels.
    pub width: u32,
    /// Output height in pixels.
    pub height: u32,
    /// Near plane distance.
    pub near: f32,
    /// Far plane distance.
    pub far: f32,
}

impl CameraView {
    /// The view of `camera` at `width`×`height`, its depth range fitted to `bounds`.
    pub fn new(camera: &Camera, width: u32, height: u32, bounds: (Vec3, Vec3)) -> Self {
        let forward = (camera.target - camera.position).normalize();
        let right = forward.cross(camera.up).normalize();
        let up = right.cross(forward);
        let mut view = CameraView {
            position: camera.position,
            right,
            up,
            forward,
            projection: camera.projection,
            width,
            height,
            near: 0.01,
            far: 100.0,
        };
        view.fit_depth(bounds);
        view
    }

    /// Fit the near and far planes to `bounds`.
    pub fn fit_depth(&mut self, (lo, hi): (Vec3, Vec3)) {
        let (mut dmin, mut dmax) = (f32::INFINITY, f32::NEG_INFINITY);
        for c in super::mesh::box_corners((lo, hi)) {
            let d = (c - self.position).dot(self.forward);
            dmin = dmin.min(d);
            dmax = dmax.max(d);
        }
        let span = (dmax - dmin).max(1e-3);
        match self.projection {
            // The eye sees what lies in front of it: an orthographic camera inside a room looks at the wall ahead,
            // not at the back of the one behind it (the reference's visibility rays end at the eye too).
            Projection::Orthographic { .. } => {
                self.near = (dmin - 0.05 * span).max(0.0);
                self.far = (dmax + 0.05 * span).max(self.near + 1e-3);
            }
            Projection::Perspective { .. } => {
                self.far = dmax.max(1e-2) * 1.05;
                self.near = (dmin * 0.9).max(self.far * 1e-4);
            }
        }
    }

    /// Width over height.
    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height as f32
    }

    /// Half extents of the image at distance 1 (perspective) or in meters (orthographic).
    pub fn half_extents(&self) -> Vec2 {
        let hh = match self.projection {
            Projection::Orthographic { half_height } => half_height,
            Projection::Perspective { fov } => (fov * 0.5).tan(),
        };
        Vec2::new(hh * self.aspect(), hh)
    }

    /// The view-projection matrix (Vulkan clip space).
    pub fn view_proj(&self) -> Mat4 {
        let (r, u, f, p) = (self.right, self.up, self.forward, self.position);
        // Camera frame with +y down so that image row 0 is the top (Vulkan NDC).
        let view = rows_to_mat([
            [r.x, r.y, r.z, -r.dot(p)],
            [-u.x, -u.y, -u.z, u.dot(p)],
            [f.x, f.y, f.z, -f.dot(p)],
            [0.0, 0.0, 0.0, 1.0],
        ]);
        let h = self.half_extents();
        let (n, fa) = (self.near, self.far);
        let proj = match self.projection {
            Projection::Perspective { .. } => rows_to_mat([
                [1.0 / h.x, 0.0, 0.0, 0.0],
                [0.0, 1.0 / h.y, 0.0, 0.0],
                [0.0, 0.0, fa / (fa - n), -fa * n / (fa - n)],
                [0.0, 0.0, 1.0, 0.0],
            ]),
            Projection::Orthographic { .. } => rows_to_mat([
                [1.0 / h.x, 0.0, 0.0, 0.0],
                [0.0, 1.0 / h.y, 0.0, 0.0],
                [0.0, 0.0, 1.0 / (fa - n), -n / (fa - n)],
                [0.0, 0.0, 0.0, 1.0],
            ]),
        };
        proj * view
    }

    /// Continuous pixel coordinates (x right, y down) of a world point, if it is in front of the camera.
    pub fn project(&self, p: Vec3) -> Option<Vec2> {
        let d = p - self.position;
        let z = d.dot(self.forward);
        let h = self.half_extents();
        let (x, y) = match self.projection {
            Projection::Orthographic { .. } => (d.dot(self.right), d.dot(self.up)),
            Projection::Perspective { .. } => {
                if z <= 0.0 {
                    return None;
                }
                (d.dot(self.right) / z, d.dot(self.up) / z)
            }
        };
        Some(Vec2::new((x / h.x + 1.0) * 0.5 * self.width as f32, (1.0 - y / h.y) * 0.5 * self.height as f32))
    }

    /// Ray through continuous pixel coordinates.
    pub fn ray(&self, px: Vec2) -> (Vec3, Vec3) {
        let h = self.half_extents();
        let x = (px.x / self.width as f32 * 2.0 - 1.0) * h.x;
        let y = (1.0 - px.y / self.height as f32 * 2.0) * h.y;
        match self.projection {
            Projection::Orthographic { .. } => (self.position + self.right * x + self.up * y, self.forward),
            Projection::Perspective { .. } => {
                (self.position, (self.right * x + self.up * y + self.forward).normalize())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spot() -> Light {
        Light {
            kind: LightKind::Spot,
            position: Vec3::new(0.0, 2.0, 0.0),
            target: Vec3::new(0.0, 0.5, 0.0),
            cone: 40f32.to_radians(),
            intensity: 1.0,
            color: Vec3::ONE,
            angular_radius: 0.0,
            radius: 0.0,
        }
    }

    #[test]
    fn light_basis_matches_top_camera_axes() {
        let (r, d, f) = LightView::basis(&spot());
        assert!((r - Vec3::X).length() < 1e-6 && (d - Vec3::Z).length() < 1e-6 && (f - Vec3::NEG_Y).length() < 1e-6);
    }

    #[test]
    fn view_proj_agrees_with_uv_and_ray() {
        let pts = [Vec3::new(0.3, 0.5, 0.1), Vec3::new(-0.3, 0.2, -0.2)];
        let v = LightView::fit(&spot(), pts.iter().copied(), pts.iter().copied(), 1024, 1.0).unwrap();
        for p in pts {
            let clip = v.view_proj() * p.extend(1.0);
            let ndc = clip.truncate() / clip.w;
            let uv = v.uv(p);
            assert!((ndc.x - (uv.x * 2.0 - 1.0)).abs() < 1e-5 && (ndc.y - (uv.y * 2.0 - 1.0)).abs() < 1e-5);
            assert!(ndc.z > 0.0 && ndc.z < 1.0);
            let (o, dir) = v.ray(uv);
            assert!(((p - o).normalize() - dir).length() < 1e-5);
        }
    }

    #[test]
    fn camera_projection_roundtrip() {
        let cam = Camera {
            name: "top".into(),
            projection: Projection::Orthographic { half_height: 1.0 },
            position: Vec3::new(0.0, 3.0, 0.0),
            target: Vec3::ZERO,
            up: Vec3::NEG_Z,
            aspect: None,
        };
        let v = CameraView::new(&cam, 256, 256, (Vec3::splat(-1.0), Vec3::splat(1.0)));
        // Row 0 is z = -1 and columns run along +x (docs/design.md's `top` camera).
        let px = v.project(Vec3::new(-1.0, 0.0, -1.0)).unwrap();
        assert!(px.length() < 1e-4, "{px}");
        let px = v.project(Vec3::new(1.0, 0.0, 1.0)).unwrap();
        assert!((px - Vec2::splat(256.0)).length() < 1e-3);
        let clip = v.view_proj() * Vec3::new(0.5, 0.0, -0.5).extend(1.0);
        let want = v.project(Vec3::new(0.5, 0.0, -0.5)).unwrap() / 128.0 - Vec2::ONE;
        assert!((clip.truncate().truncate() / clip.w - want).length() < 1e-5);
    }

    fn point() -> Light {
        Light {
            kind: LightKind::Point,
            position: Vec3::new(0.1, 1.0, 0.2),
            target: Vec3::new(0.3, 0.0, -0.1),
            ..spot()
        }
    }

    /// Each face is a right-handed orthonormal frame, and the six squares hold every direction exactly once (away
    /// from the seams).
    #[test]
    fn cube_faces_partition_the_sphere() {
        let faces: Vec<LightView> = (0..CUBE_FACES).map(|k| LightView::cube_face(&point(), k)).collect();
        for f in &faces {
            assert!((f.right.cross(f.down) - f.forward).length() < 1e-6 && f.face);
        }
        let mut seed = 12345u32;
        let mut rnd = || {
            seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
            (seed >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
        };
        for _ in 0..2000 {
            let d = Vec3::new(rnd(), rnd(), rnd());
            if d.length() < 0.1 {
                continue;
            }
            let inside = faces
                .iter()
                .filter(|f| {
                    let (xy, c) = f.image_coords(f.origin + d);
                    c > 0.0 && xy.abs().max_element() < 1.0
                })
                .count();
            assert_eq!(inside, 1, "{d}");
        }
    }

    /// A triangle through a face's frustum is clipped to it; one behind the light, or beside the frustum, adds
    /// nothing; one inside adds its corners.
    #[test]
    fn face_points_clip_to_the_frustum() {
        let f = LightView::cube_face(&point(), 0);
        let at = |x: f32, y: f32, c: f32| f.origin + f.right * x + f.down * y + f.forward * c;
        let mut out = Vec::new();
        f.face_points(&[at(-5.0, 0.0, 1.0), at(5.0, -0.5, 1.0), at(0.0, 5.0, 1.0)], &[0, 1, 2], &mut out);
        assert!(out.len() >= 3 && out.iter().all(|(xy, c)| xy.abs().max_element() <= 1.0 && *c > 0.0), "{out:?}");
        assert!(
            out.iter().any(|(xy, _)| (xy.x - 1.0).abs() < 1e-5) && out.iter().any(|(xy, _)| (xy.y - 1.0).abs() < 1e-5)
        );
        let mut none = Vec::new();
        f.face_points(&[at(0.0, 0.0, -1.0), at(1.0, 0.0, -1.0), at(0.0, 1.0, -2.0)], &[0, 1, 2], &mut none);
        f.face_points(&[at(3.0, 0.0, 1.0), at(4.0, 0.0, 1.0), at(3.5, 0.5, 2.0)], &[0, 1, 2], &mut none);
        assert!(none.is_empty(), "{none:?}");
        let mut inside = Vec::new();
        f.face_points(&[at(0.1, 0.1, 1.0), at(0.2, 0.1, 1.0), at(0.1, 0.3, 2.0)], &[0, 1, 2], &mut inside);
        assert_eq!(inside.len(), 3);
        let fitted = f.fit_face(&inside, &inside, 64, 1.0).unwrap();
        let w = fitted.window;
        assert!(w.x0 >= -1.0 && w.y0 >= -1.0 && w.x0 + w.w <= 1.0 && w.y0 + w.w <= 1.0, "{w:?}");
    }
}

//! The BVH walked on the host, in f32 as the GPU walks it: the tests check every flattened layout against brute
//! force with it.

use super::*;

impl SceneBvh {
    #[cfg(test)]
    /// The GPU's closest-hit query in f32, on the host (tests check the flattened layouts against brute force):
    /// (t, instance, triangle) of the nearest hit with 0 < t < `tmax`.
    pub fn intersect(&self, layout: BvhLayout, o: Vec3, d: Vec3, tmax: f32) -> Option<(f32, u32, u32)> {
        let mut best: Option<(f32, u32, u32)> = None;
        let mut t_best = tmax;
        for (ii, inst) in self.instances.iter().enumerate() {
            let (lo, hi) = (Vec3::from_slice(&inst.lo[..3]), Vec3::from_slice(&inst.hi[..3]));
            if slab(lo, hi, o, d.recip(), t_best).is_none() {
                continue;
            }
            let m = |r: [f32; 4], v: Vec3, w: f32| r[0] * v.x + r[1] * v.y + r[2] * v.z + r[3] * w;
            let of = &inst.object_from_world;
            let lo_ = Vec3::new(m(of[0], o, 1.0), m(of[1], o, 1.0), m(of[2], o, 1.0));
            let ld = Vec3::new(m(of[0], d, 0.0), m(of[1], d, 0.0), m(of[2], d, 0.0));
            let root = match layout {
                BvhLayout::Pair | BvhLayout::Auto => inst.lo[3],
                BvhLayout::Single => inst.hi[3],
                BvhLayout::Threaded => inst.pad[0],
                BvhLayout::Wide => inst.ior_rgb[3],
            }
            .to_bits();
            let mut visit = |first: u32, count: u32, t_best: &mut f32| {
                for tri in first..first + count {
                    let p = self.triangles[tri as usize].p.map(|v| Vec3::from_slice(&v[..3]));
                    if let Some(t) = watertight(lo_, ld, &p) {
                        if t < *t_best {
                            *t_best = t;
                            best = Some((t, ii as u32, tri));
                        }
                    }
                }
            };
            let inv = ld.recip();
            let mut stack = vec![root];
            match layout {
                BvhLayout::Pair | BvhLayout::Auto => {
                    while let Some(n) = stack.pop() {
                        let node = &self.pair_nodes[n as usize];
                        for (lo, hi) in [(node.lo0, node.hi0), (node.lo1, node.hi1)] {
                            let (idx, count) = (lo[3].to_bits(), hi[3].to_bits());
                            if idx == EMPTY && count == 0 {
                                continue;
                            }
                            let (l, h) = (Vec3::from_slice(&lo[..3]), Vec3::from_slice(&hi[..3]));
                            if slab(l, h, lo_, inv, t_best).is_none() {
                                continue;
                            }
                            if count > 0 {
                                visit(idx, count, &mut t_best);
                            } else {
                                stack.push(idx);
                            }
                        }
                    }
                }
                BvhLayout::Threaded => {
                    let mut n = root;
                    while n != EMPTY {
                        let node = &self.threaded_nodes[n as usize];
                        let (l, h) = (Vec3::from_slice(&node.lo[..3]), Vec3::from_slice(&node.hi[..3]));
                        let escape = node.lo[3].to_bits();
                        if slab(l, h, lo_, inv, t_best).is_some() {
                            let info = node.hi[3].to_bits();
                            if info >> 29 > 0 {
                                visit(info & 0x1FFF_FFFF, info >> 29, &mut t_best);
                                n = escape;
                            } else {
                                n += 1;
                            }
                        } else {
                            n = escape;
                        }
                    }
                }
                BvhLayout::Wide => {
                    while let Some(n) = stack.pop() {
                        let w = &self.wide_nodes[n as usize].words();
                        let imask = w[3] >> 24;
                        for c in 0..8 {
                            let meta = wide_byte(w, 6, c);
                            if meta == 0 {
                                continue;
                            }
                            let (l, h) = wide_child_box(w, c);
                            if slab(l, h, lo_, inv, t_best).is_none() {
                                continue;
                            }
                            if imask & (1 << c) != 0 {
                                stack.push(w[4] + (imask & ((1 << c) - 1)).count_ones());
                            } else {
                                let first = w[5] + (meta & 0x1F);
                                for k in first..first + (meta >> 5).count_ones() {
                                    visit(self.wide_prims[k as usize], 1, &mut t_best);
                                }
                            }
                        }
                    }
                }
                BvhLayout::Single => {
                    while let Some(n) = stack.pop() {
                        let node = &self.single_nodes[n as usize];
                        let (l, h) = (Vec3::from_slice(&node.lo[..3]), Vec3::from_slice(&node.hi[..3]));
                        if slab(l, h, lo_, inv, t_best).is_none() {
                            continue;
                        }
                        let (idx, count) = (node.lo[3].to_bits(), node.hi[3].to_bits());
                        if count > 0 {
                            visit(idx, count, &mut t_best);
                        } else {
                            stack.push(idx);
                            stack.push(idx + 1);
                        }
                    }
                }
            }
        }
        best
    }
}

/// Byte `c` of the wide node's byte array that starts at word `word` (a child's meta byte or one of its planes).
fn wide_byte(w: &[u32; 20], word: usize, c: usize) -> u32 {
    (w[word + c / 4] >> (8 * (c % 4))) & 0xFF
}

/// Child `c`'s box in a wide node: `p + 2^(e - 127) * q` for its quantized planes (records.rs, `WideNode`).
fn wide_child_box(w: &[u32; 20], c: usize) -> (Vec3, Vec3) {
    let p = Vec3::new(f32::from_bits(w[0]), f32::from_bits(w[1]), f32::from_bits(w[2]));
    let e = Vec3::from_array([0, 8, 16].map(|s| f32::from_bits(((w[3] >> s) & 0xFF) << 23)));
    let q = |k: usize| wide_byte(w, 8 + 2 * k, c) as f32;
    (p + e * Vec3::new(q(0), q(2), q(4)), p + e * Vec3::new(q(1), q(3), q(5)))
}

#[cfg(test)]
/// Ray/box slab test: the entry distance if the ray meets the box before `tmax`.
pub(super) fn slab(lo: Vec3, hi: Vec3, o: Vec3, inv_d: Vec3, tmax: f32) -> Option<f32> {
    let t0 = (lo - o) * inv_d;
    let t1 = (hi - o) * inv_d;
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element().min(tmax);
    (near <= far).then_some(near)
}

#[cfg(test)]
/// The watertight ray/triangle test of Woop, Benthin and Wald (JCGT 2013) in f32, as bvh.glsl computes it.
pub fn watertight(o: Vec3, d: Vec3, p: &[Vec3; 3]) -> Option<f32> {
    let a = d.abs();
    let kz = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    let mut kx = (kz + 1) % 3;
    let mut ky = (kx + 1) % 3;
    if d[kz] < 0.0 {
        std::mem::swap(&mut kx, &mut ky);
    }
    let s = Vec3::new(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);
    let (a, b, c) = (p[0] - o, p[1] - o, p[2] - o);
    let (ax, ay) = (a[kx] - s.x * a[kz], a[ky] - s.y * a[kz]);
    let (bx, by) = (b[kx] - s.x * b[kz], b[ky] - s.y * b[kz]);
    let (cx, cy) = (c[kx] - s.x * c[kz], c[ky] - s.y * c[kz]);
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 {
        return None;
    }
    let t = (u * a[kz] + v * b[kz] + w * c[kz]) * s.z / det;
    (t > 0.0 && t.is_finite()).then_some(t)
}

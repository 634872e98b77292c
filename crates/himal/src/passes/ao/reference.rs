//! CPU twins of the AO passes (same math, same order as the WGSL), for the
//! GPU tests: `hbao` (ao.hbao), `dilate_stability` (ao.stability), `pack`
//! (ao.pack), `blur` (ao.blur_x / the blur of ao.blur_y) and
//! `temporal_filter` (the STF of ao.blur_y_stf); O4: `hbao_ssdo`,
//! `pack_ssdo`, `blur` on four channels, `temporal_filter_ssdo`, and the
//! lighting's lookups `ssdo_visibility`, `specular_occlusion_lagarde`.

use glam::{IVec2, Mat4, Vec2, Vec3, Vec3Swizzles, Vec4, Vec4Swizzles};

use super::AoUniform;
use super::settings::jitter_4x4;

/// Linear depth of pixels without geometry (`AO_SKY_DEPTH` in shaders/ao.wgsl).
pub const SKY_DEPTH: f32 = 65000.0;

/// A row-major image of `T`.
#[derive(Clone, Debug, PartialEq)]
pub struct Image<T> {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `width * height` texels, row 0 first (the top row, as a texture's y = 0).
    pub data: Vec<T>,
}

impl<T: Copy> Image<T> {
    /// Wraps row-major `data`; panics unless it holds `width * height` texels.
    pub fn new(width: u32, height: u32, data: Vec<T>) -> Self {
        assert_eq!(data.len(), (width * height) as usize, "image size");
        Self {
            width,
            height,
            data,
        }
    }

    /// Fills the image with `f(texel coordinate)`, row by row.
    pub fn from_fn(width: u32, height: u32, f: impl FnMut(IVec2) -> T) -> Self {
        let mut f = f;
        let data = (0..height as i32)
            .flat_map(|y| (0..width as i32).map(move |x| IVec2::new(x, y)))
            .map(&mut f)
            .collect();
        Self::new(width, height, data)
    }

    /// Texel at `p` clamped to the edge.
    pub fn clamped(&self, p: IVec2) -> T {
        let x = p.x.clamp(0, self.width as i32 - 1) as usize;
        let y = p.y.clamp(0, self.height as i32 - 1) as usize;
        self.data[y * self.width as usize + x]
    }

    /// Texel at `p` (a `textureLoad`), unclamped: `p` must lie inside the image.
    pub fn get(&self, p: IVec2) -> T {
        self.data[p.y as usize * self.width as usize + p.x as usize]
    }
}

/// Bilinear fetch at `uv` with clamp-to-edge (a linear sampler's result).
pub fn bilinear<const N: usize>(img: &Image<[f32; N]>, uv: Vec2) -> [f32; N] {
    let t = uv * Vec2::new(img.width as f32, img.height as f32) - 0.5;
    let i = t.floor();
    let f = t - i;
    let i = i.as_ivec2();
    let (a, b) = (img.clamped(i), img.clamped(i + IVec2::X));
    let (c, d) = (img.clamped(i + IVec2::Y), img.clamped(i + IVec2::ONE));
    std::array::from_fn(|k| {
        let top = a[k] + (b[k] - a[k]) * f.x;
        let bottom = c[k] + (d[k] - c[k]) * f.x;
        top + (bottom - top) * f.y
    })
}

fn v4(a: [f32; 4]) -> Vec4 {
    Vec4::from_array(a)
}

/// `ao_linear_depth`.
pub fn linear_depth(p: &AoUniform, d: f32) -> f32 {
    if d <= 0.0 {
        return SKY_DEPTH;
    }
    let [p22, p23, p32, p33] = p.depth;
    let z_v = (p23 - d * p33) / (d * p32 - p22);
    (-z_v).min(SKY_DEPTH)
}

/// `ao_clip_w`.
pub fn clip_w(p: &AoUniform, z: f32) -> f32 {
    p.depth[3] - p.depth[2] * z
}

/// `ao_view_position`.
pub fn view_position(p: &AoUniform, uv: Vec2, z: f32) -> Vec3 {
    let ndc = Vec2::new(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
    (ndc * Vec2::new(p.proj[0], p.proj[1]) * clip_w(p, z)).extend(-z)
}

/// `ao_ray`.
fn ray(p: &AoUniform, q: Vec3) -> Vec3 {
    (q.truncate() * -p.depth[2]).extend(q.z)
}

/// View position of AO texel `q` (`texel_position` in hbao.wgsl).
fn texel_position(p: &AoUniform, depth: &Image<f32>, q: IVec2) -> Vec3 {
    let ao_size = v4(p.ao_size).xy().as_ivec2();
    let full = q.clamp(IVec2::ZERO, ao_size - 1) * p.hbao_steps[2] as i32;
    let z = linear_depth(p, depth.get(full));
    let jitter = Vec2::new(p.jitter[0], p.jitter[1]);
    let uv = (full.as_vec2() + 0.5 + jitter) * v4(p.full_size).zw();
    view_position(p, uv, z)
}

fn nearer(a: Vec3, b: Vec3) -> Vec3 {
    let (la, lb) = (a.length_squared(), b.length_squared());
    if la == 0.0 {
        b
    } else if lb == 0.0 || la < lb {
        a
    } else {
        b
    }
}

#[allow(clippy::too_many_arguments)] // mirrors the WGSL function's parameters
fn integrate_direction(
    p: &AoUniform,
    depth: &Image<f32>,
    pos: Vec3,
    n: Vec3,
    q: IVec2,
    dir: Vec2,
    step_px: f32,
    offset: f32,
) -> f32 {
    let v = (-pos).normalize();
    let t3 = Vec3::new(dir.x, -dir.y, 0.0);
    let mut t = n.cross(t3.cross(v));
    let t_len = t.length();
    let mut sin_t = 0.0;
    if t_len > 1e-12 {
        t /= t_len;
        let screen = t.xy() * -pos.z + pos.xy() * t.z;
        if screen.dot(t3.xy()) < 0.0 {
            t = -t;
        }
        sin_t = t.dot(v);
    }
    let mut sin_h = (sin_t.clamp(-1.0, 1.0).asin() + p.hbao[3])
        .min(std::f32::consts::FRAC_PI_2)
        .sin();
    let mut ray = offset * step_px + 1.0;
    let mut occlusion = 0.0;
    for _ in 0..p.hbao_steps[1] as u32 {
        let sq = (q.as_vec2() + 0.5 + dir * ray).floor().as_ivec2();
        if sq.cmplt(IVec2::ZERO).any() || sq.cmpge(v4(p.ao_size).xy().as_ivec2()).any() {
            break;
        }
        let d = texel_position(p, depth, sq) - pos;
        let d2 = d.length_squared();
        if d2 > 0.0 && d2 < p.hbao[0] * p.hbao[0] {
            let sin_s = d.dot(v) / d2.sqrt();
            if sin_s > sin_h {
                occlusion += (1.0 - d2 * p.hbao[1]) * (sin_s - sin_h);
                sin_h = sin_s;
            }
        }
        ray += step_px;
    }
    occlusion
}

/// ao.hbao: (AO, continuity) at AO resolution from full-resolution device depth.
pub fn hbao(p: &AoUniform, depth: &Image<f32>) -> Image<[f32; 2]> {
    let full = hbao_any(p, depth, false);
    Image::from_fn(full.width, full.height, |q| {
        let v = full.get(q);
        [v[0], v[1]]
    })
}

/// ao.hbao's SSDO permutation (O4): (AO, continuity, c1, c2).
pub fn hbao_ssdo(p: &AoUniform, depth: &Image<f32>) -> Image<[f32; 4]> {
    hbao_any(p, depth, true)
}

fn hbao_any(p: &AoUniform, depth: &Image<f32>, ssdo: bool) -> Image<[f32; 4]> {
    let jitter = jitter_4x4();
    let (w, h) = (p.ao_size[0] as u32, p.ao_size[1] as u32);
    Image::from_fn(w, h, |q| {
        let pos = texel_position(p, depth, q);
        if -pos.z >= SKY_DEPTH {
            return [1.0, 0.0, 0.0, 0.0];
        }
        let tp = |o: IVec2| texel_position(p, depth, q + o);
        let dx = nearer(tp(IVec2::X) - pos, pos - tp(-IVec2::X));
        let dy = nearer(tp(IVec2::Y) - pos, pos - tp(-IVec2::Y));
        let continuous = dx.length() < p.stf[2] && dy.length() < p.stf[2];
        let c = dx.cross(dy);
        let mut n = if c.length() > 1e-20 {
            c / c.length()
        } else {
            Vec3::Z
        };
        if n.dot(ray(p, pos)) > 0.0 {
            n = -n;
        }
        let mask = if continuous { 1.0 } else { 0.0 };
        let radius_px = (p.hbao[0] * p.proj[3] / clip_w(p, -pos.z)).min(p.hbao_steps[3]);
        if radius_px < 1.0 {
            return [1.0, mask, 0.0, 0.0];
        }
        let step_px = radius_px / (p.hbao_steps[1] + 1.0);
        let j = jitter[((q.y & 3) * 4 + (q.x & 3)) as usize];
        let sector = std::f32::consts::TAU / p.hbao_steps[0];
        let mut occlusion = 0.0;
        let mut harmonic = Vec2::ZERO;
        for d in 0..p.hbao_steps[0] as u32 {
            let a = (d as f32 + j[0]) * sector;
            let dir = Vec2::new(a.cos(), a.sin());
            let occ = integrate_direction(p, depth, pos, n, q, dir, step_px, j[1]);
            occlusion += occ;
            harmonic += occ * dir;
        }
        let ao = (1.0 - occlusion / p.hbao_steps[0] * p.hbao[2]).clamp(0.0, 1.0);
        if ssdo {
            let c = harmonic * (2.0 / p.hbao_steps[0] * p.hbao[2]);
            [ao, mask, c.x, c.y]
        } else {
            [ao, mask, 0.0, 0.0]
        }
    })
}

/// ao.stability: 1 where all 4x4 neighbours (offsets -2..=1) are continuous.
pub fn dilate_stability(raw: &Image<[f32; 2]>) -> Image<f32> {
    Image::from_fn(raw.width, raw.height, |q| {
        let mut stable = 1.0f32;
        for y in -2..=1 {
            for x in -2..=1 {
                stable = stable.min(raw.clamped(q + IVec2::new(x, y))[1]);
            }
        }
        stable
    })
}

/// ao.pack: full-resolution (AO bilinear from the AO resolution, linear depth).
pub fn pack(p: &AoUniform, depth: &Image<f32>, raw: &Image<[f32; 2]>) -> Image<[f32; 2]> {
    Image::from_fn(depth.width, depth.height, |px| {
        let z = linear_depth(p, depth.get(px));
        let uv = (px.as_vec2() / p.hbao_steps[2] + 0.5) * v4(p.ao_size).zw();
        [bilinear(raw, uv)[0], z]
    })
}

/// ao.pack's SSDO permutation: full-resolution (AO, Z, c1, c2).
pub fn pack_ssdo(p: &AoUniform, depth: &Image<f32>, raw: &Image<[f32; 4]>) -> Image<[f32; 4]> {
    Image::from_fn(depth.width, depth.height, |px| {
        let z = linear_depth(p, depth.get(px));
        let uv = (px.as_vec2() / p.hbao_steps[2] + 0.5) * v4(p.ao_size).zw();
        let v = bilinear(raw, uv);
        [v[0], z, v[2], v[3]]
    })
}

/// `ao_blur_tap`: channel 0 AO, 1 Z, the rest (O4 coefficients) weighted as AO;
/// `total` holds (sum AO w, sum w, sum c w...).
fn blur_tap<const N: usize>(
    v: [f32; N],
    r: f32,
    z0: f32,
    scale: f32,
    p: &AoUniform,
    total: &mut [f32; N],
) {
    let dz = (v[1] - z0) * p.blur[2] / z0;
    let w = scale * (-r * r * p.blur[1] - dz * dz).exp2();
    total[0] += v[0] * w;
    total[1] += w;
    for k in 2..N {
        total[k] += v[k] * w;
    }
}

/// One 1D cross-bilateral pass (`ao_cross_bilateral`) along `step` ((1,0) or
/// (0,1)) of (AO, Z) or, with SSDO, (AO, Z, c1, c2).
pub fn blur<const N: usize>(p: &AoUniform, img: &Image<[f32; N]>, step: IVec2) -> Image<[f32; N]> {
    let radius = p.blur[0];
    let inner = if p.blur[3] > 0.5 {
        (radius * 0.5).floor()
    } else {
        radius
    };
    let inv = Vec2::new(1.0 / img.width as f32, 1.0 / img.height as f32);
    Image::from_fn(img.width, img.height, |px| {
        let c = img.get(px);
        let mut total = c;
        total[1] = 1.0;
        let mut r = 1.0f32;
        while r <= inner {
            let o = step * r as i32;
            blur_tap(img.clamped(px + o), r, c[1], 1.0, p, &mut total);
            blur_tap(img.clamped(px - o), r, c[1], 1.0, p, &mut total);
            r += 1.0;
        }
        let centre = (px.as_vec2() + 0.5) * inv;
        while r <= radius {
            let o = step.as_vec2() * inv * (r + 0.5);
            blur_tap(bilinear(img, centre + o), r + 0.5, c[1], 2.0, p, &mut total);
            blur_tap(bilinear(img, centre - o), r + 0.5, c[1], 2.0, p, &mut total);
            r += 2.0;
        }
        let mut out = total.map(|t| t / total[1]);
        out[1] = c[1];
        out
    })
}

/// The matrices the temporal filter reads from `View`.
pub struct StfView {
    /// This frame's NDC (reverse-Z device depth) to world, jitter included.
    pub inv_view_proj: Mat4,
    /// The previous frame's world to clip, with that frame's jitter.
    pub prev_view_proj: Mat4,
}

/// The selective temporal filter of ao.blur_y_stf: blurred (AO, Z), this
/// frame's device depth, the stability mask and the previous history
/// (AO, Z, N) give the new history.
pub fn temporal_filter(
    p: &AoUniform,
    view: &StfView,
    blurred: &Image<[f32; 2]>,
    depth: &Image<f32>,
    stability: &Image<f32>,
    history: &Image<[f32; 4]>,
) -> Image<[f32; 4]> {
    let blurred = Image::from_fn(blurred.width, blurred.height, |q| {
        let v = blurred.get(q);
        [v[0], v[1], 0.0, 0.0]
    });
    let dir = Image::new(
        history.width,
        history.height,
        vec![[0.0; 2]; history.data.len()],
    );
    temporal_filter_ssdo(p, view, &blurred, depth, stability, history, &dir).0
}

/// ao.blur_y_stf's SSDO entry (`fs_ssdo`): blurred (AO, Z, c1, c2) and the
/// two histories give the next (AO, Z, N) and (c1, c2).
pub fn temporal_filter_ssdo(
    p: &AoUniform,
    view: &StfView,
    blurred: &Image<[f32; 4]>,
    depth: &Image<f32>,
    stability: &Image<f32>,
    history: &Image<[f32; 4]>,
    history_dir: &Image<[f32; 2]>,
) -> (Image<[f32; 4]>, Image<[f32; 2]>) {
    let full = v4(p.full_size);
    let ao_size = v4(p.ao_size).xy().as_ivec2();
    let both = Image::from_fn(blurred.width, blurred.height, |px| {
        let [mut ao, z, c1, c2] = blurred.get(px);
        let mut dir = Vec2::new(c1, c2);
        let mut n = 1.0;
        let d = depth.get(px);
        if d > 0.0 {
            let uv = (px.as_vec2() + 0.5) * full.zw();
            let ndc = Vec4::new(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, d, 1.0);
            let world = view.inv_view_proj * ndc;
            let world = world.xyz() / world.w;
            let prev_clip = view.prev_view_proj * world.extend(1.0);
            let w_i = prev_clip.w;
            let prev_uv = Vec2::new(0.5, -0.5) * prev_clip.xy() / prev_clip.w
                + 0.5
                + (Vec2::new(p.jitter[2], p.jitter[3]) - Vec2::new(p.jitter[0], p.jitter[1]))
                    * full.zw();
            let prev_px = (prev_uv * full.xy()).floor().as_ivec2();
            let inside = prev_px.cmpge(IVec2::ZERO).all()
                && prev_px.cmplt(full.xy().as_ivec2()).all()
                && w_i > 0.0;
            let (w_prev, n_prev) = if inside {
                let h = history.get(prev_px);
                (h[1], h[2])
            } else {
                (0.0, 0.0)
            };
            let q = (px / p.hbao_steps[2] as i32).min(ao_size - 1);
            let stable = stability.get(q) > 0.5;
            let same_surface = (w_prev - w_i).abs() < p.stf[0] * w_prev;
            if same_surface && !(stable && p.stf[3] > 0.5) {
                let ao_prev = bilinear(history, prev_uv)[0];
                ao = (n_prev * ao_prev + ao) / (n_prev + 1.0);
                let dir_prev = Vec2::from_array(bilinear(history_dir, prev_uv));
                dir = (n_prev * dir_prev + dir) / (n_prev + 1.0);
                n = (n_prev + 1.0).min(p.stf[1]);
            }
        }
        ([ao, z, n, 1.0], [dir.x, dir.y])
    });
    let (w, h) = (both.width, both.height);
    let (a, d): (Vec<_>, Vec<_>) = both.data.into_iter().unzip();
    (Image::new(w, h, a), Image::new(w, h, d))
}

/// `ssdo_visibility` (shaders/ao.wgsl): the O4 directional term along unit
/// `l` at view-space `pos` with normal `n`, harmonic `c` = (c1, c2).
pub fn ssdo_visibility(pos: Vec3, n: Vec3, l: Vec3, c: Vec2, gain: f32, soft: f32) -> f32 {
    let v = (-pos).normalize();
    let screen = l.xy() * -pos.z + pos.xy() * l.z;
    let len = screen.length();
    if len <= 1e-6 {
        return 1.0;
    }
    let t3 = (screen / len).extend(0.0);
    let rise = gain * (c.x * t3.x - c.y * t3.y);
    if rise <= 0.0 {
        return 1.0;
    }
    let mut sin_t = 0.0;
    let mut t = n.cross(t3.cross(v));
    let t_len = t.length();
    if t_len > 1e-12 {
        t /= t_len;
        let st = t.xy() * -pos.z + pos.xy() * t.z;
        if st.dot(t3.xy()) < 0.0 {
            t = -t;
        }
        sin_t = t.dot(v);
    }
    let sin_l = l.dot(v);
    (1.0 + (sin_l - sin_t - rise) / soft).clamp(0.0, 1.0)
}

/// `specular_occlusion_lagarde` (shaders/ao.wgsl): reflection occlusion from
/// AO alone (Lagarde & de Rousiers 2014), `roughness` perceptual.
pub fn specular_occlusion_lagarde(n_o_v: f32, ao: f32, roughness: f32) -> f32 {
    let alpha = roughness * roughness;
    ((n_o_v + ao).powf((-16.0 * alpha - 1.0).exp2()) - 1.0 + ao).clamp(0.0, 1.0)
}

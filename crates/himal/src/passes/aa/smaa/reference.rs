//! CPU twins of `edges.wgsl`, `weights.wgsl` and `blend.wgsl`, line by line
//! (same constants, clamp-to-edge addressing, bilinear sampling at texel
//! centres minus ½ as the GPU does).

use super::lut;

/// A small RGBA float image (row-major).
#[derive(Clone, Debug, PartialEq)]
pub struct Plane<const N: usize> {
    /// Width in texels.
    pub width: usize,
    /// Height in texels.
    pub height: usize,
    /// Texels, row-major (`y * width + x`).
    pub texels: Vec<[f32; N]>,
}

impl<const N: usize> Plane<N> {
    /// A `width` x `height` plane of zeros.
    pub fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            texels: vec![[0.0; N]; width * height],
        }
    }

    /// Texel at (x, y), clamped to the edge.
    pub fn load(&self, x: i64, y: i64) -> [f32; N] {
        let x = x.clamp(0, self.width as i64 - 1) as usize;
        let y = y.clamp(0, self.height as i64 - 1) as usize;
        self.texels[y * self.width + x]
    }

    /// Bilinear sample at normalised `uv` (clamp to edge).
    pub fn sample(&self, u: f32, v: f32) -> [f32; N] {
        let x = u * self.width as f32 - 0.5;
        let y = v * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let mut out = [0.0; N];
        let corners = [
            (x0, y0, (1.0 - fx) * (1.0 - fy)),
            (x0 + 1, y0, fx * (1.0 - fy)),
            (x0, y0 + 1, (1.0 - fx) * fy),
            (x0 + 1, y0 + 1, fx * fy),
        ];
        for (cx, cy, w) in corners {
            let t = self.load(cx, cy);
            for c in 0..N {
                out[c] += w * t[c];
            }
        }
        out
    }

    /// Nearest-texel sample at normalised `uv`.
    pub fn sample_point(&self, u: f32, v: f32) -> [f32; N] {
        let x = (u * self.width as f32).floor() as i64;
        let y = (v * self.height as f32).floor() as i64;
        self.load(x, y)
    }
}

/// Edge-detection settings (the WGSL override constants).
#[derive(Clone, Copy, Debug)]
pub struct EdgeSettings {
    /// Gamma-encoded luma contrast at which an edge starts (`THRESHOLD`).
    pub threshold: f32,
    /// Predicated thresholding: the threshold depends on whether depth (and normals) show a
    /// geometric edge.
    pub predication: bool,
    /// Relative depth step to a neighbour that counts as a geometric edge.
    pub predication_threshold: f32,
    /// Factor on the threshold under predication (raises it off geometric edges).
    pub predication_scale: f32,
    /// How far a geometric edge lowers the predicated threshold: `scale threshold (1 - strength
    /// edge)`.
    pub predication_strength: f32,
    /// Normal discontinuities count as geometric edges too.
    pub normal_predication: bool,
    /// Neighbours' normals whose cosine falls below this make a geometric edge (0.906: about 25°).
    pub normal_cos: f32,
}

impl Default for EdgeSettings {
    fn default() -> Self {
        Self {
            threshold: 0.1,
            predication: true,
            predication_threshold: 0.01,
            predication_scale: 2.0,
            predication_strength: 0.4,
            normal_predication: true,
            normal_cos: 0.906,
        }
    }
}

const LOCAL_CONTRAST_ADAPTATION: f32 = 2.0;

fn step(edge: f32, x: f32) -> f32 {
    if x >= edge { 1.0 } else { 0.0 }
}

/// IEC 61966-2-1 linear → sRGB.
pub fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.0031308 {
        c * 12.92
    } else {
        1.055 * c.max(0.0).powf(1.0 / 2.4) - 0.055
    }
}

/// sRGB → linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Twin of `edges.wgsl`: `color` linear RGBA, `depth` device depth,
/// `normals` decoded from the G-buffer frame.
pub fn detect_edges(
    color: &Plane<4>,
    depth: &Plane<1>,
    normals: &Plane<3>,
    s: EdgeSettings,
) -> Plane<2> {
    let luma = |x: i64, y: i64| {
        let c = color.load(x, y);
        let g = |v: f32| linear_to_srgb(v.clamp(0.0, 1.0));
        0.2126 * g(c[0]) + 0.7152 * g(c[1]) + 0.0722 * g(c[2])
    };
    let depth_step = |a: f32, b: f32| (a - b).abs() / a.min(b).max(1e-7);
    let mut out = Plane::new(color.width, color.height);
    for y in 0..color.height as i64 {
        for x in 0..color.width as i64 {
            let l = luma(x, y);
            let (l_left, l_top) = (luma(x - 1, y), luma(x, y - 1));
            let mut threshold = [s.threshold; 2];
            if s.predication {
                let d = depth.load(x, y)[0];
                let neighbours = [(x - 1, y), (x, y - 1)];
                for (k, &(nx, ny)) in neighbours.iter().enumerate() {
                    let dn = depth.load(nx, ny)[0];
                    let mut edge = step(s.predication_threshold, depth_step(d, dn));
                    if s.normal_predication && d > 0.0 && dn > 0.0 {
                        let (a, b) = (normals.load(x, y), normals.load(nx, ny));
                        let cos = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
                        if cos < s.normal_cos {
                            edge = 1.0;
                        }
                    }
                    threshold[k] =
                        s.predication_scale * s.threshold * (1.0 - s.predication_strength * edge);
                }
            }
            let delta = [(l - l_left).abs(), (l - l_top).abs()];
            let mut edges = [step(threshold[0], delta[0]), step(threshold[1], delta[1])];
            if edges[0] + edges[1] == 0.0 {
                continue;
            }
            let (l_right, l_bottom) = (luma(x + 1, y), luma(x, y + 1));
            let mut max_delta = [
                delta[0].max((l - l_right).abs()),
                delta[1].max((l - l_bottom).abs()),
            ];
            max_delta[0] = max_delta[0].max((l_left - luma(x - 2, y)).abs());
            max_delta[1] = max_delta[1].max((l_top - luma(x, y - 2)).abs());
            let final_delta = max_delta[0].max(max_delta[1]);
            for k in 0..2 {
                edges[k] *= step(final_delta, LOCAL_CONTRAST_ADAPTATION * delta[k]);
            }
            out.texels[y as usize * color.width + x as usize] = edges;
        }
    }
    out
}

/// The lookup textures as float planes (what the GPU samples).
pub struct Luts {
    /// The area texture: blending weights by edge distances and crossing pattern (RG).
    pub area: Plane<2>,
    /// The search texture: the edge searches' length corrections (R).
    pub search: Plane<1>,
}

impl Luts {
    /// Decodes the generated lookup textures (`smaa::lut`) into float planes.
    pub fn generate() -> Self {
        let area_bytes = lut::area_texture();
        let (aw, ah) = lut::AREA_SIZE;
        let mut area = Plane::new(aw, ah);
        for (i, t) in area.texels.iter_mut().enumerate() {
            *t = [
                area_bytes[2 * i] as f32 / 255.0,
                area_bytes[2 * i + 1] as f32 / 255.0,
            ];
        }
        let search_bytes = lut::search_texture();
        let (sw, sh) = lut::SEARCH_SIZE;
        let mut search = Plane::new(sw, sh);
        for (t, &b) in search.texels.iter_mut().zip(&search_bytes) {
            *t = [b as f32 / 255.0];
        }
        Self { area, search }
    }
}

const AREATEX_MAX_DISTANCE: f32 = 16.0;
const SEARCHTEX_SIZE: [f32; 2] = [66.0, 33.0];
const SEARCHTEX_PACKED_SIZE: [f32; 2] = [64.0, 16.0];

fn search_length(luts: &Luts, e: [f32; 2], offset: f32) -> f32 {
    let scale = [
        (SEARCHTEX_SIZE[0] * 0.5 - 1.0) / SEARCHTEX_PACKED_SIZE[0],
        (-SEARCHTEX_SIZE[1] + 1.0) / SEARCHTEX_PACKED_SIZE[1],
    ];
    let bias = [
        (SEARCHTEX_SIZE[0] * offset + 0.5) / SEARCHTEX_PACKED_SIZE[0],
        (SEARCHTEX_SIZE[1] - 0.5) / SEARCHTEX_PACKED_SIZE[1],
    ];
    luts.search
        .sample_point(scale[0] * e[0] + bias[0], scale[1] * e[1] + bias[1])[0]
}

fn area(luts: &Luts, sqrt_d: [f32; 2], e1: f32, e2: f32, subsample: f32) -> [f32; 2] {
    let (aw, ah) = (lut::AREA_SIZE.0 as f32, lut::AREA_SIZE.1 as f32);
    let u = (AREATEX_MAX_DISTANCE * (4.0 * e1).round() + sqrt_d[0] + 0.5) / aw;
    let v = (AREATEX_MAX_DISTANCE * (4.0 * e2).round() + sqrt_d[1] + 0.5) / ah + subsample / 7.0;
    luts.area.sample(u, v)
}

/// The switches of `weights.wgsl` (its override constants).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WeightSettings {
    /// Orthogonal search steps (2 pixels each) each way.
    pub max_search_steps: f32,
    /// Diagonal search steps each way; 0 turns diagonal detection off.
    pub max_search_steps_diag: f32,
    /// Percent of a corner's blending kept; 100 turns corner detection off.
    pub corner_rounding: f32,
    /// Area tables: horizontal, vertical, first diagonal (0 for SMAA 1x).
    pub subsample: [f32; 3],
}

impl Default for WeightSettings {
    /// What `aa.smaa.weights` runs: the reference's HIGH preset with 8
    /// orthogonal steps (diagonals 8, corner rounding 25).
    fn default() -> Self {
        Self {
            max_search_steps: 8.0,
            max_search_steps_diag: 8.0,
            corner_rounding: 25.0,
            subsample: [0.0; 3],
        }
    }
}

/// `smaa_decode_diag_bilinear` on (red, green).
fn decode_diag(e: [f32; 2]) -> [f32; 2] {
    [(e[0] * (5.0 * e[0] - 3.75).abs()).round(), e[1].round()]
}

/// `smaa_search_diag`: (steps, mean of the last fetch); `end` the last edges.
fn search_diag(
    edges: &Plane<2>,
    tc: [f32; 2],
    dir: [f32; 2],
    rt: [f32; 4],
    decode: bool,
    max_steps: f32,
    end: &mut [f32; 2],
) -> [f32; 2] {
    let mut coord = [tc[0], tc[1], -1.0, 1.0];
    if decode {
        coord[0] += 0.25 * rt[0];
    }
    while coord[2] < max_steps - 1.0 && coord[3] > 0.9 {
        coord[0] += rt[0] * dir[0];
        coord[1] += rt[1] * dir[1];
        coord[2] += 1.0;
        let mut f = edges.sample(coord[0], coord[1]);
        if decode {
            f = decode_diag(f);
        }
        *end = f;
        coord[3] = 0.5 * (f[0] + f[1]);
    }
    [coord[2], coord[3]]
}

fn area_diag(luts: &Luts, dist: [f32; 2], e: [f32; 2], subsample: f32) -> [f32; 2] {
    let (aw, ah) = (lut::AREA_SIZE.0 as f32, lut::AREA_SIZE.1 as f32);
    let n = lut::AREA_MAX_DISTANCE_DIAG as f32;
    let u = (n * e[0] + dist[0] + 0.5) / aw + 0.5;
    let v = (n * e[1] + dist[1] + 0.5) / ah + subsample / 7.0;
    luts.area.sample(u, v)
}

/// `smaa_diag_weights`.
fn diag_weights(
    edges: &Plane<2>,
    luts: &Luts,
    tc: [f32; 2],
    e: [f32; 2],
    rt: [f32; 4],
    s: &WeightSettings,
) -> [f32; 2] {
    let at = |u: f32, v: f32| edges.sample(u, v);
    let steps = s.max_search_steps_diag;
    let mut weights = [0.0f32; 2];
    let mut end = [0.0f32; 2];
    let mut d = [0.0f32; 4];
    if e[0] > 0.0 {
        let r = search_diag(edges, tc, [-1.0, 1.0], rt, false, steps, &mut end);
        d[0] = r[0] + if end[1] > 0.9 { 1.0 } else { 0.0 };
        d[2] = r[1];
    }
    let r = search_diag(edges, tc, [1.0, -1.0], rt, false, steps, &mut end);
    (d[1], d[3]) = (r[0], r[1]);
    let crossing = |c: [f32; 4], d: [f32; 4]| {
        let cc = [2.0 * c[0] + c[1], 2.0 * c[2] + c[3]];
        [
            if d[2] >= 0.9 { 0.0 } else { cc[0] },
            if d[3] >= 0.9 { 0.0 } else { cc[1] },
        ]
    };
    if d[0] + d[1] > 2.0 {
        let a = [tc[0] + (-d[0] + 0.25) * rt[0], tc[1] + d[0] * rt[1]];
        let b = [tc[0] + d[1] * rt[0], tc[1] + (-d[1] - 0.25) * rt[1]];
        let ea = decode_diag(at(a[0] - rt[0], a[1]));
        let eb = decode_diag(at(b[0] + rt[0], b[1]));
        // c.yxwz = decode(c.xyzw)
        let c = [ea[1], ea[0], eb[1], eb[0]];
        let w = area_diag(luts, [d[0], d[1]], crossing(c, d), s.subsample[2]);
        weights = [weights[0] + w[0], weights[1] + w[1]];
    }
    let r = search_diag(edges, tc, [-1.0, -1.0], rt, true, steps, &mut end);
    d = [r[0], 0.0, r[1], 0.0];
    if at(tc[0] + rt[0], tc[1])[0] > 0.0 {
        let r = search_diag(edges, tc, [1.0, 1.0], rt, true, steps, &mut end);
        d[1] = r[0] + if end[1] > 0.9 { 1.0 } else { 0.0 };
        d[3] = r[1];
    }
    if d[0] + d[1] > 2.0 {
        let a = [tc[0] - d[0] * rt[0], tc[1] - d[0] * rt[1]];
        let b = [tc[0] + d[1] * rt[0], tc[1] + d[1] * rt[1]];
        let eb = at(b[0] + rt[0], b[1]);
        let c = [
            at(a[0] - rt[0], a[1])[1],
            at(a[0], a[1] - rt[1])[0],
            eb[1],
            eb[0],
        ];
        let w = area_diag(luts, [d[0], d[1]], crossing(c, d), 0.0);
        weights = [weights[0] + w[1], weights[1] + w[0]];
    }
    weights
}

/// `smaa_corner`: `d` the pixels to the two ends of the line.
fn corner(
    edges: &Plane<2>,
    weights: [f32; 2],
    tc: [f32; 2],
    d: [f32; 2],
    horizontal: bool,
    rt: [f32; 4],
    rounding_percent: f32,
) -> [f32; 2] {
    if rounding_percent >= 100.0 {
        return weights;
    }
    let step = |edge: f32, x: f32| if x >= edge { 1.0 } else { 0.0 };
    let lr = [step(d[0], d[1]), step(d[1], d[0])];
    let k = (1.0 - rounding_percent / 100.0) / (lr[0] + lr[1]);
    let rounding = [k * lr[0], k * lr[1]];
    let at = |p: [f32; 2], o: [f32; 2], c: usize| {
        edges.sample(p[0] + o[0] * rt[0], p[1] + o[1] * rt[1])[c]
    };
    let mut factor = [1.0f32, 1.0];
    if horizontal {
        let a = [tc[0] - d[0] * rt[0], tc[1]];
        let b = [tc[0] + d[1] * rt[0], tc[1]];
        factor[0] -= rounding[0] * at(a, [0.0, 1.0], 0);
        factor[0] -= rounding[1] * at(b, [1.0, 1.0], 0);
        factor[1] -= rounding[0] * at(a, [0.0, -2.0], 0);
        factor[1] -= rounding[1] * at(b, [1.0, -2.0], 0);
    } else {
        let a = [tc[0], tc[1] - d[0] * rt[1]];
        let b = [tc[0], tc[1] + d[1] * rt[1]];
        factor[0] -= rounding[0] * at(a, [1.0, 0.0], 1);
        factor[0] -= rounding[1] * at(b, [1.0, 1.0], 1);
        factor[1] -= rounding[0] * at(a, [-2.0, 0.0], 1);
        factor[1] -= rounding[1] * at(b, [-2.0, 1.0], 1);
    }
    [
        weights[0] * factor[0].clamp(0.0, 1.0),
        weights[1] * factor[1].clamp(0.0, 1.0),
    ]
}

/// Twin of `weights.wgsl`.
pub fn blending_weights(edges: &Plane<2>, luts: &Luts, s: &WeightSettings) -> Plane<4> {
    let (w, h) = (edges.width as f32, edges.height as f32);
    let rt = [1.0 / w, 1.0 / h, w, h];
    let at = |u: f32, v: f32| edges.sample(u, v);
    let subsample = s.subsample;
    let mut out = Plane::new(edges.width, edges.height);
    for y in 0..edges.height {
        for x in 0..edges.width {
            let frag = [x as f32 + 0.5, y as f32 + 0.5];
            let tc = [frag[0] * rt[0], frag[1] * rt[1]];
            let off0 = [
                tc[0] - 0.25 * rt[0],
                tc[1] - 0.125 * rt[1],
                tc[0] + 1.25 * rt[0],
                tc[1] - 0.125 * rt[1],
            ];
            let off1 = [
                tc[0] - 0.125 * rt[0],
                tc[1] - 0.25 * rt[1],
                tc[0] - 0.125 * rt[0],
                tc[1] + 1.25 * rt[1],
            ];
            let steps = s.max_search_steps as i32;
            let mut e = edges.load(x as i64, y as i64);
            let mut weights = [0.0f32; 4];
            let mut diag = [0.0f32; 2];
            if e[1] > 0.0 && s.max_search_steps_diag > 0.0 {
                diag = diag_weights(edges, luts, tc, e, rt, s);
            }
            if diag[0] + diag[1] > 0.0 {
                weights = [diag[0], diag[1], 0.0, 0.0];
                e[0] = 0.0;
            } else if e[1] > 0.0 {
                // Left.
                let (mut u, mut ee) = (off0[0], [0.0, 1.0]);
                for _ in 0..steps {
                    if !(ee[1] > 0.8281 && ee[0] == 0.0) {
                        break;
                    }
                    ee = at(u, off0[1]);
                    u -= 2.0 * rt[0];
                }
                let left = rt[0] * (-(255.0 / 127.0) * search_length(luts, ee, 0.0) + 3.25) + u;
                let e1 = at(left, off1[1])[0];
                // Right.
                let (mut u, mut ee) = (off0[2], [0.0, 1.0]);
                for _ in 0..steps {
                    if !(ee[1] > 0.8281 && ee[0] == 0.0) {
                        break;
                    }
                    ee = at(u, off0[3]);
                    u += 2.0 * rt[0];
                }
                let right = -rt[0] * (-(255.0 / 127.0) * search_length(luts, ee, 0.5) + 3.25) + u;
                let e2 = at(right + rt[0], off1[1])[0];
                let d = [
                    (rt[2] * left - frag[0]).round().abs(),
                    (rt[2] * right - frag[0]).round().abs(),
                ];
                let a = area(luts, [d[0].sqrt(), d[1].sqrt()], e1, e2, subsample[0]);
                let a = corner(edges, a, tc, d, true, rt, s.corner_rounding);
                weights[0] = a[0];
                weights[1] = a[1];
            }
            if e[0] > 0.0 {
                // Up.
                let (mut v, mut ee) = (off1[1], [1.0, 0.0]);
                for _ in 0..steps {
                    if !(ee[0] > 0.8281 && ee[1] == 0.0) {
                        break;
                    }
                    ee = at(off1[0], v);
                    v -= 2.0 * rt[1];
                }
                let up = rt[1]
                    * (-(255.0 / 127.0) * search_length(luts, [ee[1], ee[0]], 0.0) + 3.25)
                    + v;
                let e1 = at(off0[0], up)[1];
                // Down.
                let (mut v, mut ee) = (off1[3], [1.0, 0.0]);
                for _ in 0..steps {
                    if !(ee[0] > 0.8281 && ee[1] == 0.0) {
                        break;
                    }
                    ee = at(off1[2], v);
                    v += 2.0 * rt[1];
                }
                let down = -rt[1]
                    * (-(255.0 / 127.0) * search_length(luts, [ee[1], ee[0]], 0.5) + 3.25)
                    + v;
                let e2 = at(off0[0], down + rt[1])[1];
                let d = [
                    (rt[3] * up - frag[1]).round().abs(),
                    (rt[3] * down - frag[1]).round().abs(),
                ];
                let a = area(luts, [d[0].sqrt(), d[1].sqrt()], e1, e2, subsample[1]);
                let a = corner(edges, a, tc, d, false, rt, s.corner_rounding);
                weights[2] = a[0];
                weights[3] = a[1];
            }
            out.texels[y * edges.width + x] = weights;
        }
    }
    out
}

/// Twin of `blend.wgsl`: `color` linear RGBA.
pub fn neighbourhood_blend(color: &Plane<4>, weights: &Plane<4>) -> Plane<4> {
    let (w, h) = (color.width as f32, color.height as f32);
    let mut out = Plane::new(color.width, color.height);
    for y in 0..color.height as i64 {
        for x in 0..color.width as i64 {
            let own = weights.load(x, y);
            let a = [
                weights.load(x + 1, y)[3],
                weights.load(x, y + 1)[1],
                own[2],
                own[0],
            ];
            let i = y as usize * color.width + x as usize;
            if a.iter().sum::<f32>() < 1e-5 {
                out.texels[i] = color.load(x, y);
                continue;
            }
            let horizontal = a[0].max(a[2]) > a[1].max(a[3]);
            let (offset, mut weight) = if horizontal {
                ([a[0], 0.0, a[2], 0.0], [a[0], a[2]])
            } else {
                ([0.0, a[1], 0.0, a[3]], [a[1], a[3]])
            };
            let sum = weight[0] + weight[1];
            weight = [weight[0] / sum, weight[1] / sum];
            let tc = [(x as f32 + 0.5) / w, (y as f32 + 0.5) / h];
            let c1 = color.sample(tc[0] + offset[0] / w, tc[1] + offset[1] / h);
            let c2 = color.sample(tc[0] - offset[2] / w, tc[1] - offset[3] / h);
            for c in 0..4 {
                out.texels[i][c] = weight[0] * c1[c] + weight[1] * c2[c];
            }
        }
    }
    out
}

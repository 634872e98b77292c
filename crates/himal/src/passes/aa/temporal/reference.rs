//! CPU twins of `resolve.wgsl`, `taa.wgsl`, `unsharp.wgsl`, `taa_ao.wgsl` and
//! `taa_motion.wgsl` (planes of linear RGB, AO or motion; textures are read
//! with clamp-to-edge like the GPU).

use super::{AaParams, ResolveMode};
use crate::passes::aa::smaa::reference::{Plane, linear_to_srgb};

fn rgb(t: [f32; 4]) -> [f32; 3] {
    [t[0], t[1], t[2]]
}

fn box3x3(img: &Plane<4>, x: i64, y: i64) -> ([f32; 3], [f32; 3]) {
    let c = rgb(img.load(x, y));
    let (mut lo, mut hi) = (c, c);
    for j in -1..=1 {
        for i in -1..=1 {
            let s = rgb(img.load(x + i, y + j));
            for k in 0..3 {
                lo[k] = lo[k].min(s[k]);
                hi[k] = hi[k].max(s[k]);
            }
        }
    }
    (lo, hi)
}

fn jitter_free(p: &AaParams, m: [f32; 2], size: [f32; 2]) -> [f32; 2] {
    [
        m[0] + (p.jitter[2] - p.jitter[0]) / size[0],
        m[1] + (p.jitter[3] - p.jitter[1]) / size[1],
    ]
}

fn avg(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        0.5 * (a[0] + b[0]),
        0.5 * (a[1] + b[1]),
        0.5 * (a[2] + b[2]),
    ]
}

/// `AA_REACTIVE_GAIN` (shaders/aa.wgsl).
pub const REACTIVE_GAIN: f32 = 4.0;

/// Twin of `aa.resolve`: returns (colour, jitter-free motion). `reactive`
/// (E4, `REACTIVE`): the particles' coverage (the frame's size) and the
/// TAA's previous history (its alpha: last frame's coverage).
#[allow(clippy::too_many_arguments)]
pub fn resolve(
    p: &AaParams,
    mode: ResolveMode,
    current: &Plane<4>,
    previous: &Plane<4>,
    previous2: &Plane<4>,
    motion: &Plane<2>,
    previous_motion: &Plane<2>,
    reactive: Option<(&Plane<1>, &Plane<4>)>,
) -> (Plane<4>, Plane<2>) {
    let (w, h) = (current.width, current.height);
    let size = [w as f32, h as f32];
    let mut out = Plane::new(w, h);
    let mut out_motion = Plane::new(w, h);
    let phase_a = p.state[1] < 0.5;
    let d_now = if phase_a { (1, 0) } else { (0, 1) };
    let d_prev = (1 - d_now.0, 1 - d_now.1);
    for y in 0..h as i64 {
        for x in 0..w as i64 {
            let i = y as usize * w + x as usize;
            let m = jitter_free(p, motion.load(x, y), size);
            out_motion.texels[i] = m;
            let c = rgb(current.load(x, y));
            let mut now = c;
            if mode == ResolveMode::FlipQuad {
                now = avg(c, rgb(current.load(x + d_now.0, y + d_now.1)));
            }
            let mut result = now;
            if mode != ResolveMode::PassThrough && p.state[0] >= 2.0 {
                let fx = x as f32 + 0.5 + m[0] * size[0];
                let fy = y as f32 + 0.5 + m[1] * size[1];
                let (qx, qy) = (fx.floor() as i64, fy.floor() as i64);
                let m_prev = previous_motion.load(qx, qy);
                let dm = [(m[0] - m_prev[0]) * size[0], (m[1] - m_prev[1]) * size[1]];
                let motion_ok = (dm[0] * dm[0] + dm[1] * dm[1]).sqrt() < p.tuning[0];
                let q2x = (qx as f32 + 0.5 + m_prev[0] * size[0]).floor() as i64;
                let q2y = (qy as f32 + 0.5 + m_prev[1] * size[1]).floor() as i64;
                let (lo, hi) = box3x3(current, x, y);
                let s2 = rgb(previous2.load(q2x, q2y));
                let t = p.tuning[1];
                let colour_ok = (0..3).all(|k| s2[k] >= lo[k] - t && s2[k] <= hi[k] + t);
                if motion_ok && colour_ok {
                    let mut before = rgb(previous.load(qx, qy));
                    if mode == ResolveMode::FlipQuad {
                        before = avg(before, rgb(previous.load(qx + d_prev.0, qy + d_prev.1)));
                    }
                    result = avg(now, before);
                    if let Some((cov, hist)) = reactive {
                        let c = cov.load(x, y)[0].max(hist.load(qx, qy)[3]);
                        let k = (REACTIVE_GAIN * c).clamp(0.0, 1.0);
                        result = std::array::from_fn(|j| result[j] + (now[j] - result[j]) * k);
                    }
                }
            }
            out.texels[i] = [result[0], result[1], result[2], 1.0];
        }
    }
    (out, out_motion)
}

fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// Twin of `aa.taa`: the next history (= the frame's colour; alpha 1, or
/// with `reactive`, E4, the particles' coverage, which with the history's
/// alpha raises the new frame's weight).
pub fn taa(
    p: &AaParams,
    input: &Plane<4>,
    history: &Plane<4>,
    motion: &Plane<2>,
    previous_motion: &Plane<2>,
    reactive: Option<&Plane<1>>,
) -> Plane<4> {
    let (w, h) = (input.width, input.height);
    let size = [w as f32, h as f32];
    let mut out = Plane::new(w, h);
    for y in 0..h as i64 {
        for x in 0..w as i64 {
            let xv = rgb(input.load(x, y));
            let (lo, hi) = box3x3(input, x, y);
            let m = motion.load(x, y);
            let uv = [
                (x as f32 + 0.5) / size[0] + m[0],
                (y as f32 + 0.5) / size[1] + m[1],
            ];
            let qx = ((uv[0] * size[0]).floor() as i64).clamp(0, w as i64 - 1);
            let qy = ((uv[1] * size[1]).floor() as i64).clamp(0, h as i64 - 1);
            let m_prev = previous_motion.load(qx, qy);
            let inside = uv.iter().all(|&v| (0.0..=1.0).contains(&v));
            let dm = [(m[0] - m_prev[0]) * size[0], (m[1] - m_prev[1]) * size[1]];
            let motion_ok = (dm[0] * dm[0] + dm[1] * dm[1]).sqrt() < p.tuning[0];
            let srgb = |c: [f32; 3]| c.map(linear_to_srgb);
            let contrast = luminance(srgb(hi)) - luminance(srgb(lo));
            let k = (contrast * p.tuning[3]).clamp(0.0, 1.0);
            let mut alpha = p.state[2] + (p.state[3] - p.state[2]) * k;
            if p.state[0] < 3.0 || !motion_ok || !inside {
                alpha = 1.0;
            }
            let h4 = history.sample(uv[0], uv[1]);
            let hs = rgb(h4);
            let mut coverage = 1.0;
            if let Some(cov) = reactive {
                coverage = cov.load(x, y)[0];
                alpha = alpha.max((REACTIVE_GAIN * coverage.max(h4[3])).clamp(0.0, 1.0));
            }
            let i = y as usize * w + x as usize;
            for c in 0..3 {
                let t = p.tuning[1];
                let hc = hs[c].clamp(lo[c] - t, hi[c] + t);
                out.texels[i][c] = hc + (xv[c] - hc) * alpha;
            }
            out.texels[i][3] = coverage;
        }
    }
    out
}

/// Twin of `aa.unsharp`.
pub fn unsharp(p: &AaParams, input: &Plane<4>) -> Plane<4> {
    let (w, h) = (input.width, input.height);
    let mut out = Plane::new(w, h);
    let s = p.tuning[2];
    for y in 0..h as i64 {
        for x in 0..w as i64 {
            let c = rgb(input.load(x, y));
            let mut blur = [0.0f32; 3];
            for j in -1i64..=1 {
                for i in -1i64..=1 {
                    let wgt = ((2 - i.abs()) * (2 - j.abs())) as f32 / 16.0;
                    let t = rgb(input.load(x + i, y + j));
                    for k in 0..3 {
                        blur[k] += wgt * t[k];
                    }
                }
            }
            let i = y as usize * w + x as usize;
            for k in 0..3 {
                out.texels[i][k] = (c[k] + s * (c[k] - blur[k])).max(0.0);
            }
            out.texels[i][3] = 1.0;
        }
    }
    out
}

/// Shared by the buffer TAAs: the new-frame weight, 1 without usable history.
fn buffer_alpha(p: &AaParams, contrast: f32, motion_ok: bool, inside: bool) -> f32 {
    if p.state[0] < 1.0 || !motion_ok || !inside {
        return 1.0;
    }
    let k = (contrast * p.tuning[3]).clamp(0.0, 1.0);
    p.state[2] + (p.state[3] - p.state[2]) * k
}

fn inside_uv(uv: [f32; 2]) -> bool {
    uv.iter().all(|&v| (0.0..=1.0).contains(&v))
}

/// Twin of `aa.taa_ao`: `ao` is (AO, Z, N, _), `history` (AO, m0, _);
/// `motion` is jitter-free when `jitter_free_motion`, else the G-buffer's.
/// Returns (AO output, next history).
pub fn taa_ao(
    p: &AaParams,
    ao: &Plane<4>,
    history: &Plane<4>,
    motion: &Plane<2>,
    jitter_free_motion: bool,
) -> (Plane<4>, Plane<4>) {
    let (w, h) = (ao.width, ao.height);
    let size = [w as f32, h as f32];
    let (mut out, mut next) = (Plane::new(w, h), Plane::new(w, h));
    for y in 0..h as i64 {
        for x in 0..w as i64 {
            let c = ao.load(x, y);
            let (mut lo, mut hi) = (c[0], c[0]);
            for j in -1..=1 {
                for i in -1..=1 {
                    let s = ao.load(x + i, y + j)[0];
                    lo = lo.min(s);
                    hi = hi.max(s);
                }
            }
            let raw = motion.load(x, y);
            let m = if jitter_free_motion {
                raw
            } else {
                jitter_free(p, raw, size)
            };
            let uv = [
                (x as f32 + 0.5) / size[0] + m[0],
                (y as f32 + 0.5) / size[1] + m[1],
            ];
            let qx = ((uv[0] * size[0]).floor() as i64).clamp(0, w as i64 - 1);
            let qy = ((uv[1] * size[1]).floor() as i64).clamp(0, h as i64 - 1);
            let hq = history.load(qx, qy);
            let dm = [(m[0] - hq[1]) * size[0], (m[1] - hq[2]) * size[1]];
            let motion_ok = (dm[0] * dm[0] + dm[1] * dm[1]).sqrt() < p.tuning[0];
            let alpha = buffer_alpha(p, hi - lo, motion_ok, inside_uv(uv));
            let t = p.tuning[1];
            let hs = history.sample(uv[0], uv[1])[0].clamp(lo - t, hi + t);
            let r = hs + (c[0] - hs) * alpha;
            let i = y as usize * w + x as usize;
            out.texels[i] = [r, c[1], c[2], 1.0];
            next.texels[i] = [r, m[0], m[1], 1.0];
        }
    }
    (out, next)
}

/// Twin of `aa.taa_motion`: the stabilised jitter-free motion from the
/// G-buffer `motion` and the previous stabilised `history`.
pub fn taa_motion(p: &AaParams, motion: &Plane<2>, history: &Plane<2>) -> Plane<2> {
    let (w, h) = (motion.width, motion.height);
    let size = [w as f32, h as f32];
    let mut out = Plane::new(w, h);
    for y in 0..h as i64 {
        for x in 0..w as i64 {
            let m = jitter_free(p, motion.load(x, y), size);
            let (mut lo, mut hi) = (m, m);
            for j in -1..=1 {
                for i in -1..=1 {
                    let s = jitter_free(p, motion.load(x + i, y + j), size);
                    for k in 0..2 {
                        lo[k] = lo[k].min(s[k]);
                        hi[k] = hi[k].max(s[k]);
                    }
                }
            }
            let uv = [
                (x as f32 + 0.5) / size[0] + m[0],
                (y as f32 + 0.5) / size[1] + m[1],
            ];
            let qx = ((uv[0] * size[0]).floor() as i64).clamp(0, w as i64 - 1);
            let qy = ((uv[1] * size[1]).floor() as i64).clamp(0, h as i64 - 1);
            let m_prev = history.load(qx, qy);
            let dm = [(m[0] - m_prev[0]) * size[0], (m[1] - m_prev[1]) * size[1]];
            let motion_ok = (dm[0] * dm[0] + dm[1] * dm[1]).sqrt() < p.tuning[0];
            let spread = [(hi[0] - lo[0]) * size[0], (hi[1] - lo[1]) * size[1]];
            let spread = (spread[0] * spread[0] + spread[1] * spread[1]).sqrt();
            let alpha = buffer_alpha(p, spread, motion_ok, inside_uv(uv));
            let hs = history.sample(uv[0], uv[1]);
            let i = y as usize * w + x as usize;
            for k in 0..2 {
                let t = p.tuning[1] / size[k];
                let hc = hs[k].clamp(lo[k] - t, hi[k] + t);
                out.texels[i][k] = hc + (m[k] - hc) * alpha;
            }
        }
    }
    out
}

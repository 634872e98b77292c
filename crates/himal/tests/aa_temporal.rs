//! A2–A4 GPU passes against their CPU twins: FLIPQUAD resolve (with
//! accepted and rejected history), TAA update, unsharp.

use half::f16;
use himal::gpu::testing::shared_context;
use himal::gpu::{GpuContext, read_texture};
use himal::graph::FrameGraph;
use himal::passes::aa::smaa::reference::{Plane, srgb_to_linear};
use himal::passes::aa::temporal::reference as twin;
use himal::passes::aa::temporal::{
    AaParams, MOTION_FORMAT, RESOLVED_FORMAT, ResolveMode, TemporalPass, TemporalTuning,
};

const W: usize = 24;
const H: usize = 20;
const SRGB: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

fn texture(ctx: &GpuContext, format: wgpu::TextureFormat, bytes: &[u8], bpp: u32) -> wgpu::Texture {
    let t = himal::gpu::texture_2d(
        &ctx.device,
        "test.aa",
        (W as u32, H as u32),
        1,
        format,
        wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_DST
            | wgpu::TextureUsages::COPY_SRC,
    );
    if !bytes.is_empty() {
        ctx.queue.write_texture(
            t.as_image_copy(),
            bytes,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(W as u32 * bpp),
                rows_per_image: None,
            },
            t.size(),
        );
    }
    t
}

/// An sRGB test image: stripes and a square whose position depends on `shift`.
fn image(shift: i64, tint: u8) -> Vec<[u8; 4]> {
    (0..W * H)
        .map(|i| {
            let (x, y) = ((i % W) as i64, (i / W) as i64);
            let sx = x - shift;
            let square = (6..14).contains(&sx) && (5..13).contains(&y);
            let stripe = ((sx + 2 * y) / 3) % 2 == 0;
            match (square, stripe) {
                (true, _) => [230, 200, tint, 255],
                (false, true) => [40, 60, 90, 255],
                (false, false) => [120, 130, 110, 255],
            }
        })
        .collect()
}

fn linear(img: &[[u8; 4]]) -> Plane<4> {
    let mut p = Plane::new(W, H);
    for (t, b) in p.texels.iter_mut().zip(img) {
        *t = [
            srgb_to_linear(b[0] as f32 / 255.0),
            srgb_to_linear(b[1] as f32 / 255.0),
            srgb_to_linear(b[2] as f32 / 255.0),
            1.0,
        ];
    }
    p
}

/// Motion field (uv units) rounded through f16 as the GPU stores it.
fn motion(f: impl Fn(usize, usize) -> [f32; 2]) -> (Vec<f16>, Plane<2>) {
    let mut plane = Plane::new(W, H);
    let mut halfs = Vec::new();
    for y in 0..H {
        for x in 0..W {
            let m = f(x, y).map(f16::from_f32);
            halfs.extend(m);
            plane.texels[y * W + x] = m.map(f32::from);
        }
    }
    (halfs, plane)
}

fn read_f16(ctx: &GpuContext, t: &wgpu::Texture) -> Vec<f32> {
    let bytes = read_texture(ctx, t, 0, 0).expect("read back").bytes;
    bytemuck::cast_slice::<u8, f16>(&bytes)
        .iter()
        .map(|v| f32::from(*v))
        .collect()
}

fn submit(ctx: &GpuContext, g: FrameGraph<'_>) {
    himal::graph::run(ctx, g, None, "test").expect("frame graph");
    ctx.wait("test").expect("gpu");
}

fn worst(gpu: &[f32], cpu: &Plane<4>) -> f32 {
    cpu.texels
        .iter()
        .enumerate()
        .flat_map(|(i, t)| (0..3).map(move |c| (i, c, t[c])))
        .map(|(i, c, v)| (gpu[i * 4 + c] - v).abs())
        .fold(0.0, f32::max)
}

#[test]
fn resolve_taa_and_unsharp_match_their_cpu_twins() {
    chain_against_twins(false);
}

/// E4: the same chain reading a particle coverage mask (`REACTIVE`) and a
/// history whose alpha holds last frame's coverage.
#[test]
fn reactive_resolve_and_taa_match_their_cpu_twins() {
    chain_against_twins(true);
}

fn chain_against_twins(reactive: bool) {
    let ctx = shared_context().expect("GPU (lavapipe)");
    let pass = TemporalPass::new(ctx, SRGB).expect("pipelines");
    // Frame B (phase 1); the scene moved 1 px right per frame, except a
    // 4-pixel-wide band whose motion is incoherent between frames.
    let (cur, prev, prev2) = (image(2, 40), image(1, 40), image(0, 40));
    let jitter = [1.0 / 6.0, -0.5];
    let prev_jitter = [-0.5, -1.0 / 6.0];
    // Raw motion includes the jitter change: jitter-free m0 = -1 px in x.
    let raw = |x: usize, _y: usize| {
        let m0 = if (16..20).contains(&x) { -3.0 } else { -1.0 };
        [
            (m0 - (prev_jitter[0] - jitter[0])) / W as f32,
            (-(prev_jitter[1] - jitter[1])) / H as f32,
        ]
    };
    let (m_half, m_plane) = motion(raw);
    let (mp_half, mp_plane) = motion(|_, _| [-1.0 / W as f32, 0.0]);
    let tuning = TemporalTuning::default();
    let params = AaParams::new(jitter, prev_jitter, 5, 1, &tuning);
    pass.update(&ctx.queue, &params);

    let t_cur = texture(ctx, SRGB, bytemuck::cast_slice(&cur), 4);
    let t_prev = texture(ctx, SRGB, bytemuck::cast_slice(&prev), 4);
    let t_prev2 = texture(ctx, SRGB, bytemuck::cast_slice(&prev2), 4);
    let t_m = texture(ctx, MOTION_FORMAT, bytemuck::cast_slice(&m_half), 4);
    let t_mp = texture(ctx, MOTION_FORMAT, bytemuck::cast_slice(&mp_half), 4);
    let t_mn = texture(ctx, MOTION_FORMAT, &[], 4);
    // TAA history: the previous image, linear, as f16.
    let mut hist_plane = linear(&prev);
    // Coverage in [0, 0.25): partial weights below 1 / AA_REACTIVE_GAIN.
    let cov_bytes: Vec<u8> = (0..W * H)
        .map(|i| {
            if reactive {
                ((i % W) * 7 + (i / W) * 5) as u8 % 64
            } else {
                0
            }
        })
        .collect();
    let mut cov_plane = Plane::<1>::new(W, H);
    for (t, &b) in cov_plane.texels.iter_mut().zip(&cov_bytes) {
        t[0] = b as f32 / 255.0;
    }
    if reactive {
        for (i, t) in hist_plane.texels.iter_mut().enumerate() {
            t[3] = (((i % W) * 5 + (i / W) * 13) % 7) as f32 / 28.0;
        }
    }
    let t_cov = texture(ctx, wgpu::TextureFormat::R8Unorm, &cov_bytes, 1);
    let hist: Vec<f16> = hist_plane
        .texels
        .iter()
        .flatten()
        .map(|&v| f16::from_f32(v))
        .collect();
    let t_hist = texture(ctx, RESOLVED_FORMAT, bytemuck::cast_slice(&hist), 8);
    let t_hist_next = texture(ctx, RESOLVED_FORMAT, &[], 8);
    let t_taa_out = texture(ctx, RESOLVED_FORMAT, &[], 8);
    let t_resolved = texture(ctx, RESOLVED_FORMAT, &[], 8);
    let t_unsharp = texture(ctx, RESOLVED_FORMAT, &[], 8);
    let mut g = FrameGraph::new();
    let c = g.import_texture("cur", &t_cur);
    let p1 = g.import_texture("prev", &t_prev);
    let p2 = g.import_texture("prev2", &t_prev2);
    let m = g.import_texture("m", &t_m);
    let mp = g.import_texture("mp", &t_mp);
    let mn = g.import_texture("mn", &t_mn);
    let cov = g.import_texture("cov", &t_cov);
    let h = g.import_texture("h", &t_hist);
    let (resolved, mn) = pass.add_resolve(
        ctx,
        &mut g,
        (ResolveMode::FlipQuad, false),
        c,
        (p1, p2),
        m,
        mp,
        mn,
        reactive.then_some((cov, h)),
    );
    let keep = g.import_texture("resolved.copy", &t_resolved);
    let keep = pass.add_unsharp(ctx, &mut g, resolved, keep);
    g.mark_output(keep);
    g.mark_output(mn);
    submit(ctx, g);
    // Second graph (pass ids are unique per graph): TAA on the unsharpened
    // resolve, then unsharp again.
    let mut g = FrameGraph::new();
    let keep = g.import_texture("resolved.copy", &t_resolved);
    let mn = g.import_texture("mn", &t_mn);
    let mp = g.import_texture("mp", &t_mp);
    let h = g.import_texture("h", &t_hist);
    let hn = g.import_texture("hn", &t_hist_next);
    let out = g.import_texture("out", &t_taa_out);
    let cov = g.import_texture("cov", &t_cov);
    let cov = reactive.then_some(cov);
    let (hn, out) = pass.add_taa(ctx, &mut g, keep, (h, hn), mn, mp, cov, out);
    let u = g.import_texture("unsharp", &t_unsharp);
    let u = pass.add_unsharp(ctx, &mut g, out, u);
    for h in [hn, u] {
        g.mark_output(h);
    }
    submit(ctx, g);

    let mut hist_f16 = hist_plane.clone();
    for t in &mut hist_f16.texels {
        *t = t.map(|v| f32::from(f16::from_f32(v)));
    }
    // CPU chain, each step fed with the GPU's previous result where the GPU
    // quantises (f16 targets).
    let (cpu_resolved, cpu_motion) = twin::resolve(
        &params,
        ResolveMode::FlipQuad,
        &linear(&cur),
        &linear(&prev),
        &linear(&prev2),
        &m_plane,
        &mp_plane,
        reactive.then_some((&cov_plane, &hist_f16)),
    );
    if reactive {
        let (plain, _) = twin::resolve(
            &params,
            ResolveMode::FlipQuad,
            &linear(&cur),
            &linear(&prev),
            &linear(&prev2),
            &m_plane,
            &mp_plane,
            None,
        );
        let moved = (plain.texels.iter().zip(&cpu_resolved.texels))
            .filter(|(a, b)| (a[0] - b[0]).abs() > 1e-3)
            .count();
        println!("reactive: {moved} resolved pixels moved toward the current frame");
        assert!(
            moved > 50,
            "the coverage barely changed the resolve ({moved})"
        );
    }
    let gpu_motion = read_f16(ctx, &t_mn);
    let dm = cpu_motion
        .texels
        .iter()
        .enumerate()
        .map(|(i, t)| {
            (gpu_motion[2 * i] - t[0])
                .abs()
                .max((gpu_motion[2 * i + 1] - t[1]).abs())
        })
        .fold(0.0, f32::max);
    // f16 storage of the same f32 value: 0 measured 2026-11-22; threshold 1e-4.
    assert!(dm < 1e-4, "motion history differs by {dm}");
    let cpu_unsharp0 = twin::unsharp(&params, &cpu_resolved);
    let gpu_unsharp0 = read_f16(ctx, &t_resolved);
    let d_resolve = worst(&gpu_unsharp0, &cpu_unsharp0);
    // How many pixels took the previous frame: the stripes moved coherently.
    let accepted = cpu_resolved
        .texels
        .iter()
        .zip(&linear(&cur).texels)
        .filter(|(a, b)| (a[0] - b[0]).abs() > 1e-3)
        .count();
    println!(
        "resolve+unsharp: max |diff| {d_resolve}, {accepted} pixels differ from the current frame"
    );
    // Measured 2026-11-22: 0.0022 (f16 targets); threshold 0.004.
    assert!(d_resolve < 0.004, "resolve + unsharp differ by {d_resolve}");
    assert!(accepted > 50, "the resolve should mix frames ({accepted})");

    let mut gpu_in = Plane::<4>::new(W, H);
    for (k, t) in gpu_in.texels.iter_mut().enumerate() {
        *t = [
            gpu_unsharp0[4 * k],
            gpu_unsharp0[4 * k + 1],
            gpu_unsharp0[4 * k + 2],
            1.0,
        ];
    }
    let gpu_mn = {
        let mut p = Plane::<2>::new(W, H);
        for (k, t) in p.texels.iter_mut().enumerate() {
            *t = [gpu_motion[2 * k], gpu_motion[2 * k + 1]];
        }
        p
    };
    let cpu_taa = twin::taa(
        &params,
        &gpu_in,
        &hist_f16,
        &gpu_mn,
        &mp_plane,
        reactive.then_some(&cov_plane),
    );
    let gpu_taa = read_f16(ctx, &t_taa_out);
    let d_taa = worst(&gpu_taa, &cpu_taa);
    println!("taa: max |diff| {d_taa}");
    // Measured 2026-11-22: 0.00049; threshold 0.004.
    assert!(d_taa < 0.004, "TAA differs by {d_taa}");

    let mut taa_in = Plane::<4>::new(W, H);
    for (k, t) in taa_in.texels.iter_mut().enumerate() {
        *t = [gpu_taa[4 * k], gpu_taa[4 * k + 1], gpu_taa[4 * k + 2], 1.0];
    }
    let cpu_u = twin::unsharp(&params, &taa_in);
    let d_u = worst(&read_f16(ctx, &t_unsharp), &cpu_u);
    println!("unsharp: max |diff| {d_u}");
    // Measured 2026-11-22: 0.00047; threshold 0.004.
    assert!(d_u < 0.004, "unsharp differs by {d_u}");
}

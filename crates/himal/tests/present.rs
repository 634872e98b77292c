//! Window presentation (`himal::present`): the GPU pass that copies a frame
//! into a swapchain-format image and blends the HUD over it, against its CPU
//! twin `present::reference::compose`.

use himal::gpu::read_texture;
use himal::gpu::testing::shared_context;
use himal::present::{Hud, Overlay, Presenter, reference::compose};
use wgpu::util::DeviceExt;

const W: u32 = 96;
const H: u32 = 64;

/// A frame like the renderer's output: Rgba8UnormSrgb with an Rgba8Unorm view.
fn frame_texture(ctx: &himal::gpu::GpuContext, texels: &[[u8; 4]]) -> wgpu::Texture {
    ctx.device.create_texture_with_data(
        &ctx.queue,
        &wgpu::TextureDescriptor {
            label: Some("test.frame"),
            size: wgpu::Extent3d {
                width: W,
                height: H,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8UnormSrgb,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[wgpu::TextureFormat::Rgba8Unorm],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        bytemuck::cast_slice(texels),
    )
}

fn target(ctx: &himal::gpu::GpuContext, format: wgpu::TextureFormat) -> wgpu::Texture {
    himal::gpu::texture_2d(
        &ctx.device,
        "test.swapchain",
        (W, H),
        1,
        format,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    )
}

#[test]
fn presented_frame_with_hud_matches_the_cpu_twin() {
    let ctx = shared_context().expect("GPU");
    // A gradient frame with every byte value, and a HUD with text and bars.
    let texels: Vec<[u8; 4]> = (0..W * H)
        .map(|i| {
            let (x, y) = (i % W, i / W);
            [
                (x * 255 / (W - 1)) as u8,
                (y * 255 / (H - 1)) as u8,
                ((x * y) % 256) as u8,
                255,
            ]
        })
        .collect();
    let hud = Hud {
        lines: vec!["himal 60.0 fps".into()],
        timings: vec![("gbuffer".into(), 2.5), ("lighting".into(), 1.0)],
    };
    let overlay = Overlay::hud(&hud);
    let origin = [3, 5];
    let expected = compose(&texels, W, &overlay, origin);
    let frame = frame_texture(ctx, &texels);
    let mut presenter = Presenter::new(ctx).expect("presenter");
    for format in [
        wgpu::TextureFormat::Bgra8Unorm,
        wgpu::TextureFormat::Bgra8UnormSrgb,
        wgpu::TextureFormat::Rgba8Unorm,
    ] {
        let t = target(ctx, format);
        let view = t.create_view(&Default::default());
        presenter
            .present(ctx, &frame, Some((&overlay, origin)), &view, format)
            .expect("present");
        let got = read_texture(ctx, &t, 0, 0).expect("read back");
        let bgra = matches!(
            format,
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
        );
        let mut worst = 0i32;
        let mut differing = 0;
        for (i, e) in expected.iter().enumerate() {
            let g = &got.bytes[4 * i..4 * i + 4];
            let g = if bgra {
                [g[2], g[1], g[0], g[3]]
            } else {
                [g[0], g[1], g[2], g[3]]
            };
            let d = (0..4)
                .map(|c| (i32::from(g[c]) - i32::from(e[c])).abs())
                .max()
                .unwrap_or(0);
            worst = worst.max(d);
            differing += usize::from(d > 0);
        }
        println!(
            "{format:?}: worst {worst}/255, {differing} of {} texels differ",
            expected.len()
        );
        // Measured 2026-11-22 on lavapipe: exact for the unorm targets; the
        // sRGB target is off by 1/255 in 876 of 6144 texels (the f32 decode
        // in the shader and the hardware encode do not round-trip exactly).
        assert!(worst <= 1, "{format:?}: worst {worst}/255");
    }
    // The HUD is really there: the panel darkens the frame under it.
    let under = 4 * (origin[1] * W + origin[0] + 1) as usize;
    assert!(expected[under / 4][0] < texels[under / 4][0] || texels[under / 4][0] < 20);
}

#[test]
fn presenting_without_an_overlay_is_a_copy() {
    let ctx = shared_context().expect("GPU");
    let texels: Vec<[u8; 4]> = (0..W * H)
        .map(|i| [(i % 251) as u8, (i % 13 * 19) as u8, 7, 255])
        .collect();
    let frame = frame_texture(ctx, &texels);
    let mut presenter = Presenter::new(ctx).expect("presenter");
    let t = target(ctx, wgpu::TextureFormat::Rgba8Unorm);
    presenter
        .present(
            ctx,
            &frame,
            None,
            &t.create_view(&Default::default()),
            wgpu::TextureFormat::Rgba8Unorm,
        )
        .expect("present");
    let got = read_texture(ctx, &t, 0, 0).expect("read back");
    assert_eq!(got.bytes, bytemuck::cast_slice::<[u8; 4], u8>(&texels));
}

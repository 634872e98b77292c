//! Anti-aliasing and AO together (issue #4 leftovers, TECHNIQUES A3 / O2):
//! - AO under projection jitter: on a static camera the temporal modes'
//!   jitter must not make the AO wobble (the STF reprojects with
//!   jitter-free motion).
//! - `--aa-buffers ao|motion`: the TAA on the AO and on the motion vectors
//!   lowers their temporal std on the slow-motion sequence of `aa_frame.rs`.

mod common;

use common::{renderer, scene_and_camera};
use glam::Vec3;
use himal::passes::aa::{AaBuffers, AaMode, TemporalTuning};
use himal::passes::ao::{AoSettings, AoView};
use himal::passes::debug::DebugView;
use himal::scene::Scene;
use himal::{FrameSettings, ViewBuffer};

fn ao_settings(scene: &Scene, size: (u32, u32), aa: AaMode, ao: AoSettings) -> FrameSettings {
    let mut s = FrameSettings::new(size.0, size.1, scene.sun.clone());
    s.shadow_resolution = 0;
    s.aerial_extinction = 0.0;
    s.ao = ao;
    s.aa = aa;
    s.view = ViewBuffer::Ao(AoView::Ao);
    s.raw = true;
    s
}

/// Mean over pixels with geometry of the temporal std of AO over frames
/// `warm..frames` of a static camera (time frozen: the grass does not sway).
fn static_ao_std(aa: AaMode, ao: AoSettings, buffers: AaBuffers, size: (u32, u32)) -> f32 {
    let (warm, frames) = (8, 20);
    let (scene, mut camera) = scene_and_camera("grass_patch", "main");
    // The O2 flicker test's distance: blades of one or two pixels.
    camera.position -= camera.forward * camera.position.length();
    let mut r = renderer(&scene);
    let mut s = ao_settings(&scene, size, aa, ao);
    s.aa_buffers = buffers;
    let images: Vec<Vec<[f32; 4]>> = (0..frames)
        .map(|_| common::render_rgba(&mut r, &camera, &s))
        .collect();
    let images = &images[warm as usize..];
    let pixels: Vec<usize> = (0..images[0].len())
        .filter(|&i| images[0][i][1] < 1000.0)
        .collect();
    common::mean_temporal_std(images, &pixels)
}

#[test]
fn ao_does_not_wobble_under_jitter() {
    let size = (200, 125);
    let ao = AoSettings::default;
    let hraa = static_ao_std(AaMode::Hraa, ao(), AaBuffers::default(), size);
    let taa = static_ao_std(AaMode::Taa, ao(), AaBuffers::default(), size);
    let both = AaBuffers {
        ao: true,
        motion: true,
    };
    let hraa_buffers = static_ao_std(AaMode::Hraa, ao(), both, size);
    eprintln!(
        "static AO temporal std: hraa {hraa:.5}, taa {taa:.5}, hraa + --aa-buffers ao,motion {hraa_buffers:.5}"
    );
    // Measured 2026-11-22 (lavapipe): hraa 0.00032, taa 0.00051 (the STF
    // reprojecting with the jitter change: 0.00094 and 0.00108; --aa none: 0);
    // thresholds 0.0005 and 0.0007.
    assert!(hraa <= 0.0005, "hraa {hraa}");
    assert!(taa <= 0.0007, "taa {taa}");
    // Measured 0.00030: the AO TAA must not add wobble; threshold the hraa bound.
    assert!(hraa_buffers <= 0.0005, "hraa + buffers {hraa_buffers}");
}

/// Mean over pixels of the temporal std, and of the frame-to-frame change,
/// of channels `channels` (summed) of the raw view `s.view` over 32 frames of
/// the slow sideways motion of `tests/aa_frame.rs` (aa_edges.toml, 128x128,
/// 0.1 px per frame) after 8 warm-up frames.
fn slow_motion_std(s: &FrameSettings, channels: &[usize]) -> (f32, f32) {
    let (scene, camera) = scene_and_camera("aa_edges", "main");
    let mut r = renderer(&scene);
    let images: Vec<Vec<[f32; 4]>> = (0..40)
        .map(|i| {
            let mut cam = camera.clone();
            cam.position += Vec3::new(0.0034 * i as f32, 0.0, 0.0);
            common::render_rgba(&mut r, &cam, s)
        })
        .collect();
    let images = &images[8..];
    let n = images.len() as f32;
    let pixels = images[0].len();
    let sum = |f: &dyn Fn(usize, usize) -> f32| -> f32 {
        (0..pixels)
            .map(|i| channels.iter().map(|&c| f(i, c)).sum::<f32>())
            .sum::<f32>()
            / pixels as f32
    };
    let std = sum(&|i, c| {
        let mean = images.iter().map(|f| f[i][c]).sum::<f32>() / n;
        (images.iter().map(|f| (f[i][c] - mean).powi(2)).sum::<f32>() / n).sqrt()
    });
    let change = sum(&|i, c| {
        images
            .windows(2)
            .map(|w| (w[1][i][c] - w[0][i][c]).abs())
            .sum::<f32>()
            / (n - 1.0)
    });
    (std, change)
}

fn slow_motion_settings(
    view: ViewBuffer,
    buffers: AaBuffers,
    tuning: TemporalTuning,
) -> FrameSettings {
    let (scene, _) = scene_and_camera("aa_edges", "main");
    let mut s = ao_settings(&scene, (128, 128), AaMode::Hraa, AoSettings::default());
    s.view = view;
    s.aa_buffers = buffers;
    s.aa_tuning = tuning;
    s.bloom.enabled = false;
    s.adaptation.enabled = false;
    s
}

#[test]
fn taa_on_ao_reduces_its_temporal_std() {
    let view = ViewBuffer::Ao(AoView::Ao);
    let t = TemporalTuning::default;
    let ao_only = AaBuffers {
        ao: true,
        motion: false,
    };
    let without = slow_motion_std(&slow_motion_settings(view, AaBuffers::default(), t()), &[0]);
    let with = slow_motion_std(&slow_motion_settings(view, ao_only, t()), &[0]);
    eprintln!(
        "slow motion, AO: temporal std {:.5} without, {:.5} with aa.taa_ao ({:.2}x); frame-to-frame change {:.5}, {:.5}",
        without.0,
        with.0,
        with.0 / without.0,
        without.1,
        with.1
    );
    // Measured 2026-11-22 (lavapipe, hraa): std 0.01006 without, 0.00514 with
    // (0.51x); threshold 0.7x.
    assert!(with.0 <= 0.7 * without.0, "{with:?} vs {without:?}");
}

#[test]
fn taa_on_motion_reduces_its_temporal_std() {
    let view = ViewBuffer::Debug(DebugView::Motion);
    let motion = AaBuffers {
        ao: false,
        motion: true,
    };
    // Without accumulation (new-frame weight 1) the stage writes the plain
    // jitter-free motion: the baseline.
    let plain = TemporalTuning {
        alpha_low_frequency: 1.0,
        alpha_high_frequency: 1.0,
        ..TemporalTuning::default()
    };
    let without = slow_motion_std(&slow_motion_settings(view, motion, plain), &[0, 1]);
    let with = slow_motion_std(
        &slow_motion_settings(view, motion, TemporalTuning::default()),
        &[0, 1],
    );
    eprintln!(
        "slow motion, motion (px): temporal std {:.5} without, {:.5} with aa.taa_motion ({:.2}x); frame-to-frame change {:.5}, {:.5}",
        without.0,
        with.0,
        with.0 / without.0,
        without.1,
        with.1
    );
    // Measured 2026-11-22 (lavapipe, hraa): std 0.00144 px without, 0.00069
    // with (0.48x); frame-to-frame 0.00143, 0.00053; threshold 0.7x.
    assert!(with.0 <= 0.7 * without.0, "{with:?} vs {without:?}");
}

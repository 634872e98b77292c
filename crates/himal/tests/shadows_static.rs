//! S2 static shadow map: time slicing (CPU) and the shadow draw calls it
//! saves over a camera path through a field of boxes (GPU frames).

use std::fmt::Write;

mod common;

use common::renderer;
use glam::Vec3;
use himal::FrameSettings;
use himal::passes::shadows::ShadowMode;
use himal::passes::shadows::static_map::StaticMapState;
use himal::scene::Aabb;

#[test]
fn static_map_fills_in_capped_slices_and_follows_the_sun() {
    let bounds = Aabb::new(Vec3::splat(-500.0), Vec3::splat(500.0));
    let mut state = StaticMapState::default();
    let (total, cap) = (100usize, 30usize);
    let mut fills = 0;
    let mut covered = vec![0u32; total];
    for frame in 0..40 {
        // The sun turns 0.25° a frame (a minute of the day), faster than one fill.
        let a = 0.6 + 0.25f32.to_radians() * frame as f32;
        let sun = Vec3::new(a.cos(), a.sin(), 0.3).normalize();
        let before = state.shown.map(|(i, _)| i);
        let Some(u) = state.plan(&bounds, sun, 512, total, cap) else {
            continue;
        };
        assert!(
            u.range.len() <= cap,
            "frame {frame}: {} draws",
            u.range.len()
        );
        if u.clear {
            covered.iter_mut().for_each(|c| *c = 0);
        }
        for i in u.range.clone() {
            covered[i] += 1;
        }
        // The fill writes the map not shown.
        assert_ne!(Some(u.target), before, "frame {frame} writes the shown map");
        if u.range.end == total {
            fills += 1;
            // Each static draw once per fill.
            assert!(
                covered.iter().all(|&c| c == 1),
                "frame {frame}: {covered:?}"
            );
            assert_eq!(state.shown.map(|(i, _)| i), Some(u.target));
        }
    }
    // 4 frames a fill (100 / 30, rounded up): 10 fills in 40 frames.
    assert_eq!(fills, 10);
}

/// `scenes/shadow_field.toml` (a 1 km plane, one orbiting ball) with a 12x12
/// grid of houses 40 m apart.
fn field() -> String {
    let mut s = common::scene_text("shadow_field");
    for z in 0..12 {
        let _ = write!(
            s,
            "\n[[object]]\nname = \"row{z}\"\nprimitive = \"box\"\nmaterial = \"white\"\nsize = [6.0, 8.0, 6.0]\nposition = [-220.0, 4.0, {}]\nrepeat = {{ count = 12, step = [40.0, 0, 0] }}\n",
            -220.0 + 40.0 * z as f32
        );
    }
    s
}

#[test]
fn static_map_saves_shadow_draws_on_a_camera_path() {
    let text = field();
    let scene = common::parse_scene(&text, "shadow_field.toml");
    let camera = scene.camera("walk").expect("camera").clone();
    let mut totals = Vec::new();
    for mode in [ShadowMode::Csm, ShadowMode::CsmStatic] {
        let mut r = renderer(&scene);
        let mut s = FrameSettings::new(64, 36, scene.sun.clone());
        s.shadow_resolution = 256;
        s.shadows.mode = mode;
        s.shadows.static_resolution = 1024;
        // S2's saving is counted in object draws (one per object, V6 off);
        // instancing (V6) merges both paths' draws to a few hundred, where
        // csm+static still draws 14 % fewer (424 vs 366 on 2026-12-02).
        s.instancing = false;
        let cap = s.shadows.static_draw_cap;
        let mut sum = 0u32;
        for i in 0..24 {
            let mut cam = camera.clone();
            cam.position += Vec3::new(1.0, 0.0, 1.0).normalize() * (6.0 * i as f32);
            s.time_s = i as f32 / 30.0;
            let frame = r.render(&cam, &s).expect("frame");
            let st = &frame.shadows;
            assert!(
                st.static_draws <= cap,
                "frame {i}: {} static draws > cap {cap}",
                st.static_draws
            );
            sum += st.draws;
            if i < 4 || i == 23 {
                eprintln!(
                    "{mode:?} frame {i}: {} shadow draws ({} cascades, {} static, static shown {})",
                    st.draws, st.cascades_rendered, st.static_draws, st.static_shown
                );
            }
        }
        totals.push(sum);
    }
    let saved = 1.0 - totals[1] as f64 / totals[0] as f64;
    eprintln!(
        "24 frames: {} shadow draws with csm, {} with csm+static: {:.1}% fewer",
        totals[0],
        totals[1],
        100.0 * saved
    );
    // Issue #6 (talk: 40-60%) asks >= 40%. Measured 2026-11-22 on lavapipe:
    // 4657 vs 1736 draws, 62.7% fewer; no frame above the cap of 48.
    assert!(
        saved >= 0.40,
        "only {:.1}% fewer shadow draws",
        100.0 * saved
    );
}

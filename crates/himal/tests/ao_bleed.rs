//! O5 AO colour bleeding (Ryse): the WGSL formula and the bleed texture's
//! passes against their CPU twins (`passes/ao/bleed/reference.rs`), and the
//! coloured occlusion of a white floor next to a red wall
//! (`scenes/ao_bleed_corner.toml`) against a ray-traced one-bounce estimate
//! (`himal_reference::bounce`). Numbers: `cargo test --release -p himal
//! --test ao_bleed -- --nocapture`; docs/techniques/O5.md.

mod common;

use common::{pixel_ray_from, render_rgba as render, renderer};
use glam::{Vec3, Vec4};
use himal::FrameSettings;
use himal::gpu::testing::run_compute;
use himal::passes::ao::bleed::reference as twin;
use himal::passes::ao::{AoMode, AoSettings};
use himal::scene::{Camera, Scene, SunLight};
use himal_reference::ao::{Shape, one_bounce_occlusion, trace_index};

const SIZE: (u32, u32) = (160, 120);
const RED: Vec3 = Vec3::new(0.8, 0.05, 0.05);
const WHITE: Vec3 = Vec3::splat(0.8);

/// The analytic shapes of `ao_bleed_corner.toml` and their albedos.
fn shapes() -> (Vec<Shape>, Vec<Vec3>) {
    let floor = Shape::Plane {
        normal: Vec3::Y,
        offset: 0.0,
    };
    let wall = Shape::Box {
        min: Vec3::new(-2.0, 0.0, -0.4),
        max: Vec3::new(2.0, 2.0, 0.0),
    };
    (vec![floor, wall], vec![WHITE, RED])
}

fn load() -> (Scene, Camera) {
    common::scene_and_camera("ao_bleed_corner", "main")
}

/// A raw frame of `view` lit by the sky alone (the sun's illuminance zero,
/// so the floor shows ambient diffuse, whose occlusion O5 changes).
fn settings(scene: &Scene, view: &str, ao: AoMode, bleed: bool) -> FrameSettings {
    let mut s = common::raw_settings(scene, SIZE, view);
    let sky = himal::passes::sky::SkyLight::of_sun(&scene.sun);
    s.sun.light = Some(SunLight {
        to_light: sky.sun_direction,
        illuminance_klux: Vec3::ZERO,
    });
    s.shadow_resolution = 0;
    s.aerial_extinction = 0.0;
    s.environment_specular = false;
    s.ao = AoSettings {
        mode: ao,
        bleed,
        ..AoSettings::default()
    };
    s
}

#[test]
fn bleed_formula_matches_the_cpu_twin() {
    const KERNEL: &str = r#"
#import ao_bleed
@group(0) @binding(0) var<storage, read> input: array<vec4f>;
@group(0) @binding(1) var<storage, read_write> output: array<vec4f>;
@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    if (id.x >= arrayLength(&input)) { return; }
    let x = input[id.x];
    output[id.x] = vec4f(ao_bleed_occlusion(x.w, ao_bleed_colour(vec4f(x.rgb, 0.5)) * 0.5), 0.0);
}
"#;
    // occl in [0, 1] x bleed channels across the 0.7 / 3 cap.
    let mut input = Vec::new();
    for i in 0..=16 {
        for j in 0..=12 {
            let c = j as f32 / 12.0;
            input.push(Vec4::new(c, 0.5 * c, 0.05 + 0.1 * c, i as f32 / 16.0));
        }
    }
    let bytes = bytemuck::cast_slice::<Vec4, u8>(&input);
    let out = run_compute(KERNEL, "cs_main", bytes, bytes.len() as u64, [4, 1, 1])
        .unwrap_or_else(|e| panic!("kernel: {e}"));
    let gpu: &[Vec4] = bytemuck::cast_slice(&out);
    let mut worst = 0.0f32;
    for (x, g) in input.iter().zip(gpu) {
        let bleed = twin::bleed_colour(x.truncate().extend(0.5)) * 0.5;
        let cpu = twin::bleed_occlusion(x.w, bleed);
        worst = worst.max((g.truncate() - cpu).abs().max_element());
    }
    eprintln!(
        "bleed formula: max |GPU - CPU| {worst:.2e} over {} inputs",
        input.len()
    );
    // Measured 2026-12-05 (lavapipe): 1.2e-7; f32 pow on both sides.
    assert!(worst < 1e-5, "{worst}");
}

#[test]
fn bleed_texture_matches_the_cpu_twin() {
    let (scene, camera) = load();
    let mut r = renderer(&scene);
    let mut frame = |view| render(&mut r, &camera, &settings(&scene, view, AoMode::Hbao, true));
    let albedo = frame("albedo");
    let depth = frame("depth");
    let bleed = frame("ao-bleed");
    let (w, h) = (SIZE.0 as usize, SIZE.1 as usize);
    let albedo: Vec<Vec3> = albedo.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect();
    let depth: Vec<f32> = depth.iter().map(|p| p[0]).collect();
    let cpu = twin::bleed_texture(&albedo, &depth, w, h);
    let mut worst = 0.0f32;
    for y in 0..h {
        for x in 0..w {
            let g = Vec4::from(bleed[y * w + x]);
            let c = cpu.data[(y / 4) * cpu.w + x / 4];
            worst = worst.max((g - c).abs().max_element());
        }
    }
    let floor_red = twin::bleed_colour(cpu.data[(h / 4 - 2) * cpu.w + cpu.w / 2]);
    eprintln!("bleed texture: max |GPU - CPU| {worst:.2e}; bleed near the bottom {floor_red}");
    // Measured 2026-12-05 (lavapipe): 1.1e-3, the Rgba16Float rounding of
    // values up to 0.8 (half a unit in the last place: 2.4e-4) over three steps.
    assert!(worst < 2e-3, "{worst}");
}

/// Measured occlusion per pixel (GPU bleed on, off; each frame over the
/// frame without AO) and the one-bounce reference, every other pixel.
#[derive(Default)]
struct Region {
    on: Vec<Vec3>,
    off: Vec<Vec3>,
    reference: Vec<Vec3>,
}

impl Region {
    fn push(&mut self, on: Vec3, off: Vec3, reference: Vec3) {
        self.on.push(on);
        self.off.push(off);
        self.reference.push(reference);
    }
}

/// (floor within 0.6 m of the wall, every pixel with geometry, open floor).
fn corner(floor_albedo: f32, wall: Vec3) -> (Region, Region, Region) {
    let text = format!("albedo_linear = [{floor_albedo}, {floor_albedo}, {floor_albedo}]");
    let wall_text = format!("albedo_linear = [{}, {}, {}]", wall.x, wall.y, wall.z);
    let scene = common::scene_with(
        "ao_bleed_corner",
        &[
            ("albedo_linear = [0.8, 0.8, 0.8]", text.as_str()),
            ("albedo_linear = [0.8, 0.05, 0.05]", wall_text.as_str()),
        ],
    );
    let camera = scene.camera("main").expect("camera").clone();
    let (shapes, mut albedo) = shapes();
    albedo[0] = Vec3::splat(floor_albedo);
    albedo[1] = wall;
    let mut r = renderer(&scene);
    let mut frame = |ao, bleed| render(&mut r, &camera, &settings(&scene, "lighting", ao, bleed));
    // Without AO the frame is the unoccluded ambient: the divisor.
    let open = frame(AoMode::Off, false);
    let off = frame(AoMode::Hbao, false);
    let on = frame(AoMode::Hbao, true);
    let radius = AoSettings::default().radius;
    let (mut near, mut all, mut far) = (Region::default(), Region::default(), Region::default());
    let v3 = |p: [f32; 4]| Vec3::new(p[0], p[1], p[2]);
    for y in (1..SIZE.1).step_by(2) {
        for x in (1..SIZE.0).step_by(2) {
            let (o, d) = pixel_ray_from(&camera, SIZE, x, y);
            let Some((k, hit)) = trace_index(&shapes, o, d, 0.0) else {
                continue;
            };
            let p = o + d * hit.t;
            let i = (y * SIZE.0 + x) as usize;
            let base = v3(open[i]).max(Vec3::splat(1e-6));
            let (g_on, g_off) = (v3(on[i]) / base, v3(off[i]) / base);
            let reference = one_bounce_occlusion(&shapes, &albedo, p, hit.normal, radius, 128, 32);
            all.push(g_on, g_off, reference);
            // The floor in front of the wall, away from its ends.
            if k == 0 && p.z > 0.05 && p.z < 0.6 && p.x.abs() < 1.2 {
                near.push(g_on, g_off, reference);
            } else if k == 0 && p.z > radius + 0.1 {
                far.push(g_on, g_off, reference);
            }
        }
    }
    (near, all, far)
}

fn mean(v: &[Vec3]) -> Vec3 {
    v.iter().sum::<Vec3>() / v.len().max(1) as f32
}

/// Mean |a - b| over pixels and channels.
fn mae(a: &[Vec3], b: &[Vec3]) -> f32 {
    let s: f32 = a
        .iter()
        .zip(b)
        .map(|(a, b)| (*a - *b).abs().element_sum())
        .sum();
    s / (3 * a.len().max(1)) as f32
}

fn tint(o: Vec3) -> f32 {
    o.x / o.y
}

fn report(floor: f32, wall: Vec3) -> (Region, Region, Region) {
    let (near, all, far) = corner(floor, wall);
    let (on, off, reference) = (mean(&near.on), mean(&near.off), mean(&near.reference));
    eprintln!(
        "floor albedo {floor}, wall {wall}: floor near the wall ({} px) occlusion off {off:.3} on {on:.3} one-bounce {reference:.3}",
        near.on.len()
    );
    eprintln!(
        "  R/G tint off {:.3} on {:.3} one-bounce {:.3}; MAE vs one-bounce near: off {:.3} on {:.3}; all {} px: off {:.3} on {:.3}; open floor ({} px) on {:.3}",
        tint(off),
        tint(on),
        tint(reference),
        mae(&near.off, &near.reference),
        mae(&near.on, &near.reference),
        all.on.len(),
        mae(&all.off, &all.reference),
        mae(&all.on, &all.reference),
        far.on.len(),
        mean(&far.on),
    );
    (near, all, far)
}

#[test]
fn bleed_tints_the_floor_by_the_red_wall() {
    // A dark floor (0.2): the floor's own albedo stays under the 0.7 / 3 cap
    // in G and B, so the red wall in the low-frequency albedo shows.
    let (near, _, far) = report(0.2, RED);
    let (on, off, reference) = (mean(&near.on), mean(&near.off), mean(&near.reference));
    assert!(
        near.on.len() > 200 && !far.on.is_empty(),
        "{} px",
        near.on.len()
    );
    // Measured 2026-12-05 (lavapipe, 160x120): R/G off 1.000, on 1.049,
    // one-bounce 1.187: tinted toward red, by a quarter of the reference's.
    assert!(tint(on) > tint(off) + 0.03, "on {on}, off {off}");
    assert!(tint(on) < tint(reference), "on {on}, reference {reference}");
    // The open floor (no occlusion) is untouched: measured 0.999..1.000.
    assert!(mean(&far.on).min_element() > 0.99, "{}", mean(&far.on));
}

/// Where O5 helps and where it does not, against the one-bounce estimate
/// (the numbers behind its default, off; docs/techniques/O5.md).
#[test]
fn bleed_against_the_one_bounce_estimate() {
    // White floor, red wall: the white floor saturates every channel
    // (min(3 x 0.8, 0.7)), so no red tint and all of the occlusion lifted.
    let (near, all, _) = report(0.8, RED);
    let on = mean(&near.on);
    // Measured 2026-12-05: R/G 1.000; MAE near the wall off 0.057, on
    // 0.130; whole frame off 0.029, on 0.032.
    assert!((tint(on) - 1.0).abs() < 0.01, "{on}");
    assert!(mae(&near.off, &near.reference) < mae(&near.on, &near.reference));
    assert!(mae(&all.off, &all.reference) < 0.05 && mae(&all.on, &all.reference) < 0.06);
    // A white corner (both 0.8): bounce light is what O5 stands in for.
    // Measured: near the wall off 0.110, on 0.037; whole frame off 0.038,
    // on 0.018 (grey 0.5 corner: off 0.018, on 0.039; 0.2: off 0.014, on 0.054).
    let (near, all, _) = report(0.8, WHITE);
    assert!(
        mae(&near.on, &near.reference) < 0.06,
        "{}",
        mae(&near.on, &near.reference)
    );
    assert!(mae(&all.on, &all.reference) < mae(&all.off, &all.reference));
}

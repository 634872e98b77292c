//! Height-field sky occlusion (TECHNIQUES L2): the GPU passes against their
//! CPU twin (`passes/skyocc/reference.rs`), the visibility against rays
//! marched over the analytic height field of a canyon and a wall, and the
//! lighting's `SKY_OCCLUSION` permutation against `shade_sky_occluded`.

mod common;

use common::{environment_specular, lighting_params, pixel_ray, render_rgba, renderer};
use glam::{IVec2, Vec2, Vec3};
use himal::gpu::testing::shared_context;
use himal::gpu_scene::SceneGpu;
use himal::passes::lighting::reference::{ambient_luminance_ratio, shade_sky_occluded};
use himal::passes::skyocc::reference::{
    self as twin, HeightImage, MARGIN_TEXELS, RENDER_TEXELS, SECTOR_SIZE, SECTOR_TEXELS, TEXEL_SIZE,
};
use himal::passes::skyocc::{SectorReadback, SkyOccPass, SkyOccView};
use himal::scene::Scene;
use himal::{FrameSettings, ViewBuffer};

/// `scenes/skyocc_ground.toml` plus the objects of `scenes/<objects>.toml`.
fn scene_on_ground(objects: &str) -> Scene {
    let text = format!(
        "{}\n{}",
        common::scene_text("skyocc_ground"),
        common::scene_text(objects)
    );
    common::parse_scene(&text, &format!("skyocc_ground.toml + {objects}.toml"))
}

/// The analytic height of `scenes/skyocc_canyon_and_wall.toml`.
fn canyon_height(x: f32, z: f32) -> f32 {
    if !(8.0..=56.0).contains(&z) {
        return 0.0;
    }
    if (10.0..=20.0).contains(&x) || (26.0..=36.0).contains(&x) {
        5.0
    } else if (46.0..=47.0).contains(&x) {
        4.0
    } else {
        0.0
    }
}

fn scene() -> Scene {
    scene_on_ground("skyocc_canyon_and_wall")
}

/// Twin inputs: bumpy sloped terrain with a pit, and the raw image of that
/// terrain with a 6 m wall on it.
fn synthetic_images(origin: Vec2) -> (HeightImage, HeightImage) {
    let terrain = |x: f32, z: f32| {
        let (lx, lz) = (x - origin.x, z - origin.y);
        let h = 0.05 * lx + 0.3 * (lx * 0.7).sin() * (lz * 0.45).cos();
        let pit = (50.0..60.0).contains(&lx) && (40.0..50.0).contains(&lz);
        if pit { h - 4.0 } else { h }
    };
    let raw = HeightImage::from_fn(RENDER_TEXELS, TEXEL_SIZE, origin, |x, z| {
        let (lx, lz) = (x - origin.x, z - origin.y);
        let wall = (30.0..31.0).contains(&lx) && lz > 20.0;
        terrain(x, z) + if wall { 6.0 } else { 0.0 }
    });
    (
        raw,
        HeightImage::from_fn(RENDER_TEXELS, TEXEL_SIZE, origin, terrain),
    )
}

#[test]
fn blur_and_visibility_match_cpu_twin() {
    let ctx = shared_context().expect("GPU");
    let scene = scene();
    let mut pass = SkyOccPass::new(ctx, &scene).expect("pass");
    let (raw, ground) = synthetic_images(Vec2::new(-9.0, 3.0));
    let gpu = pass
        .run_kernels(ctx, &[(raw.clone(), ground.clone())])
        .expect("kernels");
    let disk = twin::poisson_disk(twin::SAMPLES);
    let (blurred, cpu) = twin::sector_visibility(&raw, &ground, &disk);
    let blur_err = gpu[0]
        .blurred
        .iter()
        .zip(&blurred.h)
        .map(|(g, c)| (g - c).abs())
        .fold(0.0f32, f32::max);
    let (mut sum, mut worst, mut differing) = (0.0f32, 0.0f32, 0usize);
    let mut height_err = 0.0f32;
    for (g, c) in gpu[0].sh.iter().zip(&cpu) {
        let e = (*g - c.sh).abs().max_element();
        sum += e;
        worst = worst.max(e);
        if e > 0.01 {
            differing += 1;
        }
    }
    for (g, c) in gpu[0].heights.iter().zip(&cpu) {
        height_err = height_err.max((*g - c.heights).abs().max_element());
    }
    let n = cpu.len() as f32;
    eprintln!(
        "skyocc twin: blur max {blur_err:.2e} m; SH mean {:.2e}, worst {worst:.3}, {differing} of {n} texels > 0.01; heights max {height_err:.2e}",
        sum / n
    );
    // Same f32 arithmetic, same order: measured blur max 0 m on 2026-11-22; threshold 1e-4.
    assert!(blur_err < 1e-4, "blur {blur_err}");
    // The fade height sums 32 texels in the same order: measured 0 m on
    // 2026-11-22 (3.2e-4 with per-texel rotated taps); threshold 2e-3.
    assert!(height_err < 2e-3, "heights {height_err}");
    // fp16 storage (~1e-3) plus rare samples flipped by rounding at a
    // texel edge (one sample = 1/32 of the cap). Measured on 2026-11-22 (with the 5x5 smoothing): mean 6.3e-4, worst 0.001, 0 texels > 0.01.
    assert!(sum / n < 3e-3, "SH mean error {}", sum / n);
    assert!((differing as f32) < 0.02 * n, "{differing} texels differ");
}

/// GPU sector (0, 0) of the canyon scene through the whole pipeline.
fn canyon_sector() -> SectorReadback {
    let ctx = shared_context().expect("GPU");
    let scene = scene();
    let gpu_scene = SceneGpu::upload(ctx, &scene).expect("upload");
    let mut pass = SkyOccPass::new(ctx, &scene).expect("pass");
    let mut out = pass
        .render_sectors(ctx, &gpu_scene, &[IVec2::new(0, 0)])
        .expect("render");
    out.remove(0)
}

#[test]
fn sky_visibility_matches_ray_traced_height_field() {
    let sector = canyon_sector();
    // Rendered heights: the analytic field, texel for texel; the terrain
    // height (the plane alone, the boxes left out) is 0 everywhere.
    let (mut wrong, mut wrong_terrain) = (0, 0);
    for j in 0..SECTOR_TEXELS {
        for i in 0..SECTOR_TEXELS {
            let (x, z) = ((i as f32 + 0.5) * TEXEL_SIZE, (j as f32 + 0.5) * TEXEL_SIZE);
            let r = (j + MARGIN_TEXELS) * RENDER_TEXELS + i + MARGIN_TEXELS;
            if (sector.raw[r] - canyon_height(x, z)).abs() > 1e-3 {
                wrong += 1;
            }
            if sector.heights[j * SECTOR_TEXELS + i].x.abs() > 1e-3 {
                wrong_terrain += 1;
            }
        }
    }
    // Box edges fall on texel edges; measured 0 wrong texels on 2026-11-22.
    assert!(
        wrong == 0,
        "{wrong} height texels differ from the analytic field"
    );
    assert!(
        wrong_terrain == 0,
        "{wrong_terrain} terrain texels are not 0"
    );
    // Ground texels of the canyon floor and both sides of the wall, every
    // 4th texel along x and 16th along z, in the middle of the structures.
    let mut rows = Vec::new();
    for (name, x0, x1) in [("canyon", 20.0, 26.0), ("wall", 38.0, 56.0)] {
        let (mut frac_err, mut cos_err, mut n) = (0.0f32, 0.0f32, 0);
        for j in (96..160).step_by(16) {
            for i in (0..SECTOR_TEXELS).step_by(2) {
                let (x, z) = ((i as f32 + 0.5) * TEXEL_SIZE, (j as f32 + 0.5) * TEXEL_SIZE);
                if x < x0 || x > x1 || canyon_height(x, z) != 0.0 {
                    continue;
                }
                let sh = sector.sh[j * SECTOR_TEXELS + i];
                let p = Vec3::new(x, twin::ORIGIN_LIFT, z);
                let f_ref = twin::ray_traced_visibility(&canyon_height, p, 1024, false, 60.0);
                let c_ref = twin::ray_traced_visibility(&canyon_height, p, 1024, true, 60.0);
                // The stored fraction: L0 = C0 (1 - cos A) = C0 f.
                let f = sh.x / twin::SH_CAP_C0;
                let c = twin::sh2_visibility_cosine(sh, Vec3::Y);
                frac_err += (f - f_ref).abs();
                cos_err += (c - c_ref).abs();
                n += 1;
            }
        }
        rows.push((name, frac_err / n as f32, cos_err / n as f32, n));
    }
    for (name, f, c, n) in &rows {
        eprintln!(
            "skyocc vs ray traced, {name}: {n} texels, MAE fraction {f:.4}, MAE cosine-weighted along +Y {c:.4}"
        );
    }
    for (name, f, c, n) in rows {
        assert!(n >= 40, "{name}: {n} texels");
        // Issue threshold 0.1. Measured on 2026-11-22 (fraction / cosine):
        // canyon 0.058 / 0.024 (48 texels), wall 0.076 / 0.026 (136 texels), with the
        // 5x5 smoothing of the SH2 (without: 0.049 / 0.039 and 0.082 / 0.033).
        assert!(f <= 0.1, "{name}: fraction MAE {f}");
        assert!(c <= 0.1, "{name}: cosine MAE {c}");
    }
}

#[test]
fn lighting_with_sky_occlusion_matches_cpu_twin() {
    let scene = scene();
    let camera = scene.camera("main").expect("camera").clone();
    let (w, h) = (96u32, 64u32);
    let mut r = renderer(&scene);
    let mut s = FrameSettings::new(w, h, scene.sun.clone());
    s.view = ViewBuffer::Debug(himal::passes::debug::DebugView::Lighting);
    s.raw = true;
    s.sky_occlusion = true;
    s.shadow_resolution = 0;
    s.ao.mode = himal::passes::ao::AoMode::Off;
    s.aerial_extinction = 0.0;
    s.environment_specular = false;
    let gpu = r.render(&camera, &s).expect("frame");
    assert_eq!(gpu.sky_occlusion.rendered, gpu.sky_occlusion.wanted);
    let img = gpu.image.to_rgba_f32().expect("f32");
    s.sky_occlusion = false;
    let open = render_rgba(&mut r, &camera, &s);
    // Bent normals off (`--bent-normals off`): the same visibility along n.
    s.sky_occlusion = true;
    s.bent_normals = false;
    let unbent = render_rgba(&mut r, &camera, &s);
    s.bent_normals = true;
    s.sky_occlusion = false;
    let bent_changed = img
        .iter()
        .zip(&unbent)
        .filter(|(a, b)| (a[1] - b[1]).abs() > 0.005 * a[1].abs().max(1e-3))
        .count();
    eprintln!(
        "bent normals off: {bent_changed} of {} pixels differ by > 0.5%",
        img.len()
    );
    // Measured 2026-11-22: 1487 of 6144 (the canyon walls and the ground beside them).
    assert!(bent_changed > 200, "{bent_changed}");
    // The same two frames with the environment specular (L3 normalisation).
    s.environment_specular = true;
    let open_env = render_rgba(&mut r, &camera, &s);
    s.sky_occlusion = true;
    let occluded_env = render_rgba(&mut r, &camera, &s);
    let ctx = r.context();
    let sector = r
        .sky_occlusion()
        .read_sector(ctx, IVec2::new(0, 0))
        .expect("read")
        .expect("sector (0, 0) resident");
    let light = lighting_params(&scene);
    let mut light_env = lighting_params(&scene);
    light_env.environment = Some(environment_specular(&r));
    // The G-buffer stores albedo in 8-bit sRGB and material parameters in 8 bits.
    let q8 = |v: f32| (v * 255.0).round() / 255.0;
    let q8_srgb = |v: f32| {
        let s = if v <= 0.0031308 {
            v * 12.92
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        };
        let s = (s * 255.0).round() / 255.0;
        if s <= 0.04045 {
            s / 12.92
        } else {
            ((s + 0.055) / 1.055).powf(2.4)
        }
    };
    let material = himal::math::brdf::Material {
        albedo: Vec3::splat(q8_srgb(0.5)),
        glossiness: q8(0.4),
        reflectance: q8(0.04),
        metallic: 0.0,
        anisotropy: 0.0,
    };
    let (mut sum, mut worst, mut n, mut darker) = (0.0f32, 0.0f32, 0, 0);
    let (mut worst_open, mut worst_ratio) = (0.0f32, 0.0f32);
    let (mut worst_l3, mut min_l3, mut n_l3) = (0.0f32, 1.0f32, 0usize);
    for y in 0..h {
        for x in 0..w {
            // Ground pixels (plane y = 0) inside sector (0, 0), away from the boxes.
            let dir = pixel_ray(&camera, (w, h), x, y);
            if dir.y > -0.05 {
                continue;
            }
            let p = camera.position + dir * (-camera.position.y / dir.y);
            let l = Vec2::new(p.x, p.z) / SECTOR_SIZE;
            if !(0.02..0.98).contains(&l.x) || !(0.02..0.98).contains(&l.y) {
                continue;
            }
            // Skip pixels near a box's foot or whose ray meets a box first.
            let t_hit = -camera.position.y / dir.y;
            let blocked = (0..(t_hit * 10.0) as usize).any(|k| {
                let a = camera.position + dir * (k as f32 * 0.1);
                canyon_height(a.x, a.z) > a.y
            });
            let near_box = [-0.5f32, 0.0, 0.5]
                .iter()
                .any(|d| canyon_height(p.x + d, p.z) > 0.0);
            if blocked || near_box {
                continue;
            }
            let sh = twin::sector_lookup(&sector.sh, &sector.heights, l, p.y);
            let cpu = shade_sky_occluded(
                &material,
                1.0,
                Vec3::X,
                Vec3::NEG_Z,
                Vec3::Y,
                -dir,
                &light,
                1.0,
                Some(sh),
            );
            let g = img[(y * w + x) as usize];
            let g = Vec3::new(g[0], g[1], g[2]);
            let rel = ((g - cpu).abs() / cpu.max(Vec3::splat(1e-3))).max_element();
            sum += rel;
            worst = worst.max(rel);
            n += 1;
            let o = open[(y * w + x) as usize];
            let cpu_open = shade_sky_occluded(
                &material,
                1.0,
                Vec3::X,
                Vec3::NEG_Z,
                Vec3::Y,
                -dir,
                &light,
                1.0,
                None,
            );
            let o = Vec3::new(o[0], o[1], o[2]);
            worst_open = worst_open.max(((o - cpu_open).abs() / cpu_open).max_element());
            // The occluded/open ratio cancels what both permutations share.
            let ratio = ((g / o - cpu / cpu_open).abs()).max_element();
            worst_ratio = worst_ratio.max(ratio);
            if g.x < o[0] * 0.98 {
                darker += 1;
            }
            // L3: with the environment specular, occluded/open against the twin,
            // which scales the cube by `ambient_luminance_ratio`.
            let rgb = |c: [f32; 4]| Vec3::new(c[0], c[1], c[2]);
            let i = (y * w + x) as usize;
            let twin = |sh| {
                shade_sky_occluded(
                    &material,
                    1.0,
                    Vec3::X,
                    Vec3::NEG_Z,
                    Vec3::Y,
                    -dir,
                    &light_env,
                    1.0,
                    sh,
                )
            };
            let want = twin(Some(sh)) / twin(None);
            let got = rgb(occluded_env[i]) / rgb(open_env[i]);
            worst_l3 = worst_l3.max((got - want).abs().max_element());
            min_l3 = min_l3.min(ambient_luminance_ratio(
                &light.sky_irradiance,
                Vec3::Y,
                Some(sh),
            ));
            n_l3 += 1;
        }
    }
    let mean = sum / n.max(1) as f32;
    eprintln!(
        "lighting with sky occlusion vs CPU: {n} pixels, mean relative {mean:.5}, worst {worst:.5}; {darker} darker than without; without: worst {worst_open:.5}; ratio occluded/open worst {worst_ratio:.5}"
    );
    assert!(n > 1000, "{n} pixels");
    assert!(
        darker > n / 20,
        "sky occlusion must darken some ground: {darker} of {n}"
    );
    // The base twin (no sky occlusion) is off by the same ~1.4% on this
    // plane (measured worst 0.0138 without, 0.0139 with, mean 0.0134 with,
    // on 2026-11-22), so the sky occlusion adds nothing measurable; the ratio
    // occluded/open isolates it: measured worst 0.00093 (fp16 HDR and SH); threshold 0.01.
    assert!(mean < 0.02, "mean {mean}");
    assert!(worst < 0.03, "worst {worst}");
    assert!(worst_ratio < 0.01, "ratio worst {worst_ratio}");
    eprintln!(
        "L3 environment specular, occluded/open frame vs the twin: {n_l3} pixels, worst {worst_l3:.5}, smallest ratio {min_l3:.3}"
    );
    // Measured 2026-11-22 (lavapipe): worst 0.0022 over 2196 pixels, ratios
    // down to 0.62 (fp16 HDR differences of small specular terms). Threshold 0.02.
    assert!(
        n_l3 > 500 && min_l3 < 0.9,
        "{n_l3} pixels, smallest ratio {min_l3}"
    );
    assert!(worst_l3 < 0.02, "L3 ratio worst {worst_l3}");
}

/// `--view sky-visibility` along a wall that is not aligned with the texels:
/// the fade must not step from texel to texel (the streaks of a nearest,
/// object-top fade height). Measures the mean second difference along
/// image rows on the wall.
#[test]
fn sky_visibility_is_smooth_along_a_rotated_wall() {
    let scene = scene_on_ground("skyocc_rotated_wall");
    let camera = scene.camera("main").expect("camera").clone();
    let (w, h) = (160u32, 96u32);
    let mut r = renderer(&scene);
    let mut s = FrameSettings::new(w, h, scene.sun.clone());
    s.view = ViewBuffer::SkyOcc(SkyOccView::Visibility);
    s.raw = true;
    s.sky_occlusion = true;
    let img = render_rgba(&mut r, &camera, &s);
    // Wall pixels: the ray meets the facing side's plane inside the wall,
    // 0.3 m from its edges.
    let (centre, yaw) = (Vec3::new(32.0, 2.0, 32.0), 30f32.to_radians());
    let along = Vec3::new(yaw.cos(), 0.0, -yaw.sin());
    let normal = Vec3::new(yaw.sin(), 0.0, yaw.cos());
    let face = centre + normal * 0.25;
    let on_wall = |x: u32, y: u32| {
        let d = pixel_ray(&camera, (w, h), x, y);
        let t = (face - camera.position).dot(normal) / d.dot(normal);
        let p = camera.position + d * t;
        t > 0.0 && (p - face).dot(along).abs() < 9.7 && (0.3..3.7).contains(&p.y)
    };
    let (mut sum, mut n) = (0.0f32, 0);
    for y in 0..h {
        for x in 1..w - 1 {
            if on_wall(x - 1, y) && on_wall(x, y) && on_wall(x + 1, y) {
                let v = |x: u32| img[(y * w + x) as usize][0];
                sum += (v(x + 1) - 2.0 * v(x) + v(x - 1)).abs();
                n += 1;
            }
        }
    }
    let roughness = sum / n.max(1) as f32;
    eprintln!(
        "rotated wall: {n} pixel triples, mean |second difference| of the visibility {roughness:.5}"
    );
    assert!(n > 1000, "{n} wall pixels");
    // Measured 2026-11-22: 0.00031. The fade before (object-top height,
    // nearest texel, per-texel rotated fade taps) 0.00344; with the terrain
    // height and unrotated taps but nearest texels 0.00074. Threshold 0.0006.
    assert!(roughness < 6e-4, "{roughness}");
}

/// Moving objects stay out of the height field: a sector is rendered once,
/// and their footprint would stay where they were at that moment.
#[test]
fn height_field_holds_static_geometry_only() {
    let ctx = shared_context().expect("GPU");
    let scene = scene_on_ground("skyocc_pillar_and_cart");
    let gpu_scene = SceneGpu::upload(ctx, &scene).expect("upload");
    let mut pass = SkyOccPass::new(ctx, &scene).expect("pass");
    let sector = pass
        .render_sectors(ctx, &gpu_scene, &[IVec2::new(0, 0)])
        .expect("render")
        .remove(0);
    let raw_at = |name: &str| {
        let o = scene.objects.iter().find(|o| o.name == name).expect(name);
        let p = o.transform_at(0.0).w_axis;
        let t = (Vec2::new(p.x, p.z) / TEXEL_SIZE).floor().as_uvec2();
        sector.raw[(t.y as usize + MARGIN_TEXELS) * RENDER_TEXELS + t.x as usize + MARGIN_TEXELS]
    };
    let (pillar, cart) = (raw_at("pillar"), raw_at("cart"));
    eprintln!("height field: pillar {pillar} m, moving cart {cart} m");
    assert!((pillar - 3.0).abs() < 1e-3, "pillar {pillar}");
    assert!(cart.abs() < 1e-3, "cart {cart}");
}

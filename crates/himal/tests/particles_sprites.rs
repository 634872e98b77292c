//! E4 sprites (`passes/particles/sprite.rs`): the built-in puff, sprites
//! chosen in the scene file, what they change in the frame, and the
//! sprite shading functions against their CPU twins.

mod common;

use glam::{Vec2, Vec3};
use himal::passes::particles::sprite::{SPRITE_SIZE, mip_chain, puff_layer, sprite_layers};
use himal::scene::Sprite;

#[test]
fn the_puff_is_a_soft_normal_mapped_cloud() {
    let a = puff_layer();
    assert_eq!(a, puff_layer(), "the puff is not deterministic");
    let n = SPRITE_SIZE as usize;
    assert_eq!(a.len(), n * n * 4);
    let (mut opaque, mut border_max, mut z_sum, mut x_sq) = (0usize, 0u8, 0.0f32, 0.0f32);
    let mut weight = 0.0f32;
    for row in 0..n {
        for col in 0..n {
            let t = &a[(row * n + col) * 4..][..4];
            let p = Vec2::new(
                2.0 * (col as f32 + 0.5) / n as f32 - 1.0,
                1.0 - 2.0 * (row as f32 + 0.5) / n as f32,
            );
            let normal = Vec3::new(t[0] as f32, t[1] as f32, t[2] as f32) / 127.5 - Vec3::ONE;
            assert!(
                (normal.length() - 1.0).abs() < 0.02,
                "texel ({col}, {row}): |n| = {}",
                normal.length()
            );
            if p.length() >= 1.0 {
                border_max = border_max.max(t[3]);
            }
            let alpha = t[3] as f32 / 255.0;
            opaque += usize::from(t[3] > 127);
            z_sum += alpha * normal.z;
            x_sq += alpha * normal.x * normal.x;
            weight += alpha;
        }
    }
    let (mean_z, rms_x) = (z_sum / weight, (x_sq / weight).sqrt());
    let cover = opaque as f32 / (n * n) as f32;
    println!(
        "puff: {:.1} % of the square over half opaque, opacity outside the disc at most {border_max}, \
         opacity-weighted mean n.z {mean_z:.3}, rms n.x {rms_x:.3}",
        100.0 * cover
    );
    // No quad edge: nothing outside the inscribed circle (measured 0).
    assert_eq!(border_max, 0, "the puff reaches the quad's edge");
    // A cloud, not a dot or a square (measured 38 %; the disc is 78.5 %).
    assert!((0.3..0.7).contains(&cover), "cover {cover}");
    // Faces the camera on the whole but has relief (measured 0.76, 0.44).
    assert!(mean_z > 0.6 && rms_x > 0.2, "n.z {mean_z}, n.x {rms_x}");
    let mips = mip_chain(&a, SPRITE_SIZE);
    assert_eq!(mips.len(), SPRITE_SIZE.ilog2() as usize + 1);
    assert_eq!(mips.last().map(Vec::len), Some(4));
}

#[test]
fn scene_files_choose_sprites() {
    let base =
        std::fs::read_to_string(common::scenes_dir().join("particles_smoke.toml")).expect("scene");
    let with = |smoke: &str, burst: &str, dir: &std::path::Path| {
        let text = base
            .replacen(
                "capacity = 256",
                &format!("capacity = 256\nsprite = \"{smoke}\""),
                1,
            )
            .replacen(
                "capacity = 128",
                &format!("capacity = 128\nsprite = \"{burst}\""),
                1,
            );
        himal::scene::Scene::from_toml_str(&text, "particles_smoke.toml", dir)
    };
    let dir = std::env::temp_dir().join(format!("himal-sprites-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let scene = with("puff", "disc", &dir).expect("puff and disc");
    assert_eq!(scene.emitters[0].sprite, Sprite::Puff);
    assert_eq!(scene.emitters[1].sprite, Sprite::Disc);
    // An image: any size, resized; two emitters naming it share its layer.
    let img = image::RgbaImage::from_fn(40, 24, |x, y| image::Rgba([128, 128, 255, (x + y) as u8]));
    img.save(dir.join("spark.png")).expect("png");
    let scene = with("spark.png", "spark.png", &dir).expect("image sprite");
    let Sprite::Image(i) = &scene.emitters[0].sprite else {
        panic!("not an image: {:?}", scene.emitters[0].sprite);
    };
    assert_eq!(i.rgba.len(), (SPRITE_SIZE * SPRITE_SIZE * 4) as usize);
    let (layers, images) = sprite_layers(&scene.emitters);
    assert_eq!((layers, images.len()), (vec![1, 1], 1));
    // A missing or unreadable file names the scene file and the sprite.
    std::fs::write(dir.join("broken.png"), b"not a png").expect("write");
    for bad in ["nosuch.png", "broken.png"] {
        let e = with(bad, "disc", &dir).expect_err(bad).to_string();
        println!("{e}");
        assert!(
            e.contains("particles_smoke.toml") && e.contains(bad) && e.contains("sprite"),
            "{bad}: {e}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn puff_sprites_change_the_smoke_and_stay_deterministic() {
    let (disc_scene, camera) = common::scene_and_camera("particles_smoke", "side");
    let puff_scene = common::scene_with(
        "particles_smoke",
        &[("capacity = 256", "capacity = 256\nsprite = \"puff\"")],
    );
    let mut s = himal::FrameSettings::new(160, 120, disc_scene.sun.clone());
    s.time_s = 2.0;
    s.view = himal::ViewBuffer::ParticleLighting;
    let mut r = common::renderer(&disc_scene);
    let disc = common::render_rgba(&mut r, &camera, &s);
    let mut r = common::renderer(&puff_scene);
    let puff = common::render_rgba(&mut r, &camera, &s);
    let again = common::render_rgba(&mut common::renderer(&puff_scene), &camera, &s);
    assert!(
        puff == again,
        "the puff frame differs between two renderers"
    );
    let differ = (disc.iter().zip(&puff))
        .filter(|(a, b)| (0..3).any(|k| (a[k] - b[k]).abs() > 2.0 / 255.0))
        .count();
    println!(
        "puff vs disc smoke: {differ} of {} pixels differ",
        disc.len()
    );
    // Measured 1,358 of the plume's about 2,400 pixels.
    assert!(differ > 500, "the puff barely changed the smoke: {differ}");
}

const SHADING_KERNEL: &str = r#"
#import particles

struct Query {
    view_m: mat4x4f,
    // xy: corner, z: sun luminance scale, w: a slot (as a float)
    corner: vec4f,
    sun: vec4f,
    lamp: vec4f,
    lamp_dir: vec4f,
    // xyz: a sprite-space normal
    tangent: vec4f,
}

@group(0) @binding(0) var<storage, read> input: array<Query>;
@group(0) @binding(1) var<storage, read_write> output: array<vec4f>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let i = id.x;
    if (i >= arrayLength(&input)) {
        return;
    }
    let q = input[i];
    let r2 = min(dot(q.corner.xy, q.corner.xy), 0.999);
    let n = particle_sprite_normal(q.view_m, q.corner.xy, r2);
    var acc = ParticleLight(vec4f(0.0), vec4f(0.0));
    acc = particle_light_add(acc, q.sun.rgb, normalize(vec3f(0.3, 0.8, 0.5)));
    acc = particle_light_add(acc, q.lamp.rgb, q.lamp_dir.xyz);
    let rot = particle_sprite_angle(u32(q.corner.w));
    output[4u * i] = vec4f(n, 0.0);
    output[4u * i + 1u] = vec4f(particle_light_diffuse(acc, n), 0.0);
    output[4u * i + 2u] = vec4f(particle_sprite_normal_mapped(q.view_m, q.tangent.xyz, rot), 0.0);
    output[4u * i + 3u] = vec4f(particle_sprite_rotate(q.corner.xy, rot), rot);
}
"#;

#[test]
fn sprite_shading_matches_cpu_twin() {
    use glam::{Mat4, Vec2, Vec3};
    use himal::passes::particles::ParticleLightGpu;
    use himal::passes::particles::reference::{
        light_add, light_diffuse, sprite_angle, sprite_normal, sprite_normal_mapped, sprite_rotate,
    };
    let mut rng = common::Lcg(5);
    let mut input: Vec<f32> = Vec::new();
    let mut twin = Vec::new();
    for _ in 0..256 {
        let eye = Vec3::new(
            rng.next() * 10.0 - 5.0,
            rng.next() * 4.0,
            rng.next() * 10.0 - 5.0,
        );
        let turn =
            glam::Quat::from_euler(glam::EulerRot::YXZ, rng.next() * 6.0, rng.next() - 0.5, 0.0);
        let view = Mat4::from_rotation_translation(turn, eye).inverse();
        let c = Vec2::new(rng.next() * 2.0 - 1.0, rng.next() * 2.0 - 1.0) * 0.7;
        let sun = Vec3::new(90.0, 85.0, 72.0) * rng.next();
        let lamp = Vec3::new(20.0, 14.0, 8.0) * rng.next();
        let lamp_dir = Vec3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5).normalize();
        input.extend(view.to_cols_array());
        let slot = (rng.next() * 60_000.0) as u32;
        let t = Vec3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next()).normalize();
        input.extend([c.x, c.y, 0.0, slot as f32]);
        input.extend(sun.extend(0.0).to_array());
        input.extend(lamp.extend(0.0).to_array());
        input.extend(lamp_dir.extend(0.0).to_array());
        input.extend(t.extend(0.0).to_array());
        let n = sprite_normal(view, c, c.length_squared().min(0.999));
        let mut acc = ParticleLightGpu::default();
        acc = light_add(acc, sun, Vec3::new(0.3, 0.8, 0.5).normalize());
        acc = light_add(acc, lamp, lamp_dir);
        let rot = sprite_angle(slot);
        let mapped = sprite_normal_mapped(view, t, rot);
        twin.push((
            n,
            light_diffuse(&acc, n),
            mapped,
            sprite_rotate(c, rot),
            rot,
        ));
    }
    let out = himal::gpu::testing::run_compute(
        SHADING_KERNEL,
        "main",
        bytemuck::cast_slice(&input),
        (twin.len() * 64) as u64,
        [4, 1, 1],
    )
    .expect("kernel");
    let gpu: &[[f32; 4]] = bytemuck::cast_slice(&out);
    let (mut worst_n, mut worst_c, mut worst_m, mut worst_r) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
    for (k, (n, c, mapped, turned, rot)) in twin.iter().enumerate() {
        let g = &gpu[4 * k..4 * k + 4];
        worst_n = worst_n.max((Vec3::from_slice(&g[0][..3]) - *n).abs().max_element());
        worst_c = worst_c.max(
            (Vec3::from_slice(&g[1][..3]) - *c).abs().max_element() / c.max_element().max(1e-3),
        );
        worst_m = worst_m.max((Vec3::from_slice(&g[2][..3]) - *mapped).abs().max_element());
        let gr = glam::Vec4::from_array(g[3]);
        worst_r = worst_r.max(
            (gr - glam::Vec4::new(turned.x, turned.y, rot.x, rot.y))
                .abs()
                .max_element(),
        );
    }
    println!(
        "sprite normal |GPU - CPU| {worst_n:.2e}, diffuse relative {worst_c:.2e}, \
         normal-mapped {worst_m:.2e}, angle and rotation {worst_r:.2e}"
    );
    // Measured 6.0e-8 and 2.2e-6 (relative): f32 rounding of the same
    // expressions (1 / pi folded differently); the mapped normal 1.2e-7,
    // the angle's cos/sin and the turned corner 6.0e-8.
    assert!(
        worst_n < 1e-5 && worst_c < 1e-4 && worst_m < 1e-5 && worst_r < 1e-5,
        "normal {worst_n}, diffuse {worst_c}, mapped {worst_m}, rotation {worst_r}"
    );
}

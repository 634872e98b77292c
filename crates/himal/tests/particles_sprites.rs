//! E4 normal-mapped sprites (`passes/particles/sprite.rs`): the built-in
//! puff, sprites chosen in the scene file, and what they change in the
//! frame. The shading functions' GPU-vs-twin test is in particles.rs
//! (`sprite_shading_matches_cpu_twin`).

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

//! L1 Bruneton sky: GPU tables against the CPU twin (transmittance, single
//! scattering), the sky pass and the environment capture against the CPU
//! lookup, the SH3 sky light against numerical integration, the night floor.
//! Tables at `TableSizes::TEST` (computed in ~1 s on lavapipe).

mod common;

use std::path::Path;
use std::sync::OnceLock;

use glam::{Vec2, Vec3};
use himal::gpu::read_texture;
use himal::gpu::testing::shared_context;
use himal::math::sh::Sh9Rgb;
use himal::passes::sky::bruneton::reference::{self, CpuTables};
use himal::passes::sky::bruneton::{
    AtmosphereConfig, BrunetonTables, SKY_SH_SAMPLES, SkyShProjector, TableSizes,
};
use himal::passes::sky::{SkyModel, sun_position};
use himal::scene::Scene;

fn test_config() -> AtmosphereConfig {
    AtmosphereConfig::earth(TableSizes::TEST)
}

/// Test-size tables on the shared context, computed once per test binary.
fn tables() -> &'static BrunetonTables {
    static TABLES: OnceLock<BrunetonTables> = OnceLock::new();
    TABLES.get_or_init(|| {
        let ctx = shared_context().expect("GPU");
        BrunetonTables::compute_with(ctx, test_config(), None)
            .expect("tables")
            .0
    })
}

fn cpu_tables() -> &'static CpuTables {
    static CPU: OnceLock<CpuTables> = OnceLock::new();
    CPU.get_or_init(|| {
        CpuTables::read(shared_context().expect("GPU"), tables()).expect("read-back")
    })
}

/// Unit vector towards a sun at `elevation_deg`, azimuth 30 degrees from -Z.
fn sun_at(elevation_deg: f32) -> Vec3 {
    let (e, a) = (elevation_deg.to_radians(), 30f32.to_radians());
    Vec3::new(e.cos() * a.sin(), e.sin(), -e.cos() * a.cos())
}

#[test]
fn transmittance_table_matches_ray_marching() {
    let cpu = cpu_tables();
    let c = &cpu.config;
    let (w, h) = c.sizes.transmittance;
    let (mut worst, mut count) = (0.0f64, 0);
    for j in 0..h {
        for i in 0..w {
            let (r, mu) = reference::transmittance_texel_r_mu(c, i, j);
            let marched = reference::transmittance_to_top(c, r, mu, 4000);
            // Grazing rays through the whole atmosphere: f16 keeps no relative precision there.
            if marched.min_element() < 1e-3 {
                continue;
            }
            let table = cpu.transmittance.texel(i, j, 0).as_dvec3();
            worst = worst.max(((table - marched) / marched).abs().max_element());
            count += 1;
        }
    }
    eprintln!(
        "transmittance: {count} of {} texels, worst relative error {worst:.2e}",
        w * h
    );
    assert!(count > (w * h / 2) as usize, "{count}");
    // Measured 1.85e-4 on 2026-11-22 (f32 table, 500-step trapezoid per
    // texel vs 4000 midpoint steps); issue threshold 0.01.
    assert!(worst < 0.01, "{worst}");
}

#[test]
fn single_scattering_table_matches_cpu_integration() {
    let cpu = cpu_tables();
    let c = &cpu.config;
    let (sx, sy, sz) = c.sizes.scattering_extent();
    let mut worst = 0.0f64;
    let mut count = 0;
    // A spread of texels: every r layer, view up/grazing/down, several suns.
    for z in [0, sz / 2, sz - 1] {
        for y in [1, sy / 4, sy / 2 + 1, 3 * sy / 4, sy - 2] {
            for x in [3, sx / 3 + 5, sx / 2 + 2, sx - 4] {
                let (r, mu, mu_s, nu, _) = reference::scattering_texel_coords(c, x, y, z);
                // Sun well above the horizon (the GPU fades the disk at the horizon).
                if mu_s < 0.1 {
                    continue;
                }
                let (rayleigh, mie) = reference::single_scattering(c, r, mu, mu_s, nu, 2000);
                let g_r = cpu.single_rayleigh.texel(x, y, z).as_dvec3();
                let g_m = cpu.single_mie.texel(x, y, z).as_dvec3();
                // Relative, floored at 1e-4 (per unit solar irradiance; the
                // sky's visible values are 1e-2..1): Mie far above its scale height is ~1e-7.
                let rel = |g: glam::DVec3, c: glam::DVec3| {
                    ((g - c).abs() / c.max(glam::DVec3::splat(1e-4))).max_element()
                };
                let e = rel(g_r, rayleigh).max(rel(g_m, mie));
                eprintln!(
                    "  r {r:.1} mu {mu:.4} mu_s {mu_s:.3} nu {nu:.3}: rayleigh rel {:.4}, mie rel {:.4}",
                    rel(g_r, rayleigh),
                    rel(g_m, mie)
                );
                worst = worst.max(e);
                count += 1;
            }
        }
    }
    eprintln!("single scattering GPU vs CPU: {count} texels, worst relative {worst:.4}");
    assert!(count >= 20, "{count}");
    // The GPU's 150-step trapezoid with table transmittance against 2000
    // midpoint steps with marched transmittance: measured 0.0086 (Mie near
    // the ground) on 2026-11-22; threshold 0.02.
    assert!(worst < 0.02, "{worst}");
}

#[test]
fn sky_sh_matches_numerical_integration() {
    let ctx = shared_context().expect("GPU");
    let cpu = cpu_tables();
    let projector = SkyShProjector::new(ctx).expect("projector");
    let normals = [
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Z,
        Vec3::NEG_Z,
    ];
    // Worst relative error for normals up, down, horizontal; GPU vs CPU projection.
    let (mut worst, mut worst_twin) = ([0.0f32; 3], 0.0f32);
    // Errors averaged over the sphere of normals (Ramamoorthi & Hanrahan's measure).
    let (mut worst_mean, mut worst_rms) = (0.0f32, 0.0f32);
    let lum = |v: Vec3| v.dot(Vec3::new(0.2126, 0.7152, 0.0722));
    for elevation in [-2.0f32, 2.0, 10.0, 25.0, 45.0, 80.0] {
        let sun = sun_at(elevation);
        let (radiance_sh, _) = projector.project(ctx, tables(), sun, None).expect("sh");
        let sh = radiance_sh.radiance_to_irradiance_coeffs();
        // Twin: the same quadrature on the CPU lookups.
        let cpu_sh = Sh9Rgb::project(|d| cpu.sky_radiance(d, sun), SKY_SH_SAMPLES)
            .radiance_to_irradiance_coeffs();
        // L(w) dw on a 96 x 192 midpoint grid; E(n) = sum L max(n.w, 0) dw.
        let radiance: Vec<(Vec3, Vec3)> = sphere_grid(96)
            .map(|(w, d_omega)| (w, cpu.sky_radiance(w, sun) * d_omega))
            .collect();
        let irradiance =
            |n: Vec3| -> Vec3 { radiance.iter().map(|(w, l)| *l * n.dot(*w).max(0.0)).sum() };
        for n in normals {
            let e = irradiance(n);
            let rel = (sh.eval(n) - e).length() / e.length();
            let twin = (sh.eval(n) - cpu_sh.eval(n)).length() / cpu_sh.eval(n).length();
            let kind = if n.y > 0.5 {
                0
            } else if n.y < -0.5 {
                1
            } else {
                2
            };
            worst[kind] = worst[kind].max(rel);
            worst_twin = worst_twin.max(twin);
            eprintln!(
                "  sun {elevation:5.1} deg, n {n}: SH {:.4}, integrated {:.4}, rel {rel:.4}, GPU vs CPU SH {twin:.2e}",
                sh.eval(n),
                e
            );
        }
        // Over 16 x 32 normals weighted by solid angle, on luminance: mean
        // relative error and RMS error over RMS irradiance.
        let (mut rel_sum, mut err2, mut e2, mut weight) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
        for (n, d_omega) in sphere_grid(16) {
            let e = lum(irradiance(n));
            let d = lum(sh.eval(n)) - e;
            rel_sum += d.abs() / e * d_omega;
            err2 += d * d * d_omega;
            e2 += e * e * d_omega;
            weight += d_omega;
        }
        let (mean, rms) = (rel_sum / weight, (err2 / e2).sqrt());
        eprintln!(
            "  sun {elevation:5.1} deg over the sphere of normals: mean relative {mean:.4}, normalised RMS {rms:.4}"
        );
        worst_mean = worst_mean.max(mean);
        worst_rms = worst_rms.max(rms);
    }
    eprintln!(
        "sky SH3 irradiance vs integration, worst: over the sphere mean {worst_mean:.4} / RMS {worst_rms:.4}; up {:.4}, down {:.4}, horizontal {:.4}; GPU vs CPU projection {worst_twin:.2e}",
        worst[0], worst[1], worst[2]
    );
    // The projection itself: GPU against the same quadrature on the CPU
    // lookups, measured 2.4e-5 on 2026-11-22 (f32 sums); threshold 1e-4.
    assert!(worst_twin < 1e-4, "{worst_twin}");
    // The issue's 3%, as Ramamoorthi & Hanrahan (2001) state SH3's irradiance
    // error: averaged over all normals. Measured 2026-11-22, worst over the
    // six suns (2 deg): mean relative 0.0204, normalised RMS 0.0197.
    assert!(worst_mean < 0.03, "mean over normals {worst_mean}");
    assert!(worst_rms < 0.03, "RMS over normals {worst_rms}");
    // Single normals (the quadrature is converged: n = 256 changes E by
    // < 0.5%). Measured 2026-11-22, worst over the six suns: horizontal
    // 0.0196; up 0.099 and down 0.46, both at a 2-degree sun: the bright
    // horizon over a darker ground is band 4 and up, which SH3 drops (band 4
    // would still leave 0.13, band 6 0.07: docs/techniques/L1.md), and
    // E(down) is small. Thresholds 0.03, 0.12, 0.5.
    assert!(worst[2] < 0.03, "horizontal {}", worst[2]);
    assert!(worst[0] < 0.12, "up {}", worst[0]);
    assert!(worst[1] < 0.5, "down {}", worst[1]);
}

/// Midpoint grid over the sphere, `rows` x 2 `rows`: (direction, solid angle).
fn sphere_grid(rows: usize) -> impl Iterator<Item = (Vec3, f32)> {
    use std::f32::consts::{PI, TAU};
    let cols = 2 * rows;
    (0..rows).flat_map(move |i| {
        let theta = (i as f32 + 0.5) / rows as f32 * PI;
        let d_omega = theta.sin() * (PI / rows as f32) * (TAU / cols as f32);
        (0..cols).map(move |j| {
            let phi = (j as f32 + 0.5) / cols as f32 * TAU;
            let w = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            (w, d_omega)
        })
    })
}

#[test]
fn night_floor_is_dark_but_not_black() {
    let ctx = shared_context().expect("GPU");
    let projector = SkyShProjector::new(ctx).expect("projector");
    let e_up = |hours: f32| {
        let sun = sun_position(hours, 45.0, 172).direction;
        let (sh, _) = projector.project(ctx, tables(), sun, None).expect("sh");
        sh.radiance_to_irradiance_coeffs().eval(Vec3::Y)
    };
    let (night, noon) = (e_up(22.0), e_up(12.0));
    let ratio = night / noon;
    eprintln!("sky irradiance up: 22:00 {night}, noon {noon}, ratio {ratio}");
    // Measured 2026-11-22: night (1.6, 2.2, 3.8) e-3 klux, ratio to noon
    // (3.9, 2.6, 2.4) e-4 (the night floor NIGHT_SKY_RADIANCE); brief: > 0 and < 1e-2.
    assert!(night.min_element() > 0.0, "{night}");
    assert!(ratio.max_element() < 1e-2, "{ratio}");
}

const SKY_SCENE: &str = r#"
[sun]
time = "16:30"

[[camera]]
name = "main"
position = [0, 1, 0]
target = [0.3, 1.25, -1]
fov_y = 100
"#;

#[test]
fn sky_pass_and_capture_match_the_cpu_lookup() {
    let scene = Scene::from_toml_str(SKY_SCENE, "sky.toml", Path::new(".")).expect("scene");
    let camera = scene.camera("main").expect("camera").clone();
    let size = (64u32, 48u32);
    let mut s = common::raw_settings(&scene, size, "lighting");
    s.sky_model = SkyModel::Bruneton;
    let mut r = common::renderer(&scene);
    let t = BrunetonTables::compute_with(r.context(), test_config(), None).expect("tables");
    r.set_bruneton_tables(t.0).expect("set tables");
    let img = common::render_rgba(&mut r, &camera, &s);
    let ctx = r.context();
    let cpu = CpuTables::read(ctx, r.bruneton_tables().expect("tables")).expect("read-back");
    let sun = r.sky_light().expect("sky light").sun_direction;
    let (mut worst, mut sum, mut n) = (0.0f32, 0.0f32, 0);
    for y in 0..size.1 {
        for x in 0..size.0 {
            let dir = common::pixel_ray(&camera, size, x, y);
            // The sun disk (Preetham's) is added on top: skip its surroundings.
            if dir.dot(sun) > 0.999 {
                continue;
            }
            let c = cpu.sky_radiance(dir, sun);
            let g = img[(y * size.0 + x) as usize];
            let rel = ((Vec3::new(g[0], g[1], g[2]) - c).abs() / c).max_element();
            worst = worst.max(rel);
            sum += rel;
            n += 1;
        }
    }
    let mean = sum / n as f32;
    eprintln!("Bruneton sky pass GPU vs CPU: {n} pixels, mean {mean:.5}, worst {worst:.4}");
    // Same lookups, f32 on both sides but the sampler's 8-bit filter
    // weights: measured mean 5.4e-4, worst 1.0e-3 on 2026-11-22; thresholds 2e-3, 5e-3.
    assert!(mean < 2e-3 && worst < 5e-3, "mean {mean}, worst {worst}");

    // The environment source cube was captured from the same tables.
    let source = r.envmap().source();
    let edge = source.width();
    let mut worst_cube = 0.0f32;
    for face in 0..6u32 {
        let texels = read_texture(ctx, source, 0, face)
            .expect("face")
            .to_rgba_f32()
            .expect("rgba");
        for (x, y) in [
            (1, 1),
            (edge / 2, edge / 3),
            (edge - 2, edge / 2),
            (edge / 4, edge - 3),
        ] {
            let uv = Vec2::new(
                (x as f32 + 0.5) / edge as f32,
                (y as f32 + 0.5) / edge as f32,
            );
            let dir = himal::passes::envmap::reference::cube_face_direction(face as usize, uv);
            let c = cpu.sky_radiance(dir, sun);
            let g = texels[(y * edge + x) as usize];
            worst_cube =
                worst_cube.max(((Vec3::new(g[0], g[1], g[2]) - c).abs() / c).max_element());
        }
    }
    eprintln!("environment capture GPU vs CPU: worst {worst_cube:.4}");
    // f16 cube texels: measured 8e-4 on 2026-11-22; threshold 5e-3.
    assert!(worst_cube < 5e-3, "{worst_cube}");
}

#[test]
fn table_cache_round_trips_and_rejects_stale_and_damaged_files() {
    let ctx = shared_context().expect("GPU");
    let dir = std::env::temp_dir().join(format!("himal-sky-cache-{}", std::process::id()));
    let path = himal::passes::sky::bruneton::cache_file(&dir, &test_config());
    tables().save(ctx, &path).expect("save");
    let loaded = BrunetonTables::load(ctx, test_config(), &path).expect("load");
    for (a, b) in [
        (&tables().transmittance, &loaded.transmittance),
        (&tables().scattering, &loaded.scattering),
        (&tables().single_mie, &loaded.single_mie),
        (&tables().irradiance, &loaded.irradiance),
    ] {
        let (a, b) = (
            reference::CpuTable::read(ctx, a).expect("a"),
            reference::CpuTable::read(ctx, b).expect("b"),
        );
        assert!(a.texels == b.texels, "cached table differs");
    }
    let mut other = test_config();
    other.mie_g = 0.7;
    let e = BrunetonTables::load(ctx, other, &path)
        .err()
        .expect("stale file accepted");
    assert!(e.to_string().contains("stale"), "{e}");
    // Every kind of damage is refused, naming the file and the problem.
    let good = std::fs::read(&path).expect("read");
    let refuses = |bytes: &[u8], what: &str| {
        std::fs::write(&path, bytes).expect("write");
        let e = BrunetonTables::load(ctx, test_config(), &path)
            .err()
            .unwrap_or_else(|| panic!("{what}: accepted"));
        let e = e.to_string();
        assert!(e.contains("himal-sky"), "{what}: names the file: {e}");
        e
    };
    // File layout (cache.rs): magic 8, version 4, key 8, payload length 8,
    // checksum 8, then per table a u64 length and its texels.
    const HEADER: usize = 36;
    let mut flipped = good.clone();
    flipped[HEADER + 8 + 100] ^= 0x10;
    assert!(refuses(&flipped, "flipped texel").contains("checksum"));
    assert!(refuses(&vec![0; good.len()], "zeroed").contains("not a himal sky table"));
    assert!(refuses(&good[..good.len() / 2], "half").contains("truncated"));
    assert!(refuses(b"HIMALSKY", "magic only").contains("truncated"));
    let mut longer = good.clone();
    longer.extend([7u8; 5]);
    assert!(refuses(&longer, "trailing bytes").contains("5 trailing bytes"));
    let mut old = good.clone();
    old[8..12].copy_from_slice(&1u32.to_le_bytes());
    assert!(refuses(&old, "version 1").contains("stale"));
    // NaN texels with a matching checksum: the values themselves are checked.
    let mut nan = good.clone();
    nan[HEADER + 8..HEADER + 12].copy_from_slice(&f32::NAN.to_le_bytes());
    let sum = himal::gpu::cache::fnv1a(&nan[HEADER..]);
    nan[28..36].copy_from_slice(&sum.to_le_bytes());
    assert!(refuses(&nan, "NaN").contains("transmittance table holds NaN"));
    // Not a regular file: never read (an endless device would hang the load).
    if std::path::Path::new("/dev/zero").exists() {
        let e = BrunetonTables::load(ctx, test_config(), std::path::Path::new("/dev/zero"))
            .err()
            .expect("/dev/zero accepted");
        assert!(e.to_string().contains("not a regular file"), "{e}");
    }
    // The intact file still loads.
    std::fs::write(&path, &good).expect("restore");
    BrunetonTables::load(ctx, test_config(), &path).expect("intact file loads");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn moon_lights_the_night_only() {
    use himal::passes::sky::bruneton::{MOON_ILLUMINANCE_KLUX, moon_light};
    assert_eq!(moon_light(sun_at(10.0)), None);
    let (dir, e) = moon_light(sun_at(-30.0)).expect("moon at night");
    assert!(
        (dir + sun_at(-30.0)).length() < 1e-6,
        "opposite the sun: {dir}"
    );
    assert!(
        (e - MOON_ILLUMINANCE_KLUX).abs().max_element() < 1e-9,
        "{e}"
    );
    // Fades in continuously below the horizon.
    let (_, dusk) = moon_light(sun_at(-0.5)).expect("dusk");
    assert!(
        dusk.max_element() < 0.02 * MOON_ILLUMINANCE_KLUX.max_element(),
        "{dusk}"
    );
}

/// `himal bake`'s path: the tables computed one step at a time (waiting for
/// each) equal the single-submission tables, and the progress runs 0..=n.
#[test]
fn tables_computed_step_by_step_are_the_same() {
    let ctx = shared_context().expect("GPU");
    let mut calls = Vec::new();
    let stepped = BrunetonTables::compute_with_progress(ctx, test_config(), &mut |done, n, id| {
        calls.push((done, n, id.to_string()))
    })
    .expect("tables");
    let n = calls.last().map(|c| c.1).unwrap_or(0);
    // transmittance, direct irradiance, single; density, irradiance, multiple per order 2..=4.
    assert_eq!(n, 12, "{n} steps");
    let done: Vec<usize> = calls.iter().map(|c| c.0).collect();
    assert_eq!(done, (0..=n).collect::<Vec<_>>());
    assert_eq!(calls[0].2, "sky.tables.transmittance");
    let one = tables();
    for (a, b, what) in [
        (&stepped.transmittance, &one.transmittance, "transmittance"),
        (&stepped.irradiance, &one.irradiance, "irradiance"),
        (&stepped.scattering, &one.scattering, "scattering"),
        (&stepped.single_mie, &one.single_mie, "single Mie"),
    ] {
        for z in 0..a.depth_or_array_layers() {
            let (ta, tb) = (read_texture(ctx, a, 0, z), read_texture(ctx, b, 0, z));
            let (ta, tb) = (ta.expect("read"), tb.expect("read"));
            assert!(ta.bytes == tb.bytes, "{what} layer {z} differs");
        }
    }
}

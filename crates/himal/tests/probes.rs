//! L5 radiance-transfer probes: the bake, the cell files and the per-frame
//! CPU path (transfer, clip map, sampling) against a path-traced one-bounce
//! reference (docs/techniques/L5.md).

mod common;

use glam::{Vec2, Vec3};
use himal::math::sh::sh4_basis;
use himal::passes::indirect::cell::{Cell, CellKey};
use himal::passes::indirect::pool::CellPool;
use himal::passes::indirect::reference::{
    ClipMap, Sh4, lighting_sh, sky_radiance_sh, transfer_cell,
};
use himal::passes::indirect::{BakeSettings, ProbeStore, bake_cell};
use himal::passes::sky::SkyLight;
use himal::passes::sky::reference::{GROUND_ALBEDO, sky_irradiance_sh};
use himal::scene::Scene;
use himal::scene::raycast::RayScene;
use himal_reference::bounce::{Found, Light, Samples, Surfaces, one_bounce_irradiance};

/// The grid origin of a scene: the world's, centred on (0, 0).
const ORIGIN: Vec2 = Vec2::new(-5120.0, -5120.0);

struct Caster<'a>(&'a RayScene);

impl Surfaces for Caster<'_> {
    fn nearest(&self, o: Vec3, d: Vec3) -> Option<Found> {
        self.0.trace(o, d, 0.0, f32::INFINITY).map(|h| Found {
            t: h.t,
            normal: h.normal,
            albedo: h.albedo,
        })
    }
    fn clear(&self, o: Vec3, d: Vec3) -> bool {
        self.0.unoccluded(o, d, 0.0, f32::INFINITY)
    }
}

/// The four mip-0 cells around the origin ([-64, 64] m in x and z).
fn centre_cells() -> Vec<CellKey> {
    [(79, 79), (80, 79), (79, 80), (80, 80)]
        .into_iter()
        .map(|(x, z)| CellKey { mip: 0, x, z })
        .collect()
}

/// Deterministic numbers in [0, 1).
fn hash01(i: u32, salt: u32) -> f32 {
    let mut h = i.wrapping_mul(0x9E37_79B9) ^ salt.wrapping_mul(0x85EB_CA6B);
    h ^= h >> 16;
    h = h.wrapping_mul(0x7FEB_352D);
    h ^= h >> 15;
    (h >> 8) as f32 / (1u32 << 24) as f32
}

/// A sample point on a surface: position, normal, and whether it is ground.
struct Point {
    p: Vec3,
    n: Vec3,
    ground: bool,
}

/// `ground` points from rays straight down over [-56, 56]^2 (bilinear taps stay on baked probes) (ground or
/// roof), then `walls` points from horizontal rays 1.5 m up that hit a
/// non-ground surface within 20 m.
fn sample_points(rs: &RayScene, ground: u32, walls: u32) -> Vec<Point> {
    let mut out = Vec::new();
    for i in 0..ground {
        let xz = Vec2::new(hash01(i, 1), hash01(i, 2)) * 112.0 - 56.0;
        let from = Vec3::new(xz.x, 200.0, xz.y);
        if let Some(h) = rs.trace(from, -Vec3::Y, 0.0, 400.0) {
            out.push(Point {
                p: from - Vec3::Y * h.t,
                n: h.normal,
                ground: h.ground,
            });
        }
    }
    let mut i = 0;
    let mut found = 0;
    while found < walls && i < walls * 40 {
        i += 1;
        let xz = Vec2::new(hash01(i, 3), hash01(i, 4)) * 112.0 - 56.0;
        let a = hash01(i, 5) * std::f32::consts::TAU;
        let d = Vec3::new(a.cos(), 0.0, a.sin());
        let from = Vec3::new(xz.x, 1.5, xz.y);
        if let Some(h) = rs.trace(from, d, 0.0, 20.0)
            && !h.ground
            && h.normal.y.abs() < 0.1
        {
            out.push(Point {
                p: from + d * h.t,
                n: h.normal,
                ground: false,
            });
            found += 1;
        }
    }
    out
}

/// Reference irradiance at every point for every light, on two threads.
fn reference(
    rs: &RayScene,
    points: &[Point],
    lights: &[Light],
    samples: Samples,
) -> Vec<Vec<Vec3>> {
    let caster = Caster(rs);
    let half = points.len().div_ceil(2);
    std::thread::scope(|s| {
        let jobs: Vec<_> = points
            .chunks(half)
            .enumerate()
            .map(|(c, chunk)| {
                let caster = &caster;
                s.spawn(move || {
                    chunk
                        .iter()
                        .enumerate()
                        .map(|(i, q)| {
                            one_bounce_irradiance(
                                caster,
                                q.p,
                                q.n,
                                lights,
                                samples,
                                (c * half + i) as u32,
                            )
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        jobs.into_iter()
            .flat_map(|j| j.join().expect("reference thread"))
            .collect()
    })
}

fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// Relative L1 error sum |E - E_ref| / sum E_ref (luminance) over points.
fn relative_l1(pairs: &[(f32, f32)]) -> f32 {
    let err: f32 = pairs.iter().map(|(a, r)| (a - r).abs()).sum();
    let total: f32 = pairs.iter().map(|(_, r)| r).sum();
    err / total.max(1e-9)
}

/// One scene at one time of day: relative L1 errors against the path tracer.
struct Row {
    /// Probes on open ground, and on roofs and walls.
    ground: f32,
    other: f32,
    /// himal without probes (the sky SH's flat ground bounce).
    flat_ground: f32,
    flat_other: f32,
    /// Probes against the path tracer lit by the probes' own SH2 lighting
    /// (what remains is the probes' spacing, height and SH2 radiance).
    sh_lit_ground: f32,
    /// Mean indirect illuminance on open ground (klux), reference and probes.
    mean_ref: f32,
    mean_probe: f32,
}

fn accuracy(name: &str) -> Vec<Row> {
    let scene: Scene = common::scene(name);
    let rs = RayScene::from_scene(&scene, None);
    let settings = BakeSettings::default();
    let cells: Vec<Cell> = centre_cells()
        .into_iter()
        .map(|k| bake_cell(&rs, k, ORIGIN, &settings))
        .collect();
    let points = sample_points(&rs, 1000, 300);
    let times = [8.0, 12.0, 17.0];
    let skies: Vec<SkyLight> = times
        .iter()
        .map(|&t| {
            SkyLight::new(
                t,
                scene.sun.latitude_deg,
                scene.sun.day_of_year,
                scene.sun.turbidity,
            )
        })
        .collect();
    let sky_fns: Vec<Box<dyn Fn(Vec3) -> Vec3 + Sync>> = skies
        .iter()
        .map(|s| {
            let sky = s.sky.clone();
            Box::new(move |d: Vec3| {
                if d.y > 0.0 {
                    sky.radiance(d)
                } else {
                    Vec3::ZERO
                }
            }) as Box<dyn Fn(Vec3) -> Vec3 + Sync>
        })
        .collect();
    let lightings: Vec<Sh4> = skies
        .iter()
        .map(|sky| {
            let sh = sky_radiance_sh(|d| sky.sky.radiance(d));
            lighting_sh(&sh, sky.sun_direction, sky.sun_illuminance)
        })
        .collect();
    // The same lighting as the probes get it, sun included, as a radiance
    // function: separates what SH2 lighting costs from what probes cost.
    let sh_fns: Vec<Box<dyn Fn(Vec3) -> Vec3 + Sync>> = lightings
        .iter()
        .map(|l| {
            let l = *l;
            Box::new(move |d: Vec3| {
                let y = sh4_basis(d);
                (0..4).map(|j| l[j] * y[j]).sum::<Vec3>()
            }) as Box<dyn Fn(Vec3) -> Vec3 + Sync>
        })
        .collect();
    let mut lights: Vec<Light> = skies
        .iter()
        .zip(&sky_fns)
        .map(|(s, f)| Light {
            sky: f.as_ref(),
            to_sun: s.sun_direction,
            sun_illuminance: s.sun_illuminance,
        })
        .collect();
    lights.extend(sh_fns.iter().map(|f| Light {
        sky: f.as_ref(),
        to_sun: Vec3::Y,
        sun_illuminance: Vec3::ZERO,
    }));
    let truth = reference(
        &rs,
        &points,
        &lights,
        Samples {
            primary: 256,
            sky: 16,
        },
    );
    let mut rows = Vec::new();
    for t in 0..times.len() {
        let lighting = lightings[t];
        let probes: Vec<(CellKey, Vec<Sh4>)> = cells
            .iter()
            .map(|c| (c.key, transfer_cell(c, &lighting)))
            .collect();
        let mut pool = CellPool::default();
        for c in &cells {
            pool.admit(c.key, ORIGIN, Vec2::ZERO);
        }
        // Every point lies over the baked cells: no fallback, so a gap would show.
        let map = ClipMap::inject_resident(
            ORIGIN,
            Vec2::ZERO,
            &pool,
            |k| {
                probes
                    .iter()
                    .find(|(key, _)| *key == k)
                    .map(|(_, p)| p.as_slice())
            },
            None,
        );
        let (mut ground, mut other) = (Vec::new(), Vec::new());
        for (q, e) in points.iter().zip(&truth) {
            let got = map
                .irradiance(Vec2::ZERO, q.p, q.n)
                .expect("inside the clip map");
            let pair = (luminance(got), luminance(e[t]));
            if q.ground {
                ground.push(pair)
            } else {
                other.push(pair)
            }
        }
        let sh_lit: Vec<(f32, f32)> = points
            .iter()
            .zip(&truth)
            .filter(|(q, _)| q.ground)
            .map(|(q, e)| {
                let got = map.irradiance(Vec2::ZERO, q.p, q.n).expect("inside");
                (luminance(got), luminance(e[times.len() + t]))
            })
            .collect();
        // himal without probes: the sky SH's flat ground below the horizon
        // (GROUND_ALBEDO lit by the unshadowed sun and sky), E = L_g pi (1 - n.y) / 2.
        let sky = &skies[t];
        let e_up = sky_irradiance_sh(&sky.sky).eval(Vec3::Y).max(Vec3::ZERO)
            + sky.sun_illuminance * sky.sun_direction.y.max(0.0);
        let l_ground = GROUND_ALBEDO * e_up / std::f32::consts::PI;
        let flat = |n: Vec3| l_ground * (std::f32::consts::PI * (1.0 - n.y) * 0.5);
        let flat_pairs = |keep: bool| -> Vec<(f32, f32)> {
            points
                .iter()
                .zip(&truth)
                .filter(|(q, _)| q.ground == keep)
                .map(|(q, e)| (luminance(flat(q.n)), luminance(e[t])))
                .collect()
        };
        let row = Row {
            ground: relative_l1(&ground),
            other: relative_l1(&other),
            flat_ground: relative_l1(&flat_pairs(true)),
            flat_other: relative_l1(&flat_pairs(false)),
            sh_lit_ground: relative_l1(&sh_lit),
            mean_ref: ground.iter().map(|p| p.1).sum::<f32>() / ground.len() as f32,
            mean_probe: ground.iter().map(|p| p.0).sum::<f32>() / ground.len() as f32,
        };
        eprintln!(
            "| {name} | {:>4}h | {} / {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} / {:.3} |",
            times[t],
            ground.len(),
            other.len(),
            row.ground,
            row.flat_ground,
            row.sh_lit_ground,
            row.other,
            row.flat_other,
            row.mean_ref,
            row.mean_probe
        );
        rows.push(row);
    }
    rows
}
#[test]
fn l5_probes_against_path_traced_one_bounce_village_and_valley() {
    eprintln!(
        "| scene | time | points ground / other | probes ground | flat ground | probes vs SH2-lit truth | probes other | flat other | mean E ref / probes (klux) |"
    );
    let all: Vec<_> = ["l5_village", "l5_valley"]
        .into_iter()
        .map(|n| (n, accuracy(n)))
        .collect();
    for (name, rows) in &all {
        for (t, r) in rows.iter().enumerate() {
            assert!(
                r.mean_ref > 0.1,
                "{name} time {t}: no indirect light to compare"
            );
            // Measured (L5.md): on open ground the probes' error is at most
            // 0.62 of the flat ground's (village 12h: 0.617 vs 1.000).
            assert!(
                r.ground < 0.65 * r.flat_ground,
                "{name} time {t}: open ground {} vs flat {}",
                r.ground,
                r.flat_ground
            );
        }
    }
    // The goal, 0.20 on open ground, is met in the valley at noon
    // and 17:00 (measured 0.098 and 0.199); the village's near-wall bounce
    // and the 08:00 sun are beyond 8 m spacing and SH2 (explained in L5.md).
    assert!(
        all[1].1[1].ground <= 0.12,
        "valley at noon: {}",
        all[1].1[1].ground
    );
    assert!(
        all[1].1[2].ground <= 0.22,
        "valley at 17:00: {}",
        all[1].1[2].ground
    );
}

#[test]
fn the_bake_is_deterministic_and_its_files_round_trip() {
    let scene = common::scene("l5_village");
    let rs = RayScene::from_scene(&scene, None);
    let key = CellKey {
        mip: 0,
        x: 80,
        z: 79,
    };
    let quick = BakeSettings {
        rays: 32,
        visibility_rays: 8,
        ..Default::default()
    };
    let one = bake_cell(
        &rs,
        key,
        ORIGIN,
        &BakeSettings {
            threads: 1,
            ..quick
        },
    );
    let two = bake_cell(
        &rs,
        key,
        ORIGIN,
        &BakeSettings {
            threads: 2,
            ..quick
        },
    );
    assert_eq!(
        one.encode(),
        two.encode(),
        "same bytes for any thread count"
    );
    // Probes stand 3 m above the meadow, and on it, not on the roofs.
    assert!(
        one.heights.iter().all(|h| (h - 3.0).abs() < 1e-3),
        "{:?}",
        one.heights
    );
    let back = Cell::decode(&one.encode(), std::path::Path::new("m0_80_79.hmlp")).unwrap();
    assert_eq!(back.key, key);
}

/// The village with its four centre cells baked quickly, round-tripped
/// through the file format (the twins see the GPU's f16 transfer).
fn village_store() -> (Scene, RayScene, std::sync::Arc<ProbeStore>) {
    let scene = common::scene("l5_village");
    let rs = RayScene::from_scene(&scene, None);
    let quick = BakeSettings {
        rays: 64,
        visibility_rays: 16,
        ..Default::default()
    };
    let cells: Vec<Cell> = centre_cells()
        .into_iter()
        .map(|k| {
            let c = bake_cell(&rs, k, ORIGIN, &quick);
            Cell::decode(&c.encode(), std::path::Path::new("twin")).unwrap()
        })
        .collect();
    let store = std::sync::Arc::new(ProbeStore::from_cells(ORIGIN, cells));
    (scene, rs, store)
}

/// The CPU twins' clip map for a camera at `cam` (x, z): the cells the GPU
/// pool streams there, their SH probes under `light`, injected.
fn twin_clip_map(
    store: &ProbeStore,
    light: &himal::passes::indirect::IndirectLight,
    cam: Vec2,
) -> ClipMap {
    let mut pool = CellPool::default();
    pool.stream(ORIGIN, cam, |k| store.cell(k).is_some());
    let sh: Vec<(CellKey, Vec<Sh4>)> = pool
        .resident()
        .filter_map(|(_, k)| {
            store
                .cell(k)
                .map(|c| (k, transfer_cell(c, &light.lighting)))
        })
        .collect();
    ClipMap::inject_resident(
        ORIGIN,
        cam,
        &pool,
        |k| {
            sh.iter()
                .find(|(key, _)| *key == k)
                .map(|(_, p)| p.as_slice())
        },
        Some(light.fallback()),
    )
}

/// Pixels of `camera` whose ray meets a surface within 50 m of the origin
/// (the baked cells) away from silhouettes (the four neighbours' rays meet
/// a surface with the same normal): (pixel index, point, hit).
fn interior_pixels(
    rs: &RayScene,
    camera: &himal::scene::Camera,
    size: (u32, u32),
) -> Vec<(usize, Vec3, himal::scene::raycast::SurfaceHit)> {
    let hit = |x: i32, y: i32| {
        let (x, y) = (
            x.clamp(0, size.0 as i32 - 1) as u32,
            y.clamp(0, size.1 as i32 - 1) as u32,
        );
        let (o, d) = common::pixel_ray_from(camera, size, x, y);
        rs.trace(o, d, 0.0, 1e4).map(|h| (o + d * h.t, h))
    };
    let mut out = Vec::new();
    for y in 0..size.1 as i32 {
        for x in 0..size.0 as i32 {
            let Some((p, h)) = hit(x, y) else { continue };
            let same = [(1, 0), (-1, 0), (0, 1), (0, -1)]
                .iter()
                .all(|&(a, b)| hit(x + a, y + b).map(|n| n.1.normal) == Some(h.normal));
            if p.x.abs().max(p.z.abs()) <= 50.0 && same {
                out.push(((y as u32 * size.0 + x as u32) as usize, p, h));
            }
        }
    }
    out
}

/// `--view indirect` (transfer, injection and clip-map sampling on the GPU)
/// against the CPU twins at every pixel whose surface the baked cells cover.
#[test]
fn gpu_indirect_matches_the_cpu_twins() {
    use himal::passes::indirect::IndirectLight;
    use himal::passes::sky::SkyModel;

    let (scene, rs, store) = village_store();
    let mut r = common::renderer(&scene);
    r.set_probe_cells(Some(store.clone()));
    let camera = scene.camera("main").expect("camera").clone();
    let size = (96, 64);
    let mut s = common::raw_settings(&scene, size, "indirect");
    s.indirect = true;
    s.sky_model = SkyModel::Preetham;
    let gpu = common::render_rgba(&mut r, &camera, &s);

    let light = IndirectLight::of_sky(&SkyLight::of_sun(&scene.sun));
    let cam = Vec2::new(camera.position.x, camera.position.z);
    let map = twin_clip_map(&store, &light, cam);
    let mut errors = Vec::new();
    for (i, p, h) in interior_pixels(&rs, &camera, size) {
        let Some(cpu) = map.irradiance(cam, p, h.normal) else {
            continue;
        };
        let g = Vec3::from_slice(&gpu[i][..3]);
        let scale = cpu.max_element().max(0.05);
        errors.push((g - cpu).abs().max_element() / scale);
    }
    errors.sort_by(f32::total_cmp);
    let compared = errors.len();
    let mean = errors.iter().sum::<f32>() / compared as f32;
    let p99 = errors[compared * 99 / 100];
    let worst = errors[compared - 1];
    eprintln!(
        "indirect GPU vs twin: {compared} px, mean rel. {mean:.5}, p99 {p99:.4}, worst {worst:.4}"
    );
    assert!(compared > 1000, "{compared} pixels compared");
    // Measured: mean 0.0091, p99 0.051, worst 0.053 (f16 clip textures,
    // lavapipe's 8-bit bilinear weights across steep probe gradients, and
    // positions rebuilt from depth).
    assert!(mean < 0.012, "mean {mean}");
    assert!(p99 < 0.065, "p99 {p99}");
}

/// Deferred lighting with L5 on minus off, against its formula on the
/// twins: albedo / pi * (E_probes - E_flat ground(n)) on diffuse surfaces
/// (AO, sky occlusion and shadows off, so nothing else differs).
#[test]
fn lighting_swaps_the_flat_ground_for_the_probes() {
    use himal::passes::indirect::IndirectLight;
    let (scene, rs, store) = village_store();
    let light = IndirectLight::of_sky(&SkyLight::of_sun(&scene.sun));
    // Measured: mean 3.0e-4, p99 8e-4 of the lit value (f16 HDR targets).
    check_swap("sky", scene, &rs, &store, &light, 0.002, 0.005);
}

/// Under an HDR environment (the generated studio) the probes transfer
/// its upper half and replace the irradiance of its lower half.
#[test]
fn under_an_hdr_environment_the_probes_replace_its_lower_half() {
    use himal::passes::indirect::IndirectLight;
    use himal::passes::indirect::reference::sky_radiance_sh;
    use himal::scene::{EnvironmentDesc, EnvironmentImage, STUDIO};
    let (mut scene, rs, store) = village_store();
    let desc = EnvironmentDesc::new(STUDIO);
    let env = EnvironmentImage::load(&desc).expect("the studio");
    scene.environment = Some(desc);
    let above = sky_radiance_sh(|d| env.sample(d));
    let below = env.radiance_sh().add(&above.scale(-1.0));
    let light = IndirectLight::of_environment(
        &above,
        &below.radiance_to_irradiance_coeffs(),
        Vec3::Y,
        Vec3::ZERO,
    );
    assert!(
        light.lighting[0].max_element() > 0.0,
        "the studio lights the probes"
    );
    // Measured: mean 3.3e-4, p99 8e-4 of the lit value.
    check_swap("studio", scene, &rs, &store, &light, 0.002, 0.005);
}

/// The lit frame with the probes minus without, against the twins:
/// albedo / pi (E_probes - E_ground) at interior pixels.
fn check_swap(
    label: &str,
    scene: Scene,
    rs: &RayScene,
    store: &std::sync::Arc<ProbeStore>,
    light: &himal::passes::indirect::IndirectLight,
    max_mean: f32,
    max_p99: f32,
) {
    use himal::passes::ao::AoMode;
    use himal::passes::sky::SkyModel;
    let camera = scene.camera("main").expect("camera").clone();
    let size = (96, 64);
    let mut r = common::renderer(&scene);
    r.set_probe_cells(Some(store.clone()));
    let frame = |r: &mut himal::Renderer, on: bool| {
        let mut s = common::raw_settings(&scene, size, "lighting");
        s.indirect = on;
        s.sky_model = SkyModel::Preetham;
        s.ao.mode = AoMode::Off;
        s.sky_occlusion = false;
        s.shadow_resolution = 0;
        s.aerial_extinction = 0.0;
        common::render_rgba(r, &camera, &s)
    };
    let off = frame(&mut r, false);
    let on = frame(&mut r, true);
    let cam = Vec2::new(camera.position.x, camera.position.z);
    let map = twin_clip_map(store, light, cam);
    let mut errors = Vec::new();
    // Pixels the probes change by over 1 % (the test is not of zero against zero).
    let mut moved = 0;
    for (i, p, h) in interior_pixels(rs, &camera, size) {
        let Some(e_probes) = map.irradiance(cam, p, h.normal) else {
            continue;
        };
        let e_ground = light.ground.eval(h.normal).max(Vec3::ZERO);
        let want = h.albedo * (e_probes - e_ground) / std::f32::consts::PI;
        let got = Vec3::from_slice(&on[i][..3]) - Vec3::from_slice(&off[i][..3]);
        let scale = Vec3::from_slice(&off[i][..3]).max_element().max(1e-3);
        errors.push((got - want).abs().max_element() / scale);
        moved += usize::from(want.abs().max_element() > 0.01 * scale);
    }
    errors.sort_by(f32::total_cmp);
    let n = errors.len();
    let mean = errors.iter().sum::<f32>() / n as f32;
    eprintln!(
        "{label}: lighting on - off vs twin: {n} px ({moved} changed > 1 %), mean {mean:.5}, p99 {:.4} (of the lit value)",
        errors[n * 99 / 100]
    );
    assert!(n > 1000, "{n} pixels");
    // Measured: 248 (sky) and 232 (studio) of 3,159: the sunlit and
    // sky-lit pixels barely change, the shaded ones do.
    assert!(moved > n / 20, "{moved} of {n} pixels changed");
    assert!(mean < max_mean, "{mean}");
    assert!(
        errors[n * 99 / 100] < max_p99,
        "p99 {}",
        errors[n * 99 / 100]
    );
}

/// A flight across the world: the pool never holds more than 16 cells per
/// mip, and every clip-map texel the lighting can sample (12 texels of each
/// side of the camera, bilinear taps included) finds its own mip's cell.
#[test]
fn a_flight_keeps_the_pool_bounded_and_the_clip_map_covered() {
    use himal::passes::indirect::cell::MIPS;
    use himal::passes::indirect::pool::{CELLS_PER_MIP, cells_per_axis};
    use himal::passes::indirect::reference::{CLIP_RES, texel_size};

    let mut pool = CellPool::default();
    let (mut uploads, mut frames, mut missing) = (0usize, 0, 0);
    // 9 km diagonal, 7 m per frame (25 m/s at 1/30 s... a fast flight).
    let (a, b) = (Vec2::new(-4500.0, -4300.0), Vec2::new(4400.0, 4550.0));
    let steps = ((b - a).length() / 7.0) as usize;
    for i in 0..=steps {
        let cam = a.lerp(b, i as f32 / steps as f32);
        let step = pool.stream(ORIGIN, cam, |_| true);
        uploads += step.uploads.len();
        frames += 1;
        for mip in 0..MIPS as u8 {
            let n = pool.resident().filter(|(_, k)| k.mip == mip).count();
            assert!(n <= CELLS_PER_MIP, "frame {i}: mip {mip} holds {n}");
        }
        let bases = ClipMap::bases(ORIGIN, cam);
        for (c, base) in bases.iter().enumerate() {
            for t in 0..CLIP_RES * CLIP_RES {
                let g = *base + glam::IVec2::new(t % CLIP_RES, t / CLIP_RES);
                let centre = ORIGIN + (g.as_vec2() + 0.5) * texel_size(c);
                if (centre - cam).abs().max_element() > 12.0 * texel_size(c) {
                    continue;
                }
                let key = CellKey {
                    mip: c as u8,
                    x: g.x.div_euclid(8),
                    z: g.y.div_euclid(8),
                };
                let cells = cells_per_axis(c as u8);
                if key.x < 0 || key.z < 0 || key.x >= cells || key.z >= cells {
                    continue; // beyond the world's edge
                }
                if pool.slot_of(key).is_none() {
                    missing += 1;
                }
            }
        }
    }
    eprintln!(
        "flight: {frames} frames, {uploads} cell uploads ({:.2} per frame), pool <= 16 per mip",
        uploads as f32 / frames as f32
    );
    assert_eq!(missing, 0, "texels without their cell");
}

/// L3 + L5 (the talk's "indirect light from the nearest probe"): the relit
/// environment cube reads the probes' clip map. A face relit with
/// `--indirect on` equals the lighting pass (L5 included) rendered from the
/// cube's position, and differs from the face relit without the probes.
#[test]
fn relit_environment_faces_take_the_probes_indirect_light() {
    use himal::passes::envmap::probe::face_camera;
    use himal::{FrameSettings, ViewBuffer};
    let (mut scene, _, store) = village_store();
    // The cube 1.5 m above the village street; the main camera stands
    // there too, so the relight's clip map (centred on the camera) and the
    // direct render's (centred on the face camera) are the same.
    let probe = Vec3::new(2.0, 1.5, -3.0);
    scene.probes = vec![probe];
    let mut camera = scene.camera("main").expect("camera").clone();
    camera.position = probe;
    let base = |w, h, indirect| {
        let mut s = FrameSettings::new(w, h, scene.sun.clone());
        s.shadow_resolution = 0;
        s.aerial_extinction = 0.0;
        s.ao.mode = himal::passes::ao::AoMode::Off;
        s.environment_specular = false;
        s.sky_occlusion = false;
        s.indirect = indirect;
        s
    };
    let relit = |indirect| {
        let mut r = common::renderer(&scene);
        r.set_probe_cells(Some(store.clone()));
        r.render(&camera, &base(32, 32, indirect)).expect("frame");
        let size = r.envmap().source().width() as usize;
        let faces: Vec<Vec<Vec3>> = (0..6)
            .map(|f| common::read_rgb(r.context(), r.envmap().source(), 0, f))
            .collect();
        (size, faces)
    };
    let (n, on) = relit(true);
    let (_, off) = relit(false);
    let mut direct_renderer = common::renderer(&scene);
    direct_renderer.set_probe_cells(Some(store.clone()));
    let (mut worst, mut changed, mut texels) = (0.0f32, 0usize, 0usize);
    // Side faces and the floor (-Y): the sun's disk (+Y) is left out of the cube.
    for face in [0usize, 1, 3, 4, 5] {
        let mut s = base(n as u32, n as u32, true);
        s.view = "lighting".parse::<ViewBuffer>().expect("view");
        s.raw = true;
        s.environment_probes = false;
        let direct = common::render_rgba(&mut direct_renderer, &face_camera(probe, face), &s);
        for y in 0..n {
            for x in 0..n {
                // Cube faces are seen from inside: mirrored in x.
                let d = direct[y * n + (n - 1 - x)];
                let d = Vec3::new(d[0], d[1], d[2]);
                let (c, o) = (on[face][y * n + x], off[face][y * n + x]);
                let scale = d.max(Vec3::splat(1e-2));
                worst = worst.max(((c - d).abs() / scale).max_element());
                changed += usize::from(((c - o).abs() / scale).max_element() > 0.01);
                texels += 1;
            }
        }
    }
    eprintln!(
        "relit with L5 vs direct lighting: {texels} texels, worst relative error {worst:.2e}; \
         {changed} changed by over 1 % against the relight without"
    );
    // Measured: worst 0 (the same permutation and clip map); 6,297 of
    // 81,920 texels changed by over 1 %: the probes reach the cube.
    assert!(worst < 1e-3, "{worst}");
    assert!(changed > texels / 20, "{changed} of {texels}");
}

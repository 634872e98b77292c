//! L1 sky WGSL twins: `shaders/sky.wgsl` and `shaders/sh.wgsl` validated by
//! naga with the CPU layouts, and run on the adapter against the CPU
//! (`PreethamSky::radiance`, `PreethamSky::sun_disk_radiance`, `Sh9Rgb::eval`).
//! Measured numbers: `cargo test --release -p himal --test sky_wgsl -- --nocapture`.

use glam::Vec3;
use himal::gpu::testing::run_compute;
use himal::math::sh::{Sh9Gpu, Sh9Rgb};
use himal::passes::sky::{PreethamSky, SkyGpuParams, sky_irradiance_sh, sky_radiance_sh};

fn module_text(path: &str) -> &'static str {
    himal::shader::source(path).unwrap_or_else(|| panic!("{path} is not embedded"))
}

fn struct_layout(module: &naga::Module, name: &str) -> (u32, Vec<u32>) {
    for (_, ty) in module.types.iter() {
        if ty.name.as_deref() == Some(name)
            && let naga::TypeInner::Struct { members, span } = &ty.inner
        {
            return (*span, members.iter().map(|m| m.offset).collect());
        }
    }
    panic!("struct {name} not found");
}

#[test]
fn wgsl_modules_validate_and_match_the_cpu_layouts() {
    // Uniform bindings make naga check the uniform address-space layout rules.
    let entry = r#"
#import sh
#import sky
@group(0) @binding(0) var<uniform> sky_params: SkyParams;
@group(0) @binding(1) var<uniform> sky_sh: Sh9;
@group(0) @binding(2) var<storage, read_write> output: array<vec4f>;
@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    let d = normalize(vec3f(f32(id.x), 1.0, 0.5));
    output[id.x] = vec4f(preetham_sky_radiance(sky_params, d) + sun_disk_radiance(sky_params, d)
        + sh9_eval(sky_sh, d) + xyy_to_linear_srgb(d), 1.0);
}
"#;
    let shader =
        himal::shader::compose_str("tests/sky_wgsl.rs", entry).unwrap_or_else(|e| panic!("{e}"));
    for path in ["shaders/sh.wgsl", "shaders/sky.wgsl"] {
        let text = module_text(path);
        assert!(!text.contains("@group"), "{path} must not declare bindings");
        assert!(!text.contains("const PI"), "{path} must not define PI");
        // Modules validate on their own too (no imports needed).
        himal::shader::compose(path).unwrap_or_else(|e| panic!("{e}"));
    }
    let (span, offsets) = struct_layout(&shader.module, "SkyParams");
    assert_eq!(span as usize, std::mem::size_of::<SkyGpuParams>());
    assert_eq!(offsets, (0..12).map(|i| 16 * i).collect::<Vec<u32>>());
    let (span, _) = struct_layout(&shader.module, "Sh9");
    assert_eq!(span as usize, std::mem::size_of::<Sh9Gpu>());
}

const KERNEL: &str = r#"
#import sh
#import sky
struct SkyTestInput {
    params: SkyParams,
    sh: Sh9,
    dirs: array<vec4f>,
}
@group(0) @binding(0) var<storage, read> input: SkyTestInput;
@group(0) @binding(1) var<storage, read_write> output: array<vec4f>;
@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    let i = id.x;
    if (i >= arrayLength(&input.dirs)) {
        return;
    }
    let d = input.dirs[i].xyz;
    output[4u * i] = vec4f(preetham_sky_radiance(input.params, d), 0.0);
    output[4u * i + 1u] = vec4f(sun_disk_radiance(input.params, d), 0.0);
    output[4u * i + 2u] = vec4f(sh9_eval(input.sh, d), 0.0);
    output[4u * i + 3u] = vec4f(sh9_eval_radiance_from_irradiance(input.sh, d), 0.0);
}
"#;

struct GpuResult {
    sky: Vec3,
    disk: Vec3,
    sh: Vec3,
    sh_radiance: Vec3,
}

/// Runs the kernel for `dirs` with the sky's parameters and `sh`.
fn run_kernel(sky: &PreethamSky, sh: &Sh9Rgb, dirs: &[Vec3]) -> Vec<GpuResult> {
    let mut input: Vec<u8> = Vec::new();
    input.extend_from_slice(bytemuck::bytes_of(&sky.gpu_params()));
    input.extend_from_slice(bytemuck::bytes_of(&Sh9Gpu::from(sh)));
    for d in dirs {
        input.extend_from_slice(bytemuck::bytes_of(&d.extend(0.0).to_array()));
    }
    let out_bytes = (dirs.len() * 4 * 16) as u64;
    let groups = (dirs.len() as u32).div_ceil(64);
    let out = run_compute(KERNEL, "cs_main", &input, out_bytes, [groups, 1, 1])
        .unwrap_or_else(|e| panic!("sky kernel: {e}"));
    let v: &[[f32; 4]] = bytemuck::cast_slice(&out);
    v.chunks(4)
        .map(|c| GpuResult {
            sky: Vec3::from_slice(&c[0][..3]),
            disk: Vec3::from_slice(&c[1][..3]),
            sh: Vec3::from_slice(&c[2][..3]),
            sh_radiance: Vec3::from_slice(&c[3][..3]),
        })
        .collect()
}

fn fibonacci_sphere(n: usize) -> Vec<Vec3> {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - y * y).sqrt();
            let phi = golden * i as f32;
            Vec3::new(r * phi.cos(), y, r * phi.sin())
        })
        .collect()
}

/// A few hundred directions: the sphere, both sides of the horizon, and rings
/// across the sun disk's soft edge.
fn test_directions(sun: Vec3, disk_outer: f32) -> Vec<Vec3> {
    let mut dirs = fibonacci_sphere(320);
    for i in 0..32 {
        let phi = i as f32 * 0.37;
        let y = if i % 2 == 0 { 0.002 } else { -0.05 };
        dirs.push(Vec3::new(phi.cos(), y, phi.sin()).normalize());
    }
    let (u, v) = sun.any_orthonormal_pair();
    for i in 0..64 {
        let angle = disk_outer * 1.2 * (i / 8) as f32 / 7.0;
        let phi = (i % 8) as f32 * 0.785;
        dirs.push((sun * angle.cos() + (u * phi.cos() + v * phi.sin()) * angle.sin()).normalize());
    }
    dirs
}

fn skies() -> Vec<(&'static str, PreethamSky)> {
    let at = |elev: f32, az: f32| {
        let (e, a) = (elev.to_radians(), az.to_radians());
        Vec3::new(e.cos() * a.sin(), e.sin(), -e.cos() * a.cos())
    };
    vec![
        ("noon T2", PreethamSky::new(at(65.0, 160.0), 2.0)),
        ("morning T4", PreethamSky::new(at(12.0, 80.0), 4.0)),
        ("sunset T6", PreethamSky::new(at(1.0, 275.0), 6.0)),
        ("night T3", PreethamSky::new(at(-20.0, 0.0), 3.0)),
    ]
}

#[test]
fn gpu_preetham_sky_and_sun_disk_match_cpu() {
    let (mut worst_sky, mut worst_disk) = (0.0f32, 0.0f32);
    for (name, sky) in skies() {
        let outer = sky.gpu_params().sun_disk[1];
        let dirs = test_directions(sky.sun_direction(), outer);
        let gpu = run_kernel(&sky, &Sh9Rgb::zero(), &dirs);
        // Disk error relative to the disk's centre radiance.
        let centre = sky
            .sun_disk_radiance(sky.sun_direction())
            .length()
            .max(1e-30);
        let (mut s, mut k) = (0.0f32, 0.0f32);
        for (d, g) in dirs.iter().zip(&gpu) {
            let cpu = sky.radiance(*d);
            s = s.max((g.sky - cpu).length() / cpu.length().max(1e-30));
            k = k.max((g.disk - sky.sun_disk_radiance(*d)).length() / centre);
        }
        println!("{name:11}: sky max rel err {s:.2e}, sun disk max err / centre {k:.2e}");
        worst_sky = worst_sky.max(s);
        worst_disk = worst_disk.max(k);
    }
    // Measured on 2026-11-22 (lavapipe): sky 1.05e-4 (its exp/acos; a 1e-4
    // change of Perez D alone moves this to 1.65e-4), disk 1.2e-7.
    // Thresholds 5e-4 and 1e-5 leave room for other adapters' transcendentals.
    assert!(worst_sky < 5e-4, "sky {worst_sky}");
    assert!(worst_disk < 1e-5, "disk {worst_disk}");
}

#[test]
fn gpu_sh9_eval_matches_cpu() {
    let mut worst = 0.0f32;
    let mut worst_radiance = 0.0f32;
    for (name, sky) in skies() {
        let sh = sky_irradiance_sh(&sky);
        let dirs = test_directions(sky.sun_direction(), 0.01);
        let gpu = run_kernel(&sky, &sh, &dirs);
        let w = dirs.iter().zip(&gpu).fold(0.0f32, |w, (d, g)| {
            let cpu = sh.eval(*d);
            w.max((g.sh - cpu).length() / cpu.length())
        });
        println!("{name:11}: sh9_eval max rel err {w:.2e}");
        worst = worst.max(w);
        // Radiance from the irradiance coefficients (the Bruneton fog colour):
        // GPU vs CPU, and the CPU inverse against the radiance SH itself.
        let radiance = sky_radiance_sh(&sky);
        let irradiance = radiance.radiance_to_irradiance_coeffs();
        let (mut w_gpu, mut w_inverse) = (0.0f32, 0.0f32);
        let gpu = run_kernel(&sky, &irradiance, &dirs);
        for (d, g) in dirs.iter().zip(&gpu) {
            let cpu = irradiance.radiance_from_irradiance_eval(*d);
            let scale = radiance.c[0].length() * 0.282095;
            w_gpu = w_gpu.max((g.sh_radiance - cpu).length() / scale);
            w_inverse = w_inverse.max((cpu - radiance.eval(*d)).length() / scale);
        }
        println!(
            "{name:11}: radiance from irradiance, GPU vs CPU {w_gpu:.2e}, inverse {w_inverse:.2e}"
        );
        worst_radiance = worst_radiance.max(w_gpu.max(w_inverse));
    }
    // Measured 2026-11-22 (lavapipe): at most 5e-7 (relative to the mean
    // radiance); threshold 1e-5.
    assert!(
        worst_radiance < 1e-5,
        "radiance from irradiance {worst_radiance}"
    );
    // Measured 0 on 2026-11-22 (lavapipe: same f32 operations in the same
    // order); threshold 2e-6 allows FMA contraction elsewhere. A 5e-5 change
    // of one basis constant gives 3e-5.
    assert!(worst < 2e-6, "{worst}");
}

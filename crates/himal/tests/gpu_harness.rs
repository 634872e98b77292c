//! The GPU test harness itself: a kernel that imports a shared module runs
//! on the adapter and matches the CPU.

use himal::gpu::testing::run_compute;

#[test]
fn compute_kernel_with_import_matches_cpu() {
    let src = r#"
#import color
@group(0) @binding(0) var<storage, read> input: array<vec4f>;
@group(0) @binding(1) var<storage, read_write> output: array<f32>;
@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    if (id.x < arrayLength(&input)) { output[id.x] = luminance(input[id.x].rgb); }
}
"#;
    let colours: Vec<[f32; 4]> = (0..256)
        .map(|i| {
            let f = i as f32 / 255.0;
            [f, 1.0 - f, f * f, 1.0]
        })
        .collect();
    let out = run_compute(
        src,
        "cs_main",
        bytemuck::cast_slice(&colours),
        256 * 4,
        [4, 1, 1],
    )
    .expect("kernel runs");
    let gpu: &[f32] = bytemuck::cast_slice(&out);
    for (c, g) in colours.iter().zip(gpu) {
        let cpu = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
        // f32 on both sides; differences are rounding only (measured 0).
        assert!((cpu - g).abs() < 1e-6, "{cpu} vs {g}");
    }
}

#[test]
fn validation_errors_become_err_not_panic() {
    // Binding 1 is declared but the kernel writes out of its declared type
    // size: instead, give a kernel whose entry point does not exist.
    let src = "@group(0) @binding(0) var<storage, read> input: array<f32>;\n@group(0) @binding(1) var<storage, read_write> output: array<f32>;\n@compute @workgroup_size(1) fn cs_main() { output[0] = input[0]; }\n";
    let r = run_compute(src, "no_such_entry", &[0; 16], 16, [1, 1, 1]);
    assert!(r.is_err(), "missing entry point must be an error");
}

//! Harness for GPU-versus-CPU tests: runs a WGSL compute kernel over an
//! input buffer and returns its output buffer.

use std::sync::OnceLock;

use super::{GpuContext, GpuError, GpuOptions};
use crate::gpu::pipeline::Program;

/// One device shared by a test binary's tests (device creation on
/// lavapipe costs ~100 ms; tests run in parallel threads).
pub fn shared_context() -> Result<&'static GpuContext, GpuError> {
    static CTX: OnceLock<Result<GpuContext, String>> = OnceLock::new();
    CTX.get_or_init(|| GpuContext::new(&GpuOptions::default()).map_err(|e| e.to_string()))
        .as_ref()
        .map_err(|e| GpuError::Other(e.clone()))
}

/// Runs `entry` of `source` (which may `#import` shared modules) with
/// `@group(0) @binding(0) var<storage, read> input` holding `input` and
/// `@group(0) @binding(1) var<storage, read_write> output` of
/// `output_bytes`, dispatching `workgroups`; returns the output bytes.
pub fn run_compute(
    source: &str,
    entry: &str,
    input: &[u8],
    output_bytes: u64,
    workgroups: [u32; 3],
) -> Result<Vec<u8>, GpuError> {
    run_compute_with(source, entry, input, &[], output_bytes, workgroups)
}

/// [`run_compute`] with more read-only storage buffers bound by name
/// (`extra`: binding name, contents), for kernels over shared modules that
/// bring a binding of their own (`shaders/ambient_lights.wgsl`).
pub fn run_compute_with(
    source: &str,
    entry: &str,
    input: &[u8],
    extra: &[(&str, &[u8])],
    output_bytes: u64,
    workgroups: [u32; 3],
) -> Result<Vec<u8>, GpuError> {
    use wgpu::util::DeviceExt;
    let ctx = shared_context()?;
    let program = Program::from_source(ctx, "test-kernel", source)?;
    let pipeline = program.compute_pipeline(ctx, entry, &[])?;
    // Storage buffers must not be empty.
    let padded_input;
    let input = if input.is_empty() {
        padded_input = [0u8; 16];
        &padded_input[..]
    } else {
        input
    };
    let input_buffer = ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("test.input"),
            contents: input,
            usage: wgpu::BufferUsages::STORAGE,
        });
    let output_buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("test.output"),
        size: output_bytes.max(16),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let extra: Vec<(&str, wgpu::Buffer)> = extra
        .iter()
        .map(|(name, bytes)| {
            let usage = wgpu::BufferUsages::STORAGE;
            let desc = wgpu::util::BufferInitDescriptor {
                label: Some(name),
                contents: bytes,
                usage,
            };
            (*name, ctx.device.create_buffer_init(&desc))
        })
        .collect();
    let mut entries = vec![
        ("input", input_buffer.as_entire_binding()),
        ("output", output_buffer.as_entire_binding()),
    ];
    entries.extend(extra.iter().map(|(n, b)| (*n, b.as_entire_binding())));
    let bind_group = program.bind_group(ctx, 0, &entries)?;
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(workgroups[0], workgroups[1], workgroups[2]);
    }
    ctx.queue.submit([encoder.finish()]);
    ctx.check("run_compute")?;
    let mut bytes = super::read_buffer(ctx, &output_buffer)?;
    bytes.truncate(output_bytes as usize);
    Ok(bytes)
}

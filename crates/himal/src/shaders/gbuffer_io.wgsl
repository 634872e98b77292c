// What every G-buffer shader shares (passes/gbuffer/gbuffer.wgsl and
// textured.wgsl): the vertex input (twin of renderer/scene_gpu.rs
// `vertex_layout`), the targets, and the motion vector.

struct GBufferVertexIn {
    @location(0) position: vec3f,
    @location(1) normal: vec3f,
    @location(2) tangent: vec4f,
    @location(3) uv: vec2f,
    @location(4) color: vec4f,
    @location(5) surface: vec4f,
    // objects[instances[instance]] is the object drawn (V6)
    @builtin(instance_index) instance: u32,
}

struct GBufferOut {
    @location(0) albedo: vec4f,
    @location(1) frame: vec4f,
    @location(2) material: vec4f,
    @location(3) motion: vec2f,
}

// Screen motion (previous uv - current uv, uv y down) from this and the
// previous frame's clip positions. Both matrices carry their frame's jitter
// (the AA contract), so the motion includes the jitter change; passes/aa
// removes it.
fn gbuffer_motion(curr_clip: vec4f, prev_clip: vec4f) -> vec2f {
    let curr = curr_clip.xy / curr_clip.w;
    let prev = prev_clip.xy / prev_clip.w;
    return (prev - curr) * vec2f(0.5, -0.5);
}

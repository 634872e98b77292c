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
    // TEXCOORD_1 (glTF materials pick a set per slot: gltf_material.wgsl)
    @location(6) uv1: vec2f,
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

// `--view lod`: the albedo of a surface drawn at `level` (mesh LOD or
// terrain quadtree level), one hue per level over the surface's own
// brightness, so shapes stay readable.
fn lod_view_albedo(level: u32, albedo: vec3f) -> vec3f {
    let hues = array<vec3f, 8>(
        vec3f(0.9, 0.15, 0.1), vec3f(0.95, 0.6, 0.05), vec3f(0.85, 0.85, 0.1),
        vec3f(0.2, 0.75, 0.2), vec3f(0.1, 0.7, 0.8), vec3f(0.15, 0.3, 0.9),
        vec3f(0.6, 0.2, 0.85), vec3f(0.85, 0.85, 0.85));
    let l = dot(albedo, vec3f(0.2126, 0.7152, 0.0722));
    return hues[level % 8u] * clamp(0.45 + 1.5 * l, 0.45, 1.0);
}

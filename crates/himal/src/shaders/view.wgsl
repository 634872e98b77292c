// Per-frame camera data shared by every pass (twin: renderer/uniforms.rs `ViewUniform`).
// Reverse-Z: depth 1 at the near plane, 0 at infinity (the cleared value).

struct View {
    view_proj: mat4x4f,
    inv_view_proj: mat4x4f,
    prev_view_proj: mat4x4f,
    view: mat4x4f,
    // xyz camera position (world), w near plane distance
    camera_position: vec4f,
    // width, height, 1/width, 1/height in pixels
    viewport: vec4f,
    // xy: this frame's sub-pixel jitter in clip units, already inside view_proj,
    // inv_view_proj and prev_view_proj (the previous frame's); z: frame index; w: exposure EV bias
    jitter: vec4f,
    // x: animation time now (s); y: animation time of the previous frame; zw: 0
    time: vec4f,
    // xyz: unit view direction; w: the far plane of an orthographic camera
    // (parallel rays), 0 for a perspective one
    camera_forward: vec4f,
}

fn is_orthographic(view: View) -> bool {
    return view.camera_forward.w > 0.0;
}

// Distance along the view axis of device depth d (reverse-Z): near / d, or
// linear between the near and far planes of an orthographic camera.
fn view_distance(view: View, d: f32) -> f32 {
    let near = view.camera_position.w;
    if (is_orthographic(view)) {
        return near + (1.0 - d) * (view.camera_forward.w - near);
    }
    return near / max(d, 1e-9);
}

// Unit vector from world point p towards the eye (the view vector V):
// the same for every point under an orthographic camera.
fn to_eye(view: View, p: vec3f) -> vec3f {
    if (is_orthographic(view)) {
        return -view.camera_forward.xyz;
    }
    return normalize(view.camera_position.xyz - p);
}

// Full-screen triangle: vertex 0..2 covers the screen; uv has y down.
fn fullscreen_clip(vertex_index: u32) -> vec4f {
    let uv = vec2f(f32((vertex_index << 1u) & 2u), f32(vertex_index & 2u));
    return vec4f(uv * vec2f(2.0, -2.0) + vec2f(-1.0, 1.0), 0.0, 1.0);
}

// World position of the pixel centre at `uv` (y down) with device depth `depth`.
fn world_from_depth(view: View, uv: vec2f, depth: f32) -> vec3f {
    let ndc = vec4f(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, depth, 1.0);
    let p = view.inv_view_proj * ndc;
    return p.xyz / p.w;
}

// World position at a fragment (`@builtin(position)`.xy, pixel centres)
// with device depth `depth`: what the full-screen passes reconstruct.
fn world_at_fragment(view: View, frag_xy: vec2f, depth: f32) -> vec3f {
    return world_from_depth(view, frag_xy * view.viewport.zw, depth);
}

// Unit direction from the camera through the pixel at `uv` (works at depth 0 = infinity).
fn view_ray(view: View, uv: vec2f) -> vec3f {
    let ndc = vec4f(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 1.0, 1.0);
    let p = view.inv_view_proj * ndc;
    return -to_eye(view, p.xyz / p.w);
}

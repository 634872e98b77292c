// shadows.sun: depth of every object seen from the sun (orthographic), the
// single-map foundation of TECHNIQUES S1 (cascades replace the fit later).
// Bindings: shadow (uniform ShadowView: light view-projection), objects (as gbuffer).
// Standard depth here (0 near .. 1 far, compare LessEqual), unlike the camera's reverse-Z.

#import scene

struct ShadowView {
    light_view_proj: mat4x4f,
}

@group(0) @binding(0) var<uniform> shadow: ShadowView;
@group(0) @binding(1) var<storage, read> objects: array<Object>;

@vertex
fn vs_main(@location(0) position: vec3f, @builtin(instance_index) object: u32) -> @builtin(position) vec4f {
    return shadow.light_view_proj * (objects[object].model * vec4f(position, 1.0));
}

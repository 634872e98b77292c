// present: the rendered frame (display-encoded, read through a non-sRGB view)
// with the HUD overlay blended over it, written to a window's swapchain image.
// Blending happens on display-encoded values, as UI compositing usually does.
// Bindings: params (PresentParams), frame_load, overlay_load.
// CPU twin: present/reference.rs `compose`.
#import view
#import color
#import fullscreen

struct PresentParams {
    overlay_origin: vec2u,
    overlay_size: vec2u,
    // 1: the target is an sRGB format, so write linear values (the hardware encodes)
    target_srgb: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<uniform> params: PresentParams;
@group(0) @binding(1) var frame_load: texture_2d<f32>;
@group(0) @binding(2) var overlay_load: texture_2d<f32>;

@fragment
fn fs_main(@builtin(position) position: vec4f) -> @location(0) vec4f {
    let p = vec2u(position.xy);
    let frame_size = textureDimensions(frame_load);
    var c = textureLoad(frame_load, min(p, frame_size - 1u), 0).rgb;
    if all(p >= params.overlay_origin) && all(p - params.overlay_origin < params.overlay_size) {
        let o = textureLoad(overlay_load, p - params.overlay_origin, 0);
        c = o.rgb * o.a + c * (1.0 - o.a);
    }
    if params.target_srgb != 0u {
        c = srgb_to_linear(c);
    }
    return vec4f(c, 1.0);
}

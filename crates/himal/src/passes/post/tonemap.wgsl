// post.tonemap: Reinhard global operator on the GPU-reduced log-average
// luminance (TECHNIQUES H3; Reinhard et al. 2002 eq. 2-3):
//   L = key / L_avg * L_w,  L_d = L / (1 + L),  colour scaled by L_d / L_w (hue kept).
// Bindings: view (exposure bias in jitter.w), hdr, exposure (storage: result of post.luminance).
// Target: Rgba8UnormSrgb (hardware sRGB encoding). CPU twin: post/reference.rs.
#import view
#import color

override KEY: f32 = 0.18;

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var hdr: texture_2d<f32>;
@group(0) @binding(2) var<storage, read> exposure: vec4f;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4f {
    return fullscreen_clip(i);
}

fn reinhard(c: vec3f, scale: f32) -> vec3f {
    let l_w = luminance(c) * scale;
    if (l_w <= 0.0) {
        return vec3f(0.0);
    }
    let l_d = l_w / (1.0 + l_w);
    return c * scale * (l_d / l_w);
}

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let c = textureLoad(hdr, vec2i(frag.xy), 0).rgb;
    let scale = KEY / max(exposure.y, 1e-6) * exp2(view.jitter.w);
    return vec4f(reinhard(c, scale), 1.0);
}

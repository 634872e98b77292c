// V3 depth impostors in the frame: the atlas planes (one layer per tree
// species and seed) as textures, for shaders/impostor_draw.wgsl. Bound in
// group 0 of gbuffer.wgsl, gbuffer/textured.wgsl (one layout) and the
// shadow depth shaders (shadow_caster.wgsl); tests/impostor_frame.rs
// measures the frame.
#import impostor_draw

// RGBA8: tint t, leaf fraction, material AO, coverage.
@group(0) @binding(8) var impostor_color_load: texture_2d_array<f32>;
// RGBA8: tree-space normal * 0.5 + 0.5.
@group(0) @binding(9) var impostor_normal_load: texture_2d_array<f32>;
// R32F: depth * 0.5 + 0.5.
@group(0) @binding(10) var impostor_depth_load: texture_2d_array<f32>;

fn impostor_depth_texel(layer: i32, x: u32, y: u32) -> f32 {
    return textureLoad(impostor_depth_load, vec2u(x, y), layer, 0).r;
}

fn impostor_color_texel(layer: i32, x: u32, y: u32) -> vec4f {
    return textureLoad(impostor_color_load, vec2u(x, y), layer, 0);
}

fn impostor_normal_texel(layer: i32, x: u32, y: u32) -> vec4f {
    return textureLoad(impostor_normal_load, vec2u(x, y), layer, 0);
}

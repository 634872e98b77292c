// skyocc.view: `--view sky-visibility` (VIEW 1: the diffuse sky visibility
// lighting multiplies with, the SH2 along the bent normal, grey; raw: (V, f,
// fade-free L0 / C0, 1)) and `--view bent-normal` (VIEW 2: the bent normal,
// n * 0.5 + 0.5; raw: n). DISPLAY = true writes viewable values (sRGB), false raw.
// Bindings: view, G-buffer frame, depth, the sky occlusion table and pool.
#import view
#import color
#import tangent_frame
#import sky_occlusion
#import fullscreen

override VIEW: u32 = 1u;
override DISPLAY: bool = true;

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var gbuffer_frame: texture_2d<f32>;
@group(0) @binding(2) var depth: texture_depth_2d;
@group(0) @binding(3) var skyocc_table: texture_2d<i32>;
@group(0) @binding(4) var skyocc_vis: texture_2d_array<f32>;
@group(0) @binding(5) var skyocc_heights_load: texture_2d_array<f32>;
@group(0) @binding(6) var skyocc_sampler: sampler;

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let px = vec2i(frag.xy);
    let d = textureLoad(depth, px, 0);
    if (d <= 0.0) {
        return vec4f(0.0, 0.0, 0.0, 1.0);
    }
    let p = world_at_fragment(view, frag.xy, d);
    let n = quat_to_frame(unpack_quat(textureLoad(gbuffer_frame, px, 0)))[2];
    let sh = sky_occlusion_lookup(skyocc_table, skyocc_vis, skyocc_heights_load, skyocc_sampler, p, n);
    let bent = bent_normal_from_sh_visibility(n, sh);
    let v = sh2_visibility_cosine(sh, bent);
    if (VIEW == 2u) {
        return select(vec4f(bent, 1.0), vec4f(srgb_to_linear(bent * 0.5 + 0.5), 1.0), DISPLAY);
    }
    return select(vec4f(v, sh.x / SKYOCC_CAP_C0, 0.0, 1.0), vec4f(srgb_to_linear(vec3f(v)), 1.0), DISPLAY);
}

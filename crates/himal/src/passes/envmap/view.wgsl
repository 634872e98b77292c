// envmap.view: VIEW 1 (`--view env-probe`) is the prefiltered environment
// radiance that each pixel's ambient specular reads (L3/L4): the active cube
// (the nearest probe's relit cube, the sky's, or an HDR environment's) along
// the M4 reflection vector at the roughness mip, before the DFG term. VIEW 2
// (`--view env-mirror`) reads mip 0 instead: the relit cube as a mirror. Sky pixels
// show the cube along the view ray at mip 0. DISPLAY: exposure-scaled and
// clamped like `--view lighting`; raw: radiance (kcd/m^2).
// Same lookup as `shade` in passes/lighting/deferred.wgsl.
#import view
#import tangent_frame
#import brdf
#import envmap
#import post
#import fullscreen

override VIEW: u32 = 1u;
override DISPLAY: bool = true;

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var gbuffer_frame: texture_2d<f32>;
@group(0) @binding(2) var gbuffer_material: texture_2d<f32>;
@group(0) @binding(3) var depth: texture_depth_2d;
@group(0) @binding(4) var env_specular: texture_cube<f32>;
@group(0) @binding(5) var env_sampler: sampler;
@group(0) @binding(6) var<storage, read> exposure: vec4f;
@group(0) @binding(7) var<uniform> post: Post;

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let px = vec2i(frag.xy);
    let d = textureLoad(depth, px, 0);
    // A point on the pixel's ray (depth 1 = the near plane under reverse-Z).
    let p = world_at_fragment(view, frag.xy, select(1.0, d, d > 0.0));
    let v = to_eye(view, p);
    var radiance: vec3f;
    if (d <= 0.0) {
        radiance = textureSampleLevel(env_specular, env_sampler, -v, 0.0).rgb;
    } else {
        let tbn = quat_to_frame(unpack_quat(textureLoad(gbuffer_frame, px, 0)));
        let m = textureLoad(gbuffer_material, px, 0);
        let r = reflect(-v, m4_reflection_normal(tbn[2], tbn[1], v, m.w));
        let roughness = perceptual_roughness_from_glossiness(m.x);
        let lod = select(0.0, roughness * f32(textureNumLevels(env_specular) - 1u), VIEW == 1u);
        radiance = textureSampleLevel(env_specular, env_sampler, r, lod).rgb;
    }
    let scale = exposure_scale(post, exposure.y);
    return select(vec4f(radiance, 1.0), vec4f(min(radiance * scale, vec3f(1.0)), 1.0), DISPLAY);
}

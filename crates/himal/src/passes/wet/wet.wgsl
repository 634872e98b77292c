// gbuffer.wet: a wetness example of roughness changed in the G-buffer after
// texturing, and E3's screen-space normal-variance filter for it (Ryse:
// "where roughness is changed in the G-buffer, a normal variance filter runs
// in screen space"). Up-facing surfaces get a water film: w = amount *
// smoothstep(0.6, 0.95, n.y); albedo darkens by 1 - 0.4 w (dielectric part),
// roughness moves toward the film's, r_w = mix(r, 0.08, w). SPECULAR_AA:
// the mipmapped normal maps' variance (E3 part 1) widened the textured
// roughness, not this new one, so the normals' variance over the pixel's
// neighbourhood, sigma^2 = (1 - |m|) / |m| with m the 3 x 3 tent-weighted
// mean of the G-buffer normals, widens it: r' = toksvig_roughness(r_w, w
// sigma^2). Sky pixels pass through. CPU twin: passes/wet/reference.rs.
// Docs: docs/techniques/E3.md "Roughness changed in the G-buffer".
#import view
#import fullscreen
#import tangent_frame
#import brdf
#import gbuffer_material

override SPECULAR_AA: bool = true;

struct WetParams {
    // x: amount in [0, 1]
    amount: vec4f,
}

@group(0) @binding(0) var gbuffer_albedo: texture_2d<f32>;
@group(0) @binding(1) var gbuffer_frame: texture_2d<f32>;
@group(0) @binding(2) var gbuffer_material: texture_2d<f32>;
@group(0) @binding(3) var depth: texture_depth_2d;
@group(0) @binding(4) var<uniform> wet: WetParams;

struct WetOut {
    @location(0) albedo: vec4f,
    @location(1) material: vec4f,
}

fn normal_at(q: vec2i) -> vec3f {
    return quat_to_frame(unpack_quat(textureLoad(gbuffer_frame, q, 0)))[2];
}

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> WetOut {
    let px = vec2i(frag.xy);
    var out: WetOut;
    out.albedo = textureLoad(gbuffer_albedo, px, 0);
    out.material = textureLoad(gbuffer_material, px, 0);
    if (textureLoad(depth, px, 0) <= 0.0) {
        return out;
    }
    let n = normal_at(px);
    let w = wet.amount.x * smoothstep(0.6, 0.95, n.y);
    let m = out.material;
    out.albedo = vec4f(out.albedo.rgb * (1.0 - 0.4 * w * (1.0 - gbuffer_metallic(m.z))), out.albedo.a);
    var r = mix(perceptual_roughness_from_glossiness(m.x), 0.08, w);
    if (SPECULAR_AA && w > 0.0) {
        // Tent weights (1, 2, 1) / 4 per axis; a sky neighbour counts as the centre.
        let last = vec2i(textureDimensions(depth)) - 1;
        var mean = vec3f(0.0);
        for (var j = 0; j < 9; j++) {
            let o = vec2i(j % 3, j / 3) - 1;
            let q = clamp(px + o, vec2i(0), last);
            let weight = f32((2 - abs(o.x)) * (2 - abs(o.y))) / 16.0;
            var nq = n;
            if (textureLoad(depth, q, 0) > 0.0) {
                nq = normal_at(q);
            }
            mean += weight * nq;
        }
        let len = max(length(mean), 1e-4);
        r = toksvig_roughness(r, w * (1.0 - len) / len);
    }
    out.material = vec4f(1.0 - r, m.yzw);
    return out;
}

// debug.view: shows one G-buffer or HDR buffer (`himal render --view BUFFER`).
// VIEW selects the buffer (ids in passes/debug/mod.rs `DebugView`); DISPLAY = 1
// maps to viewable [0,1] for PNG (sRGB target), DISPLAY = 0 writes raw values
// (Rgba32Float, for EXR): albedo linear, normal/tangent in [-1,1], depth as
// stored (reverse-Z), motion in pixels, lighting and bloom in HDR units,
// luminance as (L_w, L_w / L_exposure, L_exposure).
#import view
#import color
#import tangent_frame
#import post
#import fullscreen
#import gbuffer_material

override VIEW: u32 = 1u;
override DISPLAY: bool = true;

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var gbuffer_albedo: texture_2d<f32>;
@group(0) @binding(2) var gbuffer_frame: texture_2d<f32>;
@group(0) @binding(3) var gbuffer_material: texture_2d<f32>;
@group(0) @binding(4) var motion: texture_2d<f32>;
@group(0) @binding(5) var depth: texture_depth_2d;
@group(0) @binding(6) var hdr: texture_2d<f32>;
@group(0) @binding(7) var<storage, read> exposure: vec4f;
@group(0) @binding(8) var<uniform> post: Post;
@group(0) @binding(9) var bloom: texture_2d<f32>;
@group(0) @binding(10) var bloom_sampler: sampler;

// Display value v in [0,1] stored as-is by the sRGB target.
fn shown(v: vec3f) -> vec4f {
    return vec4f(srgb_to_linear(clamp(v, vec3f(0.0), vec3f(1.0))), 1.0);
}

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let px = vec2i(frag.xy);
    let d = textureLoad(depth, px, 0);
    let sky = d <= 0.0;
    let tbn = quat_to_frame(unpack_quat(textureLoad(gbuffer_frame, px, 0)));
    let m = textureLoad(gbuffer_material, px, 0);
    var raw = vec4f(0.0, 0.0, 0.0, 1.0);
    var disp = vec3f(0.0);
    switch VIEW {
        case 1u, 14u, 15u: { // albedo (linear; the sRGB target encodes it); 14: lod, hues by level; 15: impostors by capture
            raw = vec4f(textureLoad(gbuffer_albedo, px, 0).rgb, 1.0);
            return select(raw, vec4f(0.0, 0.0, 0.0, 1.0), sky);
        }
        case 2u: { raw = vec4f(tbn[2], 1.0); disp = tbn[2] * 0.5 + 0.5; }
        case 3u: { raw = vec4f(tbn[0], 1.0); disp = tbn[0] * 0.5 + 0.5; }
        case 4u: { raw = vec4f(vec3f(m.x), 1.0); disp = vec3f(m.x); }
        case 5u: { raw = vec4f(vec3f(m.y), 1.0); disp = vec3f(m.y); }
        case 6u: { let metal = gbuffer_metallic(m.z); raw = vec4f(vec3f(metal), 1.0); disp = vec3f(metal); }
        case 16u: { let f = gbuffer_foliage(m.z); raw = vec4f(vec3f(f), 1.0); disp = vec3f(f); } // V5 leaf amount
        case 7u: { raw = vec4f(vec3f(m.w), 1.0); disp = vec3f(m.w); }
        case 8u: {
            raw = vec4f(vec3f(d), 1.0);
            // log scale 1 m .. 4 km
            let dist = view_distance(view, d);
            disp = vec3f(1.0 - clamp(log2(max(dist, 1.0)) / 12.0, 0.0, 1.0));
        }
        case 9u: {
            let mv = textureLoad(motion, px, 0).xy * view.viewport.xy;
            raw = vec4f(mv, 0.0, 1.0);
            disp = vec3f(0.5 + mv / 16.0, 0.5);
        }
        case 13u: { // sectors: the 64 m grid (world origin on a sector corner)
            let p = world_from_depth(view, frag.xy * view.viewport.zw, d);
            let s = p.xz / 64.0;
            let cell = vec2i(floor(s));
            var h = u32(cell.x) * 0x8da6b343u ^ u32(cell.y) * 0xd8163841u;
            h = (h ^ (h >> 15u)) * 0x2c1b3c6du;
            h = h ^ (h >> 12u);
            let hue = vec3f(f32(h & 255u), f32((h >> 8u) & 255u), f32((h >> 16u) & 255u)) / 255.0;
            let albedo = textureLoad(gbuffer_albedo, px, 0).rgb;
            let l = dot(albedo, vec3f(0.2126, 0.7152, 0.0722));
            // Edges about 1.5 px wide at any distance.
            let f = abs(fract(s + 0.5) - 0.5) / max(fwidth(s), vec2f(1e-6));
            let edge = 1.0 - smoothstep(0.75, 1.5, min(f.x, f.y));
            raw = vec4f(vec2f(cell), 0.0, 1.0);
            disp = mix((0.25 + 0.75 * hue) * clamp(0.4 + 1.5 * l, 0.4, 1.0), vec3f(0.02), edge);
        }
        case 11u: { // luminance (H3); display: log2(L_w / L_exposure) over +-8 EV, grey
            let l_w = luminance(textureLoad(hdr, px, 0).rgb);
            let l_e = max(exposure.y, 1e-6);
            raw = vec4f(l_w, l_w / l_e, l_e, 1.0);
            let ev = log2(max(l_w, 1e-9) / l_e);
            return select(raw, shown(vec3f(0.5 + ev / 16.0)), DISPLAY);
        }
        case 12u: { // bloom (H2, HDR units); display: exposure-scaled, clamped, no curve
            let uv = frag.xy * view.viewport.zw;
            let b = textureSampleLevel(bloom, bloom_sampler, uv, 0.0).rgb;
            raw = vec4f(b, 1.0);
            let scale = exposure_scale(post, exposure.y);
            return select(raw, vec4f(min(b * scale, vec3f(1.0)), 1.0), DISPLAY);
        }
        default: { // 10: lighting (HDR); display: exposure-scaled, clamped, no curve
            let c = textureLoad(hdr, px, 0).rgb;
            raw = vec4f(c, 1.0);
            let scale = exposure_scale(post, exposure.y);
            return select(raw, vec4f(min(c * scale, vec3f(1.0)), 1.0), DISPLAY);
        }
    }
    if (sky && VIEW != 8u) {
        raw = vec4f(0.0, 0.0, 0.0, 1.0);
        disp = vec3f(0.0);
    }
    return select(raw, shown(disp), DISPLAY);
}

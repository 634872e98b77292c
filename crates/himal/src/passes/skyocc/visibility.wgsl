// skyocc.visibility: per texel of each new sector, SSAO-style sampling of the
// blurred height field with a per-texel rotated Poisson disk (TECHNIQUES L2).
// Disk point q maps to the hemisphere direction d = (q.x s, 1 - |q|^2, q.y s),
// s = sqrt(2 - |q|^2) (equal area: uniform directions). d is visible when the
// ray from the texel's point (raw height + ORIGIN_LIFT) stays above the
// blurred height at STEPS points up to RADIUS metres. Visible fraction f and
// the sum of visible directions become an SH2 cap (shaders/sky_occlusion.wgsl),
// written for the sector and a BORDER ring (smoothed into the pool by
// visibility_smooth.wgsl); (terrain, fade) heights go to the sector's pool
// layer (terrain: the ground alone, rendered into ground_load); the fade height
// is the blurred field averaged over the disk scaled to FADE_RADIUS (a wide
// blur, as the talk's blurred map; the sampled field stays sharp).
// Twin: passes/skyocc/reference.rs `visibility_at`, `sector_visibility`.
#import sky_occlusion
#import math

override RADIUS: f32 = 8.0;
override STEPS: u32 = 8u;
override MARGIN: i32 = 36;
override TEXEL: f32 = 0.25;
override ORIGIN_LIFT: f32 = 0.05;
override FADE_RADIUS: f32 = 2.0;
// Ring of texels around the sector computed for the smoothing pass
// (reference::SMOOTH_BORDER).
override BORDER: i32 = 2;

@group(0) @binding(0) var raw_load: texture_2d_array<f32>;
@group(0) @binding(1) var blurred_load: texture_2d_array<f32>;
@group(0) @binding(2) var<storage, read> disk: array<vec2f>;
@group(0) @binding(3) var<storage, read> jobs: array<SectorJob>;
// The sector plus BORDER texels on each side, layer = job (smoothed into the
// pool by visibility_smooth.wgsl).
@group(0) @binding(4) var vis_out: texture_storage_2d_array<rgba32float, write>;
@group(0) @binding(5) var heights_out: texture_storage_2d_array<rg32float, write>;
@group(0) @binding(6) var ground_load: texture_2d_array<f32>;

@compute @workgroup_size(8, 8, 1)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    let ext = vec2i(textureDimensions(vis_out));
    let u = vec2i(id.xy);
    if (u.x >= ext.x || u.y >= ext.y) {
        return;
    }
    let job = jobs[id.z];
    let size = vec2i(textureDimensions(raw_load));
    let layer = i32(id.z);
    let x = u + vec2i(MARGIN - BORDER);
    let h_raw = textureLoad(raw_load, x, layer, 0).x;
    let origin = job.origin.xy;
    let p = vec3f(origin.x + (f32(x.x) + 0.5) * TEXEL, h_raw + ORIGIN_LIFT, origin.y + (f32(x.y) + 0.5) * TEXEL);
    let noise = fract(52.982918 * fract(0.06711056 * f32(x.x) + 0.00583715 * f32(x.y)));
    let angle = TAU * noise;
    let s = sin(angle);
    let c = cos(angle);
    var count = 0u;
    var sum = vec3f(0.0);
    var h_fade = 0.0;
    let n = arrayLength(&disk);
    for (var k = 0u; k < n; k = k + 1u) {
        let dk = disk[k];
        let q = vec2f(c * dk.x - s * dk.y, s * dk.x + c * dk.y);
        let r2 = min(dot(q, q), 1.0);
        let lift = sqrt(max(2.0 - r2, 0.0));
        let dir = vec3f(q.x * lift, 1.0 - r2, q.y * lift);
        // Fade taps unrotated: one kernel for every texel (a blur; rotated
        // per texel they streak the fade along walls).
        let tf = clamp(vec2i(floor((p.xz + dk * FADE_RADIUS - origin) / TEXEL)), vec2i(0), size - 1);
        h_fade += textureLoad(blurred_load, tf, layer, 0).x;
        var visible = true;
        for (var i = 1u; i <= STEPS; i = i + 1u) {
            let a = p + dir * (RADIUS * f32(i) / f32(STEPS));
            let t = clamp(vec2i(floor((a.xz - origin) / TEXEL)), vec2i(0), size - 1);
            if (textureLoad(blurred_load, t, layer, 0).x > a.y) {
                visible = false;
                break;
            }
        }
        if (visible) {
            count += 1u;
            sum += dir;
        }
    }
    let f = f32(count) / f32(max(n, 1u));
    h_fade /= f32(max(n, 1u));
    textureStore(vis_out, u, layer, sh2_from_visibility(f, sum));
    let v = u - vec2i(BORDER);
    if (all(v >= vec2i(0)) && all(v < ext - 2 * BORDER)) {
        let h_ground = textureLoad(ground_load, x, layer, 0).x;
        textureStore(heights_out, v, i32(job.layer.x), vec4f(h_ground, h_fade, 0.0, 1.0));
    }
}

// post.luminance: log-average luminance of the HDR image, reduced on the GPU
// (TECHNIQUES H3; Reinhard et al. 2002 eq. 1: L_avg = exp(mean(log(delta + L)))).
// Two steps with a fixed reduction order, so the result is deterministic:
//   cs_partial: each 64x64 tile (16x16 threads, 4x4 pixels each) -> (sum of log L, pixel count)
//   cs_final:   one workgroup sums the tiles -> result = (log average, average, tiles, pixels)
// Bindings: hdr (texture), partials (storage), result (storage). CPU twin: post/reference.rs.
#import color

const DELTA: f32 = 1e-4;

@group(0) @binding(0) var hdr: texture_2d<f32>;
@group(0) @binding(1) var<storage, read_write> partials: array<vec2f>;
@group(0) @binding(2) var<storage, read_write> result: vec4f;

var<workgroup> tile_sum: array<vec2f, 256>;

// Sums tile_sum[0..256] into tile_sum[0] in a fixed order (deterministic).
// Called from uniform control flow by all 256 invocations.
fn reduce_tile(li: u32) {
    workgroupBarrier();
    for (var stride = 128u; stride > 0u; stride = stride >> 1u) {
        if (li < stride) {
            tile_sum[li] = tile_sum[li] + tile_sum[li + stride];
        }
        workgroupBarrier();
    }
}

@compute @workgroup_size(16, 16)
fn cs_partial(@builtin(global_invocation_id) gid: vec3u, @builtin(local_invocation_index) li: u32,
              @builtin(workgroup_id) wg: vec3u, @builtin(num_workgroups) nwg: vec3u) {
    let size = textureDimensions(hdr);
    var v = vec2f(0.0);
    // Fewer, fuller workgroups: barriers dominate on software adapters.
    for (var j = 0u; j < 4u; j = j + 1u) {
        for (var i = 0u; i < 4u; i = i + 1u) {
            let p = gid.xy * 4u + vec2u(i, j);
            if (p.x < size.x && p.y < size.y) {
                let c = textureLoad(hdr, vec2i(p), 0).rgb;
                // Guard against NaN/Inf from upstream passes.
                let l = clamp(luminance(c), 0.0, 65504.0);
                v = v + vec2f(log(DELTA + l), 1.0);
            }
        }
    }
    tile_sum[li] = v;
    reduce_tile(li);
    if (li == 0u) {
        partials[wg.y * nwg.x + wg.x] = tile_sum[0];
    }
}

@compute @workgroup_size(256)
fn cs_final(@builtin(local_invocation_index) li: u32) {
    let n = arrayLength(&partials);
    var v = vec2f(0.0);
    for (var i = li; i < n; i = i + 256u) {
        v = v + partials[i];
    }
    tile_sum[li] = v;
    reduce_tile(li);
    if (li == 0u) {
        let log_avg = tile_sum[0].x / max(tile_sum[0].y, 1.0);
        result = vec4f(log_avg, exp(log_avg), f32(n), tile_sum[0].y);
    }
}
